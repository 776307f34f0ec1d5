"""Files of a sequence run (``mcgeom odometry``, ``mcgeom demo``): trajectories
in the formats the field's tools read, the steps with their scale status, the
errors against ground truth, and the plot.

Everything is written into a fresh folder beside ``out`` and moved into place
at the end, so that an interrupted or failed run leaves no half-written
output (an existing ``out`` is replaced only once the new one is complete).

* ``trajectory_tum.txt``: TUM (``timestamp tx ty tz qx qy qz qw``,
  world_from_rig, world = the rig frame of the first frame) of the frames
  whose position is known in metres; frames behind a direction-only segment
  are left out, never written with a guessed scale;
* ``trajectory_kitti.txt``: the same frames, 12 numbers a line (KITTI has no
  time stamps: ``trajectory_frames.txt`` lists the frame of each line);
* ``steps.csv``: one line per step ``frame1, frame2, correspondences,
  inliers, rotation_deg, translation_m, scale, segment, reason``
  (``translation_m`` empty when the step's length is not known in metres);
* with ground truth: ``errors.txt`` (ATE after an SE(3) alignment, no scale;
  RPE; scale drift), ``errors.csv`` (the ATE of each frame) and ``rpe.csv``
  (the relative pose error of each step);
* ``trajectory.png``: the top view coloured by scale status (and the errors).
"""

from __future__ import annotations

import csv
import io
import os
import shutil
import tempfile
from pathlib import Path
from typing import Any, Optional

import numpy as np

from ..io.trajectory import write_kitti, write_tum
from ..plots import plot_trajectory
from .evaluation import SequenceErrors
from .trajectory import Trajectory

__all__ = ["write_outputs", "steps_csv"]


def steps_csv(trajectory: Trajectory, frame_numbers: Optional[np.ndarray] = None) -> str:
    """The ``steps.csv`` text of a trajectory (see the module docstring);
    ``frame_numbers`` maps frame indices to the images' own numbers."""
    fn = np.arange(trajectory.n_frames) if frame_numbers is None else np.asarray(frame_numbers)
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["frame1", "frame2", "correspondences", "inliers", "rotation_deg",
                "translation_m", "scale", "segment", "reason"])
    for s in trajectory.steps:
        length = f"{s.length:.6f}" if np.isfinite(s.length) else ""
        rot = f"{s.rotation_deg:.6f}" if np.isfinite(s.rotation_deg) else ""
        w.writerow([int(fn[s.frame1]), int(fn[s.frame2]), s.n_correspondences, s.n_inliers,
                    rot, length, s.status, s.segment, s.reason])
    return buf.getvalue()


def _errors_files(folder: Path, errors: SequenceErrors, frame_numbers: np.ndarray) -> None:
    (folder / "errors.txt").write_text(errors.summary() + "\n")
    with open(folder / "errors.csv", "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["frame", "ate_m"])
        for k, e in zip(errors.frames, errors.ate["errors"]):
            w.writerow([int(frame_numbers[k]), f"{e:.6f}"])
    # the relative pose error of each step between frames with a metric
    # position (Sturm et al. 2012; evo's RPE with delta = 1 frame)
    rpe = errors.rpe
    with open(folder / "rpe.csv", "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["frame1", "frame2", "translation_error_m", "rotation_error_deg",
                    "length_ratio"])
        for (i, j), et, er, lr in zip(rpe["pairs"], rpe["translation"], rpe["rotation_deg"],
                                      rpe["length_ratio"]):
            w.writerow([int(frame_numbers[errors.frames[i]]),
                        int(frame_numbers[errors.frames[j]]), f"{et:.6f}", f"{er:.6f}",
                        f"{lr:.6f}"])


def write_outputs(out: Any, trajectory: Trajectory, *, timestamps: Optional[np.ndarray] = None,
                  frame_numbers: Optional[np.ndarray] = None,
                  gt_poses: Optional[np.ndarray] = None,
                  errors: Optional[SequenceErrors] = None, title: str = "",
                  extra: Optional[dict] = None) -> Path:
    """Write the files of the module docstring into the folder ``out``.

    ``timestamps`` (F,): seconds (or frame numbers) for the TUM file, default
    the frame numbers; ``frame_numbers`` (F,): the images' frame numbers,
    default 0..F-1; ``gt_poses`` (F, 4, 4) world_from_rig with the first
    frame the identity and ``errors`` (:func:`mcgeom.sequence.evaluation.evaluate`)
    when ground truth is known; ``extra``: further files, name -> text (e.g.
    the demo's ``groundtruth_tum.txt`` is written by the caller's callable
    ``extra[name](path)`` when a value is callable). Returns ``out``.
    """
    out = Path(out)
    F = trajectory.n_frames
    fn = np.arange(F) if frame_numbers is None else np.asarray(frame_numbers)
    ts = fn.astype(float) if timestamps is None else np.asarray(timestamps, dtype=float)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.partial-", dir=out.parent))
    try:
        known = trajectory.known
        write_tum(tmp / "trajectory_tum.txt", trajectory.poses[known], ts[known],
                  comment="mcgeom odometry: world_from_rig (world = rig frame of the first "
                          "frame), metres; frames with a metric position only")
        write_kitti(tmp / "trajectory_kitti.txt", trajectory.poses[known])
        (tmp / "trajectory_frames.txt").write_text(
            "".join(f"{int(k)}\n" for k in fn[known]))
        (tmp / "steps.csv").write_text(steps_csv(trajectory, fn))
        if errors is not None:
            _errors_files(tmp, errors, fn)
        for name, value in (extra or {}).items():
            if callable(value):
                value(tmp / name)
            else:
                (tmp / name).write_text(value)
        plot_trajectory(tmp / "trajectory.png", trajectory.segments, gt_poses=gt_poses,
                        step_status=trajectory.status,
                        step_errors=None if errors is None else errors.step_errors,
                        title=title, ate=None if errors is None else errors.ate,
                        frame_offset=int(fn[0]))
        if out.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{out.name}.old-", dir=out.parent))
            os.replace(out, old / out.name)
            os.replace(tmp, out)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return out
