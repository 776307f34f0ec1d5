"""``bnb_lp`` (thesis ch. 10) on the real recordings, started from the inliers of
the default robust pipeline.

For every pair of KITTI raw 0023 and DDAD scene_01 (parked) / scene_02 (moving),
in both correspondence modes of :mod:`mcgeom.experiments.real_data` (intra-camera
only; intra + cross-camera), the experiment

1. matches the frames and runs :func:`mcgeom.cv.estimate` (5+1 LO-RANSAC, 1.5 px),
   as :func:`mcgeom.experiments.real_data.evaluate_pair` does;
2. keeps at most ``--inliers`` (300) of its inliers (a seeded random subset) as
   Plücker rays in the rig frame;
3. runs ``mcgeom.estimate(rays, method="bnb_lp", gap=...)`` on them (default gap
   1e-4 rad: the certified gap of issue 18) and prints, next to the 5+1 start,
   the rotation error (deg), |t| against the ground truth, the verdict, the time,
   the blocks examined, the certified gap, why the search stopped, and how many
   correspondences the residual-outlier guard removed.

``--cache DIR`` stores the rays of each pair and mode (``.npz``) on the first run
and reads them on the next, so that a change of ``bnb_lp`` is measured on the
same correspondences (the matching takes most of the time otherwise)::

    mcgeom experiment bnb_real --cache /tmp/bnb_real
    mcgeom experiment bnb_real --sets kitti_raw --max-pairs 2 --max-seconds 5

The data are read in place (``--data``, else $MCGEOM_REAL_DATA, else ../shared/data).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any, Iterator, Optional

import numpy as np

from .common import (Progress, no_progress, non_negative_float, non_negative_int,
                     positive_float, positive_int, write_line)
from .real_data import (MODES, STATIC_T, THRESHOLD_PX, Features, add_data_argument,
                        correspondences, data_root_or_none, load_sequences, rot_angle_deg)

#: the recordings of issue 18's bnb_lp figures
BNB_SETS = ("kitti_raw", "dgp_scene_01", "dgp_scene_02")


def inlier_cases(keys=BNB_SETS, root: Optional[Path] = None, max_pairs: Optional[int] = None,
                 n_inliers: int = 300, threshold: float = THRESHOLD_PX, seed: int = 0,
                 cache: Optional[Path] = None,
                 progress: Progress = no_progress) -> Iterator[dict]:
    """Yield one case per recording, pair and mode: the rays (rig frame, metres) of
    at most ``n_inliers`` inliers of :func:`mcgeom.cv.estimate` (``threshold`` in
    pixels), the ground truth ``R_gt``, ``t_gt`` (rig2_from_rig1) and the 5+1
    estimate's rotation error (deg) and metric |t| (m).

    With ``cache`` (a folder) the cases are stored there as ``.npz`` and read back
    on later calls with the same arguments.
    """
    from mcgeom.cv import estimate
    from mcgeom.types import RayPairs

    seqs = load_sequences(keys, root, max_pairs)
    for seq in seqs:
        feats = Features(seq.nfeatures) if seq.kind == "images" else None
        for k1, k2 in progress(seq.pairs, total=len(seq.pairs), desc=seq.key):
            names = {mode: f"{seq.key}_{k1}-{k2}_{mode}_{n_inliers}_{threshold:g}_{seed}.npz"
                     for mode in MODES}
            corr = None
            for mode in MODES:
                path = Path(cache) / names[mode] if cache is not None else None
                R_gt, t_gt = seq.gt_motion(k1, k2)
                case = {"key": seq.key, "pair": (k1, k2), "mode": mode, "R_gt": R_gt,
                        "t_gt": t_gt, "static": bool(seq.static)}
                if path is not None and path.is_file():
                    z = np.load(path)
                    rays = RayPairs(z["o1"], z["d1"], z["o2"], z["d2"], z["c1"], z["c2"])
                    case.update(rays=rays, rot_5p1=float(z["rot_5p1"]),
                                t_5p1=float(z["t_5p1"]), n_inliers=int(z["n_inliers"]))
                    yield case
                    continue
                if corr is None:
                    corr = correspondences(seq, k1, k2, feats)
                use = corr if mode == "intra+cross" else corr.subset(corr.intra)
                m = estimate(use.p1, use.p2, use.c1, use.c2, seq.rig, threshold=threshold)
                inl = use.subset(m.inliers)
                keep = np.arange(len(inl.p1))
                if len(keep) > n_inliers:
                    keep = np.sort(np.random.default_rng(seed).choice(keep, n_inliers,
                                                                      replace=False))
                inl = inl.subset(np.isin(np.arange(len(inl.p1)), keep))
                rays = seq.rig.ray_pairs(inl.p1, inl.p2, inl.c1, inl.c2)
                # |t| of 5+1 where it is metric (observable, or t = 0 on a static
                # rig), nan where t is a direction only
                t5 = float(np.linalg.norm(m.t))
                case.update(rays=rays, rot_5p1=rot_angle_deg(m.R @ R_gt.T),
                            t_5p1=t5 if (m.scale.observable or t5 == 0.0) else float("nan"),
                            n_inliers=int(np.count_nonzero(m.inliers)))
                if path is not None:
                    path.parent.mkdir(parents=True, exist_ok=True)
                    np.savez(path, o1=rays.origins1, d1=rays.dirs1, o2=rays.origins2,
                             d2=rays.dirs2, c1=rays.cam1, c2=rays.cam2,
                             rot_5p1=case["rot_5p1"], t_5p1=case["t_5p1"],
                             n_inliers=case["n_inliers"])
                yield case


def run_bnb(case: dict, **options: Any) -> dict:
    """``bnb_lp`` on one case of :func:`inlier_cases`: errors against the ground
    truth and the search's figures (``options`` go to the estimator)."""
    import mcgeom

    row = {k: case[k] for k in ("key", "pair", "mode", "static", "rot_5p1", "t_5p1",
                                "n_inliers")}
    row.update(n=len(case["rays"]), t_gt=float(np.linalg.norm(case["t_gt"])))
    t0, c0 = time.perf_counter(), time.process_time()
    try:
        m = mcgeom.estimate(case["rays"], method="bnb_lp", **options)
    except Exception as exc:  # report, do not hide: the row says FAILED
        row.update(ok=False, error=f"{type(exc).__name__}: {exc}",
                   time=time.perf_counter() - t0)
        return row
    info = m.info
    t_norm = float(np.linalg.norm(m.t))
    t_shown = t_norm if (m.scale.observable or t_norm == 0.0) else float("nan")
    row.update(ok=True, time=time.perf_counter() - t0, cpu=time.process_time() - c0,
               rot=rot_angle_deg(m.R @ case["R_gt"].T),
               t_est=t_shown, observable=bool(m.scale.observable), reason=m.scale.reason,
               blocks=int(info.get("blocks", 0)), gap=float(info.get("gap", float("nan"))),
               linf=float(info.get("linf", float("nan"))), stop=str(info.get("stop", "-")),
               pruned=int(info.get("pruned", 0)), domain=str(info.get("domain", "-")),
               start=str(info.get("initial_method", "-")))
    return row


HEADER = ("%-13s %-5s %-11s %4s %8s %8s %7s %7s %7s %-5s %7s %7s %8s %9s %9s %-10s %4s  %s" % (
    "set", "pair", "mode", "n", "rot5p1", "rot_bnb", "|t_gt|", "|t5p1|", "|t_bnb|", "verd",
    "cpu(s)", "wall(s)", "blocks", "gap(rad)", "linf", "stop", "pruned", "domain / reason"))


def format_row(r: dict) -> str:
    """One printed line of :func:`run_bnb`'s row."""
    head = "%-13s %-5s %-11s %4d %8.3f" % (r["key"], "%d-%d" % r["pair"], r["mode"], r["n"],
                                           r["rot_5p1"])
    if not r["ok"]:
        return head + "  FAILED after %.2f s: %s" % (r["time"], r["error"])
    return head + " %8.3f %7.3f %7.3f %7.3f %-5s %7.3f %7.3f %8d %9.2e %9.2e %-10s %4d  %s / %s" % (
        r["rot"], r["t_gt"], r["t_5p1"], r["t_est"], "OBS" if r["observable"] else "unobs",
        r["cpu"], r["time"], r["blocks"], r["gap"], r["linf"], r["stop"], r["pruned"], r["domain"],
        r["reason"])


def summary(rows: list[dict]) -> list[str]:
    """Per recording and mode: median rotation error, worst rotation error, median
    and worst time, how many hit a budget, and the static pairs' |t|."""
    out = []
    for key in dict.fromkeys(r["key"] for r in rows):
        for mode in MODES:
            sel = [r for r in rows if r["key"] == key and r["mode"] == mode]
            ok = [r for r in sel if r["ok"]]
            if not sel:
                continue
            if not ok:
                out.append("%-13s %-11s all %d FAILED" % (key, mode, len(sel)))
                continue
            rot = np.array([r["rot"] for r in ok])
            tm = np.array([r["cpu"] for r in ok])
            budget = sum(r["stop"] in ("time_limit", "max_blocks") for r in ok)
            out.append("%-13s %-11s %d pairs: rot median %.3f max %.3f deg (5+1 median %.3f) | "
                       "CPU median %.3f max %.3f s | stopped by a budget %d | failed %d | "
                       "observable %d" % (
                           key, mode, len(sel), np.median(rot), rot.max(),
                           np.median([r["rot_5p1"] for r in ok]), np.median(tm), tm.max(),
                           budget, len(sel) - len(ok), sum(r["observable"] for r in ok)))
    return out


def ladybug_outliers(trials: int = 100, seed: int = 0, threshold: float = 1.0,
                     progress: Progress = no_progress, **options: Any) -> list[dict]:
    """The residual-outlier case of issue 18: ``bnb_lp`` on the inliers of the
    robust pipeline on the Ladybug head of :mod:`mcgeom.experiments.robust_vs_poselib`
    (300 correspondences, 30 % outliers, 0.5 px, ``threshold`` px), with and
    without its outlier guard (``prune``). One row per trial: the rotation
    errors (deg) of the robust start and of ``bnb_lp`` with and without the
    guard, the CPU seconds of each, how many true outliers were among the
    start's inliers and how many correspondences the guard dropped (and how
    many of those were true outliers)."""
    import mcgeom
    from mcgeom import metrics, synth
    from mcgeom.cv import estimate

    rng = np.random.default_rng(seed)
    rig = synth.ladybug2()
    rows = []
    for _ in progress(range(trials), total=trials, desc="ladybug"):
        R = synth.random_rotation(rng, 0.3)
        while metrics.rotation_error(R, np.eye(3)) < 0.05:
            R = synth.random_rotation(rng, 0.3)
        t = rng.normal(size=3)
        t /= np.linalg.norm(t)
        p = synth.make_problem(rig, R, t, 300, rng, pixel_noise=0.5, outlier_fraction=0.3)
        m = estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, rig, threshold=threshold)
        rays = rig.ray_pairs(p.pixels1, p.pixels2, p.cam1, p.cam2)
        row = {"rot_start": np.degrees(metrics.rotation_error(m.R, R)),
               "outliers_in": int(np.count_nonzero(m.inliers & ~p.inlier))}
        for guard in (False, True):
            c0 = time.process_time()
            b = mcgeom.estimate(rays, "bnb_lp", mask=m.inliers, prune=guard, **options)
            key = "guard" if guard else "plain"
            row[f"rot_{key}"] = np.degrees(metrics.rotation_error(b.R, R))
            row[f"cpu_{key}"] = time.process_time() - c0
            if guard:
                idx = b.info["pruned_index"]
                row["pruned"] = int(idx.size)
                row["pruned_outliers"] = int(np.count_nonzero(~p.inlier[idx]))
        rows.append(row)
    return rows


def ladybug_summary(rows: list[dict], bad_deg: float = 1.0) -> list[str]:
    """Medians and the share of trials whose rotation error exceeds ``bad_deg``."""
    out = []
    n = len(rows)
    for key, name in (("start", "robust start (5+1 LO-RANSAC)"), ("plain", "bnb_lp, no guard"),
                      ("guard", "bnb_lp with the guard")):
        rot = np.array([r[f"rot_{key}"] for r in rows])
        line = "%-30s rot median %.3f deg, > %g deg on %d/%d trials (%.1f %%)" % (
            name, np.median(rot), bad_deg, np.count_nonzero(rot > bad_deg), n,
            100.0 * np.count_nonzero(rot > bad_deg) / n)
        if key != "start":
            line += ", CPU median %.3f s" % np.median([r[f"cpu_{key}"] for r in rows])
        out.append(line)
    out.append("trials with true outliers among the start's inliers: %d/%d; the guard dropped "
               "%d correspondences in all, %d of them true outliers, and left %d true outliers" % (
                   sum(r["outliers_in"] > 0 for r in rows), n, sum(r["pruned"] for r in rows),
                   sum(r["pruned_outliers"] for r in rows),
                   sum(r["outliers_in"] - r["pruned_outliers"] for r in rows)))
    return out


def add_arguments(ap: argparse.ArgumentParser) -> None:
    """The options of ``mcgeom experiment bnb_real``."""
    ap.add_argument("--sets", nargs="*", default=list(BNB_SETS), choices=BNB_SETS,
                    metavar="SET", help="recordings, of " + ", ".join(BNB_SETS))
    ap.add_argument("--max-pairs", type=positive_int, default=None,
                    help="only the first pairs of each recording (default: all)")
    ap.add_argument("--inliers", type=positive_int, default=300,
                    help="inliers of the 5+1 estimate given to bnb_lp (a seeded subset; default: 300)")
    ap.add_argument("--gap", type=non_negative_float, default=1e-4,
                    help="bnb_lp's gap: stop when no block can improve by more (rad; default: 1e-4)")
    ap.add_argument("--max-seconds", type=non_negative_float, default=0.0,
                    help="bnb_lp's wall-time budget, seconds (default: 0, none)")
    ap.add_argument("--threshold", type=positive_float, default=THRESHOLD_PX,
                    help="inlier threshold of the 5+1 start, pixels (default: 1.5)")
    ap.add_argument("--seed", type=int, default=0, help="seed of the inlier subset and the Ladybug trials (default: 0)")
    ap.add_argument("--cache", type=Path, default=None,
                    help="folder for the inlier rays (.npz), written once and then read "
                         "(default: none, match every time)")
    ap.add_argument("--ladybug", type=non_negative_int, default=0, metavar="TRIALS",
                    help="also run the synthetic residual-outlier case (Ladybug head, 30 %% "
                         "outliers) with this many trials, with and without the guard (default: 0)")
    ap.add_argument("--skip-real", action="store_true",
                    help="only the synthetic case, no recordings needed (default: off)")
    add_data_argument(ap)


def run_cli(args: argparse.Namespace, progress: Progress = no_progress) -> int:
    """Print one row per pair and mode, then the per-recording summary; 2 if the
    data are missing."""
    options = {"gap": args.gap}
    if args.max_seconds > 0:
        options["max_seconds"] = args.max_seconds
    if args.ladybug:
        rows = ladybug_outliers(args.ladybug, args.seed, progress=progress, **options)
        write_line("residual outliers: bnb_lp on the inliers of the robust pipeline, Ladybug "
                   "head, 300 correspondences, 30 %% outliers, 0.5 px, %d trials, options %s" % (
                       args.ladybug, options))
        for line in ladybug_summary(rows):
            write_line(line)
        write_line("")
    if args.skip_real:
        return 0
    root = data_root_or_none(args, "bnb_real")
    if root is None:
        return 2
    write_line("bnb_lp on <= %d inliers of 5+1 (%.2f px), options %s" % (
        args.inliers, args.threshold, options))
    write_line(HEADER)
    rows = []
    for case in inlier_cases(args.sets, root, args.max_pairs, args.inliers, args.threshold,
                             args.seed, args.cache, progress):
        r = run_bnb(case, **options)
        rows.append(r)
        write_line(format_row(r))
    write_line("")
    for line in summary(rows):
        write_line(line)
    write_line("|t_bnb| is nan where the verdict is unobservable (t is then no metric "
               "estimate), 0 for the static answer; static pairs have |t_gt| < %.2f m; cpu(s): "
               "process CPU time of the call (the machine may be shared: wall time is not the "
               "cost)" % STATIC_T)
    return 0
