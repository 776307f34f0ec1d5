"""The generic minimal 6-point solver (``_core.sixpt``, csrc/sixpt.c), the
``six_point`` estimator and ``robust.ransac(rays, "six_point")``."""

from __future__ import annotations

import numpy as np
import pytest

import mcgeom
from mcgeom import _core, metrics, robust, synth
from mcgeom.errors import DegenerateError
from mcgeom.estimators.six_point import minimal_solutions
from mcgeom.types import RayPairs


def _six(rng, centres, cross=True, R=None):
    R = synth.random_rotation(rng, 0.5) if R is None else R
    t = rng.normal(size=3)
    c1 = np.arange(6) % len(centres)
    c2 = (c1 + 1) % len(centres) if cross else c1
    X = centres[c1] + rng.uniform(2.0, 10.0, (6, 1)) * rng.normal(size=(6, 3))
    o1, o2 = centres[c1], centres[c2]
    return (o1, X - o1, o2, X @ R.T + t - o2), R, t


def test_sixpt_returns_truth_and_only_exact_solutions():
    rng = np.random.default_rng(3)
    for _ in range(3):
        (o1, d1, o2, d2), R, t = _six(rng, 0.5 * rng.normal(size=(6, 3)))
        Rs, ts = _core.sixpt(o1, d1, o2, d2)
        assert Rs.shape[1:] == (3, 3) and ts.shape == (len(Rs), 3)
        assert any(metrics.rotation_error(Ri, R) < 1e-8 and np.linalg.norm(ti - t) < 1e-8 *
                   np.linalg.norm(t) for Ri, ti in zip(Rs, ts))
        for Ri, ti in zip(Rs, ts):
            r = _core.gec_residuals(o1, d1, o2, d2, Ri, ti)
            assert np.abs(r).max() < 1e-8


def test_sixpt_central_camera_has_no_solution():
    rng = np.random.default_rng(4)
    (o1, d1, o2, d2), _, _ = _six(rng, np.zeros((1, 3)), cross=False)
    Rs, ts = _core.sixpt(o1, d1, o2, d2)
    assert len(Rs) == 0 and ts.shape == (0, 3)


def test_sixpt_bad_input_names_the_argument():
    rng = np.random.default_rng(5)
    (o1, d1, o2, d2), _, _ = _six(rng, 0.5 * rng.normal(size=(6, 3)))
    with pytest.raises(ValueError, match="at least 6"):
        _core.sixpt(o1[:5], d1[:5], o2[:5], d2[:5])
    with pytest.raises(ValueError, match="exactly 6"):
        _core.sixpt(np.vstack([o1, o1[:1]]), np.vstack([d1, d1[:1]]), np.vstack([o2, o2[:1]]),
                    np.vstack([d2, d2[:1]]))
    bad = d2.copy()
    bad[2] = 0.0
    with pytest.raises(ValueError, match="dirs2.*zero-length"):
        _core.sixpt(o1, d1, o2, bad)
    bad = o1.copy()
    bad[0, 0] = np.nan
    with pytest.raises(ValueError, match="origins1.*NaN"):
        _core.sixpt(bad, d1, o2, d2)
    with pytest.raises(ValueError, match="minimal sample has 6"):
        minimal_solutions(RayPairs(o1[:5], d1[:5], o2[:5], d2[:5]))


def _problem(seed, n=40, cross=0.5, noise=0.0, outliers=0.0):
    rng = np.random.default_rng(seed)
    R = synth.random_rotation(rng, 0.3)
    t = rng.normal(size=3)
    t *= 0.8 / np.linalg.norm(t)
    p = synth.make_problem(synth.generic_rig(6, rng), R, t, n, rng, cross_fraction=cross,
                           angular_noise=noise, require_visible=False)
    rays = p.rays
    if outliers:
        k = int(outliers * n)
        d2 = rays.dirs2.copy()
        d2[:k] = rng.normal(size=(k, 3))
        rays = RayPairs(rays.origins1, rays.dirs1, rays.origins2, d2)
    return rays, R, t


def test_estimator_recovers_cross_camera_motion():
    rays, R, t = _problem(11, n=12, cross=0.8)
    m = mcgeom.estimate(rays, "six_point")
    assert metrics.rotation_error(m.R, R) < 1e-8
    assert np.linalg.norm(m.t - t) < 1e-8 * np.linalg.norm(t)
    assert m.scale.observable
    assert m.info["start"] == "six_point"


def test_estimator_errors():
    rays, _, _ = _problem(12, n=12)
    with pytest.raises(ValueError, match="at least 6"):
        mcgeom.estimate(rays.take(np.arange(5)), "six_point")
    with pytest.raises(ValueError, match="max_scale_rel_std"):
        mcgeom.estimate(rays, "six_point", max_scale_rel_std=-1.0)


def test_ransac_with_six_point_sampler():
    rays, R, t = _problem(13, n=60, cross=0.5, noise=2e-4, outliers=0.3)
    m = robust.ransac(rays, "six_point", threshold=2e-3, max_iters=60, seed=1)
    assert metrics.rotation_error(m.R, R) < 5e-3
    assert m.inliers[int(0.3 * 60):].mean() > 0.9
    assert m.inliers[:int(0.3 * 60)].mean() < 0.2
