"""``bnb_lp``: globally optimal L-infinity rig motion by branch and bound (thesis ch. 10).

The search over rotations and its LP feasibility tests run in one C call
(``csrc/bnb.c``, Algorithm 7); this module prepares the rays, chooses the
initial bound, polishes the optimum and builds the scale verdict.

The objective (see bnb.c): for a rotation ``R``, ``f(R)`` is the smallest
angle ``eps`` (radians) such that every correspondence's bearings, each
perturbed by at most ``eps``, admit a common translation ``t`` through the
wedge constraints of eqs. 10.9-10.13 (and every camera keeps a non-zero
baseline direction). The estimator returns the rotation minimising ``f``
(to the requested resolution), the translation of the LP at ``f(R)``, ``f``
itself and a certified lower bound of ``min f`` over all rotations.

Steps:
1. the inliers (``mask``) in a canonical order, so that the result does not
   depend on the order of the correspondences;
2. an initial motion from a registered estimator (default: ``refine``, i.e.
   ``linear17`` then Levenberg-Marquardt; ``five_plus_one`` where linear17
   cannot run; the identity when neither can): its ``f`` is the first bound
   (Algorithm 7, step 1);
3. the global search to ``resolution`` (rad), then local minimisations of
   the L-infinity error over (R, t) jointly (``polish``, in the same C call,
   csrc/linf_local.c: trust-region sequential LP on the closed-form
   per-correspondence errors) from its best rotation and from 12 rotations
   3-100 resolutions around it, each verified by the exact LP test: the
   bottom of the optimum's basin rather than the centre of a block, and the
   lower of nearby basins that the bound cannot tell apart;
4. the initial estimate is kept when its ``f`` equals the optimum within the
   LP precision (noise-free data: both are exact, the smooth one is exact to
   rounding);
5. the scale verdict from the information of the Sampson cost at the result
   (as for every estimator).

Frames and units: rays in the rig frame (metres), motion rig2_from_rig1
(``X2 = R X1 + t``), errors and resolutions in radians.
"""

from __future__ import annotations

from typing import Any, Optional, Union

import numpy as np

from .. import _core
from ..errors import DegenerateError, NumericalError
from ..geometry import refine_centred
from ..observability import scale_verdict
from ..registry import get, register, resolve_lp_backend
from ..types import RayPairs, RigMotion
from ._common import central_travel, travel_direction

__all__ = ["bnb_lp", "linf_error", "apex_groups"]

_MIN_PAIRS = 6
#: f values closer than this (rad) are the same within the LP's precision
_SAME_F = 2e-9

InitialLike = Union[str, RigMotion, tuple, list, None]


def apex_groups(rays: RayPairs) -> np.ndarray:
    """Labels 0..G-1 of the correspondences that share an apex: the same ray
    origins at both times (one camera, or one ordered pair of cameras).

    Labels follow the sorted order of the origin pairs, so they do not depend
    on the order of the correspondences.
    """
    key = np.concatenate([rays.origins1, rays.origins2], axis=1)
    _, labels = np.unique(key, axis=0, return_inverse=True)
    return labels.reshape(-1).astype(np.int32)


def linf_error(rays: RayPairs, R: Any, *, lp_backend: Optional[str] = None,
               tol: float = 1e-11) -> tuple[float, np.ndarray]:
    """``f(R)`` of bnb.c (radians, to ``tol``) and the translation of its LP (metres).

    ``rays`` in the rig frame; ``R`` (3, 3) the rotation rig2_from_rig1.
    """
    sub = rays.take(rays.canonical_order())
    res = _core.bnb_linf(sub.dirs1, sub.origins1, sub.dirs2, sub.origins2,
                         apex_groups(sub), R, max_blocks=0, tol=tol, polish_tol=0.0,
                         lp_backend=resolve_lp_backend(lp_backend))
    return float(res["initial_linf"]), res["t"]


def _objective(rays: RayPairs, R: Any) -> float:
    return linf_error(rays, R, tol=1e-9)[0]


def _initial(rays: RayPairs, initial: InitialLike) -> tuple[np.ndarray, np.ndarray, str]:
    """(R0, t0, source) of the first bound."""
    if isinstance(initial, RigMotion):
        return initial.R, initial.t, initial.method
    if isinstance(initial, (tuple, list)):
        if len(initial) != 2:
            raise ValueError("initial must be an (R, t) pair")
        R0 = np.asarray(initial[0], dtype=np.float64)
        t0 = np.asarray(initial[1], dtype=np.float64)
        if R0.shape != (3, 3) or t0.shape != (3,):
            raise ValueError(f"initial: R must be 3x3 and t a 3-vector, got {R0.shape}, {t0.shape}")
        if not (np.isfinite(R0).all() and np.isfinite(t0).all()):
            raise ValueError("initial: R and t must be finite")
        # the search is global, but its first bound and the kept-initial test
        # use R0 as a rotation: a reflection or a scaled matrix is a mistake
        if _core._not_rotation(R0):
            raise ValueError("initial: R is not a rotation (|R R^T - I| > 1e-6 or det R <= 0)")
        return R0, t0, "given"
    names = [initial] if isinstance(initial, str) else ["refine", "five_plus_one"]
    if initial is not None and not isinstance(initial, str):
        raise ValueError("initial must be None, an estimator name, a RigMotion or an (R, t) "
                         f"pair, got {type(initial).__name__}")
    errors, degenerate = [], []
    for name in names:
        info = get(name)
        if info.name == "bnb_lp":
            raise ValueError("initial: bnb_lp cannot start itself")
        try:
            m = info(rays)
            return m.R, m.t, name
        except (ValueError, DegenerateError, NumericalError) as e:
            errors.append(f"{name}: {e}")
            degenerate.append(isinstance(e, DegenerateError))
    if isinstance(initial, str):
        raise DegenerateError(f"no initial estimate for bnb_lp: {errors[0]}")
    if all(degenerate):
        # every method that could start found the data degenerate: the
        # L-infinity optimum is then a set of rotations, and a search from
        # the identity returns one of them as if it were the motion
        raise DegenerateError("bnb_lp: the data do not determine the motion (" +
                              "; ".join(errors) + ")")
    # the search is global: any start will do, a poor one only costs time
    # (Algorithm 7, step 1: "a random guess if necessary")
    return np.eye(3), np.zeros(3), "identity"


def _cube_rotations() -> list[np.ndarray]:
    """The 24 rotations of the cube (signed permutation matrices, det +1)."""
    out = []
    for perm in ((0, 1, 2), (1, 2, 0), (2, 0, 1), (1, 0, 2), (0, 2, 1), (2, 1, 0)):
        for signs in np.ndindex(2, 2, 2):
            M = np.zeros((3, 3))
            M[range(3), perm] = [1 - 2 * s for s in signs]
            if np.linalg.det(M) > 0:
                out.append(M)
    return out


def _start_from_cube(args: tuple, kw: dict) -> Optional[dict]:
    """bnb_linf from the first rotation of the cube it can start from (None if none)."""
    for Rs in _cube_rotations():
        try:
            res = _core.bnb_linf(*args, Rs, **kw)
        except NumericalError:
            continue
        res["R_init"] = Rs
        return res
    return None


def _inliers(rays: RayPairs, mask: Any) -> np.ndarray:
    n = len(rays)
    if mask is None:
        return np.ones(n, bool)
    m = np.asarray(mask)
    if m.size != n:
        raise ValueError(f"mask must have one entry per correspondence ({n}), got {m.size}")
    return m.reshape(-1).astype(bool)


@register(
    "bnb_lp",
    min_sample=_MIN_PAIRS,
    camera_kinds=("most-general", "locally-central", "axial", "locally-central-and-axial"),
    family="globally-optimal",
    needs_rotation=False,
    recovers_scale=True,
    description="Globally optimal L-infinity motion: branch and bound over rotations with "
                "LP feasibility tests, certified lower bound (thesis ch. 10)",
    options={"initial": "first bound: an estimator name, RigMotion or (R, t); default refine "
                        "(linear17 + LM), else five_plus_one, else the identity",
             "mask": "inliers to use (bool or OpenCV uint8, one per correspondence)",
             "resolution": "rotation resolution of the global search, radians (1e-4)",
             "gap": "stop when no block can improve by more than this, radians (0)",
             "lp_backend": "LP solver: 'native' or 'glpk' (default: the registry's)",
             "preemptive": "per-camera 2-variable tests first (True)",
             "working_sets": "LPs by constraint generation over working sets (True); "
                             "False: every LP on all rows (the thesis's way, same answers)",
             "polish": "local minimisations of the L-infinity error over (R, t) by "
                       "sequential LP around the best rotation (True): the bottom of the "
                       "optimum's basin rather than a block centre",
             "max_blocks": "block budget of the global search (2e6)",
             "max_seconds": "wall-time budget of the global search and polish, seconds "
                            "(0: none); info['stop'] is 'time_limit' when it ended them",
             "max_scale_rel_std": "relative std of |t| above which the scale is reported "
                                  "unobservable (0.1)"},
    objective=_objective,
)
def bnb_lp(rays: RayPairs, *, initial: InitialLike = None, mask: Any = None,
           resolution: float = 1e-4, gap: float = 0.0, lp_backend: Optional[str] = None,
           preemptive: bool = True, working_sets: bool = True, polish: bool = True,
           max_blocks: int = 2_000_000, max_seconds: float = 0.0,
           max_scale_rel_std: float = 0.1) -> RigMotion:
    """Globally optimal L-infinity rig motion rig2_from_rig1 (thesis ch. 10).

    ``rays``: correspondences in the rig frame (metres), outlier-free or with
    ``mask`` selecting the inliers (run :mod:`mcgeom.robust` first on raw
    matches: one outlier sets the L-infinity error). Returns a
    :class:`RigMotion` whose ``info`` holds ``linf`` (f at the returned
    rotation, radians), ``lower_bound`` (certified: no rotation has a smaller
    f), ``gap``, ``initial_linf``, ``initial_method``, ``blocks``, ``leaves``,
    ``lps_2var``, ``lps_3var``, ``seconds`` (C search time), ``stop``,
    ``lp_backend`` and ``t_metric``.
    ``residual_rms`` is the RMS Sampson angular error (radians) of the inliers.
    Raises ValueError for bad input (shape, NaN, too few correspondences, bad
    options), DegenerateError when the named initial estimator fails.
    """
    if not isinstance(rays, RayPairs):
        raise TypeError(f"rays must be a RayPairs, got {type(rays).__name__}")
    rays.check_finite()
    inl = _inliers(rays, mask)
    if inl.sum() < _MIN_PAIRS:
        raise ValueError(f"too few correspondences: bnb_lp needs at least {_MIN_PAIRS} "
                         f"(inliers), got {int(inl.sum())}")
    for name, v, lo, hi in (("resolution", resolution, 1e-12, 1.0), ("gap", gap, 0.0, 1.0)):
        if not (np.isfinite(v) and lo <= v < hi):
            raise ValueError(f"{name} must be in [{lo}, {hi}), got {v}")
    backend = resolve_lp_backend(lp_backend)
    sub = rays.take(np.flatnonzero(inl))
    sub = sub.take(sub.canonical_order())
    groups = apex_groups(sub)
    R0, t0, source = _initial(sub, initial)
    args = (sub.dirs1, sub.origins1, sub.dirs2, sub.origins2, groups)
    kw = dict(resolution=resolution, gap=gap, preemptive=preemptive, working_sets=working_sets,
              max_blocks=max_blocks, lp_backend=backend, polish_tol=1e-9 if polish else 0.0,
              max_seconds=max_seconds)
    try:
        res = _core.bnb_linf(*args, R0, **kw)
    except NumericalError:
        # the kernel needs a start whose error is below ~86 deg for some t (its
        # first bound); far from the motion (e.g. the identity fallback for a
        # rotation near pi) there is none: start from the 24 rotations of the
        # cube instead (every rotation lies within about 63 deg of one of them)
        res = _start_from_cube(args, kw)
        if res is None:
            raise
        R0, t0, source = res["R_init"], None, source + ", then a rotation of the cube"
    R, t, linf = res["R"], res["t"], res["linf"]
    # the initial estimate, when it is as good within the LP's precision
    f0 = res["initial_linf"]
    if t0 is not None and f0 <= linf + _SAME_F:
        R, t, linf, from_initial = np.asarray(R0, float), np.asarray(t0, float), f0, True
    else:
        from_initial = False
    R = _core.project_so3(R)
    rel = float("inf")
    try:
        rel = float(refine_centred(sub, R, t, max_iterations=0)["scale_rel_std"])
    except (ValueError, DegenerateError):
        pass
    verdict = scale_verdict(sub, np.ones(len(sub), bool), R, t, rel, max_scale_rel_std,
                            not np.linalg.norm(t) > 0)
    t_metric = np.array(t)
    if not verdict.observable:
        # central rays (one camera, coincident centres): the L-infinity t is
        # anywhere on the line t + lam u and says nothing of u; the rays do
        central = central_travel(sub, R)
        t = travel_direction(sub, np.ones(len(sub), bool), R, t) if central is None else central
        if not np.linalg.norm(t) > 0 and t0 is not None:
            t = t0 / max(np.linalg.norm(t0), 1e-300)
    r = _core.gec_residuals(sub.origins1, sub.dirs1, sub.origins2, sub.dirs2, R, t_metric)
    info = {
        "linf": linf, "lower_bound": res["lower_bound"],
        "gap": max(linf - res["lower_bound"], 0.0),
        "initial_linf": f0, "initial_method": source, "kept_initial": from_initial,
        "blocks": res["blocks"], "leaves": res["leaves"], "queued": res["queued"],
        "lps_2var": res["lps_2var"], "lps_3var": res["lps_3var"], "hints": res["hints"],
        "seconds": res["seconds"], "stop": res["stop"], "lp_backend": backend,
        "polish_tests": res["polish_tests"],
        "resolution": float(resolution), "n_used": len(sub), "groups": int(groups.max()) + 1,
        "t_metric": t_metric,
    }
    return RigMotion(R, np.asarray(t, float), verdict, "bnb_lp",
                     float(np.sqrt(np.mean(r ** 2))), inl, info)
