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


# --- trajectory metrics (issue 17) and their agreement with evo ----------------

def _trajectory(n: int, seed: int) -> np.ndarray:
    """A world_from_rig ground truth of n poses: a car-like drive of ~1 m steps
    with turns and some pitch/roll, first pose the identity."""
    rng = np.random.default_rng(seed)
    steps = [odometry.to_matrix(synth.rotation_about(rng.normal(size=3) * [0.02, 0.02, 1.0],
                                                     rng.normal(0.0, 0.08)),
                                [rng.normal(0, 0.05), rng.normal(0, 0.05), -1.0])
             for _ in range(n - 1)]
    return np.asarray(odometry.chain(steps))


def _noisy(gt: np.ndarray, seed: int, scale: float = 1.0) -> np.ndarray:
    """An estimate: the truth with drifting rotation and position errors, a scale
    error, expressed in another world frame (a rigid transform away)."""
    rng = np.random.default_rng(seed)
    est = gt.copy()
    est[:, :3, 3] *= scale
    drift = np.eye(4)
    for k in range(1, len(gt)):
        drift = drift @ odometry.to_matrix(synth.rotation_about(rng.normal(size=3), 0.004),
                                           rng.normal(0.0, 0.03, 3))
        est[k] = est[k] @ drift
    other_world = odometry.to_matrix(synth.rotation_about((1, 2, 3), 0.7), [5.0, -3.0, 2.0])
    return other_world @ est


@pytest.fixture
def evo_pair(tmp_path):
    """(est, gt) as our reader reads them back and as evo reads the same TUM files."""
    file_interface = pytest.importorskip("evo.tools.file_interface")
    from mcgeom.io import trajectory as tio
    gt = _trajectory(40, seed=5)
    est = _noisy(gt, seed=6, scale=1.03)
    ts = 0.1 * np.arange(len(gt))
    tio.write_tum(tmp_path / "gt.txt", gt, ts)
    tio.write_tum(tmp_path / "est.txt", est, ts)
    ours = (tio.read_tum(tmp_path / "est.txt")[1], tio.read_tum(tmp_path / "gt.txt")[1])
    evos = (file_interface.read_tum_trajectory_file(str(tmp_path / "est.txt")),
            file_interface.read_tum_trajectory_file(str(tmp_path / "gt.txt")))
    return ours, evos


def test_ate_agrees_with_evo(evo_pair):
    from evo.core import metrics as evo_metrics
    (est, gt), (evo_est, evo_gt) = evo_pair
    evo_est.align(evo_gt, correct_scale=False)
    ape = evo_metrics.APE(evo_metrics.PoseRelation.translation_part)
    ape.process_data((evo_gt, evo_est))
    ours = metrics.absolute_trajectory_error(est, gt)
    stats = ape.get_all_statistics()
    for key in ("rmse", "mean", "median", "max", "std"):
        assert ours[key] == pytest.approx(stats[key], rel=1e-9), key
    np.testing.assert_allclose(ours["errors"], ape.error, rtol=1e-9)
    np.testing.assert_allclose(ours["aligned"], np.asarray(evo_est.poses_se3), atol=1e-9)
    assert ours["rmse"] > 0.1   # a real error was measured, not a trivial agreement


@pytest.mark.parametrize("delta", [1, 3])
def test_rpe_agrees_with_evo(evo_pair, delta):
    from evo.core import metrics as evo_metrics
    from evo.core.units import Unit
    (est, gt), (evo_est, evo_gt) = evo_pair
    ours = metrics.relative_pose_error(est, gt, delta=delta)
    for relation, key in ((evo_metrics.PoseRelation.translation_part, "translation"),
                          (evo_metrics.PoseRelation.rotation_angle_deg, "rotation_deg")):
        rpe = evo_metrics.RPE(relation, delta=delta, delta_unit=Unit.frames, all_pairs=True)
        rpe.process_data((evo_gt, evo_est))
        np.testing.assert_allclose(ours[key], rpe.error, rtol=1e-9)
        stats = rpe.get_all_statistics()
        suffix = "" if key == "translation" else "_deg"
        name = "translation" if key == "translation" else "rotation"
        assert ours[f"{name}_rmse{suffix}"] == pytest.approx(stats["rmse"], rel=1e-9)
        assert ours[f"{name}_mean{suffix}"] == pytest.approx(stats["mean"], rel=1e-9)
    assert len(ours["pairs"]) == len(est) - delta


def test_scale_drift_agrees_with_evo_path_lengths(evo_pair):
    (est, gt), (evo_est, evo_gt) = evo_pair
    expected = 100.0 * (evo_est.path_length / evo_gt.path_length - 1.0)
    assert metrics.scale_drift(est, gt) == pytest.approx(expected, rel=1e-9)
    assert metrics.path_length(gt) == pytest.approx(evo_gt.path_length, rel=1e-9)


def test_alignment_recovers_a_rigid_transform_and_never_the_scale():
    gt = _trajectory(25, seed=7)
    A = odometry.to_matrix(synth.rotation_about((0.3, -1, 0.2), 2.5), [10.0, 4.0, -1.0])
    moved = A @ gt
    R, t = metrics.align_se3(moved[:, :3, 3], gt[:, :3, 3])
    np.testing.assert_allclose(R, A[:3, :3].T, atol=1e-12)
    np.testing.assert_allclose(t, -A[:3, :3].T @ A[:3, 3], atol=1e-11)
    assert metrics.absolute_trajectory_error(moved, gt)["rmse"] < 1e-11
    # 2 % too long: SE(3) alignment keeps the error (a Sim(3) one would remove it)
    long = moved.copy()
    long[:, :3, 3] *= 1.02
    ate = metrics.absolute_trajectory_error(long, gt)
    assert ate["rmse"] > 0.01 * 0.2 * metrics.path_length(gt) / 2
    assert metrics.scale_drift(long, gt) == pytest.approx(2.0, rel=1e-12)


def test_rpe_of_a_known_step_error():
    gt = _trajectory(6, seed=8)
    est = gt.copy()
    # the step 2 -> 3 is 10 cm too long along its own direction; later poses follow
    Q = np.linalg.inv(gt[2]) @ gt[3]
    step = Q.copy()
    step[:3, 3] *= 1.0 + 0.1 / np.linalg.norm(Q[:3, 3])
    for k in range(3, 6):
        est[k] = est[2] @ step @ np.linalg.inv(gt[3]) @ gt[k]
    rpe = metrics.relative_pose_error(est, gt)
    np.testing.assert_allclose(rpe["translation"], [0, 0, 0.1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(rpe["rotation_deg"], 0, atol=1e-9)
    assert rpe["length_ratio"][2] == pytest.approx(1 + 0.1 / np.linalg.norm(Q[:3, 3]))


def test_degenerate_alignments_still_give_the_least_squares_error():
    # a straight line (collinear positions: evo refuses) and a static rig
    line = np.tile(np.eye(4), (5, 1, 1))
    line[:, 2, 3] = np.arange(5.0)
    assert metrics.absolute_trajectory_error(line, line)["rmse"] < 1e-12
    static = np.tile(np.eye(4), (4, 1, 1))
    ate = metrics.absolute_trajectory_error(static, static)
    assert ate["rmse"] == 0.0 and np.isnan(ate["rmse_percent"])
    with pytest.raises(ValueError, match="do not move"):
        metrics.scale_drift(static, static)


@pytest.mark.parametrize("call, message", [
    (lambda g: metrics.absolute_trajectory_error(g[:3], g), r"3 poses and gt_poses 5"),
    (lambda g: metrics.relative_pose_error(g, g, delta=5), r"delta must be in \[1, 4\]"),
    (lambda g: metrics.relative_pose_error(g, g, delta=1.5), r"delta must be an integer"),
    (lambda g: metrics.scale_drift(g[0], g[0]), r"got one \(4, 4\) matrix"),
    (lambda g: metrics.align_se3(g[:, :3, 3], g[:4, :3, 3]), r"same non-empty \(N, 3\)"),
    (lambda g: metrics.absolute_trajectory_error(g * np.array([1, 1, 1, np.nan])[None, :, None], g),
     r"est_poses has 5 pose\(s\) with non-finite"),
])
def test_trajectory_metrics_refuse_bad_input(call, message):
    with pytest.raises(ValueError, match=message):
        call(_trajectory(5, seed=9))
