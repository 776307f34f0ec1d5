"""The robust search in one C call (``mcg_robust_rig_motion``, csrc/robust.c)
for the estimators of :data:`C_SAMPLERS`, its inputs and its result."""

from __future__ import annotations

import math
import time
from typing import Any, Optional

import numpy as np

from .. import _core
from ..estimators._common import camera_ids
# the vertical's checks (the messages name gravity1/gravity2) of the upright solver
from ..estimators.upright_four_point import check_gravity
from ..observability import NO_PARALLAX_FACTOR
from ..types import RayPairs, RigMotion
from ._no_motion import (MAX_THRESHOLD_RAD, FITS_RAD, check_threshold_angle, nothing_found,
                         per_camera_counts)
from ._options import RansacOptions
from ._scoring import Scorer
from ._verdict import C_WORDED, conclude, conclude_c, one_pair_checked, unconfirmed_reason


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


def ransac_c(rays: RayPairs, focal: Optional[np.ndarray], options: RansacOptions,
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
        # (ransac_prechecked, focal_array): the wrappers need not check
        # their shapes and types again (prechecked)
        cam1, cam2 = cam1.astype(np.int32), cam2.astype(np.int32)
    intra = cam1 == cam2
    if method == "five_plus_one" and not np.bincount(cam1[intra], minlength=1).max(initial=0) >= 5:
        raise ValueError(f"too few correspondences: {method} needs 5 intra-camera "
                         f"correspondences in one camera ({per_camera_counts(rays)})")
    # the threshold as an angle (radians), as Scorer's loss scale: threshold /
    # median(focal) can exceed the limit only if threshold > min(focal) (the
    # median is >= the minimum; the rounded quotient is monotone), so the
    # median (a partition of all N) is taken only then
    if focal is None:
        check_threshold_angle(options.threshold, options.threshold, focal)
    elif options.threshold > MAX_THRESHOLD_RAD * float(np.minimum.reduce(focal)):
        check_threshold_angle(options.threshold, options.threshold / float(np.median(focal)),
                              focal)
    seed = _c_seed(options)
    # (a caller's camera table is checked there)
    prechecked = ids32 and (focal is None or focal.flags.c_contiguous) and \
        (pixel_cameras is None or from_rig)

    ext = _extrinsic_table(calibration_std, n_cameras)

    def search(threshold: float, refine: bool, ended: Optional[dict] = None) -> Optional[dict]:
        return _c_search(rays, cam1, cam2, n_cameras, focal, cam_axes, cam_focal, options,
                         threshold, refine, method, seed, prechecked, solver_kw, ended, ext)

    ended: dict = {}
    out = search(options.threshold, options.refine, ended)
    if out is not None and len(rays) > 6 and np.count_nonzero(out["inliers"]) <= 6:
        # only the sample itself within the threshold (a threshold below the
        # noise: every exact minimal sample fits itself): no consensus
        ended = {k: out[k] for k in ("iterations", "hypotheses", "stop", "sample_size")}
        out = None
    if out is None:
        # nothing explains 6 correspondences within the threshold: a probe at
        # the angle of a plain fit (FITS_RAD) tells a too small threshold
        # (named by _threshold_too_small) from degenerate data
        wide = FITS_RAD if focal is None else FITS_RAD * float(np.median(focal))
        probe = search(wide, False) if options.threshold < wide else None
        scorer = Scorer(rays, options.threshold, focal, options)
        if probe is not None:
            scorer.best = (probe["R"], probe["t"])
            scorer.n_hyp = int(probe["hypotheses"])
        return nothing_found(rays, scorer, options, method, t_start, 6, "", ended)
    return _c_conclude(rays, out, focal, options, method, t_start, calibration_std, cam1, cam2,
                       n_cameras)


def _search_info(res: Any, method: str) -> dict:
    """``info``'s entries of the search (``res``: the ``mcg_robust_result *``
    of the C search, ``method`` the sampler it used)."""
    sampler = _core.SAMPLER_OF[res.sampler]
    info = {"iterations": res.iterations, "hypotheses": res.hypotheses,
            "local_optimizations": res.local_optimizations, "score": res.score,
            "stop": _core.ROBUST_STOP_NAMES.get(res.stop, "unknown"), "c_seconds": res.seconds,
            "c_stage_seconds": _core.robust_stage_seconds(res),
            "sampler": method, "sample_size": res.sample_size, "confidence": res.confidence}
    if sampler.startswith("six_point"):
        info["six_point_solver"] = "homotopy" if sampler == "six_point_homotopy" else "local"
        info["found_rate"] = res.found_rate
    return info


def estimate_pinhole_c(tables: tuple, px1: np.ndarray, px2: np.ndarray, ids1: np.ndarray,
                       ids2: np.ndarray, options: RansacOptions,
                       calibration_std: Optional[np.ndarray],
                       gravity: Optional[dict] = None,
                       sampler: str = "auto") -> Optional[RigMotion]:
    """The robust estimate of :func:`mcgeom.cv.estimate` from the pixels of a
    rig of undistorted pinholes in one C call (``_core.robust_pinhole_raw``:
    the rays, the search, the final refinement and the scale verdict), the
    verdict worded here: :func:`ransac_prechecked`'s RigMotion on the
    pixels' rays for the sampler of :func:`mcgeom.cv.choose_sampler` (picked
    by the C search; ``sampler`` "auto") or five_plus_one (``sampler``
    "five_plus_one") -- or, with ``gravity`` (``{"gravity1": g1, "gravity2":
    g2}``, the vertical in rig frames 1 and 2, checked and named as by
    :func:`ransac`), "upright_four_point" -- without its Python steps (issue
    19: every step of a call that follows other work, e.g. a feature
    matcher, costs ~5x its warm time). ``tables`` the rig's
    :attr:`~mcgeom.rig.Rig.pinhole_tables`, ``calibration_std`` its
    :attr:`~mcgeom.rig.Rig.calibration_error`; pixels (N, 2) float64 and
    ids (N,) int64, C-contiguous (their values are the kernel's to check).
    None where the kernel refuses the input or decides nothing (a bad pixel
    or id, 6 correspondences or fewer, fewer than 6 distinct ones, no
    consensus, a threshold above 1 rad at some pair): the caller's general
    path then decides, and names what is wrong."""
    n = px1.shape[0]
    if n <= 6 or options.strategy != "auto":
        return None
    vertical = None
    if gravity is not None:
        sampler = "upright_four_point"
        kw = _solver_keywords(sampler, gravity)
        vertical = (kw["gravity1"], kw["gravity2"])
    t_start = time.perf_counter()
    intr, rot, centres, focal = tables
    got = _core.robust_pinhole_raw(
        intr, rot, centres, focal, ids1, ids2, px1, px2,
        (options.threshold, options.prob, min(options.min_iters, options.max_iters),
         int(options.max_iters), options.max_seconds,
         options.lo_max_rounds if options.local_optimization else 0, options.refine,
         options.loss, options.max_scale_rel_std, sampler, NO_PARALLAX_FACTOR),
        _c_seed(options), calibration_std, vertical)
    if got is None:
        return None
    st, res, buf, mask = got
    w = buf[n:]     # (the kernel's workspace: rays, pixels per radian, ids)
    if st != _core.STATUS_OK or res.n_inliers <= 6:
        return None
    # a threshold above MAX_THRESHOLD_RAD at some pair (ransac_c's test):
    # each pair's pixels per radian is at least its cameras' smaller focal
    # length (csrc/pixel_rays.c: a bearing's variance is at most 1 / f^2),
    # so the pairs are looked at only when the rig's smallest focal allows it
    if options.threshold > MAX_THRESHOLD_RAD * (1.0 - 1e-9) * float(
            np.minimum.reduce(focal)) and options.threshold > MAX_THRESHOLD_RAD * float(
            np.minimum.reduce(w[12 * n:13 * n])):
        return None
    method = _core.SAMPLER_OF[res.sampler]
    info = _search_info(res, method)
    unconfirmed = unconfirmed_reason(info["stop"], res.iterations, res.sample_size,
                                     res.confidence)
    inl = (mask & 1).view(bool)
    # the pixels' rays (views of the kernel's workspace)
    rays = RayPairs.prechecked(*(w[3 * n * b:3 * n * (b + 1)].reshape(n, 3) for b in range(4)),
                               ids1, ids2)
    if res.have_scale and res.scale.reason in C_WORDED:
        return _checked(conclude_c(res, _core.robust_struct(res), inl, options, method, info,
                                   t_start, unconfirmed), res, rays, buf[:n], options, method)
    # a verdict the numpy layer decides (static, undecided): the dict of the
    # general conclusion, from the same call
    ids32 = w[13 * n:].view(np.int32)
    out = _core._robust_result(res, mask, buf[:n])
    out["extrinsic_std_given"] = calibration_std is not None
    return _c_conclude(rays, out, w[12 * n:13 * n], options, method, t_start, calibration_std,
                       ids32[:n], ids32[n:2 * n], len(focal))


def _c_seed(options: RansacOptions) -> int:
    """The C search's seed: the options' one, else fresh entropy."""
    return options.seed if options.seed is not None else \
        int(np.random.SeedSequence().entropy % (1 << 63))


def _c_search(rays: RayPairs, cam1: np.ndarray, cam2: np.ndarray, n_cameras: int,
              focal: Optional[np.ndarray], cam_axes: Optional[np.ndarray],
              cam_focal: Optional[np.ndarray], options: RansacOptions, threshold: float,
              refine: bool, method: str, seed: int, prechecked: bool,
              solver_kw: dict, search_info: Optional[dict] = None,
              extrinsic_std: Optional[np.ndarray] = None) -> Optional[dict]:
    """One C search (``_core.robust_rig_motion``) with ``options`` at
    ``threshold``, the verdict's evidence and the verdict itself gathered in
    the same call (``solver_kw`` from :func:`_solver_keywords`: the vertical,
    or the 6-point sampler's solver; ``extrinsic_std`` the calibration table
    of :func:`_extrinsic_table`, None: none given to C); None when it found
    no motion (``search_info`` then says how the search ended). The result's
    ``extrinsic_std_given`` says whether the C verdict saw the calibration
    error."""
    kw = dict(solver_kw)
    out = _core.robust_rig_motion(
        rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, cam1, cam2, n_cameras,
        focal=focal, cam_axes=cam_axes, cam_focal=cam_focal, threshold=threshold,
        prob=options.prob, min_iterations=min(options.min_iters, options.max_iters),
        max_iterations=int(options.max_iters), max_seconds=options.max_seconds, seed=seed,
        lo_rounds=options.lo_max_rounds if options.local_optimization else 0,
        refine=refine, loss=options.loss, max_scale_rel_std=options.max_scale_rel_std,
        sampler=kw.pop("sampler", method), prechecked=prechecked,
        verdict_still_factor=NO_PARALLAX_FACTOR, search_info=search_info,
        extrinsic_std=extrinsic_std, **kw)
    if out is not None:
        out["extrinsic_std_given"] = extrinsic_std is not None
    return out


def _extrinsic_table(calibration_std: Any, n_cameras: int) -> Optional[np.ndarray]:
    """``calibration_std`` (as :func:`mcgeom.robust.ransac` takes it: one
    (position m, rotation rad) pair for every camera, or (M, 2) per camera id)
    as the C verdict's table, float64 C-contiguous (n_cameras, 2); None when
    there is none or it is not such a table of finite values >= 0 (the
    verdict in Python then propagates it, and names what is wrong)."""
    if calibration_std is None or n_cameras < 1:
        return None
    sig = np.asarray(calibration_std, dtype=np.float64)
    if sig.shape == (2,):
        sig = np.tile(sig, (n_cameras, 1))
    if sig.ndim != 2 or sig.shape[1] != 2 or sig.shape[0] < n_cameras:
        return None
    sig = np.ascontiguousarray(sig[:n_cameras])
    return sig if np.isfinite(sig).all() and (sig >= 0).all() else None


def _checked(m: RigMotion, res: Any, rays: RayPairs, weights: np.ndarray,
             options: RansacOptions, method: str) -> RigMotion:
    """``m``, the RigMotion :func:`conclude_c` made of the C call's result
    ``res``, after the checks of its consensus: those of the call itself
    where it ran them (``res.have_consensus``), else
    :func:`one_pair_checked`'s."""
    if res.have_consensus:
        return m
    return one_pair_checked(m, rays, weights, options, method)


def _c_conclude(rays: RayPairs, out: dict, focal: Optional[np.ndarray], options: RansacOptions,
                method: str, t_start: float, calibration_std: Any, cam1: np.ndarray,
                cam2: np.ndarray, n_cameras: int) -> RigMotion:
    """The RigMotion of a C search's result ``out`` (``_core.robust_rig_motion``
    with ``verdict_still_factor`` :data:`NO_PARALLAX_FACTOR`, not None) on
    ``rays`` (camera ids ``cam1``/``cam2`` as passed to it): the verdict here,
    and the checks of its consensus (:func:`_checked`)."""
    R, t, inl = out["R"], out["t"], out["inliers"]
    res = out["_res"]
    info = _search_info(res, method)
    unconfirmed = unconfirmed_reason(info["stop"], res.iterations, res.sample_size,
                                     res.confidence)
    if res.have_scale and res.scale.reason in C_WORDED and \
            (calibration_std is None or out.get("extrinsic_std_given", False)):
        # the search decided the verdict itself (csrc/robust_verdict.c)
        return _checked(conclude_c(res, out["_f"], inl, options, method, info, t_start,
                                   unconfirmed), res, rays, out["weights"], options, method)
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
    m = conclude(rays, R, t, None, inl, fit, out["loss_scale"],
                 math.hypot(*out["t_hypothesis"].tolist()), options, method, info, t_start,
                 out["scale_profile"], calibration_std, rms=float(out["inlier_rms"]),
                 c_ids=(cam1, cam2, n_cameras, out["mask"], out["verdict"]),
                 zero_profile=float(out["zero_profile"]), unconfirmed=unconfirmed)
    return one_pair_checked(m, rays, out["weights"], options, method)
