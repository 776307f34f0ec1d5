"""Is every estimator honest on the real recordings? (issue 18)

For each frame pair of the real recordings in ../shared/data (read in place,
see :mod:`mcgeom.experiments.real_data`), the robust pipeline
(:func:`mcgeom.cv.estimate`, default 5+1) selects the inliers among the
intra-camera correspondences, and among intra- plus cross-camera ones; every
requested estimator then runs on those inlier rays through
:func:`mcgeom.estimate` with the rig's calibration error
(``calibration_std``, the documented default where the file gives none;
``known_rotation_translation`` is given the ground-truth rotation, and
``upright_four_point`` the recording's own vertical where it has one --
KITTI raw's OXTS roll and pitch -- and is skipped elsewhere)::

    mcgeom experiment honesty
    mcgeom experiment honesty --estimators refine e_socp --sets kitti_raw --max-pairs 3

Printed per estimator, recording, pair and mode: the rotation error (deg), the
returned ``|t|`` and whether it is metric (``m``), a unit direction (``u``) or
zero (``0``), the ground-truth ``|t|``, the scale error of a metric answer,
the verdict (OBS, unobs, or static = "no translation detected"), its
``rel_std`` and the time. The summary counts, per estimator, the confident
wrong answers: an observable verdict whose ``|t|`` is more than 3 ``rel_std``
(and more than :data:`SCALE_SLACK`, the ground truth's own jitter) from the
truth, or an observable non-zero ``|t|`` on a static recording.
"""

from __future__ import annotations

import argparse
import os
import time
from typing import Any, Optional, Sequence as Seq

import numpy as np

from .common import Progress, no_progress, positive_float, positive_int, write_line
from .real_data import (MODES, SET_KEYS, STATIC_T, THRESHOLD_PX, Features, Sequence,
                        add_data_argument, correspondences, data_root_or_none, load_sequences,
                        rot_angle_deg)

#: the estimators evaluated by default (every registered one but bnb_lp, ~1 s a
#: pair: ``--estimators bnb_lp`` adds it); upright_four_point runs on the
#: recordings that give a vertical (:attr:`Sequence.vertical`: KITTI raw's OXTS
#: roll and pitch) and is skipped, with a row saying so, on the others
DEFAULT_ESTIMATORS = ("linear17", "refine", "e_socp", "known_rotation_translation",
                      "five_plus_one", "eigensolver", "six_point", "upright_four_point")
#: the recordings evaluated by default (keys of real_data.SET_KEYS)
DEFAULT_SETS = ("kitti_raw", "dgp_scene_01", "dgp_scene_02", "euroc")
#: relative scale error tolerated beyond 3 rel_std: the ground truth's own
#: per-step jitter (KITTI raw OXTS: ~5 % of |t|, see the data README)
SCALE_SLACK = 0.05


def inlier_rays(seq: Sequence, corr: Any, mode: str, threshold: float = THRESHOLD_PX):
    """The inlier rays (:class:`mcgeom.types.RayPairs`, rig frame) of
    :func:`mcgeom.cv.estimate` on the correspondences of ``mode`` ("intra" or
    "intra+cross"), and the robust estimate itself; ``threshold`` in pixels."""
    from mcgeom.cv import estimate
    use = corr if mode == "intra+cross" else corr.subset(corr.intra)
    m = estimate(use.p1, use.p2, use.c1, use.c2, seq.rig, threshold=threshold)
    inl = use.subset(np.asarray(m.inliers, bool))
    return seq.rig.ray_pairs(inl.p1, inl.p2, inl.c1, inl.c2), m


def needs_vertical(name: str) -> bool:
    """Whether the registered estimator ``name`` takes the vertical
    (``gravity1``/``gravity2``: upright_four_point)."""
    from mcgeom import registry
    return "gravity1" in registry.get(name).options


def evaluate(rays: Any, name: str, R_gt: np.ndarray, t_gt: np.ndarray,
             calibration_std: Any = None,
             vertical: Optional[tuple[np.ndarray, np.ndarray]] = None) -> dict:
    """Run estimator ``name`` on ``rays`` and compare with the ground truth
    ``(R_gt, t_gt)`` (rig2_from_rig1, metres). ``calibration_std``: the rig's
    extrinsic calibration error (:attr:`mcgeom.rig.Rig.extrinsic_std`, what a
    user with the rig file passes to :func:`mcgeom.estimate`; None: noise
    only). ``vertical``: (gravity1, gravity2) in the rig frames at the two
    times, for an estimator that takes them. A failure is reported in the row
    (``ok`` False, ``error``), not raised."""
    import mcgeom
    opts: dict = {"rotation": R_gt} if name == "known_rotation_translation" else {}
    if vertical is not None:
        opts.update(gravity1=vertical[0], gravity2=vertical[1])
    t0 = time.perf_counter()
    try:
        m = mcgeom.estimate(rays, name, calibration_std=calibration_std, **opts)
    except Exception as exc:   # the row says FAILED and why
        return {"ok": False, "error": f"{type(exc).__name__}: {exc}",
                "time": time.perf_counter() - t0}
    dt = time.perf_counter() - t0
    t = np.asarray(m.t, float).ravel()
    nt = float(np.linalg.norm(t))
    static = isinstance(m.info, dict) and m.info.get("translation_detected") is False
    kind = "0" if nt == 0.0 else ("m" if m.scale.observable else "u")
    ngt = float(np.linalg.norm(t_gt))
    scale_err = (abs(nt / ngt - 1.0) if m.scale.observable and ngt >= STATIC_T
                 else float("nan"))
    rel = float(m.scale.rel_std)
    if m.scale.observable:
        wrong = (nt > STATIC_T) if ngt < STATIC_T else \
            (scale_err > 3.0 * rel + SCALE_SLACK)
    else:
        wrong = False
    return {"ok": True, "rot_err": rot_angle_deg(np.asarray(m.R) @ R_gt.T), "t": nt,
            "kind": kind, "t_gt": ngt, "scale_err": scale_err,
            "verdict": "static" if static else ("OBS" if m.scale.observable else "unobs"),
            "rel_std": rel, "time": dt, "reason": m.scale.reason,
            "confident_wrong": bool(wrong)}


HEADER = "%-13s %-5s %-11s %-26s %5s %8s %8s %7s %8s %-6s %8s %7s  %s" % (
    "set", "pair", "mode", "estimator", "#rays", "rot(deg)", "|t|", "|t_gt|", "scale_err",
    "verd", "rel_std", "time(s)", "reason")


def format_row(key: str, pair: tuple, mode: str, name: str, n: int, r: dict) -> str:
    """One printed row of :func:`run`."""
    head = "%-13s %-5s %-11s %-26s %5d" % (key, "%d-%d" % pair, mode, name, n)
    if not r["ok"]:
        return f"{head}  FAILED after {r['time']:.2f} s: {r['error'][:110]}"
    scale = "%8.3f" % r["scale_err"] if np.isfinite(r["scale_err"]) else "%8s" % "-"
    flag = "  << confident and wrong" if r["confident_wrong"] else ""
    return "%s %8.3f %7.3f%s %7.3f %s %-6s %8.3g %7.3f  %s%s" % (
        head, r["rot_err"], r["t"], r["kind"], r["t_gt"], scale, r["verdict"], r["rel_std"],
        r["time"], r["reason"][:70], flag)


def run(seqs: Seq[Sequence], estimators: Seq[str] = DEFAULT_ESTIMATORS,
        threshold: float = THRESHOLD_PX, out=print,
        progress: Progress = no_progress) -> list[dict]:
    """Every estimator on the inliers of every pair and mode of ``seqs``;
    prints the rows with ``out`` and returns them (dicts with ``set``,
    ``pair``, ``mode``, ``estimator`` and the fields of :func:`evaluate`)."""
    rows = []
    out(HEADER)
    for seq in seqs:
        feats = Features(seq.nfeatures) if seq.kind == "images" else None
        for k1, k2 in progress(seq.pairs, total=len(seq.pairs), desc=seq.key):
            corr = correspondences(seq, k1, k2, feats)
            R_gt, t_gt = seq.gt_motion(k1, k2)
            for mode in MODES:
                if mode == "intra+cross" and bool(np.all(corr.intra)):
                    continue   # no overlapping cameras: the same as intra
                try:
                    rays, _ = inlier_rays(seq, corr, mode, threshold)
                except Exception as exc:   # the robust pipeline itself failed
                    out(f"{seq.key:13s} {k1}-{k2} {mode:11s} cv.estimate FAILED: "
                        f"{type(exc).__name__}: {exc}")
                    continue
                for name in estimators:
                    vertical = None
                    if needs_vertical(name):
                        if seq.vertical is None:
                            out(f"{seq.key:13s} {'%d-%d' % (k1, k2):5s} {mode:11s} "
                                f"{name:26s} skipped: the recording gives no vertical")
                            continue
                        vertical = (seq.vertical(k1), seq.vertical(k2))
                    r = evaluate(rays, name, R_gt, t_gt, seq.rig.extrinsic_std, vertical)
                    r.update(set=seq.key, pair=(k1, k2), mode=mode, estimator=name,
                             n=len(rays))
                    rows.append(r)
                    out(format_row(seq.key, (k1, k2), mode, name, len(rays), r))
    return rows


def summarize(rows: Seq[dict], out=print) -> None:
    """Per estimator, recording and mode: median and largest rotation error,
    verdict counts, median scale error of the metric answers, confident wrong
    answers, failures and median time."""
    out("")
    out("%-26s %-13s %-11s %5s %9s %9s %4s %5s %6s %9s %6s %6s %8s" % (
        "estimator", "set", "mode", "pairs", "rot_med", "rot_max", "OBS", "unobs", "static",
        "scale_med", "wrong", "failed", "time_med"))
    keys = sorted({(r["estimator"], r["set"], r["mode"]) for r in rows})
    for name, key, mode in keys:
        sel = [r for r in rows if (r["estimator"], r["set"], r["mode"]) == (name, key, mode)]
        ok = [r for r in sel if r["ok"]]
        if not ok:
            out("%-26s %-13s %-11s %5d  all FAILED" % (name, key, mode, len(sel)))
            continue
        rot = np.array([r["rot_err"] for r in ok])
        sc = [r["scale_err"] for r in ok if np.isfinite(r["scale_err"])]
        count = {v: sum(r["verdict"] == v for r in ok) for v in ("OBS", "unobs", "static")}
        out("%-26s %-13s %-11s %5d %9.3f %9.3f %4d %5d %6d %9s %6d %6d %8.3f" % (
            name, key, mode, len(sel), np.median(rot), rot.max(), count["OBS"], count["unobs"],
            count["static"], "%.3f" % np.median(sc) if sc else "-",
            sum(r["confident_wrong"] for r in ok), len(sel) - len(ok),
            np.median([r["time"] for r in ok])))


def add_arguments(ap: argparse.ArgumentParser) -> None:
    """The options of ``mcgeom experiment honesty``."""
    ap.add_argument("--estimators", nargs="+", default=list(DEFAULT_ESTIMATORS),
                    metavar="NAME", help="registered estimators to evaluate (default: "
                    + " ".join(DEFAULT_ESTIMATORS) + ")")
    ap.add_argument("--sets", nargs="+", default=list(DEFAULT_SETS), choices=SET_KEYS,
                    metavar="SET", help="recordings, of " + ", ".join(SET_KEYS)
                    + " (default: " + " ".join(DEFAULT_SETS) + ")")
    ap.add_argument("--max-pairs", type=positive_int, default=None,
                    help="only the first pairs of each recording (default: all)")
    ap.add_argument("--threshold", type=positive_float, default=THRESHOLD_PX,
                    help="inlier threshold of cv.estimate, pixels")
    add_data_argument(ap)


def run_cli(args: argparse.Namespace, progress: Progress = no_progress) -> int:
    """Print the rows and the summary; 2 if the data are missing."""
    from mcgeom import registry
    known = set(registry.names())
    bad = [e for e in args.estimators if e not in known]
    if bad:
        raise ValueError(f"--estimators: unknown estimator(s) {bad}; registered: "
                         f"{sorted(known)}")
    root = data_root_or_none(args, "honesty")
    if root is None:
        return 2
    import mcgeom
    out = write_line
    out("mcgeom %s from %s; data %s" % (mcgeom.__version__, os.path.dirname(mcgeom.__file__),
                                        root))
    out("each estimator on the inliers of cv.estimate (threshold %.2f px); "
        "known_rotation_translation is given the GT rotation; |t| kind: m metric, u unit "
        "direction, 0 zero" % args.threshold)
    t0 = time.perf_counter()
    seqs = load_sequences(args.sets, root, args.max_pairs)
    rows = run(seqs, args.estimators, args.threshold, out, progress)
    summarize(rows, out)
    out("total %.1f s" % (time.perf_counter() - t0))
    return 0


__all__ = ["DEFAULT_ESTIMATORS", "DEFAULT_SETS", "SCALE_SLACK", "inlier_rays", "evaluate",
           "run", "summarize", "add_arguments", "run_cli"]
