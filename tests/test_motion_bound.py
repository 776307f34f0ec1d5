"""The Cramer-Rao bound of mcgeom.experiments.motion_bound, checked against
what it claims to be: the spread of an estimator that attains it (linear17's
Sampson optimum, which is at the bound on these problems) over many noise
draws of ONE geometry -- an independent route to the same number -- and the
median of a Gaussian mixture; and its refusals."""

from __future__ import annotations

import math

import numpy as np
import pytest

import mcgeom
from mcgeom import metrics, synth
from mcgeom.experiments.motion_bound import median_abs_error, motion_bound


def _draws(p, pixel: float, angular: float, k: int, seed: int):
    """|t| / |t_true| - 1 and the rotation error vector (rad) of linear17 on
    ``k`` fresh noise draws of the geometry of ``p``."""
    rng = np.random.default_rng(seed)
    px1 = np.empty((len(p), 2))
    px2 = np.empty((len(p), 2))
    X2 = p.points @ p.R.T + p.t
    for cam in np.unique(p.cam1):
        sel = p.cam1 == cam
        px1[sel] = p.rig.camera(int(cam)).project(p.points[sel])[0]
        px2[sel] = p.rig.camera(int(cam)).project(X2[sel])[0]
    scale, rot = [], []
    for _ in range(k):
        q1 = px1 + rng.normal(0.0, pixel, px1.shape) if pixel else px1
        q2 = px2 + rng.normal(0.0, pixel, px2.shape) if pixel else px2
        rays = p.rig.ray_pairs(q1, q2, p.cam1, p.cam2)
        if angular:
            d1 = synth.perturb_directions(rays.dirs1, angular, rng)
            d2 = synth.perturb_directions(rays.dirs2, angular, rng)
            rays = mcgeom.RayPairs(rays.origins1, d1, rays.origins2, d2, rays.cam1, rays.cam2)
        m = mcgeom.estimate(rays, "linear17")
        scale.append(np.linalg.norm(m.info["t_metric"]) / np.linalg.norm(p.t) - 1.0)
        dR = m.R @ p.R.T
        ang = metrics.rotation_error(m.R, p.R)
        axis = np.array([dR[2, 1] - dR[1, 2], dR[0, 2] - dR[2, 0], dR[1, 0] - dR[0, 1]])
        rot.append(ang * axis / max(np.linalg.norm(axis), 1e-300))
    return np.array(scale), np.array(rot)


@pytest.mark.parametrize("kind", ["pixel", "angular"])
def test_bound_is_the_spread_of_an_estimator_that_attains_it(kind):
    rng = np.random.default_rng(5)
    if kind == "pixel":
        rig, pixel, angular = synth.ring_rig(4, 0.25, 500.0), 0.5, 0.0
    else:
        rig, pixel, angular = synth.generic_rig(6, rng), 0.0, float(np.deg2rad(0.05))
    R, t = synth.random_motion(rng, max_angle=0.3, t_norm=1.0)
    p = synth.make_problem(rig, R, t, 200, rng)
    b = motion_bound(p, pixel_noise=pixel, angular_noise=angular)
    scale, rot = _draws(p, pixel, angular, 400, seed=11)
    # the std of a std from 400 draws is ~3.5 %: the estimator's spread is
    # the bound's within sampling (0.9 .. 1.15), in |t| and in rotation
    assert 0.9 < np.std(scale) / b.scale_rel_std < 1.15, (np.std(scale), b.scale_rel_std)
    assert 0.85 < np.mean(np.sum(rot ** 2, axis=1)) / np.trace(b.covariance[:3, :3]) < 1.2
    # bias well under the spread: the bound of an unbiased estimator applies
    assert abs(np.mean(scale)) < 0.2 * b.scale_rel_std


def test_the_bound_scales_with_the_noise_and_the_draws_follow_it():
    rng = np.random.default_rng(2)
    R, t = synth.random_motion(rng, max_angle=0.3, t_norm=1.0)
    p = synth.make_problem(synth.ring_rig(4, 0.25, 500.0), R, t, 120, rng)
    b1, b2 = motion_bound(p, pixel_noise=0.5), motion_bound(p, pixel_noise=1.0)
    assert b2.scale_rel_std == pytest.approx(2.0 * b1.scale_rel_std, rel=1e-4)
    np.testing.assert_allclose(b2.covariance, 4.0 * b1.covariance, rtol=1e-3,
                               atol=1e-6 * np.abs(b2.covariance).max())
    e = b1.rotation_errors_deg(20000, np.random.default_rng(0))
    assert np.mean(np.radians(e) ** 2) == pytest.approx(np.trace(b1.covariance[:3, :3]), rel=0.05)


def test_median_abs_error_of_a_gaussian_mixture():
    q75 = 0.6744897501960817     # the median of |N(0, 1)|
    assert median_abs_error(np.full(7, 0.02)) == pytest.approx(q75 * 0.02, rel=1e-9)
    stds = np.array([0.01, 0.03, 0.1])
    e = np.random.default_rng(0).normal(size=(200000, 3)) * stds
    assert median_abs_error(stds) == pytest.approx(np.median(np.abs(e)), rel=0.01)
    for bad in ([], [0.0, 1.0], [np.nan], [-1.0]):
        with pytest.raises(ValueError, match="positive numbers"):
            median_abs_error(np.array(bad))
    # a problem that fixes nothing: an error above any bound
    assert median_abs_error(np.array([0.01, np.inf, 0.01])) > median_abs_error(
        np.full(3, 0.01))
    assert median_abs_error(np.array([0.01, np.inf])) == np.inf


def test_refusals_name_what_is_wrong():
    rng = np.random.default_rng(1)
    R, t = synth.random_motion(rng, max_angle=0.3, t_norm=1.0)
    p = synth.make_problem(synth.ring_rig(4, 0.25, 500.0), R, t, 40, rng)
    for kw in ({}, {"pixel_noise": 0.5, "angular_noise": 1e-3}, {"pixel_noise": -1.0}):
        with pytest.raises(ValueError, match="exactly one of pixel_noise"):
            motion_bound(p, **kw)
    # one camera: a central camera, whose |t| no correspondence fixes
    one = synth.make_problem(synth.ring_rig(1, 0.25, 500.0), R, t, 40, rng)
    with pytest.raises(ValueError, match="do not fix the motion"):
        motion_bound(one, pixel_noise=0.5)
    assert math.isfinite(motion_bound(p, pixel_noise=0.5).scale_rel_std)


def test_a_subset_of_the_pairs_bounds_less_tightly():
    rng = np.random.default_rng(4)
    R, t = synth.random_motion(rng, max_angle=0.3, t_norm=1.0)
    p = synth.make_problem(synth.ring_rig(4, 0.25, 500.0), R, t, 120, rng, outlier_fraction=0.25)
    every = motion_bound(p, pixel_noise=0.5)
    np.testing.assert_array_equal(motion_bound(p, pixel_noise=0.5,
                                               use=np.ones(len(p), bool)).covariance,
                                  every.covariance)
    inl = motion_bound(p, pixel_noise=0.5, use=p.inlier)
    # fewer pairs, less information: the inliers' bound is the wider one
    assert inl.scale_rel_std > every.scale_rel_std
    assert np.all(np.linalg.eigvalsh(inl.covariance - every.covariance) > -1e-12)
    with pytest.raises(ValueError, match="boolean mask of the 120"):
        motion_bound(p, pixel_noise=0.5, use=p.inlier[:10])
