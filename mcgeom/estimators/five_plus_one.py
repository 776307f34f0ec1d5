"""``five_plus_one``: the 5+1 method of thesis ch. 7 (5 points in one camera, 1 in another).

The registered estimator and its robust search. The pieces live in:

* :mod:`mcgeom.estimators.essential`: the rotation and the translation line
  ``t(lam) = t0 + lam w`` from the essential matrix of one camera ``a``
  (OpenCV's 5-point solver, decomposed with the cheirality check of
  ``cv2.recoverPose``);
* :mod:`mcgeom.estimators.five_plus_one_minimal`: eq. 7.4, the metric scale
  ``lam`` from any other correspondence (written for any camera pair of the
  rig and for cross-camera correspondences), the minimal solver and sampler;
* here: :func:`five_plus_one` on all correspondences (the least-squares
  ``lam = -sum(a b) / sum(b^2)`` of eq. 7.4 over every correspondence not of
  camera ``a``, then a joint refinement), and :func:`propose`, the two-stage
  RANSAC of ch. 7.4 (USAC 5-point search, then a 1-point scale RANSAC).

Critical configuration (ch. 7.3.2, Theorem 3): camera ``b`` can fix the scale
only if the line of its possible positions ``R^T (c_b - t(lam))`` misses its
first position ``c_b``, i.e. unless the displacements ``delta(c) = R^T (c - t) -
c`` of ``c_a`` and ``c_b`` are parallel. The angle between them is the critical
angle of ch. 7.5.2 (zero for a pure translation); it is reported per camera.
Cross-camera correspondences do not have this limitation.
"""


from __future__ import annotations

from typing import Any, Optional, Sequence

import numpy as np

from .. import _core
from ..errors import DegenerateError
from ..geometry import count_in_front, rcross, refine_centred
from ..observability import (ZERO_FACTOR, scale_determined, scale_profile, scale_verdict,
                              total_scale_std)
from ..registry import register
from ..types import RayPairs, RigMotion, ScaleVerdict
from ..validation import integral_camera_ids
from ._common import camera_ids, in_mirrored_minimum, intra_counts, travel_direction
from ._finish import unrefined_scale_std
from ._outliers import guard_verdict
from ._static import with_static_check
from .essential import USAC_EXPLICIT, bearings_planar, essential_motions
from .five_plus_one_minimal import (PRIMARY_RULE, critical_angles, exact_candidates,
                                    minimal_solutions, sample_five_plus_one, scale_terms)

__all__ = ["five_plus_one", "solve", "propose", "scale_one_point_ransac", "minimal_answer"]


# ------------------------------------------------ exactly minimal input (6)

def minimal_answer(rays: RayPairs, method: str = "five_plus_one",
                   noise_level: float = float("nan"),
                   with_inliers: bool = False) -> Optional[RigMotion]:
    """The answer on exactly minimal input: 6 correspondences, 5 of one camera
    and 1 other (issue 18); None when ``rays`` is not such a set, no exact
    solution puts all six points in front, or the rig did not translate
    measurably (the caller's usual path then answers).

    Six correspondences fit up to ten motions exactly, and several of them can
    put every point in front of the cameras (~45 % of noise-free
    configurations: ``mcgeom experiment minimal_5p1``); nothing in the data
    tells the physical one. So every such motion is returned in
    ``info["candidates"]`` (dicts with ``R``, ``t`` in metres, ``min_depth``,
    ``max_residual`` and ``why``; :func:`exact_candidates`), ``R`` and ``t``
    are those of the primary, chosen by :data:`PRIMARY_RULE`
    (``info["primary_rule"]``), and the verdict is never observable: it says
    "ambiguous: k motions fit the 6 correspondences exactly" when k > 1, "no
    redundancy" otherwise. ``t`` is the primary's unit travel direction (no
    redundancy supports a metric scale); its metric value is
    ``info["t_metric"]``. ``method`` names the motion; ``noise_level``
    (radians) enables the no-parallax test of :func:`scale_verdict`;
    ``with_inliers``: the motion's ``inliers`` mask (all six) as a robust
    search reports it, else None as the direct estimators.
    """
    if len(rays) != 6:
        return None
    cands = exact_candidates(rays)
    if not cands:
        return None
    R, t = cands[0]["R"], cands[0]["t"]
    every = np.ones(6, bool)
    base = scale_verdict(rays, every, R, t, float("inf"), 0.1, noise_level=noise_level)
    if base.reason.startswith("no translation"):
        return None
    k = len(cands)
    what = (f"ambiguous: {k} motions fit the 6 correspondences exactly and put all 6 points "
            "in front of the cameras (info['candidates']); nothing in the data tells the "
            f"physical one; the one returned has the {PRIMARY_RULE}" if k > 1 else
            "no redundancy: one motion fits the 6 correspondences exactly with all 6 points "
            "in front of the cameras (the other exact solutions put points behind)")
    verdict = ScaleVerdict(False, f"{what}; 6 correspondences for the 6 unknowns of the "
                                  "motion: no uncertainty can be estimated, the scale is "
                                  "not checked", base.conditioning, float("inf"),
                           base.critical_angle)
    info = {"candidates": cands, "ambiguous": k > 1, "primary_rule": PRIMARY_RULE,
            "t_metric": np.array(t), "scale_determined": False, "translation_detected": True,
            "t_direction": travel_direction(rays, every, R, t), "inlier_ratio": 1.0}
    r = _core.gec_residuals(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, R, t)
    return RigMotion(np.array(R), info["t_direction"], verdict, method,
                     float(np.sqrt(np.mean(r ** 2))), every if with_inliers else None, info)


# -------------------------------------------------------------- estimator

def _camera_option(what: str, value: object) -> int:
    """A camera id option by the one rule of camera ids
    (:func:`mcgeom.validation.integral_camera_ids`: integers, or floats with a whole
    value); ValueError naming ``what`` for 1.5, "1", True, a list."""
    arr = np.asarray(value) if not isinstance(value, (str, bytes)) else None
    if arr is None or arr.ndim != 0 or arr.dtype.kind == "b":
        raise ValueError(f"{what} must be an integer camera id, got {value!r}")
    try:
        return int(integral_camera_ids(what, arr))
    except ValueError:
        raise ValueError(f"{what} must be an integer camera id, got {value!r}") from None


def _choose_camera(rays: RayPairs, five_camera: Optional[int]):
    cam1, cam2, centres, intra, counts = intra_counts(rays)
    if five_camera is None:
        a = int(np.argmax(counts))
    else:
        a = int(five_camera)
        if not 0 <= a < len(counts):
            raise ValueError(f"five_camera {a} is not a camera of these rays (0..{len(counts) - 1})")
    if counts[a] < 5:
        raise ValueError(f"too few correspondences: five_plus_one needs 5 intra-camera "
                         f"correspondences in camera {a}, got {counts[a]}")
    return a, cam1, cam2, centres, np.flatnonzero(intra & (cam1 == a))


def _five_of(rays: RayPairs) -> int:
    """The camera with the most intra-camera correspondences (the 5-point one
    of a 5+1 set)."""
    return int(np.argmax(intra_counts(rays)[4]))


def _scale_ls(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """Least-squares scale of eq. 7.4 over many correspondences and its relative std."""
    bb = float(b @ b)
    if not bb > 0.0:
        return float("nan"), float("inf")
    lam = -float(a @ b) / bb
    r = a + lam * b
    dof = max(len(a) - 1, 1)
    sig = np.sqrt(float(r @ r) / dof / bb)
    return lam, (sig / abs(lam) if lam != 0 else float("inf"))


def solve(rays: RayPairs, five_camera: Optional[int] = None,
          essential: Optional[Sequence] = None) -> dict:
    """The linear part of the method on all given correspondences (no refinement).

    Returns a dict with R, t, the 5-point camera, the scale ``lam``, its relative
    std from the residuals of eq. 7.4, the number of scale correspondences and
    the critical angles. ``essential`` may give ``(R, t0, w)`` candidates (e.g.
    from a robust search) instead of running the 5-point solver.
    """
    a, cam1, cam2, centres, own = _choose_camera(rays, five_camera)
    if essential is None:
        essential = essential_motions(rays, own, centres[a])
    if not essential:
        raise DegenerateError(f"five_plus_one: the 5-point solver found no motion in camera {a} "
                              "(too few usable points, or degenerate: no translation)")
    others = np.flatnonzero(~((cam1 == a) & (cam2 == a)))
    cands = []
    for R, t0, w in essential:
        if others.size:
            sa, sb = scale_terms(rays.take(others), R, t0, w)
            lam, rel = _scale_ls(sa, sb)
        else:
            lam, rel = float("nan"), float("inf")
        # with no usable scale (critical motion: a ~ 0, lam ~ 0 of random sign)
        # keep the 5-point direction, whose sign the cheirality check fixed
        determined = bool(np.isfinite(lam) and rel <= 1.0)
        t = t0 + (lam if determined else 1.0) * w
        res = np.abs(_core.gec_residuals(rays.origins1, rays.dirs1, rays.origins2,
                                         rays.dirs2, R, t))
        cost = float(np.sum(res ** 2))
        cands.append(dict(R=R, t=t, t0=t0, w=w, lam=lam, scale_rel_std=rel, cost=cost,
                          five_camera=a, n_scale=int(others.size), scale_determined=determined,
                          in_front=count_in_front(rays, R, t)))
    # Cheirality first, then cost: with few correspondences (6: the minimal
    # problem) several 5-point solutions fit every epipolar constraint to
    # rounding, and only the physical one puts the points in front of the
    # cameras (the verdict would otherwise reject the kept one for cheirality).
    # 5 % of the correspondences of slack: noise may put a few far or
    # near-parallel points behind under the right motion.
    top = max(c["in_front"] for c in cands)
    slack = int(0.05 * len(rays))
    best = min((c for c in cands if c["in_front"] >= top - slack), key=lambda c: c["cost"])
    best["critical_angles"] = critical_angles(best["R"], best["t"], centres, a)
    return best


def _from_camera(rays: RayPairs, a: int, refine: bool) -> tuple[float, dict, Optional[dict]]:
    """The linear 5+1 solution with camera ``a`` as the 5-point camera, refined
    on all correspondences; returns (final cost, linear solution, refinement)."""
    sol = solve(rays, a)
    if not refine:
        return sol["cost"], sol, None
    # all six degrees of freedom even if |t| is not observable: holding a wrong
    # |t| would bend R and the direction (see mcgeom.robust._python_search.finish); with 6
    # rays the square system polishes the minimal solution
    try:
        out = _refine_all(rays, sol["R"], sol["t"], False)
    except DegenerateError:
        out = _refine_all(rays, sol["R"], sol["t"], True)
    return float(out["final_cost"]), sol, out


def _refine_all(rays: RayPairs, R: np.ndarray, t: np.ndarray, fix_scale: bool) -> dict:
    # converged to rounding, not to a relative cost change of 1e-10: the result
    # must not depend on which camera's start won (order, rig frame)
    return refine_centred(rays, R, t, loss="none", fix_scale=fix_scale, max_iterations=100,
                          cost_tolerance=1e-15, step_tolerance=1e-13)


@register(
    "five_plus_one",
    min_sample=6,
    camera_kinds=("most-general", "locally-central", "axial", "locally-central-and-axial"),
    family="minimal",
    needs_rotation=False,
    recovers_scale=True,
    description="5+1 method: 5-point essential matrix in one camera (OpenCV), metric scale "
                "from the other cameras by eq. 7.4, critical angle (thesis ch. 7)",
    options={"five_camera": "camera whose 5-point essential matrix gives R and the direction "
                            "(default: the one with most intra-camera correspondences)",
             "refine": "joint nonlinear refinement on all correspondences (default True; "
                       "without it the std of |t| also counts the distance to the optimum)",
             "max_scale_rel_std": "relative std of |t| above which the scale is reported "
                                  "unobservable (0.1)",
             "calibration_std": "extrinsic calibration error of the cameras: (position std "
                                "m, rotation std rad) for all, or one pair per camera id; "
                                "included in the relative std of |t| (default None: exact)"},
    minimal_solver=minimal_solutions,
    sampler=sample_five_plus_one,
    proposer=lambda rays, thr, prob, rng: propose(rays, thr, prob, rng),
)
def five_plus_one(rays: RayPairs, *, five_camera: Optional[int] = None, refine: bool = True,
                  max_scale_rel_std: float = 0.1, calibration_std=None) -> RigMotion:
    """Rig motion rig2_from_rig1 (R, t in metres) by the 5+1 method on all correspondences.

    ``rays`` in the rig frame with origins at the camera centres; camera ids
    from ``rays.cam1``/``cam2`` or, if absent, from equal origins. All
    correspondences are taken as inliers (use :func:`mcgeom.robust.ransac` with
    outliers). The scale is the least-squares solution of eq. 7.4 over every
    correspondence not of the 5-point camera, then (``refine``) the motion is
    refined jointly on all correspondences (Sampson angular error). ``info``
    holds the 5-point camera, the critical angles (radians) per camera, the
    linear scale and its relative std. ``calibration_std`` (see
    :func:`mcgeom.observability.calibration_scale_std`) adds the rig's
    extrinsic calibration error to the relative std of ``|t|`` (``info``:
    ``scale_rel_std_noise``, ``scale_rel_std_calibration``, ``covariance``).
    ``t`` is the metric estimate wherever the data determine a scale
    (``info['scale_determined']``), a unit direction where not. Raises
    ValueError when no camera has 5 intra-camera correspondences,
    DegenerateError when the 5-point solver fails and the rig did translate.
    A rig that did not translate measurably gives the rotation, ``t = 0`` and
    the verdict "no translation detected" (the shared test of
    :mod:`mcgeom.estimators._static`, the robust layer's statistic).
    On exactly 6 correspondences (5 of one camera, 1 other) every motion that
    fits them exactly with all points in front is in ``info["candidates"]``
    and the verdict says when they are ambiguous (:func:`minimal_answer`).
    """
    if not isinstance(rays, RayPairs):
        raise TypeError(f"rays must be a RayPairs, got {type(rays).__name__}")
    if five_camera is not None:  # 1.5, "1" or True would otherwise pick a camera silently
        five_camera = _camera_option("five_camera", five_camera)
    if len(rays) < 6:
        raise ValueError(f"too few correspondences: five_plus_one needs at least 6, got {len(rays)}")
    rays.check_finite()
    return with_static_check(rays, "five_plus_one", lambda: _five_plus_one(
        rays, five_camera, refine, max_scale_rel_std, calibration_std))


def _five_plus_one(rays: RayPairs, five_camera: Optional[int], refine: bool,
                   max_scale_rel_std: float, calibration_std: Any = None) -> RigMotion:
    """:func:`five_plus_one` on checked rays, without the static-rig test."""
    if len(rays) == 6:
        # exactly minimal: every exact motion with all points in front
        # (minimal_answer), unless the set is not 5 + 1 or none passes
        m = minimal_answer(rays)
        if m is not None and five_camera in (None, _five_of(rays)):
            return m
    if five_camera is None:
        # every camera that can be the 5-point camera, best final cost wins: the
        # refinement from a single camera's start can stop in a local minimum,
        # and the choice must not depend on the rig frame or the order of rays
        counts = intra_counts(rays)[4]
        cams = [int(k) for k in np.argsort(-counts, kind="stable") if counts[k] >= 5]
        if not cams:
            raise ValueError("too few correspondences: five_plus_one needs 5 intra-camera "
                             f"correspondences in one camera, most found: {int(counts.max())}")
    else:
        cams = [five_camera]
    found, err = [], None
    for a in cams:
        try:
            found.append((a, _from_camera(rays, a, refine)))
        except DegenerateError as e:
            err = e
    if not found:
        raise err if err is not None else DegenerateError("five_plus_one: no motion found")
    # Several starts usually reach the same minimum, equal in cost to rounding;
    # among those take the lowest camera id, so that the end point (equal only
    # to the refinement's tolerance) does not depend on the order of the rays.
    low = min(c[0] for _, c in found)
    _, (_, sol, out) = min((fa for fa in found if fa[1][0] <= low * (1 + 1e-9) + 1e-300),
                           key=lambda fa: fa[0])
    R, t, rel = sol["R"], sol["t"], sol["scale_rel_std"]
    info = {"five_camera": sol["five_camera"], "critical_angles": sol["critical_angles"],
            "scale_linear": sol["lam"], "scale_rel_std_linear": rel,
            "n_scale_correspondences": sol["n_scale"], "cameras_tried": cams}
    # the verdict rests on the refined evidence only (not on which camera's
    # linear start won: several converge to the same minimum)
    fixed = sol["n_scale"] == 0 or (out is None and not sol["scale_determined"])
    if out is not None:
        R, t = out["R"], out["t"]
        if len(rays) > 6:
            rel, parts = total_scale_std(rays, out["R"], out["t"], out, calibration_std)
            info.update(parts)
            if fixed:
                rel = float("inf")
            info["refinement"] = {k: out[k] for k in ("iterations", "converged") if k in out}
            if rel <= max_scale_rel_std:
                k = 1.0 + 3.0 * max_scale_rel_std
                info["scale_profile"] = scale_profile(rays, R, t, out["final_cost"],
                                                      out["sigma2"], (1.0 / k, k))
    if out is None and len(rays) > 6 and not fixed:
        # unrefined: the spread of the scale samples misses the 5-point
        # motion's own error (rms of error / that std 2.98 over the property
        # suite's kinds); the Sampson cost's std and the distance to its
        # optimum, whichever is larger (_finish.unrefined_scale_std)
        geo, info["move_to_optimum"] = unrefined_scale_std(rays, R, t)
        rel = max(rel, geo)
    sol["critical_angles"] = critical_angles(R, t, camera_ids(rays)[2], sol["five_camera"])
    info["critical_angles"] = sol["critical_angles"]
    # a profile that does not exclude |t| x/ (1 + 3 max_scale_rel_std) makes
    # the verdict "not observable" (it sees the non-linear cost); rel keeps
    # the first-order std, which says whether a metric estimate exists at all
    verdict = scale_verdict(rays, np.ones(len(rays), bool), R, t, rel, max_scale_rel_std,
                            fixed, profile=info.get("scale_profile", float("nan")))
    # every correspondence was taken as an inlier: a fit pulled by gross
    # outliers is no metric estimate (mcgeom.estimators._outliers)
    observable = verdict.observable
    verdict, info["outlier_move_stds"] = guard_verdict(rays, R, t, verdict, "five_plus_one",
                                                       max_scale_rel_std, info=info)
    pulled = observable and not verdict.observable
    info["t_metric"] = np.array(t)   # metric estimate, whatever the verdict
    # t is the maximum-likelihood metric estimate wherever the data define a
    # scale at all (the verdict says how far to trust it), a unit direction
    # where they do not (mcgeom.observability.scale_determined)
    zero = float("nan")
    if not verdict.observable and out is not None and len(rays) > 6 and not pulled and \
            scale_determined(rel, fixed):
        zero = scale_profile(rays, R, t, out["final_cost"], out["sigma2"], (ZERO_FACTOR,))
    info["scale_determined"] = scale_determined(rel, fixed, zero) and not pulled
    if not verdict.observable:
        info["t_direction"] = travel_direction(rays, np.ones(len(rays), bool), R, t)
        if in_mirrored_minimum(info["t_direction"], t):
            # no metric estimate (as mcgeom.robust._verdict.conclude): its length
            # goes along the travel
            info["t_metric"] = float(np.linalg.norm(t)) * info["t_direction"]
            info["scale_determined"] = False
        if not info["scale_determined"]:
            t = info["t_direction"]
    r = np.abs(_core.gec_residuals(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, R, t))
    return RigMotion(R, t, verdict, "five_plus_one", float(np.sqrt(np.mean(r ** 2))), None, info)


#: The 5-point search of :func:`propose` counts inliers within this many
#: thresholds. At 1 threshold it sees ~60 % of a camera's points as inliers at
#: 30 % outliers and 0.5 px noise (the Sampson distance of a true match exceeds
#: 1 px for ~16 % of them), which needs ~60 adaptive USAC iterations; at 2 it sees
#: ~69 % and needs ~27. Measured on the Ladybug head (300 problems): USAC 2.4 ->
#: 1.2 ms per call, rotation median 0.0177 -> 0.0176 deg, scale median 0.182 ->
#: 0.175; the motion is scored and refined on every camera at 1 threshold anyway.
_SEARCH_WIDENING = 2.0


def propose(rays: RayPairs, threshold: float, prob: float, rng: np.random.Generator,
            max_cameras: int = 3, scale_samples: int = 64):
    """Two-stage robust hypotheses of thesis ch. 7.4 (Fig. 7.6), camera after camera.

    For the cameras in decreasing number of intra-camera correspondences (up
    to ``max_cameras``): the essential matrix by OpenCV's robust 5-point search
    (USAC at ``_SEARCH_WIDENING`` times ``threshold``, radians ~ normalised image
    units), then the scale by a
    1-point RANSAC over the correspondences of all other cameras (eq. 7.4). A
    generator of ``(R, t, expected_inlier_ratio)``, the last being the fraction
    of its camera's points within ``threshold`` of the 5-point search's model: the caller scores each
    motion on all correspondences and stops asking once one explains about
    that fraction everywhere (the usual case: one camera is enough).
    """
    import cv2
    cam1, cam2, centres, intra, counts = intra_counts(rays)
    order = [int(k) for k in np.argsort(-counts, kind="stable") if counts[k] >= 8][:max_cameras]
    for a in order:
        own = np.flatnonzero(intra & (cam1 == a))
        if bearings_planar(rays.dirs1[own], rays.dirs2[own], threshold):
            continue   # every ray (outliers too) within the threshold of one plane
        stats: dict = {}
        try:
            # 0.99 is enough here: the motion is checked on every camera and the
            # next camera is tried when it falls short
            # (and at most 300 samples: enough up to ~55 % outliers in that
            # camera; beyond, the next camera is tried rather than waiting)
            cands = essential_motions(rays, own, centres[a], method=USAC_EXPLICIT,
                                      threshold=_SEARCH_WIDENING * threshold,
                                      prob=min(prob, 0.99), stats=stats, max_iters=300,
                                      planar_check=False, ratio_threshold=threshold)
        except (DegenerateError, cv2.error):
            continue
        # A correspondence between cameras centred where camera a is (a central
        # rig, coincident centres) has e(lam) = lam b (eq. 7.4 with a = 0): its
        # only root is lam = 0, the trivial motion whose epipolar constraint
        # vanishes for every such ray (zero residuals, a false consensus).
        # Only cameras with another centre can fix the scale.
        here = np.all(np.abs(centres - centres[a]) <= 1e-9 * (1.0 + np.abs(centres[a]).max()),
                      axis=1)
        others = np.flatnonzero(~(here[cam1] & here[cam2]))
        if others.size == 0:   # one camera (or one centre) only: R and the direction, no scale
            for R, t0, w in cands:
                yield R, t0 + w, stats.get("inlier_ratio", 1.0)
            continue
        # Cross-camera correspondences fix the scale whatever the motion, while
        # near the critical motion the intra-camera ones of the other cameras
        # hardly depend on it -- but their thousands of small, model-error-driven
        # slopes can outvote the informative few. Score on the cross ones when
        # there are enough of them.
        cross = np.flatnonzero(~intra)
        sub = rays.take(cross if cross.size >= 20 else others)
        for R, t0, w in cands:
            lam = scale_one_point_ransac(sub, R, t0, w, threshold, rng, scale_samples, prob)
            if lam is not None:
                yield R, t0 + lam * w, stats.get("inlier_ratio", 1.0)


def scale_one_point_ransac(rays: RayPairs, R: np.ndarray, t0: np.ndarray, w: np.ndarray,
                           threshold: float, rng: np.random.Generator,
                           samples: int = 64, prob: float = 0.999) -> Optional[float]:
    """The scale ``lam`` of ``t = t0 + lam w`` by 1-point RANSAC (thesis ch. 7.4).

    Each of up to ``samples`` correspondences, in a random order, proposes
    ``lam = -a / b`` (eq. 7.4); the proposals are scored by MSAC on the Sampson
    angular residuals (``threshold`` radians) of every correspondence, in
    batches of 16 with the adaptive stop of a 1-point sample (``prob``); the
    best is re-estimated by weighted least squares on its inliers
    (``_core.scale_ransac``). Only ``lam > 0`` is considered: the
    5-point camera's cheirality check fixed the sense of its own travel ``lam
    w``, and near the critical motion the Sampson error hardly tells ``lam``
    from ``-lam`` (each camera's epipolar constraint ignores the sign of its
    translation), so a negative proposal often wins by noise -- a reversed
    travel from which the final refinement cannot recover (it slides |t| to
    infinity instead of crossing it; measured: a quarter of the Ladybug
    hypotheses). None if no correspondence proposes a positive scale.
    """
    # The search runs in C (csrc/scale_line.c): the proposals' MSAC scores
    # over every correspondence and the least-squares step were ~0.5 ms of
    # numpy per call, a tenth of a Ladybug problem. The random order is drawn
    # here, among the correspondences that propose a positive scale, as the
    # numpy search did: the same random stream gives the same hypotheses.
    a, b = _scale_line_terms(rays, R, t0, w)
    ok = np.flatnonzero((np.abs(b) > 1e-9 * (1.0 + np.abs(a))) & (a * b < 0.0))
    if ok.size == 0:
        return None
    found = _core.scale_ransac(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, R, t0, w,
                               rng.permutation(ok)[:samples], threshold, prob, samples)
    return None if found is None else found[0]


def _scale_line_terms(rays: RayPairs, R: np.ndarray, t0: np.ndarray,
                      w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The epipolar residual ``a + lam b`` (eq. 7.4) of each correspondence
    along ``t = t0 + lam w``, unit bearings: ``e = d2 . (s x R d1)`` with ``s =
    t0 + lam w + R o1 - o2`` (the numerator of the Sampson residual that
    ``_core.scale_ransac`` scores)."""
    d1 = rays.dirs1 / np.linalg.norm(rays.dirs1, axis=1, keepdims=True)
    d2 = rays.dirs2 / np.linalg.norm(rays.dirs2, axis=1, keepdims=True)
    rd1 = d1 @ R.T
    s0 = t0 + rays.origins1 @ R.T - rays.origins2
    return (np.einsum("ij,ij->i", d2, rcross(s0, rd1)),
            np.einsum("ij,ij->i", d2, rcross(w, rd1)))
