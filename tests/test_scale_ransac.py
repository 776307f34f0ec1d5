"""``_core.scale_ransac`` (csrc/scale_line.c), the 1-point scale search of the 5+1
method (thesis ch. 7.4), against a numpy reference of the same algorithm."""

from __future__ import annotations

import numpy as np
import pytest

from mcgeom import _core, synth
from mcgeom.estimators import five_plus_one as fpo
from mcgeom.types import RayPairs


def _rows(a, b):
    return np.einsum("ij,ij->i", a, b)


def _terms(rays: RayPairs, R, t0, w):
    """Per correspondence ``r(lam) = (a + lam b) / sqrt(A + 2 B lam + C lam^2)``:
    the pair's essential matrix is ``[s]x R`` with ``s = t0 + lam w + R o1 - o2``,
    affine in lam inside the Sampson numerator and gradients."""
    d1 = rays.dirs1 / np.linalg.norm(rays.dirs1, axis=1, keepdims=True)
    d2 = rays.dirs2 / np.linalg.norm(rays.dirs2, axis=1, keepdims=True)
    rd1 = d1 @ R.T
    s0 = t0 + rays.origins1 @ R.T - rays.origins2

    def tangent(v, d):
        return v - _rows(v, d)[:, None] * d

    g0, g1 = np.cross(s0, rd1), np.cross(w, rd1)
    pg0, pg1 = tangent(g0, d2), tangent(g1, d2)
    pk0, pk1 = tangent(np.cross(d2, s0), rd1), tangent(np.cross(d2, w), rd1)
    return (_rows(d2, g0), _rows(d2, g1), _rows(pg0, pg0) + _rows(pk0, pk0),
            _rows(pg0, pg1) + _rows(pk0, pk1), _rows(pg1, pg1) + _rows(pk1, pk1))


def _reference(rays, R, t0, w, threshold, perm, samples, prob):
    """The numpy implementation the C kernel replaced (batches of 16, adaptive
    stop, two weighted least-squares rounds kept while the score improves)."""
    a, b, A, B, C = _terms(rays, R, t0, w)
    valid = (np.abs(b) > 1e-9 * (1.0 + np.abs(a))) & (a * b < 0.0)
    order = np.array([k for k in perm if valid[k]][:samples], dtype=int)
    if order.size == 0:
        return None
    thr2 = threshold ** 2

    def r2(lam):
        return (a + lam * b) ** 2 / np.maximum(A + 2.0 * lam * B + lam * lam * C, 1e-300)

    lam, best, inl, used = 0.0, np.inf, None, 0
    while used < order.size:
        pick = order[used:used + 16]
        used += pick.size
        scores = [np.minimum(r2(-a[j] / b[j]), thr2).sum() for j in pick]
        k = int(np.argmin(scores))
        if scores[k] < best:
            lam, best = -a[pick[k]] / b[pick[k]], scores[k]
            inl = r2(lam) < thr2
        ratio = inl.mean()
        needed = np.log1p(-prob) / np.log1p(-ratio) if 0 < ratio < 1 else (
            1.0 if ratio >= 1 else np.inf)
        if used >= needed:
            break
    for _ in range(2):
        wts = 1.0 / np.maximum(A + 2.0 * lam * B + lam * lam * C, 1e-300)
        bb = np.sum(wts[inl] * b[inl] ** 2)
        if not bb > 0:
            break
        cand = -np.sum(wts[inl] * a[inl] * b[inl]) / bb
        if not cand > 0:
            break
        sc = np.minimum(r2(cand), thr2).sum()
        if not sc < best:
            break
        lam, best, inl = cand, sc, r2(cand) < thr2
    return lam, best, int(np.count_nonzero(inl))


def _problem(seed: int, outliers: float = 0.3, noise: float = 0.5):
    """Other-camera correspondences of a 6-camera ring of radius 1 m (wide
    enough for the scale to be well observed) with the line of translations of
    camera 0 (the true R, t0 = c - R c, w towards the true t)."""
    rng = np.random.default_rng(seed)
    rig = synth.ring_rig(6, 1.0, 500.0)
    R = synth.random_rotation(rng, 0.3)
    t = rng.normal(size=3)
    p = synth.make_problem(rig, R, t, 300, rng, pixel_noise=noise, outlier_fraction=outliers)
    rays = rig.ray_pairs(p.pixels1, p.pixels2, p.cam1, p.cam2)
    c = rig.centres[0]
    t0 = c - R @ c
    lam_true = np.linalg.norm(t - t0)
    w = (t - t0) / lam_true
    others = np.flatnonzero(~((rays.cam1 == 0) & (rays.cam2 == 0)))
    return rays.take(others), R, t0, w, lam_true, rng


@pytest.mark.parametrize("seed", range(12))
def test_matches_numpy_reference(seed):
    rays, R, t0, w, lam_true, rng = _problem(seed)
    perm = rng.permutation(len(rays))
    thr = 1.0 / 500.0
    ref = _reference(rays, R, t0, w, thr, perm, 64, 0.999)
    got = _core.scale_ransac(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, R, t0, w,
                             perm, thr, 0.999, 64)
    assert ref is not None and got is not None
    assert got[0] == pytest.approx(ref[0], rel=1e-9)
    assert got[1] == pytest.approx(ref[1], rel=1e-9)
    assert got[2] == ref[2]
    # and the scale is the truth's to the noise (0.5 px on a 1 m ring: the
    # 1-point estimate is within 1 % on most seeds, 20 % on the worst)
    assert abs(got[0] / lam_true - 1.0) < 0.3


def test_score_is_msac_of_gec_residuals():
    rays, R, t0, w, _, rng = _problem(3)
    thr = 2e-3
    lam, score, m = _core.scale_ransac(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, R,
                                       t0, w, rng.permutation(len(rays)), thr)
    r = _core.gec_residuals(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, R,
                            t0 + lam * w)
    assert score == pytest.approx(np.minimum(r ** 2, thr ** 2).sum(), rel=1e-9)
    assert m == np.count_nonzero(np.abs(r) < thr)


def test_no_positive_proposal_is_none():
    rays, R, t0, w, _, rng = _problem(1)
    perm = rng.permutation(len(rays))
    args = (rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, R, t0)
    assert _core.scale_ransac(*args, np.zeros(3), perm, 1e-3) is None
    assert _core.scale_ransac(*args, w, np.zeros(0, int), 1e-3) is None


@pytest.mark.parametrize("change, match", [
    (dict(threshold=0.0), "threshold"),
    (dict(prob=1.0), "prob"),
    (dict(max_proposals=0), "max_proposals"),
    (dict(order=np.array([0, 10 ** 6])), "order"),
    (dict(order=np.array([0.5])), "order"),
    (dict(t0=np.array([0.0, np.nan, 0.0])), "t0 contains NaN"),
    (dict(dirs2="zero"), "zero-length"),
])
def test_bad_input_names_the_problem(change, match):
    rays, R, t0, w, _, rng = _problem(2)
    kw = dict(origins1=rays.origins1, dirs1=rays.dirs1, origins2=rays.origins2,
              dirs2=rays.dirs2, R=R, t0=t0, w=w, order=rng.permutation(len(rays)),
              threshold=1e-3, prob=0.999, max_proposals=64)
    kw.update(change)
    if isinstance(kw["dirs2"], str):
        kw["dirs2"] = rays.dirs2.copy()
        kw["dirs2"][5] = 0.0
    with pytest.raises(ValueError, match=match):
        _core.scale_ransac(**kw)


def test_five_plus_one_uses_it():
    """The proposer's scale search returns the reference's answer for its order."""
    rays, R, t0, w, lam_true, _ = _problem(4)
    lam = fpo.scale_one_point_ransac(rays, R, t0, w, 1.0 / 500.0, np.random.default_rng(0))
    # (its random order: the correspondences that propose a positive scale, shuffled)
    a, b = _terms(rays, R, t0, w)[:2]
    ok = np.flatnonzero((np.abs(b) > 1e-9 * (1.0 + np.abs(a))) & (a * b < 0.0))
    perm = np.random.default_rng(0).permutation(ok)
    ref = _reference(rays, R, t0, w, 1.0 / 500.0, perm, 64, 0.999)
    assert lam == pytest.approx(ref[0], rel=1e-9)
    assert abs(lam / lam_true - 1.0) < 0.3
