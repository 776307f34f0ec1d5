"""The peers' generalized relative-pose solvers, mcgeom's and PoseLib's, on the same problems.

Part ``minimal``: noise-free random minimal configurations per family
(generic 4-camera rigs with intra- and cross-camera rays, 2-camera heads; the
four rays start from at least two cameras, as four rays of one camera are a
central camera without metric scale; and the degenerate cases of the
upright problem: no yaw with intra-camera rays only
-- the critical motion of thesis ch. 7.3.2, where |t| is not observable and
no solver can return the truth --, cameras stacked along the vertical with
intra-camera rays -- an axial rig rotating about its axis, critical too --
and a yaw within 1e-4 rad of 180 degrees, where the half-angle tangent that
mcgeom's polynomial uses is large). Printed per family and solver: the
fraction of configurations where some returned solution matches the truth to
1e-8 (max |R - R_true| and |t - t_true| / |t_true|), the mean number of real
solutions and the time per call (median over batches). Both are called
through their Python bindings on prepared arrays; PoseLib's
``gen_relpose_upright_4pt`` assumes the vertical along y, so its rays are
re-expressed in such frames first (outside the timing).

The 6-point comparison (also part ``minimal``): mcgeom's ``sixpt``
(csrc/sixpt.c) and PoseLib's ``gen_relpose_6pt`` on noise-free 6-point
configurations per family (generic 6-camera rigs with mixed, intra- or
cross-camera rays, 2-camera heads; and the degenerate cases, where failure
is expected for both: every ray from one centre, a central camera without
metric scale, and no rotation with intra-camera rays, the critical motion of
ch. 7.3.2), the same columns (the time: one pass over the scored calls).

Part ``ransac``: the robust estimate from pixels with 1 px threshold, median
rotation error (deg), scale error ``| |t| / |t_true| - 1 |`` (the metric
estimate ``info["t_metric"]``, whatever the verdict), time per problem
(ms) and, for mcgeom's C search, its time and the mean number of samples its
adaptive stop drew (w^3 for the upright 3+1, w^4 for the upright 4-point,
w^5 for the two-stage 5+1, w^6 for the 6-point) of: mcgeom's façade as it
chooses its sampler (upright with a vertical prior, else 5+1 when a camera
has 5 intra-camera correspondences, else 6-point; the sampler column counts
its choices), the C search forced to 5+1, to the generic 6-point, and to the
upright sampler (3+1 where a camera has 3 intra-camera correspondences, else
4-point) with the vertical known to 0.2 deg (each gravity vector turned by
0.2 deg about a random axis), the C search with Kneip and Li's eigensolver
(``ransac:eigensolver``: 17-pair samples, linear17's rotation refined by
the eigensolver; capped at the façade's 1000 samples), 17-point RANSAC
(``ransac:linear17``: the C search's linear17 samples, ~55 us each;
capped at the façade's 1000 samples, and at each cap of ``--caps17``), and
PoseLib's
``estimate_generalized_relative_pose`` (its 5+1 sampler,
:mod:`.poselib_peer`) with ``min_iterations=100`` and with its defaults; on
the cases of ``robust_vs_poselib`` (ring4, ladybug6 with 30 % outliers, car8
driving forward), a 12-camera rig with 8 correspondences per camera (half
cross-camera, 40 % outliers) and the 8-camera car rig turning. A method that
cannot sample a case (5+1 and PoseLib without a 5-point camera pair) counts
as failed there. Where the façade chose a sampler, the row forcing it reuses
the façade's run (the same C call with the same seed); the 6-point row runs
only where the façade chose it: its samples are solved by ``mcg_sixpt_local``
(~1 ms, its rate of success measured by the search) and every 256th by
``mcg_sixpt`` (a homotopy continuation of 64 paths, 14-30 ms per sample by
machine), which on the cases with a 5-point camera would only measure that.
``--outliers F ...`` runs each chosen case at these outlier fractions
instead of its own: the upright sampler's smaller samples (w^3 against
5+1's w^5) pay off once outliers are many, while with few outliers both
searches draw a handful of samples and share the same local optimisation
and final refinement (measured in session 30, 40 problems, vertical 0.2 deg
off: Ladybug head upright vs 5+1 0.99x / 1.33x / 2.40x / 4.78x as fast at
0 / 30 / 50 / 60 % outliers, the car rig turning 1.06x / 1.43x / 2.92x /
6.05x; without outliers the upright search also searches its best's scale
once more, whose |t| carries the vertical's error). After each case a line
compares the façade with 17-point RANSAC at the same success rate
(:func:`equal_success`): at 40 % outliers a 17-pair sample is all inliers
once in ~6,000 draws, so 17-point RANSAC at the default cap mostly fails
and its time is that of a failure.

``mcgeom experiment peer_solvers [--part minimal|minimal4|minimal6|ransac|all]
[--configs 10000] [--configs6 N] [--chunk6 500] [--problems 50] [--seed 0]
[--cases CASE ...] [--outliers F ...] [--caps17 N ...]`` (needs poselib).
The 6-point table runs the families in rounds of ``--chunk6`` configurations
each and prints the table so far to stderr after every round (10,000
configurations of each of the 7 families take mcgeom's homotopy 20-40
minutes on a 2-core machine).
"""

from __future__ import annotations

import argparse
import re
import sys
import time
from typing import Callable, Optional, Sequence

import numpy as np

from mcgeom import _core, synth
from mcgeom.cv import RIG_LINEAR17_RANSAC, estimate
from mcgeom.estimators.upright_four_point import upright_rotation
from mcgeom.rig import Rig

from .common import Progress, add_count_and_seed, fraction, import_peer, no_progress, positive_int
from .poselib_peer import POSELIB_SETTINGS, poselib_estimate, poselib_setup
from .robust_vs_poselib import CASES as ROBUST_CASES, car_forward, random_motion, rot_scale_errors

#: e_z -> e_y: PoseLib's upright solvers rotate about y
_Z_TO_Y = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])


# ------------------------------------------------------------- minimal part

def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _config(family: str, rng: np.random.Generator):
    """One noise-free minimal configuration: rays (4 x 3 each), g1, g2, R, t."""
    g1 = _unit(rng.normal(size=3))
    if family == "no yaw, intra (critical)":
        R = np.eye(3)
    elif family == "yaw pi - 1e-4":
        R = synth.rotation_about(g1, np.pi - 1e-4 * rng.choice([-1.0, 1.0]))
    else:
        R = synth.random_rotation(rng)
    t = rng.normal(size=3)
    if family.startswith("2-camera head"):
        centres = np.array([[-0.15, 0.0, 0.0], [0.15, 0.0, 0.0]])
    elif family.startswith("vertical stack"):
        centres = np.outer(np.arange(4) * 0.3, g1)
        R = synth.rotation_about(g1, rng.uniform(-np.pi, np.pi))
    else:
        centres = 0.5 * rng.normal(size=(4, 3))
    m = len(centres)
    c1 = rng.integers(0, m, 4)
    if np.all(c1 == c1[0]):   # at least two cameras: four rays of one are a central camera
        c1[0] = (c1[0] + 1) % m
    cross = "cross" in family or (family.startswith("generic") and "intra" not in family)
    c2 = (c1 + rng.integers(1, m, 4)) % m if cross else c1
    if family.startswith("generic") and "intra" not in family:
        c2 = np.where(rng.random(4) < 0.5, c1, c2)   # mixed intra- and cross-camera
    X = centres[c1] + rng.uniform(2.0, 10.0, (4, 1)) * _unit(rng.normal(size=(4, 3)))
    o1, o2 = centres[c1], centres[c2]
    return (o1, X - o1, o2, X @ R.T + t - o2), g1, R @ g1, R, t


FAMILIES = ("generic 4-cam, mixed", "generic 4-cam, intra", "2-camera head, intra",
            "2-camera head, cross", "no yaw, intra (critical)", "vertical stack, intra (critical)",
            "yaw pi - 1e-4")


def _hit(sols, R: np.ndarray, t: np.ndarray) -> bool:
    return any(np.abs(Rs - R).max() < 1e-8 and np.linalg.norm(ts - t) < 1e-8 * np.linalg.norm(t)
               for Rs, ts in sols)


def _timed(fn: Callable, args: list, batch: int = 200) -> float:
    """Median seconds per call of ``fn(*a)`` over batches of ``batch`` argument tuples."""
    per = []
    for k in range(0, len(args), batch):
        chunk = args[k:k + batch]
        t0 = time.perf_counter()
        for a in chunk:
            fn(*a)
        per.append((time.perf_counter() - t0) / len(chunk))
    return float(np.median(per))


def run_minimal(configs: int = 10000, seed: int = 0, families=FAMILIES,
                progress: Progress = no_progress) -> dict:
    """{family: {solver: (success fraction, mean real solutions, seconds per call)}}."""
    poselib = import_peer("poselib", "peer_solvers")
    out = {}
    for fam in progress(families, total=len(families), desc="families"):
        rng = np.random.default_rng(seed)
        ours_args, theirs_args, truth, frames = [], [], [], []
        for _ in range(configs):
            (o1, d1, o2, d2), g1, g2, R, t = _config(fam, rng)
            ours_args.append((o1, d1, o2, d2, g1, g2))
            Q1, Q2 = _Z_TO_Y @ upright_rotation(g1), _Z_TO_Y @ upright_rotation(_unit(g2))
            theirs_args.append((list(o1 @ Q1.T), list(_unit(d1) @ Q1.T), list(o2 @ Q2.T),
                                list(_unit(d2) @ Q2.T)))
            truth.append((R, t))
            frames.append((Q1, Q2))
        res = {}
        hits, counts = 0, 0
        for a, (R, t) in zip(ours_args, truth):
            try:
                sols = _core.upright4(*a)
            except Exception:       # DegenerateError: no yaw determined
                sols = []
            hits += _hit(sols, R, t)
            counts += len(sols)
        res["mcgeom upright4"] = (hits / configs, counts / configs,
                                  _timed(_safe(_core.upright4), ours_args))
        hits, counts = 0, 0
        for a, (R, t), (Q1, Q2) in zip(theirs_args, truth, frames):
            sols = [(Q2.T @ np.asarray(p.R) @ Q1, Q2.T @ np.asarray(p.t))
                    for p in poselib.gen_relpose_upright_4pt(*a)]
            hits += _hit(sols, R, t)
            counts += len(sols)
        res["poselib upright_4pt"] = (hits / configs, counts / configs,
                                      _timed(poselib.gen_relpose_upright_4pt, theirs_args))
        out[fam] = res
    return out


#: families of the 6-point comparison; the last two are degenerate (the
#: paper's central case: every ray from one centre has no metric scale; and
#: the critical motion of thesis ch. 7.3.2: no rotation with intra-camera rays
#: leaves |t| free): no solver can return the truth, failure is expected
SIX_FAMILIES = ("generic 6-cam, mixed", "generic 6-cam, intra", "generic 6-cam, cross",
                "2-camera head, intra", "2-camera head, cross", "one centre (central)",
                "no rotation, intra (critical)")


def _config6(family: str, rng: np.random.Generator):
    """One noise-free 6-point configuration: rays (6 x 3 each), R, t (X2 = R X1 + t)."""
    R = np.eye(3) if "critical" in family else synth.random_rotation(rng)
    t = rng.normal(size=3)
    if family.startswith("2-camera head"):
        centres = np.array([[-0.15, 0.0, 0.0], [0.15, 0.0, 0.0]])
    elif "central" in family:
        centres = np.zeros((1, 3))
    else:
        centres = 0.5 * rng.normal(size=(6, 3))
    m = len(centres)
    c1 = rng.integers(0, m, 6)
    if m > 1 and np.all(c1 == c1[0]):   # one camera's six rays are a central camera
        c1[0] = (c1[0] + 1) % m
    c2 = c1
    if m > 1 and "cross" in family:
        c2 = (c1 + rng.integers(1, m, 6)) % m
    elif m > 1 and "mixed" in family:
        c2 = np.where(rng.random(6) < 0.5, c1, (c1 + rng.integers(1, m, 6)) % m)
    X = centres[c1] + rng.uniform(2.0, 10.0, (6, 1)) * _unit(rng.normal(size=(6, 3)))
    o1, o2 = centres[c1], centres[c2]
    return (o1, X - o1, o2, X @ R.T + t - o2), R, t


def _sixpt_list(o1, d1, o2, d2) -> list:
    Rs, ts = _core.sixpt(o1, d1, o2, d2)
    return list(zip(Rs, ts))


def _sixpt_local_list(o1, d1, o2, d2) -> list:
    Rs, ts = _core.sixpt_local(o1, d1, o2, d2)
    return list(zip(Rs, ts))


def run_minimal6(configs: int = 10000, seed: int = 0, families=SIX_FAMILIES,
                 progress: Progress = no_progress, chunk: Optional[int] = None,
                 on_chunk: Optional[Callable[[int, dict], None]] = None) -> dict:
    """The 6-point solvers: {family: {solver: (success fraction, mean real
    solutions, seconds per call)}}: mcgeom's ``_core.sixpt`` (csrc/sixpt.c),
    its local search ``_core.sixpt_local`` (csrc/sixpt_local.c, the robust
    search's) and ``poselib.gen_relpose_6pt`` on the same noise-free
    configurations.

    The families are run in turn, ``chunk`` configurations of each at a time
    (default: all at once), and ``on_chunk(done, table)`` receives the table of
    the first ``done`` configurations per family after each round: mcgeom's
    homotopy takes 14-30 ms a call, so 10,000 configurations of 7 families run
    for 20-40 minutes, and a run stopped early still has figures
    for every family. Each family draws from its own generator seeded with
    ``seed``, so the configurations do not depend on ``chunk``."""
    poselib = import_peer("poselib", "peer_solvers")
    # (sixpt_local: the robust search's solver of 6-point samples, incomplete
    # by design -- its success fraction here is what the search measures
    # and allows for)
    solvers = (("mcgeom sixpt", _safe(_sixpt_list), False),
               ("mcgeom sixpt_local", _safe(_sixpt_local_list), False),
               ("poselib gen_relpose_6pt", _safe(poselib.gen_relpose_6pt), True))
    rngs = {fam: np.random.default_rng(seed) for fam in families}
    acc = {fam: {name: [0, 0, 0.0] for name, _, _ in solvers} for fam in families}
    chunk = configs if chunk is None else max(1, min(chunk, configs))
    out: dict = {}
    done = 0
    for start in progress(range(0, configs, chunk), total=-(-configs // chunk),
                          desc="6-point rounds"):
        m = min(chunk, configs - start)
        for fam in families:
            cfgs = [_config6(fam, rngs[fam]) for _ in range(m)]
            for name, fn, unit in solvers:
                a = acc[fam][name]
                # PoseLib takes unit directions: made outside the timing
                calls = [((o1, _unit(d1), o2, _unit(d2)) if unit else (o1, d1, o2, d2), R, t)
                         for (o1, d1, o2, d2), R, t in cfgs]
                t0 = time.perf_counter()
                for args, R, t in calls:
                    sols = [(np.asarray(p.R), np.asarray(p.t)) if hasattr(p, "R") else p
                            for p in fn(*args)]
                    a[0] += _hit(sols, R, t)
                    a[1] += len(sols)
                # one pass: the solver is timed on the same calls that are scored
                a[2] += time.perf_counter() - t0
        done += m
        out = {fam: {name: (h / done, c / done, secs / done)
                     for name, (h, c, secs) in res.items()} for fam, res in acc.items()}
        if on_chunk is not None:
            on_chunk(done, out)
    return out


def _safe(fn: Callable) -> Callable:
    def call(*a):
        try:
            return fn(*a)
        except Exception:
            return []
    return call


def minimal_table(res: dict) -> str:
    lines = [f"{'family':<34} {'solver':<24} {'found 1e-8':>10} {'mean sols':>9} "
             f"{'us/call':>9}"]
    for fam, solvers in res.items():
        for name, (frac, nsol, secs) in solvers.items():
            lines.append(f"{fam:<34} {name:<24} {100 * frac:9.2f}% {nsol:9.2f} "
                         f"{1e6 * secs:9.2f}")
    return "\n".join(lines)


# -------------------------------------------------------------- RANSAC part

def rig12(radius: float = 0.6, f: float = 500.0) -> Rig:
    """12 cameras on a ring, looking outward every 30 deg (neighbours overlap)."""
    return synth.ring_rig(12, radius, f, name="ring12")


def _car_turning(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A car driving forward about 1 m while yawing up to 10 deg, with a little
    pitch and roll (the vertical tilts by up to 0.6 deg)."""
    R = (synth.rotation_about([0, 0, 1], rng.uniform(-0.17, 0.17))
         @ synth.rotation_about(rng.normal(size=3), rng.uniform(0.0, 0.01)))
    return R, np.array([1.0, 0.0, 0.0]) + 0.05 * rng.normal(size=3)


#: name: (rig, correspondences, outlier fraction, pixel noise, cross fraction, motion):
#: the cases of robust_vs_poselib / bench robust (ring4, ladybug6 with 30 %
#: outliers, car8 driving forward with a yaw under 2 deg and 20 % outliers),
#: the 12-camera rig with 8 correspondences per camera (half cross-camera, 40 %
#: outliers: no camera has the 5 intra-camera ones of a 5+1 sample) and the car
#: rig turning (the vertical known to 0.2 deg in the upright rows of every case)
RANSAC_CASES: dict = {
    "ring4 4x50 0.5px": ROBUST_CASES["ring4 4x50 0.5px"][:4] + (0.0, random_motion),
    "ladybug6 300c 30%out": ROBUST_CASES["ladybug6 300c 30%out 0.5px"][:4] + (0.0, random_motion),
    "car8 fwd<=2deg 20%out": ROBUST_CASES["car8 fwd<=2deg 400c 20%out"][:4] + (0.0, car_forward),
    "ring12 12x8 half-cross 40%out": (rig12, 96, 0.4, 0.5, 0.5, random_motion),
    "car8 320c turning <=10deg": (synth.vehicle8, 320, 0.0, 0.5, 0.0, _car_turning),
}


def with_outliers(cases: dict, fractions: Sequence[float]) -> dict:
    """``cases`` (entries of :data:`RANSAC_CASES`) once per outlier fraction of
    ``fractions`` (each in [0, 1)), the fraction in the name (``... @50%out``):
    where the upright sampler pays off (its 3+1 or 4-point samples against
    5+1's five intra-camera pairs: w^3 against w^5 at inlier ratio w)."""
    out = {}
    for name, (make_rig, n, _, noise, cross, motion) in cases.items():
        for f in fractions:
            if not 0.0 <= f < 1.0:
                raise ValueError(f"outlier fraction must be in [0, 1), got {f!r}")
            # (the case's own fraction leaves its name)
            base = re.sub(r"\s*\d+%out\b", "", name)
            out[f"{base} @{100 * f:g}%out"] = (make_rig, n, float(f), noise, cross, motion)
    return out


def _sampler_label(info: dict) -> str:
    """The sampler column's name of a search: ``info["sampler"]``, and for the
    upright sampler which samples it drew (``upright 3+1`` where a camera has
    3 intra-camera correspondences, ``upright 4-pt`` elsewhere)."""
    name = info.get("sampler", "")
    if name == "upright_four_point" and info.get("sample_size") in (3, 4):
        return "upright 3+1" if info["sample_size"] == 3 else "upright 4-pt"
    return name


def _final_seconds(info: dict) -> float:
    """Seconds of the C call after its search (``info["c_stage_seconds"]``'s
    final refinement and verdict; NaN without them): the stage that every
    sampler's estimate goes through (its cost depends on how near the optimum
    the search left the motion, not on what it sampled)."""
    st = info.get("c_stage_seconds")
    return st["final"] + st["verdict"] if st else np.nan


#: the façade's default sample cap (``maxIters`` of :func:`mcgeom.cv.estimate`)
DEFAULT_CAP17 = 1000


def row17(cap: int) -> str:
    """The row name of 17-point RANSAC capped at ``cap`` samples."""
    return "mcgeom 17-pt" if cap == DEFAULT_CAP17 else f"mcgeom 17-pt <={cap}"


def _methods(rig: Rig, setup: tuple, p, g1: np.ndarray, g2: np.ndarray, deg: float,
             caps17: Sequence[int] = (DEFAULT_CAP17,)) -> dict:
    """{row: call returning (R, t, sampler, seconds in C, samples drawn, seconds
    of the C call's final stage)} of one problem."""
    def facade(**kw):
        m = estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, rig, threshold=1.0, **kw)
        return (m.R, m.info["t_metric"], _sampler_label(m.info),
                m.info.get("c_seconds", np.nan), m.info.get("iterations", np.nan),
                _final_seconds(m.info))

    def peer(opt):
        return lambda: poselib_estimate(setup, p, opt) + ("5+1", np.nan, np.nan, np.nan)

    runs = {"mcgeom façade (auto)": facade,
            "mcgeom 5+1": lambda: facade(method="ransac:five_plus_one"),
            "mcgeom 6-pt": lambda: facade(method="ransac:six_point"),
            f"mcgeom upright ({deg:g} deg)": lambda: facade(gravity1=g1, gravity2=g2),
            "mcgeom eigensolver": lambda: facade(method="ransac:eigensolver")}
    for cap in caps17:
        runs[row17(cap)] = lambda cap=cap: facade(method=RIG_LINEAR17_RANSAC, maxIters=cap)
    runs.update({name: peer(opt) for name, opt in POSELIB_SETTINGS.items()})
    return runs


def run_ransac(problems: int = 50, seed: int = 0, cases: Optional[dict] = None,
               gravity_error_deg: float = 0.2, progress: Progress = no_progress,
               caps17: Sequence[int] = (DEFAULT_CAP17,)) -> dict:
    """{case: {method: (errors problems x 2, seconds per problem, samplers, seconds
    in C, samples drawn, seconds of the C final stage)}}: the rotation (deg) and
    scale errors, NaN where the method cannot sample the data (a ValueError,
    e.g. 5+1 without a 5-point camera) or finds no motion; the samplers the
    façade chose; the time of mcgeom's C call (``info["c_seconds"]``: rays,
    sampling, scoring, LO, final refinement, verdict; NaN for the Python
    drivers and PoseLib), its samples (``info["iterations"]``: the adaptive
    stop's count, NaN for PoseLib) and the part of its time after the search
    (:func:`_final_seconds`: the final refinement, scale profiles and
    verdict, which every sampler's estimate goes through). Each gravity vector is turned by
    ``gravity_error_deg`` about a random axis (the IMU's error). 17-point
    RANSAC runs once per sample cap of ``caps17`` (rows :func:`row17`): its
    17-pair samples are all inliers with probability w^17, so where outliers
    are many it needs caps far above the default to succeed as often as the
    minimal samplers (see :func:`equal_success`)."""
    if not caps17 or any(int(c) < 1 for c in caps17):
        raise ValueError(f"caps17 must be sample caps >= 1, got {list(caps17)!r}")
    caps17 = sorted({int(c) for c in caps17})
    # (a warm-up call of a high cap would take seconds: the default cap warms up)
    slow17 = {row17(c) for c in caps17 if c > DEFAULT_CAP17}
    out = {}
    for name, (make_rig, n, outl, noise, cross, motion) in (cases or RANSAC_CASES).items():
        rng = np.random.default_rng(seed)
        rig = make_rig()
        setup = poselib_setup(rig, "peer_solvers")
        res: dict = {}
        for k in progress(range(problems), total=problems, desc=name):
            R, t = motion(rng)
            p = synth.make_problem(rig, R, t, n, rng, pixel_noise=noise, outlier_fraction=outl,
                                   cross_fraction=cross, require_visible=cross == 0.0)
            g1 = synth.tilted(synth.GRAVITY, gravity_error_deg, rng)
            g2 = synth.tilted(R @ synth.GRAVITY, gravity_error_deg, rng)
            runs = _methods(rig, setup, p, g1, g2, gravity_error_deg, caps17)
            if k == 0:      # untimed warm-up: first calls load plugins and caches
                for meth, fn in runs.items():
                    if meth == "mcgeom 6-pt" or meth in slow17:
                        continue
                    try:
                        fn()
                    except (ValueError, ArithmeticError):
                        pass
            chosen = None
            for meth, fn in runs.items():
                forced = _FORCED.get(meth)
                if forced is not None and forced == chosen:
                    # the façade ran this very search (same C call, same seed)
                    e, s, used, cs, its, fs = res["mcgeom façade (auto)"]
                    err, secs, sampler, c_secs, iters, f_secs = \
                        e[-1], s[-1], used[-1], cs[-1], its[-1], fs[-1]
                elif meth == "mcgeom 6-pt":
                    continue    # only where the façade chose it (see the module)
                else:
                    t0 = time.perf_counter()
                    try:
                        Re, te, sampler, c_secs, iters, f_secs = fn()
                        err = rot_scale_errors(Re, te, R, t)
                    except (ValueError, ArithmeticError):   # cannot sample / nothing found
                        err, sampler, c_secs, iters, f_secs = \
                            (np.nan, np.nan), "-", np.nan, np.nan, np.nan
                    secs = time.perf_counter() - t0
                if meth == "mcgeom façade (auto)":
                    chosen = sampler
                e, s, used, cs, its, fs = res.setdefault(meth, ([], [], [], [], [], []))
                e.append(err)
                s.append(secs)
                used.append(sampler)
                cs.append(c_secs)
                its.append(iters)
                fs.append(f_secs)
        out[name] = {k: (np.array(e), np.array(s), u, np.array(cs), np.array(its, dtype=float),
                         np.array(fs, dtype=float))
                     for k, (e, s, u, cs, its, fs) in res.items()}
    return out


#: the rows that force one sampler of the façade's choice
_FORCED = {"mcgeom 5+1": "five_plus_one", "mcgeom 6-pt": "six_point"}


def ransac_table(res: dict) -> str:
    """Per case and method: the sampler (the façade's most frequent choice),
    median rotation error (deg) and scale error of the problems it solved, the
    fraction it failed, the median time, the speed-up over 5+1 and 17-point
    RANSAC (their median time / this one's), and the median time of the C
    search with its speed-up over 5+1's (the search alone, without the
    façade's Python conversions and verdict), and the mean number of samples
    the C search drew (its adaptive stop: w^3 for the upright 3+1, w^4 for
    the upright 4-point, w^5 for the two-stage 5+1, w^6 for the 6-point),
    and the median ms of the C call's final stage (``C final``: refinement,
    scale profiles, verdict: work that every sampler's estimate goes
    through, so a faster sampler cannot make the estimate cheaper than it)."""
    # column widths of the longest names (--outliers' cases, the upright row)
    wc = max([30] + [len(case) for case in res])
    wm = max([23] + [len(meth) for methods in res.values() for meth in methods])
    lines = [f"{'case':<{wc}} {'method':<{wm}} {'sampler':<18} {'rot med deg':>11} "
             f"{'scale med':>9} {'failed':>6} {'ms med':>8} {'vs 5+1':>7} {'vs 17-pt':>8} "
             f"{'C ms med':>8} {'C vs 5+1':>8} {'samples':>7} {'C final':>7}"]
    for case, methods in res.items():
        ok5 = np.isfinite(methods["mcgeom 5+1"][0][:, 0])   # (rows not run are absent)
        base5 = np.median(methods["mcgeom 5+1"][1]) if ok5.any() else np.nan
        base17 = np.median(methods[_rows17(methods)[0]][1])
        c5 = methods["mcgeom 5+1"][3]
        c5 = np.median(c5[np.isfinite(c5)]) if np.isfinite(c5).any() else np.nan
        for meth, (e, secs, used, c_secs, iters, f_secs) in methods.items():
            ok = np.isfinite(e[:, 0])
            med = np.median(e[ok], axis=0) if ok.any() else (np.nan, np.nan)
            names, counts = np.unique(used, return_counts=True)
            sampler = ", ".join(f"{k} {c}" if len(names) > 1 else str(k)
                                for k, c in zip(names, counts))
            ms = np.median(secs)
            cms = np.median(c_secs[np.isfinite(c_secs)]) if np.isfinite(c_secs).any() \
                else np.nan
            its = np.mean(iters[np.isfinite(iters)]) if np.isfinite(iters).any() else np.nan
            fms = np.median(f_secs[np.isfinite(f_secs)]) if np.isfinite(f_secs).any() \
                else np.nan
            lines.append(f"{case:<{wc}} {meth:<{wm}} {sampler[:18]:<18} {med[0]:11.4f} "
                         f"{med[1]:9.4f} {np.mean(~ok):6.2f} {1e3 * ms:8.2f} "
                         f"{base5 / ms:6.2f}x {base17 / ms:7.2f}x {1e3 * cms:8.2f} "
                         f"{c5 / cms:7.2f}x {its:7.1f} {1e3 * fms:7.3f}")
        lines.append(equal_success(methods))
    return "\n".join(lines)


def _rows17(methods: dict) -> list[str]:
    """The 17-point RANSAC rows of a case, in the order of their caps."""
    return [m for m in methods if m.startswith("mcgeom 17-pt")]


def equal_success(methods: dict, row: str = "mcgeom façade (auto)") -> str:
    """One line: how much faster ``row`` is than 17-point RANSAC at the same
    success. The reference is the 17-point row with the smallest cap that
    failed at most as often as ``row`` (median times, theirs over ``row``'s);
    when no cap got there, the largest cap's time gives a lower bound
    (``>=``: 17-point RANSAC would need more samples still, and succeeds less
    often even so). A 17-point sample of 17 pairs is all inliers with
    probability w^17 (1.7e-4 at w = 0.6): at the default cap it fails where
    a minimal sampler does not, and its time then measures a failure."""
    e, secs = methods[row][0], methods[row][1]
    fail = float(np.mean(~np.isfinite(e[:, 0])))
    ms = 1e3 * float(np.median(secs))
    head = f"  {row} against 17-point RANSAC at equal success (failed {fail:.2f}, {ms:.1f} ms):"
    runs = [(name, float(np.mean(~np.isfinite(methods[name][0][:, 0]))),
             1e3 * float(np.median(methods[name][1]))) for name in _rows17(methods)]
    for name, f17, ms17 in runs:
        if f17 <= fail:
            return f"{head} {name} failed {f17:.2f} in {ms17:.1f} ms: {ms17 / ms:.2f}x faster"
    name, f17, ms17 = runs[-1]
    return (f"{head} no cap got there (the largest, {name}, failed {f17:.2f} in "
            f"{ms17:.1f} ms): >= {ms17 / ms:.2f}x faster")


# ---------------------------------------------------------------------- CLI

def add_arguments(ap: argparse.ArgumentParser) -> None:
    """The options of ``mcgeom experiment peer_solvers``."""
    ap.add_argument("--part", choices=("minimal", "minimal4", "minimal6", "ransac", "all"),
                    default="all",
                    help="minimal solvers on noise-free configurations (minimal4: the "
                         "upright 4-point only, minimal6: the 6-point only), RANSAC from "
                         "pixels, or both")
    ap.add_argument("--configs", type=positive_int, default=10000,
                    help="noise-free configurations per family (minimal part)")
    ap.add_argument("--configs6", type=positive_int, default=None,
                    help="configurations per family of the 6-point comparison (minimal "
                         "part; default --configs; mcgeom's homotopy takes 14-30 ms a call)")
    ap.add_argument("--chunk6", type=positive_int, default=500,
                    help="6-point configurations per family and round; the table so far "
                         "goes to stderr after each round")
    add_count_and_seed(ap, "--problems", 50, "problems per case (RANSAC part)")
    ap.add_argument("--cases", nargs="*", default=None, choices=list(RANSAC_CASES),
                    metavar="CASE", help="cases of the RANSAC part (default: all), of: "
                    + "; ".join(RANSAC_CASES).replace("%", "%%"))
    ap.add_argument("--outliers", nargs="+", type=fraction, default=None, metavar="F",
                    help="run each case of the RANSAC part at these outlier fractions "
                         "instead of its own (e.g. 0.3 0.5 0.6: the regime where the "
                         "upright sampler's smaller samples pay off; default: each "
                         "case's own)")
    ap.add_argument("--caps17", nargs="+", type=positive_int, default=[DEFAULT_CAP17],
                    metavar="N",
                    help="sample caps of 17-point RANSAC, one row each (default: the "
                         "façade's 1000); each case then says how much faster the façade "
                         "is than 17-point RANSAC at the same success (e.g. 1000 5000 "
                         "20000 100000 on the 12-camera case: at 40%% outliers 17-point "
                         "samples are all inliers once in ~6,000 draws)")


def run_cli(args: argparse.Namespace, progress: Progress = no_progress) -> int:
    """Print the tables of the requested parts."""
    import_peer("poselib", "peer_solvers")
    def partial(done: int, table: dict) -> None:
        # a long run stopped early keeps the figures of the rounds done
        print(f"[6-point: {done} configurations per family so far]\n{minimal_table(table)}",
              file=sys.stderr, flush=True)

    if args.part in ("minimal", "minimal4", "all"):
        print(minimal_table(run_minimal(args.configs, args.seed, progress=progress)))
        print(flush=True)
    if args.part in ("minimal", "minimal6", "all"):
        print(minimal_table(run_minimal6(args.configs6 or args.configs, args.seed,
                                         progress=progress, chunk=args.chunk6,
                                         on_chunk=partial)))
    if args.part in ("ransac", "all"):
        if args.part == "all":
            print()
        cases = {k: RANSAC_CASES[k] for k in args.cases or RANSAC_CASES}
        if args.outliers:
            cases = with_outliers(cases, args.outliers)
        print(ransac_table(run_ransac(args.problems, args.seed, cases, progress=progress,
                                      caps17=args.caps17)))
    return 0
