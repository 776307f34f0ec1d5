"""The best available starting motion for a local or bounded search (issue 18).

``refine`` (Levenberg-Marquardt) and ``bnb_lp`` (branch and bound around a
start) converge to the minimum nearest their start. A fixed start fails
where its method does: linear17 near the critical motion (KITTI raw pairs:
refine from it ends 2.9-7.0 deg off while 5+1 is within 0.02 deg), 5+1 where
no camera has 5 intra-camera correspondences. :func:`best_start` runs each
candidate estimator and keeps the motion of lowest robust cost (Cauchy loss
of the Sampson angular residuals, thesis eq. 8.15) on all correspondences.

Frames and units (docs/architecture.md §3): rays in the rig frame (metres),
motion rig2_from_rig1 ``X2 = R X1 + t``, residuals and loss scale in radians.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from .. import _core
from ..errors import DegenerateError
from ..registry import get
from ..types import RayPairs, RigMotion

__all__ = ["START_CANDIDATES", "robust_cost", "metric_translation", "best_start"]

#: the estimators tried by default, in this order (ties keep the first)
START_CANDIDATES = ("five_plus_one", "linear17")


def metric_translation(m: RigMotion) -> np.ndarray:
    """The metric translation (metres) of a motion whatever its verdict: ``t``
    when observable, else ``info["t_metric"]`` when the estimator kept it."""
    if not m.scale.observable and isinstance(m.info, dict):
        tm = m.info.get("t_metric")
        if tm is not None and np.all(np.isfinite(np.asarray(tm, dtype=np.float64))):
            return np.asarray(tm, dtype=np.float64).reshape(3)
    return np.asarray(m.t, dtype=np.float64).reshape(3)


def robust_cost(rays: RayPairs, R: np.ndarray, t: np.ndarray, loss_scale: float) -> float:
    """``sum s^2 log(1 + r^2 / s^2)`` (Cauchy) of the Sampson angular residuals
    ``r`` (radians) of ``(R, t)`` (``t`` metric), ``s = loss_scale`` radians:
    the cost the robust refinements minimise; infinite for a non-finite motion."""
    R = np.asarray(R, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)
    if not (np.all(np.isfinite(R)) and np.all(np.isfinite(t))):
        return float("inf")
    r = _core.gec_residuals(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, R, t)
    s2 = float(loss_scale) ** 2
    return float(s2 * np.sum(np.log1p(r * r / s2)))


def best_start(rays: RayPairs, loss_scale: float = 5e-3,
               candidates: Sequence[str] = START_CANDIDATES) -> tuple[RigMotion, dict]:
    """The candidate estimate of lowest robust cost on ``rays``, and a report.

    Each name of ``candidates`` is run through the registry on all of
    ``rays`` (options at their defaults); a candidate that raises ValueError
    or DegenerateError (e.g. 5+1 without a camera with 5 intra-camera
    correspondences) is skipped. Candidates that report no translation (a
    static rig: ``info["translation_detected"] is False``, ``t = 0``) are
    compared only when no candidate found a translation: their Sampson cost
    at ``t = 0`` is not comparable (the epipolar constraint of one camera
    vanishes there). The motion returned is the candidate's own (``t`` a unit
    vector when its verdict says so; its metric ``t`` is
    :func:`metric_translation`).

    ``loss_scale`` (radians) is the Cauchy scale of :func:`robust_cost`.
    Returns ``(motion, report)``, ``report`` = ``{"chosen": name, "costs":
    {name: cost}, "errors": {name: message}}``. Raises DegenerateError naming
    every candidate's failure when none gives a motion.
    """
    if not (np.isfinite(loss_scale) and loss_scale > 0):
        raise ValueError(f"loss_scale must be a positive number of radians, got {loss_scale}")
    if isinstance(candidates, str) or len(candidates) == 0:
        raise ValueError(f"candidates must be a non-empty sequence of estimator names, got "
                         f"{candidates!r}")
    costs: dict = {}
    errors: dict = {}
    moving: list = []
    still: list = []
    for name in candidates:
        est = get(name)   # ValueError naming the known estimators for a bad name
        try:
            m = est(rays)
        except (ValueError, DegenerateError) as e:
            errors[name] = f"{type(e).__name__}: {e}"
            continue
        costs[name] = robust_cost(rays, m.R, metric_translation(m), loss_scale)
        static = isinstance(m.info, dict) and m.info.get("translation_detected") is False
        (still if static else moving).append((name, m))
    pool = moving or still
    if not pool:
        raise DegenerateError("no starting motion: " + "; ".join(
            f"{k}: {v}" for k, v in errors.items()))
    # min keeps the first of equal costs: the order of ``candidates`` breaks ties
    name, m = min(pool, key=lambda nm: costs[nm[0]])
    return m, {"chosen": name, "costs": costs, "errors": errors}
