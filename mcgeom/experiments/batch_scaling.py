"""Throughput of ``mcgeom batch`` on Dask: sequences per minute with 1 and 2
worker processes, the scheduler's overhead per task, and what they predict for
10,000 sequences on 100 workers.

K short sequences are rendered (the demo's courtyard and rig at 320x240,
different seeds and starts), then the same manifest runs on a fresh
``LocalCluster`` of 1 and of 2 single-threaded worker processes (cluster
start and the workers' first import of mcgeom are left out of the timing: a
warm-up call runs on every worker first). The overhead per task is measured
twice: K x 25 no-op tasks through the same client (the scheduler's round trip
per task), and the batch's wall time times the workers minus the summed
in-task time, per sequence (which also holds the idle tail of the last tasks).

Model of a large batch (N sequences, W workers, t_task the mean in-task time,
o the scheduler's cost per task, which it pays serially):
``T ~ N / W x t_task + N x o``. It assumes equal tasks, a shared file system
as fast as the local disk, one scheduler, and W far below N (no tail). A
small-scale simulation checks it: M sleep tasks of a known length on the
2-worker cluster, measured against the model's prediction.
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Optional

from .common import Progress, add_count_and_seed, import_peer, no_progress, positive_int
from .render import render_sequence, surround_rig

__all__ = ["BatchTiming", "noop_task", "sleep_task", "warm_up", "render_manifest",
           "time_batch", "predicted_seconds", "add_arguments", "run_cli"]

#: starts along the loop (metres) cycled over the sequences: straights and turns
_STARTS = (0.0, 12.0, 30.0, 45.0, 60.0, 72.0)


def noop_task(i: int) -> int:
    """A task that does nothing (the scheduler's round trip alone)."""
    return i


def sleep_task(seconds: float) -> float:
    """A task of a known length (the small-scale simulation), seconds."""
    time.sleep(seconds)
    return seconds


def warm_up() -> bool:
    """Import the pipeline on a worker (not part of any timing)."""
    import mcgeom.sequence.run  # noqa: F401

    return True


@dataclass(frozen=True)
class BatchTiming:
    """One batch run: ``workers``; ``wall_s`` from submission to the summary;
    ``task_s``: the summed in-task time of the sequences; ``sequences`` (all
    ok when ``failed`` is 0); ``noop_s``: per no-op task (scheduler round trip);
    ``sim``: (tasks, task seconds, measured wall s) of the sleep simulation."""

    workers: int
    wall_s: float
    task_s: float
    sequences: int
    failed: int
    noop_s: float
    sim: tuple

    @property
    def per_minute(self) -> float:
        """Sequences per minute."""
        return 60.0 * self.sequences / self.wall_s

    @property
    def overhead_s(self) -> float:
        """Wall time x workers minus the in-task time, per sequence, seconds."""
        return (self.wall_s * self.workers - self.task_s) / self.sequences


def predicted_seconds(n: int, workers: int, task_s: float, overhead_s: float) -> float:
    """The model of the module docstring: ``n / workers x task_s + n x overhead_s``."""
    return n / workers * task_s + n * overhead_s


def render_manifest(root: Path, k: int, frames: int, seed: int = 0,
                    progress: Progress = no_progress) -> Path:
    """Render ``k`` sequences of ``frames`` frames into ``root`` and write
    ``root/manifest.csv`` (with ground truth); its path."""
    rig = surround_rig(320, 240)
    lines = ["name,rig,images,gt"]
    for i in progress(range(k), total=k, desc="render"):
        name = f"seq{i:03d}"
        render_sequence(root / name, n_frames=frames, seed=seed + i,
                        start=_STARTS[i % len(_STARTS)], step=0.9, rig=rig)
        lines.append(f"{name},{name}/rig.json,{name}/images,{name}/groundtruth_tum.txt")
    (root / "manifest.csv").write_text("\n".join(lines) + "\n")
    return root / "manifest.csv"


def time_batch(manifest: Path, out: Path, workers: int, noop_tasks: int,
               sim_tasks: int, sim_seconds: float) -> BatchTiming:
    """Run the batch on a fresh local cluster of ``workers`` processes and
    time it, then the no-op tasks and the sleep simulation on the same client."""
    from mcgeom.batch import connect, run

    with connect(workers=workers) as client:
        client.run(warm_up)
        t0 = time.perf_counter()
        rows = run(manifest, out, client=client)
        wall = time.perf_counter() - t0
        t0 = time.perf_counter()
        client.gather([client.submit(noop_task, i, pure=False) for i in range(noop_tasks)])
        noop = (time.perf_counter() - t0) / noop_tasks
        t0 = time.perf_counter()
        client.gather([client.submit(sleep_task, sim_seconds, pure=False)
                       for _ in range(sim_tasks)])
        sim = (sim_tasks, sim_seconds, time.perf_counter() - t0)
    failed = sum(r["status"] != "ok" for r in rows)
    return BatchTiming(workers, wall, sum(r["seconds"] or 0.0 for r in rows), len(rows),
                       failed, noop, sim)


def add_arguments(ap: argparse.ArgumentParser) -> None:
    """The options of ``mcgeom experiment batch_scaling``."""
    add_count_and_seed(ap, "--sequences", 8, "rendered sequences in the batch")
    ap.add_argument("--frames", type=positive_int, default=5, help="frames per sequence")
    ap.add_argument("--noop-tasks", type=positive_int, default=200,
                    help="no-op tasks that measure the scheduler's round trip")
    ap.add_argument("--keep", default=None, help="keep the rendered sequences and outputs "
                    "in this folder (default: a temporary folder, removed)")


def run_cli(args: argparse.Namespace, progress: Progress = no_progress) -> int:
    """Print the throughput, the overheads and the extrapolation."""
    import_peer("distributed", "the batch_scaling experiment", "'mcgeom[batch]'")
    root = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="mcgeom_batch_"))
    root.mkdir(parents=True, exist_ok=True)
    try:
        manifest = render_manifest(root / "data", args.sequences, args.frames, args.seed,
                                   progress)
        res: list[BatchTiming] = []
        for w in progress((1, 2), total=2, desc="workers"):
            res.append(time_batch(manifest, root / f"out_{w}", w, args.noop_tasks,
                                  sim_tasks=20 * w, sim_seconds=0.25))
        _report(res, args.sequences, args.frames)
    finally:
        if not args.keep:
            shutil.rmtree(root, ignore_errors=True)
    return 0 if all(r.failed == 0 for r in res) else 1


def _report(res: list[BatchTiming], k: int, frames: int) -> None:
    print(f"batch_scaling: {k} rendered sequences of {frames} frames (320x240, 5 cameras), "
          f"LocalCluster, 1 thread per worker process")
    print(f"{'workers':>7} {'wall s':>7} {'seq/min':>8} {'task s':>7} {'noop ms':>8} "
          f"{'idle+sched s/seq':>16} {'failed':>6}")
    for r in res:
        print(f"{r.workers:7d} {r.wall_s:7.2f} {r.per_minute:8.1f} "
              f"{r.task_s / r.sequences:7.2f} {1e3 * r.noop_s:8.2f} {r.overhead_s:16.3f} "
              f"{r.failed:6d}")
    one, two = res
    print(f"speed-up 2 workers / 1 worker: {two.per_minute / one.per_minute:.2f}x")
    print("small-scale simulation (sleep tasks, model T = N/W x t + N x o with o the "
          "no-op round trip):")
    for r in res:
        n, t, wall = r.sim
        pred = predicted_seconds(n, r.workers, t, r.noop_s)
        print(f"  {n} tasks of {t:.2f} s on {r.workers} worker(s): measured {wall:.2f} s, "
              f"model {pred:.2f} s ({100 * (wall / pred - 1):+.1f} %)")
    t_task = two.task_s / two.sequences
    o = two.noop_s
    n, w = 10_000, 100
    total = predicted_seconds(n, w, t_task, o)
    print(f"extrapolation to {n} sequences on {w} workers: t_task {t_task:.2f} s (these "
          f"{frames}-frame sequences), o {1e3 * o:.2f} ms: T ~ {n}/{w} x {t_task:.2f} + "
          f"{n} x {o * 1e3:.2f} ms = {total:.0f} s ({total / 60:.1f} min); the scheduler "
          f"term is {100 * n * o / total:.1f} % of it")
    # a real sequence is longer: per-task cost grows with frames, overhead does not
    per_frame = t_task / frames
    for f in (100, 1000):
        tt = per_frame * f
        tot = predicted_seconds(n, w, tt, o)
        print(f"  with {f}-frame sequences (t_task ~ {tt:.0f} s at {per_frame:.2f} s/frame): "
              f"T ~ {tot / 3600:.1f} h, scheduler {100 * n * o / tot:.3f} %")
