"""The whole sequence pipeline on the real image recordings: images to tracks
(SIFT, intra- and cross-camera matching) to a metric trajectory, against the
recordings' ground truth.

Sets (``../shared/data``): KITTI raw 0023 (stereo, 7 frames, 0.9 m steps),
DDAD scene_02 (6-camera surround rig, 3 frames, 1.27 m steps), DDAD scene_01
(the parked car: the truth does not move), EuRoC V1_01 (a static MAV, 24
frames). Printed per set: the steps by scale status, the ATE after an SE(3)
alignment (no scale), the end-point error without alignment (metres), the
per-step translation errors (metres) and, for the static sets, the largest
distance and rotation from the start (target: within 2 cm and 0.2 deg).

    mcgeom experiment odometry_real [--sets kitti_raw,ddad_02,ddad_01,euroc] [--data DIR]
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Optional

import numpy as np

from mcgeom.io.images import find_image_sequence
from mcgeom.metrics import rotation_angle
from mcgeom.sequence import build_tracks, estimate_trajectory
from mcgeom.sequence.evaluation import evaluate

from . import real_data as erd
from .common import Progress, no_progress, write_line

#: name -> (data folder, loader options, levels from an image to the sequence folder)
SETS = {
    "kitti_raw": ("kitti_raw_0023_tiny", {}, 3),
    "ddad_02": ("dgp_ddad_testscene", {"scene": "scene_02"}, 2),
    "ddad_01": ("dgp_ddad_testscene", {"scene": "scene_01"}, 2),
    "euroc": ("euroc_v101_kimera", {}, 3),
}


def load(name: str, root: Path) -> tuple:
    """``(rig, images folder, gt)`` of a set: the rig from its calibration,
    the folder holding its camera folders, and world_from_rig ground truth
    (F, 4, 4) with the first frame the identity (metres)."""
    folder, options, up = SETS[name]
    d = erd.import_loader(folder, root).load(**options)
    rig = erd.rig_from_calib(d)
    first = Path(d["frames"][0]["images"][rig.names[0]])
    images = first.parents[up - 1]
    T = np.array([f["T_world_rig"] for f in d["frames"]])
    return rig, images, np.linalg.inv(T[0]) @ T


def run_set(name: str, root: Path, progress: Progress = no_progress) -> dict:
    """The pipeline on one set; a dict of the figures printed."""
    rig, images, gt = load(name, root)
    seq = find_image_sequence(images, rig)
    if seq.n_frames != len(gt):
        raise ValueError(f"{name}: {seq.n_frames} frames of images but {len(gt)} ground-truth "
                         f"poses")
    tracks = build_tracks(rig, seq, progress=progress)
    traj = estimate_trajectory(rig, tracks)
    err = evaluate(traj, gt)
    known = traj.known
    out = {"name": name, "frames": seq.n_frames, "cameras": len(rig),
           "status": traj.status_counts,
           "errors": err, "step_errors": None if err is None else err.step_errors}
    if known[-1]:
        out["end_error_m"] = float(np.linalg.norm(traj.poses[-1, :3, 3] - gt[-1, :3, 3]))
    if known.any():
        c = traj.poses[known, :3, 3]
        out["max_from_start_m"] = float(np.max(np.linalg.norm(c, axis=1)))
        out["max_rotation_from_start_deg"] = float(np.degrees(max(
            rotation_angle(T[:3, :3]) for T in traj.poses[known])))
    out["true_path_m"] = float(np.sum(np.linalg.norm(np.diff(gt[:, :3, 3], axis=0), axis=1)))
    return out


def report(r: dict, out=write_line) -> None:
    """Print one set's figures."""
    s = r["status"]
    out(f"-- {r['name']}: {r['frames']} frames, {r['cameras']} cameras, true path "
        f"{r['true_path_m']:.3f} m; steps {s['metric']} metric / {s['carried']} carried / "
        f"{s['unknown']} unknown")
    if r["errors"] is not None:
        out("   " + r["errors"].summary())
    if "end_error_m" in r:
        out(f"   end-point error (no alignment): {r['end_error_m']:.3f} m")
    if r["step_errors"] is not None:
        out("   per-step translation error [m]: " + " ".join(
            "-" if not np.isfinite(e) else f"{e:.3f}" for e in r["step_errors"]))
    if r["true_path_m"] < 0.05 and "max_from_start_m" in r:
        ok = r["max_from_start_m"] <= 0.02 and r["max_rotation_from_start_deg"] <= 0.2
        out(f"   static truth: the estimate stays within {100 * r['max_from_start_m']:.2f} cm "
            f"and {r['max_rotation_from_start_deg']:.3f} deg of the start "
            f"({'within' if ok else 'OUTSIDE'} 2 cm / 0.2 deg)")


def add_arguments(ap: argparse.ArgumentParser) -> None:
    """The experiment's options."""
    ap.add_argument("--sets", default=",".join(SETS),
                    help="comma-separated sets: " + ", ".join(SETS))
    erd.add_data_argument(ap)


def run_cli(args: argparse.Namespace, progress: Progress = no_progress) -> int:
    """``mcgeom experiment odometry_real``."""
    root: Optional[Path] = erd.data_root_or_none(args, "odometry_real")
    if root is None:
        return 2
    names = [n for n in args.sets.split(",") if n]
    unknown = [n for n in names if n not in SETS]
    if unknown:
        print(f"mcgeom experiment odometry_real: error: unknown set(s) {', '.join(unknown)}; "
              f"choose from {', '.join(SETS)}")
        return 2
    for name in names:
        report(run_set(name, root, progress))
    return 0
