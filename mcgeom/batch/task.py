"""One sequence of a batch: :func:`mcgeom.sequence.run.run_odometry` into
``DIR/<name>/`` and the summary row of the result.

This is the function a Dask worker runs (one task per sequence); it never
raises for a failing sequence: any exception becomes a row with status
``failed`` and the error text, so that one bad sequence does not stop the
others. The row is also written, last and atomically, to
``DIR/<name>/result.json``: the done-marker that a re-run reads to skip the
sequences already done (only ``ok`` rows of the same entry are skipped; a
failed sequence is tried again, its input may have been fixed).
"""

from __future__ import annotations

import json
import math
import os
import shutil
import tempfile
import time
from pathlib import Path
from typing import Any, Optional

import cv2

from ..sequence.run import run_odometry
from .manifest import ManifestEntry

__all__ = ["SUMMARY_COLUMNS", "RESULT_FILE", "run_sequence", "done_row", "failed_row"]

#: the columns of ``summary.csv``, in order (see :func:`run_sequence`)
SUMMARY_COLUMNS = ("name", "status", "frames", "path_length_m", "metric_share",
                   "carried_share", "unknown_share", "seconds", "ate_rmse_m",
                   "rpe_translation_rmse_m", "rpe_rotation_rmse_deg", "scale_drift_percent",
                   "error")
#: the done-marker of a sequence, in its output folder
RESULT_FILE = "result.json"


def failed_row(name: str, error: str, seconds: Optional[float] = None) -> dict:
    """The summary row of a sequence that failed with ``error`` (text);
    ``seconds`` None when not known (a task whose worker died)."""
    row = {k: None for k in SUMMARY_COLUMNS}
    row.update(name=name, status="failed", seconds=seconds, error=error)
    return row


def _finite(x: Any) -> Optional[float]:
    """A float for the row, None for NaN (JSON has no NaN; CSV gets empty)."""
    x = float(x)
    return x if math.isfinite(x) else None


def _ok_row(name: str, run: Any, seconds: float) -> dict:
    traj = run.trajectory
    counts = traj.status_counts
    n = max(len(traj.steps), 1)
    row = failed_row(name, "", seconds)
    # path of the metric trajectory only: direction-only stretches have no length
    row.update(status="ok", frames=int(traj.n_frames), path_length_m=traj.metric_path_length,
               metric_share=counts["metric"] / n, carried_share=counts["carried"] / n,
               unknown_share=counts["unknown"] / n, error=None)
    if run.errors is not None:
        e = run.errors
        row.update(ate_rmse_m=_finite(e.ate["rmse"]),
                   rpe_translation_rmse_m=_finite(e.rpe["translation_rmse"]),
                   rpe_rotation_rmse_deg=_finite(e.rpe["rotation_rmse_deg"]),
                   scale_drift_percent=_finite(e.scale_drift_percent))
    return row


def _write_json_atomic(path: Path, data: dict) -> None:
    # a temporary file beside the target, then one rename: a reader (a re-run)
    # sees the old marker or the new one, never half of one
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        with os.fdopen(fd, "w") as f:
            json.dump(data, f, indent=1)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def done_row(entry: ManifestEntry, out_root: Any) -> Optional[dict]:
    """The row of ``entry`` when ``out_root/<name>/`` already holds its finished
    run (an ``ok`` marker of the same paths and options), else None."""
    marker = Path(out_root) / entry.name / RESULT_FILE
    try:
        data = json.loads(marker.read_text())
    except (OSError, ValueError):
        return None
    if (not isinstance(data, dict) or data.get("entry") != entry.identity()
            or not isinstance(data.get("row"), dict) or data["row"].get("status") != "ok"):
        return None
    return data["row"]


def _remove_stale_partials(out: Path) -> None:
    # a worker killed mid-write (the retry case) leaves the hidden temporary
    # folders of mcgeom.sequence.outputs' atomic write beside ``out``; the
    # batch runs one task per sequence at a time, so any such folder of this
    # sequence is stale when its task starts
    if out.parent.is_dir():
        for stale in out.parent.glob(f".{out.name}.partial-*"):
            shutil.rmtree(stale, ignore_errors=True)
        for stale in out.parent.glob(f".{out.name}.old-*"):
            shutil.rmtree(stale, ignore_errors=True)


def run_sequence(entry: ManifestEntry, out_root: Any,
                 opencv_threads: Optional[int] = None) -> dict:
    """Run the sequence pipeline on ``entry`` into ``out_root/<name>/`` and
    return its summary row (keys :data:`SUMMARY_COLUMNS`).

    ``status``: ``ok`` or ``failed``; ``frames``; ``path_length_m`` (metres,
    the metric trajectory); ``metric_share`` / ``carried_share`` /
    ``unknown_share`` of the steps; ``seconds`` (wall time of the run); with
    ground truth ``ate_rmse_m``, ``rpe_translation_rmse_m``,
    ``rpe_rotation_rmse_deg`` and ``scale_drift_percent`` (None when not
    measurable); ``error``: the error text of a failed sequence. Never raises
    for a failing sequence; the row is written to ``result.json`` last.
    ``opencv_threads``: when given, ``cv2.setNumThreads`` of this process (a
    batch worker takes one core: OpenCV's own thread pool would compete with
    the other workers).
    """
    if opencv_threads is not None:
        cv2.setNumThreads(int(opencv_threads))
    out = Path(out_root) / entry.name
    _remove_stale_partials(out)
    t0 = time.perf_counter()
    try:
        run = run_odometry(entry.rig, entry.images, out, gt=entry.gt, title=entry.name,
                           **entry.options)
        row = _ok_row(entry.name, run, time.perf_counter() - t0)
    except Exception as exc:  # noqa: BLE001 - recorded in the row: the batch goes on
        row = failed_row(entry.name, f"{type(exc).__name__}: {exc}", time.perf_counter() - t0)
    _write_json_atomic(out / RESULT_FILE, {"entry": entry.identity(), "row": row})
    return row
