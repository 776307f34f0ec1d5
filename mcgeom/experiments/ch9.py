"""Thesis ch. 10.5.1 synthetic set-up, E+SOCP (ch. 9) next to linear17 and five_plus_one.

Four cameras, 50 points each (200 in all), a random rigid motion, Gaussian
pixel noise sigma from 0 to 0.5 px, ``runs`` problems per level (the thesis
used 10). Printed per noise level and method: mean rotation error (deg),
translation-direction error (deg), scale ratio |t_est| / |t_true| and the
distance between the estimated and the true final centre of the first camera
(the quantities of Figs. 10.4-10.5). All methods see the same correspondences
(no outliers) and run without RANSAC. ``mcgeom experiment ch9 --runs 10``
"""

from __future__ import annotations

import argparse

import numpy as np

import mcgeom
from mcgeom import metrics, synth
from mcgeom.rig import Rig

from .common import Progress, add_count_and_seed, no_progress

METHODS = ("e_socp", "linear17", "five_plus_one")
LEVELS = (0.0, 0.1, 0.2, 0.3, 0.4, 0.5)


def rig4(f: float = 800.0) -> Rig:
    """Four cameras on a 1 m x 0.5 m frame looking front, back, left, right."""
    cams = []
    for k, (pos, yaw) in enumerate((((0.5, 0.0, 0.0), 0.0), ((-0.5, 0.0, 0.0), 180.0),
                                    ((0.0, 0.25, 0.0), 90.0), ((0.0, -0.25, 0.0), -90.0))):
        d = np.array([np.cos(np.radians(yaw)), np.sin(np.radians(yaw)), 0.0])
        cams.append(synth.look_at_camera(f"cam{k}", pos, d, f=f, width=1024, height=768))
    return Rig(tuple(cams))


def _metric(m) -> np.ndarray:
    # the metric translation also when the scale was reported unobservable
    return np.asarray(m.info.get("t_metric", m.t) if m.info.get("t_metric") is not None
                      else m.t)


def problems(runs: int, sigma: float, seed: int = 0):
    """The ch. 10.5.1 problems at one noise level: (R, t, problem) per run."""
    rig = rig4()
    rng = np.random.default_rng(seed)
    for _ in range(runs):
        R, t = synth.random_motion_between(rng, np.radians(5), np.radians(20), 0.5, 1.5)
        yield R, t, synth.make_problem(rig, R, t, 200, rng, pixel_noise=sigma)


def run(runs: int = 10, seed: int = 0, levels=LEVELS, methods=METHODS,
        progress: Progress = no_progress) -> dict:
    """{sigma: {method: runs x 4 array}}: rotation error (deg), direction error
    (deg), scale ratio and final-centre distance (m) per problem (see :func:`table`)."""
    rig = rig4()
    c1 = rig.centres[0]
    out = {}
    for sigma in levels:
        rows = {m: [] for m in methods}
        for R, t, p in progress(problems(runs, sigma, seed), total=runs,
                                desc=f"{sigma:.2f} px"):
            for name in methods:
                try:
                    m = mcgeom.estimate(p.rays, name)
                except (ValueError, mcgeom.DegenerateError):
                    rows[name].append((np.nan,) * 4)
                    continue
                tm = _metric(m)
                rot = np.degrees(metrics.rotation_error(m.R, R))
                cosd = np.clip(tm @ t / (np.linalg.norm(tm) * np.linalg.norm(t)), -1, 1)
                ratio = np.linalg.norm(tm) / np.linalg.norm(t)
                # the first camera's final centre in the rig1 frame: R^T (c1 - t)
                dist = np.linalg.norm(m.R.T @ (c1 - tm) - R.T @ (c1 - t))
                rows[name].append((rot, np.degrees(np.arccos(cosd)), ratio, dist))
        out[sigma] = {k: np.array(v) for k, v in rows.items()}
    return out


def table(res: dict) -> str:
    """Means over the problems of :func:`run` that did not fail, per level and method."""
    lines = [f"{'sigma px':>8} {'method':<14} {'rot deg':>9} {'dir deg':>9} {'scale':>8} "
             f"{'centre m':>9} {'failed':>6}"]
    for sigma, methods in res.items():
        for name, e in methods.items():
            ok = np.all(np.isfinite(e), axis=1)
            mean = np.nanmean(e[ok], axis=0) if ok.any() else [np.nan] * 4
            lines.append(f"{sigma:8.2f} {name:<14} {mean[0]:9.4f} {mean[1]:9.3f} {mean[2]:8.4f} "
                         f"{mean[3]:9.4f} {int((~ok).sum()):6d}")
    return "\n".join(lines)


def add_arguments(ap: argparse.ArgumentParser) -> None:
    """The options of ``mcgeom experiment ch9``."""
    add_count_and_seed(ap, "--runs", 10, "problems per noise level")


def run_cli(args: argparse.Namespace, progress: Progress = no_progress) -> int:
    """Print the table of mean errors per noise level and method."""
    print(table(run(args.runs, args.seed, progress=progress)))
    return 0
