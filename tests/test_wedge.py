"""Bitangent wedge normals (csrc/wedge.c, thesis eqs. 10.9-10.12).

Conservativeness by sampling: for random geometry, rays inside both error
cones imply translation directions t = l' u' - l u (l, l' >= 0: the point in
front of both cameras, the epipolar plane containing both rays); none may be
excluded by the two half-spaces. Tightness: the planes touch the cones, and
directions outside the set of implied directions by a margin are excluded in
most cases.
"""

from __future__ import annotations

import numpy as np
import pytest

from mcgeom import _core


def _unit(a):
    return a / np.linalg.norm(a, axis=-1, keepdims=True)


def _in_cone(rng, axis, eps, n, boundary=False):
    """n unit vectors within angle eps of the unit axis (uniform in the cap)."""
    r = rng.normal(size=(n, 3))
    p = _unit(np.cross(axis, r))
    q = np.cross(axis, p)
    if boundary:
        th = np.full(n, eps)
    else:
        th = np.arccos(1.0 - rng.uniform(size=n) * (1.0 - np.cos(eps)))
    ph = rng.uniform(0, 2 * np.pi, size=n)
    return (np.cos(th)[:, None] * axis
            + np.sin(th)[:, None] * (np.cos(ph)[:, None] * p + np.sin(ph)[:, None] * q))


def _implied(rng, v, vp, eps, epsp, n):
    u = _in_cone(rng, v, eps, n, boundary=False)
    up = _in_cone(rng, vp, epsp, n, boundary=False)
    ub = _in_cone(rng, v, eps, n, boundary=True)
    upb = _in_cone(rng, vp, epsp, n, boundary=True)
    u = np.vstack([u, ub])
    up = np.vstack([up, upb])
    lam = np.exp(rng.uniform(-6, 6, size=2 * n))
    lam[:10] = 0.0
    lamp = np.ones(2 * n)
    lamp[10:20] = 0.0
    t = lamp[:, None] * up - lam[:, None] * u
    return _unit(t)


def _geometry(rng):
    v = _unit(rng.normal(size=3))
    vp = _unit(rng.normal(size=3))
    eps, epsp = rng.uniform(0, 0.25, size=2) ** 1.5
    return v, vp, eps, epsp


def test_conservative_by_sampling():
    rng = np.random.default_rng(5)
    worst = 0.0
    n_wedges = 0
    for _ in range(400):
        v, vp, eps, epsp = _geometry(rng)
        r = _core.wedge_normals(v, vp, eps, epsp)
        if r is None:
            continue
        n_wedges += 1
        n1, n2 = r
        t = _implied(rng, v, vp, eps, epsp, 1000)
        worst = max(worst, -(t @ n1).min(), -(t @ n2).min())
    print(f"{n_wedges} wedges, worst violation {worst:.2e}")
    assert n_wedges > 300
    assert worst <= 1e-12


def test_conservative_in_rig_frame():
    """Full motion X2 = R X1 + t: the rays of a point in front of both cameras
    (bearings perturbed within eps) satisfy n.t >= n.(c - R c)."""
    from mcgeom._core import rot_from_angle_axis
    rng = np.random.default_rng(7)
    worst = np.inf
    for _ in range(300):
        R = rot_from_angle_axis(rng.normal(size=3) * 0.3)
        t = rng.normal(size=3)
        c = rng.normal(size=3) * 0.5
        X1 = c + rng.normal(size=3) * 3.0
        X2 = R @ X1 + t
        d1 = _unit(X1 - c)
        d2 = _unit(X2 - c)
        eps, epsp = rng.uniform(0.001, 0.05, size=2)
        # the measured bearings, within eps of the true ones
        m1 = _in_cone(rng, d1, eps, 1)[0]
        m2 = _in_cone(rng, d2, epsp, 1)[0]
        r = _core.wedge_normals(R @ m1, m2, eps, epsp)
        if r is None:
            continue
        for n in r:
            worst = min(worst, n @ t - n @ (c - R @ c))
    assert worst >= -1e-12


def test_tight():
    rng = np.random.default_rng(11)
    fracs = []
    for _ in range(200):
        v, vp, eps, epsp = _geometry(rng)
        r = _core.wedge_normals(v, vp, eps, epsp)
        if r is None:
            continue
        n1, n2 = r
        # each plane touches both cones: min over each cone boundary of n.u = 0
        for n in (n1, n2):
            for ax, e in ((vp, epsp), (-v, eps)):
                b = _in_cone(rng, ax, e, 20000, boundary=True)
                assert abs((b @ n).min()) < 1e-4
        # directions farther than a margin from every implied direction
        t = _implied(rng, v, vp, eps, epsp, 3000)
        d = _unit(rng.normal(size=(2000, 3)))
        far = (d @ t.T).max(axis=1) < np.cos(0.1)
        if far.sum() < 50:
            continue
        excluded = ((d[far] @ n1) < 0) | ((d[far] @ n2) < 0)
        fracs.append(excluded.mean())
    fracs = np.array(fracs)
    print(f"excluded fraction of far directions: median {np.median(fracs):.3f}, "
          f"min {fracs.min():.3f}")
    assert np.median(fracs) > 0.8
    # negative depth: t along +v (the point behind the time-1 camera) excluded
    v = np.array([0.0, 0.0, 1.0])
    vp = _unit(np.array([0.0, 0.6, 1.0]))
    n1, n2 = _core.wedge_normals(v, vp, 0.02, 0.02)
    assert min(n1 @ v, n2 @ v) < 0
    assert min(n1 @ -vp, n2 @ -vp) < 0


def test_thesis_closed_form():
    """|in-plane part|^2 = sin^2 beta of eq. 10.10; n1, n2 symmetric about it."""
    rng = np.random.default_rng(3)
    for _ in range(100):
        v, vp, eps, epsp = _geometry(rng)
        r = _core.wedge_normals(v, vp, eps, epsp)
        if r is None:
            continue
        n1, n2 = r
        al = np.arccos(np.clip(v @ vp, -1, 1))
        sb2 = (np.sin(eps) ** 2 + 2 * np.sin(eps) * np.sin(epsp) * np.cos(al)
               + np.sin(epsp) ** 2) / np.sin(al) ** 2
        y = 0.5 * (n1 + n2)
        assert abs(y @ y - sb2) < 1e-9
        x = _unit(np.cross(v, vp))
        assert abs(0.5 * (n1 - n2) @ x - np.sqrt(1 - sb2)) < 1e-9
        assert np.linalg.norm(n1) == pytest.approx(1.0) and np.linalg.norm(n2) == pytest.approx(1.0)


def test_degenerate_and_invalid():
    z = np.array([0.0, 0.0, 1.0])
    assert _core.wedge_normals(z, 2 * z, 0.01, 0.01) is None
    assert _core.wedge_normals(z, -z, 0.01, 0.01) is None
    assert _core.wedge_normals(z, [0, 0.05, 1], 0.03, 0.03) is None
    assert _core.wedge_normals(z, [0, 0.5, 1], 0.03, 0.03) is not None
    with pytest.raises(ValueError):
        _core.wedge_normals([0, 0, 0], z, 0.1, 0.1)
    with pytest.raises(ValueError):
        _core.wedge_normals([np.nan, 0, 1], z, 0.1, 0.1)
    with pytest.raises(ValueError):
        _core.wedge_normals(z, [0, 1, 1], -0.1, 0.1)
    with pytest.raises(ValueError):
        _core.wedge_normals(z, [0, 1, 1], 0.1, 2.0)
