"""Robust rig motion from pixels: mcgeom's default pipeline against PoseLib, same problems.

Cases (issues 3, 18): a Ladybug2-like 6-camera head with 300 correspondences,
30 % outliers and 0.5 px noise; the 8-camera car rig of ch. 7.5.2 driving
forward with at most 2 deg of yaw (400 correspondences, 20 % outliers,
0.5 px); a 2-camera non-overlapping head with 200
correspondences and 0.5 px noise; a 4-camera ring with 4 x 50 points at 0.1,
0.3 and 0.5 px. Both methods get the same pixels, the same calibration and the
same 1 px epipolar threshold; PoseLib runs ``estimate_generalized_relative_pose``
with its default RANSAC and bundle options. Printed per case: median and 90th
percentile of rotation error (deg), translation-direction error (deg) and scale
error |(|t_est| / |t_true|) - 1| of the RETURNED t (|t_true| 0.5-1.5 m, so a unit
vector is no metric answer; row "mcgeom t_metric": info['t_metric'], the metric
estimate whatever the verdict),
failure rate (rotation error > 1 deg or direction error > 10 deg), median wall
time and the ratio PoseLib / mcgeom, and the same for the process CPU time of
each call (all threads of the process; not inflated when other jobs share the
machine's cores, as wall time is). Then, per case, the difference of the
medians (mcgeom - PoseLib) of the rotation and scale errors with a paired
bootstrap 95 % interval over the problems: medians of a few hundred problems
differ by a few per cent from run to run, so a difference whose interval
contains 0 is not a difference.
``mcgeom experiment robust_vs_poselib [--problems 600] [--seed 0]`` (needs poselib)
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from mcgeom import metrics, synth
from mcgeom.cv import estimate
from mcgeom.rig import Rig

from .common import Progress, add_count_and_seed, import_peer, no_progress
from .poselib_peer import poselib_estimate, poselib_setup


def ring4(radius: float = 0.25, f: float = 500.0) -> Rig:
    """4 cameras on a horizontal ring looking outward every 90 deg (1024 x 768 px)."""
    return synth.ring_rig(4, radius, f, name="ring")


def random_motion(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A rotation of 3-17 deg about a random axis, |t| uniform in 0.5-1.5 m in
    a random direction (not unit: a unit-norm t must not score as metric)."""
    R = synth.random_rotation(rng, 0.3)
    while metrics.rotation_error(R, np.eye(3)) < 0.05:
        R = synth.random_rotation(rng, 0.3)
    t = rng.normal(size=3)
    return R, t * rng.uniform(0.5, 1.5) / np.linalg.norm(t)


def car_forward(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A car driving forward 0.5-1.5 m while yawing at most 2 deg (near the
    critical motion of thesis ch. 7.3.2 for intra-camera correspondences)."""
    Rw = synth.rotation_about([0.0, 0.0, 1.0], np.radians(rng.uniform(-2.0, 2.0)))
    return Rw.T, -Rw.T @ np.array([rng.uniform(0.5, 1.5), 0.0, 0.0])


CASES: dict[str, tuple] = {
    # name: (rig, correspondences, outlier fraction, pixel noise[, motion])
    "ladybug6 300c 30%out 0.5px": (synth.ladybug2, 300, 0.3, 0.5),
    "car8 fwd<=2deg 400c 20%out": (synth.vehicle8, 400, 0.2, 0.5, car_forward),
    "stereo2 200c 0.5px": (lambda: synth.stereo_head(0.5), 200, 0.0, 0.5),
    "ring4 4x50 0.1px": (ring4, 200, 0.0, 0.1),
    "ring4 4x50 0.3px": (ring4, 200, 0.0, 0.3),
    "ring4 4x50 0.5px": (ring4, 200, 0.0, 0.5),
}


def _mcgeom(rig: Rig, p) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    m = estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, rig, threshold=1.0)
    return m.R, m.t, m.info["t_metric"]


def rot_scale_errors(R: np.ndarray, t: np.ndarray, R_true: np.ndarray,
                     t_true: np.ndarray) -> tuple[float, float]:
    """Errors of an estimate (R, t) of rig2_from_rig1 against the truth: the
    rotation error (degrees) and the scale error ``| |t| / |t_true| - 1 |``
    (relative; the metres of t and t_true cancel). The error pair of the
    peer comparisons (this module, ``bench robust``, ``peer_solvers``)."""
    return (float(np.degrees(metrics.rotation_error(R, R_true))),
            abs(float(np.linalg.norm(t) / np.linalg.norm(t_true)) - 1.0))


def _errors(R, t, Rt, tt) -> tuple[float, float, float]:
    """:func:`rot_scale_errors` and, between them, the angle (degrees) between
    t and the true translation."""
    rot, scale = rot_scale_errors(R, t, Rt, tt)
    cosang = np.clip(t @ tt / (np.linalg.norm(t) * np.linalg.norm(tt) + 1e-300), -1, 1)
    return rot, float(np.degrees(np.arccos(cosang))), scale


def run(trials: int = 50, seed: int = 0, cases=None, progress: Progress = no_progress) -> dict:
    """{case: {method: (errors trials x 3, wall seconds, CPU seconds)}}; errors as
    in :func:`_errors` (degrees, degrees, relative)."""
    out = {}
    for name, (make_rig, n, outl, noise, *motion) in (cases or CASES).items():
        rng = np.random.default_rng(seed)
        rig = make_rig()
        setup = poselib_setup(rig)
        draw = motion[0] if motion else random_motion
        res = {"mcgeom": ([], [], []), "poselib": ([], [], []), "mcgeom t_metric": ([], [], [])}
        for _ in progress(range(trials), total=trials, desc=name):
            R, t = draw(rng)
            p = synth.make_problem(rig, R, t, n, rng, pixel_noise=noise, outlier_fraction=outl)
            for meth, fn in (("mcgeom", _mcgeom),
                             ("poselib", lambda _, q: poselib_estimate(setup, q))):
                t0, c0 = time.perf_counter(), time.process_time()
                Re, te, *tm = fn(rig, p)
                res[meth][2].append(time.process_time() - c0)
                res[meth][1].append(time.perf_counter() - t0)
                res[meth][0].append(_errors(Re, te, R, t))
                if tm:   # the metric estimate whatever the verdict, same call
                    for k in (1, 2):
                        res["mcgeom t_metric"][k].append(res[meth][k][-1])
                    res["mcgeom t_metric"][0].append(_errors(Re, tm[0], R, t))
        out[name] = {k: tuple(np.array(a) for a in v) for k, v in res.items()}
    return out


def table(res: dict) -> str:
    """Medians, 90th percentiles, failure rates and times of :func:`run` per case."""
    lines = [f"{'case':<28} {'method':<8} {'rot med/p90 deg':>17} {'dir med/p90 deg':>17} "
             f"{'scale med/p90':>15} {'fail':>6} {'ms med':>8} {'speedup':>8} {'cpu ms':>8} "
             f"{'cpu spd':>8}"]
    for case, methods in res.items():
        t_pl = np.median(methods["poselib"][1])
        c_pl = np.median(methods["poselib"][2])
        for meth, (e, secs, cpu) in methods.items():
            med, p90 = np.median(e, 0), np.percentile(e, 90, axis=0)
            fail = np.mean((e[:, 0] > 1.0) | (e[:, 1] > 10.0))
            ratio = t_pl / np.median(secs)
            lines.append(f"{case:<28} {meth:<8} {med[0]:7.4f}/{p90[0]:<9.4f} {med[1]:7.3f}/{p90[1]:<9.3f} "
                         f"{med[2]:6.3f}/{p90[2]:<8.3f} {fail:6.3f} {1e3 * np.median(secs):8.2f} "
                         f"{ratio:7.2f}x {1e3 * np.median(cpu):8.2f} {c_pl / np.median(cpu):7.2f}x")
    return "\n".join(lines)


def median_differences(res: dict, boot: int = 2000, seed: int = 1) -> str:
    """Per case: median(mcgeom) - median(PoseLib) of the rotation error (deg)
    and of the scale error, each with a paired bootstrap 95 % interval."""
    rng = np.random.default_rng(seed)
    lines = [f"{'case':<28} {'rot med diff deg [95% CI]':>36} {'scale med diff [95% CI]':>34}"]
    for case, methods in res.items():
        a, b = methods["mcgeom"][0], methods["poselib"][0]
        idx = rng.integers(0, len(a), size=(boot, len(a)))
        cells = []
        for col in (0, 2):
            d = np.median(a[:, col]) - np.median(b[:, col])
            bs = np.median(a[idx, col], axis=1) - np.median(b[idx, col], axis=1)
            lo, hi = np.percentile(bs, [2.5, 97.5])
            cells.append(f"{d:+.5f} [{lo:+.5f}, {hi:+.5f}]")
        ratio = np.median(a[:, 2]) / max(np.median(b[:, 2]), 1e-300)
        lines.append(f"{case:<28} {cells[0]:>36} {cells[1]:>34}  scale median ratio "
                     f"mcgeom/PoseLib {ratio:.2f}")
    return "\n".join(lines)


def add_arguments(ap: argparse.ArgumentParser) -> None:
    """The options of ``mcgeom experiment robust_vs_poselib``."""
    add_count_and_seed(ap, "--problems", 600, "problems per case")
    ap.add_argument("--cases", nargs="*", default=None, choices=list(CASES), metavar="CASE",
                    help="cases to run (default: all), of: "
                         + "; ".join(CASES).replace("%", "%%"))


def run_cli(args: argparse.Namespace, progress: Progress = no_progress) -> int:
    """Print the comparison table and the bootstrap intervals."""
    import_peer("poselib", "robust_vs_poselib")
    res = run(args.problems, args.seed, {k: CASES[k] for k in args.cases or CASES},
              progress=progress)
    print(table(res))
    print()
    print(median_differences(res))
    return 0
