"""The result of the sequence back end: a rig trajectory that never invents a scale.

Frames and units (docs/architecture.md §3): a pose is **world_from_rig**, a
4x4 matrix ``T`` with ``X_world = T[:3, :3] X_rig + T[:3, 3]`` (metres); the
world frame is the rig frame of frame 0, so ``poses[0]`` is the identity. A
step's motion is rig2_from_rig1 (``X_{k+1} = R X_k + t``, the convention of
:class:`mcgeom.RigMotion`).

Scale status of a step k -> k+1 (issue 17):

* ``"metric"``: its own two-frame verdict says the metric scale is observable
  (a turn seen through offset cameras, or cross-camera correspondences;
  thesis ch. 7.3.2);
* ``"carried"``: not observable on its own, but tracks seen in three
  consecutive frames tie its length to its neighbours' (the trilinear
  relations of thesis eq. 6.11), and that chain reaches an observed step;
* ``"unknown"``: neither; its length is not known in metres.

Segments. Steps whose lengths are tied by tracks form a *segment* (a maximal
run of frames; consecutive segments share their boundary frame). A segment
with at least one observed step is metric (its steps are ``metric`` or
``carried``); a segment without one is **direction-only**: its steps are
``unknown``, its poses hold rotations and translation *directions* (each
step's direction from its two-frame estimate, the relative step lengths
from the tracks, normalised to a path length of 1, no unit).

How poses are stored:

* :attr:`Segment.poses` ``(n, 4, 4)``: the poses of the segment's frames
  relative to the *position* of its first frame, in the world orientation
  (its first pose is ``[R_world_rig(first), 0]``: carried over in rotation
  only). When the rotation chain from frame 0 is broken (a step without any
  motion), the orientation is that of the segment's first frame instead
  (``world_rotation`` False, first pose the identity).
* :attr:`Trajectory.poses` ``(F, 4, 4)``: world_from_rig of every frame whose
  position follows from frame 0 through metric segments only (metric segments
  are stitched at their shared frame: no length is guessed there). A frame
  behind a direction-only segment or a failed step has a NaN translation
  (and NaN rotation if the rotation chain is broken): :attr:`Trajectory.known`
  says which frames are located.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from ..metrics import rotation_angle
from ..types import RigMotion

__all__ = ["SCALE_STATUS", "Step", "Segment", "Trajectory"]

#: the scale status of a step, see the module docstring
SCALE_STATUS = ("metric", "carried", "unknown")


@dataclass(frozen=True)
class Step:
    """One step ``frame1 -> frame2 = frame1 + 1`` of the trajectory.

    ``motion``: the two-frame estimate (rig2_from_rig1, its verdict and
    inlier mask over the step's correspondences), None if the step could not
    be estimated (``reason`` says why). ``status``: one of
    :data:`SCALE_STATUS`. ``R``, ``t``: the motion rig2_from_rig1 the
    trajectory uses (``t`` in metres for metric/carried steps; for
    ``unknown`` steps ``t`` holds the direction only, unit length, or NaN when
    there is none). ``length``: ``|t|`` in metres, NaN unless metric or
    carried. ``n_correspondences``/``n_inliers``: the step's two-frame
    correspondences and the robust pipeline's inliers among them.
    ``segment``: the index of its segment in :attr:`Trajectory.segments`.
    """

    frame1: int
    frame2: int
    motion: Optional[RigMotion]
    status: str
    R: np.ndarray
    t: np.ndarray
    length: float
    n_correspondences: int
    n_inliers: int
    segment: int
    reason: str

    @property
    def rotation_deg(self) -> float:
        """Rotation angle of the step in degrees (NaN without a motion)."""
        if not np.all(np.isfinite(self.R)):
            return float("nan")
        return float(np.degrees(rotation_angle(self.R)))


@dataclass(frozen=True)
class Segment:
    """A maximal run of frames whose step lengths are tied by tracks.

    ``frames`` (n,): consecutive frame indices. ``poses`` (n, 4, 4): the
    frames' poses relative to the position of ``frames[0]`` (see the module
    docstring), metres when ``metric``, else translations with no unit (the
    path length of the segment normalised to 1). ``world_rotation``: the
    orientation of ``poses`` is the world's (rotation chain from frame 0
    intact), else that of ``frames[0]``. ``scale_source``: how the metric
    was fixed (``"tracks"``: the inhomogeneous system of the rig offsets,
    thesis ch. 6 with ch. 4.2; ``"steps"``: the observed steps' two-frame
    lengths; ``"two-frame"``: a one-step segment; ``"none"``).
    """

    frames: np.ndarray
    poses: np.ndarray
    metric: bool
    world_rotation: bool
    scale_source: str
    info: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Trajectory:
    """A rig trajectory: poses, steps and segments (see the module docstring).

    ``poses`` (F, 4, 4) world_from_rig (metres; NaN translation where the
    position is not known metrically from frame 0); ``steps`` (F - 1) the
    steps k -> k+1; ``segments`` in frame order.
    """

    poses: np.ndarray
    steps: tuple
    segments: tuple

    @property
    def n_frames(self) -> int:
        """Number of frames F."""
        return int(self.poses.shape[0])

    @property
    def known(self) -> np.ndarray:
        """(F,) bool: frames whose position is known in metres from frame 0."""
        return np.all(np.isfinite(self.poses[:, :3, 3]), axis=1)

    @property
    def status(self) -> tuple:
        """The scale status of every step (:data:`SCALE_STATUS`)."""
        return tuple(s.status for s in self.steps)

    @property
    def status_counts(self) -> dict:
        """Number of steps per scale status, every key of :data:`SCALE_STATUS`."""
        status = self.status
        return {k: status.count(k) for k in SCALE_STATUS}

    @property
    def metric_path_length(self) -> float:
        """Length (metres) of the path through the frames located in metres
        (:attr:`known`); direction-only stretches have no length."""
        c = self.poses[self.known, :3, 3]
        return float(np.sum(np.linalg.norm(np.diff(c, axis=0), axis=1))) if len(c) > 1 else 0.0

    @property
    def centres(self) -> np.ndarray:
        """(F, 3) positions of the rig in the world frame (metres; NaN where
        not known)."""
        return self.poses[:, :3, 3].copy()
