"""Pixel-noise model of a calibrated rig: pixels per radian of the Sampson residual.

The estimators work in radians on the unit sphere (the Sampson angular error
of the generalized epipolar constraint, thesis eq. 8.15); a user's threshold
is in pixels. This module converts, per correspondence, under the model:
isotropic pixel noise on an undistorted pinhole image (lens distortion is
not modelled), with focal length ``f = (fx + fy) / 2`` pixels per unit of the normalised image
plane. A pixel error at angle ``theta`` from the optical axis then moves the
bearing by ``cos^2(theta) / f`` radians radially and ``cos(theta) / f``
tangentially.

* :func:`pixels_per_radian`: the average over the directions in the image,
  one number per correspondence, for thresholds and RANSAC scoring;
* :func:`sampson_pixel_scale`: the exact first-order value at a given motion
  (the noise along the gradient of the epipolar constraint only), for the
  final refinement of :mod:`mcgeom.robust`.

Only the public API of :class:`mcgeom.rig.Rig` is used (``intrinsics``,
``rotations``); the rays must carry camera ids of that rig (``rays.cam1``,
``rays.cam2``) and be in its rig frame.
"""

from __future__ import annotations

from typing import Optional

import numpy as np

from . import _core
from .rig import Rig
from .types import MotionFocal, RayPairs

__all__ = ["pixels_per_radian", "sampson_pixel_scale", "camera_table", "ray_pairs_per_radian",
           "pinhole_ray_pairs"]


def camera_table(rig: Rig) -> tuple[np.ndarray, np.ndarray]:
    """(M,) mean focal lengths (pixels) and (M, 3) optical axes (rig frame) of the cameras.

    The pixel-noise model of every camera of ``rig`` (the table that
    :func:`sampson_pixel_scale` evaluates; :func:`mcgeom.robust.ransac` passes
    it to the C search as ``pixel_cameras``).
    """
    # (made once by the rig, read-only: this is asked once per estimate)
    return rig.focal_axes


def pixels_per_radian(rig: Rig, rays: RayPairs) -> np.ndarray:
    """Pixels per radian of Sampson residual, per correspondence: (N,) float64.

    A pixel error at angle theta from a pinhole camera's axis moves the bearing
    by cos^2(theta) / f radians radially and cos(theta) / f tangentially; the
    mean variance of the two bearings of a correspondence, (cos^4 + cos^2) / 2
    per bearing, gives f_eff = f / sqrt(mean). Thresholds in pixels then mean
    pixels across the whole image, and the refinement weights residuals by
    their pixel-noise variance. (``cos`` is clipped to [1e-3, 1]: a bearing at
    or behind the image plane keeps a finite value.)
    """
    focal, axes = camera_table(rig)
    var = None
    for ids, d in ((rays.cam1, rays.dirs1), (rays.cam2, rays.dirs2)):
        # (in place, without np.clip's Python layers: this runs once per
        # estimate of the façade, issue 19; the same values)
        # The dot product and cos^4 = (cos^2)^2 are spelled out, in the
        # order of csrc/pixel_rays.c (the façade's fast path), so that both
        # give the same bits on any machine: numpy's einsum sums in a
        # SIMD-dependent order and its power may use SVML on AVX-512.
        z = axes[ids]
        cz = z[:, 0] * d[:, 0]
        cz += z[:, 1] * d[:, 1]
        cz += z[:, 2] * d[:, 2]
        np.maximum(cz, 1e-3, out=cz)
        np.minimum(cz, 1.0, out=cz)
        c2 = np.multiply(cz, cz, out=cz)
        f = focal[ids]
        term = 0.5 * (c2 * c2 + c2) / (f * f)
        var = term if var is None else np.add(var, term, out=var)   # (0 + x = x exactly)
    var *= 0.5
    return 1.0 / np.sqrt(var, out=var)


def ray_pairs_per_radian(rig: Rig, px1: np.ndarray, px2: np.ndarray, ids1: np.ndarray,
                         ids2: np.ndarray) -> tuple[RayPairs, np.ndarray]:
    """:meth:`mcgeom.rig.Rig.ray_pairs_prechecked` and :func:`pixels_per_radian`
    of its rays, for the same checked input (its preconditions: finite
    float64 C-contiguous (N, 2) pixels, (N,) int64 ids of the rig's cameras,
    arrays made by the caller's checks, not the user's own, as the result
    keeps them).

    Returns the rays (rig frame, metres, unit bearings, camera ids) and (N,)
    pixels per radian. When every camera of ``rig`` is an undistorted pinhole
    both come from one C pass (``_core.pinhole_ray_pairs``,
    csrc/pixel_rays.c: the same bits as the numpy path); otherwise, or when
    a pixel has no finite bearing (its ValueError names it), from the rig
    and :func:`pixels_per_radian`.
    """
    out = pinhole_ray_pairs(rig, px1, px2, ids1, ids2)
    if out is None:
        rays = rig.ray_pairs_prechecked(px1, px2, ids1, ids2)
        return rays, pixels_per_radian(rig, rays)
    # ids2 may be ids1 (the same cameras at both times): then its own
    # array, as the rig's
    rays, ppr = out
    if ids2 is ids1:
        rays = RayPairs.prechecked(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, ids1,
                                   ids2.copy())
    return rays, ppr


def pinhole_ray_pairs(rig: Rig, px1: np.ndarray, px2: np.ndarray, ids1: np.ndarray,
                      ids2: np.ndarray) -> Optional[tuple[RayPairs, np.ndarray]]:
    """The rays and pixels per radian of :func:`ray_pairs_per_radian` from the
    C pass alone (``_core.pinhole_ray_pairs``), which checks the pixels
    (finite bearings) and the ids (cameras of ``rig``) itself: ``px1``,
    ``px2`` float64 C-contiguous (N, 2) pixels and ``ids1``, ``ids2`` int64
    C-contiguous (N,) ids (their types are the caller's to guarantee, their
    values need not be checked). None when a camera of ``rig`` is not an
    undistorted pinhole or the kernel refuses a pixel or an id (the general
    path names which). The rays keep ``ids1``/``ids2`` as their camera ids."""
    tables = rig.pinhole_tables
    if tables is None:
        return None
    intr, rot, centres, focal = tables
    out = _core.pinhole_ray_pairs(intr, rot, centres, focal, ids1, ids2, px1, px2)
    if out is None:
        return None
    o1, d1, o2, d2, ppr = out
    # made here: float64 C-contiguous (N, 3)
    return RayPairs.prechecked(o1, d1, o2, d2, ids1, ids2), ppr


def sampson_pixel_scale(rig: Rig) -> MotionFocal:
    """Pixels per radian of each correspondence's Sampson residual at a given motion.

    Returns ``motion_focal(rays, R, t) -> (N,)`` for the rays of ``rig``.
    :func:`pixels_per_radian` averages the pixel-noise variance of a bearing over
    the directions in the image; the Sampson error (thesis eq. 8.15 and
    ``csrc/refine.c``) only feels the noise along the gradient of the epipolar
    constraint, whose direction the motion fixes. With the tangent gradients
    ``g1 = P(a) (d2 x c)`` (bearing ``a = R d1``) and ``g2 = P(d2) (c x a)``,
    the angular residual is ``e / sqrt(|g1|^2 + |g2|^2)``, while unit pixel
    noise moves ``e`` by a variance ``sum_k cz_k^2 / f_k^2 (|g_k|^2 -
    (g_k . axis_k)^2)`` (a pinhole bearing's covariance: ``cos^4 / f^2``
    radially, ``cos^2 / f^2`` tangentially); their ratio gives the residual in
    pixels, i.e. the image-plane Sampson error -- the first-order maximum
    likelihood residual for isotropic pixel noise. Same lens assumption as
    :func:`pixels_per_radian` (undistorted pinhole), whose value is kept where
    the pixel variance vanishes (no first-order constraint). Computed by
    ``_core.sampson_pixel_scale``.
    """
    focal, axes = camera_table(rig)
    min_var_ratio = 1e-12 / float(np.square(focal).max())

    def motion_focal(rays: RayPairs, R: np.ndarray, t: np.ndarray) -> np.ndarray:
        # in C (csrc/pixel_scale.c): ~30 array passes in numpy, ~0.4 ms of a
        # Ladybug problem per call
        f = _core.sampson_pixel_scale(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2,
                                      R, t, axes[rays.cam1], axes[rays.cam2],
                                      focal[rays.cam1], focal[rays.cam2], min_var_ratio)
        bad = f == 0.0                   # no first-order constraint
        if bad.any():
            f[bad] = pixels_per_radian(rig, rays)[bad]
        return f

    return motion_focal
