"""Static and near-static rigs: the one test every estimator applies (issue 18).

A rig that did not translate (parked car, hovering drone, a pure rotation, or
a scene so far away that the translation moves no point measurably) has no
essential matrix: ``E = [t]x R`` vanishes for every camera, the linear methods
find no null space of the right dimension, the minimal ones fit noise, and a
free translation absorbs calibration error as a confident but wrong
``|t|`` (seen on the parked DDAD scene: 0.25-0.36 m, truth 0). The honest
answer is the one the robust pipeline gives (:func:`mcgeom.robust.ransac`):
the rotation, ``t = 0`` and the verdict "no translation detected".

The test: is the rotation-only model as good as the full one, in the residual
sense? The best pure rotation of the intra-camera correspondences (Wahba's
problem, :func:`mcgeom.geometry.rotation_fit`) leaves residual angles between
``d2`` and ``R d1``; they are compared with the noise level of the full
model by the statistic of the robust verdict
(:func:`mcgeom.observability.no_parallax`: at least 90 % within 1.5 noise
levels). Without an inlier threshold the noise level is
:data:`NOISE_FACTOR` times the robust standard deviation of the full model's
Sampson angular residuals (thesis eq. 8.15, 1 dof) -- the counterpart of the
threshold the robust layer passes: under pure bearing noise sigma the
rotation angle (2 dof, both bearings noisy) is Rayleigh with scale
``sqrt(2) sigma``, whose 90 % quantile ``3.03 sigma`` is inside ``1.5 x 3
sigma``, while a translation whose parallax exceeds ~4.5 sigma on more than a
tenth of the points is detected. Cross-camera correspondences do not enter
the test (a static rig's cross-camera rays still have the stereo baseline: the
rotation alone does not predict them), as in the robust verdict.

Frames and units (docs/architecture.md §3): rays in the rig frame (metres),
motion rig2_from_rig1 ``X2 = R X1 + t``, angles and noise levels in radians.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np

from .. import _core
from ..geometry import rotation_fit, rotation_only_residuals, same_camera
from ..observability import NO_PARALLAX_FACTOR, no_parallax
from ..types import RayPairs, RigMotion, ScaleVerdict

__all__ = ["StaticTest", "NOISE_FACTOR", "DEFAULT_NOISE_LEVEL", "noise_level_of",
           "static_test", "static_motion", "check_static"]

#: noise level = this many robust standard deviations of the full model's
#: Sampson residuals (what an inlier threshold is to the noise: see above)
NOISE_FACTOR = 3.0
#: noise level (radians) when no full model exists (the estimator found no
#: motion with a translation): the robust layer's default threshold in radians
DEFAULT_NOISE_LEVEL = 1e-3
#: floor of the estimated noise level (radians): noise-free data fitted to
#: rounding would otherwise call a rotation that is exact only to rounding a
#: translation
_FLOOR = 1e-9
#: 1 / the median of |N(0, 1)|: the standard deviation from the median absolute residual
_MAD_TO_STD = 1.4826


@dataclass(frozen=True)
class StaticTest:
    """Outcome of :func:`static_test`.

    ``static``: a pure rotation explains the intra-camera correspondences as
    well as the full model (no translation detected). ``R``: that rotation
    (rig2_from_rig1). ``noise_level`` (radians) and where it came from
    (``noise_source``: "given", "full model" or "default"). ``explained``: the
    fraction of the ``n_intra`` intra-camera correspondences within
    ``NO_PARALLAX_FACTOR * noise_level``; ``median_angle`` (radians) their
    median rotation residual; ``cross_median`` (radians) the median Sampson
    residual of the cross-camera correspondences under ``(R, t = 0)`` (nan
    without any).
    """

    static: bool
    R: np.ndarray
    noise_level: float
    noise_source: str
    explained: float
    n_intra: int
    median_angle: float
    cross_median: float


def noise_level_of(rays: RayPairs, R: np.ndarray, t: np.ndarray) -> float:
    """Noise level (radians) of a full motion ``(R, t)`` (``t`` metric, metres):
    :data:`NOISE_FACTOR` times the robust standard deviation (1.4826 x the
    median absolute value) of its Sampson angular residuals, at least 1e-9."""
    r = np.abs(_core.gec_residuals(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2,
                                   np.asarray(R, dtype=np.float64),
                                   np.asarray(t, dtype=np.float64)))
    r = r[np.isfinite(r)]
    if r.size == 0:
        return DEFAULT_NOISE_LEVEL
    return max(NOISE_FACTOR * _MAD_TO_STD * float(np.median(r)), _FLOOR)


def static_test(rays: RayPairs, noise_level: float, *, rotation: Optional[np.ndarray] = None,
                noise_source: str = "given") -> StaticTest:
    """Does a pure rotation explain the intra-camera correspondences of ``rays``?

    ``noise_level`` in radians (an inlier threshold of the Sampson distance,
    or :func:`noise_level_of` a full model). ``rotation`` (3x3,
    rig2_from_rig1) is used as given (an estimator told the rotation);
    otherwise the best one is fitted (Wahba's problem on the intra-camera
    rays). Decided by :func:`mcgeom.observability.no_parallax`, the statistic
    of the robust verdict; with fewer than 5 intra-camera correspondences the
    answer is "not static".
    """
    if not (np.isfinite(noise_level) and noise_level > 0):
        raise ValueError(f"noise_level must be a positive number of radians, got {noise_level}")
    same = same_camera(rays)
    if rotation is None:
        R, ang = rotation_fit(rays, same)
    else:
        R = np.asarray(rotation, dtype=np.float64)
        ang = rotation_only_residuals(rays.take(np.flatnonzero(same)), R) if same.any() \
            else np.zeros(0)
    cross = np.flatnonzero(~same)
    cross_median = float("nan")
    if cross.size:
        rc = np.abs(_core.gec_residuals(rays.origins1[cross], rays.dirs1[cross],
                                        rays.origins2[cross], rays.dirs2[cross], R,
                                        np.zeros(3)))
        cross_median = float(np.median(rc))
    explained = (float(np.count_nonzero(ang < NO_PARALLAX_FACTOR * noise_level)) / ang.size
                 if ang.size else 0.0)
    return StaticTest(static=no_parallax(ang, noise_level), R=R, noise_level=float(noise_level),
                      noise_source=noise_source, explained=explained, n_intra=int(ang.size),
                      median_angle=float(np.median(ang)) if ang.size else float("nan"),
                      cross_median=cross_median)


def static_motion(rays: RayPairs, method: str, test: StaticTest,
                  info: Optional[dict] = None) -> RigMotion:
    """The answer for a rig that did not translate: ``R`` of ``test``, ``t = 0``,
    the verdict "no translation detected" (not observable: neither the
    direction nor the scale of ``t`` is determined), as :func:`mcgeom.robust.ransac`
    reports it. ``residual_rms`` is the RMS rotation residual of the
    intra-camera correspondences (radians); ``info`` (extended, not
    modified) gets ``translation_detected = False``, ``t_metric = 0`` and the
    test's figures under ``"static_test"``."""
    reason = ("no translation detected: a pure rotation explains "
              f"{100 * test.explained:.0f} % of the {test.n_intra} intra-camera correspondences "
              f"within {NO_PARALLAX_FACTOR:g} x the noise level "
              f"{np.degrees(test.noise_level) * 3600:.3g} arcsec ({test.noise_source}; median "
              f"residual {np.degrees(test.median_angle) * 3600:.3g} arcsec); static rig, pure "
              "rotation or scene at infinity: t = 0, neither the direction nor the scale of t "
              "is determined")
    verdict = ScaleVerdict(False, reason, 0.0, float("inf"), 0.0)
    same = same_camera(rays)
    ang = rotation_only_residuals(rays.take(np.flatnonzero(same)), test.R) if same.any() \
        else np.zeros(0)
    out = dict(info or {})
    out.update(translation_detected=False, t_metric=np.zeros(3),
               static_test={"noise_level": test.noise_level, "noise_source": test.noise_source,
                            "explained": test.explained, "n_intra": test.n_intra,
                            "median_angle": test.median_angle,
                            "cross_median": test.cross_median})
    rms = float(np.sqrt(np.mean(ang ** 2))) if ang.size else float("nan")
    return RigMotion(np.array(test.R, dtype=np.float64), np.zeros(3), verdict, method, rms,
                     None, out)


def check_static(rays: RayPairs, method: str, full: Optional[RigMotion] = None, *,
                 noise_level: Optional[float] = None,
                 rotation: Optional[np.ndarray] = None) -> Optional[RigMotion]:
    """The static-rig test every estimator runs on its result; the static answer or None.

    ``full`` is the estimator's own motion with a translation (None when it
    found none, e.g. a linear method's ``DegenerateError`` on ``E = 0``): its
    metric translation (``info["t_metric"]`` when the verdict made ``t`` a
    unit vector) gives the noise level (:func:`noise_level_of`) unless
    ``noise_level`` (radians) is given; without either the noise level is
    :data:`DEFAULT_NOISE_LEVEL`. ``rotation`` fixes the rotation (estimators
    told it). Returns :func:`static_motion` (method ``method``, with the full
    estimate under ``info["full_estimate"]``) when the rotation-only model
    explains the data as well as the full one, else None (keep ``full``).
    """
    if noise_level is not None:
        level, source = float(noise_level), "given"
    elif full is not None:
        t = full.info.get("t_metric") if isinstance(full.info, dict) else None
        t = np.asarray(full.t if t is None else t, dtype=np.float64).reshape(3)
        if not np.all(np.isfinite(t)):
            t = np.asarray(full.t, dtype=np.float64).reshape(3)
        level, source = noise_level_of(rays, full.R, t), "full model"
    else:
        level, source = DEFAULT_NOISE_LEVEL, "default"
    test = static_test(rays, level, rotation=rotation, noise_source=source)
    if not test.static:
        return None
    extra = {} if full is None else {"full_estimate": {
        "R": np.array(full.R), "t": np.array(full.t), "reason": full.scale.reason}}
    if full is not None and isinstance(full.info, dict):
        extra = {**{k: v for k, v in full.info.items() if k != "t_metric"}, **extra}
    return static_motion(rays, method, test, extra)
