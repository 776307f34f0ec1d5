"""Thesis ch. 8.5.1 synthetic experiment: linear17 next to PoseLib.

Three generalized cameras (a non-axial rig, an axial rig, a non-overlapping
stereo head), 100 intra-camera rays, Gaussian angular noise of 0.05 deg on the
ray directions, 1,000 random trials each. For each method: median and 90th
percentile of the rotation error, the translation-direction error (degrees)
and the scale error |1 - |t_est| / |t_true|| (thesis Figs. 8.6-8.9).

PoseLib's ``estimate_generalized_relative_pose`` (RANSAC over its minimal
6-point solver + non-linear refinement) receives the same rays as pixels of a
virtual pinhole camera (f = 500 px) per rig camera. The table:
``mcgeom experiment ch8 [--trials 1000]`` (needs poselib).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import mcgeom
from mcgeom import metrics, synth

from .common import Progress, add_count_and_seed, import_peer, no_progress

RIGS = {
    "non-axial rig": (lambda rng: synth.generic_rig(4, rng)),
    "axial rig": (lambda rng: synth.axial_rig(3)),
    "stereo head": (lambda rng: synth.stereo_head(0.5)),
}
F_VIRTUAL = 500.0


def _errors(R, t, R_true, t_true):
    """(rotation error deg, direction error deg, |1 - scale ratio|)"""
    d, ratio = metrics.translation_errors(t, t_true)
    return np.degrees(metrics.rotation_error(R, R_true)), np.degrees(d), abs(1 - ratio)


def _poselib(prob):
    poselib = import_peer("poselib", "the ch8 experiment")
    rig, rays = prob.rig, prob.rays
    exts, cams = [], []
    for c in rig.cameras:
        p = poselib.CameraPose()
        p.R = c.R
        p.t = c.t
        exts.append(p)
        cams.append({"model": "PINHOLE", "width": 2000, "height": 2000,
                     "params": [F_VIRTUAL, F_VIRTUAL, 0.0, 0.0]})
    matches = []
    for i in range(len(rig.cameras)):
        for j in range(len(rig.cameras)):
            sel = (rays.cam1 == i) & (rays.cam2 == j)
            if sel.sum() == 0:
                continue
            b1 = rays.dirs1[sel] @ rig.cameras[i].R.T   # bearings in camera frames
            b2 = rays.dirs2[sel] @ rig.cameras[j].R.T
            pm = poselib.PairwiseMatches()
            pm.cam_id1, pm.cam_id2 = i, j
            pm.x1 = F_VIRTUAL * b1[:, :2] / b1[:, 2:]
            pm.x2 = F_VIRTUAL * b2[:, :2] / b2[:, 2:]
            matches.append(pm)
    pose, _ = poselib.estimate_generalized_relative_pose(
        matches, exts, cams, exts, cams,
        {"max_epipolar_error": 3.0, "min_iterations": 100, "max_iterations": 1000}, {})
    return pose.R, pose.t


def run(trials: int = 1000, seed: int = 0, noise_deg: float = 0.05, n_rays: int = 100,
        progress: Progress = no_progress) -> dict:
    """{rig: {method: (trials x 3 errors array, seconds)}}: per trial the rotation
    error (deg), translation-direction error (deg) and |1 - scale ratio|; the
    total time of the method's calls (s)."""
    out = {}
    for name, factory in RIGS.items():
        rng = np.random.default_rng(seed)
        errs = {"linear17": [], "poselib": []}
        secs = {"linear17": 0.0, "poselib": 0.0}
        for _ in progress(range(trials), total=trials, desc=f"ch8 {name}"):
            rig = factory(rng)
            R, t = synth.random_motion(rng, max_angle=0.5, t_norm=1.0)
            while np.linalg.norm(R - np.eye(3)) < 0.1:   # keep the scale observable
                R, t = synth.random_motion(rng, max_angle=0.5, t_norm=1.0)
            prob = synth.make_problem(rig, R, t, n_rays, rng, angular_noise=np.deg2rad(noise_deg),
                                      require_visible=False)
            t0 = time.perf_counter()
            m = mcgeom.estimate(prob.rays, "linear17")
            secs["linear17"] += time.perf_counter() - t0
            errs["linear17"].append(_errors(m.R, m.t if m.scale.observable else m.info["t_metric"],
                                            R, t))
            t0 = time.perf_counter()
            Rp, tp = _poselib(prob)
            secs["poselib"] += time.perf_counter() - t0
            errs["poselib"].append(_errors(Rp, tp, R, t))
        out[name] = {k: (np.array(v), secs[k]) for k, v in errs.items()}
    return out


def table(res: dict) -> str:
    """The table of :func:`run`: medians and 90th percentiles, ms per call."""
    lines = [f"{'rig':<14} {'method':<9} {'rot med/p90 [deg]':>19} {'dir med/p90 [deg]':>19} "
             f"{'scale err med/p90':>19} {'ms/call':>8}"]
    for rig, methods in res.items():
        for meth, (e, secs) in methods.items():
            med, p90 = np.median(e, 0), np.percentile(e, 90, axis=0)
            lines.append(f"{rig:<14} {meth:<9} {med[0]:9.4f}/{p90[0]:<9.4f} "
                         f"{med[1]:9.4f}/{p90[1]:<9.4f} {med[2]:9.4f}/{p90[2]:<9.4f} "
                         f"{1000 * secs / len(e):8.3f}")
    return "\n".join(lines)


def add_arguments(ap: argparse.ArgumentParser) -> None:
    """The options of ``mcgeom experiment ch8``."""
    add_count_and_seed(ap, "--trials", 1000, "random trials per rig")


def run_cli(args: argparse.Namespace, progress: Progress = no_progress) -> int:
    """Print the ch. 8.5.1 table (PoseLib checked before the long run)."""
    import_peer("poselib", "the ch8 experiment")
    print(table(run(args.trials, args.seed, progress=progress)))
    return 0
