"""Is the first-order calibration part of the std of |t| right on a real
near-critical step? DDAD scene_02 (6 cameras, 1.27 m straight ahead with
0.107 deg of yaw: close to the critical motion of thesis ch. 7.3.2).

Per seed of the robust estimate (:func:`mcgeom.cv.estimate`, 1 px): the
verdict, the error of the metric estimate ``info["t_metric"]`` against the
ground truth, the verdict's relative std of |t| with its noise and
calibration parts, and on the estimate's inliers (least squares, the rig's
stated extrinsic error: 2 mm / 0.1 deg by default) the first-order
calibration part (:func:`mcgeom.observability.calibration_scale_std`) next
to the sampled one (:func:`mcgeom.observability.sampled_calibration_scale_std`,
``--draws`` rigs drawn with that error, each refitted). Where the two
differ, the estimate is not linear in the extrinsics over their error and
the first-order figure, which the verdict uses, does not tell the spread.

    mcgeom experiment calibration_real [--seeds 10] [--draws 256] [--step 0] [--data DIR]
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Optional

import numpy as np

from mcgeom.cv import estimate
from mcgeom.io.images import find_image_sequence
from mcgeom.observability import calibration_scale_std, sampled_calibration_scale_std
from mcgeom.sequence import build_tracks

from . import real_data as erd
from .common import Progress, no_progress, positive_int, write_line
from .odometry_real import load

#: the set: DDAD scene_02 of ``../shared/data``
SET = "ddad_02"


def ddad_tracks(root: Path, progress: Progress = no_progress) -> tuple:
    """``(rig, tracks, gt)`` of the set: its rig, the feature tracks of its
    images (:func:`mcgeom.sequence.build_tracks`) and world_from_rig ground
    truth (F, 4, 4), the first frame the identity."""
    rig, images, gt = load(SET, root)
    return rig, build_tracks(rig, find_image_sequence(images, rig), progress=progress), gt


def run(root: Path, seeds: int = 10, draws: int = 256, step: int = 0,
        progress: Progress = no_progress, data: Optional[tuple] = None) -> list[dict]:
    """One row per seed 0 .. ``seeds`` - 1 of the estimate of frames ``step``
    -> ``step`` + 1 (see the module); ``data`` the :func:`ddad_tracks` of
    ``root`` when already built."""
    if not 0 <= step < 2:
        raise ValueError(f"step must be 0 or 1 for {SET} (3 frames), got {step}")
    rig, tracks, gt = data if data is not None else ddad_tracks(root, progress)
    p1, p2, c1, c2, _ = tracks.correspondences(step, step + 1)
    rays = rig.ray_pairs(p1, p2, c1, c2)
    true_t = np.linalg.solve(gt[step + 1], gt[step])[:3, 3]
    rows = []
    for seed in progress(range(seeds), total=seeds, desc="seeds"):
        m = estimate(p1, p2, c1, c2, rig, threshold=1.0, seed=seed)
        inl = rays.take(np.flatnonzero(np.asarray(m.inliers, bool)))
        t = m.info["t_metric"]
        rows.append({
            "seed": seed, "metric": bool(m.scale.observable),
            "scale_err": float(np.linalg.norm(t) / np.linalg.norm(true_t) - 1.0),
            "rel_std": float(m.scale.rel_std),
            "noise": float(m.info.get("scale_rel_std_noise", np.nan)),
            "calibration": float(m.info.get("scale_rel_std_calibration", np.nan)),
            "inliers": len(inl), "cross": int(np.count_nonzero(inl.cam1 != inl.cam2)),
            "first_order": float(calibration_scale_std(inl, m.R, t, rig.extrinsic_std)[0]),
            "sampled": sampled_calibration_scale_std(inl, m.R, t, rig.extrinsic_std,
                                                     draws=draws, seed=seed)})
    return rows


def report(rows: list[dict], draws: int, out=write_line) -> None:
    """The table and the ratio of the sampled to the first-order figure."""
    out(f"{SET}: the verdict's relative std of |t| (noise, calibration) and, on the inliers "
        f"(least squares), the calibration part first-order and sampled ({draws} rigs)")
    out(f"{'seed':>4} {'verdict':>9} {'|t| err':>8} {'rel_std':>8} {'noise':>7} {'calib':>7} "
        f"{'inliers':>7} {'cross':>5} {'1st ord':>8} {'sampled':>8} {'ratio':>6}")
    for r in rows:
        out(f"{r['seed']:>4} {'metric' if r['metric'] else 'not':>9} {r['scale_err']:>+8.3f} "
            f"{r['rel_std']:>8.3f} {r['noise']:>7.4f} {r['calibration']:>7.3f} "
            f"{r['inliers']:>7} {r['cross']:>5} {r['first_order']:>8.3f} {r['sampled']:>8.3f} "
            f"{r['sampled'] / r['first_order']:>6.2f}")
    met = [r for r in rows if r["metric"]]
    ratio = np.median([r["sampled"] / r["first_order"] for r in rows])
    out(f"median sampled / first-order: {ratio:.2f} over {len(rows)} seeds; {len(met)} called "
        f"metric" + (f", whose sampled calibration part is {min(r['sampled'] for r in met):.3f}"
                     f"-{max(r['sampled'] for r in met):.3f}" if met else ""))


def add_arguments(ap: argparse.ArgumentParser) -> None:
    """The experiment's options."""
    ap.add_argument("--seeds", type=positive_int, default=10, help="seeds of the estimate")
    ap.add_argument("--draws", type=positive_int, default=256,
                    help="rigs drawn for the sampled calibration part (even)")
    ap.add_argument("--step", type=int, default=0, help="the step: frames STEP -> STEP + 1")
    erd.add_data_argument(ap)


def run_cli(args: argparse.Namespace, progress: Progress = no_progress) -> int:
    """``mcgeom experiment calibration_real``."""
    root: Optional[Path] = erd.data_root_or_none(args, "calibration_real")
    if root is None:
        return 2
    if args.draws % 2:
        print(f"mcgeom experiment calibration_real: error: --draws must be even, got "
              f"{args.draws}")
        return 2
    report(run(root, args.seeds, args.draws, args.step, progress), args.draws)
    return 0
