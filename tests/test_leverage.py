"""_core.sampson_leverage / max_leverage (csrc/leverage.c) against an
independent reference: the Jacobian of the public residual
(_core.gec_residuals) by central differences in numpy, the hat matrix's
diagonal J (J^T J)^-1 J^T by numpy's solver; the 6-parameter fit and R held;
the degenerate and bad inputs."""

from __future__ import annotations

import numpy as np
import pytest

from mcgeom import _core
from problems import make


def _rotvec(w):
    th = np.linalg.norm(w)
    if th == 0:
        return np.eye(3)
    k = w / th
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * K @ K


def _reference(rays, R, t, hold, eps=1e-6):
    a = (rays.origins1, rays.dirs1, rays.origins2, rays.dirs2)
    cols = []
    for j in range(3, 6) if hold else range(6):
        d = np.zeros(3)
        d[j % 3] = eps
        if j < 3:
            cols.append((_core.gec_residuals(*a, _rotvec(d) @ R, t)
                         - _core.gec_residuals(*a, _rotvec(-d) @ R, t)) / (2 * eps))
        else:
            cols.append((_core.gec_residuals(*a, R, t + d)
                         - _core.gec_residuals(*a, R, t - d)) / (2 * eps))
    J = np.stack(cols, axis=1)
    return np.einsum("ij,ij->i", J, np.linalg.solve(J.T @ J, J.T).T)


@pytest.mark.parametrize("kind", ["most-general", "axial", "locally-central",
                                  "locally-central-and-axial"])
@pytest.mark.parametrize("hold", [False, True])
def test_against_finite_differences(kind, hold):
    p = make(kind, 11, n=40, angular_noise=1e-3)
    r = p.rays
    lev = _core.sampson_leverage(r.origins1, r.dirs1, r.origins2, r.dirs2, p.R, p.t, hold)
    ref = _reference(r, p.R, p.t, hold)
    assert np.abs(lev - ref).max() < 1e-6
    assert abs(lev.sum() - (3 if hold else 6)) < 1e-9
    st = _core.leverage_stats(r.origins1, r.dirs1, r.origins2, r.dirs2, p.R, p.t, hold)
    assert st["max_leverage"] == lev.max() and lev[st["leverage_pair"]] == lev.max()


@pytest.mark.parametrize("weighted", [False, True])
def test_hc_std_against_numpy(weighted):
    """travel_std_hc: the root sum of squares of the deletion moves
    w_k g^T H^-1 J_k^T r_k / (1 - h_k), H = J^T W J, g the gradient of the
    centroid's travel |t + R c - c| (numpy, the Jacobian by central
    differences); and travel_std, sigma sqrt(g^T H^-1 g)."""
    p = make("most-general", 21, n=50, angular_noise=1e-3)
    r = p.rays
    a = (r.origins1, r.dirs1, r.origins2, r.dirs2)
    rng = np.random.default_rng(3)
    w = rng.uniform(0.5, 2.0, len(r)) if weighted else np.ones(len(r))
    w[:3] = 0.0 if weighted else 1.0       # (pairs the fit did not use)
    eps = 1e-6
    cols = []
    for j in range(6):
        d = np.zeros(3)
        d[j % 3] = eps
        if j < 3:
            cols.append((_core.gec_residuals(*a, _rotvec(d) @ p.R, p.t)
                         - _core.gec_residuals(*a, _rotvec(-d) @ p.R, p.t)) / (2 * eps))
        else:
            cols.append((_core.gec_residuals(*a, p.R, p.t + d)
                         - _core.gec_residuals(*a, p.R, p.t - d)) / (2 * eps))
    J = np.stack(cols, axis=1)
    res = _core.gec_residuals(*a, p.R, p.t)
    used = w > 0
    c = 0.5 * (r.origins1[used].mean(0) + r.origins2[used].mean(0))
    tau = p.t + p.R @ c - c
    u = tau / np.linalg.norm(tau)
    g = np.concatenate([np.cross(p.R @ c, u), u])
    H = J.T @ (w[:, None] * J)
    Hg = np.linalg.solve(H, g)
    h = w * np.einsum("ij,ij->i", J, np.linalg.solve(H, J.T).T)
    moves = w * (J @ Hg) * res / (1.0 - h)
    sd = np.sqrt(np.sum(w * res ** 2) / (used.sum() - 6) * g @ Hg)
    st = _core.leverage_stats(*a, p.R, p.t, weights=w)
    assert st["travel_std_hc"] == pytest.approx(np.sqrt(np.sum(moves ** 2)), rel=1e-6)
    assert st["travel_std"] == pytest.approx(sd, rel=1e-6)
    assert st["max_influence"] == pytest.approx(np.abs(moves).max() / np.linalg.norm(tau),
                                                rel=1e-6)


def test_gross_outlier_has_the_leverage():
    """A random time-2 bearing pulls the least-squares fit onto itself: at the
    fit its residual is small, its leverage near 1."""
    import mcgeom
    p = make("axial", 1003, n=60, angular_noise=1e-3)
    rng = np.random.default_rng(5003)
    bad = rng.random(60) < 0.02
    d2 = p.rays.dirs2.copy()
    d2[bad] = rng.normal(size=(int(bad.sum()), 3))
    rays = mcgeom.RayPairs(p.rays.origins1, p.rays.dirs1, p.rays.origins2, d2, p.rays.cam1,
                           p.rays.cam2)
    fit = mcgeom.geometry.refine_centred(rays, p.R, p.t)
    st = _core.leverage_stats(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2,
                              fit["R"], fit["t"])
    assert bad[st["leverage_pair"]] and st["max_leverage"] > 0.95


def test_degenerate_and_bad_input():
    p = make("most-general", 2, n=20)
    r = p.rays
    a = (r.origins1, r.dirs1, r.origins2, r.dirs2)
    assert _core.sampson_leverage(*(x[:5] for x in a), p.R, p.t) is None   # 5 pairs
    assert _core.leverage_stats(*(np.ascontiguousarray(x[:5]) for x in a), p.R, p.t) is None
    # one centre: |t| is determined by no pair
    o = np.zeros_like(r.origins1)
    assert _core.sampson_leverage(o, r.dirs1, o, r.dirs2, p.R, p.t) is None
    with pytest.raises(ValueError):
        _core.sampson_leverage(*a, p.R, np.array([np.nan, 0.0, 0.0]))
