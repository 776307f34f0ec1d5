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
``d2`` and ``R d1``; they are compared with a noise level by the statistic of
the robust verdict (:func:`mcgeom.observability.no_parallax`: at least 90 %
within 1.5 noise levels). The robust layer's noise level is its inlier
threshold; an estimator has none, so it is :data:`NOISE_FACTOR` times the
robust standard deviation of the Sampson angular residuals (thesis eq. 8.15)
of the most flexible full model at that rotation, every camera translating in
its own best direction (:func:`camera_residuals`; its residuals do not depend
on the |t| a near-critical estimate may have slid to). Under ideal isotropic
noise the rotation angle (2 dof) would have its 90 % quantile at 3 such
standard deviations; on the real recordings (cv.estimate inliers, measured
with ``mcgeom experiment honesty``'s data) it is at 6.8-9.0 of them on the
static ones (DDAD scene_01 parked, EuRoC hovering: the free directions also
fit structured matching error) and at 155-455 on the moving ones (KITTI raw
0023, DDAD scene_02), medians 1.8-5.6 against 52-105. ``NOISE_FACTOR = 10``
(90 % within 15 standard deviations) sits between the two with margins of
1.6x and 10x. The angles and the noise level are measured at one
rotation: the pure rotation's, then the full estimate's own (see
:func:`check_static`; a tiny ``t`` that trades against its rotation fits the
matching error at that rotation, and its angles must be judged there). Cross-camera correspondences do not enter the test (a static
rig's cross-camera rays still have the stereo baseline: the rotation alone
does not predict them), as in the robust verdict.

Frames and units (docs/architecture.md §3): rays in the rig frame (metres),
motion rig2_from_rig1 ``X2 = R X1 + t``, angles and noise levels in radians.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Optional

import numpy as np

from .. import _core
from ..errors import DegenerateError
from ..geometry import rotation_fit, rotation_only_residuals, same_camera
from ..observability import (NO_PARALLAX_FACTOR, NO_PARALLAX_FRACTION, NO_PARALLAX_MIN,
                             no_parallax)
from ..types import RayPairs, RigMotion, ScaleVerdict
from ._common import camera_ids

__all__ = ["StaticTest", "NOISE_FACTOR", "DEFAULT_NOISE_LEVEL", "camera_residuals",
           "noise_level_of", "with_static_check",
           "static_test", "static_motion", "check_static", "intra_groups", "KERNEL_OPTIONS"]

#: noise level = this many robust standard deviations of the per-camera
#: Sampson residuals (what an inlier threshold is to the noise: see above)
NOISE_FACTOR = 10.0
#: noise level (radians) when no full model exists (the estimator found no
#: motion with a translation): the robust layer's default threshold in radians
DEFAULT_NOISE_LEVEL = 1e-3
#: floor of the estimated noise level (radians): noise-free data fitted to
#: rounding would otherwise call a rotation that is exact only to rounding a
#: translation
_FLOOR = 1e-9
#: fewest intra-camera correspondences of a camera whose residuals measure the
#: noise (a static rig with 7 per camera and 3e-4 rad noise read as moving)
_MIN_PER_CAMERA = 12
#: fewest distinct intra-camera correspondences of a static answer (repeats of
#: one correspondence "explain" any rotation-only model)
_MIN_DISTINCT = 5
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


def camera_residuals(rays: RayPairs, R: np.ndarray) -> np.ndarray:
    """Sampson angular residuals (radians) of the intra-camera correspondences
    when every camera moves in its own best direction under the rotation ``R``.

    For camera ``i`` at ``c_i`` the translation of its centre ``u_i`` (any
    length: one camera cannot see it) is the null vector of the rows
    ``R d1 x d2`` (the essential matrix of thesis ch. 2.3 about ``c_i``), and
    the residuals are those of the generalized epipolar constraint with
    ``t = u_i + c_i - R c_i``. This model has at least the freedom of any rig
    motion with rotation ``R`` (each camera its own direction, no common
    scale), so its residuals measure the noise without depending on ``|t|``
    -- which a near-critical estimate may have slid anywhere (a metric ``t`` of
    a few mm puts the epipoles where the rotation-induced shift ``R c - c``
    points, and its residuals are then the model's error, not the noise).
    The null vector is found by least median of squares (Rousseeuw 1984) over
    the directions two rows fix, on the sine of the angle between ``u`` and
    each row's plane, then least squares on the rows within 2.5 robust
    standard deviations: the outliers an estimator may be handed (the
    OpenCV-style façade calls non-robust methods on raw matches) would
    otherwise swing the plain least-squares null vector, inflate the noise
    level and make a moving rig pass for a static one. Its 32 samples come
    from a fixed stream, so the result is a function of the data. One C call
    for all cameras (``mcg_static_noise``, O(N) with camera ids below N, no Python loop).
    Cameras with fewer than :data:`_MIN_PER_CAMERA` intra-camera
    correspondences are left out: with a handful of rays the fitted direction
    (2 dof) absorbs the noise and its residuals understate it. Returned in
    the order of ``rays``.
    """
    return _camera_residuals(rays, R)[0]


#: pairs of rows the least-median-of-squares direction of a camera tries
_LMEDS_SAMPLES = 32


def _camera_residuals(rays: RayPairs, R: np.ndarray) -> tuple[np.ndarray, float]:
    """:func:`camera_residuals` and their median (radians; nan without any)."""
    cam1, cam2, _ = camera_ids(rays)
    group = np.where(cam1 == cam2, cam1, -1)
    res, med, used = _core.static_noise(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2,
                                        group, R, _MIN_PER_CAMERA, _LMEDS_SAMPLES)
    return res[res >= 0], (med if used else float("nan"))


def noise_level_of(rays: RayPairs, R: np.ndarray) -> float:
    """Noise level (radians) of the intra-camera correspondences near the rotation ``R``.

    :data:`NOISE_FACTOR` times the robust standard deviation (1.4826 x the
    median absolute value) of :func:`camera_residuals`, the smaller of those
    at ``R`` and at the best pure rotation (a wrong ``R`` must not inflate
    the noise and make a moving rig pass for a static one); at least 1e-9;
    :data:`DEFAULT_NOISE_LEVEL` when no camera has 12 intra-camera
    correspondences.
    """
    R0 = rotation_fit(rays, same_camera(rays))[0]
    return min(_noise_levels(rays, (np.asarray(R, dtype=np.float64), R0)))


def _noise_levels(rays: RayPairs, rotations: tuple) -> list:
    """:data:`NOISE_FACTOR` x the robust std of :func:`camera_residuals` at each
    rotation (radians, at least :data:`_FLOOR`); :data:`DEFAULT_NOISE_LEVEL`
    for all when no camera has :data:`_MIN_PER_CAMERA` intra-camera
    correspondences."""
    out = []
    for Rk in rotations:
        med = _camera_residuals(rays, Rk)[1]
        if not np.isfinite(med):
            return [DEFAULT_NOISE_LEVEL] * len(rotations)
        out.append(max(NOISE_FACTOR * _MAD_TO_STD * med, _FLOOR))
    return out


def static_test(rays: RayPairs, noise_level: float, *, rotation: Optional[np.ndarray] = None,
                noise_source: str = "given", _fit: Optional[np.ndarray] = None) -> StaticTest:
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
    if rotation is None and _fit is None:
        R, ang = rotation_fit(rays, same)
    else:
        # the given rotation, or the caller's pure-rotation fit of these rays
        R = np.asarray(rotation if rotation is not None else _fit, dtype=np.float64)
        ang = rotation_only_residuals(rays.take(np.flatnonzero(same)), R) if same.any() \
            else np.zeros(0)
    cross_median = _cross_median(rays, R)
    explained = (float(np.count_nonzero(ang < NO_PARALLAX_FACTOR * noise_level)) / ang.size
                 if ang.size else 0.0)
    # a rotation from fewer than 5 distinct correspondences is not determined
    # (repeats of one correspondence "explain" any rotation-only model)
    static = bool(no_parallax(ang, noise_level)) and \
        rays.take(np.flatnonzero(same)).n_distinct(at_least=_MIN_DISTINCT) >= _MIN_DISTINCT
    return StaticTest(static=static, R=R, noise_level=float(noise_level),
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


#: the constants of the test, as mcg_static_check takes them
_C_OPTIONS = dict(noise_factor=NOISE_FACTOR, noise_floor=_FLOOR,
                  default_level=DEFAULT_NOISE_LEVEL, parallax_factor=NO_PARALLAX_FACTOR,
                  fraction=NO_PARALLAX_FRACTION, min_pairs=NO_PARALLAX_MIN,
                  min_distinct=_MIN_DISTINCT, min_rows=_MIN_PER_CAMERA, samples=_LMEDS_SAMPLES)
#: the constants above as the ``mcg_static_options *`` of the kernel, made once
#: (check_static runs on every estimator call; ``mcgeom bench linear17`` times
#: the bare kernel with it)
KERNEL_OPTIONS = _core.static_options(**_C_OPTIONS)


def intra_groups(rays: RayPairs) -> np.ndarray:
    """(N,) int32: the camera of each intra-camera correspondence, -1 for
    cross-camera ones (RayPairs bounds the ids by MAX_CAMERA_ID < 2^31)."""
    if rays.cam1 is not None and rays.cam2 is not None:
        cam1, cam2 = rays.cam1, rays.cam2
    else:
        cam1, cam2, _ = camera_ids(rays)
    # a cast and a masked store: a third of np.where(..., -1).astype's time
    # (issue 22: this runs on every estimator call)
    group = cam1.astype(np.int32)
    group[cam1 != cam2] = -1
    return group


def _cross_median(rays: RayPairs, R: np.ndarray) -> float:
    """Median Sampson residual (radians) of the cross-camera correspondences under
    ``(R, t = 0)``; nan without any."""
    cross = np.flatnonzero(~same_camera(rays))
    if not cross.size:
        return float("nan")
    return float(np.median(np.abs(_core.gec_residuals(
        rays.origins1[cross], rays.dirs1[cross], rays.origins2[cross], rays.dirs2[cross], R,
        np.zeros(3)))))


def check_static(rays: RayPairs, method: str, full: Optional[RigMotion] = None, *,
                 noise_level: Optional[float] = None,
                 rotation: Optional[np.ndarray] = None) -> Optional[RigMotion]:
    """The static-rig test every estimator runs on its result; the static answer or None.

    ``full`` is the estimator's own motion with a translation (None when it
    found none, e.g. a linear method's ``DegenerateError`` on ``E = 0``).
    The noise level is ``noise_level`` (radians) when given, else
    :func:`noise_level_of` at the rotation of ``full`` (or ``rotation``, or
    the best pure rotation). ``rotation`` fixes the rotation of the static
    answer (estimators told it). Returns :func:`static_motion` (method
    ``method``, with the full estimate under ``info["full_estimate"]``) when
    the rotation-only model explains the data as well as the full one, else
    None (keep ``full``).

    Both models at one rotation (issue 18, EuRoC hovering, 0.9 mm between
    the frames): the rotation-only angles -- the parallax the translation has
    to explain -- are compared with the noise level measured at the same
    rotation. The pure rotation is tried first (the given one, or the best
    fit); then, with a full estimate, the estimate's own rotation: a
    translation that adds no parallax beyond the noise at its own rotation
    was not detected. (Angles at the best pure rotation against the noise at
    the estimate's rotation mix two models: a full estimate whose tiny ``t``
    trades against its rotation fits the matching error there, 0.025 px
    against 0.08 px at the pure rotation on EuRoC, and the hovering rig read
    as moving.) On the real recordings the 90 % quantile of the angles at
    the estimate's rotation is 6.4-8.0 robust noise stds on the static pairs
    and 149-351 on the moving ones (KITTI, DDAD; 460-830 on noisy critical
    synthetic motions), against the bound of ``1.5 x NOISE_FACTOR = 15``.
    The noise level stays the smaller of the two rotations' (a wrong
    rotation must not inflate it).
    """
    # one C call (mcg_static_check: the pure-rotation fit, the noise levels,
    # the statistic at both rotations); its rule and constants are those of
    # static_test, noise_level_of and observability.no_parallax above
    if noise_level is not None and not (np.isfinite(noise_level) and noise_level > 0):
        raise ValueError(f"noise_level must be a positive number of radians, got {noise_level}")
    r = _core.static_check_rays(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2,
                                intra_groups(rays), None if full is None else full.R,
                                rotation, 0.0 if noise_level is None else float(noise_level),
                                KERNEL_OPTIONS)
    if r is None:  # the rig moved: keep the full estimate
        return None
    source = "given" if noise_level is not None else \
        "default" if r["noise_from_default"] else "per-camera fit"
    if r["decided_at"] == 1:
        source += "; angles at the estimate's rotation"
    test = StaticTest(static=True, R=r["R"], noise_level=r["noise_level"], noise_source=source,
                      explained=r["explained"], n_intra=r["n_intra"],
                      median_angle=r["median_angle"], cross_median=_cross_median(rays, r["R"]))
    extra = {} if full is None else {"full_estimate": {
        "R": np.array(full.R), "t": np.array(full.t), "reason": full.scale.reason}}
    if full is not None and isinstance(full.info, dict):
        extra = {**{k: v for k, v in full.info.items() if k != "t_metric"}, **extra}
    return static_motion(rays, method, test, extra)


def with_static_check(rays: RayPairs, method: str, estimate: Callable[[], RigMotion], *,
                      errors: tuple = (DegenerateError,),
                      rotation: Optional[np.ndarray] = None) -> RigMotion:
    """``estimate()`` (an estimator's own computation on ``rays``) followed by
    :func:`check_static`, the way every estimator runs the shared test.

    When ``estimate`` raises one of ``errors`` (the estimator found no motion
    with a translation, e.g. ``E = 0``), the static answer is returned if the
    data are static and the error re-raised otherwise; when it returns a
    motion, the static answer replaces it if a pure rotation explains the data
    as well. ``rotation``: the known rotation of estimators told it.
    """
    try:
        m = estimate()
    except errors:
        still = check_static(rays, method, rotation=rotation)
        if still is None:
            raise
        return still
    return check_static(rays, method, m, rotation=rotation) or m
