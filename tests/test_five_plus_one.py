"""The 5+1 method (thesis ch. 7): eq. 7.4 in our convention, the minimal solver,
the critical configuration (Theorem 3) and the estimator on all correspondences."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import mcgeom
from mcgeom import metrics, synth
from mcgeom.errors import DegenerateError
from mcgeom.estimators import five_plus_one_minimal as minimal
from problems import rot_err

SETTINGS = settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
seeds = st.integers(min_value=0, max_value=2**31 - 1)


def _motion(rng, min_angle=0.05, max_angle=0.4, t_norm=1.0):
    R = synth.random_rotation(rng, max_angle)
    while metrics.rotation_error(R, np.eye(3)) < min_angle:
        R = synth.random_rotation(rng, max_angle)
    t = rng.normal(size=3)
    return R, t * t_norm / np.linalg.norm(t)


def _problem(seed, n=60, rig=None, **kw):
    rng = np.random.default_rng(seed)
    rig = rig or synth.generic_rig(4, rng)
    R, t = _motion(rng)
    return synth.make_problem(rig, R, t, n, rng, require_visible=False, **kw)


def test_eq_7_4_terms_vanish_at_the_true_scale():
    p = _problem(1)
    R, t = p.R, p.t
    a_cam = 0
    c = p.rig.centres[a_cam]
    t0 = c - R @ c
    lam = np.linalg.norm(t - t0)
    w = (t - t0) / lam
    a, b = minimal.scale_terms(p.rays, R, t0, w)
    assert np.abs(a + lam * b).max() < 1e-12
    # the 5-point camera's own correspondences carry no scale information (a = 0)
    own = (p.rays.cam1 == a_cam) & (p.rays.cam2 == a_cam)
    assert np.abs(a[own]).max() < 1e-12


def test_minimal_sample_recovers_motion_exactly():
    p = _problem(2)
    idx = minimal.sample_five_plus_one(p.rays, np.random.default_rng(0))
    sols = minimal.minimal_solutions(p.rays.take(idx))
    assert sols
    best = min(sols, key=lambda s: rot_err(s[0], p.R) + np.linalg.norm(s[1] - p.t))
    assert rot_err(best[0], p.R) < 1e-8
    assert np.linalg.norm(best[1] - p.t) < 1e-8 * np.linalg.norm(p.t)


@SETTINGS
@given(seed=seeds)
def test_estimator_exact_on_noise_free_data(seed):
    p = _problem(seed)
    m = mcgeom.estimate(p.rays, "five_plus_one")
    assert rot_err(m.R, p.R) < 1e-8
    assert np.linalg.norm(m.t - p.t) < 1e-8 * np.linalg.norm(p.t)
    assert m.scale.observable
    assert np.isfinite(m.scale.critical_angle) and m.scale.critical_angle > 0


def test_any_camera_can_be_the_five_point_camera():
    p = _problem(3, n=80)
    for a in range(len(p.rig.cameras)):
        m = mcgeom.estimate(p.rays, "five_plus_one", five_camera=a)
        assert m.info["five_camera"] == a
        assert rot_err(m.R, p.R) < 1e-8


def test_critical_angle_is_zero_without_rotation():
    rig = synth.generic_rig(4, np.random.default_rng(4))
    ang = minimal.critical_angles(np.eye(3), np.array([0.3, 0.1, 0.0]), rig.centres, 0)
    assert np.nanmax(ang) < 1e-12
    R = synth.rotation_about([0, 0, 1], 0.2)
    ang = minimal.critical_angles(R, np.array([0.3, 0.1, 0.0]), rig.centres, 0)
    assert np.nanmax(ang) > 0.01


def test_theorem_3_axis_perpendicular_to_plane_of_centres_is_critical():
    """Theorem 3: rotation about the normal of the plane (C2, C1', C1) is critical.

    Here the rig moves in the plane of the camera centres and rotates about its
    normal such that camera b's displacement stays parallel to camera a's."""
    ca, cb = np.zeros(3), np.array([1.0, 0.0, 0.0])
    # choose (R, t) so that both displacements R^T (c - t) - c are along x:
    # R^T (cb - t) - cb = R^T (ca - t) - ca + (R^T - I) cb  ->  (R^T - I) cb || x
    # only if (R^T - I) cb || displacement of ca: take the displacement along it.
    R = synth.rotation_about([0, 0, 1], 0.1)
    d_rel = (R.T - np.eye(3)) @ cb
    t = -R @ (5.0 * d_rel)          # camera a displaces by 5 d_rel
    ang = minimal.critical_angles(R, t, np.stack([ca, cb]), 0)
    assert ang[1] < 1e-9


def test_no_rotation_is_reported_scale_unobservable_with_direction():
    rng = np.random.default_rng(5)
    rig = synth.generic_rig(4, rng)
    t = np.array([0.4, -0.1, 0.2])
    p = synth.make_problem(rig, np.eye(3), t, 80, rng, require_visible=False,
                           angular_noise=1e-4)
    m = mcgeom.estimate(p.rays, "five_plus_one")
    assert not m.scale.observable
    assert "critical" in m.scale.reason or "uncertain" in m.scale.reason
    assert rot_err(m.R, np.eye(3)) < 1e-3
    assert abs(np.linalg.norm(m.t) - 1.0) < 1e-12
    assert np.degrees(np.arccos(np.clip(m.t @ t / np.linalg.norm(t), -1, 1))) < 1.0


def test_cross_camera_correspondences_fix_the_scale_without_rotation():
    rng = np.random.default_rng(6)
    rig = synth.generic_rig(4, rng)
    t = np.array([0.4, -0.1, 0.2])
    p = synth.make_problem(rig, np.eye(3), t, 120, rng, require_visible=False,
                           cross_fraction=0.3)
    m = mcgeom.estimate(p.rays, "five_plus_one")
    assert m.scale.observable
    assert np.linalg.norm(m.t - t) < 1e-8


def test_single_camera_has_no_scale():
    p = _problem(7)
    one = (p.rays.cam1 == 0) & (p.rays.cam2 == 0)
    m = mcgeom.estimate(p.rays.take(one), "five_plus_one")
    assert not m.scale.observable
    assert "one camera" in m.scale.reason


@pytest.mark.parametrize("bad", ["few", "nan", "no_camera_with_5", "camera_id"])
def test_bad_input_is_named(bad):
    p = _problem(8)
    rays = p.rays
    if bad == "few":
        with pytest.raises(ValueError, match="too few"):
            mcgeom.estimate(rays.take(np.arange(5)), "five_plus_one")
    elif bad == "nan":
        d = rays.dirs1.copy()
        d[3, 1] = np.nan
        with pytest.raises(ValueError, match="NaN"):
            mcgeom.estimate(mcgeom.RayPairs(rays.origins1, d, rays.origins2, rays.dirs2,
                                            rays.cam1, rays.cam2), "five_plus_one")
    elif bad == "no_camera_with_5":
        pick = np.concatenate([np.flatnonzero(rays.cam1 == k)[:4] for k in range(4)])
        with pytest.raises(ValueError, match="5 intra-camera"):
            mcgeom.estimate(rays.take(pick), "five_plus_one")
    else:
        with pytest.raises(ValueError, match="five_camera"):
            mcgeom.estimate(rays, "five_plus_one", five_camera=9)


def test_degenerate_sample_raises_or_returns_nothing():
    """Five identical correspondences carry no essential matrix."""
    p = _problem(9)
    own = np.flatnonzero((p.rays.cam1 == 0) & (p.rays.cam2 == 0))
    other = np.flatnonzero(p.rays.cam1 == 1)[:1]
    idx = np.concatenate([np.repeat(own[:1], 5), other])
    try:
        sols = minimal.minimal_solutions(p.rays.take(idx))
    except DegenerateError:
        return
    for R, t in sols:   # whatever comes back must not claim the true motion by chance
        assert np.all(np.isfinite(R)) and np.all(np.isfinite(t))
