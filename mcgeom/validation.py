"""Argument validators shared by every layer: numeric arrays, rotations,
3-vectors, pixels, points, integers, ray arrays and camera ids.

Each returns the value in the canonical form (float64, C-contiguous where it
matters) or raises ``ValueError`` with a message that names the argument
(``what``) and what is wrong with it. They sit below ``types`` and ``rig``,
which both use them, so neither has to import the other.
"""

from __future__ import annotations

import operator
from typing import Any, Optional

import numpy as np

__all__ = ["MAX_CAMERA_ID", "ROTATION_TOL", "MIN_DIRECTION_NORM", "MAX_ORIGIN", "numeric",
           "rotation_problem", "check_rotation", "check_vector3", "check_pixels", "check_points",
           "check_int", "as_vectors", "as_camera_ids", "integral_camera_ids", "check_directions",
           "check_origins", "check_seed", "check_poses"]

#: tolerance of max |R^T R - I| for a matrix to count as a rotation
ROTATION_TOL = 1e-6


def numeric(what: str, value: Any) -> np.ndarray:
    """``value`` as a float64 array, refusing strings, booleans and ragged lists."""
    try:
        arr = np.asarray(value)
    except (ValueError, TypeError) as exc:  # ragged nested lists
        raise ValueError(f"{what} must be a numeric array ({exc})") from None
    if arr.dtype.kind not in "iuf":
        raise ValueError(f"{what} must be a numeric array, got dtype {arr.dtype}")
    return arr.astype(np.float64)


def rotation_problem(R: np.ndarray) -> str | None:
    """Why ``R`` (3x3 float64) is not a rotation, or None if it is one."""
    if not np.all(np.isfinite(R)):
        return "(non-finite entries)"
    ortho = float(np.max(np.abs(R.T @ R - np.eye(3))))
    if ortho >= ROTATION_TOL:
        return f"(not orthonormal: max |R^T R - I| = {ortho:.3g})"
    det = float(np.linalg.det(R))
    if det <= 0:
        return f"(det = {round(det, 6)})"
    return None


def check_rotation(what: str, value: Any) -> np.ndarray:
    """``value`` as a 3x3 rotation matrix or ValueError('<what> is not a rotation ...')."""
    R = numeric(what, value)
    if R.shape != (3, 3):
        raise ValueError(f"{what} must have shape (3, 3), got {R.shape}")
    problem = rotation_problem(R)
    if problem is not None:
        raise ValueError(f"{what} is not a rotation {problem}")
    return R


def check_vector3(what: str, value: Any) -> np.ndarray:
    """``value`` ((3,), (3, 1) or (1, 3)) as a finite (3,) vector."""
    t = numeric(what, value)
    if t.size != 3 or t.ndim > 2 or (t.ndim == 2 and 1 not in t.shape):
        raise ValueError(f"{what} must have 3 elements, got shape {t.shape}")
    t = t.reshape(3)
    if not np.all(np.isfinite(t)):
        raise ValueError(f"{what} has non-finite entries")
    return t


def check_pixels(what: str, pixels: Any, n: int | None = None) -> np.ndarray:
    """``pixels`` as a finite (N, 2) float64 array or ValueError naming the problem."""
    px = numeric(what, pixels)
    if px.ndim != 2 or px.shape[1] != 2:
        raise ValueError(f"{what} must have shape (N, 2), got {px.shape}")
    if n is not None and px.shape[0] != n:
        raise ValueError(f"{what} has {px.shape[0]} rows, expected {n}")
    bad = ~np.all(np.isfinite(px), axis=1)
    if np.any(bad):
        k = int(np.flatnonzero(bad)[0])
        raise ValueError(f"{what} has {int(bad.sum())} non-finite row(s) (first: row {k})")
    return np.ascontiguousarray(px)


def check_points(what: str, points: Any) -> np.ndarray:
    """``points`` as a finite (N, 3) float64 array or ValueError naming the problem."""
    P = numeric(what, points)
    if P.ndim != 2 or P.shape[1] != 3:
        raise ValueError(f"{what} must have shape (N, 3), got {P.shape}")
    if not np.all(np.isfinite(P)):
        raise ValueError(f"{what} has non-finite entries")
    return np.ascontiguousarray(P)


def check_poses(what: str, poses: Any, n: int | None = None,
                rotation_tol: float = ROTATION_TOL) -> np.ndarray:
    """``poses`` as a finite (N, 4, 4) float64 array of rigid transforms (e.g.
    world_from_rig, metres), N >= 1 (or exactly ``n``), or ValueError naming the
    first bad pose: each top-left 3x3 a rotation to ``rotation_tol`` (max
    |R^T R - I|, det > 0), bottom row (0, 0, 0, 1) exactly."""
    T = numeric(what, poses)
    if T.ndim == 2 and T.shape == (4, 4):
        raise ValueError(f"{what} must have shape (N, 4, 4), got one (4, 4) matrix "
                         "(wrap it as poses[None])")
    if T.ndim != 3 or T.shape[1:] != (4, 4) or T.shape[0] == 0:
        raise ValueError(f"{what} must have shape (N, 4, 4) with N >= 1, got {T.shape}")
    if n is not None and T.shape[0] != n:
        raise ValueError(f"{what} has {T.shape[0]} poses, expected {n}")
    finite = np.all(np.isfinite(T), axis=(1, 2))
    if not np.all(finite):
        k = int(np.flatnonzero(~finite)[0])
        raise ValueError(f"{what} has {int((~finite).sum())} pose(s) with non-finite "
                         f"entries (first: pose {k})")
    bottom = np.all(T[:, 3, :] == (0.0, 0.0, 0.0, 1.0), axis=1)
    if not np.all(bottom):
        k = int(np.flatnonzero(~bottom)[0])
        raise ValueError(f"{what}: pose {k} has bottom row {T[k, 3].tolist()}, "
                         "not (0, 0, 0, 1)")
    R = T[:, :3, :3]
    ortho = np.max(np.abs(np.einsum("nji,njk->nik", R, R) - np.eye(3)), axis=(1, 2))
    bad = (ortho >= rotation_tol) | (np.linalg.det(R) <= 0)
    if np.any(bad):
        k = int(np.flatnonzero(bad)[0])
        raise ValueError(f"{what}: pose {k} is not rigid: its 3x3 part is not a rotation "
                         f"(max |R^T R - I| = {ortho[k]:.3g}, det = "
                         f"{float(np.linalg.det(R[k])):.6g})")
    return np.ascontiguousarray(T)


def check_int(what: str, value: Any) -> int:
    """A plain Python int from an int-like value (not bool, not float)."""
    if isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{what} must be an integer, got {value!r}")
    try:
        return operator.index(value)
    except TypeError:
        raise ValueError(f"{what} must be an integer, got {value!r}") from None


#: largest camera id of a RayPairs (2^20 - 1, the C core's size limit)
MAX_CAMERA_ID = 2 ** 20 - 1

#: a ray direction shorter than this is a zero-length direction, for every estimator
#: (the C kernels' bound, csrc/include/mcgeom.h: |d| < 1e-50 is MCG_EINVAL)
MIN_DIRECTION_NORM = 1e-50

#: largest |coordinate| of a ray origin (metres): the bound of the C kernels
#: whose products of origins must stay finite (mcg_verdict_stats, and
#: mcg_robust_rig_motion, which gathers its evidence). No rig lies 1e150 m
#: away; the estimators that check rays in numpy (RayPairs.check_finite) refuse
#: such origins with the same message instead of failing deep inside
MAX_ORIGIN = 1e150


def check_directions(what: str, d: np.ndarray) -> None:
    """ValueError naming ``what`` if a row of the (N, 3) float64 array ``d`` is shorter
    than :data:`MIN_DIRECTION_NORM` (NaN rows count too; one rule for every estimator:
    directions scaled by 1e-150 are zero-length everywhere, not accepted by some)."""
    short = np.flatnonzero(~(np.einsum("ij,ij->i", d, d) >= MIN_DIRECTION_NORM ** 2))
    if short.size:
        raise ValueError(f"{what} contains a zero-length direction (row {short[0]}; "
                         f"|d| < {MIN_DIRECTION_NORM:g})")


def check_origins(what: str, o: np.ndarray) -> None:
    """ValueError naming ``what`` and the row if a coordinate of the (N, 3)
    float64 array ``o`` exceeds :data:`MAX_ORIGIN` in magnitude (finite
    values; NaN and inf are the finiteness check's)."""
    far = np.flatnonzero(np.abs(o).max(axis=1, initial=0.0) > MAX_ORIGIN)
    if far.size:
        bound = f"{MAX_ORIGIN:.0e}".replace("e+", "e")
        raise ValueError(f"{what} has a coordinate beyond {bound} m in magnitude "
                         f"(row {far[0]}): origins are camera centres in metres")


def integral_camera_ids(what: str, arr: np.ndarray) -> np.ndarray:
    """Camera ids of an integer dtype: integer arrays as they are (the caller checks the
    range before any cast: a uint64 2**63 must not wrap), floats as int64 only when every
    value is a finite whole number (``2.0``: what ``np.loadtxt`` gives); anything else is
    a ValueError naming ``what``. The one rule of ``Rig.ray_pairs``, ``RayPairs`` and the
    OpenCV-style façade."""
    if arr.dtype.kind in "iu":
        return arr
    if arr.dtype.kind == "f" and np.all(np.isfinite(arr)) and np.all(arr == np.round(arr)):
        return arr.astype(np.int64)
    raise ValueError(f"{what} must hold integer camera ids, got dtype {arr.dtype}"
                     + (" with a fractional or non-finite value" if arr.dtype.kind == "f" else ""))


def check_seed(seed: Any) -> Optional[int]:
    """A RANSAC seed: None (fresh entropy) or a non-negative integer; ValueError naming
    ``seed`` otherwise (numpy's own messages name nothing)."""
    if seed is None:
        return None
    try:
        value = check_int("seed", seed)   # no bool, no float, no string
    except ValueError:
        value = -1
    if value < 0:
        raise ValueError(f"seed must be None or a non-negative integer, got {seed!r}")
    return value


def as_vectors(name: str, a: Any, n: Optional[int] = None) -> np.ndarray:
    """Return ``a`` as a C-contiguous float64 (N, 3) array or raise ValueError.

    Finiteness is not checked here (the C kernels check it without an extra
    pass over the data); shape and dtype are.
    """
    arr = np.asarray(a)
    if arr.dtype.kind not in "fiu":
        raise ValueError(f"{name} must be a numeric array, got dtype {arr.dtype}")
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"{name} must have shape (N, 3), got {arr.shape}")
    if n is not None and arr.shape[0] != n:
        raise ValueError(f"{name} has {arr.shape[0]} rows, expected {n}")
    return np.ascontiguousarray(arr, dtype=np.float64)


def as_camera_ids(name: str, a: Any, n: int) -> Optional[np.ndarray]:
    if a is None:
        return None
    arr = np.asarray(a)
    if arr.ndim != 1 or arr.shape[0] != n:
        raise ValueError(f"{name} must have shape ({n},), got {arr.shape}")
    arr = integral_camera_ids(name, arr)
    if arr.size and arr.min() < 0:
        raise ValueError(f"{name} holds a negative camera id ({int(arr.min())})")
    # ids index per-camera tables (centres, counts) in the estimators: a huge
    # label would allocate terabytes. The C core's size limit bounds them.
    if arr.size and arr.max() > MAX_CAMERA_ID:
        raise ValueError(f"{name} holds camera id {int(arr.max())}, above the largest "
                         f"supported {MAX_CAMERA_ID} (ids are 0-based camera indices)")
    return np.ascontiguousarray(arr, dtype=np.int64)
