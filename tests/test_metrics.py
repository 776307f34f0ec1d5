"""mcgeom.metrics: the motion and trajectory errors (radians, metres)."""

from __future__ import annotations

import numpy as np
import pytest

from mcgeom import metrics, odometry, synth


def test_motion_errors_of_a_known_perturbation():
    R = synth.rotation_about((0, 0, 1), 0.2)
    M_true = odometry.to_matrix(R, [1.0, 0.0, 0.0])
    M_est = odometry.to_matrix(synth.rotation_about((0, 0, 1), 0.25), [2.0, 2.0, 0.0])
    e = metrics.motion_errors(M_est, M_true)
    assert e["rot_err"] == pytest.approx(0.05, abs=1e-14)
    assert e["dir_err"] == pytest.approx(np.pi / 4, abs=1e-14)
    assert e["scale_ratio"] == pytest.approx(np.sqrt(8.0), abs=1e-14)
    assert e["t_err"] == pytest.approx(np.sqrt(5.0), abs=1e-14)


def test_loop_closure_error_of_a_closed_and_an_open_chain():
    step = odometry.to_matrix(synth.rotation_about((0, 0, 1), np.pi / 2), [0.0, -1.0, 0.0])
    poses = odometry.chain([step] * 4)
    gap_m, gap_rad = metrics.loop_closure_error(poses)
    assert gap_m < 1e-12 and gap_rad < 1e-12
    gap_m, gap_rad = metrics.loop_closure_error(poses[:-1])
    assert gap_m == pytest.approx(1.0, abs=1e-12)
    assert gap_rad == pytest.approx(np.pi / 2, abs=1e-12)


def test_rotation_angle_is_accurate_near_zero():
    assert metrics.rotation_angle(synth.rotation_about((1, 1, 0), 1e-10)) == pytest.approx(
        1e-10, rel=1e-6)


def test_odometry_keeps_its_public_names():
    for name in ("rotation_angle", "motion_errors", "loop_closure_error"):
        assert getattr(odometry, name) is getattr(metrics, name)
