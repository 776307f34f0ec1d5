"""``refine``: non-linear refinement of a rig motion on the Sampson angular error.

Levenberg-Marquardt over the rotation (left increments, ``R <- exp([dw]x) R``)
and the translation, minimising a robust function of the Sampson (first-order
geometric) angular error of the generalized epipolar constraint (thesis
eq. 8.15): for each correspondence, with the per-pair essential matrix
``F = [t + R o1 - o2]x R`` and unit bearings,

    r = d2^T F d1 / sqrt(|P(d1) F^T d2|^2 + |P(d2) F d1|^2),   P(d) = I - d d^T,

in radians. The thesis uses its linear method (ch. 8) as the initial estimate
of such a refinement (ch. 8.5); so does this estimator by default. The whole
optimisation runs in one C call (``csrc/refine.c``); this module chooses the
start, converts and builds the scale verdict from the refined evidence.

Frames and units: rays in the rig frame (metres), motion rig2_from_rig1
(``X2 = R X1 + t``), residuals and loss scale in radians.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, Optional, Union

import numpy as np

from .. import _core
from ..observability import critical_angle
from ..registry import register
from ..types import RayPairs, RigMotion, ScaleVerdict
from ._common import travel_direction
from ._start import best_start, metric_translation
from ._static import check_static

__all__ = ["refine", "MAX_SCALE_REL_STD"]

#: relative std of |t| above which the refined scale is reported unobservable
MAX_SCALE_REL_STD = 0.1
_MIN_PAIRS = 6

InitialLike = Union[RigMotion, tuple, list, None]


def _initial(rays: RayPairs, initial: InitialLike, loss_scale: float
             ) -> tuple[np.ndarray, np.ndarray, Optional[bool], str, Optional[RigMotion], dict]:
    """(R0, t0, observable-or-None, source, static start or None, start costs) of the
    starting motion (the costs: ``best_start``'s report, empty for a given start).

    By default the best of 5+1 and linear17 (lower robust cost,
    :func:`mcgeom.estimators._start.best_start`); when every candidate found no
    translation, that static motion is returned last (nothing to refine).
    """
    if initial is None:
        m, report = best_start(rays, loss_scale)
        if m.info.get("translation_detected") is False:
            return m.R, m.t, False, report["chosen"], m, report
        # the start's metric t even where its verdict made t a unit vector:
        # holding |t| at a wrong length bends R to compensate (see
        # mcgeom.robust._python_search.finish)
        return (m.R, metric_translation(m), bool(m.scale.observable), report["chosen"], None,
                report)
    if isinstance(initial, RigMotion):
        return initial.R, initial.t, bool(initial.scale.observable), initial.method, None, {}
    if isinstance(initial, (tuple, list)) and len(initial) == 2:
        R0 = np.asarray(initial[0], dtype=np.float64) if _numeric(initial[0]) else None
        t0 = np.asarray(initial[1], dtype=np.float64) if _numeric(initial[1]) else None
        if R0 is None or R0.shape != (3, 3):
            raise ValueError("initial: R must be a 3x3 rotation matrix, got "
                             f"{np.shape(initial[0])}")
        if t0 is None or t0.shape != (3,):
            raise ValueError(f"initial: t must be a 3-vector, got shape {np.shape(initial[1])}")
        return R0, t0, None, "given", None, {}
    raise ValueError("initial must be None, a RigMotion or an (R, t) pair, got "
                     f"{type(initial).__name__}")


def _numeric(a: Any) -> bool:
    try:
        return np.asarray(a).dtype.kind in "fiu"
    except Exception:  # ragged input and the like
        return False


def _verdict(r: dict, fixed: bool, initial_observable: Optional[bool]) -> ScaleVerdict:
    rel = float(r["scale_rel_std"])
    cond = float(r["info_cond"])
    if fixed:
        why = ("the initial estimate reported it unobservable" if initial_observable is False
               else "fix_scale was requested")
        reason = (f"scale not estimated: |t| kept fixed during the refinement ({why}); "
                  "t is a unit direction")
    elif not np.isfinite(rel):
        reason = ("critical motion: the refined information matrix leaves |t| unconstrained "
                  "(e.g. no rotation and only intra-camera correspondences, thesis ch. 7.3.2)")
    elif rel > MAX_SCALE_REL_STD:
        reason = (f"scale too uncertain: relative std {rel:.3g} of |t| after refinement "
                  "(near-critical motion, too little rotation for the noise level)")
    else:
        reason = f"scale fixed by the data: relative std {rel:.2g} of |t| after refinement"
    observable = (not fixed) and np.isfinite(rel) and rel <= MAX_SCALE_REL_STD
    return ScaleVerdict(bool(observable), reason, conditioning=cond, rel_std=rel)


def _covariance(info: np.ndarray, sigma2: float) -> Optional[np.ndarray]:
    """sigma2 * info^-1, or None when info is singular (a direction is unconstrained)."""
    if not np.isfinite(sigma2):
        return None
    d = np.sqrt(np.diag(info))
    if not (d > 0).all():
        return None
    scaled = info / np.outer(d, d)  # Jacobi scaling: rotation and metres commensurate
    w = np.linalg.eigvalsh(scaled)
    if not w[0] > 1e-12 * w[-1]:
        return None
    return sigma2 * (np.linalg.inv(scaled) / np.outer(d, d))


@register(
    "refine",
    min_sample=_MIN_PAIRS,
    camera_kinds=("most-general", "locally-central", "axial", "locally-central-and-axial"),
    family="refinement",
    needs_rotation=False,
    recovers_scale=True,
    description="Levenberg-Marquardt refinement of R, t (with metric scale) on the robust "
                "Sampson angular error of the generalized epipolar constraint",
    options={"initial": "start: RigMotion or (R, t); default: the better of the 5+1 and "
                        "linear17 estimates (lower robust cost)",
             "loss": "robust loss: 'cauchy' (default), 'huber', 'soft_l1' or 'none'",
             "loss_scale": "scale of the loss, radians (default 5e-3)",
             "max_iterations": "Levenberg-Marquardt trial steps (default 50)",
             "fix_scale": "keep |t| fixed; default: when the start reports the scale "
                          "unobservable",
             "weights": "per-correspondence weights >= 0 (default all 1)"},
)
def refine(rays: RayPairs, *, initial: InitialLike = None, loss: str = "cauchy",
           loss_scale: float = 5e-3, max_iterations: int = 50, fix_scale: Optional[bool] = None,
           weights: Any = None) -> RigMotion:
    """Refine a rig motion on the robust Sampson angular error (radians).

    ``rays`` are ray correspondences in the rig frame (metres). ``initial`` is
    the starting rig2_from_rig1 motion: a :class:`RigMotion` or an ``(R, t)``
    pair (``X2 = R X1 + t``); by default the better of the ``five_plus_one``
    and ``linear17`` estimates, the one of lower robust cost (Cauchy of the
    Sampson residuals at ``loss_scale``; ``info["start_costs"]``). When
    ``fix_scale`` is None it is set from the start's verdict: a start whose
    scale is unobservable (a unit ``t``) is refined with ``|t|`` kept fixed.
    Otherwise the refinement runs in two stages: rotation and direction of
    ``t`` with ``|t|`` held, then all six degrees of freedom (the free problem
    is flat along ``|t|`` where the scale is weakly observable, and a poor start
    can slide along that valley).

    Returns a :class:`RigMotion`. Its scale verdict comes from the refined
    evidence: observable iff the first-order relative std of ``|t|`` (from the
    covariance ``sigma2 (J^T W J)^-1``, rotation marginalised out) is at most
    0.1 and the scale was not fixed; otherwise ``t`` is returned as a unit
    direction (the metric one stays in ``info["t_metric"]``).
    ``residual_rms`` is the weighted RMS Sampson residual over all
    correspondences (radians, outliers included). ``info`` holds
    ``iterations`` (both stages), ``converged``, ``stop_reason``, ``initial_cost``,
    ``final_cost`` (robust cost ``sum w rho(r^2)``), ``sigma`` (residual std,
    radians), ``information`` (6x6 J^T W J, order [dw (rad), dt (m)]),
    ``covariance`` (``sigma^2`` times its inverse, None when singular),
    ``n_used``, ``scale_rel_std``, ``info_cond``, ``fix_scale``, ``loss``,
    ``loss_scale``, ``initial_method`` and ``t_metric``.

    Raises ValueError on bad input (naming it), DegenerateError when the start
    constrains nothing (or linear17 cannot start).
    """
    if not isinstance(rays, RayPairs):
        raise TypeError(f"rays must be a RayPairs, got {type(rays).__name__}")
    n = len(rays)
    if n < _MIN_PAIRS:
        raise ValueError(f"too few correspondences: refine needs at least {_MIN_PAIRS}, got {n}")
    if not isinstance(loss, str) or loss not in _core.LOSS_NAMES:
        raise ValueError(f"loss must be one of {sorted(_core.LOSS_NAMES)}, got {loss!r}")
    R0, t0, start_observable, source, still, report = _initial(rays, initial, loss_scale)
    starts = {k: report[k] for k in ("costs", "errors") if k in report}
    if still is not None:
        # the rig did not translate (every start says so): R, t = 0, as 5+1
        return replace(still, method="refine", info={**still.info, "initial_method": source,
                                                     "start_costs": starts})
    fixed = bool(fix_scale) if fix_scale is not None else start_observable is False
    if fixed and not np.linalg.norm(t0) > 0:
        raise ValueError("fix_scale needs a non-zero initial t")
    args = (rays.origins1, rays.dirs1, rays.origins2, rays.dirs2)
    kw = dict(weights=weights, loss=loss, loss_scale=loss_scale, max_iterations=max_iterations)
    if fixed or not np.linalg.norm(t0) > 0:
        r = _core.refine_motion(*args, R0, t0, fix_scale=fixed, **kw)
        first = r
    else:
        # Two stages: rotation and direction of t with |t| held, then all six.
        # Where the scale is weakly observable (locally-central rigs, small
        # rotations) the free problem is flat along |t| and a poor start can
        # slide along it (to t -> 0 or to the central-camera asymptote
        # |t| -> inf); from a converged direction it does not.
        first = _core.refine_motion(*args, R0, t0, fix_scale=True, **kw)
        r = _core.refine_motion(*args, first["R"], first["t"], **kw)
    verdict = replace(_verdict(r, fixed, start_observable),
                      critical_angle=critical_angle(rays, r["R"], r["t"]))
    t_metric = r["t"].copy()
    t = r["t"]
    if not verdict.observable and np.linalg.norm(t) > 0:
        # a unit direction whose sign cheirality picks (travel_direction, as
        # _finish's): where |t| is unobservable the epipolar constraint may
        # not tell t from -t (no rotation, intra-camera rays: F = [t]x), and
        # the start's metric t can lie in the mirrored minimum (5+1's
        # t_metric on a critical motion of tests/test_refine.py: 1.7 cm
        # backwards, refined there with |t| held: the unit t pointed back)
        t = travel_direction(rays, np.ones(n, bool), r["R"], t)
    info = {
        "iterations": r["iterations"] + (first["iterations"] if first is not r else 0),
        "converged": r["converged"],
        "stop_reason": r["reason"],
        "initial_cost": first["initial_cost"],
        "final_cost": r["final_cost"],
        "sigma": float(np.sqrt(r["sigma2"])) if np.isfinite(r["sigma2"]) else float("inf"),
        "information": r["information"],
        "covariance": _covariance(r["information"], r["sigma2"]),
        "n_used": r["n_used"],
        "scale_rel_std": r["scale_rel_std"],
        "info_cond": r["info_cond"],
        "fix_scale": fixed,
        "loss": loss,
        "loss_scale": float(loss_scale),
        "initial_method": source,
        "start_costs": starts,
        "t_metric": None if fixed else t_metric,
    }
    m = RigMotion(r["R"], t, verdict, "refine", float(r["rms"]), None, info)
    # the refined motion is the best fit with a translation: is the rotation
    # alone as good (a static rig whose free t absorbed calibration error)?
    return check_static(rays, "refine", m) or m
