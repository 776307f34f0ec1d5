"""Chaining frame-to-frame rig motions into a trajectory, and its errors.

Poses are world_from_rig 4x4 matrices (metres); a motion is rig2_from_rig1
(DESIGN.md section 3), so the next pose is ``T_world_rig2 = T_world_rig1 @
inv(M)``.
"""

from __future__ import annotations

from typing import Iterable, Sequence

import numpy as np

from .synth import rotation_error, translation_errors

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


def rotation_angle(R: np.ndarray) -> float:
    """Rotation angle of a 3x3 rotation, radians in [0, pi] (accurate near 0)."""
    return rotation_error(R, np.eye(3))


def motion_errors(M_est: np.ndarray, M_true: np.ndarray) -> dict:
    """Rotation error (rad), translation direction error (rad), scale ratio
    |t_est|/|t_true| and translation error (m) of a 4x4 motion estimate."""
    dir_err, ratio = translation_errors(M_est[:3, 3], M_true[:3, 3])
    return {
        "rot_err": rotation_error(M_est[:3, :3], M_true[:3, :3]),
        "dir_err": dir_err,
        "scale_ratio": ratio,
        "t_err": float(np.linalg.norm(M_est[:3, 3] - M_true[:3, 3])),
    }


def loop_closure_error(poses: Sequence[np.ndarray]) -> tuple[float, float]:
    """(position gap in metres, rotation gap in radians) between last and first pose."""
    D = np.linalg.inv(poses[0]) @ poses[-1]
    return float(np.linalg.norm(D[:3, 3])), rotation_angle(D[:3, :3])
