"""Trajectory files: TUM and KITTI pose lists (I/O only: parsing and conventions).

Both formats hold **world_from_rig** poses, ``X_world = R X_rig + t`` (metres),
one pose a line; :mod:`mcgeom.metrics` measures them, :mod:`mcgeom.plots` draws them.

* **TUM** (the TUM RGB-D benchmark's format, Sturm et al., IROS 2012; read by
  ``evo`` as ``read_tum_trajectory_file``): ``timestamp tx ty tz qx qy qz qw`` --
  the timestamp (seconds, or the frame index when a sequence has no times), the
  position ``t`` and the orientation ``R`` as a Hamilton unit quaternion with
  **w last**. Written normalised with ``qw >= 0`` (q and -q are the same
  rotation). Lines starting with ``#`` and blank lines are comments.
* **KITTI** (the KITTI odometry benchmark's ``poses/XX.txt``): 12 numbers a line,
  the top 3x4 block ``[R | t]`` row-major; the pose index is the frame. ``#``
  comments and blank lines are skipped as ``evo`` skips them.

Numbers are written with Python's shortest round-trip repr, so reading a written
file gives the same float64 values back. The quaternion conversions are the C
core's (``mcg_quat_from_rot`` / ``mcg_rot_from_quat``: Shepperd's method).

Writes are atomic (a temporary file in the same folder, then ``os.replace``): a
reader never sees half a file, and a failed write leaves the old file as it was.
A malformed file raises ``ValueError("<file>:<line>: <problem>")``; poses that are
not rigid transforms raise ``ValueError`` naming the pose.
"""

from __future__ import annotations

import os
import tempfile
from typing import Any, Optional, Union

import numpy as np

from mcgeom import _core
from mcgeom.io._common import describe_path, read_text
from mcgeom.validation import check_poses, numeric

__all__ = ["write_atomically", "write_tum", "read_tum", "write_kitti", "read_kitti",
           "FILE_ROTATION_TOL", "QUATERNION_NORM_TOL"]

#: max |R^T R - I| of a rotation read from a KITTI file: the benchmark's own files
#: print 7 significant digits, so their rotations are orthonormal only to ~1e-7
FILE_ROTATION_TOL = 1e-5
#: max |‖q‖ - 1| of a TUM quaternion (files print 4 to 17 digits); beyond it the
#: line is not a rotation as written, and normalising it would hide the error
QUATERNION_NORM_TOL = 1e-3


def write_atomically(path: Union[str, os.PathLike], data: Union[str, bytes]) -> None:
    """Write ``data`` (text as UTF-8, or bytes) to ``path`` all at once.

    The data goes to a temporary file in the same folder (same file system), is
    flushed to disk, then renamed over ``path`` with ``os.replace``, which is
    atomic: ``path`` holds either its old content or the whole new one. The
    folder must exist (``OSError`` otherwise).
    """
    target = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(target))
    raw = data.encode("utf-8") if isinstance(data, str) else bytes(data)
    fd, tmp = tempfile.mkstemp(prefix=".tmp-", suffix="-" + os.path.basename(target),
                               dir=folder)
    try:
        # mkstemp creates the file 0600; give it the mode a plain open() would
        mask = os.umask(0)
        os.umask(mask)
        os.fchmod(fd, 0o666 & ~mask)
        with os.fdopen(fd, "wb") as fh:
            fh.write(raw)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, target)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise


def _number(x: float) -> str:
    """Shortest text that reads back as the same float64."""
    return repr(float(x))


def _timestamps(timestamps: Any, n: int) -> np.ndarray:
    """(n,) finite, strictly increasing float64 timestamps; frame indices if None."""
    if timestamps is None:
        return np.arange(n, dtype=np.float64)
    ts = numeric("timestamps", timestamps)
    if ts.shape != (n,):
        raise ValueError(f"timestamps must have shape ({n},) (one per pose), got {ts.shape}")
    if not np.all(np.isfinite(ts)):
        raise ValueError("timestamps has non-finite entries")
    if n > 1 and not np.all(np.diff(ts) > 0):
        k = int(np.flatnonzero(np.diff(ts) <= 0)[0])
        raise ValueError(f"timestamps must increase strictly: timestamps[{k + 1}] = "
                         f"{float(ts[k + 1])!r} follows {float(ts[k])!r}")
    return ts


def write_tum(path: Union[str, os.PathLike], poses: Any, timestamps: Any = None,
              comment: str = "") -> None:
    """Write world_from_rig ``poses`` (N, 4, 4), metres, as a TUM trajectory file.

    ``timestamps`` (N,): seconds, strictly increasing; default the frame index
    0..N-1. ``comment``: optional text written as ``#`` lines at the top, after
    the column header line. Atomic (:func:`write_atomically`).
    """
    T = check_poses("poses", poses)
    ts = _timestamps(timestamps, T.shape[0])
    lines = [f"# {line}" for line in comment.splitlines()]
    lines.append("# timestamp tx ty tz qx qy qz qw (world_from_rig, metres)")
    for k in range(T.shape[0]):
        w, x, y, z = _core.quat_from_rot(T[k, :3, :3])  # unit, w >= 0
        lines.append(" ".join(_number(v) for v in (ts[k], *T[k, :3, 3], x, y, z, w)))
    write_atomically(path, "\n".join(lines) + "\n")


def write_kitti(path: Union[str, os.PathLike], poses: Any) -> None:
    """Write world_from_rig ``poses`` (N, 4, 4), metres, as a KITTI pose file: the
    top 3x4 ``[R | t]`` of each, row-major, 12 numbers a line. No comment lines
    (the benchmark's tools do not skip them). Atomic (:func:`write_atomically`)."""
    T = check_poses("poses", poses)
    lines = [" ".join(_number(v) for v in T[k, :3, :].ravel()) for k in range(T.shape[0])]
    write_atomically(path, "\n".join(lines) + "\n")


def _rows(path: Union[str, os.PathLike], ncols: int, layout: str) -> tuple[list[int], np.ndarray]:
    """(line numbers, (M, ncols) float64) of the data lines of a whitespace-separated
    file; ValueError('<file>:<line>: ...') at the first malformed line."""
    where = describe_path(path)
    numbers, rows = [], []
    for lineno, line in enumerate(read_text(path).splitlines(), start=1):
        text = line.strip()
        if not text or text.startswith("#"):
            continue
        fields = text.split()
        if len(fields) != ncols:
            hint = ""
            if layout == "KITTI" and len(fields) == 13:
                hint = " (a leading timestamp column? KITTI pose files have none)"
            raise ValueError(f"{where}:{lineno}: a {layout} line has {ncols} numbers "
                             f"({_COLUMNS[layout]}), got {len(fields)}{hint}")
        try:
            values = [float(f) for f in fields]
        except ValueError:
            bad = next(f for f in fields if not _is_float(f))
            raise ValueError(f"{where}:{lineno}: {bad!r} is not a number") from None
        if not all(np.isfinite(values)):
            raise ValueError(f"{where}:{lineno}: non-finite number in {text!r}")
        numbers.append(lineno)
        rows.append(values)
    if not rows:
        raise ValueError(f"{where}: no poses (an empty {layout} trajectory file)")
    return numbers, np.asarray(rows, dtype=np.float64)


_COLUMNS = {"TUM": "timestamp tx ty tz qx qy qz qw",
            "KITTI": "r11 r12 r13 tx r21 r22 r23 ty r31 r32 r33 tz"}


def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def read_tum(path: Union[str, os.PathLike]) -> tuple[np.ndarray, np.ndarray]:
    """Read a TUM trajectory file: ``(timestamps (N,), poses (N, 4, 4))``.

    ``poses`` are world_from_rig (metres, as written); each quaternion
    ``(qx, qy, qz, qw)`` must have norm 1 to :data:`QUATERNION_NORM_TOL` and is
    normalised before conversion. Timestamps must increase strictly.
    ValueError ``"<file>:<line>: <problem>"`` on a malformed line.
    """
    where = describe_path(path)
    linenos, rows = _rows(path, 8, "TUM")
    poses = np.tile(np.eye(4), (rows.shape[0], 1, 1))
    for k, (lineno, row) in enumerate(zip(linenos, rows)):
        qx, qy, qz, qw = row[4:]
        norm = float(np.sqrt(qx * qx + qy * qy + qz * qz + qw * qw))
        if abs(norm - 1.0) > QUATERNION_NORM_TOL:
            raise ValueError(f"{where}:{lineno}: the quaternion (qx qy qz qw) = "
                             f"{[qx, qy, qz, qw]} has norm {norm:.6g}, not 1")
        poses[k, :3, :3] = _core.rot_from_quat([qw, qx, qy, qz])
        poses[k, :3, 3] = row[1:4]
        if k and not rows[k, 0] > rows[k - 1, 0]:
            raise ValueError(f"{where}:{lineno}: timestamp {float(rows[k, 0])!r} does not "
                             f"follow the previous one ({float(rows[k - 1, 0])!r}): "
                             "timestamps must increase strictly")
    return rows[:, 0].copy(), poses


def read_kitti(path: Union[str, os.PathLike],
               rotation_tol: Optional[float] = None) -> np.ndarray:
    """Read a KITTI pose file: world_from_rig ``poses (N, 4, 4)`` (metres), frame
    ``k`` on the ``k``-th data line.

    Rotations are kept as written (no re-orthonormalisation, as the benchmark's
    tools and ``evo`` read them) but must be rotations to ``rotation_tol``
    (default :data:`FILE_ROTATION_TOL`). ValueError ``"<file>:<line>: <problem>"``
    on a malformed line.
    """
    where = describe_path(path)
    tol = FILE_ROTATION_TOL if rotation_tol is None else float(rotation_tol)
    linenos, rows = _rows(path, 12, "KITTI")
    poses = np.tile(np.eye(4), (rows.shape[0], 1, 1))
    poses[:, :3, :] = rows.reshape(-1, 3, 4)
    for k, lineno in enumerate(linenos):
        try:
            check_poses("pose", poses[k:k + 1], rotation_tol=tol)
        except ValueError as exc:
            problem = str(exc).split("not rigid: ", 1)[-1]
            raise ValueError(f"{where}:{lineno}: {problem}") from None
    return poses
