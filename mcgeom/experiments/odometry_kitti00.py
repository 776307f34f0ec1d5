"""The sequence back end on real tracks: the KITTI-00 stereo rig, frames 13-76.

The GTSAM tracked stereo correspondences (no images; both cameras of every
landmark's observation, 0.537 m baseline) become :class:`mcgeom.sequence.Tracks`
and go through :func:`mcgeom.sequence.estimate_trajectory`. Nothing of the
ground truth enters the estimate (unlike ``ch6_kitti``, which takes the true
rotations). Printed per variant, against the KITTI ground truth (first frame
the identity):

* ATE RMSE: the RMS position error after the rigid (SE(3), no scale)
  alignment of the estimated centres to the true ones, in metres and in %
  of the true path length (target: <= 1 %);
* scale drift: estimated / true path length - 1, in % (target: |.| <= 2 %);
* the end-point error without any alignment, and the scale status counts.

Variants: the back end with the metric from the tracks (the rig offsets in
the ch. 6 system) or from the observed steps' two-frame lengths, and
trilinear windows of 2, 3 and 4 frames; next to (a) chaining the two-frame
estimates of the default robust pipeline naively and (b) chaining PoseLib's
``estimate_generalized_relative_pose`` (LO-RANSAC + refinement; needs poselib).

    mcgeom experiment odometry_kitti00 [--first 13] [--last 76] [--data DIR]

The data are read in place (--data or MCGEOM_REAL_DATA; see
mcgeom.experiments.real_data).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Callable, Optional

import numpy as np

from mcgeom.metrics import absolute_trajectory_error, polyline_length
from mcgeom.odometry import chain
from mcgeom.sequence import Tracks, estimate_trajectory

from . import real_data as erd
from .ch6_kitti import FIRST_GOOD_FRAME, load_observations
from .common import Progress, import_peer, no_progress, non_negative_int, write_line

#: (name, options of estimate_trajectory)
VARIANTS = (
    ("back end: metric from tracks, window 2", dict(window=2, metric_from="tracks")),
    ("back end: metric from tracks, window 3", dict(window=3, metric_from="tracks")),
    ("back end: metric from tracks, window 4", dict(window=4, metric_from="tracks")),
    ("back end: metric from steps, window 2", dict(window=2, metric_from="steps")),
)


def load(first: int = FIRST_GOOD_FRAME, last: int = 76, root: Optional[Path] = None
         ) -> tuple:
    """``(rig, tracks, gt)``: the KITTI-00 stereo rig, the tracks of frames
    ``first..last`` renumbered from 0 (each landmark one track, seen by cam0
    and cam1) and the true world_from_rig poses (m, 4, 4), the first the
    identity (metres)."""
    rig, track, frame, cam, px, T = load_observations(first, last, root)
    tracks = Tracks(track, frame, cam, px, len(T))
    return rig, tracks, np.linalg.inv(T[0]) @ T


def _at(centres: np.ndarray) -> np.ndarray:
    """Poses (n, 4, 4) with the given centres (the ATE uses positions only)."""
    T = np.tile(np.eye(4), (len(centres), 1, 1))
    T[:, :3, 3] = centres
    return T


def _row(centres: np.ndarray, gt: np.ndarray, seconds: float, note: str) -> dict:
    ok = np.all(np.isfinite(centres), axis=1)
    g = gt[:, :3, 3]
    length = polyline_length(g)
    # RMS after the rigid motion (no scale) that best maps the estimate onto
    # the truth (Umeyama 1991 without the scale factor), as evo computes it
    ate = (absolute_trajectory_error(_at(centres[ok]), gt[ok])["rmse"] if ok.sum() >= 3
           else float("nan"))
    return {"ate": ate, "ate_pct": 100.0 * ate / length,
            "drift_pct": 100.0 * (polyline_length(centres[ok]) / polyline_length(g[ok]) - 1.0),
            "end": float(np.linalg.norm(centres[-1] - g[-1])) if ok[-1] else float("nan"),
            "frames": int(ok.sum()), "seconds": seconds, "note": note}


def _poselib_motions(rig, tracks: Tracks, threshold: float,
                     progress: Progress) -> list[np.ndarray]:
    """rig2_from_rig1 4x4 motions of PoseLib's generalized relative pose on
    every step (every camera combination of the tracks, as the back end)."""
    poselib = import_peer("poselib", "odometry_kitti00 (the PoseLib reference)")
    exts, cams = [], []
    for c in rig.cameras:
        pose = poselib.CameraPose()
        pose.R, pose.t = c.R, c.t            # cam_from_rig, as mcgeom
        exts.append(pose)
        K = c.K
        cams.append({"model": "PINHOLE", "width": int(c.width), "height": int(c.height),
                     "params": [K[0, 0], K[1, 1], K[0, 2], K[1, 2]]})
    # PoseLib scales max_epipolar_error by the cameras' focal length (pixels,
    # like mcgeom's threshold); more iterations than its 1000 minimum so that
    # its RANSAC is not the weak point of the comparison
    ransac = {"max_epipolar_error": threshold, "min_iterations": 2000,
              "max_iterations": 100000, "success_prob": 0.9999, "seed": 0}
    out = []
    steps = range(tracks.n_frames - 1)
    for k in progress(steps, total=len(steps), desc="poselib"):
        p1, p2, c1, c2, _ = tracks.correspondences(k, k + 1)
        matches = []
        for i in range(len(rig.cameras)):
            for j in range(len(rig.cameras)):
                sel = (c1 == i) & (c2 == j)
                if sel.any():
                    pm = poselib.PairwiseMatches()
                    pm.cam_id1, pm.cam_id2 = i, j
                    pm.x1, pm.x2 = p1[sel], p2[sel]
                    matches.append(pm)
        pose, _ = poselib.estimate_generalized_relative_pose(matches, exts, cams, exts, cams,
                                                             ransac, {})
        M = np.eye(4)
        M[:3, :3], M[:3, 3] = np.asarray(pose.R), np.asarray(pose.t)
        out.append(M)
    return out


def evaluate(first: int = FIRST_GOOD_FRAME, last: int = 76, threshold: float = 1.0,
             out: Callable[[str], None] = print, root: Optional[Path] = None,
             progress: Progress = no_progress, with_poselib: bool = True) -> dict:
    """Run the variants, print a table, return {name: row}: ``ate`` (m),
    ``ate_pct`` (% of the true path), ``drift_pct`` (%), ``end`` (m),
    ``frames`` (located), ``seconds``, ``note``. ``threshold``: pixels."""
    rig, tracks, gt = load(first, last, root)
    out(f"KITTI-00 frames {first}-{last}: {tracks.n_frames} frames, {len(tracks)} "
        f"observations of {len(np.unique(tracks.track))} landmarks (cam0 + cam1); true path "
        f"{polyline_length(gt[:, :3, 3]):.2f} m")
    res = {}
    traj = None
    for name, opts in progress(VARIANTS, total=len(VARIANTS), desc="variants"):
        t0 = time.perf_counter()
        tr = estimate_trajectory(rig, tracks, threshold=threshold, **opts)
        st = tr.status
        res[name] = _row(tr.centres, gt, time.perf_counter() - t0,
                         f"{st.count('metric')} metric / {st.count('carried')} carried / "
                         f"{st.count('unknown')} unknown, {len(tr.segments)} segment(s)")
        traj = traj or tr
    motions = [s.motion for s in traj.steps]
    n_obs = sum(m is not None and m.scale.observable for m in motions)
    if all(m is not None for m in motions):
        naive = chain(m.T for m in motions)
        res["(a) naive chain of the two-frame steps"] = _row(
            np.array(naive)[:, :3, 3], gt, float("nan"),
            f"{n_obs}/{len(motions)} steps observable")
    if with_poselib:
        t0 = time.perf_counter()
        pl = chain(_poselib_motions(rig, tracks, threshold, progress))
        res["(b) naive chain of PoseLib generalized relpose"] = _row(
            np.array(pl)[:, :3, 3], gt, time.perf_counter() - t0, "always metric")
    out(f"{'variant':>48} {'ATE [m]':>8} {'ATE %':>6} {'drift %':>8} {'end [m]':>8} "
        f"{'s':>6}  scale status")
    for name, r in res.items():
        out(f"{name:>48} {r['ate']:8.3f} {r['ate_pct']:6.2f} {r['drift_pct']:8.2f} "
            f"{r['end']:8.3f} {r['seconds']:6.1f}  {r['note']}")
    return res


def add_arguments(ap: argparse.ArgumentParser) -> None:
    """The options of ``mcgeom experiment odometry_kitti00``."""
    ap.add_argument("--first", type=non_negative_int, default=FIRST_GOOD_FRAME,
                    help="first frame (the ground truth of frames 0-12 is suspect)")
    ap.add_argument("--last", type=non_negative_int, default=76, help="last frame")
    ap.add_argument("--no-poselib", action="store_true",
                    help="leave out the PoseLib reference")
    erd.add_data_argument(ap)


def run_cli(args: argparse.Namespace, progress: Progress = no_progress) -> int:
    """Print the table; 2 if the data are missing (the command line reports a
    missing poselib; --no-poselib leaves it out)."""
    root = erd.data_root_or_none(args, "odometry_kitti00")
    if root is None:
        return 2
    if args.last < args.first + 2:
        print(f"mcgeom experiment odometry_kitti00: error: --last ({args.last}) must be at "
              f"least --first + 2 ({args.first + 2})", file=sys.stderr)
        return 2
    evaluate(args.first, args.last, out=write_line, root=root, progress=progress,
             with_poselib=not args.no_poselib)
    return 0
