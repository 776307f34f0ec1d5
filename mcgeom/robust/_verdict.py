"""The scale verdict and the returned ``RigMotion`` of a robust estimate
(both searches), and the search's confidence."""

from __future__ import annotations

import math
import time
from dataclasses import replace
from typing import Any, Optional

import numpy as np

# travel_direction: the direction an estimator reports when |t| is not
# observable; the robust layer finishes any estimator's motion and must report
# the same (see mcgeom.estimators._common: no estimator imports this package)
from .. import _core
from ..estimators._common import in_mirrored_minimum, travel_direction
from ..estimators._outliers import MAX_LEVERAGE, SCREEN_LEVERAGE, one_pair_rule
from ..observability import (ZERO_FACTOR, combine_rel_std, scale_determined, scale_profile,
                             scale_verdict, scale_verdict_stats, total_scale_std, verdict_text)
from ..types import RayPairs, RigMotion, ScaleVerdict
from ._options import RansacOptions
from ._scoring import true_fraction


def search_confidence(samples: int, sample_size: int, inlier_fraction: float) -> float:
    """How likely a search of ``samples`` uniform samples of ``sample_size``
    correspondences drew one of inliers only, at an ``inlier_fraction`` of
    them: 1 - (1 - w^m)^k (the adaptive stop's rule read backwards; the C
    search's ``confidence``, csrc/robust.c search_confidence)."""
    p = float(inlier_fraction) ** int(sample_size)
    if samples <= 0 or not p > 0.0:
        return 0.0
    if not p < 1.0:
        return 1.0
    return float(-math.expm1(samples * math.log1p(-p)))


def unconfirmed_reason(stop: str, samples: int, sample_size: int, confidence: float
                       ) -> Optional[str]:
    """The verdict's reason when a cap (``stop`` not "confidence") ended the
    search at a ``confidence`` below :data:`CONFIRMED`, else None."""
    if stop == "confidence" or confidence >= CONFIRMED:
        return None
    return (f"consensus not confirmed: the search reached its "
            f"{'time limit' if stop == 'max_seconds' else 'sample cap'} after {samples} "
            f"samples of {sample_size} with a chance of {confidence:.2g} to have drawn one of "
            f"inliers of this consensus; the motion may be a partial fit: raise the cap "
            f"(maxIters, max_iters) or the time limit")


def conclude(rays: RayPairs, R: np.ndarray, t: np.ndarray, r: Optional[np.ndarray],
             inl: np.ndarray, fit: Optional[tuple], loss_scale: float, n0: float,
             options: RansacOptions, method: str, info: dict, t_start: float,
             profile: Optional[float] = None, calibration_std: Any = None,
             rms: Optional[float] = None, c_ids: Optional[tuple] = None,
             zero_profile: float = float("nan"),
             unconfirmed: Optional[str] = None) -> RigMotion:
    """Scale verdict and the returned ``RigMotion`` of a robust estimate.

    ``r`` are the residuals at the final (R, t) (pixels when thresholds are),
    ``inl`` the inliers; ``fit`` = (refinement dict, the mask of the pairs it
    used, its loss scale (radians), their weights) of the final refinement,
    None without one (``loss_scale`` then sets the noise level); ``n0`` the
    length of the robust hypothesis' t before the refinement; ``profile`` the
    statistic of :func:`scale_profile`, when already computed (by C);
    ``calibration_std`` as in :func:`ransac` (its effect enters ``rel_std``);
    ``rms`` the RMS residual of the inliers when the caller has it (``r`` may
    then be None). ``c_ids = (cam1, cam2, n_cameras, mask, stats)`` (the C
    search's camera ids, its inlier mask, bit 0, and the verdict's evidence
    it gathered, or None) switches the verdict's evidence and the travel
    direction to one C pass over all the rays (:func:`scale_verdict_stats`);
    ``zero_profile`` the statistic of :func:`scale_profile` at
    ``ZERO_FACTOR`` when already computed (by C). ``unconfirmed``: None, or
    why the search's consensus is not confirmed (a cap ended it at a
    confidence below :data:`CONFIRMED`): then no scale is reported (the
    verdict says why, ``t`` is the unit direction of travel).
    """
    rel_std = float("inf")
    given, profile = profile, float("nan")
    if fit is not None:
        out, used, scale_used, w_used = fit
        info["refinement"] = {k: out[k] for k in ("iterations", "converged") if k in out}
        # (the rays enter only the calibration part: no copy without one)
        rel_std, parts = total_scale_std(rays if calibration_std is None else rays.take(used),
                                         R, t, out, calibration_std, w_used, options.loss,
                                         scale_used)
        info.update(parts)
    info.update(inlier_ratio=float(true_fraction(inl)), time_s=time.perf_counter() - t_start)
    if fit is not None and rel_std <= options.max_scale_rel_std:
        if given is not None and math.isfinite(given):
            profile = float(given)
        else:
            k = 1.0 + 3.0 * options.max_scale_rel_std
            profile = scale_profile(rays.take(used), R, t, out["final_cost"], out["sigma2"],
                                    (1.0 / k, k), options.loss, scale_used, w_used)
        info["scale_profile"] = profile
    noise_level = fit[2] if fit is not None else loss_scale
    direction = None
    if c_ids is not None:
        cam1, cam2, n_cameras, mask, stats = c_ids
        verdict, direction = scale_verdict_stats(rays, cam1, cam2, n_cameras, mask, R, t,
                                                 rel_std, options.max_scale_rel_std,
                                                 noise_level=noise_level, profile=profile,
                                                 prechecked=cam1.dtype == np.int32,
                                                 stats=stats)
    else:
        v_rays, v_inl = _verdict_sample(rays, inl, options.seed)
        verdict = scale_verdict(v_rays, v_inl, R, t, rel_std, options.max_scale_rel_std,
                                noise_level=noise_level, profile=profile)
    if unconfirmed is not None and not verdict.reason.startswith("no translation"):
        # (a static rig keeps its verdict: t = 0 whatever the consensus)
        verdict = replace(verdict, observable=False, reason=unconfirmed)
    info["translation_detected"] = not verdict.reason.startswith("no translation")
    # the metric estimate whatever the verdict (when the scale is unobservable
    # the refinement may have slid |t| far along its flat valley: a guess)
    info["t_metric"] = np.array(t)
    # t is the metric estimate unless the branches below find it undetermined
    determined = info["translation_detected"]
    if not info["translation_detected"]:
        # static rig or pure rotation: the verdict says t = 0 (as the search
        # that finds no motion at all does, _no_translation), not a unit
        # vector whose direction the data do not determine
        t = np.zeros(3)
    elif not verdict.observable:
        nt = math.hypot(*np.asarray(t, dtype=np.float64).tolist())
        # Slid out along the flat valley (|t| grew more than 10x: the cost
        # keeps falling towards |t| = infinity, the central-camera limit):
        # keep the robust hypothesis' length. A large drop is no such slide:
        # near the critical motion the 1-point scale search may propose a
        # huge |t|, which the refinement on all inliers brings back
        # (measured on the Ladybug head: 565 -> 1.06, 45 -> 0.97 for |t| = 1).
        slid = not nt <= 10.0 * n0
        if direction is None:
            direction = travel_direction(rays, inl, R, t)
        info["t_direction"] = direction
        # A refined t in the mirrored minimum (in_mirrored_minimum) is no
        # metric estimate either: it is treated as slid: the direction, the
        # hypothesis' length. (A t dominated by the rotation-induced shift
        # may point elsewhere, up to ~130 deg off on KITTI, and is left alone.)
        slid = slid or in_mirrored_minimum(direction, t)
        if slid:
            nt = n0
        info["t_slid"] = slid
        zero = float("nan")
        if fit is not None and not slid and scale_determined(rel_std):
            zero = zero_profile
            if not math.isfinite(zero):
                zero = scale_profile(rays.take(used), R, t, out["final_cost"], out["sigma2"],
                                     (ZERO_FACTOR,), options.loss, scale_used, w_used)
        if slid or unconfirmed is not None or not scale_determined(rel_std, zero_profile=zero):
            # the data define no scale: a unit direction (issue 18: never a
            # silent unit vector where a metric estimate exists, and never a
            # metric-looking one where none does)
            # (info['t_metric'] keeps the refined t, the least-squares guess,
            # unless it slid out: then the hypothesis' length along the travel)
            if slid:
                info["t_metric"] = nt * direction
            t = direction
            determined = False
    info["scale_determined"] = determined
    if rms is None:
        rms = float(np.sqrt(np.mean(r[inl] ** 2))) if inl.any() else float("nan")
    return RigMotion(np.asarray(R), np.asarray(t), verdict, f"ransac[{method}]", rms, inl, info)


#: the reasons of the C search's verdict (``mcg_robust_result.scale``) that
#: :func:`conclude_c` words; the others (static: its text quotes the numpy
#: fit; undecided) take :func:`conclude`
C_WORDED = frozenset(k for k, v in _core.SCALE_REASONS.items()
                     if v not in ("static", "undecided"))
_AT = _core.RESULT_OFFSETS


def conclude_c(res: Any, f: np.ndarray, inl: np.ndarray, options: RansacOptions, method: str,
               info: dict, t_start: float, unconfirmed: Optional[str]) -> RigMotion:
    """The RigMotion of a C search whose own verdict decided the scale
    (``res``: its ``mcg_robust_result *``, ``res.scale.reason`` in
    :data:`C_WORDED`; ``f`` :func:`mcgeom._core.robust_struct` of it): what
    :func:`conclude` returns for it, the decisions taken in C
    (csrc/robust_verdict.c: the same rules on the same evidence), only the
    words and ``info`` made here (issue 19: the verdict's Python was ~1/3 of
    a cold call's time outside C). ``info`` as :func:`conclude` receives it,
    ``unconfirmed`` its :func:`unconfirmed_reason`."""
    sc, v = res.scale, res.verdict
    rel_std = float("inf")
    if res.refined:
        info["refinement"] = {"iterations": res.refinement.iterations,
                              "converged": bool(res.refinement.converged)}
        noise, cal = sc.rel_std_noise, sc.rel_std_calibration
        rel_std = combine_rel_std(noise, cal)
        k = _AT["scale_covariance"]
        info.update(scale_rel_std_noise=noise, scale_rel_std_calibration=cal,
                    covariance=f[k:k + 36].reshape(6, 6))
    # (the inlier count of the mask, from C: true_fraction(inl)'s value)
    info.update(inlier_ratio=res.n_inliers / inl.size, time_s=time.perf_counter() - t_start)
    profile = float("nan")
    if res.refined and rel_std <= options.max_scale_rel_std:
        profile = info["scale_profile"] = sc.profile
    reason = _core.SCALE_REASONS[sc.reason]
    n_in, crit = v.n_inliers, v.critical_angle
    # the checks of the consensus of an observable scale, in the same call
    # (csrc/consensus.c; one_pair_checked's for the other paths)
    c = _core.consensus_dict(res.consensus) if res.have_consensus else None
    if c is not None:
        _consensus_info(info, c)
    if reason == "unconfirmed":
        text = unconfirmed
        # (the verdict it replaces keeps its std: inf for too few inliers)
        quoted = float("inf") if n_in <= 6 else rel_std
    elif reason == "consensus":
        text, quoted = _consensus_reason(c, rel_std, options, method), rel_std
    else:
        text = verdict_text(reason, n_in, v.n_cross, v.n_cameras_intra, crit, rel_std,
                            options.max_scale_rel_std, profile, sc.front_fraction)
        quoted = float("inf") if reason == "no_redundancy" else rel_std
        if c is not None and c["rel_std"] != rel_std:
            text, quoted = "; ".join([text] + _consensus_notes(c)), c["rel_std"]
    observable = bool(sc.observable)
    info["translation_detected"] = True
    k = _AT["scale_t_metric"]
    info["t_metric"] = f[k:k + 3]
    if not observable:
        k = _AT["t_direction"]
        info["t_direction"] = f[k:k + 3]
        info["t_slid"] = sc.slid == 1
        if sc.slid == 1:   # the hypothesis' length along the travel, as conclude
            info["t_metric"] = math.hypot(*f[12:15].tolist()) * f[k:k + 3]
    info["scale_determined"] = bool(sc.determined)
    k = _AT["scale_t"]
    return RigMotion(f[:9].reshape(3, 3), f[k:k + 3],
                     ScaleVerdict(observable, text, float("nan"), quoted, crit),
                     f"ransac[{method}]", res.inlier_rms, inl, info)


def _consensus_reason(c: dict, rel_std: float, options: RansacOptions, method: str
                      ) -> Optional[str]:
    """The words of :func:`mcgeom._core.consensus_check`'s result ``c`` for a
    robust estimate whose relative std of |t| was ``rel_std``: why its scale
    is not metric (None: it is)."""
    pairs = ", ".join(str(k) for k in c["dropped"])
    tail = (f"the consensus of ransac[{method}] rests on them; more correspondences or "
            f"cameras would confirm the scale")
    rel, move, max_rel = c["lever_rel_std"], c["lever_move"], options.max_scale_rel_std
    reason = c["reason"]
    if reason == "one_pair":
        return one_pair_rule(c["stats"], f"ransac[{method}]", max_rel, consensus=True)
    if reason == "undetermined":
        return (f"scale not confirmed: correspondence(s) {pairs} fix a direction of the "
                f"motion almost alone (leverage above {MAX_LEVERAGE:g}) and without them the "
                f"motion is not determined; {tail}")
    if reason == "lever_std":
        return (f"scale not confirmed: without correspondence(s) {pairs} (leverage above "
                f"{MAX_LEVERAGE:g}: an error in them would not show in any residual) the "
                f"relative std of |t| is {rel:.3g}; {tail}")
    if reason == "lever_move":
        return (f"scale not supported by the bulk of the inliers: without "
                f"correspondence(s) {pairs} (leverage above {SCREEN_LEVERAGE:g}) the "
                f"travelled distance moves by {100 * move:.3g} %, "
                f"{move / rel_std:.3g} of its stds -- wrong matches the refinement "
                f"absorbed; {tail}")
    if reason == "widened_std":
        return (f"scale too uncertain: without correspondence(s) {pairs} (leverage above "
                f"{SCREEN_LEVERAGE:g}: errors in them would show little in any residual) the "
                f"rest of the consensus fixes |t| to a relative std of {rel:.3g} and the "
                f"travelled distance moves by {100 * move:.3g} %: a relative std of "
                f"{c['rel_std']:.3g} > {max_rel:g}; {tail}")
    if reason == "residuals_std":
        return (f"scale too uncertain: {_residuals_said(c)}; {c['rel_std']:.3g} > {max_rel:g}; "
                f"the consensus of ransac[{method}] does not fix |t| well enough")
    return None


def _consensus_info(info: dict, c: dict) -> None:
    """``info``'s entries of the checks of the consensus ``c``
    (:func:`mcgeom._core.consensus_check`)."""
    st = c["stats"]
    info["max_leverage"] = st["max_leverage"] if st else float("nan")
    info["max_influence_stds"] = st["max_influence_stds"] if st else float("nan")
    if not math.isnan(c["residuals_rel_std"]):
        info["scale_rel_std_residuals"] = c["residuals_rel_std"]
    if c["lever_move"] is not None:
        info["lever_pairs_move"] = c["lever_move"]
    if c["widened_by_lever"]:
        info["scale_rel_std_consensus"] = c["rel_std_lever"]


def _consensus_notes(c: dict) -> list[str]:
    """What the reason of a metric scale adds where the checks of its
    consensus ``c`` widened its std."""
    notes = []
    if c["widened_by_lever"]:
        notes.append(f"the relative std of |t| is {c['rel_std_lever']:.3g} without the "
                     f"correspondences of leverage above {SCREEN_LEVERAGE:g}, whose errors "
                     f"would show little in their residuals (the travel moves by "
                     f"{100 * c['lever_move']:.3g} % without them)")
    if c["widened_by_residuals"]:
        notes.append(_residuals_said(c))
    return notes


def _residuals_said(c: dict) -> str:
    """What the std of the inliers' own residuals says (``c`` a result of
    :func:`mcgeom._core.consensus_check` that it widened)."""
    hc, before = c["rel_std"], c["rel_std_lever"]
    return (f"the inliers' own residuals put the relative std of |t| at {hc:.3g} "
            f"(heteroscedasticity-consistent, HC3), {hc / before:.3g} times what one noise "
            f"level for all of them gives: some fit worse than the noise -- wrong matches "
            f"within the threshold, or noise beyond the model")


def one_pair_checked(m: RigMotion, rays: RayPairs, weights: Optional[np.ndarray],
                     options: RansacOptions, method: str) -> RigMotion:
    """``m``, a robust estimate on ``rays``, after the checks of its consensus
    (:func:`mcgeom._core.consensus_check`, csrc/consensus.c) on its final
    refinement (``weights``: that refinement's, float64 (N,), 0 for the
    pairs it did not use): its scale not metric and ``t`` the unit direction
    of travel where one correspondence, or a few of high leverage, carry
    the fit -- deleting one pair moves the travel by more than 4 stds and
    more than ``max_scale_rel_std``, or the refit without the pairs of
    leverage above 0.5 says so -- or where the std it reports, widened by
    that refit or by the std of the inliers' own residuals (HC3), exceeds
    ``max_scale_rel_std``; else its std so widened, the reason saying why.
    ``info["max_leverage"]``, ``info["max_influence_stds"]``,
    ``info["lever_pairs_move"]``, ``info["scale_rel_std_consensus"]``,
    ``info["scale_rel_std_residuals"]``.

    A wrong match that the consensus took in, with the leverage to pull the
    refinement onto itself, leaves every residual small: on the property
    suite's four rig kinds with 60 or 200 correspondences, 1e-3 rad noise and
    10-50 % random time-2 bearings (``robust.ransac`` at 3e-3 rad, 20
    problems per cell), 13 of 427 metric estimates were 10-73 % off at
    reported stds of 0.4-5 %, each with a used pair of leverage 0.80-0.997;
    4 of 411 with the one-pair rule and the refit without pairs of leverage
    above 0.9 (session 35), none of 404 with the refit without those above
    0.5 and the widened std (``mcgeom experiment direct_outliers --robust``).
    A wrong match that falls within the threshold has a residual spread over
    the threshold band, not the noise, and where it helps fix |t| moves the
    estimate by more than the std of one noise level says: with 10 / 30 /
    50 % random time-2 bearings (five_plus_one, 50 problems per rig kind,
    200 pairs) the rms of error / std was 1.18 / 1.20 / 1.31 (1.03 without
    outliers), 1.02 / 1.03 / 1.09 (0.99) with the HC3 std where it exceeds
    the reported one by 1.25x (session 38)."""
    if not m.scale.observable or weights is None:
        return m
    a = (rays.origins1, rays.dirs1, rays.origins2, rays.dirs2)
    cal = m.info.get("scale_rel_std_calibration", 0.0)
    try:
        c = _core.consensus_check(*a, weights, m.R, m.t, m.scale.rel_std,
                                  cal if math.isfinite(cal) else 0.0, options.max_scale_rel_std)
    except ValueError:      # (input the kernel refuses: nothing decided)
        return m
    info = m.info
    _consensus_info(info, c)
    why = _consensus_reason(c, m.scale.rel_std, options, method)
    if why is None:
        if c["rel_std"] == m.scale.rel_std:
            return m
        reason = "; ".join([m.scale.reason] + _consensus_notes(c))
        return replace(m, scale=replace(m.scale, rel_std=c["rel_std"], reason=reason))
    t_dir = travel_direction(rays, m.inliers, m.R, m.t)
    info.update(t_direction=t_dir, t_slid=False, scale_determined=False)
    return RigMotion(m.R, t_dir, replace(m.scale, observable=False, reason=why), m.method,
                     m.residual_rms, m.inliers, info)


#: the confidence (``info["confidence"]``: how likely the search drew a sample
#: of inliers of its consensus, csrc/robust.c search_confidence) below which
#: a search that its cap ended reports no scale: it is less likely than not
#: that the search drew a sample of inliers of the consensus it returns
#: (17-point RANSAC and the eigensolver sampler at their 1000-sample cap on
#: the Ladybug head, 30 % outliers, 30 problems each: right motions at
#: 0.90-0.92, partial fits 0.8-2.4 deg off with 9-24 % of the pairs at
#: 2e-4 or less, of which 3 had been called metric)
CONFIRMED = 0.5


#: intra-camera inliers the verdict's statistics (no-parallax fraction,
#: cheirality fraction) look at, at most (a uniform random sample beyond)
VERDICT_SAMPLE = 20000


def _verdict_sample(rays: RayPairs, inl: np.ndarray, seed: Optional[int]
                    ) -> tuple[RayPairs, np.ndarray]:
    """The rays and inlier mask :func:`scale_verdict` is run on.

    Up to :data:`VERDICT_SAMPLE` intra-camera inliers, all of them (the rays
    themselves, unchanged). Beyond, the verdict's O(N) numpy passes (a
    rotation fit, the cheirality test, ~1 us per inlier: 1.2 s of Python at
    1e6 inliers, issue 19) run on every cross-camera inlier, the first
    intra-camera inlier of every camera (so that the cameras with inliers,
    the critical angle and the cross-camera count are exactly those of all
    inliers) and a uniform random sample of VERDICT_SAMPLE intra-camera
    inliers: the two fractions it tests (no parallax: >= 90 % of the
    rotation residuals small; cheirality: >= 50 % in front) are then
    estimated with a binomial std below 0.4 %.
    """
    if rays.cam1 is None or rays.cam2 is None:
        return rays, inl
    idx = np.flatnonzero(inl)
    same = rays.cam1[idx] == rays.cam2[idx]
    intra = idx[same]
    if intra.size <= VERDICT_SAMPLE:
        return rays, inl
    cams = rays.cam1[intra]
    # the first of each camera: one pass per camera present (a sort of all
    # of them, np.unique, costs more at 1e6)
    first = [int(np.argmax(cams == k)) for k in np.flatnonzero(np.bincount(cams))]
    rng = np.random.default_rng(seed)
    pick = rng.choice(intra.size, VERDICT_SAMPLE, replace=False)
    keep = np.union1d(np.union1d(intra[pick], intra[first]), idx[~same])
    sub = rays.take(keep)
    return sub, np.ones(len(sub), bool)
