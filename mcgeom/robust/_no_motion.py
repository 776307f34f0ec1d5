"""When the search finds no motion: a static rig or pure rotation, a
threshold too small for the data, a cap that ended the search, or degenerate
data; and the check that the threshold is an angle below one radian."""

from __future__ import annotations

import time
from typing import Optional

import numpy as np

from ..errors import DegenerateError
from ..geometry import rotation_only_fit, rotation_only_residuals
from ..types import RayPairs, RigMotion, ScaleVerdict
from ._options import RansacOptions
from ._scoring import Scorer


#: largest inlier threshold as an angle (radians): above it every correspondence is an
#: inlier, and the Cauchy refinement's loss scale overflows long before 1e200 px
MAX_THRESHOLD_RAD = 1.0


#: a hypothesis that explains the minimal number of correspondences within this angle
#: (radians; 10 px at f = 1000 px, pixel noise and then some) fits the data: none within
#: the threshold means the threshold, not the data, is at fault
FITS_RAD = 1e-2


def _unit(focal: Optional[np.ndarray]) -> str:
    return "px" if focal is not None else "rad"


def check_threshold_angle(threshold: float, angle: float, focal: Optional[np.ndarray]) -> None:
    """ValueError naming ``threshold`` when it is an angle above :data:`MAX_THRESHOLD_RAD`
    (rather than "coordinates so large that the computation overflows" from the
    refinement, or every correspondence an inlier of a pure rotation)."""
    if angle > MAX_THRESHOLD_RAD:
        at = (f" at the rig's {float(np.median(focal)):.4g} px per radian"
              if focal is not None else "")
        limit = (f"{MAX_THRESHOLD_RAD * float(np.median(focal)):.4g} px" if focal is not None
                 else f"{MAX_THRESHOLD_RAD:g} rad")
        raise ValueError(f"threshold {threshold:g} {_unit(focal)} is an angular error of "
                         f"{angle:.3g} rad{at}: above {MAX_THRESHOLD_RAD:g} rad every "
                         f"correspondence is an inlier; it must be at most {limit} (of the "
                         f"order of the pixel noise, e.g. 1 px)")


def _threshold_too_small(rays: RayPairs, scorer: "Scorer", options: RansacOptions,
                         method: str, need: int) -> None:
    """DegenerateError naming ``threshold`` when hypotheses were found that fit ``need``
    correspondences closely, but not within the threshold: the threshold is below what
    even exact samples reach, the data are not degenerate."""
    if scorer.best is None:
        return
    r = np.sort(scorer.residuals(*scorer.best))
    if r.size < need:
        return
    r_k = float(r[need - 1])
    angle = r_k if scorer.focal is None else r_k / float(np.median(scorer.focal))
    if r_k > options.threshold and angle <= FITS_RAD:
        unit = _unit(scorer.focal)
        # a DegenerateError (a ValueError) as before: callers that catch "no motion
        # found" still do; the message names the threshold, not collinear points
        raise DegenerateError(f"threshold {options.threshold:g} {unit} is too small: the best of "
                         f"{scorer.n_hyp} hypotheses of {method} explains {need} "
                         f"correspondences within {r_k:.3g} {unit} but fewer within the "
                         f"threshold; pass a threshold of the order of the pixel noise "
                         f"(e.g. 1 px; if it is that already, the data do not determine the "
                         f"motion)")


def nothing_found(rays: RayPairs, scorer: "Scorer", options: RansacOptions, method: str,
                  t_start: float, need: int, counts: str,
                  ended: Optional[dict] = None) -> RigMotion:
    """No motion explains ``need`` correspondences: a static rig or pure
    rotation (:func:`_no_translation`), else DegenerateError; ``ended`` (how
    the search ended: ``iterations``, ``hypotheses``, ``stop``,
    ``sample_size``) names its cap when the cap ended it."""
    still = _no_translation(rays, scorer, options, method, t_start)
    if still is not None:
        return still
    _threshold_too_small(rays, scorer, options, method, need)
    if ended and ended.get("stop") in ("max_iterations", "max_seconds"):
        raise DegenerateError(_capped_message(rays, method, need, ended))
    raise DegenerateError(f"{method}: no motion found that explains at least {need} "
                          f"correspondences{counts}: degenerate data (e.g. points collinear or "
                          f"coplanar in every camera, or too few correspondences per camera: "
                          f"{per_camera_counts(rays)})")


def _capped_message(rays: RayPairs, method: str, need: int, ended: dict) -> str:
    """The error of a search that its cap ended with no consensus: the data
    may be degenerate, or no sample drawn was all inliers (issue 21: a
    17-pair sample is all inliers once in ~6,000 draws at 40 % outliers; the
    message blamed the data alone)."""
    k, m, h = int(ended["iterations"]), int(ended["sample_size"]), int(ended["hypotheses"])
    cap = ("its time limit (max_seconds)" if ended["stop"] == "max_seconds" else
           "its sample cap (maxIters of mcgeom.cv.estimate, max_iters of mcgeom.robust.ransac)")
    return (f"{method}: no motion found that explains at least {need} correspondences after "
            f"{k} sample{'' if k == 1 else 's'} ({h} hypothes{'is' if h == 1 else 'es'}): the "
            f"search reached {cap}. Either no sample was all inliers -- at an inlier fraction "
            f"w a sample of this sampler is with probability w^{m}: once in "
            f"{1 / 0.7 ** m:,.0f} draws at 30 % outliers, once in {1 / 0.5 ** m:,.0f} at "
            f"50 % -- then raise the cap, or use a sampler with smaller samples where the "
            f"data allow one (the default method picks 5+1, the upright or the 6-point "
            f"sampler); or the data are degenerate (e.g. points collinear or coplanar in "
            f"every camera; {per_camera_counts(rays)})")


def per_camera_counts(rays: RayPairs) -> str:
    """The intra-camera correspondences of each camera and the cross-camera
    ones, for the messages of a search that found nothing."""
    if rays.cam1 is None:
        return "camera ids unknown"
    same = rays.cam1 == rays.cam2
    counts = np.bincount(rays.cam1[same], minlength=int(rays.cam1.max(initial=0)) + 1)
    return (", ".join(f"camera {k}: {c}" for k, c in enumerate(counts)) +
            f"; {int((~same).sum())} cross-camera")


def _no_translation(rays: RayPairs, scorer: Scorer, options: RansacOptions, method: str,
                    t_start: float) -> Optional[RigMotion]:
    """When no motion was found: is it because the rig did not translate?

    A static rig (or a pure rotation) has no essential matrix: every search
    fails. If a pure rotation (refitted on its own inliers) explains at least
    half of the intra-camera correspondences within the threshold, report that
    rotation with ``t = 0`` and the verdict "no translation detected".
    """
    sel = np.ones(len(rays), bool)
    for _ in range(3):
        R, ang = rotation_only_fit(rays, sel)
        if ang.size < 5:
            return None
        r_all = rotation_only_residuals(rays, R)
        f = scorer.focal if scorer.focal is not None else 1.0
        sel = r_all * f < options.threshold
    same = (rays.cam1 == rays.cam2) if rays.cam1 is not None else np.ones(len(rays), bool)
    if sel.sum() < 5 or sel[same].mean() < 0.5:
        return None
    verdict = ScaleVerdict(False, "no translation detected: a pure rotation explains "
                                  f"{int(sel.sum())} of {len(rays)} correspondences and no "
                                  "motion with a translation was found (static rig or pure "
                                  "rotation): t = 0, neither its direction nor its scale is "
                                  "determined", 0.0, float("inf"), 0.0)
    info = {"translation_detected": False, "t_metric": np.zeros(3), "inlier_ratio":
            float(sel.mean()), "time_s": time.perf_counter() - t_start}
    return RigMotion(R, np.zeros(3), verdict, f"ransac[{method}]", float("nan"), sel, info)
