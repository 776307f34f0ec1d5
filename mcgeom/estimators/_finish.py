"""The last step shared by the estimators that start from an algebraic solution
(``upright_four_point``, ``eigensolver``): the joint refinement of (R, t) on
all correspondences (Sampson angular error, thesis eq. 8.15), the scale verdict
from its covariance and profile, and the :class:`RigMotion` (the unit travel
direction when ``|t|`` is not observable, as every estimator reports it).

Frames and units (docs/architecture.md §3): rays in the rig frame (metres),
``X2 = R X1 + t`` with ``t`` in metres; residuals in radians.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Callable, Optional

import numpy as np

from .. import _core
from ..errors import DegenerateError, McgeomError
from ..geometry import centroid_travel, refine_centred
from ..observability import scale_profile, scale_verdict
from ._static import check_static
from ..types import RayPairs, RigMotion
from ._common import travel_direction
from ._outliers import guard_verdict

__all__ = ["refine_and_report", "unrefined_scale_std"]


def _refine(rays: RayPairs, R: np.ndarray, t: np.ndarray, fix_scale: bool,
            iterate: bool = True) -> dict:
    # converged to rounding: the result must not depend on the start's rounding
    # (ray order, rig frame), as five_plus_one's refinement; without iterations
    # the covariance of (R, t) as given
    return refine_centred(rays, R, t, loss="none", fix_scale=fix_scale,
                          max_iterations=100 if iterate else 0,
                          cost_tolerance=1e-15, step_tolerance=1e-13)


def _move_to_optimum(rays: RayPairs, R: np.ndarray, t: np.ndarray) -> float:
    """How far the cameras' travel (the centroid's translation, whose length
    the verdict judges) lies from the Sampson optimum, relative, to first
    order: one Levenberg-Marquardt step from (R, t). inf where that step
    cannot be taken (a singular normal matrix: |t| not determined; a
    numerical failure): no metric scale is then claimed.

    Why: the covariance at an estimate that is not the optimum is that of
    the optimum, an efficient estimator; an algebraic estimate (the
    eigensolver's) is less efficient, and its error exceeds that std by
    about this move (rms of error / std over 40-60 problems of the property
    suite's four rig kinds, 100 rays, 1e-3 rad: 1.20-1.45 with the covariance
    alone, 0.98-1.20 with the move; one step finds 98-100 % of the full
    refinement's move)."""
    try:
        out = refine_centred(rays, R, t, loss="none", fix_scale=False, max_iterations=1)
    except (McgeomError, ValueError):   # (no step: nothing says how far the optimum is)
        return float("inf")
    before = centroid_travel(rays, R, t)
    return abs(centroid_travel(rays, out["R"], out["t"]) / before - 1.0) if before > 0.0 \
        else float("inf")


def unrefined_scale_std(rays: RayPairs, R: np.ndarray, t: np.ndarray,
                        at_estimate: Optional[float] = None) -> tuple[float, float]:
    """``(relative std of the travel, its move to the optimum)`` for an
    estimate (R, t) (rig2_from_rig1, metres) that is not the Sampson optimum
    (an unrefined linear or algebraic one): the first-order std of the
    Sampson cost at the estimate (``at_estimate`` when the caller has it) and
    :func:`_move_to_optimum` in quadrature. inf where the cost does not fix
    |t| there. The rms of error / this std over the property suite's four
    rig kinds (100 rays, 1e-3 rad; ``tests/test_std_calibration.py``):
    eigensolver 1.06, linear17 without refinement 1.02 (1.50 with the
    kernel's own std), five_plus_one without refinement 0.99 (2.98 with the
    spread of its scale samples)."""
    if at_estimate is None:
        try:
            at_estimate = float(refine_centred(rays, R, t, loss="none", fix_scale=False,
                                               max_iterations=0)["scale_rel_std"])
        except (McgeomError, ValueError):
            return float("inf"), float("inf")
    move = _move_to_optimum(rays, R, t)
    return float(np.hypot(at_estimate, move)), move


def refine_and_report(rays: RayPairs, starts: list, method: str,
                      max_scale_rel_std: float, info: dict, iterate: bool = True,
                      prior_check: Optional[Callable[[np.ndarray], Optional[str]]] = None
                      ) -> RigMotion:
    """Refine each start ``(R, t)`` (rig2_from_rig1, metres) on all ``rays`` and
    report the one of least final cost.

    Several starts (e.g. the local minima of an algebraic cost, which noise can
    reorder) make the result independent of which of them the algebraic cost
    happened to rank first: the refinement of each ends in a minimum of the
    Sampson cost and the lowest is kept (ties within 1e-9: the first start).
    All six degrees of freedom are refined; where the refinement cannot move
    ``|t|`` (critical motion: a singular normal matrix) it is held and the
    scale reported unobservable. The verdict is that of the other estimators
    (:func:`mcgeom.observability.scale_verdict`): the relative std of the
    travelled distance at most ``max_scale_rel_std`` and its profile excluding
    ``1 +- 3 max_scale_rel_std`` at 3 sigma. ``info`` is completed with the
    refinement's iterations and ``t_metric`` (the metric estimate whatever the
    verdict). With ``iterate=False`` no start is moved: the least Sampson cost
    among them is kept and the verdict rests on the covariance and profile
    there, the relative std widened by the start's distance from the Sampson
    optimum (``info["move_to_optimum"]``, one step's first-order estimate).
    ``prior_check(R)``: why the refined rotation contradicts a prior
    the caller gave (``upright_four_point``'s vertical), None when it does
    not; a metric verdict it contradicts is made "not observable" with that
    reason.
    """
    best = None
    for R, t in starts:
        fixed = False
        try:
            out = _refine(rays, R, t, False, iterate)
        except DegenerateError:
            out = _refine(rays, R, t, True, iterate)
            fixed = True
        if best is None or out["final_cost"] < best[0]["final_cost"] * (1.0 - 1e-9):
            best = (out, fixed)
    if best is None:
        raise DegenerateError(f"{method}: no start to refine")
    out, fixed = best
    R, t = out["R"], out["t"]
    rel = float("inf") if fixed else float(out["scale_rel_std"])
    if not iterate and np.isfinite(rel):
        # the estimate is not the optimum whose covariance gave rel: its own
        # error is larger by about its distance from it (_move_to_optimum)
        rel, info["move_to_optimum"] = unrefined_scale_std(rays, R, t, rel)
    info["refinement"] = {k: out[k] for k in ("iterations", "converged") if k in out}
    if rel <= max_scale_rel_std:
        k = 1.0 + 3.0 * max_scale_rel_std
        info["scale_profile"] = scale_profile(rays, R, t, out["final_cost"], out["sigma2"],
                                              (1.0 / k, k))
        if info["scale_profile"] < 9.0:
            rel = float("inf")
    everything = np.ones(len(rays), bool)
    verdict = scale_verdict(rays, everything, R, t, rel, max_scale_rel_std, fixed)
    # every correspondence was taken as an inlier: a fit pulled by gross
    # outliers is no metric estimate (mcgeom.estimators._outliers)
    verdict, info["outlier_move_stds"] = guard_verdict(rays, R, t, verdict, method,
                                                       max_scale_rel_std, info=info)
    if verdict.observable and prior_check is not None:
        why = prior_check(R)
        if why is not None:
            verdict = replace(verdict, observable=False, reason=why)
    info["t_metric"] = np.array(t)
    if not verdict.observable:
        nt = np.linalg.norm(t)
        t = travel_direction(rays, everything, R, t)
        info["t_metric"] = nt * t
    r = np.abs(_core.gec_residuals(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, R, t))
    m = RigMotion(R, t, verdict, method, float(np.sqrt(np.mean(r ** 2))), None, info)
    # a rig that did not translate measurably: the shared static answer (R,
    # t = 0, "no translation detected"), as every estimator gives it
    return check_static(rays, method, m) or m
