"""One run of the sequence pipeline on files: a rig file and a folder of
images to the output files of :mod:`mcgeom.sequence.outputs`
(``mcgeom odometry``; ``mcgeom demo`` runs it on its rendered images).

Everything that can be checked before the long work is checked first (the
rig file, the image layout, the ground-truth file), so that bad input gets
its clear error at once and nothing is written; the outputs are written only
at the end, all at once.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Optional

import numpy as np

from ..io import load_rig, select_frame
from ..io.images import ImageSequence, find_image_sequence
from ..io.trajectory import read_tum
from ..rig import Rig
from .backend import estimate_trajectory
from .evaluation import SequenceErrors, associate, evaluate
from .frontend import build_tracks
from .outputs import write_outputs
from .tracks import Tracks
from .trajectory import Trajectory

__all__ = ["OdometryRun", "run_odometry", "Progress"]

#: ``progress(iterable, total=, desc=)`` -> the iterable, e.g. a tqdm bar
Progress = Callable[..., Iterable]


def _no_progress(iterable: Iterable, total: Optional[int] = None,
                 desc: Optional[str] = None) -> Iterable:
    return iterable


@dataclass(frozen=True)
class OdometryRun:
    """What one run produced: the rig, the image sequence, the tracks, the
    trajectory, its errors against the ground truth (None without one) and
    the output folder; ``seconds``: wall time per stage."""

    rig: Rig
    sequence: ImageSequence
    tracks: Tracks
    trajectory: Trajectory
    errors: Optional[SequenceErrors]
    out: Path
    seconds: dict = field(default_factory=dict)


def _timestamps(sequence: ImageSequence) -> np.ndarray:
    """The frames' time stamps: seconds when the layout gives them, else the
    frame numbers."""
    return (sequence.timestamps if sequence.timestamps is not None
            else sequence.indices.astype(float))


def _gt_for(sequence: ImageSequence, gt_path: Any) -> np.ndarray:
    """Ground truth (F, 4, 4) of the sequence's frames from a TUM file, by time
    stamp (:func:`_timestamps`)."""
    gt_ts, gt_poses = read_tum(gt_path)
    ts = _timestamps(sequence)
    # half the frame interval: the nearest ground truth must be this frame's
    dt = float(np.median(np.diff(ts))) if len(ts) > 1 else 1.0
    return associate(ts, gt_ts, gt_poses, max_dt=0.5 * abs(dt))


def run_odometry(rig: Any, images: Any, out: Any, *, start: int = 0, end: Optional[int] = None,
                 step: int = 1, features: str = "sift", n_features: int = 4000,
                 cross_camera: bool = True, threshold: float = 1.0, gt: Any = None,
                 title: str = "", extra_outputs: Optional[dict] = None,
                 progress: Optional[Progress] = None, rig_frame: Any = None,
                 calibration_check: str = "sampled") -> OdometryRun:
    """Run the sequence pipeline and write its outputs.

    ``rig``: a :class:`mcgeom.rig.Rig` or a rig file (any format of
    :func:`mcgeom.load_rig`); ``images``: the folder of images
    (:func:`mcgeom.io.images.find_image_sequence`: camera folders, EuRoC/ASL
    or KITTI raw), sliced ``start:end:step``; ``out``: the output folder
    (written at the end, all at once); ``features``: ``"sift"`` or ``"orb"``;
    ``threshold``: the two-frame inlier threshold in pixels; ``gt``: a TUM
    file of world_from_rig ground truth (same clock as the images' time
    stamps, or frame numbers when the layout has none); ``progress``: wraps the
    loops over frames and steps; ``rig_frame``: the rig frame of the estimated
    motions (``frame=`` of :func:`mcgeom.load_rig`: None for the file's default,
    ``"body"``, ``"camera:<name or index>"`` or a 4x4 transform); the ground truth
    must be world_from_rig of that frame; ``calibration_check``: how a metric
    step's calibration part of the std of |t| is checked
    (:data:`mcgeom.sequence.backend.CALIBRATION_CHECKS`, see
    :func:`mcgeom.sequence.estimate_trajectory`).
    """
    bar = progress or _no_progress
    times = {}
    t0 = time.perf_counter()
    rig = select_frame(rig, rig_frame) if isinstance(rig, Rig) else load_rig(rig, frame=rig_frame)
    sequence = find_image_sequence(images, rig, start=start, end=end, step=step)
    gt_poses = None if gt is None else _gt_for(sequence, gt)
    tracks = build_tracks(rig, sequence, features=features, n_features=n_features,
                          cross_camera=cross_camera, progress=bar)
    times["front end"] = time.perf_counter() - t0
    t1 = time.perf_counter()
    trajectory = estimate_trajectory(rig, tracks, threshold=threshold, progress=bar,
                                     calibration_check=calibration_check)
    times["back end"] = time.perf_counter() - t1
    errors = None if gt_poses is None else evaluate(trajectory, gt_poses)
    t2 = time.perf_counter()
    out = write_outputs(out, trajectory, timestamps=_timestamps(sequence), frame_numbers=sequence.indices,
                        gt_poses=gt_poses, errors=errors, title=title, extra=extra_outputs)
    times["outputs"] = time.perf_counter() - t2
    return OdometryRun(rig, sequence, tracks, trajectory, errors, Path(out), times)
