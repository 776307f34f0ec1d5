"""Error metrics of motion estimates and trajectories.

A motion is rig2_from_rig1 (docs/architecture.md §3): ``X_rig2 = R X_rig1 + t``,
``t`` in metres in the rig2 frame; as a 4x4 matrix ``M = [[R, t], [0, 1]]``.
Poses are world_from_rig 4x4 matrices (metres). Angles are in radians.

These are the yardsticks of the tests, the demo, the benchmarks and the
experiments; they live apart from :mod:`mcgeom.synth` so that library code
can measure errors without depending on the synthetic-data generator.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

__all__ = ["rotation_error", "translation_errors", "rotation_angle", "motion_errors",
           "loop_closure_error"]


def rotation_error(R_est: np.ndarray, R_true: np.ndarray) -> float:
    """Angle (radians, in [0, pi]) of the rotation ``R_est R_true^T``.

    Both are 3x3 rotations between the same two frames (e.g. rig2_from_rig1).
    Computed with atan2 of the sine and cosine parts, accurate for tiny angles too
    (arccos of the trace loses half the digits near 0).
    """
    D = np.asarray(R_est, dtype=np.float64) @ np.asarray(R_true, dtype=np.float64).T
    s = 0.5 * np.linalg.norm([D[2, 1] - D[1, 2], D[0, 2] - D[2, 0], D[1, 0] - D[0, 1]])
    c = 0.5 * (np.trace(D) - 1.0)
    return float(np.arctan2(s, c))


def translation_errors(t_est: np.ndarray, t_true: np.ndarray) -> tuple[float, float]:
    """``(direction_error, scale_ratio)`` of a translation estimate.

    ``t_est`` and ``t_true`` are 3-vectors in the same frame (the rig2 frame for a
    rig2_from_rig1 motion), any unit. ``direction_error`` is the angle (radians)
    between them; ``scale_ratio`` is ``|t_est| / |t_true|`` (1 = exact metric
    scale). Both are NaN when ``t_true`` is zero; the angle is NaN when ``t_est``
    is zero.
    """
    a = np.asarray(t_est, dtype=np.float64).reshape(3)
    b = np.asarray(t_true, dtype=np.float64).reshape(3)
    na, nb = np.linalg.norm(a), np.linalg.norm(b)
    if nb == 0:
        return float("nan"), float("nan")
    if na == 0:
        return float("nan"), 0.0
    angle = np.arctan2(np.linalg.norm(np.cross(a, b)), a @ b)
    return float(angle), float(na / nb)


def rotation_angle(R: np.ndarray) -> float:
    """Rotation angle of a 3x3 rotation, radians in [0, pi] (accurate near 0)."""
    return rotation_error(R, np.eye(3))


def motion_errors(M_est: np.ndarray, M_true: np.ndarray) -> dict:
    """Errors of a 4x4 rig2_from_rig1 motion estimate against the truth.

    Returns a dict: ``rot_err`` (radians), ``dir_err`` (radians, angle between
    the translations, rig2 frame), ``scale_ratio`` (``|t_est| / |t_true|``) and
    ``t_err`` (``|t_est - t_true|``, metres).
    """
    dir_err, ratio = translation_errors(M_est[:3, 3], M_true[:3, 3])
    return {
        "rot_err": rotation_error(M_est[:3, :3], M_true[:3, :3]),
        "dir_err": dir_err,
        "scale_ratio": ratio,
        "t_err": float(np.linalg.norm(M_est[:3, 3] - M_true[:3, 3])),
    }


def loop_closure_error(poses: Sequence[np.ndarray]) -> tuple[float, float]:
    """(position gap in metres, rotation gap in radians) between the last and the
    first of a sequence of world_from_rig 4x4 poses (0 for a closed loop)."""
    D = np.linalg.inv(poses[0]) @ poses[-1]
    return float(np.linalg.norm(D[:3, 3])), rotation_angle(D[:3, :3])
