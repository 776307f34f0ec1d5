"""``linear17``: the linear 17-point generalized essential matrix (thesis ch. 8).

Thesis Algorithm 2 with the constrained least squares of Algorithm 4
(eq. 8.36) for the locally-central, axial and locally-central-and-axial
generalized cameras, the plain SVD for the most-general one (cross-camera
correspondences), the translation with metric scale from eq. 8.15 and the
refinement of ch. 8.4.3. The whole computation, the check for repeated
correspondences included, runs in one C call (``csrc/linear17.c``); this
module only converts and reports.

The linear step minimises the algebraic residual of the generalized epipolar
constraint ``d2^T [t]x R d1 + d2^T R m1 + m2^T R d1`` in the normalised frame of
Algorithm 2 step 1; the refinement then minimises the Sampson angular error of
each correspondence (radians; ``residual_rms`` is its RMS), whose optimum,
unlike the algebraic one, is not biased towards a short t (issue 22,
``mcgeom experiment linear17_accuracy``).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Optional

import numpy as np

from .. import _core
from ..errors import DegenerateError
from ..registry import register
from ..types import RayPairs, RigMotion, ScaleVerdict, make_rig_motion, make_scale_verdict
from ._finish import unrefined_scale_std
from ._outliers import (SCREEN_LEVERAGE, SCREEN_STDS, moved_verdict, one_pair_reason,
                        one_pair_rule)
from ._static import KERNEL_OPTIONS, intra_groups, with_static_check

__all__ = ["linear17", "linear17_start", "linear17_no_static_check"]

_NEEDED = {"most-general": 17, "locally-central": 16, "axial": 16,
           "locally-central-and-axial": 14, "central": 8}


_OBSERVABLE = "scale fixed by the data (rotation or cross-camera rays)"
_CENTRAL = "central camera: all rays share one centre, the scale is not observable"
#: the kernel's default max_scale_rel_std
_DEFAULT_LIMIT = _core.Linear17Options().max_scale_rel_std

_CRITICAL = ("critical motion: the data leave |t| free (no rotation and only "
             "intra-camera correspondences, thesis ch. 7.3.2)")


def _verdict(observable: bool, gc_case: str, conditioning: float,
             rel_std: float) -> ScaleVerdict:
    """The scale verdict from the kernel's O(N) evidence (scale_evidence in
    csrc/linear17.c: conditioning of eq. 8.15, relative std of |t|)."""
    if observable:
        reason = _OBSERVABLE
    elif gc_case == "central":
        reason = _CENTRAL
    elif conditioning < 1e-6:
        reason = _CRITICAL
    else:
        reason = (f"scale too uncertain: relative std {rel_std:.3g} "
                  "(near-critical motion, too little rotation for the noise level)")
    return make_scale_verdict(observable, reason, conditioning, rel_std)


@register(
    "linear17",
    min_sample=17,
    camera_kinds=("most-general", "locally-central", "axial", "locally-central-and-axial"),
    family="linear",
    needs_rotation=False,
    recovers_scale=True,
    description="linear 17-point generalized essential matrix with constrained SVD, refined "
                "to the Sampson-error optimum (thesis ch. 8)",
    options={"refine": "run the refinement of ch. 8.4.3 to the Sampson-error optimum "
                       "(default True; without it the std of |t| also counts the distance "
                       "to that optimum)",
             "max_iterations": "cap on refinement iterations (default 100)",
             "tolerance": "relative cost decrease that stops the alternation (1e-10); the "
                          "refinement also stops after a step below 0.3 standard "
                          "deviations of the estimate (csrc/linear17.c)",
             "max_scale_rel_std": "relative std of |t| above which the scale is "
                                  "reported unobservable (0.1)"},
    minimal_solver=lambda sample: _minimal(sample),
    checks_distinct=True,
)
def linear17(rays: RayPairs, *, refine: bool = True, max_iterations: Optional[int] = None,
             tolerance: Optional[float] = None, max_scale_rel_std: Optional[float] = None,
             options: Optional[_core.Linear17Options] = None) -> RigMotion:
    """Relative rig motion (R, t with metric scale) from >= 17 ray correspondences.

    ``rays`` are in the rig frame (metres); origins must be the camera centres
    for axial rigs. Returns ``RigMotion`` rig2_from_rig1 (``X2 = R X1 + t``);
    ``info`` reports the detected generalized-camera kind, the ranks, the
    refinement iterations and convergence. A rig that did not translate
    measurably (static, pure rotation: ``E = 0``) gives the rotation, ``t = 0``
    and the verdict "no translation detected" (the shared test of
    :mod:`mcgeom.estimators._static`; the linear estimate is in
    ``info["full_estimate"]`` when there was one). Raises ValueError on bad
    input (NaN/inf, zero directions, fewer than 14 rays) and DegenerateError
    when the data do not determine E otherwise (too few rays for the kind,
    degenerate configurations, or fewer than 17 distinct correspondences
    among 17 or more).
    """
    options = _options(rays, refine, max_iterations, tolerance, max_scale_rel_std, options)
    limit = _DEFAULT_LIMIT if options is None else options.max_scale_rel_std
    m = _linear17(rays, options, limit)
    return m if options is None or options.refine else _unrefined(rays, m, limit)


def linear17_start(rays: RayPairs) -> RigMotion:
    """``linear17(rays, refine=False)``'s motion for an estimator that starts
    from it (six_point, eigensolver): the linear solution with the kernel's
    verdict, without the unrefined estimate's own std (:func:`_unrefined`),
    which a start does not use. Same checks and errors as :func:`linear17`."""
    options = _options(rays, False, None, None, None, None)
    return _linear17(rays, options, options.max_scale_rel_std)


def _linear17(rays: RayPairs, options: Optional[_core.Linear17Options],
              limit: float) -> RigMotion:
    """:func:`linear17` with its kernel options made and checked (``limit``
    their ``max_scale_rel_std``), up to the unrefined estimate's std."""
    # E = 0 has no null space of the right dimension: a static rig raises
    # DegenerateError in the kernel (thesis ch. 8.3's kinds all assume t != 0)
    # the estimate and the shared static-rig test of it in one marshalling of
    # the rays (_core.linear17_static_raw; issue 22). Everything but a moving
    # rig's answer (a kernel failure, a static rig) goes the shared way, whose
    # results and errors these are: with_static_check re-runs it
    st, f, r, sst, sres, lev = _core.linear17_static_raw(
        rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, intra_groups(rays), options,
        KERNEL_OPTIONS)
    if st == _core.STATUS_OK and sst == _core.STATUS_OK and not sres.is_static:
        return _guarded(rays, _motion(f, r), limit, lev)
    return _guarded(rays, with_static_check(rays, "linear17", lambda: linear17_no_static_check(
        rays, options=options)), limit)


def _unrefined(rays: RayPairs, m: RigMotion, max_rel_std: float) -> RigMotion:
    """The verdict of an estimate that ``refine=False`` left at the linear
    solution (thesis Algorithm 2 without ch. 8.4.3): the kernel's std is the
    algebraic cost's, while the solution is not that of an efficient
    estimator (rms of error / that std 1.50 over the property suite's four
    rig kinds, errors up to 4.2 stds). The std is at least the Sampson cost's
    at the estimate with the estimate's distance from its optimum in
    quadrature (:func:`._finish.unrefined_scale_std`: rms 1.02); above
    ``max_rel_std`` the scale is not reported."""
    if not m.scale.observable:
        return m
    t = np.asarray(m.info.get("t_metric", m.t), float)
    geo, move = unrefined_scale_std(rays, m.R, t)
    m.info["move_to_optimum"] = move
    rel = max(float(m.scale.rel_std), geo)
    if rel <= max_rel_std:
        return make_rig_motion(m.R, m.t, replace(m.scale, rel_std=rel), m.method,
                               m.residual_rms, m.inliers, m.info)
    why = (f"scale too uncertain: relative std {rel:.3g} > {max_rel_std:.3g} for the "
           f"unrefined linear estimate, which lies {move:.2g} (relative) from the Sampson "
           f"optimum (refine=True reaches it)")
    return make_rig_motion(m.R, t / np.linalg.norm(t), replace(m.scale, observable=False,
                                                                reason=why, rel_std=rel),
                           m.method, m.residual_rms, m.inliers, m.info)


def _guarded(rays: RayPairs, m: RigMotion, max_rel_std: float,
             stats: Optional[dict] = None) -> RigMotion:
    """``m`` (a least-squares fit on all ``rays``), with its scale not metric
    and ``t`` the unit direction where one correspondence carries the fit
    (:func:`mcgeom.estimators._outliers.one_pair_reason`: a gross outlier
    that the fit absorbed; ``info["max_leverage"]``,
    ``info["max_influence_stds"]``; ``stats``: its statistics when
    ``_core.linear17_static_raw`` gathered them). An exact fit (RMS below
    1e-12 rad) is the data's motion and is not checked."""
    if not m.scale.observable or not m.residual_rms > 1e-12:
        return m
    why = (one_pair_reason(rays, m.R, m.t, "linear17", max_rel_std, info=m.info)
           if stats is None else one_pair_rule(stats, "linear17", max_rel_std, m.info))
    scale = replace(m.scale, observable=False, reason=why) if why is not None else m.scale
    if why is None and (m.info.get("max_leverage", 0.0) > max(SCREEN_LEVERAGE, 18.0 / len(rays))
                        or m.info.get("max_influence_stds", 0.0) > SCREEN_STDS):
        # several outliers may share the pull (the robust refit of the other
        # direct estimators, screened for its cost; a leverage above 3 p / n,
        # p = 6 parameters, is Hoaglin & Welsch's (1978) "high")
        scale, m.info["outlier_move_stds"] = moved_verdict(rays, m.R, m.t, m.scale, "linear17",
                                                           max_rel_std)
    if scale.observable:
        return m
    t = np.asarray(m.info.get("t_metric", m.t), float)
    return make_rig_motion(m.R, t / np.linalg.norm(t), scale, m.method, m.residual_rms,
                           m.inliers, m.info)


def _options(rays: RayPairs, refine: bool, max_iterations: Optional[int],
             tolerance: Optional[float], max_scale_rel_std: Optional[float],
             options: Optional[_core.Linear17Options]) -> Optional[_core.Linear17Options]:
    """The kernel's options from the keyword options (None: the defaults),
    after the checks of the arguments that precede the kernel's own."""
    if not isinstance(rays, RayPairs):
        raise TypeError(f"rays must be a RayPairs, got {type(rays).__name__}")
    n = len(rays)
    if n < 14:
        raise ValueError(f"too few correspondences: linear17 needs at least 17 "
                         f"(16 locally-central or axial, 14 locally-central-and-axial), got {n}")
    if options is None and (not refine or max_iterations is not None or tolerance is not None
                            or max_scale_rel_std is not None):
        options = _core.Linear17Options(refine=refine, max_iterations=max_iterations,
                                        tolerance=tolerance, max_scale_rel_std=max_scale_rel_std)
    return options


def linear17_no_static_check(rays: RayPairs, *, refine: bool = True,
                             max_iterations: Optional[int] = None,
                             tolerance: Optional[float] = None,
                             max_scale_rel_std: Optional[float] = None,
                             options: Optional[_core.Linear17Options] = None) -> RigMotion:
    """:func:`linear17` without the shared static-rig test (RANSAC's minimal
    solver, and ``mcgeom bench linear17``'s plugin timing): same frames, units,
    options and errors; a static rig raises DegenerateError here."""
    options = _options(rays, refine, max_iterations, tolerance, max_scale_rel_std, options)
    # NaN/inf and zero-length directions (|d| < 1e-50, the one rule of every
    # estimator: mcgeom.validation.check_directions) are rejected by the
    # kernel in its one pass over the rays; _raise then names the array
    st, f, r = _core.linear17_raw(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, options)
    if st != _core.STATUS_OK:
        _raise(st, _core.linear17_dict(f, r), rays, len(rays))
    return _motion(f, r)


def _motion(f: np.ndarray, r) -> RigMotion:
    """The RigMotion of a successful kernel call (``f``, ``r``: the buffer
    and result of :func:`mcgeom._core.linear17_raw`)."""
    d = _core.L17_OFFSETS
    gc_case = _core.GC_CASE_NAMES.get(r.gc_case, "degenerate")
    info = {
        "camera_kind": gc_case,
        "rank_A_R": r.rank_ar,
        "rank_A": r.rank_a,
        "iterations": r.iterations,
        "converged": bool(r.converged),
        "cost_linear": r.cost_linear,
        "t_metric": f[d["t_metric"]:d["t_metric"] + 3],
        "candidate_cost": f[d["candidate_cost"]:d["candidate_cost"] + r.n_candidates],
        "n_in_front": r.n_in_front,
        "E_normalised": f[d["E"]:d["E"] + 9].reshape(3, 3),
        "schur_eig": f[d["schur_eig"]:d["schur_eig"] + 9],
        "A_R_eig": f[d["ar_eig"]:d["ar_eig"] + 9],
        "normalisation": (f[d["norm_origin"]:d["norm_origin"] + 3], r.norm_scale),
    }
    verdict = _verdict(bool(r.scale_observable), gc_case, r.scale_conditioning,
                       r.scale_rel_std)
    return make_rig_motion(f[d["R"]:d["R"] + 9].reshape(3, 3), f[d["t"]:d["t"] + 3], verdict,
                           "linear17", r.cost_final, None, info)


def _minimal(sample: RayPairs) -> list:
    """The motion of a 17-ray sample for RANSAC (none if the sample is degenerate)."""
    try:
        m = linear17_no_static_check(sample, refine=False)
    except DegenerateError:
        return []
    return [(m.R, m.t if m.scale.observable else m.info["t_metric"])]


def _raise(status: int, r: dict, rays: RayPairs, n: int) -> None:
    """Turn a kernel failure into an exception that names the problem."""
    if status == _core.STATUS_EINVAL:  # find which argument is at fault
        rays.check_finite()
        for name in ("dirs1", "dirs2"):
            if (np.linalg.norm(getattr(rays, name), axis=1) == 0).any():
                raise ValueError(f"rays.{name} contains a zero-length direction")
        _core.raise_for(status, "linear17")
    if status == _core.STATUS_EDEGENERATE:
        if n >= 17 and r["n_distinct"] < 17:
            raise DegenerateError(f"linear17: only {r['n_distinct']} distinct correspondence(s) "
                                  f"among {n} (the others repeat them); linear17 needs at "
                                  "least 17")
        kind = r["gc_case"]
        if kind == "degenerate":
            raise DegenerateError(
                "linear17: degenerate data: the null space of the R-block A_R "
                f"(rank {r['rank_ar']}) matches no generalized-camera kind; typical causes: "
                "no translation (pure rotation or zero motion, E = 0) or too few distinct rays")
        need = _NEEDED.get(kind, 17)
        if n < need:
            raise DegenerateError(f"linear17: too few correspondences for a {kind} camera: "
                                  f"need {need}, got {n}")
        raise DegenerateError(
            f"linear17: E is not determined by the data ({kind} camera): the reduced system "
            "has more than one null direction (no translation or a rig that hardly moves, "
            "repeated rays, or rays in a degenerate configuration)")
    _core.raise_for(status, "linear17")
