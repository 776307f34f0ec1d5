"""The metric scale of thesis ch. 6's multi-view solve for a rig without
overlap: the algebraic least squares against the bundle adjustment that
refines them (:mod:`mcgeom.multiview_refine`).

A 4-camera ring (radius 0.5 m, f = 800 px, 90 deg apart, no two views
overlap: every track is intra-camera) drives ``--frames`` steps of 1 m,
turning by a given yaw per step (:func:`mcgeom.synth_views.rig_drive_sequence`),
with ``--sigma`` px noise. Known rotations; the centres from
:func:`mcgeom.multiview.translations_from_tracks` with the rig offsets, once
with ``refine=False`` (the algebraic solution and its first-order std) and
once with the default bundle adjustment. Per yaw and variant: how often the
scale is called metric, the median error of the travelled distance, the
median relative std, how many metric answers are more than 3 of their stds
off, how many are "metric and wrong" (off by more than max(10 %, 4 stds)),
the RMS of error / std over the metric ones (1 for an honest std), and the
median seconds per solve.

``mcgeom experiment ch6_rig_scale`` (defaults: 20 sequences per yaw).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from .. import multiview, synth
from ..metrics import polyline_length
from ..synth_views import rig_drive_sequence
from .common import Progress, add_count_and_seed, no_progress

__all__ = ["run", "add_arguments", "run_cli", "YAWS"]

#: yaw per step (deg) of the sequences: straight (critical), near-critical, turning
YAWS = (0.0, 0.5, 2.0, 10.0, 20.0)


def run(trials: int = 20, seed: int = 0, yaws=YAWS, frames: int = 6, sigma: float = 0.5,
        relations=("bilinear", "trilinear"), progress: Progress = no_progress) -> list[dict]:
    """One row per (yaw, relation, refined): the counts and medians printed by
    :func:`run_cli` (errors relative, seconds)."""
    rig = synth.ring_rig(4, radius=0.5, f=800.0)
    cells = {}
    jobs = [(y, k) for y in yaws for k in range(trials)]
    for yaw, k in progress(jobs, total=len(jobs), desc="ch6_rig_scale"):
        seq = rig_drive_sequence(rig, [yaw] * frames, sigma_px=sigma, rng=seed + k)
        true = polyline_length(seq.centres)
        for rel in relations:
            for refine in (False, True):
                t0 = time.perf_counter()
                r = multiview.translations_from_tracks(seq.track, seq.view, seq.bearings,
                                                       seq.rotations, origins=seq.origins,
                                                       relation=rel, refine=refine)
                dt = time.perf_counter() - t0
                err = polyline_length(r.centres) / true - 1.0 if r.scale.observable else float("nan")
                cells.setdefault((yaw, rel, refine), []).append(
                    (r.scale.observable, err, r.scale.rel_std, dt))
    rows = []
    for (yaw, rel, refine), v in cells.items():
        obs = np.array([o for o, *_ in v], bool)
        err = np.array([e for _, e, _, _ in v])[obs]
        std = np.array([s for _, _, s, _ in v])[obs]
        z = err / std
        rows.append({"yaw": yaw, "relation": rel, "refined": refine, "trials": len(v),
                     "metric": int(obs.sum()),
                     "median_error": float(np.median(err)) if err.size else float("nan"),
                     "median_rel_std": float(np.median(std)) if std.size else float("nan"),
                     "beyond_3_std": int(np.sum(np.abs(z) > 3.0)),
                     "metric_and_wrong": int(np.sum(np.abs(err) > np.maximum(0.1, 4 * std))),
                     "rms_z": float(np.sqrt(np.mean(z ** 2))) if z.size else float("nan"),
                     "seconds": float(np.median([d for *_, d in v]))})
    return rows


def add_arguments(ap: argparse.ArgumentParser) -> None:
    """The options of ``mcgeom experiment ch6_rig_scale``."""
    add_count_and_seed(ap, "--trials", 20, "sequences per yaw")
    ap.add_argument("--frames", type=int, default=6, help="steps per sequence")
    ap.add_argument("--sigma", type=float, default=0.5, help="pixel noise (px)")
    ap.add_argument("--yaws", type=float, nargs="+", default=list(YAWS),
                    help="yaw per step (deg), one set of sequences each")


def run_cli(args: argparse.Namespace, progress: Progress = no_progress) -> int:
    """Print the table."""
    if args.frames < 2 or not args.sigma > 0:
        raise ValueError("ch6_rig_scale: --frames must be >= 2 and --sigma > 0")
    rows = run(args.trials, args.seed, args.yaws, args.frames, args.sigma, progress=progress)
    print(f"4-camera ring without overlap, {args.frames} steps of 1 m, {args.sigma} px; travelled "
          "distance of the centres against the truth; 'wrong' = metric yet off by more than "
          "max(10 %, 4 stds)")
    print(f"{'yaw/step':>8} {'relations':>9} {'solution':>17} {'metric':>7} {'median err':>10} "
          f"{'median std':>10} {'>3 std':>6} {'wrong':>5} {'RMS err/std':>11} {'s':>6}")
    for r in rows:
        how = "bundle adjustment" if r["refined"] else "algebraic"
        print(f"{r['yaw']:7.1f}° {r['relation']:>9} {how:>17} {r['metric']:>3}/{r['trials']:<3} "
              f"{r['median_error']:+10.4f} {r['median_rel_std']:10.4f} {r['beyond_3_std']:6d} "
              f"{r['metric_and_wrong']:5d} {r['rms_z']:11.2f} {r['seconds']:6.3f}")
    return 0
