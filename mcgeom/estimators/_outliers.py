"""A least-squares estimate that rests on gross outliers is not called metric.

The direct estimators take every correspondence as an inlier
(:func:`mcgeom.robust.ransac` is the robust path). Given a few gross outliers
anyway, their least-squares fit is pulled, and its first-order std, which
assumes the model, does not see it: on a 4-camera ring (intra-camera rays,
0.5 px, 300 correspondences of which 1 % had a random time-2 bearing),
``five_plus_one`` called 3 of 20 estimates metric, 2 of them with |t| 92-95 %
off at a std of 4-6 % and the rotation 3.5-6 deg off; with the rotation
known, 3 % outliers, ``known_rotation_translation`` called 4 of 20 metric,
all 93-95 % off.

The check (:func:`guard_verdict`): at the estimate, the residuals' robust
scale ``s = 1.4826 median |r|`` (the median absolute deviation, Rousseeuw &
Croux 1993; a 50 % breakdown point); the estimate refitted with a Cauchy
loss of scale ``s``, which bounds the pull of a residual far beyond ``s``
(a redescending M-estimator, Huber 1981, ch. 4); if the cameras' travel
``|t + R c - c|`` (c their centroid) moves by more than
:data:`OUTLIER_MOVE_STDS` of the estimate's relative std and by more than
the verdict's ``max_rel_std`` (the precision a metric claim promises), the
least-squares travel is not what the bulk of the correspondences say, and the
scale is not observable. Measured on the cases above: every wrong metric
estimate but one moved by 5-4e6 stds and 21-4e5 %; on clean data (30 problems
each) the moves stayed below 1 std for ``five_plus_one`` and below 3 for
``known_rotation_translation`` with its rotation held, as the refit holds it.
The relative bound is for real data: their residuals have heavier tails than
Gaussian noise (calibration error, near-mismatches among RANSAC's inliers),
and the Cauchy refit moved correct estimates by 1-2 % -- several noise stds
of 0.2 % -- on the KITTI raw and DDAD pairs of ``mcgeom experiment honesty``
(with the std alone: 6 of 6 KITTI estimates of ``eigensolver`` called
metric before, 1 after). The exception: a fit that lands in a wrong basin
rather than being pulled (``upright_four_point``, 1 % outliers, one of 20:
|t| 96 % off, the rotation 5.7 deg off); there the Cauchy refit, too, stays
(its robust scale 1.8e-2 rad, the noise 1e-3). That estimator has a prior the
fit can be checked against, the vertical, and its rotation turned the given
vertical 5 deg away: :func:`mcgeom.estimators.upright_four_point.vertical_contradiction`
withholds the metric scale there.

Frames and units (docs/architecture.md §3): rays in the rig frame (metres),
``X2 = R X1 + t``; residuals in radians.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Optional

import numpy as np

from .. import _core
from ..errors import DegenerateError
from ..geometry import centroid_travel, refine_centred
from ..types import RayPairs, ScaleVerdict

__all__ = ["OUTLIER_MOVE_STDS", "MAX_LEVERAGE", "DELETION_STDS", "SCREEN_LEVERAGE",
           "SCREEN_STDS", "residual_scale", "travel_moved", "one_pair_reason", "one_pair_rule",
           "guard_verdict", "moved_verdict"]

#: stds of the estimate's travel that a robust refit may move it by before the
#: least-squares estimate is called unsupported by the bulk of the data
OUTLIER_MOVE_STDS = 3.0

#: largest leverage of one correspondence in a metric least-squares estimate
#: (its redundancy number 1 - h at least 0.1: below, geodetic reliability
#: analysis counts an observation as uncontrolled, Foerstner 1987); see
#: :func:`one_pair_reason`
MAX_LEVERAGE = 0.9

#: stds of the travel that deleting one correspondence may move it by (and
#: by more than the verdict's ``max_rel_std``); see :func:`one_pair_reason`
DELETION_STDS = 4.0

#: ``linear17`` runs the robust refit of :func:`moved_verdict` (~100 us, its
#: whole call is ~50 us) only where a pair's leverage (and 3 p / n, the
#: average's triple) or deletion move reaches these: several outliers
#: masking each other can leave each below the
#: one-pair rules yet together pull the fit (one problem of 20, 200 rays of a
#: 2-camera head, 3 outliers: leverages 0.58-0.67, moves 1.0-1.8 stds, |t| 50
#: % short; the refit moves it back to the truth); clean estimates with 200
#: rays stay below 0.4 and 1.1
SCREEN_LEVERAGE = 0.5
SCREEN_STDS = 1.5

#: the median absolute deviation of a Gaussian over its std's
_MAD_TO_STD = 1.4826

#: below this robust scale (radians) the estimate fits the majority exactly
#: (noise-free data): no outlier can have pulled it
_EXACT = 1e-12


def residual_scale(rays: RayPairs, R: np.ndarray, t: np.ndarray) -> float:
    """The robust scale 1.4826 median |r| (radians) of the Sampson residuals of
    ``(R, t)`` on ``rays``."""
    r = _core.gec_residuals(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, R, t)
    return _MAD_TO_STD * float(np.median(np.abs(r)))


def travel_moved(rays: RayPairs, R: np.ndarray, t: np.ndarray, rel_std: float,
                 hold_rotation: bool = False, scale: Optional[float] = None) -> float:
    """How many of its relative std ``rel_std`` the cameras' travel of the
    estimate ``(R, t)`` (rig2_from_rig1, metres) moves when the estimate is
    refitted on ``rays`` with a Cauchy loss at the residuals' robust scale
    (``hold_rotation``: R held, as a known rotation is). 0 where the estimate
    fits the majority exactly or ``rel_std`` is not a positive number; NaN
    where the refit fails. ``scale``: that robust scale when the caller has
    it (:func:`residual_scale`)."""
    if not (math.isfinite(rel_std) and rel_std > 0):
        return 0.0
    s = residual_scale(rays, R, t) if scale is None else scale
    if not s > _EXACT:
        return 0.0
    try:
        if hold_rotation:
            fit = _core.refine_translation(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2,
                                           R, t, loss="cauchy", loss_scale=s)
        else:
            fit = refine_centred(rays, R, t, loss="cauchy", loss_scale=s)
    except (ValueError, DegenerateError):
        return float("nan")
    before = centroid_travel(rays, R, t)
    after = centroid_travel(rays, fit["R"], fit["t"])
    if not before > 0:
        return 0.0
    return abs(after / before - 1.0) / rel_std


def one_pair_reason(rays: RayPairs, R: np.ndarray, t: np.ndarray, method: str,
                    max_rel_std: float = 0.1, hold_rotation: bool = False,
                    info: Optional[dict] = None) -> Optional[str]:
    """Why the least-squares estimate ``(R, t)`` of ``method`` on all ``rays``
    rests on one correspondence, None when it does not (``_core.leverage_stats``,
    ``csrc/leverage.c``; ``hold_rotation``: R held, t alone fitted):

    * its leverage is above :data:`MAX_LEVERAGE`: it fixes a direction of the
      motion by itself, and an error in it shows in no residual;
    * deleting it alone moves the cameras' travel by more than
      :data:`DELETION_STDS` of the travel's std and by more than
      ``max_rel_std`` (Cook's case deletion, linearised at the fit).

    ``info`` gets ``max_leverage`` and ``max_influence_stds`` (NaN where the
    Jacobian is singular; absent when the majority fits exactly).

    A gross outlier pulls a least-squares fit toward itself, and most where
    it has the leverage to: the fit absorbs the error, its residual and
    every other one stay small, and neither the residuals' robust scale nor
    the robust refit of :func:`travel_moved` (which starts in the pulled
    fit's basin) need see it. Measured on the property suite's four rig
    kinds with 20-200 correspondences, 1e-3 or 1e-4 rad noise and 2 %
    random time-2 bearings (20 problems per cell, `five_plus_one`,
    `six_point`, `upright_four_point`, `eigensolver`, `linear17`,
    `known_rotation_translation`; ``mcgeom experiment direct_outliers``): 76
    of the 144 cells with outliers had metric estimates with |t| 15-106 %
    off, 8 cells after the leverage test (a leverage 0.91-1.00 at
    the outlier; its residual 0.003 rad at the fit, 0.24 rad at the truth;
    clean metric estimates: at most 0.89 with 34 correspondences, 0.76 with
    60, 0.38 with 200), 2 after the deletion test (the outliers moved the
    travel by 5.0-14.8 of its stds and 18-69 %; clean estimates at most 2.8
    stds), none once ``linear17`` also runs the robust refit where these
    statistics are high (:data:`SCREEN_LEVERAGE`)."""
    st = _core.leverage_stats(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, R, t,
                              hold_rotation)
    return one_pair_rule(st, method, max_rel_std, info)


def one_pair_rule(st: Optional[dict], method: str, max_rel_std: float = 0.1,
                  info: Optional[dict] = None, consensus: bool = False) -> Optional[str]:
    """:func:`one_pair_reason`'s decision from the statistics ``st`` of
    ``_core.leverage_stats`` (None: singular, nothing decided); ``info`` gets
    ``max_leverage`` and ``max_influence_stds``. ``consensus``: the fit is a
    robust search's final refinement on its inliers (the reasons then say
    so) rather than a direct estimator's on every correspondence."""
    if info is not None:
        info["max_leverage"] = st["max_leverage"] if st else float("nan")
        info["max_influence_stds"] = st["max_influence_stds"] if st else float("nan")
    if st is None:
        return None
    if consensus:
        why = (f"the consensus of {method} rests on it, and a wrong match there would not "
               f"show in any residual: more correspondences or cameras would confirm the scale")
    else:
        why = (f"{method} takes every correspondence as an inlier: use mcgeom.robust.ransac, "
               f"or more correspondences")
    if st["max_leverage"] > MAX_LEVERAGE:
        return (f"scale not confirmed: correspondence {st['leverage_pair']} fixes a direction "
                f"of the motion almost alone (leverage {st['max_leverage']:.3g}, above "
                f"{MAX_LEVERAGE:g}), so an error in it (a gross outlier) would not show in any "
                f"residual; {why}")
    if st["max_influence_stds"] > DELETION_STDS and st["max_influence"] > max_rel_std:
        return (f"scale not supported by the bulk of the correspondences: deleting "
                f"correspondence {st['influence_pair']} alone moves the travelled distance by "
                f"{100 * st['max_influence']:.3g} % ({st['max_influence_stds']:.3g} of its "
                f"stds) -- the fit rests on one correspondence, maybe a gross outlier; {why}")
    return None


def guard_verdict(rays: RayPairs, R: np.ndarray, t: np.ndarray, verdict: ScaleVerdict,
                  method: str, max_rel_std: float = 0.1,
                  hold_rotation: bool = False,
                  info: Optional[dict] = None) -> tuple[ScaleVerdict, float]:
    """``(verdict, moved)``: the verdict of a least-squares estimate ``(R, t)``
    of ``method`` on all ``rays``, made "not observable" when one
    correspondence carries the fit (:func:`one_pair_reason`, which writes
    ``info["max_leverage"]`` and ``info["max_influence_stds"]``) or when a
    robust refit moves its travel by more than :data:`OUTLIER_MOVE_STDS` of
    its relative std and by more than ``max_rel_std`` (:func:`moved_verdict`;
    ``moved`` in stds, NaN when not checked: a verdict already not
    observable, or one correspondence carries the fit)."""
    if not verdict.observable:
        return verdict, float("nan")
    scale = residual_scale(rays, R, t)
    if not scale > _EXACT:
        return verdict, 0.0   # the majority fitted exactly: that motion is theirs
    why = one_pair_reason(rays, R, t, method, max_rel_std, hold_rotation, info)
    if why is not None:
        return replace(verdict, observable=False, reason=why), float("nan")
    return moved_verdict(rays, R, t, verdict, method, max_rel_std, hold_rotation, scale)


def moved_verdict(rays: RayPairs, R: np.ndarray, t: np.ndarray, verdict: ScaleVerdict,
                  method: str, max_rel_std: float = 0.1, hold_rotation: bool = False,
                  scale: Optional[float] = None) -> tuple[ScaleVerdict, float]:
    """``(verdict, moved)``: ``verdict`` (observable) made "not observable"
    when the robust refit of :func:`travel_moved` moves the travel by more
    than :data:`OUTLIER_MOVE_STDS` of its relative std and by more than
    ``max_rel_std``; ``moved`` in stds (``scale``: the residuals' robust
    scale, when the caller has it)."""
    moved = travel_moved(rays, R, t, verdict.rel_std, hold_rotation, scale)
    relative = moved * verdict.rel_std
    if not (moved > OUTLIER_MOVE_STDS and relative > max_rel_std):
        return verdict, moved
    reason = (f"scale not supported by the bulk of the correspondences: a robust (Cauchy) "
              f"refit moves the travelled distance by {100 * relative:.3g} % ({moved:.3g} of "
              f"its stds) -- the least-squares fit rests on gross outliers, and {method} "
              f"takes every correspondence as an inlier: use mcgeom.robust.ransac")
    return replace(verdict, observable=False, reason=reason), moved
