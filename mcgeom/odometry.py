"""Chaining frame-to-frame rig motions into a trajectory, and its errors.

Poses are world_from_rig 4x4 matrices (metres); a motion is rig2_from_rig1
(DESIGN.md section 3), so the next pose is ``T_world_rig2 = T_world_rig1 @
inv(M)``.
"""

from __future__ import annotations

from typing import Iterable, Sequence

import numpy as np

__all__ = ["relative_motion", "chain", "rotation_angle", "motion_errors", "loop_closure_error"]


def relative_motion(T_world_rig1: np.ndarray, T_world_rig2: np.ndarray) -> np.ndarray:
    """rig2_from_rig1 (4x4) between two world_from_rig poses."""
    return np.linalg.inv(T_world_rig2) @ T_world_rig1


def chain(motions: Iterable[np.ndarray], T0: np.ndarray | None = None) -> list[np.ndarray]:
    """World_from_rig poses from a start pose and successive rig2_from_rig1 motions."""
    poses = [np.eye(4) if T0 is None else np.asarray(T0, dtype=float)]
    for M in motions:
        poses.append(poses[-1] @ np.linalg.inv(M))
    return poses


def rotation_angle(R: np.ndarray) -> float:
    """Rotation angle of a 3x3 rotation, radians in [0, pi].

    Uses |R - I|_F = 2 sqrt(2) sin(angle / 2), accurate for tiny angles where
    acos((trace - 1) / 2) has ~1e-8 rad of rounding noise.
    """
    s = np.linalg.norm(np.asarray(R) - np.eye(3)) / (2.0 * np.sqrt(2.0))
    return float(2.0 * np.arcsin(min(s, 1.0)))


def motion_errors(M_est: np.ndarray, M_true: np.ndarray) -> dict:
    """Rotation error (rad), translation direction error (rad), scale ratio
    |t_est|/|t_true| and translation error (m) of a 4x4 motion estimate."""
    R_e, t_e = M_est[:3, :3], M_est[:3, 3]
    R_t, t_t = M_true[:3, :3], M_true[:3, 3]
    nt_e, nt_t = np.linalg.norm(t_e), np.linalg.norm(t_t)
    cosang = np.dot(t_e, t_t) / (nt_e * nt_t) if nt_e > 0 and nt_t > 0 else np.nan
    return {
        "rot_err": rotation_angle(R_e.T @ R_t),
        "dir_err": float(np.arccos(np.clip(cosang, -1.0, 1.0))),
        "scale_ratio": float(nt_e / nt_t) if nt_t > 0 else np.nan,
        "t_err": float(np.linalg.norm(t_e - t_t)),
    }


def loop_closure_error(poses: Sequence[np.ndarray]) -> tuple[float, float]:
    """(position gap in metres, rotation gap in radians) between last and first pose."""
    D = np.linalg.inv(poses[0]) @ poses[-1]
    return float(np.linalg.norm(D[:3, 3])), rotation_angle(D[:3, :3])
