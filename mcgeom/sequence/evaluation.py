"""A sequence trajectory against its ground truth: association by time, and
the errors of the frames whose position is known in metres.

The metric scale is the point of the pipeline, so the estimate is aligned to
the truth by a rigid motion only (SE(3), no scale): ATE after that alignment,
the relative pose error of each step, and the scale drift (path length ratio
- 1, in %), all from :mod:`mcgeom.metrics` (checked against evo). Frames of
direction-only segments have no metric position (:attr:`Trajectory.known` is
False there) and are left out: they are never scored as if metric.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Optional

import numpy as np

from .. import metrics
from ..validation import check_poses
from .trajectory import Trajectory

__all__ = ["SequenceErrors", "associate", "evaluate", "MIN_PATH_FOR_DRIFT"]

#: shortest true path (metres) over which a scale drift is reported
MIN_PATH_FOR_DRIFT = 0.1


def associate(timestamps: np.ndarray, gt_timestamps: np.ndarray, gt_poses: np.ndarray,
              max_dt: float) -> np.ndarray:
    """Ground-truth pose of each estimated frame, by nearest time stamp.

    ``timestamps`` (F,) of the estimate, ``gt_timestamps`` (G,) and
    ``gt_poses`` (G, 4, 4) world_from_rig of the truth (same clock, seconds or
    frame indices). Returns (F, 4, 4) re-expressed so that the first frame is
    the identity (the estimate's world is the rig frame of its first frame).
    ValueError when a frame has no ground truth within ``max_dt``.
    """
    ts = np.asarray(timestamps, dtype=float).reshape(-1)
    gts = np.asarray(gt_timestamps, dtype=float).reshape(-1)
    gt = check_poses("ground truth", gt_poses, n=gts.shape[0])
    order = np.argsort(gts)
    gts, gt = gts[order], gt[order]
    # the nearer of the two neighbours in time
    right = np.searchsorted(gts, ts)
    lo = np.clip(right - 1, 0, len(gts) - 1)
    hi = np.clip(right, 0, len(gts) - 1)
    j = np.where(np.abs(gts[lo] - ts) <= np.abs(gts[hi] - ts), lo, hi)
    dt = np.abs(gts[j] - ts)
    if np.any(dt > max_dt):
        k = int(np.argmax(dt > max_dt))
        raise ValueError(f"ground truth: no pose within {max_dt:g} of time stamp {ts[k]:.6f} "
                         f"(frame {k}; nearest {gts[j[k]]:.6f}); the estimate's time stamps "
                         f"span {ts[0]:.6f}..{ts[-1]:.6f}, the ground truth's "
                         f"{gts[0]:.6f}..{gts[-1]:.6f}")
    matched = gt[j]
    return np.linalg.inv(matched[0]) @ matched


@dataclass(frozen=True)
class SequenceErrors:
    """Errors of the metric part of a trajectory against its ground truth.

    ``frames``: the frames scored (known metric positions). ``ate``: the dict
    of :func:`mcgeom.metrics.absolute_trajectory_error` (metres, after SE(3)
    alignment). ``rpe``: :func:`mcgeom.metrics.relative_pose_error` over
    consecutive scored frames. ``scale_drift_percent``: path length of the
    estimate over the truth's, minus 1, in %. ``step_errors`` (F - 1,):
    translation error of each metric or carried step (m), NaN elsewhere.
    ``path_length_m``: of the truth over the scored frames.
    """

    frames: np.ndarray
    ate: dict
    rpe: dict
    scale_drift_percent: float
    step_errors: np.ndarray
    path_length_m: float

    def summary(self) -> str:
        """One line for people: ATE, its share of the path, drift, RPE."""
        share = (f" ({self.ate['rmse_percent']:.2f} % of {self.path_length_m:.2f} m)"
                 if np.isfinite(self.scale_drift_percent) else
                 f" (the truth moves {self.path_length_m:.3f} m)")
        drift = (f"scale drift {self.scale_drift_percent:+.2f} %"
                 if np.isfinite(self.scale_drift_percent) else "no scale drift (static truth)")
        return (f"ATE RMSE {self.ate['rmse']:.3f} m{share}, {drift}, "
                f"RPE per step {self.rpe['translation_rmse']:.3f} m / "
                f"{self.rpe['rotation_rmse_deg']:.3f} deg (RMSE) over {len(self.frames)} "
                f"frames")


def _step_errors(trajectory: Trajectory, gt: np.ndarray) -> np.ndarray:
    """Translation error (m) of each metric/carried step against the truth."""
    out = np.full(len(trajectory.steps), np.nan)
    for k, s in enumerate(trajectory.steps):
        if s.status == "unknown" or not np.all(np.isfinite(s.t)):
            continue
        true = np.linalg.inv(gt[k + 1]) @ gt[k]          # rig2_from_rig1
        out[k] = float(np.linalg.norm(np.asarray(s.t) - true[:3, 3]))
    return out


def evaluate(trajectory: Trajectory, gt_poses: Any) -> Optional[SequenceErrors]:
    """Score ``trajectory`` against ``gt_poses`` (F, 4, 4), one per frame, with
    the first frame the identity (:func:`associate` gives them). None when
    fewer than two frames have a metric position (nothing to score)."""
    gt = check_poses("ground truth", gt_poses, n=trajectory.n_frames)
    known = np.flatnonzero(trajectory.known)
    if known.size < 2:
        return None
    est = trajectory.poses[known]
    ref = gt[known]
    ate = metrics.absolute_trajectory_error(est, ref)
    ate["frames"] = known
    length = metrics.path_length(ref)
    # a truth that barely moves (a parked car, a hovering MAV: millimetres of
    # jitter) has no scale to compare with
    drift = metrics.scale_drift(est, ref) if length >= MIN_PATH_FOR_DRIFT else float("nan")
    return SequenceErrors(known, ate, metrics.relative_pose_error(est, ref), drift,
                          _step_errors(trajectory, gt), length)
