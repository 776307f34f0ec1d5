"""``bnb_lp``: globally optimal L-infinity rig motion by branch and bound (thesis ch. 10).

The search over rotations and its LP feasibility tests run in one C call
(``csrc/bnb.c``, Algorithm 7); this module prepares the rays, chooses the
initial bound, polishes the optimum and builds the scale verdict.

The objective (see bnb.c): for a rotation ``R``, ``f(R)`` is the smallest
angle ``eps`` (radians) such that every correspondence's bearings, each
perturbed by at most ``eps``, admit a common translation ``t`` through the
wedge constraints of eqs. 10.9-10.13 (capped where the two bearings are
more than 90 deg apart, bnb.c's ``cap_rows``; and every camera keeps a
non-zero baseline direction). The estimator returns the rotation minimising ``f``
(to the requested resolution), the translation of the LP at ``f(R)``, ``f``
itself and a certified lower bound of ``min f`` over all rotations.

Steps:
1. the inliers (``mask``) in a canonical order, so that the result does not
   depend on the order of the correspondences;
2. an initial motion (Algorithm 7, step 1): by default the best available
   one, :func:`mcgeom.estimators._start.best_start` (5+1 and linear17, the
   lower robust cost); the identity when neither can run (the search is
   global: a poor start only costs time);
3. the domain: the objective needs a non-zero baseline for every camera.
   A rig that did not translate is outside it (its wedges collapse onto
   their apexes and any rotation that a tiny baseline of free direction
   explains is as good: measured 11 deg on the parked DDAD scene, with a
   "certified" bound). The shared static test
   (:func:`mcgeom.estimators._static.check_static`: a pure rotation explains
   the intra-camera correspondences as well as the start) gives those data
   the static answer (R, ``t = 0``, "no translation detected") without a
   search;
4. the residual-outlier guard (``prune``): the correspondences whose
   :func:`wedge_errors` at the start exceed ``prune_sigmas`` robust standard
   deviations of those errors are dropped (L-infinity follows the worst
   correspondence; a point that passes the epipolar test of RANSAC but lies
   behind a camera has a large wedge error and a small Sampson error);
5. the global search to ``resolution`` (rad), then local minimisations of
   the L-infinity error over (R, t) jointly (``polish``, in the same C call,
   csrc/linf_local.c: trust-region sequential LP on the closed-form
   per-correspondence errors) from its best rotation and from 12 rotations
   3-100 resolutions around it, each verified by the exact LP test: the
   bottom of the optimum's basin rather than the centre of a block, and the
   lower of nearby basins that the bound cannot tell apart;
6. while the optimum's error is above the guard's level, its support set
   (the correspondences within 1e-8 rad of it) is dropped and the search run
   again (Sim and Hartley, "Removing outliers using the L-infinity norm",
   CVPR 2006: if the data hold an outlier, the support set holds one); at
   most 3 searches and ``max_pruned`` of the correspondences;
7. the initial estimate is kept when its ``f`` equals the optimum within the
   LP precision (noise-free data: both are exact, the smooth one is exact to
   rounding);
8. the scale verdict from the information of the Sampson cost at the
   least-squares optimum refined from the result, with the deviation of the
   result's travel from that optimum's added to the relative std
   (:func:`_scale_rel_std`: the L-infinity optimum scatters wider than the
   least-squares one; ``info["scale_linf_vs_l2"]``).

The guard's default level (5 robust sigmas: beyond it a Gaussian error has
probability 6e-7) was chosen on the real recordings: at the 5+1 start the
largest wedge error of 300 inliers is 10-16 times the median (7-11 sigmas)
on the KITTI raw pairs, 1760 times on the pair with a residual outlier (0.2
rad), 100-1600 times on the synthetic Ladybug trials with one (``mcgeom
experiment bnb_real --ladybug``), 3.7-5 times (2.5-3.4 sigmas) on clean
synthetic data. The real tails beyond 5 sigmas (calibration error,
near-mismatches) pull the L-infinity optimum: on the KITTI raw fixture of the
real-data check (200 inliers, intra + cross-camera) the rotation error is
0.166 deg with the level at 15 or 8 sigmas, 0.064 deg at 5 (4 dropped);
on four KITTI raw pairs of ``bnb_real`` 0.048/0.030/0.056/0.053 deg at 15,
0.031/0.045/0.009/0.010 at 5 (2-8 of 300 dropped).

Frames and units: rays in the rig frame (metres), motion rig2_from_rig1
(``X2 = R X1 + t``), errors and resolutions in radians.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Optional, Union

import numpy as np

from .. import _core
from ..errors import DegenerateError, NumericalError
from ..geometry import centroid_travel, refine_centred
from ..observability import scale_verdict
from ..registry import get, register, resolve_lp_backend
from ..types import RayPairs, RigMotion, ScaleVerdict
from ._common import central_travel, travel_direction
from ._start import START_CANDIDATES, best_start
from ._static import check_static

__all__ = ["bnb_lp", "linf_error", "apex_groups", "wedge_errors"]

_MIN_PAIRS = 6
#: f values closer than this (rad) are the same within the LP's precision
_SAME_F = 2e-9
#: 1 / the median of |N(0, 1)|: a robust standard deviation from a median
_MAD_TO_STD = 1.4826
#: the outlier guard's level is never below this (radians): noise-free data
#: have errors at rounding level, where "5 sigma" would drop exact inliers
_PRUNE_FLOOR = 1e-7
#: searches of the outlier guard (the first and at most two re-solves)
_MAX_ROUNDS = 3
#: a translation below this fraction of the rig's size (or of the start's
#: |t|) is the apex of the intra-camera wedges, not a direction
_AT_APEX = 1e-6
#: correspondences within this (rad) of the optimum's error are its support
#: set (the LP's and the bisection's precision)
_PINNED = 1e-8

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


def wedge_errors(rays: RayPairs, R: Any, t: Any) -> np.ndarray:
    """Per-correspondence L-infinity error (radians) of the motion ``(R, t)``.

    ``e_i`` is the smallest equal perturbation of both bearings of
    correspondence ``i`` for which ``t`` (metres, rig2_from_rig1, ``X2 = R X1 +
    t``) lies in its wedge (eqs. 10.9-10.13, the rows of bnb.c): the closed form
    of csrc/linf_local.c, ``sin e = sin(alpha / 2) |w^.b| / sqrt((m^.b)^2 +
    (w^.b)^2)`` with ``b = t - (a2 - R a1)``, ``m = u2 - R u1``, ``w = R u1 x
    u2`` and ``alpha`` the angle between ``R u1`` and ``u2``; ``e = alpha / 2``
    where ``b`` points behind the wedge (``m^.b <= 0``: a cheirality
    violation), 0 at the apex. ``max_i e_i`` over the correspondences is the
    L-infinity error of ``(R, t)`` without the per-camera non-zero-baseline
    condition. ``rays`` in the rig frame (metres).
    """
    R = np.asarray(R, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64).reshape(3)
    u1 = rays.dirs1 / np.linalg.norm(rays.dirs1, axis=1, keepdims=True)
    u2 = rays.dirs2 / np.linalg.norm(rays.dirs2, axis=1, keepdims=True)
    v = u1 @ R.T
    b = t - (rays.origins2 - rays.origins1 @ R.T)
    m = u2 - v
    w = np.cross(v, u2)
    nm = np.linalg.norm(m, axis=1)
    nw = np.linalg.norm(w, axis=1)
    half = np.arcsin(np.clip(0.5 * nm, 0.0, 1.0))
    with np.errstate(invalid="ignore", divide="ignore"):
        p = np.einsum("ij,ij->i", m, b) / nm
        q = np.abs(np.einsum("ij,ij->i", w, b)) / nw
        rho = np.hypot(p, q)
        inside = np.arcsin(np.clip(np.sin(half) * q / rho, 0.0, 1.0))
    # parallel rays (w = 0): the wedge is the half-space in front, error 0
    # there and alpha / 2 (= 0 or pi / 2) behind
    inside = np.where(nw > 0, inside, 0.0)
    e = np.where(p > 0, inside, half)
    return np.where((rho > 0) & (nm > 0), e, 0.0)


def _objective(rays: RayPairs, R: Any) -> float:
    return linf_error(rays, R, tol=1e-9)[0]


@dataclass
class _Start:
    """The first bound of the search: rotation ``R``, metric translation ``t``
    (None when unknown), where it came from, and the start's own motion
    (None for a given (R, t) pair)."""

    R: np.ndarray
    t: Optional[np.ndarray]
    source: str
    motion: Optional[RigMotion]


def _metric_t(m: RigMotion) -> np.ndarray:
    """The metric translation of a motion whatever its verdict (``t`` when
    observable, else ``info["t_metric"]`` when the estimator kept one)."""
    tm = m.info.get("t_metric") if isinstance(m.info, dict) and not m.scale.observable else None
    if tm is not None and np.all(np.isfinite(np.asarray(tm, dtype=np.float64))):
        return np.asarray(tm, dtype=np.float64).reshape(3)
    return np.asarray(m.t, dtype=np.float64).reshape(3)


def _initial(rays: RayPairs, initial: InitialLike) -> Optional[_Start]:
    """The start of the search; None when every default start found the data
    degenerate (then the data are static, or nothing determines the motion)."""
    if isinstance(initial, RigMotion):
        return _Start(initial.R, _metric_t(initial), initial.method, initial)
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
        return _Start(R0, t0, "given", None)
    if initial is not None and not isinstance(initial, str):
        raise ValueError("initial must be None, an estimator name, a RigMotion or an (R, t) "
                         f"pair, got {type(initial).__name__}")
    if isinstance(initial, str):
        info = get(initial)
        if info.name == "bnb_lp":
            raise ValueError("initial: bnb_lp cannot start itself")
        try:
            m = info(rays)
        except (ValueError, DegenerateError, NumericalError) as e:
            raise DegenerateError(f"no initial estimate for bnb_lp: {initial}: {e}") from None
        return _Start(m.R, _metric_t(m), initial, m)
    return _default_start(rays)


def _default_start(rays: RayPairs) -> Optional[_Start]:
    """The best available start (:func:`best_start`: 5+1 and linear17, the
    lower robust cost); the identity when neither can run but not every one
    found the data degenerate (the search is global: a poor start only costs
    time, Algorithm 7, step 1: "a random guess if necessary"); None when every
    candidate found the data degenerate."""
    try:
        m, report = best_start(rays)
    except DegenerateError:
        pass
    else:
        return _Start(m.R, _metric_t(m), report["chosen"], m)
    degenerate = []
    for name in START_CANDIDATES:
        try:
            get(name)(rays)
        except DegenerateError:
            degenerate.append(True)
        except (ValueError, NumericalError):
            degenerate.append(False)
    if all(degenerate):
        return None
    return _Start(np.eye(3), None, "identity", None)


def _static_answer(rays: RayPairs, start: Optional[_Start]) -> Optional[RigMotion]:
    """The static answer (R, t = 0, "no translation detected") when a pure
    rotation explains the intra-camera correspondences as well as the start
    does (:func:`check_static`, the test every estimator shares), else None.
    Raises DegenerateError when there is no start and the data are not static."""
    full = start.motion if start is not None else None
    if full is None and start is not None and start.t is not None:
        # a given (R, t): the test measures the noise at that rotation
        full = RigMotion(np.asarray(start.R), np.asarray(start.t), ScaleVerdict(True, "given"),
                         "given", float("nan"), None, {})
    static = check_static(rays, "bnb_lp", full)
    if static is None and start is None:
        raise DegenerateError("bnb_lp: the data do not determine the motion (every start "
                              f"estimator, {', '.join(START_CANDIDATES)}, found them degenerate, "
                              "and a pure rotation does not explain them)")
    return static


def _search(rays: RayPairs, R0: np.ndarray, t0: Optional[np.ndarray], source: str,
            kw: dict) -> tuple[dict, np.ndarray, Optional[np.ndarray], str]:
    """One global search (bnb.c) from ``R0``: (result, start rotation, start t,
    start name). The kernel needs a start whose error is below ~86 deg for some
    t (its first bound); far from the motion (e.g. the identity fallback for a
    rotation near pi) there is none: then the search starts from the 24
    rotations of the cube (every rotation lies within about 63 deg of one)."""
    args = (rays.dirs1, rays.origins1, rays.dirs2, rays.origins2, apex_groups(rays))
    try:
        return _core.bnb_linf(*args, R0, **kw), R0, t0, source
    except NumericalError:
        res = _start_from_cube(args, kw)
        if res is None:
            raise
        return res, res["R_init"], None, source + ", then a rotation of the cube"


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


def _check_options(resolution: float, gap: float, tol: float, max_blocks: Any,
                   max_seconds: float, prune: bool, prune_sigmas: float,
                   max_pruned: float) -> None:
    """ValueError naming the option for every out-of-range option of bnb_lp."""
    for name, v, lo, hi in (("resolution", resolution, 1e-12, 1.0), ("gap", gap, 0.0, 1.0),
                            ("tol", tol, 1e-15, 1e-2), ("max_pruned", max_pruned, 0.0, 0.5)):
        if isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)) \
                or not (np.isfinite(v) and lo <= v < hi):
            raise ValueError(f"{name} must be a number in [{lo}, {hi}), got {v!r}")
    if isinstance(max_blocks, bool) or not isinstance(max_blocks, (int, np.integer)) \
            or max_blocks < 1:
        raise ValueError(f"max_blocks must be an integer >= 1 (the block budget of the global "
                         f"search), got {max_blocks!r}")
    if isinstance(max_seconds, bool) or not isinstance(max_seconds, (int, float, np.floating,
                                                                      np.integer)) \
            or not (np.isfinite(max_seconds) and 0.0 <= max_seconds <= 1e9):
        raise ValueError(f"max_seconds must be a number of seconds in [0, 1e9] (0: no limit), "
                         f"got {max_seconds!r}")
    if not isinstance(prune, (bool, np.bool_)):
        raise ValueError(f"prune must be True or False, got {prune!r}")
    if isinstance(prune_sigmas, bool) or not isinstance(prune_sigmas, (int, float, np.floating,
                                                                        np.integer)) \
            or not (np.isfinite(prune_sigmas) and prune_sigmas >= 3.0):
        raise ValueError(f"prune_sigmas must be a number >= 3, got {prune_sigmas!r}")


def _prune_level(rays: RayPairs, R0: np.ndarray, t0: Optional[np.ndarray],
                 sigmas: float) -> tuple[float, np.ndarray]:
    """(tau, e0): the outlier level (radians) and the wedge errors of the start.

    ``e0`` = :func:`wedge_errors` at the start ``(R0, t0)`` (a robust
    least-squares motion, not pulled by one correspondence as the L-infinity
    optimum is); ``tau`` = ``sigmas`` robust standard deviations of ``e0``
    (1.4826 x its median). inf when the start has no metric translation."""
    if t0 is None or not np.all(np.isfinite(t0)):
        return float("inf"), np.zeros(len(rays))
    e0 = wedge_errors(rays, R0, t0)
    return max(sigmas * _MAD_TO_STD * float(np.median(e0)), _PRUNE_FLOOR), e0


def _worst(e: np.ndarray, level: float, budget: int) -> np.ndarray:
    """Indices of the correspondences with ``e > level``, the worst ``budget`` at most."""
    idx = np.flatnonzero(e > level)
    if idx.size > budget:
        idx = idx[np.argsort(-e[idx], kind="stable")[:budget]]
    return np.sort(idx)


def _scale_rel_std(rays: RayPairs, R: np.ndarray, t: np.ndarray) -> tuple[float, float]:
    """The relative std of the cameras' travel |t + R c - c| (c their
    centroid) at the L-infinity motion (R, t), metres, on the correspondences
    it used: ``(rel_std, deviation)``. The Sampson refinement's first-order
    std is that of the least-squares optimum; the L-infinity optimum, ruled
    by the few largest errors, scatters wider (clean synthetic data, a
    4-camera ring with intra-camera rays at 0.5 px, 30 problems: 9 of the 27
    called metric were more than 3 of that std off, RMS 2.8 stds). So the
    refinement is run to the least-squares optimum from (R, t), and the
    relative deviation of the L-infinity travel from its travel is added in
    quadrature (on those problems: none more than 3 stds off, RMS 0.96). inf
    where the refinement fails."""
    try:
        fit = refine_centred(rays, R, t)
    except (ValueError, DegenerateError):
        return float("inf"), float("inf")
    travel = centroid_travel(rays, R, t)
    travel_l2 = centroid_travel(rays, fit["R"], fit["t"])
    if not (travel_l2 > 0 and np.isfinite(travel)):
        return float("inf"), float("inf")
    dev = abs(travel / travel_l2 - 1.0)
    return float(np.hypot(float(fit["scale_rel_std"]), dev)), dev


@register(
    "bnb_lp",
    min_sample=_MIN_PAIRS,
    camera_kinds=("most-general", "locally-central", "axial", "locally-central-and-axial"),
    family="globally-optimal",
    needs_rotation=False,
    recovers_scale=True,
    description="Globally optimal L-infinity motion: branch and bound over rotations with "
                "LP feasibility tests, certified lower bound (thesis ch. 10)",
    options={"initial": "first bound: an estimator name, RigMotion or (R, t); default the "
                        "lower robust cost of five_plus_one and linear17, else the identity",
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
             "max_blocks": "block budget of the global search, an integer >= 1 (2e6)",
             "tol": "bisection tolerance of the error bounds, radians, in [1e-15, 1e-2) (1e-9)",
             "prune": "residual-outlier guard (True): drop the correspondences far outside "
                      "the start's error distribution, and those the L-infinity optimum is "
                      "pinned to while it stays above that level (Sim and Hartley), re-solve",
             "prune_sigmas": "the guard's level in robust standard deviations of the start's "
                             "per-correspondence errors (5, >= 3)",
             "max_pruned": "most correspondences the guard may drop, a fraction in [0, 0.5) "
                           "(0.1)",
             "max_seconds": "wall-time budget of each global search and polish, seconds "
                            "in [0, 1e9] (0: none); info['stop'] is 'time_limit' when it "
                            "ended them",
             "max_scale_rel_std": "relative std of |t| above which the scale is reported "
                                  "unobservable (0.1)"},
    objective=_objective,
)
def bnb_lp(rays: RayPairs, *, initial: InitialLike = None, mask: Any = None,
           resolution: float = 1e-4, gap: float = 0.0, lp_backend: Optional[str] = None,
           preemptive: bool = True, working_sets: bool = True, polish: bool = True,
           max_blocks: int = 2_000_000, max_seconds: float = 0.0, tol: float = 1e-9,
           prune: bool = True, prune_sigmas: float = 5.0, max_pruned: float = 0.1,
           max_scale_rel_std: float = 0.1) -> RigMotion:
    """Globally optimal L-infinity rig motion rig2_from_rig1 (thesis ch. 10).

    ``rays``: correspondences in the rig frame (metres), outlier-free or with
    ``mask`` selecting the inliers (run :mod:`mcgeom.robust` first on raw
    matches: one outlier sets the L-infinity error). Returns a
    :class:`RigMotion` whose ``info`` holds ``linf`` (f at the returned
    rotation, radians), ``lower_bound`` (certified: no rotation has a smaller
    f on the correspondences used), ``gap``, ``initial_linf``,
    ``initial_method``, ``blocks``, ``leaves``, ``lps_2var``, ``lps_3var``,
    ``seconds`` (C search time, all rounds), ``stop``, ``lp_backend``,
    ``t_metric``, ``domain`` ("moving" or "static") and the outlier guard's
    ``pruned`` (count), ``pruned_index`` (indices into ``rays``),
    ``prune_level`` (radians) and ``rounds``.
    ``residual_rms`` is the RMS Sampson angular error (radians) of the inliers;
    ``inliers`` excludes the correspondences the guard dropped.

    Domain: the objective (bnb.c) needs a non-zero baseline for every camera.
    A rig that did not translate (parked car, pure rotation) is outside it:
    there the wedges of each camera collapse onto their apex and the search
    returns any rotation that a tiny baseline of free direction explains, with
    a certificate that says nothing about the motion. Such data are recognised
    before the search (a pure rotation explains the intra-camera
    correspondences as well as the start does) and get the static answer: the
    rotation, ``t = 0``, the verdict "no translation detected"
    (``info["domain"] == "static"``).

    Residual outliers (``prune``): L-infinity follows the worst
    correspondence, so one outlier that passed RANSAC's epipolar test (e.g. a
    point behind a camera, which the Sampson distance does not see) moves the
    optimum by degrees. The guard drops the correspondences whose error at the
    start is above ``prune_sigmas`` robust standard deviations of the start's
    errors, and, after the search, while the optimum's error is still above
    that level, the correspondences it is pinned to (Sim and Hartley, CVPR
    2006: the support set of an L-infinity optimum holds an outlier if any
    correspondence is one), then searches again; at most ``max_pruned`` of the
    correspondences and 3 rounds.

    Raises ValueError for bad input (shape, NaN, too few correspondences, bad
    options, naming the option), DegenerateError when the named initial
    estimator fails or no start exists on data that are not static.
    """
    if not isinstance(rays, RayPairs):
        raise TypeError(f"rays must be a RayPairs, got {type(rays).__name__}")
    rays.check_finite()
    _check_options(resolution, gap, tol, max_blocks, max_seconds, prune, prune_sigmas,
                   max_pruned)
    inl = _inliers(rays, mask)
    if inl.sum() < _MIN_PAIRS:
        raise ValueError(f"too few correspondences: bnb_lp needs at least {_MIN_PAIRS} "
                         f"(inliers), got {int(inl.sum())}")
    backend = resolve_lp_backend(lp_backend)
    used = np.flatnonzero(inl)
    order = rays.take(used).canonical_order()
    used = used[order]
    sub = rays.take(used)
    start = _initial(sub, initial)
    static = _static_answer(sub, start)
    if static is not None:
        mask_out = np.zeros(len(rays), bool)
        mask_out[used] = True
        return RigMotion(static.R, static.t, static.scale, "bnb_lp", static.residual_rms,
                         mask_out, {**static.info, "domain": "static", "n_used": len(sub),
                                    "pruned": 0, "pruned_index": np.zeros(0, np.int64)})
    R0, t0, source = start.R, start.t, start.source   # not None: _static_answer raised
    # bound_steps=0: a split block's children inherit its bound instead of one
    # more relaxed test each to order the heap; with the start's incumbent
    # (best_start) the search examines the same blocks (KITTI raw, 300
    # inliers, gap 1e-4: 48050 either way) and saves those tests (1.54 ->
    # 1.17 s CPU on pair 0-1 intra-only)
    kw = dict(bound_steps=0, resolution=resolution, gap=gap, tol=tol, preemptive=preemptive,
              working_sets=working_sets, max_blocks=int(max_blocks), lp_backend=backend,
              polish_tol=1e-9 if polish else 0.0, max_seconds=float(max_seconds))
    keep = np.ones(len(sub), bool)
    level = float("inf")
    budget = min(int(max_pruned * len(sub)), len(sub) - _MIN_PAIRS)
    if prune and budget > 0:
        level, e0 = _prune_level(sub, R0, t0, prune_sigmas)
        keep[_worst(e0, level, budget)] = False
    totals = {"blocks": 0, "leaves": 0, "lps_2var": 0, "lps_3var": 0, "hints": 0,
              "seconds": 0.0, "polish_tests": 0}
    rounds = 0
    while True:
        cur = sub.take(np.flatnonzero(keep))
        res, R0_used, t0_used, src = _search(cur, R0, t0, source, kw)
        rounds += 1
        for k in totals:
            totals[k] += res[k]
        if not (prune and res["linf"] > level and rounds < _MAX_ROUNDS):
            break
        # Sim and Hartley: the correspondences the optimum is pinned to
        e = wedge_errors(cur, res["R"], res["t"])
        pinned = np.flatnonzero(keep)[e >= res["linf"] - _PINNED]
        room = budget - int(np.count_nonzero(~keep))
        if pinned.size == 0 or pinned.size > room:
            break
        keep[pinned] = False
    R, t, linf = res["R"], res["t"], res["linf"]
    # the initial estimate, when it is as good within the LP's precision
    f0 = res["initial_linf"]
    if t0_used is not None and f0 <= linf + _SAME_F:
        R, t, linf, from_initial = (np.asarray(R0_used, float), np.asarray(t0_used, float), f0,
                                    True)
    else:
        from_initial = False
    R = _core.project_so3(R)
    cur = sub.take(np.flatnonzero(keep))
    rel, linf_vs_l2 = _scale_rel_std(cur, R, t)
    verdict = scale_verdict(cur, np.ones(len(cur), bool), R, t, rel, max_scale_rel_std,
                            not np.linalg.norm(t) > 0)
    t_metric = np.array(t)
    if not verdict.observable:
        # central rays (one camera, coincident centres): the L-infinity t is
        # anywhere on the line t + lam u and says nothing of u; the rays do
        central = central_travel(cur, R)
        hint = t
        size = float(np.sqrt(np.mean(np.sum((cur.origins1 - cur.origins1.mean(axis=0)) ** 2,
                                            axis=1))))
        if t0_used is not None and not np.linalg.norm(t) > _AT_APEX * max(
                size, float(np.linalg.norm(t0_used))):
            # the LP's t sits on the apexes (intra-camera rays at R = I: every
            # apex is 0, and the wedges are closed cones there) and says
            # nothing of the direction; the start's does
            hint = t0_used
        t = travel_direction(cur, np.ones(len(cur), bool), R, hint) if central is None \
            else central
    r = _core.gec_residuals(cur.origins1, cur.dirs1, cur.origins2, cur.dirs2, R, t_metric)
    mask_out = np.zeros(len(rays), bool)
    mask_out[used[keep]] = True
    pruned_index = np.sort(used[~keep])
    info = {
        "linf": linf, "lower_bound": res["lower_bound"],
        "gap": max(linf - res["lower_bound"], 0.0),
        "initial_linf": f0, "initial_method": src, "kept_initial": from_initial,
        "queued": res["queued"], "stop": res["stop"], "lp_backend": backend,
        **totals,
        "resolution": float(resolution), "n_used": len(cur),
        "groups": int(apex_groups(cur).max()) + 1, "t_metric": t_metric, "domain": "moving",
        "pruned": int(pruned_index.size), "pruned_index": pruned_index,
        "prune_level": level, "rounds": rounds, "scale_linf_vs_l2": linf_vs_l2,
    }
    return RigMotion(R, np.asarray(t, float), verdict, "bnb_lp",
                     float(np.sqrt(np.mean(r ** 2))), mask_out, info)
