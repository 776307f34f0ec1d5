"""A batch on Dask distributed: one task per sequence, on a local cluster of
worker processes or on an existing cluster; the summary table at the end.

No cluster code of our own: a :class:`distributed.LocalCluster` (one thread
per worker process: the pipeline is CPU-bound and OpenCV is not guaranteed
to be thread-safe across calls) or a :class:`distributed.Client` to a
scheduler address. Faults are Dask's: a task whose worker dies is
rescheduled by the scheduler, up to its ``distributed.scheduler.allowed-failures``
(set to :data:`WORKER_DEATHS` for a local cluster); beyond that the sequence
is recorded as failed. Task exceptions are already rows (:func:`run_sequence`);
``retries=`` covers what escapes (e.g. a task that cannot be unpickled).

The workers read the manifest's paths and write ``DIR``: on a cluster both
must be on a file system every worker sees.
"""

from __future__ import annotations

import csv
import importlib.util
import os
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator, Optional, Sequence, Union

import dask
from distributed import Client, LocalCluster, as_completed

from ..validation import check_int
from .manifest import ManifestEntry, read_manifest
from .task import SUMMARY_COLUMNS, done_row, failed_row, run_sequence

__all__ = ["RETRIES", "WORKER_DEATHS", "connect", "run", "write_summary"]

#: retries of a task that raised (client.submit's retries=)
RETRIES = 2
#: deaths of workers running one task before it counts as failed (local cluster)
WORKER_DEATHS = 3


@contextmanager
def connect(workers: Optional[int] = None, scheduler: Optional[str] = None) -> Iterator[Client]:
    """A Dask client for a batch, closed on exit: to the scheduler at
    ``scheduler`` (e.g. ``tcp://host:8786``), or to a new
    ``LocalCluster(n_workers=workers, threads_per_worker=1, processes=True)``
    (``workers`` default: the CPU count). ValueError when both are given."""
    if workers is not None and scheduler is not None:
        raise ValueError("give workers (a local cluster) or scheduler (an existing one), "
                         "not both")
    if scheduler is not None:
        if not isinstance(scheduler, str) or not scheduler:
            raise ValueError(f"scheduler must be an address such as tcp://host:8786, got "
                             f"{scheduler!r}")
        client = Client(scheduler)
        try:
            yield client
        finally:
            client.close()
        return
    n = (os.cpu_count() or 1) if workers is None else check_int("workers", workers)
    if n < 1:
        raise ValueError(f"workers must be at least 1, got {n}")
    # a random dashboard port: several batches (or users) on one machine
    with dask.config.set({"distributed.scheduler.allowed-failures": WORKER_DEATHS}):
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                               dashboard_address=":0")
    try:
        client = Client(cluster)
        try:
            yield client
        finally:
            client.close()
    finally:
        cluster.close()


def _entries(manifest: Union[str, os.PathLike, Sequence[ManifestEntry]]) -> list[ManifestEntry]:
    if isinstance(manifest, (str, os.PathLike)):
        return read_manifest(manifest)
    entries = list(manifest)
    if not entries or not all(isinstance(e, ManifestEntry) for e in entries):
        raise ValueError("manifest must be a manifest file or a non-empty list of "
                         "ManifestEntry")
    names = [e.name for e in entries]
    if len(set(names)) != len(names):
        raise ValueError("manifest entries must have distinct names")
    return entries


def _cell(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return f"{value:.6g}" if abs(value) < 1e6 else f"{value:.6e}"
    return str(value)


def _replace_atomic(path: Path, write) -> None:
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    os.close(fd)
    try:
        write(tmp)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_summary(rows: Sequence[dict], out: Any) -> list[Path]:
    """Write ``out/summary.csv`` (and ``out/summary.parquet`` when pyarrow is
    installed), each atomically; the paths written."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)

    def csv_file(tmp: str) -> None:
        with open(tmp, "w", newline="") as f:
            w = csv.writer(f, lineterminator="\n")
            w.writerow(SUMMARY_COLUMNS)
            for r in rows:
                w.writerow([_cell(r.get(k)) for k in SUMMARY_COLUMNS])

    written = [out / "summary.csv"]
    _replace_atomic(written[0], csv_file)
    if importlib.util.find_spec("pyarrow") is not None:
        import pyarrow as pa
        import pyarrow.parquet as pq

        table = pa.Table.from_pylist([{k: r.get(k) for k in SUMMARY_COLUMNS} for r in rows])
        written.append(out / "summary.parquet")
        _replace_atomic(written[1], lambda tmp: pq.write_table(table, tmp))
    return written


def _results(client: Client, todo: list[ManifestEntry], out: Path) -> Iterator[dict]:
    # one core per worker process: OpenCV's thread pool limited to one thread
    # (Dask's nanny already sets OMP/MKL/OpenBLAS threads to 1)
    futures = {client.submit(run_sequence, e, str(out), 1, pure=False, retries=RETRIES): e
               for e in todo}
    for fut in as_completed(futures):
        entry = futures[fut]
        try:
            yield fut.result()
        except Exception as exc:  # noqa: BLE001 - e.g. KilledWorker: the sequence failed
            yield failed_row(entry.name, f"{type(exc).__name__}: {exc}")


def run(manifest: Union[str, os.PathLike, Sequence[ManifestEntry]], out: Any, *,
        client: Optional[Client] = None, workers: Optional[int] = None,
        scheduler: Optional[str] = None,
        progress: Optional[Callable[..., Iterable]] = None) -> list[dict]:
    """Run every sequence of ``manifest`` (a file, :func:`read_manifest`, or
    its entries) on Dask and write ``out/<name>/`` and ``out/summary.csv``.

    ``client``: an existing :class:`distributed.Client` (left open); else
    :func:`connect` with ``workers`` or ``scheduler``. Sequences whose
    finished run is already in ``out`` are not run again. ``progress``:
    ``progress(iterable, total=, desc=)`` wrapping the rows as they complete
    (skipped ones first). Returns the rows (keys
    :data:`mcgeom.batch.task.SUMMARY_COLUMNS`, and ``reused``: True for a
    sequence whose finished run was found in ``out`` and not run again) in
    manifest order.
    """
    entries = _entries(manifest)
    out = Path(out).resolve()
    if out.exists() and not out.is_dir():
        raise ValueError(f"out {str(out)!r} exists and is not a folder")
    if client is not None and (workers is not None or scheduler is not None):
        raise ValueError("give client, or workers / scheduler, not both")
    out.mkdir(parents=True, exist_ok=True)
    done = {e.name: done_row(e, out) for e in entries}
    todo = [e for e in entries if done[e.name] is None]
    bar = progress or (lambda it, total=None, desc=None: it)

    def rows(c: Optional[Client]) -> Iterable[dict]:
        yield from ({**r, "reused": True} for r in done.values() if r is not None)
        if todo:
            yield from ({**r, "reused": False} for r in _results(c, todo, out))

    got: dict[str, dict] = {}
    if client is not None or not todo:
        for r in bar(rows(client), total=len(entries), desc="sequences"):
            got[r["name"]] = r
    else:
        with connect(workers, scheduler) as c:
            for r in bar(rows(c), total=len(entries), desc="sequences"):
                got[r["name"]] = r
    result = [got[e.name] for e in entries]
    write_summary(result, out)
    return result
