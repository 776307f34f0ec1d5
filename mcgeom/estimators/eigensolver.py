"""``eigensolver``: Kneip and Li's eigensolver for multi-camera relative pose (CVPR 2014).

For a rotation ``R`` the generalized epipolar constraints are linear in
``(t, 1)``; the rotation minimises the smallest eigenvalue of their 4 x 4
moment matrix ``M(R)`` and ``t`` is its eigenvector (``csrc/eigensolver.c``,
equations E1-E2 there). A local minimiser of an algebraic cost on all
correspondences: more accurate than the linear 17-point solution it starts
from (it enforces ``R`` in SO(3) and ``E = [t]x R`` exactly), cheaper than the
Sampson refinement, which ``refine=True`` runs after it.

In RANSAC (``mcgeom.robust.ransac(rays, "eigensolver")``) its samples of 17
correspondences run in the C entry point (``mcg_robust_rig_motion`` with
``MCG_SAMPLER_EIGEN``: linear17's rotation, then the eigensolver from it, as
:func:`minimal_solutions` here, which the Python driver
``strategy="minimal"`` still calls).

Frames and units (docs/architecture.md §3): rays in the rig frame (metres),
``X2 = R X1 + t`` with ``t`` in metres.
"""

from __future__ import annotations

from typing import Any, Optional

import numpy as np

from .. import _core
from ..errors import DegenerateError
from ..geometry import centroid_travel
from ..registry import register
from ..types import RayPairs, RigMotion
from ..validation import check_rotation
from ._finish import refine_and_report
from ._start import best_start
from .linear17 import linear17_start

__all__ = ["eigensolver", "minimal_solutions"]


def _start(rays: RayPairs, rotation_start: Any) -> np.ndarray:
    """The start rotation: the given one, else linear17's."""
    if rotation_start is not None:
        return check_rotation("rotation_start", rotation_start)
    return linear17_start(rays).R


def _default_starts(rays: RayPairs) -> list[np.ndarray]:
    """The start rotations of the estimator without ``rotation_start``:
    linear17's (the paper's) and that of the best available estimate
    (:func:`mcgeom.estimators._start.best_start`: 5+1 or linear17, lower robust
    cost), when it differs.

    Why two: near pure forward motion with intra-camera rays the smallest
    eigenvalue has the trivial minimum R = I, t = 0 (every such ray fits it)
    within a fraction of a degree of the truth, and is nearly flat between
    them (Kneip and Li 2014, sec. 4: the rotation trades against the
    translation direction). The minimiser then slides into the trap from
    either start and the start is kept (``_solve``); linear17's rotation is
    0.119 deg off on KITTI raw 0023 driving straight, 5+1's 0.002 deg. The
    Sampson cost of :func:`refine_and_report` decides between the results.
    """
    R_lin, failure = None, None
    try:
        R_lin = linear17_start(rays).R
    except (DegenerateError, ValueError) as e:
        failure = e
    try:
        R_best = best_start(rays)[0].R
    except DegenerateError:
        R_best = None
    starts = [R for R in (R_lin, R_best) if R is not None]
    if failure is not None and not starts:
        raise failure   # linear17's own diagnosis (e.g. the degenerate geometry it met)
    if len(starts) == 2 and np.allclose(starts[0], starts[1], rtol=0.0, atol=1e-12):
        starts = starts[:1]
    return starts


def _solve(rays: RayPairs, rotation_start: Any, max_iterations: int) -> dict:
    """The eigensolver from ``rotation_start`` (None: linear17's rotation)."""
    R0 = _start(rays, rotation_start)
    args = (rays.origins1, rays.dirs1, rays.origins2, rays.dirs2)
    r = _core.eigensolver(*args, R0, max_iterations)
    r["trivial_avoided"] = False
    if max_iterations > 0 and r["has_scale"]:
        # The no-motion trap of intra-camera rays (csrc/eigensolver.c): a
        # result whose centroid hardly travels, from a start that clearly did,
        # is that trivial solution, not the motion: keep the start.
        r0 = _core.eigensolver(*args, R0, 0)
        if r0["has_scale"] and (centroid_travel(rays, r["R"], r["t"])
                                < 1e-2 * centroid_travel(rays, r0["R"], r0["t"])):
            r0["trivial_avoided"] = True
            return r0
    return r


def minimal_solutions(sample: RayPairs) -> list[tuple[np.ndarray, np.ndarray]]:
    """The motion of a 17-correspondence sample for RANSAC: the eigensolver from
    the linear 17-point rotation (none if the sample is degenerate)."""
    try:
        r = _solve(sample, None, 100)
    except (DegenerateError, ValueError):
        return []
    return [(r["R"], r["t"])] if r["has_scale"] else []


@register(
    "eigensolver",
    min_sample=17,
    camera_kinds=("most-general", "locally-central", "axial", "locally-central-and-axial"),
    family="linear",
    needs_rotation=False,
    recovers_scale=True,
    description="Kneip-Li eigensolver: the rotation minimising the smallest eigenvalue of the "
                "generalized-epipolar matrix (LM from linear17 or a given start), t from its "
                "eigenvector",
    options={"rotation_start": "start rotation (default: both linear17's and that of the "
                                "best available estimate, 5+1 or linear17; the lower Sampson "
                                "cost wins)",
             "refine": "joint Sampson refinement after it (default False; without it the "
                       "std of |t| also counts the distance to the Sampson optimum)",
             "max_iterations": "cap on the Levenberg-Marquardt steps (100)",
             "max_scale_rel_std": "relative std of |t| above which the scale is reported "
                                  "unobservable (0.1)"},
    minimal_solver=minimal_solutions,
)
def eigensolver(rays: RayPairs, *, rotation_start: Any = None, refine: bool = False,
                max_iterations: Optional[int] = None,
                max_scale_rel_std: float = 0.1) -> RigMotion:
    """Rig motion rig2_from_rig1 (R, t in metres) by Kneip and Li's eigensolver.

    ``rays`` in the rig frame (origins at the camera centres, metres). The
    rotation minimises the smallest eigenvalue of ``M(R) = sum v v^T``, ``v =
    (R d1 x d2, d2 . R m1 + m2 . R d1)`` (origins centred and scaled, unit
    directions), by Levenberg-Marquardt from ``rotation_start``, or else from
    two starts: linear17's rotation (at least 17 correspondences then, 14 for
    some camera kinds) and that of the best available estimate
    (:func:`mcgeom.estimators._start.best_start`); ``t`` comes from the
    eigenvector. With intra-camera rays only the cost has a trivial minimum at
    no motion: a result that slid into it is replaced by its start
    (``info["trivial_avoided"]``). Of the runs' results the one of least
    Sampson angular cost is kept; ``refine`` then refines all six degrees of
    freedom on that error. The verdict rests on the covariance of the
    Sampson cost at the result; without ``refine`` the relative std of |t|
    also counts the result's distance from the Sampson optimum
    (``info["move_to_optimum"]``), whose covariance that is. ``info``:
    ``lambda_min`` (the algebraic cost left) and ``iterations`` of the run of
    least algebraic cost, ``starts``.
    Raises ValueError for bad input, DegenerateError when no start is found.
    """
    if not isinstance(rays, RayPairs):
        raise TypeError(f"rays must be a RayPairs, got {type(rays).__name__}")
    n = len(rays)
    if rotation_start is None and n < 14:
        raise ValueError(f"too few correspondences: eigensolver starts from linear17, which "
                         f"needs at least 17 (14-16 for some camera kinds), got {n}; or pass "
                         "rotation_start=")
    if n < 6:
        raise ValueError(f"too few correspondences: eigensolver needs at least 6, got {n}")
    if max_iterations is None:
        max_iterations = 100
    if not (np.isfinite(max_scale_rel_std) and max_scale_rel_std > 0):
        raise ValueError(f"max_scale_rel_std must be a positive number, got {max_scale_rel_std}")
    rays.check_finite()
    starts = [rotation_start] if rotation_start is not None else _default_starts(rays)
    runs = [_solve(rays, R0, max_iterations) for R0 in starts]
    # every run's end point goes to the Sampson comparison (ties: the first,
    # linear17's); info describes the run of least algebraic cost
    r = min(runs, key=lambda x: x["lambda_min"])
    info: dict = {"lambda_min": r["lambda_min"], "iterations": r["iterations"],
                  "has_scale": r["has_scale"], "trivial_avoided": r["trivial_avoided"],
                  "starts": len(runs)}
    return refine_and_report(rays, [(x["R"], x["t"]) for x in runs], "eigensolver",
                             max_scale_rel_std, info, iterate=bool(refine))
