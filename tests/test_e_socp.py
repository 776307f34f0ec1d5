"""E+SOCP (thesis ch. 9): rotation averaging, the L-infinity translation, the
known failure mode (near-zero rotation) and the ch. 10.5.1 set-up."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import mcgeom
from mcgeom import metrics, synth
from mcgeom.estimators.e_socp import average_rotations
from problems import rot_err
from mcgeom.experiments import ch9 as experiment_ch9


def test_chordal_mean_of_rotations():
    rng = np.random.default_rng(0)
    R = synth.random_rotation(rng, np.pi)
    Rs = np.stack([synth.random_rotation(rng, 0.01) @ R for _ in range(20)])
    mean, spread = average_rotations(Rs)
    assert rot_err(mean, R) < 0.005
    assert spread.shape == (20,) and np.all(spread < 0.02)
    same, zero = average_rotations(np.stack([R, R, R]))
    assert rot_err(same, R) < 1e-12 and np.all(zero < 1e-7)


def _problem(seed, R=None, noise=0.0, n=200):
    rng = np.random.default_rng(seed)
    rig = experiment_ch9.rig4()
    if R is None:
        R = synth.random_rotation(rng, np.radians(20))
    t = np.array([0.6, -0.3, 0.2])
    return synth.make_problem(rig, R, t, n, rng, pixel_noise=noise)


def test_reports_socp_residual_and_rotation_angle():
    p = _problem(1, noise=0.3)
    m = mcgeom.estimate(p.rays, "e_socp")
    assert m.info["socp_residual"] > 0 and m.info["socp_residual"] >= m.info["socp_lower_bound"]
    assert abs(m.info["rotation_angle"] - metrics.rotation_error(p.R, np.eye(3))) < 1e-3
    assert len(m.info["cameras"]) == 4 and m.info["rotation_spread"].shape == (4,)
    assert rot_err(m.R, p.R) < np.radians(0.1)


def test_near_zero_rotation_translation_is_unreliable_and_said_so():
    """Ch. 9.5: with (almost) no rotation every half-line starts at the same
    apex, the SOCP cannot fix |t|: the verdict must say the scale is unknown."""
    p = _problem(2, R=synth.rotation_about([0, 0, 1], np.radians(0.01)), noise=0.3)
    m = mcgeom.estimate(p.rays, "e_socp")
    assert m.info["rotation_angle"] < np.radians(0.1)
    assert not m.scale.observable
    assert abs(np.linalg.norm(m.t) - 1.0) < 1e-12
    # the direction is still right
    assert np.degrees(np.arccos(np.clip(m.t @ p.t / np.linalg.norm(p.t), -1, 1))) < 2.0


def test_single_camera_gives_direction_only():
    p = _problem(3)
    one = p.rays.take(np.flatnonzero(p.rays.cam1 == 0))
    m = mcgeom.estimate(one, "e_socp")
    assert not m.scale.observable
    assert rot_err(m.R, p.R) < 1e-8


def test_bad_input():
    p = _problem(4)
    with pytest.raises(ValueError, match="too few"):
        mcgeom.estimate(p.rays.take(np.arange(3)), "e_socp")


def test_ch10_5_1_errors_grow_with_noise_and_stay_bounded():
    res = experiment_ch9.run(runs=4, levels=(0.0, 0.5))
    print("\n" + experiment_ch9.table(res))
    for name, e in res[0.0].items():
        assert np.nanmax(e[:, 0]) < 1e-6 and np.nanmax(np.abs(e[:, 2] - 1)) < 1e-6, name
    for name, e in res[0.5].items():
        assert np.nanmean(e[:, 0]) < 0.1 and np.nanmean(e[:, 3]) < 0.1, name


def test_runs_through_the_opencv_facade():
    rng = np.random.default_rng(5)
    rig = experiment_ch9.rig4()
    R = synth.rotation_about([0.3, 1.0, 0.2], np.radians(15))
    t = np.array([0.5, 0.2, 0.1])
    p = synth.make_problem(rig, R, t, 200, rng, pixel_noise=0.3, outlier_fraction=0.1)
    m = mcgeom.cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, rig, method="e_socp")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        retval, Re, te, mask = mcgeom.estimateRigMotion(p.pixels1, p.pixels2, p.cam1, p.cam2,
                                                        rig, method="e_socp")
    # the OpenCV-style call warns exactly when its t is no metric estimate
    warned = [w for w in caught if issubclass(w.category, mcgeom.ScaleNotObservableWarning)]
    assert bool(warned) == (not m.scale.observable and bool(np.any(m.t != 0)))
    assert rot_err(Re, R) < np.radians(0.1)
    if m.scale.observable:
        assert np.linalg.norm(te.ravel() - t) < 0.1 * np.linalg.norm(t)
