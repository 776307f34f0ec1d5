"""Chaining frame-to-frame rig motions into a trajectory (its errors: mcgeom.metrics).

Poses are world_from_rig 4x4 matrices (metres); a motion is rig2_from_rig1
(docs/architecture.md §3), so the next pose is ``T_world_rig2 = T_world_rig1 @
inv(M)``.
"""

from __future__ import annotations

from typing import Iterable

import numpy as np

# the trajectory metrics moved to mcgeom.metrics; re-exported so that
# mcgeom.odometry keeps its public names
from .metrics import loop_closure_error, motion_errors, rotation_angle

__all__ = ["to_matrix", "chain", "rotation_angle", "motion_errors", "loop_closure_error"]


def to_matrix(R: np.ndarray, t: np.ndarray) -> np.ndarray:
    """4x4 homogeneous matrix of a motion (R, t)."""
    M = np.eye(4)
    M[:3, :3] = R
    M[:3, 3] = t
    return M


def chain(motions: Iterable[np.ndarray], T0: np.ndarray | None = None) -> list[np.ndarray]:
    """World_from_rig poses from a start pose and successive rig2_from_rig1 motions."""
    poses = [np.eye(4) if T0 is None else np.asarray(T0, dtype=float)]
    for M in motions:
        poses.append(poses[-1] @ np.linalg.inv(M))
    return poses
