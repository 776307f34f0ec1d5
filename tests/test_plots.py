"""mcgeom.plots: the trajectory PNG is written whole, at its documented size, in
every configuration (with/without ground truth, with a direction-only segment),
and bad arguments are refused before anything is written."""

from __future__ import annotations

import os

import cv2
import numpy as np
import pytest

from mcgeom import metrics, odometry, plots, synth


def _loop(n: int = 21) -> np.ndarray:
    """World_from_rig poses of a camera-like rig (y down) driving straight, then turning."""
    steps = [odometry.to_matrix(synth.rotation_about((0, 1, 0), np.radians(9.0) if k >= 10 else 0.0),
                                [0.0, 0.0, -1.0]) for k in range(n - 1)]
    return np.asarray(odometry.chain(steps))


def _estimate(gt: np.ndarray) -> np.ndarray:
    est = gt.copy()
    est[:, :3, 3] *= 1.02
    return est


def _png_size(path) -> tuple[int, int]:
    img = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    assert img is not None, f"{path} is not a readable PNG"
    assert img.std() > 0, "blank image"
    return img.shape[1], img.shape[0]


def _segments(est: np.ndarray) -> list:
    """Metric frames 0..8, direction-only 8..12 (path length 1, no unit), metric 12..20;
    each relative to the position of its first frame."""
    out = []
    for frames, metric in ((np.arange(0, 9), True), (np.arange(8, 13), False),
                           (np.arange(12, 21), True)):
        P = est[frames].copy()
        P[:, :3, 3] -= P[0, :3, 3]
        if not metric:
            P[:, :3, 3] /= metrics.path_length(P)
        out.append(plots.PlotSegment(frames, P, metric))
    return out


def test_with_ground_truth_statuses_and_ate(tmp_path):
    gt = _loop()
    est = _estimate(gt)
    status = ["carried"] * 10 + ["metric"] * 10
    ate = metrics.absolute_trajectory_error(est, gt)
    out = tmp_path / "t.png"
    plots.plot_trajectory(out, est, gt, status, title="loop", ate=ate, frame_offset=13)
    assert _png_size(out) == (1500, 700)
    assert os.listdir(tmp_path) == ["t.png"]       # no temporary file left


def test_without_ground_truth(tmp_path):
    out = tmp_path / "t.png"
    plots.plot_trajectory(out, _loop(), title="estimate only")
    assert _png_size(out) == (900, 800)


def test_with_a_direction_only_segment(tmp_path):
    gt = _loop()
    status = ["metric"] * 8 + ["unknown"] * 4 + ["carried"] * 8
    out = tmp_path / "t.png"
    plots.plot_trajectory(out, _segments(_estimate(gt)), gt, status, plane="xz")
    assert _png_size(out) == (1500, 700)
    out2 = tmp_path / "nogt.png"
    plots.plot_trajectory(out2, _segments(_estimate(gt)), None, status)
    assert _png_size(out2) == (900, 800)


def test_step_errors_from_the_ground_truth_are_the_metric_steps_rpe():
    gt = _loop()
    segs = plots._as_segments(_segments(_estimate(gt)))   # noqa: SLF001 (test of a helper)
    err = plots._step_errors_from_gt(segs, gt, 20)
    assert np.all(np.isnan(err[8:12])) and np.all(np.isfinite(err[:8]))
    np.testing.assert_allclose(err[:8], 0.02, rtol=1e-9)    # 2 % of 1 m steps


def test_the_default_plane_is_the_one_of_largest_extent():
    pts = np.array([[0.0, 0.0, 0.0], [5.0, 0.1, 9.0], [10.0, 0.2, 3.0]])
    assert plots._plane(None, pts) == (0, 2)
    assert plots._plane("zy", pts) == (2, 1)


@pytest.mark.parametrize("kwargs, message", [
    ({"segments": []}, r"non-empty sequence of segments"),
    ({"segments": [object()]}, r"segments\[0\] has no frames/poses/metric"),
    ({"step_status": ["metric"] * 3}, r"one entry per step \(20"),
    ({"step_status": ["observed"] * 20}, r"unknown value\(s\) \['observed'\]"),
    ({"step_errors": np.zeros(5)}, r"step_errors must have shape \(20,\)"),
    ({"plane": "xx"}, r"plane must be None"),
    ({"gt_poses": _loop(), "frame_offset": 1.5}, r"frame_offset must be an integer"),
    ({"gt_poses": np.tile(np.eye(4), (3, 1, 1))}, r"gt_poses has 3 poses but the segments"),
])
def test_bad_arguments_are_refused_and_nothing_is_written(tmp_path, kwargs, message):
    args = {"segments": _loop(), "gt_poses": None, **kwargs}
    with pytest.raises(ValueError, match=message):
        plots.plot_trajectory(tmp_path / "t.png", **args)
    assert os.listdir(tmp_path) == []


def test_a_missing_folder_is_a_value_error(tmp_path):
    with pytest.raises(ValueError, match="does not exist"):
        plots.plot_trajectory(tmp_path / "no" / "t.png", _loop())


def test_pyplot_is_not_imported(tmp_path):
    import subprocess
    import sys
    code = ("import sys, numpy as np; from mcgeom import plots; import tempfile, os; "
            "d = tempfile.mkdtemp(); plots.plot_trajectory(os.path.join(d, 'a.png'), "
            "np.tile(np.eye(4), (2, 1, 1))); print('matplotlib.pyplot' in sys.modules)")
    # run away from the source tree: the installed package is the one under test
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=tmp_path)
    assert out.stdout.strip() == "False"
