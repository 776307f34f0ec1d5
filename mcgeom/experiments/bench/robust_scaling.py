"""The scaling part of ``mcgeom bench robust`` (issue 19): the robust estimate on
1e3 .. 1e6 correspondences, side by side with PoseLib on the same pixels.

The problem (:func:`ring_problem`): the 4-camera ring of
:func:`..robust_vs_poselib.ring4` (1024 x 768 px, f = 500 px, radius 0.25 m)
moving by a generic motion (rotation 3-17 deg, |t| = 1 m); each
correspondence a uniform pixel of one camera at time 1, its point 2-20 m away
along the ray, seen by the same camera at time 2 (resampled until it is in
the image); 0.5 px noise on both pixels; 20 % outliers, whose time-2 pixel is
a uniform pixel of the image (what a wrong match is). Both libraries get the
same pixels: mcgeom as the rig's rays with their pixels per radian
(:func:`mcgeom.robust.ransac`, 1 px threshold; rays in, so that the peak
memory is compared with the ray arrays it works on), PoseLib as its match
sets (``estimate_generalized_relative_pose``, ``max_epipolar_error`` 1 px,
``min_iterations=100``: the tuned setting of the speed table).

Per N, medians over :func:`scaling_problems` problems: seconds,
microseconds per correspondence, the peak memory allocated during the call
(``tracemalloc``: numpy's buffers and the C workspace, which _core allocates
with numpy) against the size of the input arrays, the share of the time
inside the C entry point (``info["c_seconds"]``), the same search without
local optimisation and final refinement (what the samples alone cost: the
floor of the fixed part), PoseLib's time and rotation error, and the façade
on the same pixels (:func:`mcgeom.cv.estimate`: pixels and camera ids in, the
rays made in C): its time and its peak memory against ITS input, the pixels
and ids (48 bytes a correspondence, half the rays' 96: the rays alone are 2x
that input, so a peak within 2x of it is out of reach of any design that
holds the rays). Then the fit
of mcgeom's medians to a fixed cost per estimate plus a cost per
correspondence (:func:`fixed_and_marginal`).
"""

from __future__ import annotations

import time
import tracemalloc
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from mcgeom import metrics, robust
from mcgeom.cv import estimate
from mcgeom.pixel_noise import pixels_per_radian
from mcgeom.rig import Rig
from mcgeom.types import RayPairs

from ..common import Progress, no_progress
from ..poselib_peer import POSELIB_SETTINGS, TUNED_PEER, poselib_estimate_pixels, poselib_setup
from ..robust_vs_poselib import ring4
from .robust import generic_motion

__all__ = ["ScaleRow", "RingProblem", "ring_problem", "bench_scaling", "scaling_problems",
           "fixed_and_marginal", "fit_worst_error", "spread_ratios", "allowed_at_smallest"]


@dataclass
class ScaleRow:
    """One size of the scaling run: medians over ``problems`` problems."""
    n: int
    seconds: float
    us_per_corr: float
    peak_mb: float       # peak memory allocated during the call (tracemalloc)
    input_mb: float      # the four ray arrays, the pixels per radian and the camera ids
    rot_deg: float
    inlier_ratio: float
    c_seconds: float = float("nan")   # of ``seconds``, inside the C entry point
    problems: int = 1                 # the medians are over this many problems
    us_per_corr_min: float = float("nan")   # the fastest and slowest of them
    us_per_corr_max: float = float("nan")
    # the same search without local optimisation and final refinement
    search_seconds: float = float("nan")
    # PoseLib (TUNED_PEER) on the same pixels: median seconds, rotation error
    peer_seconds: float = float("nan")
    peer_rot_deg: float = float("nan")
    # the façade on the same pixels (mcgeom.cv.estimate: pixels and camera
    # ids in, their rays made in C): median seconds, and problem 0's peak
    # memory against its input (the pixels and ids, MB)
    facade_seconds: float = float("nan")
    facade_peak_mb: float = float("nan")
    facade_input_mb: float = float("nan")


@dataclass(frozen=True)
class RingProblem:
    """One scaling problem: the rig, the pixel correspondences (same camera at
    both times), their rays (rig frame, metres) and the true motion
    rig2_from_rig1."""
    rig: Rig
    pixels1: np.ndarray
    pixels2: np.ndarray
    cam: np.ndarray
    rays: RayPairs
    R: np.ndarray
    t: np.ndarray


def _uniform_pixels(rng: np.random.Generator, k: int, cam) -> np.ndarray:
    return rng.uniform([-0.5, -0.5], [cam.width - 0.5, cam.height - 0.5], size=(k, 2))


def ring_problem(n: int, rng: np.random.Generator, outliers: float = 0.2) -> RingProblem:
    """``n`` correspondences of the ring4 rig (see the module), built with numpy
    per camera (synth.make_problem draws point by point)."""
    rig = ring4()
    R, t = generic_motion(rng)
    cam = np.arange(n) % len(rig)
    px1, px2 = np.empty((n, 2)), np.empty((n, 2))
    for k, c in enumerate(rig.cameras):
        rows = np.flatnonzero(cam == k)
        got = rounds = 0
        while got < len(rows):
            rounds += 1
            if rounds > 100:   # (a motion that takes every point out of view)
                raise RuntimeError(f"ring_problem: camera {k} keeps too few points in view "
                                   f"({got} of {len(rows)} after 100 draws)")
            want = len(rows) - got
            p1 = _uniform_pixels(rng, 2 * want, c)
            X = c.centre + c.pixels_to_bearings(p1) * rng.uniform(2.0, 20.0, size=(2 * want, 1))
            p2, seen = c.project(X @ R.T + t)
            take = np.flatnonzero(seen)[:want]
            px1[rows[got:got + len(take)]] = p1[take]
            px2[rows[got:got + len(take)]] = p2[take]
            got += len(take)
    px1 += rng.normal(scale=0.5, size=px1.shape)
    px2 += rng.normal(scale=0.5, size=px2.shape)
    bad = np.flatnonzero(rng.random(n) < outliers)
    for k, c in enumerate(rig.cameras):
        rows = bad[cam[bad] == k]
        px2[rows] = _uniform_pixels(rng, len(rows), c)
    return RingProblem(rig, px1, px2, cam, rig.ray_pairs(px1, px2, cam), R, t)


def fixed_and_marginal(rows: Sequence[ScaleRow]) -> tuple[float, float]:
    """The cost model ``seconds = fixed + marginal * N`` fitted to the median
    times of the scaling rows (least squares of the relative errors, so that
    1e3 counts as much as 1e6): ``(fixed seconds, marginal seconds per
    correspondence)``. A cost per correspondence that falls with N is the
    fixed part (the samples, local optimisations and final refinement, whose
    number does not grow with N) spread over more correspondences: at N the
    cost per correspondence is ``marginal + fixed / N``. Needs two sizes."""
    if len({r.n for r in rows}) < 2:
        raise ValueError("the fit needs rows of at least two sizes")
    T = np.array([r.seconds for r in rows])
    N = np.array([float(r.n) for r in rows])
    (fixed, marginal), *_ = np.linalg.lstsq(np.stack([1.0 / T, N / T], axis=1),
                                            np.ones(len(rows)), rcond=None)
    return float(fixed), float(marginal)


def fit_worst_error(rows: Sequence[ScaleRow], fixed: float, marginal: float) -> float:
    """The largest relative error of ``fixed + marginal * N`` (seconds,
    seconds per correspondence) against the rows' median seconds."""
    return max(abs(fixed + marginal * r.n - r.seconds) / r.seconds for r in rows)


def spread_ratios(rows: Sequence[ScaleRow]) -> tuple[float, float, float]:
    """Largest / smallest median cost per correspondence over the rows:
    ``(mcgeom's, PoseLib's, the façade's)`` (issue 19's target: mcgeom's
    within 2; NaN for PoseLib when it did not run)."""
    per = [r.us_per_corr for r in rows]
    peer = [r.peer_seconds / r.n for r in rows]
    fac = [r.facade_seconds / r.n for r in rows]
    return max(per) / min(per), max(peer) / min(peer), max(fac) / min(fac)


def allowed_at_smallest(rows: Sequence[ScaleRow]) -> float:
    """Seconds the estimate at the smallest N may take for its cost per
    correspondence to lie within 2x of that at the largest N."""
    small, big = min(rows, key=lambda r: r.n), max(rows, key=lambda r: r.n)
    return 2.0 * big.seconds / big.n * small.n


def scaling_problems(n: int) -> int:
    """Problems timed at size ``n``: the time of one estimate moves by up to 3x
    between problems (the samples drawn before the adaptive stop), so a single
    draw per size says little about the cost per correspondence. 1e6 / n
    problems, at least 3 and at most 15 (10 at 1e5, where 3 gave medians
    that moved by 2x between runs: 0.300-0.602 us per correspondence)."""
    return int(min(15, max(3, 1e6 // n)))


def _timed(call) -> tuple[float, object]:
    t0 = time.perf_counter()
    out = call()
    return time.perf_counter() - t0, out


def bench_scaling(sizes=(1000, 10000, 100000, 1000000), seed: int = 0, peer: bool = True,
                  progress: Progress = no_progress) -> list[ScaleRow]:
    """Seconds, per-correspondence cost and peak memory of the robust estimate
    per N, the search alone, and PoseLib (``peer``) on the same pixels: medians
    over :func:`scaling_problems` problems (problem k drawn and solved with
    seed ``seed + k``); the peak is that of problem 0's call."""
    rows = []
    setup = poselib_setup(ring4(), "mcgeom bench robust") if peer else None
    for n in progress(list(sizes), total=len(sizes), desc="scaling"):
        times, c_times, search, peer_times, rot, peer_rot, inl = [], [], [], [], [], [], []
        facade = []
        peak = inp = f_peak = f_inp = 0.0
        for k in range(scaling_problems(int(n))):
            p = ring_problem(int(n), np.random.default_rng(seed + k))
            focal = pixels_per_radian(p.rig, p.rays)

            def run(s: int, **kw) -> object:
                return robust.ransac(p.rays, "five_plus_one", threshold=1.0, focal=focal,
                                     seed=s, **kw)

            def run_facade(s: int) -> object:
                return estimate(p.pixels1, p.pixels2, p.cam, p.cam, p.rig, threshold=1.0, seed=s)
            if k == 0:
                f_inp = (p.pixels1.nbytes + p.pixels2.nbytes + 2 * p.cam.nbytes) / 1e6
                run_facade(seed)  # warm
                tracemalloc.start()
                run_facade(seed)
                f_peak = tracemalloc.get_traced_memory()[1]
                tracemalloc.stop()
                r = p.rays
                inp = (r.origins1.nbytes + r.dirs1.nbytes + r.origins2.nbytes + r.dirs2.nbytes
                       + focal.nbytes + r.cam1.nbytes + r.cam2.nbytes) / 1e6
                run(seed)  # warm
                tracemalloc.start()
                run(seed)
                peak = tracemalloc.get_traced_memory()[1]
                tracemalloc.stop()
            # timed without tracemalloc's bookkeeping
            dt, m = _timed(lambda: run(seed + k))
            times.append(dt)
            c_times.append(float(m.info.get("c_seconds", float("nan"))))
            rot.append(float(np.degrees(metrics.rotation_error(m.R, p.R))))
            inl.append(float(m.info["inlier_ratio"]))
            search.append(_timed(lambda: run(seed + k, refine=False,
                                             local_optimization=False))[0])
            facade.append(_timed(lambda: run_facade(seed + k))[0])
            if setup is not None:
                dt, (Rp, _) = _timed(lambda: poselib_estimate_pixels(
                    setup, p.pixels1, p.pixels2, p.cam, p.cam, POSELIB_SETTINGS[TUNED_PEER]))
                peer_times.append(dt)
                peer_rot.append(float(np.degrees(metrics.rotation_error(Rp, p.R))))
        dt = float(np.median(times))
        rows.append(ScaleRow(int(n), dt, 1e6 * dt / n, peak / 1e6, inp, float(np.median(rot)),
                             float(np.median(inl)), float(np.median(c_times)), len(times),
                             1e6 * min(times) / n, 1e6 * max(times) / n,
                             float(np.median(search)),
                             float(np.median(peer_times)) if peer_times else float("nan"),
                             float(np.median(peer_rot)) if peer_rot else float("nan"),
                             float(np.median(facade)), f_peak / 1e6, f_inp))
    return rows
