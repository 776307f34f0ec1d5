"""Is the metric scale of a rig motion observable? Evidence and verdict (thesis ch. 7.3.2).

Two pieces of evidence are combined:

* geometry: the critical angle of ch. 7.5.2. A camera centre ``c`` moves, seen
  from the time-1 rig frame, by ``delta(c) = R^T (c - t) - c``. Intra-camera
  correspondences of two cameras fix the scale only if their displacements are
  not parallel (Theorem 3); the critical angle of a pair is the angle between
  them, and the rig's is the largest over the cameras that have inliers.
  Cross-camera correspondences (one camera at time 1, another at time 2) fix
  the scale whatever the motion.
* statistics: the relative standard deviation of ``|t|`` from the covariance of
  the final nonlinear refinement (residual variance times the inverse
  information matrix), which accounts for the noise, the number of inliers and
  the rotation uncertainty together; and the part the rig's calibration error
  adds (:func:`calibration_scale_std`: the scale is fixed through the camera
  centres, so an error in them moves it), combined in quadrature
  (:func:`combine_rel_std`).

The verdict is "observable" when the statistics say so (relative std at most
``max_rel_std``); the critical angle and the cross-camera count explain it.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Optional

import numpy as np

from . import _core
from .errors import DegenerateError
from .geometry import (count_in_front, displacements, origin_centroid, rcross, refine_centred,
                       rotation_fit, same_camera)
from .types import RayPairs, ScaleVerdict

__all__ = ["scale_verdict", "critical_angle", "rig_critical_angle", "scale_profile",
           "scale_determined", "UNDETERMINED_REL_STD", "ZERO_FACTOR", "calibration_scale_std",
           "sampled_calibration_scale_std", "with_sampled_calibration", "SAMPLED_DRAWS",
           "SAMPLED_MAX_INTRA",
           "combine_rel_std", "total_scale_std", "no_parallax", "with_calibration",
           "scale_verdict_stats", "verdict_text"]

#: relative std of ``|t|`` above which the data define no metric scale at all:
#: a one-sigma interval that reaches zero bounds neither the length nor (with
#: the flat side of a near-critical cost) infinity. Below it ``t`` is reported
#: as its maximum-likelihood metric estimate, trusted or not by the verdict;
#: above it (and for an exactly critical motion) ``t`` has unit norm.
UNDETERMINED_REL_STD = 1.0

#: unknowns of a rig motion (rotation and metric translation)
_MOTION_DOF = 6


def rig_critical_angle(R: np.ndarray, t: np.ndarray, centres: np.ndarray) -> float:
    """Largest critical angle (radians, in [0, pi]) over pairs of the given centres.

    The angle between the displacement directions is folded to [0, pi/2]: a
    displacement and its opposite are equally critical (Theorem 3 asks for
    parallel lines, whatever their sense). 0 for fewer than two centres.
    """
    d = displacements(R, t, centres)
    n = np.linalg.norm(d, axis=1)
    d = d[n > 0] / n[n > 0, None]
    if len(d) < 2:
        return 0.0
    # |cos| folds an angle and its supplement; the smallest |cos| over pairs is
    # the largest folded angle (arctan2 of |cross| and |dot| keeps it accurate)
    cos = np.abs(d @ d.T)
    i, j = np.unravel_index(np.argmin(cos + 2.0 * np.eye(len(d))), cos.shape)
    return float(np.arctan2(np.linalg.norm(rcross(d[i], d[j])), cos[i, j]))


def critical_angle(rays: RayPairs, R: np.ndarray, t: np.ndarray,
                   mask: np.ndarray | None = None) -> float:
    """The rig's critical angle (radians) for the motion (R, t) over the cameras
    that have intra-camera correspondences (all, or those in ``mask``)."""
    sel = np.ones(len(rays), bool) if mask is None else np.asarray(mask, bool)
    centres, _ = _centres_with_intra(rays, sel)
    return rig_critical_angle(R, t, centres) if len(centres) >= 2 else 0.0


def _centres_with_intra(rays: RayPairs, mask: np.ndarray,
                        same: np.ndarray | None = None) -> tuple[np.ndarray, int]:
    """Centres of cameras with intra-camera inliers, and the number of cross-camera inliers.

    ``same`` is :func:`mcgeom.geometry.same_camera` of ``rays`` if the caller has it already.
    """
    if same is None:
        same = same_camera(rays)
    intra = mask & same
    cross = int(np.count_nonzero(mask)) - int(np.count_nonzero(intra))
    if rays.cam1 is not None and rays.cam2 is not None:
        # the origin of each camera's first intra-camera inlier, cameras in id order
        rows = np.flatnonzero(intra)
        _, first = np.unique(rays.cam1[rows], return_index=True)
        return rays.origins1[rows[first]].reshape(-1, 3), cross
    centres = np.unique(rays.origins1[intra], axis=0) if intra.any() else np.zeros((0, 3))
    return centres, cross


#: the factor of :func:`scale_profile` that asks "could the cameras not have
#: moved at all?": |t| shrunk to 1 %
ZERO_FACTOR = 0.01


def scale_determined(rel_std: float, direction_only: bool = False,
                     zero_profile: float = float("nan")) -> bool:
    """Do the data define a metric scale at all (thesis ch. 7.3.2)?

    False when the refinement had to fix ``|t|`` (``direction_only``: no
    correspondence can fix it, e.g. an exactly critical motion or one camera),
    when the information about ``|t|`` is singular (``rel_std`` not finite),
    when its relative standard deviation exceeds :data:`UNDETERMINED_REL_STD`,
    or when ``zero_profile`` (:func:`scale_profile` for the factor
    :data:`ZERO_FACTOR`, if computed) does not exclude a vanishing
    translation at 3 sigma: the length of a noise-driven translation of a
    static rig is no scale (its first-order std is unreliable there: the norm
    of pure noise has a relative std near 0.5). When True, the estimate's
    ``t`` is its maximum-likelihood metric estimate (the verdict says how far
    to trust it: observable only within ``max_rel_std``); when False, ``t``
    is a unit direction.
    """
    # (math on the scalars: numpy's scalar ufuncs cost more, on every estimate)
    if math.isfinite(zero_profile) and zero_profile < 9.0:
        return False
    return bool(not direction_only and math.isfinite(rel_std) and rel_std <= UNDETERMINED_REL_STD)


def scale_profile(rays: RayPairs, R: np.ndarray, t: np.ndarray, cost: float, sigma2: float,
                  factors: tuple = (1.0 / 1.3, 1.3), loss: str = "none",
                  loss_scale: float = 1e-3, weights: np.ndarray | None = None) -> float:
    """How strongly the data exclude ``|t|`` scaled by each of ``factors``.

    For each factor the motion is re-optimised with the centroid translation
    held at ``factor`` times its length (see
    :func:`mcgeom.geometry.refine_centred`; rotation and direction free); the
    returned value is the smallest cost increase over the free optimum ``cost``, in units of the residual variance
    ``sigma2`` (a likelihood-ratio statistic: ~chi^2 with 1 dof). Unlike the
    first-order standard deviation it sees the non-linearity of near-critical
    motions, where the cost is flat on one side of the estimate.
    """
    if not (np.isfinite(sigma2) and sigma2 > 0):
        return 0.0
    worst = np.inf
    c = origin_centroid(rays)
    shift = np.asarray(R) @ c - c
    for f in factors:
        try:
            out = refine_centred(rays, R, (np.asarray(t) + shift) * f - shift, loss=loss,
                                 loss_scale=loss_scale, fix_scale=True, weights=weights)
        except (ValueError, ArithmeticError):
            return 0.0
        worst = min(worst, (out["final_cost"] - cost) / sigma2)
    return float(max(worst, 0.0))


#: the no-parallax test: a pure rotation must explain this fraction of the
#: intra-camera correspondences ...
NO_PARALLAX_FRACTION = 0.9
#: ... each within this many noise levels (the rotation residual is a 2-dof
#: angle, the noise level that of the 1-dof Sampson distance)
NO_PARALLAX_FACTOR = 1.5
#: fewest intra-camera correspondences the no-parallax test decides on
NO_PARALLAX_MIN = 5


def no_parallax(angles: np.ndarray, noise_level: float) -> bool:
    """The no-parallax statistic: does a pure rotation explain the correspondences?

    ``angles`` (radians) are the residual angles between ``d2`` and ``R d1`` of
    the intra-camera correspondences under the best pure rotation
    (:func:`mcgeom.geometry.rotation_fit`); ``noise_level`` (radians) is the
    inlier threshold of the Sampson distance (or its equivalent). True when
    at least :data:`NO_PARALLAX_FRACTION` of them are within
    :data:`NO_PARALLAX_FACTOR` noise levels (and there are at least
    :data:`NO_PARALLAX_MIN`): the translation moves no point measurably. The
    one statistic of the robust verdict (:func:`scale_verdict`) and of every
    estimator's static-rig test (:mod:`mcgeom.estimators._static`).
    """
    angles = np.asarray(angles, dtype=np.float64)
    if angles.size < NO_PARALLAX_MIN or not noise_level > 0:
        return False
    inside = np.count_nonzero(angles < NO_PARALLAX_FACTOR * noise_level)
    return inside / angles.size >= NO_PARALLAX_FRACTION


def scale_verdict(rays: RayPairs, inliers: np.ndarray, R: np.ndarray, t: np.ndarray,
                  rel_std: float, max_rel_std: float = 0.1,
                  direction_only: bool = False,
                  noise_level: float = float("nan"),
                  profile: float = float("nan")) -> ScaleVerdict:
    """The scale verdict of a motion estimated from the ``inliers`` of ``rays``.

    ``rel_std`` is the relative std of ``|t|`` from the refinement;
    ``direction_only`` says that the refinement already had to fix ``|t|``;
    ``profile`` is the statistic of :func:`scale_profile` for the factors
    ``1 +- 3 max_rel_std``: the scale is observable only if both are excluded
    at 3 sigma (profile >= 9), i.e. a first-order "3 sigma within 30 %" that
    also holds for the non-linear cost;
    ``noise_level`` (radians, the inlier threshold) enables the no-parallax
    test of :func:`mcgeom.geometry.rotation_only_fit`: when a pure rotation
    explains at least 90 % of the intra-camera inliers within 1.5 x the threshold (the rotation
    residual is a 2-dof angle, the threshold one of the 1-dof Sampson
    distance), the translation moves no point measurably: none was detected.
    (Comparing with the Sampson residual of a free translation instead fails on
    real data: a tiny translation with a free direction fits calibration error
    5-15x better than a rotation, seen on the DGP parked car.)
    """
    inliers = np.asarray(inliers, bool)
    same = same_camera(rays)   # shared by the no-parallax test and the centres
    if np.isfinite(noise_level):
        _, ang = rotation_fit(rays, inliers & same)
        if no_parallax(ang, noise_level):
            return _static_verdict(ang)
    centres, n_cross = _centres_with_intra(rays, inliers, same)
    crit = rig_critical_angle(R, t, centres) if len(centres) >= 2 else 0.0
    n_in = int(np.count_nonzero(inliers))
    return _verdict(n_in, n_cross, len(centres), crit, rel_std, max_rel_std, direction_only,
                    profile, lambda: count_in_front(rays, R, t, inliers))


def _static_verdict(ang: np.ndarray) -> ScaleVerdict:
    """The verdict when a pure rotation explains the intra-camera inliers
    (``ang``: their rotation-only angles, radians)."""
    return ScaleVerdict(False, "no translation detected: a pure rotation explains the "
                               f"correspondences (median residual "
                               f"{np.degrees(np.median(ang)) * 3600:.3g} arcsec); static "
                               "rig, pure rotation or scene at infinity: neither the "
                               "direction nor the scale of t is determined",
                        0.0, float("inf"), 0.0)


def scale_verdict_stats(rays: RayPairs, cam1: np.ndarray, cam2: np.ndarray, n_cameras: int,
                        inliers: np.ndarray, R: np.ndarray, t: np.ndarray, rel_std: float,
                        max_rel_std: float = 0.1, noise_level: float = float("nan"),
                        profile: float = float("nan"), prechecked: bool = False,
                        stats: Optional[dict] = None) -> tuple[ScaleVerdict, np.ndarray]:
    """:func:`scale_verdict` with its O(N) evidence from one C call
    (``_core.verdict_stats``, csrc/verdict.c: the rotation-only fit and its
    angles, the cameras with intra-camera inliers, the critical angle, the
    cross-camera count, cheirality), and the direction of travel that
    :func:`mcgeom.estimators._common.travel_direction` gives for the same
    inliers and motion (from the same call).

    ``cam1``, ``cam2`` are the rays' camera ids (int, ``[0, n_cameras)``;
    origins the camera centres, metres), ``inliers`` (N,) bool or uint8
    (bit 0: inlier), (R, t) rig2_from_rig1 (metres); the other arguments as
    for :func:`scale_verdict`. The same verdict as :func:`scale_verdict` on
    these rays (all inliers: no subsample), without a Python pass over them
    (issue 19). Returns ``(verdict, t_direction)``. ``prechecked``: ``cam1``,
    ``cam2`` are int32 and ``inliers`` the uint8 mask of
    :func:`mcgeom._core.robust_rig_motion` (see :func:`mcgeom._core.verdict_stats`).
    ``stats``: that call's ``verdict`` (the same evidence, gathered by the C
    search with ``verdict_still_factor`` = :data:`NO_PARALLAX_FACTOR` and
    ``noise_level`` its ``loss_scale``): not gathered again.
    """
    s = stats
    noise_level = float(noise_level)
    if s is None:
        still = NO_PARALLAX_FACTOR * noise_level if math.isfinite(noise_level) else 0.0
        if not 0.0 <= still < 4.0:
            # beyond any angle between two bearings: every angle is explained
            still = 3.5 if still >= 4.0 else 0.0
        s = _core.verdict_stats(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, cam1,
                                cam2, n_cameras, inliers, R, t, still, prechecked=prechecked)
    n_intra = s["n_intra"]
    if math.isfinite(noise_level) and noise_level > 0 and n_intra >= NO_PARALLAX_MIN:
        # the numpy fit decides where C's fit failed (the bearings span rank
        # < 2: one direction repeated), and gives the angles that the rare
        # static answer's message quotes
        if not s["fit_ok"] or s["n_still"] / n_intra >= NO_PARALLAX_FRACTION:
            _, ang = rotation_fit(rays, np.asarray(inliers).astype(bool) & same_camera(rays))
            if s["fit_ok"] or no_parallax(ang, noise_level):
                return _static_verdict(ang), s["t_direction"]
    n_in = s["n_inliers"]
    verdict = _verdict(n_in, s["n_cross"], s["n_cameras_intra"], s["critical_angle"], rel_std,
                       max_rel_std, False, profile, lambda: s["n_in_front"])
    return verdict, s["t_direction"]


def _verdict(n_in: int, n_cross: int, n_centres: int, crit: float, rel_std: float,
             max_rel_std: float, direction_only: bool, profile: float,
             in_front) -> ScaleVerdict:
    """The verdict from its evidence (see :func:`scale_verdict`): ``n_in``
    inliers of which ``n_cross`` cross-camera, ``n_centres`` cameras with
    intra-camera inliers and their critical angle ``crit`` (radians);
    ``in_front()`` the number of inliers in front of the cameras (asked
    only when the scale would otherwise be called observable). The rule is
    the C library's (``mcg_scale_reason``, csrc/robust_verdict.c: the one
    the robust search's own verdict applies), the words :func:`verdict_text`."""
    # (direction_only: the refinement had to fix |t|, no std to judge)
    rel = float("inf") if direction_only else float(rel_std)
    name = _core.scale_reason(n_in, n_cross, n_centres, crit, rel, max_rel_std, profile)
    n_front = -1
    if name is None:
        n_front = int(in_front())
        name = _core.scale_reason(n_in, n_cross, n_centres, crit, rel, max_rel_std, profile,
                                  n_front)
    return ScaleVerdict(name == "observable",
                        verdict_text(name, n_in, n_cross, n_centres, crit, rel_std,
                                     max_rel_std, profile, n_front / n_in if n_in else 0.0),
                        float("nan"), float("inf") if name == "no_redundancy" else float(rel_std),
                        crit)


def verdict_text(reason: str, n_in: int, n_cross: int, n_centres: int, crit: float,
                 rel_std: float, max_rel_std: float, profile: float,
                 front: float = float("nan")) -> str:
    """The words of a scale verdict: ``reason`` a value of
    :data:`mcgeom._core.SCALE_REASONS` other than ``static``, ``unconfirmed``
    and ``undecided`` (whose texts quote other evidence), with the evidence
    of :func:`_verdict` (``front`` the fraction of the inliers in front of
    the cameras, for ``cheirality``)."""
    if reason == "no_redundancy":
        # no redundancy: the motion fits its 6 correspondences exactly whatever
        # the noise (a zero residual says nothing about |t|), and a minimal
        # 5+1 problem has up to ten exact solutions of which several can put
        # every point in front of the cameras (44 % of the noise-free
        # configurations of ``mcgeom experiment minimal_5p1``): nothing tells
        # the physical one
        return (f"no redundancy: {n_in} correspondences for the {_MOTION_DOF} unknowns of "
                "the motion; other exact solutions may exist and no uncertainty can be "
                "estimated")
    evidence = (f"relative std of |t| {rel_std:.3g}, critical angle {math.degrees(crit):.3g} deg "
                f"over {n_centres} cameras, {n_cross} cross-camera inliers")
    if math.isfinite(profile):
        sigmas = math.sqrt(max(profile, 0.0))
        evidence += f", |t| x/ {1 + 3 * max_rel_std:.2g} excluded at {sigmas:.2g} sigma"
    if reason == "observable":
        return f"scale observable: {evidence}"
    if reason == "cheirality":
        # last guard against a confident wrong answer: a metric motion must put
        # its inliers in front of the cameras (a flipped or twisted solution
        # that survived the search puts most of them behind)
        return (f"cheirality fails: only {100 * front:.0f} % of the inliers triangulate in "
                f"front of the cameras (a wrong solution?); {evidence}")
    why = {"one_camera": "one camera only and no cross-camera correspondence",
           "critical": ("critical motion: camera displacements parallel (no rotation, thesis "
                        "ch. 7.3.2, Theorem 3)"),
           "uncertain": "scale too uncertain for the noise (near-critical motion)"}[reason]
    return f"{why}; {evidence}"


# ------------------------------------------------ calibration error of the rig

def calibration_scale_std(rays: RayPairs, R: np.ndarray, t: np.ndarray,
                          extrinsic_std, weights: np.ndarray | None = None,
                          loss: str = "none", loss_scale: float = 1e-3
                          ) -> tuple[float, np.ndarray]:
    """Relative std of the distance travelled due to the rig's calibration error.

    First-order propagation through the least-squares estimate (the implicit
    function theorem on its normal equations): with ``theta = (w, tau)`` the
    motion (left rotation increment, radians; translation of the cameras'
    centroid ``tau = t + R c - c``, metres, as
    :func:`mcgeom.geometry.refine_centred` uses) and ``p`` the extrinsics of
    every camera (centre, metres, and orientation, radians, in the rig frame;
    one camera's error moves the origins and turns the bearings of its rays
    at both times),

        d theta / d p = -(J^T W J)^-1 J^T W (dr / dp),

    ``r`` the Sampson angular residuals (``_core.gec_residuals``), ``W`` the
    ``weights`` times the robust loss's IRLS weights at the solution (``loss``,
    ``loss_scale`` radians, as in the final refinement). The variance of
    ``|tau|`` is ``sum_j (u^T d tau / d p_j)^2 sigma_j^2`` with ``u = tau /
    |tau|`` and ``sigma_j`` from ``extrinsic_std``: an (M, 2) array (or one
    pair) of per-camera 1-sigma position (metres per axis) and rotation
    (radians per axis) errors, independent across cameras and axes. Analytic derivatives of the
    residuals, in one C pass over the pairs (``_core.calibration_scale_std``,
    csrc/calibration_std.c).

    Returns ``(rel_std, cov)``: the relative std of ``|tau|`` (0 when every
    std is 0, inf when the motion is not determined by the rays: singular
    ``J^T W J``) and the (6, 6) covariance of ``theta`` that the calibration
    error induces (order [w, tau]).
    """
    R = np.asarray(R, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)
    cam1, cam2, sig = _camera_stds(rays, extrinsic_std)
    if not np.any(sig > 0) or len(rays) == 0:
        return 0.0, np.zeros((6, 6))
    # the propagation in one C pass over the pairs (csrc/calibration_std.c;
    # issue 19: in numpy it cost 2-4 ms per robust estimate, 3-4x the search)
    return _core.calibration_scale_std(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2,
                                       cam1, cam2, sig, R, t, weights, loss, loss_scale)


def _camera_stds(rays: RayPairs, extrinsic_std) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The rays' camera ids at both times (from equal origins when the rays
    carry none) and the (M, 2) per-camera stds of ``extrinsic_std`` (one pair
    or a table of at least M rows; ValueError naming the shape otherwise)."""
    sig = np.asarray(extrinsic_std, dtype=np.float64)
    if rays.cam1 is not None and rays.cam2 is not None:
        cam1, cam2 = rays.cam1, rays.cam2
    else:   # cameras from equal origins
        allo = np.concatenate([rays.origins1, rays.origins2])
        inv = np.unique(allo, axis=0, return_inverse=True)[1].ravel()
        cam1, cam2 = inv[:len(rays)], inv[len(rays):]
    m = int(max(cam1.max(initial=-1), cam2.max(initial=-1))) + 1
    if sig.shape == (2,):
        sig = np.tile(sig, (m, 1))
    if sig.ndim != 2 or sig.shape[1] != 2 or sig.shape[0] < m:
        raise ValueError(f"calibration_std must have shape (2,) or (M, 2) with M >= {m} "
                         f"(the cameras of the rays), got {sig.shape}")
    if not (np.isfinite(sig[:m]).all() and (sig[:m] >= 0).all()):
        raise ValueError("calibration_std must hold finite values >= 0")
    return cam1, cam2, sig[:m]


def sampled_calibration_scale_std(rays: RayPairs, R: np.ndarray, t: np.ndarray,
                                  extrinsic_std, draws: int = 256, seed: int = 0,
                                  weights: np.ndarray | None = None, loss: str = "none",
                                  loss_scale: float = 1e-3,
                                  max_intra: int | None = None) -> float:
    """Relative std of the distance travelled due to the rig's calibration
    error, by sampling: the check of :func:`calibration_scale_std`'s
    first-order propagation where the estimate is not linear in the
    extrinsics over their error.

    ``draws`` rigs (an even number >= 2; antithetic pairs e, -e) with every
    camera's centre moved by N(0, sigma_pos) per axis (metres, rig frame) and
    its orientation turned about its centre by a rotation vector N(0,
    sigma_rot) per axis (radians; ``extrinsic_std`` as for
    :func:`calibration_scale_std`; a camera's centre is the mean origin of
    its rays, exact for central cameras); on each, the motion refitted from
    ``(R, t)`` (rig2_from_rig1, metres) on the same pairs with the same
    ``weights``, ``loss`` and ``loss_scale`` (radians). Returns the std of
    the centroid's travel ``|tau|`` (``tau = t + R c - c``, c the centroid of
    the nominal origins) over the draws, relative to that of ``(R, t)``
    (0 when every std is 0). At small errors it agrees with the first-order
    figure. Near the critical motion of thesis ch. 7.3.2 the estimate can
    respond to the extrinsics far from linearly: on DDAD scene_02's first
    step (6 cameras driving 1.27 m straight, 0.107 deg of yaw; the inliers
    of a metric estimate, least squares, the default 2 mm / 0.1 deg) the
    first-order figure is 0.047-0.051, the sampled one 0.14-0.17 over three
    seeds of 256 draws (a few draws tip the refit into the valley of another
    scale: the spread is heavy-tailed, and 64 draws gave 0.088). Costs
    ``draws`` refinements on the rays; ``max_intra`` (None: all) refits on
    at most that many intra-camera pairs, a random subset whose weights are
    scaled by their count over it so that the normal equations keep their
    sums, and every cross-camera pair (often few, and the ones that fix the
    scale): on that DDAD step 0.207 with 1024 against 0.214 with all 3725,
    in 0.09 s against 0.21 s. Raises ValueError on bad arguments,
    :class:`mcgeom.errors.DegenerateError` when a refit is impossible.
    """
    if not (isinstance(draws, int) and draws >= 2 and draws % 2 == 0):
        raise ValueError(f"draws must be an even integer >= 2, got {draws!r}")
    if max_intra is not None and not (isinstance(max_intra, int) and max_intra >= 1):
        raise ValueError(f"max_intra must be None or an integer >= 1, got {max_intra!r}")
    R = np.asarray(R, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)
    if R.shape != (3, 3) or t.shape != (3,):
        raise ValueError(f"R must be (3, 3) and t (3,), got shapes {R.shape} and {t.shape}")
    if not (np.isfinite(R).all() and np.isfinite(t).all()):
        raise ValueError("R and t must be finite (NaN or inf given)")
    cam1, cam2, sig = _camera_stds(rays, extrinsic_std)
    c = origin_centroid(rays)
    tau0 = float(np.linalg.norm(t + R @ c - c))
    if not np.any(sig > 0) or len(rays) == 0:
        return 0.0
    if not tau0 > 0:
        raise ValueError("the motion does not move the cameras' centroid: no relative std")
    rng = np.random.default_rng(seed)
    intra = np.flatnonzero(cam1 == cam2)
    if max_intra is not None and intra.size > max_intra:
        keep = np.concatenate([np.flatnonzero(cam1 != cam2),
                               rng.choice(intra, max_intra, replace=False)])
        w = np.ones(len(rays)) if weights is None else np.asarray(weights, dtype=np.float64)
        w = w[keep]
        w[keep.size - max_intra:] *= intra.size / max_intra
        rays, weights, cam1, cam2 = rays.take(keep), w, cam1[keep], cam2[keep]
    m = len(sig)
    # each camera's centre: the mean origin of its rays (both times)
    sums = np.zeros((m, 3))
    np.add.at(sums, cam1, rays.origins1)
    np.add.at(sums, cam2, rays.origins2)
    counts = np.bincount(cam1, minlength=m) + np.bincount(cam2, minlength=m)
    centres = sums / np.maximum(counts, 1)[:, None]
    # per camera: its rows at each time and their origins about its centre
    # (one small product per camera and draw instead of a 3 x 3 per ray)
    sides = []
    for origins, dirs, cam in ((rays.origins1, rays.dirs1, cam1), (rays.origins2, rays.dirs2, cam2)):
        rows = [np.flatnonzero(cam == k) for k in range(m)]
        sides.append((origins, dirs, [(k, r, origins[r] - centres[k]) for k, r in
                                      enumerate(rows) if r.size]))
    t_c = t + R @ c - c
    taus = []
    for _ in range(draws // 2):
        dc = rng.normal(size=(m, 3)) * sig[:, :1]
        dw = rng.normal(size=(m, 3)) * sig[:, 1:]
        for sgn in (1.0, -1.0):
            Q = [_core.rot_from_angle_axis(sgn * w) for w in dw]
            moved = []
            for origins, dirs, cams in sides:
                o, d = np.empty_like(origins), np.empty_like(dirs)
                for k, r, rel in cams:
                    # turned about the camera's centre, moved by dc (rig frame),
                    # shifted to the nominal centroid's frame (refine_centred's)
                    o[r] = rel @ Q[k].T + (centres[k] + sgn * dc[k] - c)
                    d[r] = dirs[r] @ Q[k].T
                moved += [o, d]
            out = _core.refine_motion(*moved, R, t_c, weights=weights, loss=loss,
                                      loss_scale=loss_scale)
            taus.append(float(np.linalg.norm(out["t"])))
    return float(np.std(taus) / tau0)


def combine_rel_std(noise: float, calibration: float) -> float:
    """Total relative std of ``|t|``: the noise part (from the refinement's
    residuals) and the calibration part (:func:`calibration_scale_std`),
    independent, in quadrature; inf if either is."""
    # (math on Python floats: numpy's scalar ufuncs cost more than the
    # arithmetic, on every estimate)
    noise, calibration = float(noise), float(calibration)
    if not (math.isfinite(noise) and math.isfinite(calibration)):
        return float("inf")
    return math.hypot(noise, calibration)


def total_scale_std(rays: RayPairs, R: np.ndarray, t: np.ndarray, refined: dict,
                    calibration_std, weights: np.ndarray | None = None, loss: str = "none",
                    loss_scale: float = 1e-3) -> tuple[float, dict]:
    """Relative std of ``|t|`` of a refined motion, noise and calibration error together.

    ``refined`` is the result of :func:`mcgeom.geometry.refine_centred` on
    ``rays`` (its ``scale_rel_std``, ``sigma2`` and ``information``, or
    ``sigma2`` times the inverse information as ``covariance``: the noise
    part); ``calibration_std`` the rig's extrinsic error (see
    :func:`calibration_scale_std`; None = known exactly); ``weights``,
    ``loss``, ``loss_scale`` those of the refinement. Returns the total (in
    quadrature, :func:`combine_rel_std`) and a dict for ``info``:
    ``scale_rel_std_noise``, ``scale_rel_std_calibration`` and
    ``covariance`` (6 x 6, order [w rad, tau m], tau the translation of the
    cameras' centroid: residual variance times the inverse information plus
    the calibration part).
    """
    rel_noise = float(refined["scale_rel_std"])
    # (the C search gives it: mcgeom._core.robust_rig_motion's "covariance")
    cov = refined.get("covariance")
    if cov is None:
        try:
            cov = refined["sigma2"] * np.linalg.inv(refined["information"])
        except (np.linalg.LinAlgError, KeyError, ValueError):
            cov = np.full((6, 6), np.inf)
    rel_cal = 0.0
    if calibration_std is not None:
        rel_cal, cov_cal = calibration_scale_std(rays, R, t, calibration_std, weights, loss,
                                                 loss_scale)
        cov = cov + cov_cal
    return combine_rel_std(rel_noise, rel_cal), {
        "scale_rel_std_noise": rel_noise, "scale_rel_std_calibration": rel_cal,
        "covariance": cov}


def with_calibration(motion, rays: RayPairs, calibration_std,
                     max_scale_rel_std: float = 0.1):
    """``motion`` (a :class:`mcgeom.types.RigMotion` of any estimator on ``rays``)
    with the rig's extrinsic calibration error in its scale uncertainty.

    For the estimators that do not propagate it themselves (no
    ``info['scale_rel_std_calibration']``): a metric ``t`` (observable, or
    determined) gets :func:`calibration_scale_std` at (R, t) added in
    quadrature to its ``rel_std`` (:func:`combine_rel_std`), and the verdict
    is decided again on the total against ``max_scale_rel_std``: an estimate
    whose scale the calibration leaves loose is no longer called observable
    (thesis ch. 7's verdict, with the uncertainty of the rig itself).
    ``calibration_std`` as :attr:`mcgeom.rig.Rig.extrinsic_std` ((M, 2):
    metres, radians per camera id, or one pair). Static answers (``t = 0``)
    and direction-only ones are returned unchanged.
    """
    info = motion.info if isinstance(motion.info, dict) else {}
    t = np.asarray(motion.t, dtype=np.float64)
    if calibration_std is None or "scale_rel_std_calibration" in info or \
            not np.any(t != 0) or not np.isfinite(motion.scale.rel_std) or \
            not (motion.scale.observable or info.get("scale_determined", False)):
        return motion
    cal, _ = calibration_scale_std(rays, motion.R, t, calibration_std)
    total = combine_rel_std(float(motion.scale.rel_std), cal)
    v = motion.scale
    observable = bool(v.observable and total <= max_scale_rel_std)
    if v.observable and not observable:
        reason = (f"scale too uncertain with the rig's calibration error: relative std of "
                  f"|t| {total:.3g} (noise {v.rel_std:.3g}, calibration {cal:.3g}) above "
                  f"{max_scale_rel_std:g}; {v.reason}")
    else:
        # the estimator's reason quotes its noise-only std: say what rel_std now is
        reason = (f"{v.reason}; with the rig's calibration error the relative std of |t| "
                  f"is {total:.3g} (noise {v.rel_std:.3g}, calibration {cal:.3g})")
    verdict = ScaleVerdict(observable, reason, v.conditioning, total, v.critical_angle)
    new_info = {**info, "scale_rel_std_noise": float(v.rel_std),
                "scale_rel_std_calibration": float(cal)}
    return replace(motion, scale=verdict, info=new_info)


#: rigs drawn by :func:`with_sampled_calibration` (antithetic pairs): near
#: the critical motion the refit tips into another scale's valley for a
#: fraction of the rigs (DDAD scene_02's first step: 10 % of 512 rigs moved
#: |t| by 40-74 %, the rest by a std of ~0.06); 128 rigs hold at least 4
#: such draws, enough to lift the sampled std above 0.1 there, with
#: probability 0.9992 (binomial, 10 % a draw)
SAMPLED_DRAWS = 128

#: intra-camera pairs refitted at most by :func:`with_sampled_calibration`
#: (a weighted subset, every cross-camera pair kept: see
#: :func:`sampled_calibration_scale_std`'s ``max_intra``)
SAMPLED_MAX_INTRA = 1024


def with_sampled_calibration(motion, rays: RayPairs, calibration_std,
                             max_scale_rel_std: float = 0.1, draws: int = SAMPLED_DRAWS,
                             seed: int = 0, weights: np.ndarray | None = None,
                             loss: str = "none", loss_scale: float = 1e-3):
    """``motion`` (a :class:`mcgeom.types.RigMotion` estimated from ``rays``,
    with ``inliers``) with its calibration part of the relative std of |t|
    checked by sampling (:func:`sampled_calibration_scale_std` on its
    inliers; ``weights`` (N,), one per pair of ``rays``, ``loss`` and
    ``loss_scale`` radians those of its final refinement).

    Only a metric motion (``scale.observable``, ``t`` not 0) is checked.
    Where the sampled part exceeds the first-order one that the verdict used
    (``info['scale_rel_std_calibration']``, 0 when absent), it replaces it in
    the total (the rest of the total, ``sqrt(rel_std^2 - first^2)``, is
    kept), and a total above ``max_scale_rel_std`` is no longer metric:
    near the critical motion of thesis ch. 7.3.2 a rig off by its stated
    calibration error can move |t| far more than the first-order figure
    says. ``info`` gains ``scale_rel_std_calibration_sampled`` (and the
    draws). Costs ``draws`` refinements on the inliers (at most
    :data:`SAMPLED_MAX_INTRA` intra-camera ones, all cross-camera ones). A
    refit that fails on a drawn rig (degenerate or numerical trouble) leaves
    the scale unconfirmed: not metric, the reason says why.
    """
    info = motion.info if isinstance(motion.info, dict) else {}
    t = np.asarray(motion.t, dtype=np.float64)
    v = motion.scale
    if calibration_std is None or not v.observable or not np.any(t != 0) \
            or not np.isfinite(v.rel_std) or motion.inliers is None:
        return motion
    sel = np.flatnonzero(np.asarray(motion.inliers, dtype=bool))
    if sel.size < _MOTION_DOF:
        return motion
    first = float(info.get("scale_rel_std_calibration", 0.0))
    w = None if weights is None else np.asarray(weights, dtype=np.float64)
    if w is not None and w.shape != (len(rays),):
        raise ValueError(f"weights must have shape ({len(rays)},), one per pair, got {w.shape}")
    failure: object = "no finite travel"
    try:
        sampled = sampled_calibration_scale_std(
            rays.take(sel), motion.R, t, calibration_std, draws=draws, seed=seed,
            weights=None if w is None else w[sel], loss=loss, loss_scale=loss_scale,
            max_intra=SAMPLED_MAX_INTRA)
    except (ArithmeticError, DegenerateError) as exc:   # (NumericalError is one)
        sampled, failure = float("nan"), exc
    if not np.isfinite(sampled):
        reason = (f"scale not confirmed: the refit on rigs drawn with the calibration error "
                  f"failed ({failure}); {v.reason}")
        return replace(motion, scale=ScaleVerdict(False, reason, v.conditioning, v.rel_std,
                                                  v.critical_angle),
                       info={**info, "scale_rel_std_calibration_sampled": sampled})
    new_info = {**info, "scale_rel_std_calibration_sampled": sampled,
                "calibration_draws": draws}
    if not sampled > first:
        return replace(motion, info=new_info)
    rest = math.sqrt(max(float(v.rel_std) ** 2 - first ** 2, 0.0))
    total = combine_rel_std(rest, sampled)
    observable = total <= max_scale_rel_std
    if observable:
        reason = (f"{v.reason}; with the rig's calibration error sampled ({draws} rigs) the "
                  f"relative std of |t| is {total:.3g} (calibration {sampled:.3g}, first "
                  f"order {first:.3g})")
    else:
        reason = (f"scale too uncertain with the rig's calibration error: rigs drawn with it "
                  f"({draws}) move |t| by a relative std of {sampled:.3g} (first order "
                  f"{first:.3g}), total {total:.3g} above {max_scale_rel_std:g}; {v.reason}")
    verdict = ScaleVerdict(observable, reason, v.conditioning, total, v.critical_angle)
    return replace(motion, scale=verdict, info=new_info)
