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

import time
from typing import Any, Optional, Union

import numpy as np

from .. import registry
from ..estimators.five_plus_one import minimal_answer
from ..types import MotionFocal, RayPairs, RigMotion
from ._c_search import estimate_pinhole_c, ransac_c  # noqa: F401 (mcgeom.cv's)
from ._no_motion import check_threshold_angle, nothing_found
from ._options import C_SAMPLERS, RansacOptions, focal_array, ransac_options
from ._python_search import check_solver_options, finish, run_minimal, run_proposer
from ._scoring import (WIDE, Scorer, adaptive_iterations,  # noqa: F401 (WIDE re-exported)
                       residuals, sample_across_cameras)
from ._verdict import CONFIRMED, search_confidence  # noqa: F401 (re-exported)


__all__ = ["RansacOptions", "ransac_options", "ransac", "residuals", "adaptive_iterations",
           "sample_across_cameras", "C_SAMPLERS"]

# The parts, one concern per module (all private; the names above, and those
# that mcgeom.cv and the tests reach as mcgeom.robust.<name>, are re-exported
# here): _options (RansacOptions and its checks), _scoring (residuals, MSAC,
# the samples, the Python search's scorer and local optimisation),
# _python_search (the LO-RANSAC loop over a plugin, its final refinement),
# _c_search (the search in one C call), _no_motion (what is said when no
# motion is found), _verdict (the scale verdict and the returned RigMotion).


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
    refinement (see :meth:`Scorer.scaling_at`). ``calibration_std`` is the
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
    f = focal if from_rig else focal_array(focal, n)
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
        return ransac_c(rays, f, options, pixel_cameras, t_start, calibration_std, method,
                        solver_options or {}, from_rig and pixel_cameras is not None)
    rng = np.random.default_rng(options.seed)
    scorer = Scorer(rays, options.threshold, f, options, motion_focal)
    check_threshold_angle(options.threshold, scorer.loss_scale, f)

    use_proposer = info_est.proposer is not None and options.strategy in ("auto", "proposer")
    if options.strategy == "proposer" and info_est.proposer is None:
        raise ValueError(f"estimator {method!r} has no proposer")
    if not use_proposer and info_est.minimal_solver is None:
        raise ValueError(f"estimator {method!r} has no minimal solver: it cannot drive RANSAC")
    if solver_options and info_est.minimal_solver is not None:
        check_solver_options(info_est.minimal_solver, method, solver_options)
    iterations = 0
    if use_proposer:
        iterations = run_proposer(info_est, rays, scorer, options, rng)
        # nothing proposed (e.g. no camera with enough correspondences for the
        # proposer's own search): fall back to minimal samples where possible
        use_proposer = scorer.best is not None or info_est.minimal_solver is None
    samples = 0   # minimal samples drawn (the proposer's motions are no samples)
    if not use_proposer:
        samples = run_minimal(info_est, rays, scorer, options, rng, solver_options or {})
        iterations += samples
    ended = {"iterations": iterations, "hypotheses": scorer.n_hyp,
             "stop": "max_iterations" if iterations >= options.max_iters else "confidence",
             "sample_size": info_est.min_sample}
    if scorer.best is None or scorer.best_inliers.sum() < max(6, info_est.min_sample):
        return nothing_found(rays, scorer, options, method, t_start, max(6, info_est.min_sample),
                             f" ({scorer.n_hyp} hypotheses from {iterations} samples)", ended)
    return finish(rays, scorer, options, method, iterations, t_start, calibration_std,
                  dict(ended, iterations=samples) if samples else None)
