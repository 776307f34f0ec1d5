"""Robust rig motion: LO-RANSAC with MSAC scoring, driven by any registered estimator.

Hypotheses come from the estimator's minimal solver on samples drawn across
the cameras of the rig (the estimator's own ``sampler``, else one correspondence
per camera pair in turn), or from its ``proposer`` (a method-specific robust
search such as the two-stage RANSAC of thesis ch. 7.4). Every hypothesis is
scored on all correspondences with the truncated quadratic (MSAC) of the
residual below; each new best one is locally optimised (re-estimated from its
inliers by nonlinear least squares, repeated while it improves); the number of
iterations adapts to the inlier ratio found (``prob``); the final motion is
refined on all its inliers with a robust loss.

Residual: the Sampson (first-order) angular error of the generalized epipolar
constraint (``_core.gec_residuals``), in radians on the unit sphere. With
``focal`` given (pixels, one value or one per correspondence) thresholds and
residuals are in pixels: radians x focal, the usual pinhole approximation;
per-correspondence values also weight the refinements (variance ~ 1/focal^2),
e.g. the effective focal length at each pixel of
:func:`mcgeom.pixel_noise.pixels_per_radian` (which :mod:`mcgeom.cv` passes).
``motion_focal`` (optional) gives the same per correspondence for a given
motion: the exact first-order pixel scaling, which depends on the direction of
the epipolar constraint's gradient; the final refinement uses it.
"""

from __future__ import annotations

import functools
import inspect
import math
import time
from dataclasses import dataclass, replace
from typing import Any, Callable, Optional, Union

import numpy as np

from . import _core, registry
from .errors import DegenerateError
# travel_direction: the direction an estimator reports when |t| is not
# observable; the robust layer finishes any estimator's motion and must report
# the same (see mcgeom.estimators._common: no estimator imports this module)
from .estimators._common import camera_ids, in_mirrored_minimum, travel_direction
from .estimators.five_plus_one import minimal_answer
# the vertical's checks (the messages name gravity1/gravity2) of the upright solver
from .estimators.upright_four_point import check_gravity
from .geometry import refine_centred, rotation_only_fit, rotation_only_residuals
from .observability import (NO_PARALLAX_FACTOR, ZERO_FACTOR, scale_determined, scale_profile,
                            scale_verdict, scale_verdict_stats, total_scale_std)
from .types import MotionFocal, RayPairs, RigMotion, ScaleVerdict
from .validation import check_seed

__all__ = ["RansacOptions", "ransac_options", "ransac", "residuals", "adaptive_iterations",
           "sample_across_cameras", "C_SAMPLERS"]

#: the estimators whose minimal solver the C entry point samples
#: (``mcg_robust_options.sampler``), with their sample sizes: 5 intra-camera
#: correspondences of one camera and a sixth; 4 of any cameras with the
#: vertical known; 6 not all of one camera; 17 not all of one camera for the
#: eigensolver (Kneip and Li's, from linear17's rotation) and for linear17
#: (its motion, thesis ch. 8)
C_SAMPLERS = {"five_plus_one": 6, "upright_four_point": 4, "six_point": 6, "eigensolver": 17,
              "linear17": 17}



@dataclass(frozen=True)
class RansacOptions:
    """Options of :func:`ransac` (units: radians, or pixels when ``focal`` is given)."""

    threshold: float = 1e-3
    prob: float = 0.999
    max_iters: int = 1000
    min_iters: int = 0
    seed: Optional[int] = 0
    local_optimization: bool = True
    lo_max_rounds: int = 2
    refine: bool = True
    loss: str = "cauchy"            # final refinement (scale: the threshold)
    max_scale_rel_std: float = 0.1
    # "auto": the C entry point (csrc/robust.c) for the estimators whose
    # minimal solver it samples (C_SAMPLERS: five_plus_one,
    # upright_four_point, six_point, eigensolver, linear17), else the
    # estimator's proposer, else its minimal solver; "proposer" and "minimal"
    # force the Python drivers below
    strategy: str = "auto"          # "auto" | "proposer" | "minimal"
    max_seconds: float = 0.0        # wall-time budget of the C search (0: none)

    def __post_init__(self) -> None:
        # numbers only: a string or None would otherwise fail inside numpy
        # with a TypeError that names nothing
        for name, v in (("threshold", self.threshold), ("prob", self.prob),
                        ("maxIters", self.max_iters)):
            if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, float, np.number)):
                raise ValueError(f"{name} must be a number, got {v!r}")
        # (math on Python scalars: numpy's scalar ufuncs cost ~1 us each, and
        # these checks run once per estimate)
        if not (_finite(self.threshold) and self.threshold > 0):
            raise ValueError(f"threshold must be a positive number, got {self.threshold}")
        if not (0.0 < self.prob < 1.0):
            raise ValueError(f"prob must be in (0, 1), got {self.prob}")
        if not (_finite(self.max_iters) and self.max_iters == int(self.max_iters)):
            raise ValueError(f"maxIters must be an integer, got {self.max_iters}")
        if int(self.max_iters) < 1:
            raise ValueError(f"maxIters must be >= 1, got {self.max_iters}")
        object.__setattr__(self, "seed", check_seed(self.seed))
        if isinstance(self.max_seconds, (bool, np.bool_)) or \
                not isinstance(self.max_seconds, (int, float, np.number)) or \
                not (_finite(self.max_seconds) and 0 <= self.max_seconds <= 1e9):
            raise ValueError(f"max_seconds must be a number in [0, 1e9] (0: no limit), got "
                             f"{self.max_seconds!r}")
        if self.strategy not in ("auto", "proposer", "minimal"):
            raise ValueError(f"strategy must be 'auto', 'proposer' or 'minimal', got "
                             f"{self.strategy!r}")

    def with_seed(self, seed: Any) -> "RansacOptions":
        """These options with another ``seed`` (checked as the constructor
        checks it; the other fields were checked when these were made). A
        caller that draws a seed per estimate keeps one checked set of the
        rest (issue 19: the constructor's checks cost ~15 us of a cold
        ~0.45 ms estimate)."""
        out = object.__new__(RansacOptions)
        out.__dict__.update(self.__dict__)
        object.__setattr__(out, "seed", check_seed(seed))
        return out


@functools.lru_cache(maxsize=64, typed=True)
def _checked_options(threshold: Any, prob: Any, max_iters: Any) -> RansacOptions:
    return RansacOptions(threshold=threshold, prob=prob, max_iters=max_iters)


def ransac_options(threshold: Any, prob: Any, max_iters: Any, seed: Any) -> RansacOptions:
    """``RansacOptions(threshold=..., prob=..., max_iters=..., seed=...)``,
    the first three checked once per distinct set (typed: ``True`` is no
    ``1``), the seed -- often a new one per estimate -- set on a copy
    (:meth:`RansacOptions.with_seed`): the constructor's checks cost ~15 us
    of a ~0.5 ms estimate (issue 19). Unhashable arguments are checked
    afresh (and named) every time. The same ValueError as the constructor
    on a bad value."""
    try:
        base = _checked_options(threshold, prob, max_iters)
    except TypeError:           # unhashable: no cache
        return RansacOptions(threshold=threshold, prob=prob, max_iters=max_iters, seed=seed)
    return base if type(seed) is int and seed == base.seed else base.with_seed(seed)


def _finite(v: Any) -> bool:
    """Is the real number ``v`` finite (an int too large for a float is not)?"""
    try:
        return math.isfinite(v)
    except OverflowError:
        return False


def _focal_array(focal: Union[None, float, np.ndarray], n: int) -> Optional[np.ndarray]:
    if focal is None:
        return None
    f = np.asarray(focal, dtype=np.float64)
    if f.ndim == 0:
        f = np.full(n, float(f))
    # min > 0 and max < inf: NaN fails both (two reductions, no temporaries)
    if f.shape != (n,) or (n and not (f.min() > 0 and f.max() < np.inf)):
        raise ValueError(f"focal must be a positive number or {n} positive numbers")
    # (C-contiguous: the C search takes it as it is, prechecked)
    return np.ascontiguousarray(f)


def residuals(rays: RayPairs, R: np.ndarray, t: np.ndarray,
              focal: Union[None, float, np.ndarray] = None) -> np.ndarray:
    """Absolute Sampson angular residual of every correspondence for motion (R, t).

    Radians on the unit sphere, or pixels (radians x ``focal``) when ``focal``
    is given.
    """
    return _residuals(rays, R, t, _focal_array(focal, len(rays)))


def _residuals(rays: RayPairs, R: np.ndarray, t: np.ndarray,
               focal: Optional[np.ndarray]) -> np.ndarray:
    """:func:`residuals` with ``focal`` already validated (the scoring hot path)."""
    r = np.abs(_core.gec_residuals(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2,
                                   np.asarray(R, dtype=np.float64),
                                   np.asarray(t, dtype=np.float64)))
    return r if focal is None else r * focal


def adaptive_iterations(inlier_ratio: float, sample_size: int, prob: float,
                        max_iters: int) -> int:
    """Iterations after which an all-inlier sample was drawn with probability ``prob``."""
    w = float(np.clip(inlier_ratio, 0.0, 1.0)) ** sample_size
    if w <= 0.0:
        return int(max_iters)
    if w >= 1.0:
        return 1
    k = np.log1p(-prob) / np.log1p(-w)
    return int(min(max_iters, np.ceil(k)))


def sample_across_cameras(rays: RayPairs, size: int, rng: np.random.Generator) -> np.ndarray:
    """``size`` distinct correspondences spread over the camera pairs.

    A uniform draw with at most ``ceil(size / G)`` correspondences of each of
    the G camera pairs (cam1, cam2) (raised round by round only when the
    others cannot fill the sample): no camera dominates the sample (drawing
    uniformly from all correspondences would give samples from the one
    camera that has most of them), and no camera pair is forced into it.
    Visiting every pair once per round did force them: with a sample as
    large as the pairs (17 correspondences over 16 camera pairs), every
    sample held each one-correspondence pair, and where that one was an
    outlier no sample was clean (a generic 4-camera rig, 150 pairs, 20 %
    outliers: the eigensolver's RANSAC found no consensus in 1000 samples).
    Indices into ``rays``, in the order drawn.
    """
    n = len(rays)
    if size > n:
        raise ValueError(f"too few correspondences: a sample needs {size}, got {n}")
    if rays.cam1 is None or rays.cam2 is None:
        return rng.choice(n, size, replace=False)
    key = rays.cam1 * (int(rays.cam2.max(initial=0)) + 1) + rays.cam2
    _, group = np.unique(key, return_inverse=True)
    group = group.ravel()
    perm = rng.permutation(n)
    g = group[perm]
    # rank of each drawn correspondence among those of its camera pair drawn
    # before it: round r of the draw holds ranks [r cap, (r + 1) cap)
    counts = np.bincount(g)
    by_group = np.argsort(g, kind="stable")
    rank = np.empty(n, dtype=np.int64)
    rank[by_group] = np.arange(n) - np.repeat(np.cumsum(counts) - counts, counts)
    cap = -(-size // len(counts))
    take = np.argsort((rank // cap) * n + np.arange(n), kind="stable")[:size]
    return perm[take].astype(np.int64)


def _msac(r: np.ndarray, thr: float) -> float:
    return float(np.minimum(r * r, thr * thr).sum())


class _Scorer:
    """Scores motions on all correspondences and runs the local optimisation."""

    def __init__(self, rays: RayPairs, thr: float, focal: Optional[np.ndarray],
                 opts: RansacOptions, motion_focal: Optional[MotionFocal] = None):
        self.rays, self.thr, self.focal, self.opts = rays, thr, focal, opts
        self.motion_focal = motion_focal
        # Per-correspondence focal lengths (pixels per radian of residual)
        # also weight the least squares: a residual of r radians is r * f_i
        # pixels, so its variance under pixel noise is ~ 1 / f_i^2.
        med = None if focal is None else np.median(focal)   # one median serves both
        self.weights = None if focal is None or np.ptp(focal) == 0 else (focal / med) ** 2
        # loss scale in radians (the threshold, converted from pixels if needed)
        self.loss_scale = thr if focal is None else thr / float(med)
        self.best: Optional[tuple[np.ndarray, np.ndarray]] = None
        self.best_score = np.inf
        self.best_inliers = np.zeros(len(rays), bool)
        # residuals of ``best`` on all correspondences (the final stage starts from them)
        self.best_residuals: Optional[np.ndarray] = None
        self.n_hyp = 0
        self.n_lo = 0
        self.lo_rounds = opts.lo_max_rounds

    def residuals(self, R: np.ndarray, t: np.ndarray) -> np.ndarray:
        return _residuals(self.rays, R, t, self.focal)

    def offer(self, R: np.ndarray, t: np.ndarray) -> bool:
        """Score a hypothesis; keep (and locally optimise) it if it is the best so far."""
        self.n_hyp += 1
        if not (np.all(np.isfinite(R)) and np.all(np.isfinite(t))):
            return False
        r = self.residuals(R, t)
        score = _msac(r, self.thr)
        if score >= self.best_score:
            return False
        self.best, self.best_score, self.best_inliers = (R, t), score, r < self.thr
        self.best_residuals = r
        if self.opts.local_optimization:
            self._local_optimise()
        return True

    def _local_optimise(self) -> None:
        """Re-estimate from the inliers by robust least squares while the score improves."""
        for _ in range(self.lo_rounds):
            inl = self.best_inliers
            if inl.sum() < 6:
                return
            R, t = self.best
            self.n_lo += 1
            try:
                # the length of the centroid's translation is held: LO is
                # about the inlier set, and near the critical motion a free
                # fit slides |t| towards infinity (the final stage frees it)
                out = _refine(self.rays.take(inl), R, t, self.loss_scale, "cauchy",
                              self._w(inl), fix_scale=True)
            except (ValueError, ArithmeticError):
                return
            r = self.residuals(out["R"], out["t"])
            score = _msac(r, self.thr)
            if not score < self.best_score * (1.0 - 1e-9):
                return
            same = np.array_equal(r < self.thr, inl)
            self.best, self.best_score, self.best_inliers = (out["R"], out["t"]), score, r < self.thr
            self.best_residuals = r
            if same:   # the same inliers would give the same fit again
                return

    def _w(self, mask: np.ndarray) -> Optional[np.ndarray]:
        return None if self.weights is None else self.weights[mask]

    def scaling_at(self, R: np.ndarray, t: np.ndarray
                   ) -> tuple[Optional[np.ndarray], Optional[np.ndarray], float]:
        """Pixel scaling of the residuals at motion (R, t): focal, weights, loss scale.

        Without ``motion_focal`` it is the fixed one the scoring uses. With it,
        each residual is scaled by its own pixels per radian at this motion, so
        that the weighted residuals and the loss are those of the image-plane
        Sampson error (thesis eq. 8.15 with the pixel noise propagated to first order):
        the isotropic per-correspondence focal misweighs a correspondence
        whose epipolar gradient points radially (measured on a 4-camera ring at
        0.1 px: rotation median 0.0034 -> 0.0033 deg, the optimum of the
        image-plane Sampson cost).
        """
        if self.motion_focal is None:
            return self.focal, self.weights, self.loss_scale
        f = np.asarray(self.motion_focal(self.rays, R, t), dtype=np.float64)
        med = float(np.median(f))
        return f, (f / med) ** 2, self.thr / med


#: fewest correspondences the final refinement (``refine_centred``) can fit
_MIN_REFIT = 6
#: the final refinement fits the correspondences within this many thresholds
#: (csrc/robust_internal.h WIDE; the confidence counts them as the consensus)
WIDE = 2.0


def _refine(rays: RayPairs, R: np.ndarray, t: np.ndarray, loss_scale: float, loss: str,
            weights: Optional[np.ndarray] = None, fix_scale: bool = False) -> dict:
    return refine_centred(rays, R, t, loss=loss, loss_scale=loss_scale, weights=weights,
                          fix_scale=fix_scale)


def ransac(rays: RayPairs, method: str = "five_plus_one", *,
           threshold: Optional[float] = None, prob: float = 0.999, max_iters: int = 1000,
           seed: Optional[int] = 0, focal: Union[None, float, np.ndarray] = None,
           options: Optional[RansacOptions] = None,
           motion_focal: Optional[MotionFocal] = None, calibration_std: Any = None,
           pixel_cameras: Optional[tuple[np.ndarray, np.ndarray]] = None,
           solver_options: Optional[dict] = None, **kw: Any) -> RigMotion:
    """Robust rig motion rig2_from_rig1 from correspondences with outliers.

    ``method`` is a registered estimator with a minimal solver or a proposer.
    ``threshold`` is the inlier threshold on the Sampson angular residual
    (radians; pixels when ``focal`` gives the focal length in pixels, one value
    or one per correspondence); ``prob`` the confidence of the adaptive stop;
    ``max_iters`` caps the number of samples; ``seed`` makes the run
    deterministic. ``motion_focal(rays, R, t)`` (with ``focal`` only) returns
    the pixels per radian of every residual at motion (R, t), for the final
    refinement (see :meth:`_Scorer.scaling_at`). ``calibration_std`` is the
    rig's extrinsic calibration error, one pair (position std in metres,
    rotation std in radians) for every camera or an (M, 2) array by camera id
    (:attr:`mcgeom.rig.Rig.extrinsic_std`; :func:`mcgeom.cv.estimate` passes
    the rig's): the relative std of ``|t|`` and the verdict include its
    effect (:func:`mcgeom.observability.calibration_scale_std`); None = rays
    known exactly. ``solver_options`` are keyword options of the estimator's
    minimal solver (e.g. ``gravity1``/``gravity2`` of ``upright_four_point``).
    Further ``RansacOptions`` fields may be passed as keywords.

    The methods of :data:`C_SAMPLERS` (``five_plus_one``,
    ``upright_four_point`` with ``solver_options={"gravity1": g1, "gravity2":
    g2}``, ``six_point``, ``eigensolver``, ``linear17``) with
    ``strategy="auto"`` run as one call of the C entry point
    ``mcg_robust_rig_motion`` (csrc/robust.c: the method's minimal samples,
    MSAC, local optimisation, adaptive stop, final refinement of all six
    degrees of freedom); the verdict stays here;
    ``info["sampler"]`` names the minimal solver and ``info["sample_size"]``
    the pairs of its samples (5 for 5+1, 6 for the 6-point, 17 for the
    eigensolver and linear17; the upright
    sampler's 3 for its 3+1 samples, 4 for its 4-point ones: see
    :mod:`mcgeom.estimators.upright_four_point`). ``pixel_cameras = (focal,
    axes)``, the (M,) focal lengths (pixels) and (M, 3) optical axes (rig
    frame) of the rig's cameras (see
    :func:`mcgeom.pixel_noise.camera_table`), is the camera table that
    ``motion_focal`` is computed from: the C search uses it for the final
    refinement (with ``motion_focal`` but without it, the Python drivers run).

    Returns a ``RigMotion`` with the boolean ``inliers`` mask, the scale verdict
    (from the covariance of the final refinement, plus the estimator's own
    evidence such as the critical angle of ch. 7) and ``info`` with the number
    of iterations, hypotheses, local optimisations, the inlier ratio and the time;
    ``info["t_metric"]`` is the metric guess of t whatever the verdict, and
    ``info["t_slid"]`` is True when the refinement's |t| left the data (grew
    over 10x, or crossed zero into the mirrored minimum): ``t_metric`` is then
    the robust hypothesis' length along the travel direction, and the verdict,
    never observable, was judged at the refined motion.
    Raises ValueError for bad input or when no hypothesis could be formed
    (e.g. too few correspondences), DegenerateError when no motion explains
    enough correspondences.
    """
    t_start = time.perf_counter()
    if not isinstance(rays, RayPairs):
        raise TypeError(f"rays must be a RayPairs, got {type(rays).__name__}")
    if options is None:
        thr = threshold if threshold is not None else (1.0 if focal is not None else 1e-3)
        options = ransac_options(thr, prob, max_iters, seed) if not kw else \
            RansacOptions(threshold=thr, prob=prob, max_iters=max_iters, seed=seed, **kw)
    return _ransac(rays, method, options, focal, motion_focal, calibration_std, pixel_cameras,
                   solver_options, t_start, False)


def ransac_prechecked(rays: RayPairs, method: str, options: RansacOptions, focal: np.ndarray,
                      motion_focal: MotionFocal, calibration_std: np.ndarray,
                      pixel_cameras: tuple[np.ndarray, np.ndarray],
                      solver_options: Optional[dict] = None) -> RigMotion:
    """:func:`ransac` in pixels, for a caller that made its arguments from a
    :class:`mcgeom.rig.Rig` and checked them (:func:`mcgeom.cv.estimate`);
    the same result, without the checks that cannot fail on such input
    (issue 19: each is an O(N) numpy pass).

    Preconditions (the caller's to guarantee; nothing of this is checked):
    ``rays`` from :meth:`mcgeom.rig.Rig.ray_pairs_prechecked` (or a subset:
    origins are the camera centres, ``cam1``/``cam2`` int64 ids of the rig),
    ``focal`` (N,) finite float64 > 0 (pixels per radian,
    :func:`mcgeom.pixel_noise.pixels_per_radian`), ``pixel_cameras`` the
    rig's :func:`mcgeom.pixel_noise.camera_table` and ``motion_focal`` its
    :func:`mcgeom.pixel_noise.sampson_pixel_scale`, ``calibration_std`` an
    (M, 2) array (:attr:`mcgeom.rig.Rig.extrinsic_std`), ``options`` a
    :class:`RansacOptions` (validated when made). What the data may still
    get wrong (too few or repeated correspondences, no camera with 5
    intra-camera ones for 5+1, a threshold above 1 rad) is checked as by
    :func:`ransac`, with the same messages.
    """
    return _ransac(rays, method, options, focal, motion_focal, calibration_std, pixel_cameras,
                   solver_options, time.perf_counter(), True)


def _ransac(rays: RayPairs, method: str, options: RansacOptions, focal: Any,
            motion_focal: Optional[MotionFocal], calibration_std: Any,
            pixel_cameras: Optional[tuple[np.ndarray, np.ndarray]],
            solver_options: Optional[dict], t_start: float, from_rig: bool) -> RigMotion:
    """:func:`ransac` with ``options`` made; ``from_rig``: the preconditions
    of :func:`ransac_prechecked` hold (``focal`` a checked array, camera ids
    of the rig of ``pixel_cameras``, origins at their centres)."""
    in_c = method in C_SAMPLERS and options.strategy == "auto" and \
        (motion_focal is None or pixel_cameras is not None)
    # (the C search needs no plugin: its samplers are the C solvers)
    info_est = None if in_c else registry.get(method)
    need = C_SAMPLERS[method] if in_c else info_est.min_sample
    n = len(rays)
    if n < need:
        raise ValueError(f"too few correspondences: {method} needs at least {need}, got {n}")
    if not in_c or (method == "five_plus_one" and n == 6):
        # (the C entry point checks finiteness and zero directions in its own
        # pass and names the array: no extra numpy passes on its path)
        rays.check_finite()
    registry.check_distinct(rays, need, method)
    f = focal if from_rig else _focal_array(focal, n)
    if motion_focal is not None and f is None:
        raise ValueError("motion_focal needs focal (thresholds in pixels)")
    if method == "five_plus_one" and n == 6:
        # exactly minimal input: every motion that fits it exactly, the ambiguity
        # in the verdict (issue 18; mcgeom.estimators.five_plus_one.minimal_answer)
        thr = options.threshold / (1.0 if f is None else float(np.median(f)))
        m = minimal_answer(rays, f"ransac[{method}]", thr, with_inliers=True)
        if m is not None:
            return m
    if in_c:
        return _ransac_c(rays, f, options, pixel_cameras, t_start, calibration_std, method,
                         solver_options or {}, from_rig and pixel_cameras is not None)
    rng = np.random.default_rng(options.seed)
    scorer = _Scorer(rays, options.threshold, f, options, motion_focal)
    _check_threshold_angle(options.threshold, scorer.loss_scale, f)

    use_proposer = info_est.proposer is not None and options.strategy in ("auto", "proposer")
    if options.strategy == "proposer" and info_est.proposer is None:
        raise ValueError(f"estimator {method!r} has no proposer")
    if not use_proposer and info_est.minimal_solver is None:
        raise ValueError(f"estimator {method!r} has no minimal solver: it cannot drive RANSAC")
    if solver_options and info_est.minimal_solver is not None:
        _check_solver_options(info_est.minimal_solver, method, solver_options)
    iterations = 0
    if use_proposer:
        iterations = _run_proposer(info_est, rays, scorer, options, rng)
        # nothing proposed (e.g. no camera with enough correspondences for the
        # proposer's own search): fall back to minimal samples where possible
        use_proposer = scorer.best is not None or info_est.minimal_solver is None
    samples = 0   # minimal samples drawn (the proposer's motions are no samples)
    if not use_proposer:
        samples = _run_minimal(info_est, rays, scorer, options, rng, solver_options or {})
        iterations += samples
    ended = {"iterations": iterations, "hypotheses": scorer.n_hyp,
             "stop": "max_iterations" if iterations >= options.max_iters else "confidence",
             "sample_size": info_est.min_sample}
    if scorer.best is None or scorer.best_inliers.sum() < max(6, info_est.min_sample):
        return _nothing_found(rays, scorer, options, method, t_start, max(6, info_est.min_sample),
                              f" ({scorer.n_hyp} hypotheses from {iterations} samples)", ended)
    return _finish(rays, scorer, options, method, iterations, t_start, calibration_std,
                   dict(ended, iterations=samples) if samples else None)


#: largest inlier threshold as an angle (radians): above it every correspondence is an
#: inlier, and the Cauchy refinement's loss scale overflows long before 1e200 px
MAX_THRESHOLD_RAD = 1.0
#: a hypothesis that explains the minimal number of correspondences within this angle
#: (radians; 10 px at f = 1000 px, pixel noise and then some) fits the data: none within
#: the threshold means the threshold, not the data, is at fault
_FITS_RAD = 1e-2


def _unit(focal: Optional[np.ndarray]) -> str:
    return "px" if focal is not None else "rad"


def _check_threshold_angle(threshold: float, angle: float, focal: Optional[np.ndarray]) -> None:
    """ValueError naming ``threshold`` when it is an angle above :data:`MAX_THRESHOLD_RAD`
    (rather than "coordinates so large that the computation overflows" from the
    refinement, or every correspondence an inlier of a pure rotation)."""
    if angle > MAX_THRESHOLD_RAD:
        at = (f" at the rig's {float(np.median(focal)):.4g} px per radian"
              if focal is not None else "")
        limit = (f"{MAX_THRESHOLD_RAD * float(np.median(focal)):.4g} px" if focal is not None
                 else f"{MAX_THRESHOLD_RAD:g} rad")
        raise ValueError(f"threshold {threshold:g} {_unit(focal)} is an angular error of "
                         f"{angle:.3g} rad{at}: above {MAX_THRESHOLD_RAD:g} rad every "
                         f"correspondence is an inlier; it must be at most {limit} (of the "
                         f"order of the pixel noise, e.g. 1 px)")


def _threshold_too_small(rays: RayPairs, scorer: "_Scorer", options: RansacOptions,
                         method: str, need: int) -> None:
    """DegenerateError naming ``threshold`` when hypotheses were found that fit ``need``
    correspondences closely, but not within the threshold: the threshold is below what
    even exact samples reach, the data are not degenerate."""
    if scorer.best is None:
        return
    r = np.sort(scorer.residuals(*scorer.best))
    if r.size < need:
        return
    r_k = float(r[need - 1])
    angle = r_k if scorer.focal is None else r_k / float(np.median(scorer.focal))
    if r_k > options.threshold and angle <= _FITS_RAD:
        unit = _unit(scorer.focal)
        # a DegenerateError (a ValueError) as before: callers that catch "no motion
        # found" still do; the message names the threshold, not collinear points
        raise DegenerateError(f"threshold {options.threshold:g} {unit} is too small: the best of "
                         f"{scorer.n_hyp} hypotheses of {method} explains {need} "
                         f"correspondences within {r_k:.3g} {unit} but fewer within the "
                         f"threshold; pass a threshold of the order of the pixel noise "
                         f"(e.g. 1 px; if it is that already, the data do not determine the "
                         f"motion)")


def _nothing_found(rays: RayPairs, scorer: "_Scorer", options: RansacOptions, method: str,
                   t_start: float, need: int, counts: str,
                   ended: Optional[dict] = None) -> RigMotion:
    """No motion explains ``need`` correspondences: a static rig or pure
    rotation (:func:`_no_translation`), else DegenerateError; ``ended`` (how
    the search ended: ``iterations``, ``hypotheses``, ``stop``,
    ``sample_size``) names its cap when the cap ended it."""
    still = _no_translation(rays, scorer, options, method, t_start)
    if still is not None:
        return still
    _threshold_too_small(rays, scorer, options, method, need)
    if ended and ended.get("stop") in ("max_iterations", "max_seconds"):
        raise DegenerateError(_capped_message(rays, method, need, ended))
    raise DegenerateError(f"{method}: no motion found that explains at least {need} "
                          f"correspondences{counts}: degenerate data (e.g. points collinear or "
                          f"coplanar in every camera, or too few correspondences per camera: "
                          f"{_per_camera(rays)})")


def _capped_message(rays: RayPairs, method: str, need: int, ended: dict) -> str:
    """The error of a search that its cap ended with no consensus: the data
    may be degenerate, or no sample drawn was all inliers (issue 21: a
    17-pair sample is all inliers once in ~6,000 draws at 40 % outliers; the
    message blamed the data alone)."""
    k, m, h = int(ended["iterations"]), int(ended["sample_size"]), int(ended["hypotheses"])
    cap = ("its time limit (max_seconds)" if ended["stop"] == "max_seconds" else
           "its sample cap (maxIters of mcgeom.cv.estimate, max_iters of mcgeom.robust.ransac)")
    return (f"{method}: no motion found that explains at least {need} correspondences after "
            f"{k} sample{'' if k == 1 else 's'} ({h} hypothes{'is' if h == 1 else 'es'}): the "
            f"search reached {cap}. Either no sample was all inliers -- at an inlier fraction "
            f"w a sample of this sampler is with probability w^{m}: once in "
            f"{1 / 0.7 ** m:,.0f} draws at 30 % outliers, once in {1 / 0.5 ** m:,.0f} at "
            f"50 % -- then raise the cap, or use a sampler with smaller samples where the "
            f"data allow one (the default method picks 5+1, the upright or the 6-point "
            f"sampler); or the data are degenerate (e.g. points collinear or coplanar in "
            f"every camera; {_per_camera(rays)})")


def _per_camera(rays: RayPairs) -> str:
    if rays.cam1 is None:
        return "camera ids unknown"
    same = rays.cam1 == rays.cam2
    counts = np.bincount(rays.cam1[same], minlength=int(rays.cam1.max(initial=0)) + 1)
    return (", ".join(f"camera {k}: {c}" for k, c in enumerate(counts)) +
            f"; {int((~same).sum())} cross-camera")


def _check_solver_options(solver: Callable, method: str, solver_options: dict) -> None:
    """The Python loop passes ``solver_options`` to the estimator's minimal
    solver (after the sample): a key it does not take is a ValueError naming
    it, not a TypeError in the loop."""
    params = list(inspect.signature(solver).parameters.values())
    if any(p.kind == p.VAR_KEYWORD for p in params):
        return
    taken = {p.name for p in params[1:] if p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD)}
    bad = sorted(k for k in solver_options if k not in taken)
    if bad:
        hint = (" ('solver' picks the 6-point solver of the C search, strategy='auto'; the "
                "Python loop solves with the homotopy)" if method == "six_point" and
                "solver" in bad else "")
        raise ValueError(f"solver_options {bad} are not options of {method}'s minimal solver "
                         f"in the Python loop{hint}")


def _run_proposer(info_est, rays: RayPairs, scorer: _Scorer, options: RansacOptions,
                  rng: np.random.Generator) -> int:
    """Score the proposer's motions until one explains the expected inlier ratio."""
    iterations = 0
    # a proposer's motions come out of a robust search with its own local
    # optimisation (OpenCV's USAC for 5+1): one round here is enough, the
    # final stage refits on the inliers again. (It is still needed: without
    # it a motion from one camera's rotation explains too few correspondences
    # of the others and the next camera's search runs, 1.11 -> 1.33 searches
    # per Ladybug problem; a second round changed no result, measured.)
    lo = scorer.lo_rounds
    scorer.lo_rounds = min(1, options.lo_max_rounds)
    for prop in info_est.proposer(rays, scorer.loss_scale, options.prob, rng):
        iterations += 1
        scorer.offer(prop[0], prop[1])
        # a proposer may say which inlier ratio to expect (e.g. the one of its
        # own robust search): stop once a motion explains about that
        if len(prop) > 2 and scorer.best is not None and \
                _ratio(scorer.best_inliers) >= 0.95 * prop[2]:
            break
    scorer.lo_rounds = lo
    return iterations


def _ratio(mask: np.ndarray) -> float:
    """Fraction of True in a boolean mask (``mask.mean()`` without its overhead)."""
    return np.count_nonzero(mask) / mask.size


def _run_minimal(info_est, rays: RayPairs, scorer: _Scorer, options: RansacOptions,
                 rng: np.random.Generator, solver_options: dict) -> int:
    """Classic LO-RANSAC loop over minimal samples with the adaptive stop."""
    sampler = info_est.sampler or (lambda r, g: sample_across_cameras(r, info_est.min_sample, g))
    k_needed = options.max_iters
    iterations = 0
    while iterations < max(k_needed, options.min_iters) and iterations < options.max_iters:
        iterations += 1
        try:
            idx = sampler(rays, rng)
            sols = info_est.minimal_solver(rays.take(idx), **solver_options)
        except DegenerateError:
            continue
        for R, t in sols:
            if scorer.offer(R, t):
                ratio = scorer.best_inliers.mean()
                k_needed = adaptive_iterations(ratio, info_est.min_sample, options.prob,
                                               options.max_iters)
    return iterations


def _no_translation(rays: RayPairs, scorer: _Scorer, options: RansacOptions, method: str,
                    t_start: float) -> Optional[RigMotion]:
    """When no motion was found: is it because the rig did not translate?

    A static rig (or a pure rotation) has no essential matrix: every search
    fails. If a pure rotation (refitted on its own inliers) explains at least
    half of the intra-camera correspondences within the threshold, report that
    rotation with ``t = 0`` and the verdict "no translation detected".
    """
    sel = np.ones(len(rays), bool)
    for _ in range(3):
        R, ang = rotation_only_fit(rays, sel)
        if ang.size < 5:
            return None
        r_all = rotation_only_residuals(rays, R)
        f = scorer.focal if scorer.focal is not None else 1.0
        sel = r_all * f < options.threshold
    same = (rays.cam1 == rays.cam2) if rays.cam1 is not None else np.ones(len(rays), bool)
    if sel.sum() < 5 or sel[same].mean() < 0.5:
        return None
    verdict = ScaleVerdict(False, "no translation detected: a pure rotation explains "
                                  f"{int(sel.sum())} of {len(rays)} correspondences and no "
                                  "motion with a translation was found (static rig or pure "
                                  "rotation): t = 0, neither its direction nor its scale is "
                                  "determined", 0.0, float("inf"), 0.0)
    info = {"translation_detected": False, "t_metric": np.zeros(3), "inlier_ratio":
            float(sel.mean()), "time_s": time.perf_counter() - t_start}
    return RigMotion(R, np.zeros(3), verdict, f"ransac[{method}]", float("nan"), sel, info)


def _finish(rays: RayPairs, scorer: _Scorer, options: RansacOptions, method: str,
            iterations: int, t_start: float, calibration_std: Any = None,
            sampled: Optional[dict] = None) -> RigMotion:
    """Final robust refinement on the inliers, verdict and diagnostics.
    ``sampled``: how the minimal samples' search ended (``iterations`` =
    samples drawn, ``stop``, ``sample_size``), None when no sample was drawn
    (the proposer's own robust search found the motion); it gives the
    search's confidence and, after a cap below :data:`CONFIRMED`, the
    unconfirmed verdict, as the C search's (:func:`_c_conclude`)."""
    R, t = scorer.best
    inl = scorer.best_inliers
    info: dict = {"iterations": iterations, "hypotheses": scorer.n_hyp,
                  "local_optimizations": scorer.n_lo}
    r = None
    out = used = scale_used = w_used = None
    if options.refine:
        # All six degrees of freedom are refined even when |t| turns out to be
        # unobservable: where the cost is flat in |t| the refinement may move it
        # far, but R and the direction stay right, whereas holding |t| at a
        # wrong value bends R and the direction to compensate (measured: 0.03
        # -> 0.2 deg on the Ladybug head). The verdict then reports the direction.
        # The fit uses every correspondence within 2 thresholds, with a
        # robust loss of the threshold's scale: a hard cut at the threshold
        # drops the tail of the true inliers (|r| > 1 px for ~16 % of them at
        # 0.5 px noise) and loses accuracy (measured on the Ladybug head); a
        # wider cut admits more outliers, and where |t| is weakly observable
        # each one pulls it (2.5 thresholds: Ladybug scale median 0.195,
        # 0.184, 0.194 over three seeds; 2: 0.186, 0.179, 0.174).
        # The set is gated with the scorer's residuals (the consensus RANSAC
        # found); the fit weighs them by their exact pixel scaling at the
        # motion (``scaling_at``). Gating with the latter too measured no gain
        # (Ladybug scale median 0.186 -> 0.192, 0.179 -> 0.180, 0.174 -> 0.179
        # over three seeds; 0.187, 0.176, 0.180 as done here).
        wide = WIDE * options.threshold
        sel = scorer.best_residuals < wide     # the residuals of (R, t), kept by the scorer
        for _ in range(2):   # refit once more if the set moved
            used = sel
            _, weights, scale_used = scorer.scaling_at(R, t)
            w_used = None if weights is None else weights[used]
            out = _refine(rays.take(used), R, t, scale_used, options.loss, w_used)
            R, t = out["R"], out["t"]
            r = scorer.residuals(R, t)
            sel = r < wide
            # a set too small to refit (the refinement left the consensus,
            # e.g. sliding along a central rig's free scale): stop here
            if np.array_equal(sel, used) or np.count_nonzero(sel) < _MIN_REFIT:
                break
        inl = r < options.threshold
    if r is None:
        r = scorer.best_residuals
    info["score"] = scorer.best_score
    unconfirmed = None
    if sampled is not None:
        # w as the C search's: the final consensus within WIDE thresholds
        w = np.count_nonzero(r < WIDE * options.threshold) / len(rays)
        info.update(stop=sampled["stop"], sample_size=sampled["sample_size"],
                    confidence=search_confidence(sampled["iterations"],
                                                 sampled["sample_size"], w))
        unconfirmed = _unconfirmed(sampled["stop"], sampled["iterations"],
                                   sampled["sample_size"], info["confidence"])
    fit = (out, used, scale_used, w_used) if options.refine else None
    return _conclude(rays, R, t, r, inl, fit, scorer.loss_scale, np.linalg.norm(scorer.best[1]),
                     options, method, info, t_start, calibration_std=calibration_std,
                     unconfirmed=unconfirmed)


def search_confidence(samples: int, sample_size: int, inlier_fraction: float) -> float:
    """How likely a search of ``samples`` uniform samples of ``sample_size``
    correspondences drew one of inliers only, at an ``inlier_fraction`` of
    them: 1 - (1 - w^m)^k (the adaptive stop's rule read backwards; the C
    search's ``confidence``, csrc/robust.c search_confidence)."""
    p = float(inlier_fraction) ** int(sample_size)
    if samples <= 0 or not p > 0.0:
        return 0.0
    if not p < 1.0:
        return 1.0
    return float(-math.expm1(samples * math.log1p(-p)))


def _unconfirmed(stop: str, samples: int, sample_size: int, confidence: float
                 ) -> Optional[str]:
    """The verdict's reason when a cap (``stop`` not "confidence") ended the
    search at a ``confidence`` below :data:`CONFIRMED`, else None."""
    if stop == "confidence" or confidence >= CONFIRMED:
        return None
    return (f"consensus not confirmed: the search reached its "
            f"{'time limit' if stop == 'max_seconds' else 'sample cap'} after {samples} "
            f"samples of {sample_size} with a chance of {confidence:.2g} to have drawn one of "
            f"inliers of this consensus; the motion may be a partial fit: raise the cap "
            f"(maxIters, max_iters) or the time limit")


def _conclude(rays: RayPairs, R: np.ndarray, t: np.ndarray, r: Optional[np.ndarray],
              inl: np.ndarray, fit: Optional[tuple], loss_scale: float, n0: float,
              options: RansacOptions, method: str, info: dict, t_start: float,
              profile: Optional[float] = None, calibration_std: Any = None,
              rms: Optional[float] = None, c_ids: Optional[tuple] = None,
              zero_profile: float = float("nan"),
              unconfirmed: Optional[str] = None) -> RigMotion:
    """Scale verdict and the returned ``RigMotion`` of a robust estimate.

    ``r`` are the residuals at the final (R, t) (pixels when thresholds are),
    ``inl`` the inliers; ``fit`` = (refinement dict, the mask of the pairs it
    used, its loss scale (radians), their weights) of the final refinement,
    None without one (``loss_scale`` then sets the noise level); ``n0`` the
    length of the robust hypothesis' t before the refinement; ``profile`` the
    statistic of :func:`scale_profile`, when already computed (by C);
    ``calibration_std`` as in :func:`ransac` (its effect enters ``rel_std``);
    ``rms`` the RMS residual of the inliers when the caller has it (``r`` may
    then be None). ``c_ids = (cam1, cam2, n_cameras, mask, stats)`` (the C
    search's camera ids, its inlier mask, bit 0, and the verdict's evidence
    it gathered, or None) switches the verdict's evidence and the travel
    direction to one C pass over all the rays (:func:`scale_verdict_stats`);
    ``zero_profile`` the statistic of :func:`scale_profile` at
    ``ZERO_FACTOR`` when already computed (by C). ``unconfirmed``: None, or
    why the search's consensus is not confirmed (a cap ended it at a
    confidence below :data:`CONFIRMED`): then no scale is reported (the
    verdict says why, ``t`` is the unit direction of travel).
    """
    rel_std = float("inf")
    given, profile = profile, float("nan")
    if fit is not None:
        out, used, scale_used, w_used = fit
        info["refinement"] = {k: out[k] for k in ("iterations", "converged") if k in out}
        # (the rays enter only the calibration part: no copy without one)
        rel_std, parts = total_scale_std(rays if calibration_std is None else rays.take(used),
                                         R, t, out, calibration_std, w_used, options.loss,
                                         scale_used)
        info.update(parts)
    info.update(inlier_ratio=float(_ratio(inl)), time_s=time.perf_counter() - t_start)
    if fit is not None and rel_std <= options.max_scale_rel_std:
        if given is not None and math.isfinite(given):
            profile = float(given)
        else:
            k = 1.0 + 3.0 * options.max_scale_rel_std
            profile = scale_profile(rays.take(used), R, t, out["final_cost"], out["sigma2"],
                                    (1.0 / k, k), options.loss, scale_used, w_used)
        info["scale_profile"] = profile
    noise_level = fit[2] if fit is not None else loss_scale
    direction = None
    if c_ids is not None:
        cam1, cam2, n_cameras, mask, stats = c_ids
        verdict, direction = scale_verdict_stats(rays, cam1, cam2, n_cameras, mask, R, t,
                                                 rel_std, options.max_scale_rel_std,
                                                 noise_level=noise_level, profile=profile,
                                                 prechecked=cam1.dtype == np.int32,
                                                 stats=stats)
    else:
        v_rays, v_inl = _verdict_sample(rays, inl, options.seed)
        verdict = scale_verdict(v_rays, v_inl, R, t, rel_std, options.max_scale_rel_std,
                                noise_level=noise_level, profile=profile)
    if unconfirmed is not None and not verdict.reason.startswith("no translation"):
        # (a static rig keeps its verdict: t = 0 whatever the consensus)
        verdict = replace(verdict, observable=False, reason=unconfirmed)
    info["translation_detected"] = not verdict.reason.startswith("no translation")
    # the metric estimate whatever the verdict (when the scale is unobservable
    # the refinement may have slid |t| far along its flat valley: a guess)
    info["t_metric"] = np.array(t)
    # t is the metric estimate unless the branches below find it undetermined
    determined = info["translation_detected"]
    if not info["translation_detected"]:
        # static rig or pure rotation: the verdict says t = 0 (as the search
        # that finds no motion at all does, _no_translation), not a unit
        # vector whose direction the data do not determine
        t = np.zeros(3)
    elif not verdict.observable:
        nt = math.hypot(*np.asarray(t, dtype=np.float64).tolist())
        # Slid out along the flat valley (|t| grew more than 10x: the cost
        # keeps falling towards |t| = infinity, the central-camera limit):
        # keep the robust hypothesis' length. A large drop is no such slide:
        # near the critical motion the 1-point scale search may propose a
        # huge |t|, which the refinement on all inliers brings back
        # (measured on the Ladybug head: 565 -> 1.06, 45 -> 0.97 for |t| = 1).
        slid = not nt <= 10.0 * n0
        if direction is None:
            direction = travel_direction(rays, inl, R, t)
        info["t_direction"] = direction
        # A refined t in the mirrored minimum (in_mirrored_minimum) is no
        # metric estimate either: it is treated as slid: the direction, the
        # hypothesis' length. (A t dominated by the rotation-induced shift
        # may point elsewhere, up to ~130 deg off on KITTI, and is left alone.)
        slid = slid or in_mirrored_minimum(direction, t)
        if slid:
            nt = n0
        info["t_slid"] = slid
        zero = float("nan")
        if fit is not None and not slid and scale_determined(rel_std):
            zero = zero_profile
            if not math.isfinite(zero):
                zero = scale_profile(rays.take(used), R, t, out["final_cost"], out["sigma2"],
                                     (ZERO_FACTOR,), options.loss, scale_used, w_used)
        if slid or unconfirmed is not None or not scale_determined(rel_std, zero_profile=zero):
            # the data define no scale: a unit direction (issue 18: never a
            # silent unit vector where a metric estimate exists, and never a
            # metric-looking one where none does)
            # (info['t_metric'] keeps the refined t, the least-squares guess,
            # unless it slid out: then the hypothesis' length along the travel)
            if slid:
                info["t_metric"] = nt * direction
            t = direction
            determined = False
    info["scale_determined"] = determined
    if rms is None:
        rms = float(np.sqrt(np.mean(r[inl] ** 2))) if inl.any() else float("nan")
    return RigMotion(np.asarray(R), np.asarray(t), verdict, f"ransac[{method}]", rms, inl, info)


#: the confidence (``info["confidence"]``: how likely the search drew a sample
#: of inliers of its consensus, csrc/robust.c search_confidence) below which
#: a search that its cap ended reports no scale: it is less likely than not
#: that the search drew a sample of inliers of the consensus it returns
#: (17-point RANSAC and the eigensolver sampler at their 1000-sample cap on
#: the Ladybug head, 30 % outliers, 30 problems each: right motions at
#: 0.90-0.92, partial fits 0.8-2.4 deg off with 9-24 % of the pairs at
#: 2e-4 or less, of which 3 had been called metric)
CONFIRMED = 0.5


#: intra-camera inliers the verdict's statistics (no-parallax fraction,
#: cheirality fraction) look at, at most (a uniform random sample beyond)
VERDICT_SAMPLE = 20000


def _verdict_sample(rays: RayPairs, inl: np.ndarray, seed: Optional[int]
                    ) -> tuple[RayPairs, np.ndarray]:
    """The rays and inlier mask :func:`scale_verdict` is run on.

    Up to :data:`VERDICT_SAMPLE` intra-camera inliers, all of them (the rays
    themselves, unchanged). Beyond, the verdict's O(N) numpy passes (a
    rotation fit, the cheirality test, ~1 us per inlier: 1.2 s of Python at
    1e6 inliers, issue 19) run on every cross-camera inlier, the first
    intra-camera inlier of every camera (so that the cameras with inliers,
    the critical angle and the cross-camera count are exactly those of all
    inliers) and a uniform random sample of VERDICT_SAMPLE intra-camera
    inliers: the two fractions it tests (no parallax: >= 90 % of the
    rotation residuals small; cheirality: >= 50 % in front) are then
    estimated with a binomial std below 0.4 %.
    """
    if rays.cam1 is None or rays.cam2 is None:
        return rays, inl
    idx = np.flatnonzero(inl)
    same = rays.cam1[idx] == rays.cam2[idx]
    intra = idx[same]
    if intra.size <= VERDICT_SAMPLE:
        return rays, inl
    cams = rays.cam1[intra]
    # the first of each camera: one pass per camera present (a sort of all
    # of them, np.unique, costs more at 1e6)
    first = [int(np.argmax(cams == k)) for k in np.flatnonzero(np.bincount(cams))]
    rng = np.random.default_rng(seed)
    pick = rng.choice(intra.size, VERDICT_SAMPLE, replace=False)
    keep = np.union1d(np.union1d(intra[pick], intra[first]), idx[~same])
    sub = rays.take(keep)
    return sub, np.ones(len(sub), bool)


def _camera_count(rays: RayPairs) -> tuple[np.ndarray, np.ndarray, int]:
    """``(cam1, cam2, number of cameras)`` for the C search of 5+1: the rays'
    ids, or without them one id per distinct origin (:func:`camera_ids`).
    That every camera id has one origin at both times (its central samples
    solve each camera about one centre) is checked by the search itself, in
    its pass over the input, and named by :func:`mcgeom._core.robust_rig_motion`
    (issue 19: the numpy check here cost 86 ms of a 0.98 s estimate on 1e6
    pairs)."""
    if rays.cam1 is None or rays.cam2 is None:
        cam1, cam2, centres = camera_ids(rays)
        return cam1, cam2, len(centres)
    cam1, cam2 = rays.cam1, rays.cam2
    return cam1, cam2, int(max(cam1.max(initial=-1), cam2.max(initial=-1))) + 1


def _sampler_ids(rays: RayPairs, method: str, tabled: bool
                 ) -> tuple[np.ndarray, np.ndarray, int]:
    """Camera ids and count for the C search of ``method``.

    5+1 needs the cameras (origins at their centres). The upright, 6-point
    and eigensolver samplers only use the ids to redraw samples from one centre (a
    central camera, no metric scale): rays whose origins are not camera
    centres (a generalized camera with a ray-dependent origin) are grouped
    by origin, folded into the C limit of 4096 ids (a fold may only make a
    degenerate sample reach the solver, which then finds nothing). With a
    camera table (``tabled``) the ids index it and must be the rig's.
    """
    try:
        cam1, cam2, centres = camera_ids(rays)
        if tabled or method == "five_plus_one" or len(centres) <= _MAX_CAMERAS:
            return cam1, cam2, len(centres)
    except ValueError:
        if tabled or method == "five_plus_one":
            raise
    allo = np.concatenate([rays.origins1, rays.origins2])
    _, inv = np.unique(allo, axis=0, return_inverse=True)
    inv = inv.ravel() % _MAX_CAMERAS
    n = len(rays)
    return inv[:n], inv[n:], int(inv.max()) + 1


#: camera ids the C entry point accepts (csrc/robust.c MAX_CAMERAS)
_MAX_CAMERAS = 4096


def _solver_keywords(method: str, solver_options: dict) -> dict:
    """The C search's keywords from ``solver_options``: the vertical of
    ``upright_four_point`` (checked, named); for ``six_point`` its
    ``solver``, "local" (the default: the local search, ~1 ms a sample, its
    rate of success measured by the search) or "homotopy" (the complete
    minimal solver, ~30 ms a sample), as the sampler name of
    :data:`mcgeom._core.SAMPLER_NAMES`; nothing for the others. An option
    the sampler does not take is a ValueError naming it."""
    opts = dict(solver_options)
    out = {}
    if method == "upright_four_point":
        out = {k: check_gravity(k, opts.pop(k, None)) for k in ("gravity1", "gravity2")}
    if method == "six_point" and "solver" in opts:
        solver = opts.pop("solver")
        if solver not in ("local", "homotopy"):
            raise ValueError(f"six_point's solver must be 'local' or 'homotopy', got "
                             f"{solver!r}")
        out = {"sampler": "six_point" if solver == "local" else "six_point_homotopy"}
    if opts:
        raise ValueError(f"solver_options {sorted(opts)} are not options of {method}'s "
                         f"minimal solver")
    return out


def _ransac_c(rays: RayPairs, focal: Optional[np.ndarray], options: RansacOptions,
              pixel_cameras: Optional[tuple[np.ndarray, np.ndarray]],
              t_start: float, calibration_std: Any = None, method: str = "five_plus_one",
              solver_options: Optional[dict] = None, from_rig: bool = False) -> RigMotion:
    """The methods of :data:`C_SAMPLERS`: the search and the final refinement
    in one C call (``_core.robust_rig_motion``, csrc/robust.c), the verdict here.
    ``from_rig``: the rays' ids are those of the rig of ``pixel_cameras`` and
    their origins its centres (:func:`ransac_prechecked`): not checked again."""
    solver_kw = _solver_keywords(method, solver_options or {})
    if from_rig:
        cam1, cam2, n_cameras = rays.cam1, rays.cam2, 0
    elif method == "five_plus_one":
        cam1, cam2, n_cameras = _camera_count(rays)
    else:
        cam1, cam2, n_cameras = _sampler_ids(rays, method, pixel_cameras is not None)
    cam_focal = cam_axes = None
    if pixel_cameras is not None:
        cam_focal, cam_axes = pixel_cameras
        if focal is None:
            raise ValueError("pixel_cameras needs focal (thresholds in pixels)")
        if len(cam_focal) < n_cameras:
            raise ValueError(f"pixel_cameras describes {len(cam_focal)} cameras, the rays "
                             f"use camera ids up to {n_cameras - 1}")
        n_cameras = len(cam_focal)
    ids32 = n_cameras <= _MAX_CAMERAS
    if ids32:
        # int32 once for both C calls (the search and the verdict's evidence);
        # ids are >= 0 and below n_cameras here, so nothing wraps. The rays
        # of a RayPairs are float64 C-contiguous (N, 3) and focal was checked
        # (ransac_prechecked, _focal_array): the wrappers need not check
        # their shapes and types again (prechecked)
        cam1, cam2 = cam1.astype(np.int32), cam2.astype(np.int32)
    intra = cam1 == cam2
    if method == "five_plus_one" and not np.bincount(cam1[intra], minlength=1).max(initial=0) >= 5:
        raise ValueError(f"too few correspondences: {method} needs 5 intra-camera "
                         f"correspondences in one camera ({_per_camera(rays)})")
    # the threshold as an angle (radians), as _Scorer's loss scale: threshold /
    # median(focal) can exceed the limit only if threshold > min(focal) (the
    # median is >= the minimum; the rounded quotient is monotone), so the
    # median (a partition of all N) is taken only then
    if focal is None:
        _check_threshold_angle(options.threshold, options.threshold, focal)
    elif options.threshold > MAX_THRESHOLD_RAD * float(np.minimum.reduce(focal)):
        _check_threshold_angle(options.threshold, options.threshold / float(np.median(focal)),
                               focal)
    seed = _c_seed(options)
    # (a caller's camera table is checked there)
    prechecked = ids32 and (focal is None or focal.flags.c_contiguous) and \
        (pixel_cameras is None or from_rig)

    def search(threshold: float, refine: bool, ended: Optional[dict] = None) -> Optional[dict]:
        return _c_search(rays, cam1, cam2, n_cameras, focal, cam_axes, cam_focal, options,
                         threshold, refine, method, seed, prechecked, solver_kw, ended)

    ended: dict = {}
    out = search(options.threshold, options.refine, ended)
    if out is not None and len(rays) > 6 and np.count_nonzero(out["inliers"]) <= 6:
        # only the sample itself within the threshold (a threshold below the
        # noise: every exact minimal sample fits itself): no consensus
        ended = {k: out[k] for k in ("iterations", "hypotheses", "stop", "sample_size")}
        out = None
    if out is None:
        # nothing explains 6 correspondences within the threshold: a probe at
        # the angle of a plain fit (_FITS_RAD) tells a too small threshold
        # (named by _threshold_too_small) from degenerate data
        wide = _FITS_RAD if focal is None else _FITS_RAD * float(np.median(focal))
        probe = search(wide, False) if options.threshold < wide else None
        scorer = _Scorer(rays, options.threshold, focal, options)
        if probe is not None:
            scorer.best = (probe["R"], probe["t"])
            scorer.n_hyp = int(probe["hypotheses"])
        return _nothing_found(rays, scorer, options, method, t_start, 6, "", ended)
    return _c_conclude(rays, out, focal, options, method, t_start, calibration_std, cam1, cam2,
                       n_cameras)


def ransac_rig_c(rays: RayPairs, method: str, options: RansacOptions, focal: np.ndarray,
                 pixel_cameras: tuple[np.ndarray, np.ndarray], calibration_std: Any,
                 solver_options: Optional[dict] = None) -> Optional[RigMotion]:
    """The ordinary case of :func:`ransac_prechecked` with a C sampler, in
    the fewest Python steps (issue 19: every step of a call that follows
    other work, e.g. a feature matcher, costs ~5x its warm time; this path
    measured 0.11 ms of Python per cold estimate where the general one took
    0.6 ms): one C call, then the verdict.

    Same preconditions as :func:`ransac_prechecked` (``pixel_cameras`` and
    ``focal`` given); ``method`` a name of :data:`C_SAMPLERS` (the upright
    one with its vertical in ``solver_options``, checked and named as by
    :func:`ransac`), or ``"auto"``: the C search picks as
    :func:`mcgeom.cv.choose_sampler` does (5+1 when a camera has 5
    intra-camera correspondences, else the 6-point solver).
    Returns the same RigMotion as :func:`ransac_prechecked`, or None where
    that function decides something this one does not (6 correspondences or
    fewer, a threshold above 1 rad, a search that found no consensus): the
    caller then runs it, whose checks and messages apply. Repeated
    correspondences are its DegenerateError, as there.
    """
    n = len(rays)
    if n <= 6 or options.strategy != "auto" or \
            options.threshold > MAX_THRESHOLD_RAD * float(np.minimum.reduce(focal)):
        return None
    solver_kw = _solver_keywords(method, solver_options or {})
    registry.check_distinct(rays, 6 if method == "auto" else C_SAMPLERS[method],
                            "five_plus_one" if method == "auto" else method)
    t_start = time.perf_counter()
    cam_focal, cam_axes = pixel_cameras
    n_cameras = len(cam_focal)
    # (ids of the rig's cameras, checked by its ray kernel: int32 for C)
    cam1, cam2 = rays.cam1.astype(np.int32), rays.cam2.astype(np.int32)
    out = _c_search(rays, cam1, cam2, n_cameras, focal, cam_axes, cam_focal, options,
                    options.threshold, options.refine, method, _c_seed(options), True, solver_kw)
    if out is None or out["n_inliers"] <= 6:
        return None
    return _c_conclude(rays, out, focal, options, out["sampler"], t_start, calibration_std,
                       cam1, cam2, n_cameras)


def _c_seed(options: RansacOptions) -> int:
    """The C search's seed: the options' one, else fresh entropy."""
    return options.seed if options.seed is not None else \
        int(np.random.SeedSequence().entropy % (1 << 63))


def _c_search(rays: RayPairs, cam1: np.ndarray, cam2: np.ndarray, n_cameras: int,
              focal: Optional[np.ndarray], cam_axes: Optional[np.ndarray],
              cam_focal: Optional[np.ndarray], options: RansacOptions, threshold: float,
              refine: bool, method: str, seed: int, prechecked: bool,
              solver_kw: dict, search_info: Optional[dict] = None) -> Optional[dict]:
    """One C search (``_core.robust_rig_motion``) with ``options`` at
    ``threshold``, the verdict's evidence gathered in the same call
    (``solver_kw`` from :func:`_solver_keywords`: the vertical, or the
    6-point sampler's solver); None when it found no motion
    (``search_info`` then says how the search ended)."""
    kw = dict(solver_kw)
    return _core.robust_rig_motion(
        rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, cam1, cam2, n_cameras,
        focal=focal, cam_axes=cam_axes, cam_focal=cam_focal, threshold=threshold,
        prob=options.prob, min_iterations=min(options.min_iters, options.max_iters),
        max_iterations=int(options.max_iters), max_seconds=options.max_seconds, seed=seed,
        lo_rounds=options.lo_max_rounds if options.local_optimization else 0,
        refine=refine, loss=options.loss, max_scale_rel_std=options.max_scale_rel_std,
        sampler=kw.pop("sampler", method), prechecked=prechecked,
        verdict_still_factor=NO_PARALLAX_FACTOR, search_info=search_info, **kw)


def _c_conclude(rays: RayPairs, out: dict, focal: Optional[np.ndarray], options: RansacOptions,
                method: str, t_start: float, calibration_std: Any, cam1: np.ndarray,
                cam2: np.ndarray, n_cameras: int) -> RigMotion:
    """The RigMotion of a C search's result ``out`` (``_core.robust_rig_motion``
    with ``verdict_still_factor`` :data:`NO_PARALLAX_FACTOR`, not None) on
    ``rays`` (camera ids ``cam1``/``cam2`` as passed to it): the verdict here."""
    R, t, inl = out["R"], out["t"], out["inliers"]
    info = {k: out[k] for k in ("iterations", "hypotheses", "local_optimizations", "score",
                                "stop")}
    info["c_seconds"] = out["seconds"]
    info["sampler"] = method
    info["sample_size"] = out["sample_size"]
    info["confidence"] = out["confidence"]
    if out["sampler"].startswith("six_point"):
        info["six_point_solver"] = "homotopy" if out["sampler"] == "six_point_homotopy" \
            else "local"
        info["found_rate"] = out["found_rate"]
    unconfirmed = _unconfirmed(out["stop"], out["iterations"], out["sample_size"],
                               out["confidence"])
    fit = None
    if out["refinement"] is not None:
        out["refinement"]["covariance"] = out["covariance"]   # (total_scale_std's)
        used = out["used"]
        w = out["weights"][used]
        # (the ufuncs' reduce: np.ptp's, ndarray.max's Python layers cost more
        # than their passes)
        fit = (out["refinement"], used, out["loss_scale"],
               None if focal is None or w.size == 0 or
               np.maximum.reduce(w) == np.minimum.reduce(w) else w)
    # the RMS residual of the inliers and the verdict's evidence come from C
    # (no Python pass over the rays: issue 19)
    return _conclude(rays, R, t, None, inl, fit, out["loss_scale"],
                     math.hypot(*out["t_hypothesis"].tolist()), options, method,
                     info, t_start,
                     out["scale_profile"], calibration_std, rms=float(out["inlier_rms"]),
                     c_ids=(cam1, cam2, n_cameras, out["mask"], out["verdict"]),
                     zero_profile=float(out["zero_profile"]), unconfirmed=unconfirmed)
