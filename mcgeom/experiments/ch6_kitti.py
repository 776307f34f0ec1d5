"""Thesis ch. 6 on real data: the trajectory of the KITTI-00 stereo rig over
frames 13-76 (64 views, about 55 m) from the GTSAM tracked stereo
correspondences, with the rotations known (KITTI ground truth) and the two
cameras de-rotated into the rig frame (ch. 4.2, Fig. 4.2).

Every landmark is a track; each of its frames contributes two rays (cam0 and
cam1, offset by the 0.537 m baseline), so relations between frames mix
intra- and cross-camera rays and the translation is metric (the
inhomogeneous system of mcgeom.multiview). The centres come out in the
world frame of the ground truth with view 13 at the origin, so they are
compared with the ground truth directly, without any alignment:

* RMS centre error and the end-point error (metres), and the ratio of the
  recovered to the true path length (the metric scale);
* the same after a similarity alignment, for the variants whose scale is not
  observable (none here) and to separate shape from scale;
* the scale verdict, and the time of the solve.

The variants are the algebraic solutions of the thesis (``refine=False``);
the row "bundle adjustment" is the library's default, the centres refined by
:mod:`mcgeom.multiview_refine` (angular residuals, points and centres, the
rotations held) from the trilinear constrained solution of the consecutive
window. The chained two-view estimate (``known_rotation_translation`` on each
consecutive pair, the same rays, composed) is printed as a reference: what
the multi-view solve adds over pairwise steps.

Then cam0 alone, the single central camera of ch. 6 (no metric scale), with
the real tracks and with the tracks cut to at most three consecutive frames
as in ch. 6.5.1: plain SVD against the constrained minimisation on real
noise (about 2e-4 rad here).

    mcgeom experiment ch6_kitti [--first 13] [--last 76] [--window N] [--data DIR]

Each variant runs twice: with every relation of every track (tracks here
are up to 26 frames long) and with the consecutive window of ch. 6.2.3.

The data are read in place from ../shared/data (--data or MCGEOM_REAL_DATA
overrides it; see mcgeom.experiments.real_data).
"""

from __future__ import annotations

import argparse
import functools
import sys
import time
from pathlib import Path
from typing import Optional

import numpy as np

from mcgeom import multiview
from mcgeom.metrics import polyline_length
from mcgeom.estimators.known_rotation_translation import known_rotation_translation
from mcgeom.synth_views import similarity_align, spiral_measure
from mcgeom.types import RayPairs

from . import real_data as erd  # the shared loaders of the real recordings
from .common import Progress, no_progress, non_negative_int, write_line

#: the KITTI GT of frames 0..12 disagrees with the tracks (data README)
FIRST_GOOD_FRAME = 13


@functools.lru_cache(maxsize=4)
def load_observations(first: int = FIRST_GOOD_FRAME, last: int = 76,
                      root: Optional[Path] = None) -> tuple:
    """The stereo observations of frames ``first..last``: ``(rig, track, view,
    camera, pixels, T_world_rig)``, one row per pixel (both cameras of every
    landmark's observation; view = frame - first) and the true poses (m, 4, 4).
    Cached: several evaluations read the recording once (callers select
    from the arrays, never write to them)."""
    seq = erd.load_sequences(["kitti00_tracks"], root=root)[0]
    frames = seq.d["frames"][first:last + 1]
    names = seq.d["cameras"]
    track, view, cam, px = [], [], [], []
    for v, f in enumerate(frames):
        for lm, o in f["obs"].items():
            for c, name in enumerate(names):
                track.append(lm)
                view.append(v)
                cam.append(c)
                px.append(o[name])
    T = np.array([f["T_world_rig"] for f in frames])
    return (seq.rig, np.array(track), np.array(view), np.array(cam), np.array(px, float), T)


def load_tracks(first: int = FIRST_GOOD_FRAME, last: int = 76,
                root: Optional[Path] = None) -> tuple:
    """Observations of frames ``first..last`` as tracks.

    Returns (track, view, bearings, origins, rotations, centres_gt): one row per
    ray (both cameras of every stereo observation), view = frame - first,
    bearings and origins in the rig frame (metres), rotations (m, 3, 3)
    view_from_world and the true centres (m, 3) in the world frame relative to
    view 0 (metres)."""
    rig, track, view, cam, px, T = load_observations(first, last, root)
    origins, bearings = rig.rays(cam, px)
    rotations = np.transpose(T[:, :3, :3], (0, 2, 1))   # view_from_world = R_world_rig^T
    centres = T[:, :3, 3] - T[0, :3, 3]
    return (track, view, bearings, origins, rotations, centres)


def keep_multi_view_tracks(track, view, *arrays):
    """Only the rays of landmarks seen in at least two frames (a landmark of one
    frame carries no relation)."""
    ids, inv = np.unique(track, return_inverse=True)
    n_views = np.zeros(len(ids), int)
    pair = np.unique(np.c_[inv, view], axis=0)
    np.add.at(n_views, pair[:, 0], 1)
    keep = n_views[inv] >= 2
    return (track[keep], view[keep]) + tuple(a[keep] for a in arrays)


def cut_tracks(track: np.ndarray, view: np.ndarray, max_len: int) -> np.ndarray:
    """New track ids: each track split into runs of consecutive frames, each
    run into pieces of at most ``max_len`` frames (the short tracks of thesis
    ch. 6.5.1). One observation per (track, frame) is assumed (one camera)."""
    order = np.lexsort((view, track))
    t, v = track[order], view[order]
    new_run = np.r_[True, (t[1:] != t[:-1]) | (v[1:] != v[:-1] + 1)]
    run = np.cumsum(new_run) - 1
    start = np.flatnonzero(new_run)
    pos = np.arange(len(t)) - start[run]
    piece = run.astype(np.int64) * (int(pos.max()) + 1) + pos // max_len
    out = np.empty_like(piece)
    out[order] = piece
    return out


def chained_two_view(track, view, bearings, origins, rotations) -> np.ndarray:
    """Centres from known_rotation_translation on each consecutive frame pair
    (the shared landmarks' rays: cam0-cam0, cam1-cam1, cam0-cam1, cam1-cam0),
    composed. (m, 3), view 0 at the origin; NaN after a pair with too few rays."""
    m = len(rotations)
    c = np.full((m, 3), np.nan)
    c[0] = 0.0
    for k in range(m - 1):
        a, b = np.flatnonzero(view == k), np.flatnonzero(view == k + 1)
        common = np.intersect1d(track[a], track[b])
        ia = a[np.isin(track[a], common)]
        ib = b[np.isin(track[b], common)]
        ia = ia[np.lexsort((np.arange(len(ia)), track[ia]))]   # by landmark, cam0 then cam1
        ib = ib[np.lexsort((np.arange(len(ib)), track[ib]))]
        if len(common) < 3:
            break
        # every camera combination of each shared landmark
        i1 = np.repeat(ia.reshape(-1, 2), 2, axis=1).reshape(-1)
        i2 = np.tile(ib.reshape(-1, 2), (1, 2)).reshape(-1)
        # rig k -> rig k+1 in mcgeom's convention: X2 = R X1 + t
        Rk = rotations[k + 1] @ rotations[k].T
        rays = RayPairs(origins[i1], bearings[i1], origins[i2], bearings[i2])
        t = known_rotation_translation(rays, rotation=Rk).t
        # c_{k+1} = c_k - R_{k+1}^T t in the world frame
        c[k + 1] = c[k] - rotations[k + 1].T @ t
    return c


def evaluate(first: int = FIRST_GOOD_FRAME, last: int = 76, windows=(None, 0),
             out=print, root: Optional[Path] = None,
             progress: Progress = no_progress) -> dict:
    """Run the four variants with all relations of every track (window None)
    and with the consecutive window of ch. 6.2.3 (0: the smallest, 1 frame
    for bilinear and 2 for trilinear relations; or that many frames), then the
    chained two-view reference; print a table and return {name: dict(rms,
    end, scale, rms_sim, observable, seconds, views)}: errors in metres, the
    scale as the ratio of path lengths. ``root``: the data root (default
    real_data.DATA_ROOT); ``progress`` wraps the loop over the variants."""
    track, view, bearings, origins, rotations, gt = load_tracks(first, last, root)
    track, view, bearings, origins = keep_multi_view_tracks(track, view, bearings, origins)
    lengths = np.bincount(np.unique(np.c_[track, view], axis=0)[:, 0])
    lengths = lengths[lengths > 0]
    out(f"KITTI-00 frames {first}-{last}: {len(rotations)} views, {len(np.unique(track))} "
        f"landmarks seen in >= 2 frames, {len(track)} rays (cam0 + cam1), track length "
        f"median {np.median(lengths):.0f} / max {lengths.max()} frames; true path "
        f"{polyline_length(gt):.2f} m")
    out(f"{'variant':>50} {'RMS [m]':>9} {'end [m]':>9} {'path ratio':>11} "
        f"{'RMS sim [m]':>12} {'spiral':>7} {'scale':>14} {'s':>7}")
    res = {}
    variants = [(w, rel, sol) for w in windows for rel in multiview.RELATIONS
                for sol in multiview.SOLVERS]
    for window, rel, sol in progress(variants, total=len(variants), desc="ch6_kitti stereo"):
        q = 2 if rel == "bilinear" else 3
        win = None if window is None else (window or q - 1)
        t0 = time.perf_counter()
        r = multiview.translations_from_tracks(
            track, view, bearings, rotations, origins=origins, relation=rel,
            solver=sol, pairs="all" if win is None else "window", window=win, refine=False)
        dt = time.perf_counter() - t0
        where = "all" if win is None else f"window {win}"
        res[f"{rel} + {sol}, {where}"] = _row(r.centres, gt, r.scale.observable, dt)
    t0 = time.perf_counter()
    r = multiview.translations_from_tracks(track, view, bearings, rotations, origins=origins,
                                           relation="trilinear", pairs="window", window=2)
    res["bundle adjustment"] = _row(r.centres, gt, r.scale.observable, time.perf_counter() - t0)
    t0 = time.perf_counter()
    chained = chained_two_view(track, view, bearings, origins, rotations)
    res["chained two-view"] = _row(chained, gt, True, time.perf_counter() - t0)
    _print_rows(res, out)
    return res


def evaluate_monocular(first: int = FIRST_GOOD_FRAME, last: int = 76, max_lens=(None, 3),
                       out=print, root: Optional[Path] = None,
                       progress: Progress = no_progress) -> dict:
    """cam0 alone, as the single camera of thesis ch. 6 (no offsets: no metric
    scale, compared after a similarity alignment), with the real tracks and
    with the tracks cut to at most 3 consecutive frames (the short tracks of
    ch. 6.5.1): plain SVD against the constrained minimisation on real noise.
    Returns {name: row} as :func:`evaluate`."""
    track, view, bearings, origins, rotations, gt = load_tracks(first, last, root)
    cam0 = np.all(origins == 0.0, axis=1)
    track, view, bearings = track[cam0], view[cam0], bearings[cam0]
    res = {}
    for max_len in progress(max_lens, total=len(max_lens), desc="ch6_kitti cam0"):
        tr = track if max_len is None else cut_tracks(track, view, max_len)
        tr, vw, b = keep_multi_view_tracks(tr, view, bearings)
        where = "real tracks" if max_len is None else f"tracks <= {max_len} frames"
        for rel in multiview.RELATIONS:
            for sol in multiview.SOLVERS:
                t0 = time.perf_counter()
                r = multiview.translations_from_tracks(tr, vw, b, rotations, relation=rel,
                                                       solver=sol)
                res[f"cam0 {rel} + {sol}, {where}"] = _row(
                    r.centres, gt, r.scale.observable, time.perf_counter() - t0)
    out("cam0 alone (no scale: compare 'RMS sim', the error after a similarity; spiral = "
        "largest step-direction error):")
    _print_rows(res, out)
    return res


def _print_rows(res: dict, out) -> None:
    for name, row in res.items():
        out(f"{name:>50} {row['rms']:9.3f} {row['end']:9.3f} {row['scale']:11.4f} "
            f"{row['rms_sim']:12.3f} {np.degrees(row['spiral']):7.2f} "
            f"{'metric' if row['observable'] else 'unobservable':>14} "
            f"{row['seconds']:7.3f}")


def _row(c: np.ndarray, gt: np.ndarray, observable: bool, seconds: float) -> dict:
    ok = np.isfinite(c).all(axis=1)
    err = np.linalg.norm(c[ok] - gt[ok], axis=1)
    aligned, rms_sim = similarity_align(c[ok], gt[ok])
    return {"rms": float(np.sqrt(np.mean(err ** 2))), "end": float(err[-1]),
            "scale": polyline_length(c[ok]) / polyline_length(gt[ok]), "rms_sim": float(rms_sim),
            "spiral": spiral_measure(aligned, gt[ok]),
            "observable": bool(observable), "seconds": seconds, "views": int(ok.sum())}


def add_arguments(ap: argparse.ArgumentParser) -> None:
    """The options of ``mcgeom experiment ch6_kitti``."""
    ap.add_argument("--first", type=non_negative_int, default=FIRST_GOOD_FRAME,
                    help="first frame (the ground truth of frames 0-12 is suspect)")
    ap.add_argument("--last", type=non_negative_int, default=76, help="last frame")
    ap.add_argument("--window", type=non_negative_int, default=0,
                    help="the window of the windowed runs (ch. 6.2.3): frames at most this "
                         "far apart; 0 = the smallest (1 bilinear, 2 trilinear)")
    erd.add_data_argument(ap)


def run_cli(args: argparse.Namespace, progress: Progress = no_progress) -> int:
    """Print the stereo table and the cam0 table; 2 if the data are missing."""
    out = write_line   # the first lines are printed while the bar runs
    root = erd.data_root_or_none(args, "ch6_kitti")
    if root is None:
        return 2
    if args.last <= args.first:
        print(f"mcgeom experiment ch6_kitti: error: --last ({args.last}) must be after "
              f"--first ({args.first})", file=sys.stderr)
        return 2
    evaluate(args.first, args.last, (None, args.window), out=out, root=root,
             progress=progress)
    evaluate_monocular(args.first, args.last, out=out, root=root, progress=progress)
    return 0
