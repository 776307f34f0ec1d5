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

import numpy as np

from . import _core
from .rig import Rig
from .types import MotionFocal, RayPairs

__all__ = ["pixels_per_radian", "sampson_pixel_scale", "camera_table"]


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
        cz = np.einsum("ij,ij->i", axes[ids], d)
        np.maximum(cz, 1e-3, out=cz)
        np.minimum(cz, 1.0, out=cz)
        term = 0.5 * (cz ** 4 + cz ** 2) / focal[ids] ** 2
        var = term if var is None else np.add(var, term, out=var)   # (0 + x = x exactly)
    var *= 0.5
    return 1.0 / np.sqrt(var, out=var)


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
