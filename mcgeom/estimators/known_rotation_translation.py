"""``known_rotation_translation``: the translation of a rig motion whose
rotation is known (thesis ch. 6 with the de-rotated rig of ch. 4.2, Fig. 4.2).

With R known, the generalized epipolar constraint (docs/architecture.md §3)
``d2^T [t]x R d1 + d2^T R m1 + m2^T R d1 = 0`` is linear in t:
``(R d1 x d2) . t = -(d2^T R m1 + m2^T R d1)``. It is solved as the two-view
case of :func:`mcgeom.multiview.translations_from_tracks` (view 0 = rig 1 at
the origin, view 1 = rig 2 with view_from_world rotation R, centre
c = -R^T t; each correspondence a track of two rays from the camera centres):
the bilinear relation of eq. 6.5 with the rig's offsets. That algebraic
solution starts a Sampson refinement of t with R held (``mcg_refine_translation``):
the linear |t| is biased short (see :func:`_known`). The metric scale is
returned where the data fix it; in the critical case (no rotation and only
intra-camera rays, ch. 7.3.2, the inhomogeneous term vanishes) the verdict is
"not observable" and ``t`` is the unit direction with the sign that puts the
points in front. ``residual_rms``: RMS Sampson angular residual (radians) at
``info["t_metric"]``; ``info["t_linear"]``: the linear solution.
"""

from __future__ import annotations

from typing import Any, Optional

import numpy as np

from .. import _core, multiview
from ..errors import DegenerateError
from ..observability import critical_angle
from ..registry import register
from ..types import RayPairs, RigMotion, ScaleVerdict
from ._outliers import guard_verdict
from ._static import with_static_check

__all__ = ["known_rotation_translation", "solve", "DEFAULT_ROTATION_STD"]

#: error of the given rotation (radians per axis) when the caller states none:
#: 0.01 deg, a gyro-integrated or ground-truth inter-frame rotation (KITTI OXTS,
#: DDAD poses) is good to about that; pass rotation_std=0 for an exact rotation
DEFAULT_ROTATION_STD = float(np.radians(0.01))

#: the multi-view solver behind this estimator (many views, the four variants of
#: Figs. 6.3-6.6, all pairs or a window, connectivity): see mcgeom.multiview
solve = multiview.translations_from_tracks


def _rotation(rotation: Any) -> np.ndarray:
    if rotation is None:
        raise ValueError("known_rotation_translation needs the rotation: pass rotation=R "
                         "(3x3, rig2_from_rig1)")
    R = np.asarray(rotation, dtype=np.float64)
    if R.shape != (3, 3) or not np.isfinite(R).all():
        raise ValueError(f"rotation must be a finite 3x3 matrix, got shape {R.shape}")
    if np.abs(R.T @ R - np.eye(3)).max() > 1e-6 or np.linalg.det(R) < 0:
        raise ValueError("rotation is not a rotation matrix (R^T R != I or det < 0)")
    return R


@register(
    "known_rotation_translation",
    min_sample=3,
    camera_kinds=("most-general", "locally-central", "axial", "locally-central-and-axial"),
    family="linear",
    needs_rotation=True,
    recovers_scale=True,
    description="translation (metric where observable) for a known rotation: the linear "
                "generalized epipolar constraint / bilinear relation of thesis ch. 6, refined "
                "to its Sampson optimum with R held (so metric from 6 correspondences on)",
    options={"rotation": "the known rotation R (rig2_from_rig1), required",
             "max_rel_std": "relative std of the travelled distance above which the scale "
                            "is reported unobservable (0.1)",
             "rotation_std": "error of the given rotation, radians per axis, propagated "
                             "into rel_std (DEFAULT_ROTATION_STD = 0.01 deg; 0: exact)"},
)
def known_rotation_translation(rays: RayPairs, *, rotation: Any = None,
                               max_rel_std: Optional[float] = None,
                               rotation_std: Optional[float] = None) -> RigMotion:
    """Translation t (metres, rig2_from_rig1: X2 = R X1 + t) of a rig motion with
    known rotation ``rotation`` from >= 3 ray correspondences (rig frame): the
    linear solution of ch. 6 refined to the Sampson optimum with R held
    (:func:`_known`), metric only from 6 correspondences on (fewer: the unit
    direction).

    Returns a ``RigMotion`` with ``R = rotation``; ``info`` holds the
    multi-view result (eigenvalues, timing), the linear solution
    (``t_linear``) and the refinement's summary. When the rotation alone explains
    the intra-camera correspondences (a static rig or a pure rotation, the
    shared test of :mod:`mcgeom.estimators._static`) ``t = 0`` with the
    verdict "no translation detected". ``rotation_std`` (radians per axis,
    default :data:`DEFAULT_ROTATION_STD`): the error of the given rotation,
    propagated to first order into ``rel_std`` and so into the verdict -- near
    the critical motion a rotation error of a few millidegrees moves the
    metric |t| by metres (DDAD scene_02 pair 1-2, intra-camera: |t| 0.025 m
    against 1.265 m with the ground-truth rotation "known"). Raises
    ValueError on bad input.
    """
    if not isinstance(rays, RayPairs):
        raise TypeError(f"rays must be a RayPairs, got {type(rays).__name__}")
    n = len(rays)  # the data are checked before the option, as in every estimator
    if n < 3:
        raise ValueError(f"too few correspondences: known_rotation_translation needs 3, got {n}")
    rays.check_finite()
    R = _rotation(rotation)
    rot_std = DEFAULT_ROTATION_STD if rotation_std is None else rotation_std
    if isinstance(rot_std, (bool, np.bool_)) or not isinstance(rot_std, (int, float, np.number)) \
            or not (np.isfinite(rot_std) and 0 <= rot_std < 0.1):
        raise ValueError(f"rotation_std must be a number of radians in [0, 0.1), got "
                         f"{rotation_std!r}")
    # a static rig: every relation vanishes after the rotation and the solver
    # says they "carry no information" (ValueError; the input was checked above)
    return with_static_check(rays, "known_rotation_translation",
                             lambda: _known(rays, R, max_rel_std, float(rot_std)),
                             errors=(ValueError,),
                             rotation=R)


#: fewest correspondences of the Sampson refinement of t (mcg_refine_translation)
MIN_REFINE = 6


def _rotation_rel_std(info: np.ndarray, t: np.ndarray, rot_std: float) -> float:
    """Relative std of |t| caused by an error of ``rot_std`` radians per axis
    of the given rotation, to first order at the refined t: the optimum moves
    by ``dt = -H_tt^-1 H_tw dw`` (``info`` the 6 x 6 information [dw, dt] of
    the refinement, the implicit function theorem on its normal equations),
    so the std of |t| is ``rot_std |u^T H_tt^-1 H_tw|``, u = t / |t|; inf
    where H_tt is singular."""
    nt = float(np.linalg.norm(t))
    try:
        a = np.linalg.solve(info[3:, 3:], info[3:, :3])
    except np.linalg.LinAlgError:
        return float("inf")
    if not (nt > 0 and np.isfinite(a).all()):
        return float("inf")
    return float(rot_std * np.linalg.norm((t / nt) @ a) / nt)


def _known(rays: RayPairs, R: np.ndarray, max_rel_std: Optional[float],
           rot_std: float = 0.0) -> RigMotion:
    """:func:`known_rotation_translation` on checked input, without the static-rig test.

    The linear solution of ch. 6 minimises an algebraic error, and that pulls
    |t| short wherever the scale rests on the small offset terms of the
    constraint: on a 4-camera ring (radius 0.25 m) turning 3-17 deg, intra-
    camera rays at 0.5 px, |t| came out 6-51 % short (mean 23 %) with a
    relative std of 2-6 %, more than 3 of its stds off in 39 of 40 problems.
    So it is only the start of a Sampson refinement of t with R held
    (``mcg_refine_translation``, the geometric optimum, as linear17 does for
    the 17-point solution of ch. 8): on those 40 problems the refined |t|
    is within 3 stds in all, RMS error 0.97 stds. The verdict and the
    rotation error's share come from that refinement."""
    limit = 0.1 if max_rel_std is None else float(max_rel_std)
    res = _solve(rays, R, max_rel_std)
    t_lin = -R @ res.centres[1]  # c = -R^T t
    v = res.scale
    t, rel, observable, reason = t_lin, v.rel_std, False, v.reason
    ref = None
    if len(rays) < MIN_REFINE:
        reason = (f"{len(rays)} correspondences: too few (< {MIN_REFINE}) to refine the linear "
                  f"scale, which is biased short; t is the unit direction")
    elif not (np.isfinite(t_lin).all() and np.linalg.norm(t_lin) > 0):
        reason = f"{v.reason}; no metric start for the refinement"
    else:
        try:
            ref = _core.refine_translation(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2,
                                           R, t_lin)
        except (ValueError, DegenerateError) as e:
            reason = f"the refinement of t failed ({e}); t is the unit direction"
    if ref is not None:
        t = ref["t"]
        rel = float(ref["scale_rel_std"])
        rel_rot = _rotation_rel_std(ref["information"], t, rot_std) if rot_std > 0 else 0.0
        rel_all = float(np.hypot(rel, rel_rot))
        if not ref["converged"]:
            reason = (f"the refinement of t did not converge ({ref['reason']}); "
                      f"t is the unit direction")
        elif not rel_all <= limit:
            reason = (f"scale too uncertain: relative std {rel_all:.3g} > {limit:g}"
                      + (f" (the given rotation's error, {np.degrees(rot_std):.3g} deg per axis, "
                         f"moves |t| by {100 * rel_rot:.3g} %: rotation_std)"
                         if rot_std > 0 and rel_rot > rel else "")
                      + "; t is the unit direction")
        else:
            observable = True
            reason = (f"metric: relative std {rel_all:.3g} at the Sampson optimum"
                      + ("" if rot_std == 0 else " with the rotation's error"))
        rel = rel_all
    t_metric = np.array(t, float)
    verdict = ScaleVerdict(observable, reason, v.conditioning, rel,
                           critical_angle(rays, R, t))
    # every correspondence was taken as an inlier: a fit pulled by gross
    # outliers is no metric estimate (mcgeom.estimators._outliers; R held)
    guard: dict = {}
    verdict, moved = guard_verdict(rays, R, t, verdict, "known_rotation_translation", limit,
                                   hold_rotation=True, info=guard)
    observable = verdict.observable
    if not observable and np.linalg.norm(t) > 0:
        t = t / np.linalg.norm(t)  # the direction only
    info = {"eigenvalues": res.eigenvalues, "converged": res.converged, "timing": res.timing,
            "metric": observable, "t_linear": t_lin, "outlier_move_stds": moved, **guard,
            "refinement": None if ref is None else
            {k: ref[k] for k in ("iterations", "reason", "rms", "sigma2", "scale_rel_std")}}
    info["t_metric"] = t_metric   # metric estimate, whatever the verdict
    if ref is not None:
        rms = float(ref["rms"])
    elif np.isfinite(t_metric).all():
        rms = float(np.sqrt(np.mean(_core.gec_residuals(rays.origins1, rays.dirs1, rays.origins2,
                                                        rays.dirs2, R, t_metric) ** 2)))
    else:
        rms = float("nan")
    return RigMotion(R.copy(), np.asarray(t, float), verdict, "known_rotation_translation",
                     rms, None, info)


def _solve(rays: RayPairs, R: np.ndarray, max_rel_std: Optional[float]):
    """The two-view case of :func:`mcgeom.multiview.translations_from_tracks`,
    without its bundle adjustment: the estimator refines the linear t itself
    (``_core.refine_translation``: the Sampson optimum of the two views, which
    needs no points)."""
    n = len(rays)
    k = np.arange(n)
    return multiview.translations_from_tracks(
        np.r_[k, k], np.r_[np.zeros(n, np.int64), np.ones(n, np.int64)],
        np.vstack([rays.dirs1, rays.dirs2]), np.stack([np.eye(3), R]),
        origins=np.vstack([rays.origins1, rays.origins2]), relation="bilinear",
        solver="constrained", max_rel_std=0.1 if max_rel_std is None else float(max_rel_std),
        refine=False)
