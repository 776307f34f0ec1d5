"""OpenCV-style façade: rig motion from pixel correspondences, like ``cv2.findEssentialMat``.

This module only converts OpenCV-style arguments and calls the library: the
rays come from :meth:`mcgeom.rig.Rig.ray_pairs_prechecked`, the pixel-noise
model from :mod:`mcgeom.pixel_noise`, the search from :func:`mcgeom.robust.ransac`
or the registered estimator.

``estimateRigMotion`` takes pixels of a calibrated rig (the cameras of
:class:`mcgeom.rig.Rig`), a ``prob``/``threshold`` (pixels)/``maxIters`` triple
and an optional input mask, and returns ``retval, R, t, mask`` in the
``cv2.recoverPose`` convention: ``X2 = R X1 + t`` maps rig coordinates at time 1
to time 2, ``t`` is a 3x1 column in metres (the unit of the rig extrinsics: the
maximum-likelihood metric estimate wherever the data define a scale; unit
length, with a ``ScaleNotObservableWarning``, when they do not), ``mask`` an N x 1 ``uint8`` array
with 1 for inliers, ``retval`` the number of inliers. :func:`estimate` runs the
same and returns the full :class:`mcgeom.RigMotion` (scale verdict, residuals,
diagnostics).

Method flags are module constants naming registered estimators; any registered
name may be passed as a string instead. Estimators that can drive RANSAC
(a minimal solver or a proposer) run robustly unless the ``*_DIRECT`` flag (or
``robust=False``) is used.
"""

from __future__ import annotations

import warnings
from typing import Any, Optional

import numpy as np

from . import registry
from . import robust as _robust   # (the name robust is estimate()'s flag)
from .errors import ScaleNotObservableWarning
from .observability import with_sampled_calibration
from .pixel_noise import camera_table, ray_pairs_per_radian, sampson_pixel_scale
from .rig import Rig
from .types import RigMotion
from .validation import integral_camera_ids

__all__ = [
    "RIG_5P1_RANSAC", "RIG_LINEAR17", "RIG_LINEAR17_RANSAC", "RIG_5P1_DIRECT",
    "RIG_UPRIGHT_RANSAC", "RIG_6PT_RANSAC", "estimateRigMotion", "estimate", "choose_sampler",
]

#: 5+1 method (thesis ch. 7) inside LO-RANSAC: the default (the generic 6-point
#: when no camera has 5 intra-camera correspondences, see :func:`choose_sampler`)
RIG_5P1_RANSAC = "five_plus_one"
#: linear 17-point generalized essential matrix (thesis ch. 8) on all correspondences
RIG_LINEAR17 = "linear17"
#: linear 17-point inside LO-RANSAC (17-point samples spread across cameras)
RIG_LINEAR17_RANSAC = "ransac:linear17"
#: 5+1 on all correspondences (no outlier rejection)
RIG_5P1_DIRECT = "direct:five_plus_one"
#: upright 4-point with a known vertical inside LO-RANSAC (chosen by itself when
#: ``gravity1``/``gravity2`` are passed with the default method)
RIG_UPRIGHT_RANSAC = "upright_four_point"
#: generic minimal 6-point inside LO-RANSAC (the C search, its samples solved by
#: mcg_sixpt_local and every 256th by mcg_sixpt; chosen by itself when no camera
#: has the 5 intra-camera correspondences of a 5+1 sample)
RIG_6PT_RANSAC = "ransac:six_point"


def choose_sampler(cam1: np.ndarray, cam2: np.ndarray) -> str:
    """The minimal solver (``"five_plus_one"`` or ``"six_point"``, the names of
    :data:`mcgeom.robust.C_SAMPLERS`) of the default search for correspondences of
    cameras ``cam1[k]`` -> ``cam2[k]`` (integer ids): 5+1 (thesis ch. 7) when
    some camera has at least 5 intra-camera correspondences (its 5-point
    essential matrix), else the generic 6-point solver, which samples any
    cameras (rigs with many cameras and few matches each, or mostly
    cross-camera matches). Fewer than 6 correspondences sample neither: 5+1
    then (its checks name what is missing, as before the choice existed).
    The vertical prior (``gravity1``/``gravity2``) selects the upright
    4-point solver before this is asked."""
    intra = np.asarray(cam1) == np.asarray(cam2)
    counts = np.bincount(np.asarray(cam1)[intra], minlength=1)
    if intra.size < 6 or counts.max(initial=0) >= 5:
        return RIG_5P1_RANSAC
    return "six_point"


def _gravity_method(method: str, gravity1: Any, gravity2: Any, options: dict) -> str:
    """The method to run when a vertical prior may be given: the default 5+1
    becomes the upright sampler (3+1 samples when a camera has 3
    intra-camera correspondences, else 4 of any cameras, instead of 5+1:
    fewer iterations at a given outlier rate); the prior goes into
    ``options``. ValueError when
    only one of the two is given, or the named method does not take it."""
    if gravity1 is None and gravity2 is None:
        return method
    if gravity1 is None or gravity2 is None:
        missing = "gravity1" if gravity1 is None else "gravity2"
        raise ValueError(f"{missing} is missing: a vertical prior needs the gravity direction "
                         "in the rig frame at both times (gravity1=, gravity2=)")
    if not isinstance(method, str):
        return method           # _resolve names the problem
    if method == RIG_5P1_RANSAC:
        method = RIG_UPRIGHT_RANSAC
    base = method.split(":", 1)[1] if method.startswith(("ransac:", "direct:")) else method
    if "gravity1" not in registry.get(base).options:
        raise ValueError(f"gravity1/gravity2 are given but method {method!r} does not use a "
                         f"vertical prior; use {RIG_UPRIGHT_RANSAC!r} (or the default method)")
    options["gravity1"], options["gravity2"] = gravity1, gravity2
    return method


def _points(name: str, p: Any) -> np.ndarray:
    # (a float64 C-contiguous (N, 2) array is already what _pixel_array makes)
    a = p if (type(p) is np.ndarray and p.dtype == np.float64 and p.ndim == 2
              and p.shape[1] == 2 and p.flags.c_contiguous) else _pixel_array(name, p)
    if not np.isfinite(a).all():
        raise ValueError(f"{name} contains NaN or inf")
    return a


def _pixel_array(name: str, p: Any) -> np.ndarray:
    """``p`` as a float64 C-contiguous (N, 2) array (OpenCV's (N, 1, 2) and an
    empty list accepted); ValueError naming ``name`` otherwise."""
    try:
        a = np.asarray(p)
    except ValueError as exc:   # ragged nested lists
        raise ValueError(f"{name} must be an (N, 2) array of pixels ({exc})") from None
    if a.dtype.kind not in "fiu":
        raise ValueError(f"{name} must be numeric, got dtype {a.dtype}")
    if a.ndim == 3 and a.shape[1:] == (1, 2):      # OpenCV's (N, 1, 2)
        a = a.reshape(-1, 2)
    if a.size == 0 and a.ndim <= 2:                # [] or np.float32([]): no matches
        a = a.reshape(0, 2)
    if a.ndim != 2 or a.shape[1] != 2:
        raise ValueError(f"{name} must have shape (N, 2) or (N, 1, 2), got {a.shape}")
    return np.ascontiguousarray(a, dtype=np.float64)


def _ids(name: str, ids: Any, n: int, rig: Rig) -> np.ndarray:
    a = np.asarray(ids).reshape(-1) if np.ndim(ids) else np.full(n, ids)
    if a.shape[0] != n:
        raise ValueError(f"{name} has {a.shape[0]} entries, expected {n} (one per point)")
    if n == 0:                                     # [] is float64 for numpy
        return np.zeros(0, np.int64)
    a = integral_camera_ids(name, a)   # the one rule of Rig.ray_pairs and RayPairs
    m = len(rig.cameras)
    # (two reductions; the mask of the offenders only to name the first)
    if a.min() < 0 or a.max() >= m:
        bad = (a < 0) | (a >= m)
        raise ValueError(f"{name} holds camera id {int(a[bad][0])}, but the rig has cameras "
                         f"0..{m - 1}")
    # (a copy: the rays keep the ids, not the caller's array)
    return a.astype(np.int64)


def _resolve(method: str, robust_flag: Optional[bool]) -> tuple[str, bool]:
    if not isinstance(method, str):
        raise ValueError(f"method must be a flag of mcgeom.cv or a registered estimator name, "
                         f"got {method!r}")
    if method.startswith("ransac:"):
        return method[7:], True
    if method.startswith("direct:"):
        return method[7:], False
    info = registry.get(method)
    can = info.minimal_solver is not None or info.proposer is not None
    if robust_flag is None:
        return method, can and method != RIG_LINEAR17
    return method, bool(robust_flag)


#: the RANSAC-only options of :func:`estimate` and their defaults
_RANSAC_DEFAULTS = {"prob": 0.999, "threshold": 1.0, "maxIters": 1000, "seed": 0}


def _no_ransac_options(name: str, **given: Any) -> None:
    """ValueError naming a RANSAC-only option given a non-default value for a method
    that does not run RANSAC (it would be ignored silently)."""
    for key, value in given.items():
        default = _RANSAC_DEFAULTS[key]
        same = value is default or (type(value) in (int, float) and not isinstance(value, bool)
                                    and value == default)
        if not same:
            raise ValueError(f"{key}={value!r} is a RANSAC option, but method {name!r} runs "
                             f"without RANSAC (direct) and would ignore it: drop {key}, or "
                             f"pass method='ransac:{name}' where {name} can drive RANSAC")


def estimate(points1: Any, points2: Any, cameraIds1: Any, cameraIds2: Any, rig: Rig,
             method: str = RIG_5P1_RANSAC, prob: float = 0.999, threshold: float = 1.0,
             maxIters: int = 1000, mask: Any = None, seed: Optional[int] = 0,
             robust: Optional[bool] = None, calibration_std: Any = None,
             gravity1: Any = None, gravity2: Any = None,
             calibration_check: str = "first_order",
             **options: Any) -> RigMotion:
    """Full :class:`RigMotion` rig2_from_rig1 from pixel correspondences of ``rig``.

    ``points1[k]`` (pixels, camera ``cameraIds1[k]``, time 1) and ``points2[k]``
    (camera ``cameraIds2[k]``, time 2; ``None`` = the same cameras) see the same
    scene point. ``threshold`` is in pixels (Sampson angular error times the
    mean focal length of the two cameras), ``prob`` the RANSAC confidence,
    ``maxIters`` its iteration cap, ``mask`` (N, N x 1, nonzero = use) selects
    the correspondences to consider. The returned ``inliers`` mask has N entries
    (False for masked-out correspondences). ``prob``, ``threshold``, ``maxIters``
    and ``seed`` are RANSAC options: with a method that runs without RANSAC
    (``direct:...``, ``robust=False``, ``RIG_LINEAR17``, estimators without a
    minimal solver) a non-default value is a ValueError naming the option and
    the method, not ignored.

    ``calibration_std`` overrides the rig's extrinsic calibration error
    (:attr:`mcgeom.rig.Rig.extrinsic_std`: from the rig file, else
    :data:`mcgeom.rig.DEFAULT_EXTRINSIC_STD`): one pair (position std in
    metres, rotation std in radians) for every camera, or one per camera.
    ``scale.rel_std`` (and ``info['covariance']``) include its effect on the
    metric scale, and the verdict is decided on that total.
    ``calibration_check``: ``"first_order"`` (default) propagates it to first
    order; ``"sampled"`` also checks a metric result against rigs drawn with
    it (:func:`mcgeom.observability.with_sampled_calibration`: 128 refits,
    0.05-0.1 s; near the critical motion the first-order figure can be 3x
    too small, and a result it leaves above the limit is not metric).

    ``gravity1``/``gravity2`` (3-vectors, e.g. an IMU's gravity in the rig frame
    at time 1 and at time 2) are a vertical prior: with the default method the
    search then runs the upright 4-point solver (``RIG_UPRIGHT_RANSAC``); the
    final refinement frees all six degrees of freedom. Without it the default
    method runs 5+1 when some camera has 5 intra-camera correspondences, else
    the generic 6-point solver (:func:`choose_sampler`; ``'ransac:five_plus_one'``
    forces 5+1). ``info["sampler"]`` names the minimal solver the search used.
    """
    if not isinstance(rig, Rig):
        raise TypeError(f"rig must be an mcgeom.rig.Rig, got {type(rig).__name__}")
    if calibration_check not in CALIBRATION_CHECKS:
        raise ValueError(f"calibration_check must be one of {CALIBRATION_CHECKS}, got "
                         f"{calibration_check!r}")
    if calibration_check == "sampled":
        m = estimate(points1, points2, cameraIds1, cameraIds2, rig, method, prob, threshold,
                     maxIters, mask, seed, robust, calibration_std, gravity1, gravity2,
                     **options)
        return _sampled_check(m, points1, points2, cameraIds1, cameraIds2, rig, threshold,
                              calibration_std,
                              float(options.get("max_scale_rel_std",
                                                _robust.RansacOptions.max_scale_rel_std)))
    fast = _ONE_CALL.get(method) if type(method) is str else None
    if (fast is not None and mask is None and robust is None and not options
            and calibration_std is None and (gravity1 is None) == (gravity2 is None)
            and (gravity1 is None or fast == "auto")):
        m = _estimate_pinhole(points1, points2, cameraIds1, cameraIds2, rig, threshold, prob,
                              maxIters, seed, gravity1, gravity2, fast)
        if m is not None:
            return m
    p1, p2 = _points("points1", points1), _points("points2", points2)
    n = p1.shape[0]
    if p2.shape[0] != n:
        raise ValueError(f"points2 has {p2.shape[0]} points but points1 has {n}")
    ids1 = _ids("cameraIds1", cameraIds1, n, rig)
    ids2 = ids1 if cameraIds2 is None else _ids("cameraIds2", cameraIds2, n, rig)
    use = None     # (no mask: every correspondence)
    if mask is not None:
        m = np.asarray(mask).reshape(-1)
        if m.shape[0] != n:
            raise ValueError(f"mask has {m.shape[0]} entries, expected {n}")
        if m.dtype.kind not in "biuf" or (m.dtype.kind == "f" and not np.isfinite(m).all()):
            raise ValueError(f"mask must hold finite numbers or booleans (nonzero = use), "
                             f"got dtype {m.dtype}" + (" with NaN or inf" if m.dtype.kind == "f"
                                                       else ""))
        use = m != 0
    method = _gravity_method(method, gravity1, gravity2, options)
    name, run_robust = _resolve(method, robust)
    if not run_robust:
        _no_ransac_options(name, prob=prob, threshold=threshold, maxIters=maxIters, seed=seed)
    cal = _extrinsic_std(rig, calibration_std)
    # p1, p2, ids1, ids2 are checked above (finite float64 pixels, int64 ids of
    # the rig's cameras): the rig need not check them again
    # the rays and their pixels per radian (the pixel-noise model of the
    # rig), in one C pass for a pinhole rig (issue 19)
    rays_all, focal_all = ray_pairs_per_radian(rig, p1, p2, ids1, ids2)
    # without a mask every correspondence is used: no copy of the rays
    keep = None if use is None or use.all() else np.flatnonzero(use)
    rays = rays_all if keep is None else rays_all.take(keep)
    if run_robust and method == RIG_5P1_RANSAC:
        name = choose_sampler(rays.cam1, rays.cam2)   # (the used correspondences')
    if run_robust:
        # thresholds in pixels: the pixel-noise model of the rig converts them
        # the vertical prior is for the minimal solver (the final refinement is free)
        prior = {k: options.pop(k) for k in ("gravity1", "gravity2") if k in options}
        # (as robust.ransac: an ``options=`` RansacOptions replaces the
        # others; threshold None is 1 px)
        thr = 1.0 if threshold is None else threshold
        opts = options.pop("options", None) or (
            _robust.ransac_options(thr, prob, maxIters, seed) if not options else
            _robust.RansacOptions(threshold=thr, prob=prob, max_iters=maxIters, seed=seed,
                                  **options))
        # the rays, pixel-noise tables and calibration come from the rig and
        # the checks above: the search need not check them again (issue 19)
        # (pixels per radian are per pair: those of the kept pairs are theirs)
        focal = focal_all if keep is None else focal_all[keep]
        # an exactly known calibration (every std 0) adds nothing to rel_std:
        # None skips gathering the refinement's rays for its propagation
        m = _robust.ransac_prechecked(rays, name, opts, focal,
                                      sampson_pixel_scale(rig), cal if cal.any() else None,
                                      camera_table(rig), prior or None)
        m.info.setdefault("sampler", name)
        if keep is None:
            inl = np.asarray(m.inliers, bool).copy()
        else:
            inl = np.zeros(n, bool)
            inl[keep] = m.inliers
    else:
        if "calibration_std" in registry.get(name).options:
            options = {"calibration_std": cal, **options}
        m = registry.get(name)(rays, **options)
        inl = np.ones(n, bool) if use is None else use.copy()
    return RigMotion(m.R, m.t, m.scale, m.method, m.residual_rms, inl, m.info)


def _extrinsic_std(rig: Rig, calibration_std: Any) -> np.ndarray:
    """The (M, 2) extrinsic stds (metres, radians) :func:`estimate` uses: the
    rig's, or ``calibration_std`` when given (checked by :class:`Rig`, whose
    error names the option)."""
    return rig.extrinsic_std if calibration_std is None else \
        Rig(rig.cameras, calibration_std).extrinsic_std


#: how :func:`estimate` checks the calibration part of a metric result's std
CALIBRATION_CHECKS = ("first_order", "sampled")


def _sampled_check(m: RigMotion, points1: Any, points2: Any, cameraIds1: Any, cameraIds2: Any,
                   rig: Rig, threshold: Optional[float], calibration_std: Any,
                   max_rel_std: float) -> RigMotion:
    """``m`` (:func:`estimate`'s result on these arguments, which it checked)
    with the calibration part of its std checked by drawing rigs
    (:func:`mcgeom.observability.with_sampled_calibration`, limit
    ``max_rel_std``): the rays of the correspondences, each weighted by its
    pixels per radian squared over their inliers' median, with the Cauchy
    loss at ``threshold`` pixels (1 if None) where a robust search made
    ``m`` (its final refinement's), least squares otherwise."""
    cal = _extrinsic_std(rig, calibration_std)
    if not m.scale.observable or not np.any(cal > 0) or not np.any(m.t != 0):
        return m
    p1, p2 = _points("points1", points1), _points("points2", points2)
    ids1 = _ids("cameraIds1", cameraIds1, p1.shape[0], rig)
    ids2 = ids1 if cameraIds2 is None else _ids("cameraIds2", cameraIds2, p1.shape[0], rig)
    rays, focal = ray_pairs_per_radian(rig, p1, p2, ids1, ids2)
    used = np.asarray(m.inliers, bool)
    med = float(np.median(focal[used])) if used.any() else float(np.median(focal))
    searched = "sampler" in m.info    # (the robust runs name their minimal solver)
    return with_sampled_calibration(m, rays, cal, max_rel_std, weights=(focal / med) ** 2,
                                    loss="cauchy" if searched else "none",
                                    loss_scale=(1.0 if threshold is None else threshold) / med)


#: the methods :func:`estimate` runs in one C call from the pixels (for its
#: common input), with the C search's sampler: the default method's is picked
#: by the search as :func:`choose_sampler` picks it (the upright one with a
#: vertical prior); ``ransac:five_plus_one`` forces 5+1
_ONE_CALL = {RIG_5P1_RANSAC: "auto", "ransac:five_plus_one": "five_plus_one"}


def _estimate_pinhole(points1: Any, points2: Any, cameraIds1: Any, cameraIds2: Any, rig: Rig,
                      threshold: Any, prob: Any, maxIters: Any, seed: Any,
                      gravity1: Any = None, gravity2: Any = None,
                      sampler: str = "auto") -> Optional[RigMotion]:
    """:func:`estimate` of a method of :data:`_ONE_CALL` (``sampler`` its C
    search's) without a mask, options or calibration override (a vertical
    prior or none) for the common input -- a rig of
    undistorted pinholes, float64 C-contiguous (N, 2) pixels and int64 (N,)
    camera ids --
    in the fewest Python steps (issue 19: a call after other work pays ~5x
    the warm cost of each step): one C call from the pixels to the verdict
    (:func:`mcgeom.robust.estimate_pinhole_c`), whose kernel checks the
    pixels and ids itself. None for any other input
    or whatever those decline (a refused pixel or id, too few or repeated
    correspondences, no consensus ...): the general path of :func:`estimate`
    then runs, whose checks name what is wrong. The same RigMotion as that
    path."""
    ids2 = cameraIds1 if cameraIds2 is None else cameraIds2
    if not (_plain(points1, np.float64, 2) and _plain(points2, np.float64, 2)):
        return None
    n = points1.shape[0]
    if not (points2.shape[0] == n and _plain(cameraIds1, np.int64, 1) and
            _plain(ids2, np.int64, 1) and cameraIds1.shape[0] == n and ids2.shape[0] == n):
        return None
    opts = _robust.ransac_options(1.0 if threshold is None else threshold, prob, maxIters, seed)
    tables = rig.pinhole_tables
    if tables is None:
        return None
    # pixels in, the verdict out, in one C call (the kernel checks the pixels
    # and the ids against the rig). The sampler: choose_sampler's, picked by
    # the C search; with a vertical prior the upright 4-point one, as
    # _gravity_method picks
    return _robust.estimate_pinhole_c(
        tables, points1, points2, cameraIds1, ids2, opts, rig.calibration_error,
        None if gravity1 is None else {"gravity1": gravity1, "gravity2": gravity2}, sampler)


def _plain(a: Any, dtype: type, ndim: int) -> bool:
    """Is ``a`` a C-contiguous ndarray of ``dtype`` with ``ndim`` dimensions
    (the last of size 2 when ``ndim`` is 2)?"""
    return (type(a) is np.ndarray and a.dtype == dtype and a.ndim == ndim
            and (ndim == 1 or a.shape[1] == 2) and a.flags.c_contiguous)


def estimateRigMotion(points1: Any, points2: Any, cameraIds1: Any, cameraIds2: Any, rig: Rig,
                      method: str = RIG_5P1_RANSAC, prob: float = 0.999,
                      threshold: float = 1.0, maxIters: int = 1000,
                      mask: Any = None, gravity1: Any = None, gravity2: Any = None
                      ) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
    """OpenCV-style rig motion: ``retval, R, t, mask`` (see the module docstring).

    Same arguments as :func:`estimate`. ``R`` (3x3) and ``t`` (3x1, metres) map
    rig coordinates at time 1 to time 2 (``X2 = R X1 + t``, as
    ``cv2.recoverPose``); ``mask`` is N x 1 ``uint8`` (1 = inlier); ``retval``
    the number of inliers.

    ``t`` is in metres whenever the data define a metric scale: its
    maximum-likelihood estimate. When the verdict of :func:`estimate` says
    the scale is not observable, a :class:`mcgeom.ScaleNotObservableWarning`
    is emitted: either ``t`` has unit norm (the data do not determine the
    scale at all: exactly critical motion, e.g. driving straight with
    intra-camera matches only, or one camera) or it is the metric estimate
    with a relative standard deviation above the limit (the message gives
    it). ``t = 0`` (no warning) when no translation was detected. Call
    :func:`estimate` for the full verdict.
    """
    m = estimate(points1, points2, cameraIds1, cameraIds2, rig, method=method, prob=prob,
                 threshold=threshold, maxIters=maxIters, mask=mask, gravity1=gravity1,
                 gravity2=gravity2)
    if not m.scale.observable and np.any(m.t != 0):
        if m.info.get("scale_determined", False):
            what = (f"t is the maximum-likelihood metric estimate, but its relative standard "
                    f"deviation is {m.scale.rel_std:.3g}")
        else:
            what = "t has unit norm: only its direction is determined"
        warnings.warn(f"estimateRigMotion: the metric scale is not observable ({what}); "
                      f"{m.scale.reason}", ScaleNotObservableWarning, stacklevel=2)
    out_mask = m.inliers.astype(np.uint8).reshape(-1, 1)
    return int(out_mask.sum()), np.array(m.R), np.array(m.t).reshape(3, 1), out_mask
