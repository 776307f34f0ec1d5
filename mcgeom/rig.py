"""Calibrated multi-camera rigs: pixels -> bearings -> Plücker rays, and rig files.

Frames and units (docs/architecture.md §3):

* Camera frame: OpenCV's (x right, y down, z forward), metres.
* Rig frame: whatever frame the extrinsics are expressed in, metres.
* Extrinsics of camera i are **cam_from_rig** ``(R_i, t_i)``: ``X_cam = R_i X_rig + t_i``;
  the camera centre in the rig frame is ``c_i = -R_i^T t_i``.
* Pixels follow OpenCV: ``(u, v)`` with the centre of the top-left pixel at ``(0, 0)``,
  so the image covers ``[-0.5, width - 0.5) x [-0.5, height - 0.5)``.
* The bearing of a pixel in the rig frame is ``d = R_i^T normalize([x, y, 1])`` where
  ``(x, y)`` is the undistorted normalized image point; its Plücker ray is
  ``(d, c_i x d)`` (see :class:`mcgeom.types.RayPairs`).

Lens models are OpenCV's: ``"pinhole"`` (``cv2.projectPoints`` / ``cv2.undistortPoints``
with 0, 4, 5, 8, 12 or 14 coefficients) and ``"fisheye"`` (``cv2.fisheye``, 4
coefficients). The intrinsic matrix ``K`` may have a skew term ``K[0, 1]``: OpenCV's
functions ignore skew, so they are called on normalized coordinates with an identity
camera matrix and ``K`` is applied here, exactly.

Rig files (mcgeom's JSON, OpenCV, Kalibr, COLMAP) are read and written by
:mod:`mcgeom.io`; this module knows nothing of files.
"""

from __future__ import annotations

import operator
from dataclasses import dataclass, field, replace
from typing import Any, Literal, Sequence

import cv2
import numpy as np

from mcgeom.types import RayPairs
from mcgeom.validation import (check_int, check_pixels, check_points, check_rotation,
                               check_vector3, integral_camera_ids, numeric)

__all__ = ["Camera", "Rig", "DEFAULT_EXTRINSIC_STD"]

CameraModel = Literal["pinhole", "fisheye"]

_DIST_LENGTHS = {"pinhole": (0, 4, 5, 8, 12, 14), "fisheye": (4,)}
# OpenCV's default undistortion stops after 5 (pinhole) / 10 (fisheye) iterations, far
# from double precision with real distortion; these criteria are in normalized units
# because OpenCV is called with an identity camera matrix.
_UNDISTORT_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-15)
# A projected pixel whose bearing differs from the point's direction by more than this
# (radians) lies where the distortion polynomial folds over: not a real observation.
_ROUND_TRIP_TOL = 1e-6
_IDENTITY = np.eye(3)


# --------------------------------------------------------------------------- helpers

def _frozen(a: np.ndarray) -> np.ndarray:
    """A read-only float64 C-contiguous copy (cameras are immutable values)."""
    out = np.array(a, dtype=np.float64, order="C", copy=True)
    out.setflags(write=False)
    return out


def _normalize_rows(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def _fisheye_poly(theta: np.ndarray, D: np.ndarray) -> np.ndarray:
    """OpenCV fisheye distortion ``theta_d = theta (1 + k1 theta^2 + ... + k4 theta^8)``."""
    k1, k2, k3, k4 = D
    t2 = theta * theta
    return theta * (1 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4))))


def _fisheye_theta(theta_d: np.ndarray, D: np.ndarray) -> np.ndarray:
    """Invert the fisheye polynomial on its increasing branch, by bisection.

    Used for the pixels OpenCV's fisheye undistortion cannot represent (angles of 90
    degrees or more from the optical axis, where ``tan(theta)`` changes sign). Bisection
    rather than Newton: it cannot jump to the decreasing branch past the polynomial's
    peak. Returns NaN where ``theta_d`` exceeds the peak (no ray maps there).
    """
    grid = np.linspace(0.0, np.pi, 4097)
    rising = np.diff(_fisheye_poly(grid, D)) > 0
    top = grid[np.argmin(rising)] if not rising.all() else np.pi  # last point of the branch
    lo, hi = np.zeros_like(theta_d), np.full_like(theta_d, top)
    for _ in range(64):  # interval shrinks to ~1e-19 rad
        mid = 0.5 * (lo + hi)
        below = _fisheye_poly(mid, D) < theta_d
        lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
    theta = 0.5 * (lo + hi)
    ok = np.abs(_fisheye_poly(theta, D) - theta_d) <= 1e-12 * np.maximum(1.0, theta_d)
    return np.where(ok, theta, np.nan)


# --------------------------------------------------------------------------- Camera

@dataclass(frozen=True, eq=False)
class Camera:
    """One calibrated camera of a rig (OpenCV lens model + cam_from_rig extrinsics).

    Attributes:
        name: unique name within the rig (used in messages and rig files).
        K: 3x3 upper-triangular intrinsic matrix in pixels (``fx, fy > 0``, ``K[2,2] = 1``;
            a skew ``K[0,1]`` is allowed).
        dist: 1-D OpenCV distortion coefficients: pinhole 0, 4, 5, 8, 12 or 14 values
            ``(k1, k2, p1, p2[, k3[, k4, k5, k6[, s1..s4[, tx, ty]]]])``; fisheye exactly
            4 values ``(k1, k2, k3, k4)``.
        model: ``"pinhole"`` or ``"fisheye"``.
        R: 3x3 rotation cam_from_rig.
        t: (3,) translation cam_from_rig in metres: ``X_cam = R X_rig + t``.
        width, height: image size in pixels.

    Arrays are stored as read-only float64 C-contiguous copies; every check failure is
    a ``ValueError`` naming the camera and the problem.
    """

    name: str
    K: np.ndarray
    dist: np.ndarray
    model: CameraModel
    R: np.ndarray
    t: np.ndarray
    width: int
    height: int

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"camera name must be a non-empty string, got {self.name!r}")
        who = f"camera {self.name!r}"
        if self.model not in _DIST_LENGTHS:
            raise ValueError(f"{who}: unknown model {self.model!r} (expected 'pinhole' or 'fisheye')")
        set_ = lambda field, value: object.__setattr__(self, field, value)  # noqa: E731
        set_("K", _frozen(self._checked_K(who)))
        set_("dist", _frozen(self._checked_dist(who)))
        set_("R", _frozen(check_rotation(f"{who}: extrinsic R", self.R)))
        set_("t", _frozen(check_vector3(f"{who}: extrinsic t", self.t)))
        for field in ("width", "height"):
            value = check_int(f"{who}: {field}", getattr(self, field))
            if value <= 0:
                raise ValueError(f"{who}: {field} must be positive, got {value}")
            set_(field, value)

    def _checked_K(self, who: str) -> np.ndarray:
        K = numeric(f"{who}: K", self.K)
        if K.shape != (3, 3):
            raise ValueError(f"{who}: K must have shape (3, 3), got {K.shape}")
        if not np.all(np.isfinite(K)):
            raise ValueError(f"{who}: K has non-finite entries")
        if K[1, 0] != 0 or K[2, 0] != 0 or K[2, 1] != 0:
            raise ValueError(f"{who}: K must be upper triangular (K[1,0], K[2,0], K[2,1] = 0)")
        if not (K[0, 0] > 0 and K[1, 1] > 0):
            raise ValueError(f"{who}: K must have positive focal lengths, got fx={K[0, 0]}, fy={K[1, 1]}")
        if K[2, 2] != 1:
            raise ValueError(f"{who}: K[2,2] must be 1, got {K[2, 2]}")
        return K

    def _checked_dist(self, who: str) -> np.ndarray:
        # None is the common spelling of "no distortion" in OpenCV code.
        dist = numeric(f"{who}: dist", [] if self.dist is None else self.dist)
        # calibrateCamera returns (1, n); accept row/column vectors, store 1-D.
        if dist.ndim > 2 or (dist.ndim == 2 and 1 not in dist.shape):
            raise ValueError(f"{who}: dist must be a 1-D array, got shape {dist.shape}")
        dist = dist.reshape(-1)
        if dist.size not in _DIST_LENGTHS[self.model]:
            raise ValueError(f"{who}: a {self.model} camera needs {_DIST_LENGTHS[self.model]} "
                             f"distortion coefficients, got {dist.size}")
        if not np.all(np.isfinite(dist)):
            raise ValueError(f"{who}: dist has non-finite entries")
        return dist

    # -- value semantics (ndarray fields defeat the dataclass-generated ones)
    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Camera):
            return NotImplemented
        return (self.name == other.name and self.model == other.model
                and self.width == other.width and self.height == other.height
                and all(np.array_equal(getattr(self, f), getattr(other, f))
                        for f in ("K", "dist", "R", "t")))

    def __hash__(self) -> int:
        return hash((self.name, self.model, self.width, self.height, self.K.tobytes(),
                     self.dist.tobytes(), self.R.tobytes(), self.t.tobytes()))

    # -- geometry
    @property
    def centre(self) -> np.ndarray:
        """Camera centre in the rig frame, metres: ``-R^T t``, shape (3,)."""
        return -self.R.T @ self.t

    @property
    def has_distortion(self) -> bool:
        """True if any distortion coefficient is non-zero."""
        return bool(np.any(self.dist != 0))

    def pixels_to_bearings(self, pixels: Any) -> np.ndarray:
        """Unit bearings in the RIG frame of pixels of this camera.

        Args:
            pixels: (N, 2) pixel coordinates (OpenCV convention), finite.

        Returns:
            (N, 3) float64 unit vectors ``d = R^T normalize([x, y, 1])`` in the rig frame,
            where ``(x, y)`` is the undistorted normalized point (``cv2.undistortPoints``
            or ``cv2.fisheye.undistortPoints``). Without distortion this is exactly
            ``R^T normalize(K^-1 [u, v, 1])``.

        Raises:
            ValueError: bad shape or non-finite pixels; fisheye pixels outside the range
                where the distortion polynomial can be inverted.
        """
        px = check_pixels(f"camera {self.name!r}: pixels", pixels)
        return self._bearings_checked(px)

    def _bearings_checked(self, px: np.ndarray, strict: bool = True) -> np.ndarray:
        """:meth:`pixels_to_bearings` of checked pixels (finite float64 (N, 2));
        ``strict`` False: NaN rows for fisheye pixels without a ray."""
        rays_cam = self._unproject(self._pixels_to_normalized(px), px, strict)
        return _normalize_rows(rays_cam @ self.R)  # row-wise R^T d

    def project(self, points_rig: Any) -> tuple[np.ndarray, np.ndarray]:
        """Project points given in the rig frame into this camera.

        Args:
            points_rig: (N, 3) points in the rig frame, metres, finite.

        Returns:
            ``(pixels, visible)``: (N, 2) pixel coordinates (``cv2.projectPoints`` /
            ``cv2.fisheye.projectPoints``; NaN for points not in front, ``z <= 0``) and
            an (N,) bool mask: in front, inside the image ``[-0.5, width - 0.5) x
            [-0.5, height - 0.5)``, and -- with distortion -- a pixel that unprojects
            back to the point's direction (guards against the fold-over of the
            distortion polynomial outside its calibrated range).
        """
        P = check_points(f"camera {self.name!r}: points_rig", points_rig)
        X = P @ self.R.T + self.t
        pixels = np.full((P.shape[0], 2), np.nan)
        front = X[:, 2] > 0
        if np.any(front):
            pixels[front] = self._normalized_to_pixels(self._distort(X[front]))
        visible = front.copy()
        visible[front] = self.in_image(pixels[front])
        if self.has_distortion and np.any(visible):
            visible[visible] = self.round_trip_ok(pixels[visible], X[visible])
        return pixels, visible

    def in_image(self, pixels: Any) -> np.ndarray:
        """(N,) bool: pixel inside ``[-0.5, width - 0.5) x [-0.5, height - 0.5)``."""
        px = np.asarray(pixels, dtype=np.float64).reshape(-1, 2)
        return ((px[:, 0] >= -0.5) & (px[:, 0] < self.width - 0.5)
                & (px[:, 1] >= -0.5) & (px[:, 1] < self.height - 0.5))

    # -- internals: K is applied here so that skew is honoured (OpenCV ignores it)
    def _pixels_to_normalized(self, px: np.ndarray) -> np.ndarray:
        """Distorted normalized coordinates ``K^-1 [u, v, 1]`` (back substitution)."""
        K = self.K
        y = (px[:, 1] - K[1, 2]) / K[1, 1]
        x = (px[:, 0] - K[0, 2] - K[0, 1] * y) / K[0, 0]
        return np.stack([x, y], axis=1)

    def _normalized_to_pixels(self, xy: np.ndarray) -> np.ndarray:
        K = self.K
        u = K[0, 0] * xy[:, 0] + K[0, 1] * xy[:, 1] + K[0, 2]
        v = K[1, 1] * xy[:, 1] + K[1, 2]
        return np.stack([u, v], axis=1)

    def _distort(self, X_cam: np.ndarray) -> np.ndarray:
        """Camera-frame points (z > 0) -> distorted normalized coordinates via OpenCV."""
        obj = np.ascontiguousarray(X_cam).reshape(-1, 1, 3)
        zero = np.zeros(3)
        if self.model == "fisheye":
            out, _ = cv2.fisheye.projectPoints(obj, zero, zero, _IDENTITY, self.dist)
        else:
            out, _ = cv2.projectPoints(obj, zero, zero, _IDENTITY, self.dist)
        return out.reshape(-1, 2).astype(np.float64)

    def _unproject(self, xy_d: np.ndarray, px: np.ndarray, strict: bool = True) -> np.ndarray:
        """Distorted normalized coordinates -> (N, 3) camera-frame ray directions.

        ``strict``: raise for fisheye pixels without a ray; otherwise return NaN rows.
        """
        n = xy_d.shape[0]
        if n == 0:
            return np.zeros((0, 3))
        if self.model == "pinhole" and not np.any(self.dist):
            return np.column_stack([xy_d, np.ones(n)])   # nothing to undistort
        src = np.ascontiguousarray(xy_d).reshape(-1, 1, 2)
        if self.model == "pinhole":
            xy = cv2.undistortPoints(src, _IDENTITY, self.dist,
                                     criteria=_UNDISTORT_CRITERIA).reshape(-1, 2)
            return np.column_stack([xy, np.ones(n)])
        xy = cv2.fisheye.undistortPoints(src, _IDENTITY, self.dist,
                                         criteria=_UNDISTORT_CRITERIA).reshape(-1, 2)
        return self._fisheye_rays(xy_d, xy, px, strict)

    def _fisheye_rays(self, xy_d: np.ndarray, xy: np.ndarray, px: np.ndarray,
                      strict: bool) -> np.ndarray:
        """Fisheye rays from OpenCV's result, re-solved where OpenCV cannot be right.

        OpenCV returns ``tan(theta)`` scaled points, which cannot represent rays at 90
        degrees or more from the axis (it then returns a wrong point, silently). Each
        result is checked against the forward model and re-solved by Newton otherwise.
        """
        theta_d = np.linalg.norm(xy_d, axis=1)
        theta = np.arctan(np.linalg.norm(xy, axis=1))
        back = _fisheye_poly(theta, self.dist)
        bad = ~(np.abs(back - theta_d) <= 1e-9 * np.maximum(1.0, theta_d))
        if np.any(bad):
            theta[bad] = _fisheye_theta(theta_d[bad], self.dist)
            if strict and np.any(np.isnan(theta)):
                k = int(np.flatnonzero(np.isnan(theta))[0])
                raise ValueError(
                    f"camera {self.name!r}: {int(np.isnan(theta).sum())} pixel(s) lie outside "
                    f"the range where the fisheye distortion can be inverted (first: "
                    f"({px[k, 0]:.6g}, {px[k, 1]:.6g}))")
        # direction = (sin(theta) * unit(xy_d), cos(theta)); unit(xy_d) is undefined at the
        # principal point, where theta = 0 and the ray is the optical axis anyway.
        scale = np.divide(np.sin(theta), theta_d, out=np.ones_like(theta), where=theta_d > 0)
        return np.column_stack([xy_d * scale[:, None], np.cos(theta)])

    def round_trip_ok(self, pixels: np.ndarray, X_cam: np.ndarray) -> np.ndarray:
        """(N,) bool: each pixel unprojects to the direction of its camera-frame point
        (never raises: a pixel without a ray simply fails). Used by synth too."""
        if pixels.shape[0] == 0:
            return np.zeros(0, dtype=bool)
        rays = self._unproject(self._pixels_to_normalized(pixels), pixels, strict=False)
        cos = np.sum(_normalize_rows(rays) * _normalize_rows(X_cam), axis=1)
        return cos > np.cos(_ROUND_TRIP_TOL)  # NaN rows compare False

    # -- frames
    def in_frame(self, R: np.ndarray, t: np.ndarray) -> "Camera":
        """The same camera with extrinsics w.r.t. a new rig frame ``X_new = R X_old + t``.

        ``cam_from_new = cam_from_old o old_from_new``: ``R' = R_c R^T``,
        ``t' = t_c - R_c R^T t``.
        """
        Rm = check_rotation("in_frame: R", R)
        tv = check_vector3("in_frame: t", t)
        R_new = self.R @ Rm.T
        return replace(self, R=R_new, t=self.t - R_new @ tv)


# --------------------------------------------------------------------------- Rig

#: Default per-camera extrinsic calibration error (1 sigma) used when a rig
#: states none: 2 mm of camera-centre position per axis and 0.1 degree of
#: orientation per axis. A target-based multi-camera calibration (Kalibr,
#: OpenCV stereo) typically reaches 0.5-2 mm and 0.02-0.1 deg; a factory or
#: CAD calibration is rarely better. Errors of this size set the floor of the
#: relative uncertainty of a metric scale fixed by short baselines
#: (:func:`mcgeom.observability.calibration_scale_std`).
DEFAULT_EXTRINSIC_STD = (2e-3, float(np.radians(0.1)))


def _calibration_std(value: Any, m: int) -> tuple[tuple[float, float], ...] | None:
    """``Rig.calibration_std`` checked: None, or M pairs (metres, radians) >= 0."""
    if value is None:
        return None
    try:
        a = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError("calibration_std must be a pair (position std in metres, rotation "
                         f"std in radians) or one pair per camera, got {value!r}") from None
    if a.shape == (2,):
        a = np.tile(a, (m, 1))
    if a.shape != (m, 2):
        raise ValueError(f"calibration_std must have shape (2,) or ({m}, 2) (metres, radians "
                         f"per camera), got {a.shape}")
    if not (np.all(np.isfinite(a)) and np.all(a >= 0)):
        raise ValueError(f"calibration_std must hold finite values >= 0, got {value!r}")
    return tuple((float(p), float(r)) for p, r in a)


@dataclass(frozen=True)
class Rig:
    """A calibrated multi-camera rig: cameras with extrinsics in one rig frame (metres).

    Camera ids are the indices into ``cameras``. Names must be unique.

    ``calibration_std`` is the 1-sigma error of each camera's extrinsics: one
    pair ``(position std in metres per axis, rotation std in radians per
    axis)`` for every camera, or one pair per camera (id order); None (the
    default) when the calibration does not say, and then
    :data:`DEFAULT_EXTRINSIC_STD` applies (see :attr:`extrinsic_std`). The
    scale uncertainty of every estimate from this rig includes it.

    ``frame`` says which physical frame the extrinsics (and so every ray, and every
    motion ``rig2_from_rig1`` estimated with this rig) are expressed in:

    * ``"body"``: a frame of the rig body that no camera defines (Kalibr's IMU frame,
      or the frame of an mcgeom file in which no camera sits at the origin);
    * ``"camera:<name>"``: the frame of that camera (its extrinsics are the identity);
    * ``"custom ..."``: a frame chosen with an explicit transform (:meth:`in_frame`,
      :func:`mcgeom.load_rig` with ``frame=`` a 4x4 matrix);
    * ``"unspecified"``: a rig built in code without saying (the default).

    The label is metadata: it is not compared by ``==`` (two rigs with equal cameras are
    equal) and it is never used in the mathematics.
    """

    cameras: tuple[Camera, ...]
    calibration_std: Any = None
    frame: str = field(default="unspecified", compare=False)

    def __post_init__(self) -> None:
        if not isinstance(self.frame, str) or not self.frame:
            raise ValueError(f"frame must be a non-empty string naming the rig frame, got {self.frame!r}")
        cams = self.cameras
        if isinstance(cams, Camera) or not isinstance(cams, Sequence):
            raise ValueError(f"cameras must be a sequence of Camera, got {type(cams).__name__}")
        cams = tuple(cams)
        if not cams:
            raise ValueError("a rig needs at least one camera")
        for i, cam in enumerate(cams):
            if not isinstance(cam, Camera):
                raise ValueError(f"cameras[{i}] is a {type(cam).__name__}, not a Camera")
        names = [c.name for c in cams]
        dupes = sorted({n for n in names if names.count(n) > 1})
        if dupes:
            raise ValueError(f"camera names must be unique; repeated: {', '.join(map(repr, dupes))}")
        object.__setattr__(self, "cameras", cams)
        object.__setattr__(self, "calibration_std", _calibration_std(self.calibration_std,
                                                                     len(cams)))
        object.__setattr__(self, "_centres", _frozen(np.array([c.centre for c in cams])))
        # Stacked intrinsics/extrinsics for the vectorised bearings of
        # :meth:`_pinhole_rays` (cameras are immutable: stacked once, not per call)
        object.__setattr__(self, "_Ks", _frozen(np.stack([c.K for c in cams])))
        object.__setattr__(self, "_Rs", _frozen(np.stack([c.R for c in cams])))
        object.__setattr__(self, "_plain", np.array(
            [c.model == "pinhole" and not np.any(c.dist) for c in cams]))
        object.__setattr__(self, "_all_plain", bool(self._plain.all()))  # type: ignore[attr-defined]
        # the entries of K that :meth:`_pinhole_rays` uses, one contiguous
        # (M,) row each (fx, fy, cx, cy, skew): five 1-D gathers per call
        # instead of one of N 3x3 matrices (the same numbers, the same bearings)
        Ks = self._Ks  # type: ignore[attr-defined]
        object.__setattr__(self, "_pinhole", _frozen(np.stack(
            [Ks[:, 0, 0], Ks[:, 1, 1], Ks[:, 0, 2], Ks[:, 1, 2], Ks[:, 0, 1]])))
        # the pixel-noise table of mcgeom.pixel_noise.camera_table: mean focal
        # length (pixels) and optical axis (rig frame, row 2 of cam_from_rig)
        object.__setattr__(self, "_noise_table", (
            _frozen(0.5 * (Ks[:, 0, 0] + Ks[:, 1, 1])),
            _frozen(np.ascontiguousarray(self._Rs[:, 2, :]))))  # type: ignore[attr-defined]
        # the tables of the C input stage (csrc/pixel_rays.c, issue 19): one
        # (M, 5) row of fx, fy, cx, cy, skew per camera, in camera order
        object.__setattr__(self, "_pinhole_tables", (
            _frozen(np.ascontiguousarray(self._pinhole.T)),  # type: ignore[attr-defined]
            self._Rs, self._centres, self._noise_table[0])  # type: ignore[attr-defined]
            if self._all_plain else None)  # type: ignore[attr-defined]
        object.__setattr__(self, "_extrinsic_std", _frozen(
            np.tile(DEFAULT_EXTRINSIC_STD, (len(cams), 1)) if self.calibration_std is None
            else np.array(self.calibration_std, dtype=np.float64)))
        object.__setattr__(self, "_calibration_error",
                           self._extrinsic_std if self._extrinsic_std.any() else None)

    def __len__(self) -> int:
        return len(self.cameras)

    def __repr__(self) -> str:
        return f"Rig(frame={self.frame!r}, cameras={list(self.names)!r})"

    def camera_at_origin(self, tol: float = 1e-12) -> str | None:
        """Name of the first camera whose extrinsics are the identity (within ``tol``,
        rotation entries and metres), i.e. whose frame is the rig frame; else None."""
        for c in self.cameras:
            if (float(np.max(np.abs(c.R - np.eye(3)))) <= tol
                    and float(np.max(np.abs(c.t))) <= tol):
                return c.name
        return None

    @property
    def centres(self) -> np.ndarray:
        """(M, 3) camera centres in the rig frame, metres (read-only)."""
        return self._centres  # type: ignore[attr-defined]

    @property
    def intrinsics(self) -> np.ndarray:
        """(M, 3, 3) intrinsic matrices ``K`` of the cameras in id order, pixels
        (read-only; stacked once: the cameras are immutable)."""
        return self._Ks  # type: ignore[attr-defined]

    @property
    def rotations(self) -> np.ndarray:
        """(M, 3, 3) rotations cam_from_rig of the cameras in id order (read-only):
        row 2 of ``rotations[i]`` is camera i's optical axis in the rig frame."""
        return self._Rs  # type: ignore[attr-defined]

    @property
    def extrinsic_std(self) -> np.ndarray:
        """(M, 2) 1-sigma extrinsic error of each camera: position (metres, per
        axis), rotation (radians, per axis); :data:`DEFAULT_EXTRINSIC_STD` for
        every camera when ``calibration_std`` is None."""
        return self._extrinsic_std.copy()  # type: ignore[attr-defined]

    @property
    def calibration_error(self) -> np.ndarray | None:
        """:attr:`extrinsic_std` (read-only, made once), or None when every
        std is 0 (the calibration known exactly: it adds nothing to the
        scale's uncertainty). What the robust façade passes on, once per
        estimate."""
        return self._calibration_error  # type: ignore[attr-defined]

    @property
    def focal_axes(self) -> tuple[np.ndarray, np.ndarray]:
        """(M,) mean focal lengths ``(fx + fy) / 2`` (pixels) and (M, 3) optical
        axes (rig frame: row 2 of each ``rotations[i]``) of the cameras,
        read-only, C-contiguous, made once (the rig is immutable)."""
        return self._noise_table  # type: ignore[attr-defined]

    @property
    def pinhole_tables(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None:
        """The per-camera tables of :func:`mcgeom._core.pinhole_ray_pairs` when
        every camera is an undistorted pinhole, else None: (M, 5) ``fx, fy,
        cx, cy, skew`` (pixels), (M, 3, 3) rotations cam_from_rig, (M, 3)
        centres (rig frame, metres), (M,) mean focal lengths (pixels);
        read-only, C-contiguous float64, made once (the rig is immutable)."""
        return self._pinhole_tables  # type: ignore[attr-defined]

    @property
    def names(self) -> tuple[str, ...]:
        """Camera names, in id order."""
        return tuple(c.name for c in self.cameras)

    def camera(self, i: int) -> Camera:
        """Camera with id ``i`` (0-based); ValueError for unknown ids."""
        if isinstance(i, (bool, np.bool_)):
            raise ValueError(f"camera id must be an integer, got {i!r}")
        try:
            idx = operator.index(i)
        except TypeError:
            raise ValueError(f"camera id must be an integer, got {i!r}") from None
        if not 0 <= idx < len(self.cameras):
            raise ValueError(f"unknown camera id {idx}: rig has cameras 0..{len(self.cameras) - 1}")
        return self.cameras[idx]

    def _check_ids(self, what: str, ids: Any, n: int) -> np.ndarray:
        arr = np.asarray(ids)
        if arr.ndim == 0:  # one id for every pixel
            arr = integral_camera_ids(what, arr)
            self.camera(int(arr))  # ValueError for an unknown id
            arr = np.full(n, int(arr), dtype=np.int64)
        if arr.ndim != 1:
            raise ValueError(f"{what} must have shape (N,), got {arr.shape}")
        if arr.shape[0] != n:
            raise ValueError(f"{what} has {arr.shape[0]} ids but there are {n} pixels")
        if arr.size == 0:
            return np.zeros(0, dtype=np.int64)
        arr = integral_camera_ids(what, arr)   # the one rule (mcgeom.validation)
        bad = (arr < 0) | (arr >= len(self.cameras))
        if np.any(bad):
            raise ValueError(f"{what}: unknown camera id {int(arr[bad][0])}: rig has cameras "
                             f"0..{len(self.cameras) - 1}")
        return np.ascontiguousarray(arr, dtype=np.int64)

    def rays(self, cam_ids: Any, pixels: Any) -> tuple[np.ndarray, np.ndarray]:
        """Rays of pixels, in the rig frame.

        Args:
            cam_ids: (N,) integer camera ids (or one id for all pixels).
            pixels: (N, 2) pixel coordinates of camera ``cam_ids[k]``.

        Returns:
            ``(origins, dirs)``: (N, 3) camera centres (metres) and (N, 3) unit bearings,
            both in the rig frame. The Plücker moment is ``origins x dirs``.
        """
        px = check_pixels("pixels", pixels)
        ids = self._check_ids("cam_ids", cam_ids, px.shape[0])
        return self._rays_checked(ids, px)

    def _rays_checked(self, ids: np.ndarray, px: np.ndarray, tables: dict | None = None
                      ) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`rays` for ids and pixels already checked (``ray_pairs`` checks them
        once: the checks cost more than the arithmetic at a few hundred pixels).
        ``tables``: a dict that keeps the per-camera rows gathered by ``ids``
        for a second call with the same ids (the other time of a pair)."""
        tables = {} if tables is None else tables
        if "origins" not in tables:
            tables["origins"] = self.centres[ids]   # (fancy indexing: a new array)
            origins = tables["origins"]
        else:
            origins = tables["origins"].copy()
        if self._all_plain:  # type: ignore[attr-defined]
            dirs, norms = self._pinhole_rays(ids, px, tables)
            # a pinhole bearing is v / |v| with v = (x, y, 1): unit unless |v|
            # overflowed (inf) or is NaN -- the same rows as the test below
            bad = np.flatnonzero(~(norms < np.inf))
        else:
            used = np.flatnonzero(np.bincount(ids, minlength=len(self.cameras)))
            if self._plain[used].all():  # type: ignore[attr-defined]
                dirs = self._pinhole_rays(ids, px)[0]
            else:
                dirs = np.empty((px.shape[0], 3))
                for i in used:  # one OpenCV call per camera
                    sel = ids == i
                    dirs[sel] = self.cameras[i].pixels_to_bearings(px[sel])
            # unit bearings have squared length 1
            bad = np.flatnonzero(~(np.einsum("ij,ij->i", dirs, dirs) > 0.5))
        # finite pixels far enough out (1e300) overflow |K^-1 [u, v, 1]| and come
        # out as zero or NaN bearings: name them here rather than let them fail
        # deep in an estimator
        if bad.size:
            k = int(bad[0])
            raise ValueError(f"camera {self.cameras[ids[k]].name!r}: pixel ({px[k, 0]:.6g}, "
                             f"{px[k, 1]:.6g}) has no finite bearing ({bad.size} such pixel(s); "
                             f"far outside any image)")
        return origins, dirs

    def _pinhole_rays(self, ids: np.ndarray, px: np.ndarray, tables: dict | None = None
                      ) -> tuple[np.ndarray, np.ndarray]:
        """Bearings of undistorted pinhole pixels, all cameras at once:
        ``R_i^T normalize(K_i^-1 [u, v, 1])`` row by row (the same arithmetic as
        :meth:`Camera.pixels_to_bearings`, without a call per camera), and the
        (N,) lengths ``|K_i^-1 [u, v, 1]|`` they were divided by. ``tables``
        as for :meth:`_rays_checked`."""
        tables = {} if tables is None else tables
        if "K" not in tables:
            tables["K"] = self._pinhole[:, ids]  # type: ignore[attr-defined]
            tables["R"] = self._Rs[ids]  # type: ignore[attr-defined]
        fx, fy, cx, cy, skew = tables["K"]
        y = (px[:, 1] - cy) / fy
        x = (px[:, 0] - cx - skew * y) / fx
        d = np.empty((px.shape[0], 3))
        d[:, 0] = x
        d[:, 1] = y
        d[:, 2] = 1.0
        # pixels far outside any image (1e300) overflow here: the caller names
        # them from the non-finite lengths, so numpy's warning would only add noise
        with np.errstate(over="ignore", invalid="ignore"):
            norms = np.linalg.norm(d, axis=1)
            d /= norms[:, None]
        return np.einsum("nji,nj->ni", tables["R"], d), norms

    def ray_pairs(self, pixels1: Any, pixels2: Any, cam1: Any, cam2: Any = None) -> RayPairs:
        """Ray correspondences from pixel correspondences.

        Args:
            pixels1: (N, 2) pixels at time 1, in cameras ``cam1``.
            pixels2: (N, 2) pixels at time 2, in cameras ``cam2``.
            cam1: (N,) camera ids at time 1.
            cam2: (N,) camera ids at time 2; default ``cam1`` (same camera at both times).

        Returns:
            :class:`RayPairs` in the rig frame (metres, unit directions) with camera ids.
        """
        px1 = check_pixels("pixels1", pixels1)
        px2 = check_pixels("pixels2", pixels2)
        if px2.shape[0] != px1.shape[0]:
            raise ValueError(f"pixels2 has {px2.shape[0]} rows but pixels1 has {px1.shape[0]}")
        ids1 = self._check_ids("cam1", cam1, px1.shape[0])
        ids2 = ids1 if cam2 is None else self._check_ids("cam2", cam2, px2.shape[0])
        return self.ray_pairs_prechecked(px1, px2, ids1, ids2)

    def ray_pairs_prechecked(self, px1: np.ndarray, px2: np.ndarray, ids1: np.ndarray,
                             ids2: np.ndarray) -> RayPairs:
        """:meth:`ray_pairs` without its argument checks, for callers that checked them.

        Preconditions (the caller's to guarantee; nothing is checked here):
        ``px1``, ``px2`` finite float64 C-contiguous (N, 2) pixels, ``ids1``,
        ``ids2`` (N,) int64 ids in ``0 .. len(self) - 1``. A pixel without a
        finite bearing is still a ValueError. ``mcgeom.cv`` checks its own
        (OpenCV-style) input: checking again would cost as much as the
        bearings (measured: 69 of 190 us at 300 Ladybug correspondences,
        2.3 % of an ``estimateRigMotion``).
        """
        if not self._all_plain:  # type: ignore[attr-defined]
            both = self._distorted_pairs(px1, px2, ids1, ids2)
            if both is not None:
                return both
        tables: dict = {}
        o1, d1 = self._rays_checked(ids1, px1, tables)
        # the same cameras at both times (cameraIds2 None): their rows once
        o2, d2 = self._rays_checked(ids2, px2, tables if ids2 is ids1 else None)
        # made here from checked ids: float64 C-contiguous (N, 3), no second check
        return RayPairs.prechecked(o1, d1, o2, d2, ids1, ids2.copy())

    def _distorted_pairs(self, px1: np.ndarray, px2: np.ndarray, ids1: np.ndarray,
                         ids2: np.ndarray) -> RayPairs | None:
        """:meth:`ray_pairs_prechecked` of a rig with distorted (or fisheye)
        cameras: the pixels of both times in one OpenCV call per camera, not
        one per camera and time, and without checking the checked pixels
        again (issue 19: the per-call overhead was 0.5-1.5 ms of the façade
        on such rigs). None when some pixel has no bearing: the per-time path
        then names the first one, as it always has."""
        n = px1.shape[0]
        px = np.concatenate([px1, px2])
        ids = np.concatenate([ids1, ids2])
        used = np.flatnonzero(np.bincount(ids, minlength=len(self.cameras)))
        if self._plain[used].all():  # type: ignore[attr-defined]
            return None  # only undistorted cameras used: the all-at-once pinhole path
        dirs = np.empty((2 * n, 3))
        for i in used:
            sel = np.flatnonzero(ids == i)
            dirs[sel] = self.cameras[i]._bearings_checked(px[sel], strict=False)
        # unit bearings have squared length 1 (NaN rows: no ray, fail too)
        if not (np.einsum("ij,ij->i", dirs, dirs) > 0.5).all():
            return None
        centres = self.centres
        o1 = centres[ids1]
        o2 = centres[ids2]   # (fancy indexing: new arrays, also when ids2 is ids1)
        return RayPairs.prechecked(o1, np.ascontiguousarray(dirs[:n]), o2,
                                   np.ascontiguousarray(dirs[n:]), ids1, ids2.copy())

    def project(self, cam_id: int, points_rig: Any) -> tuple[np.ndarray, np.ndarray]:
        """Project rig-frame points into camera ``cam_id``; see :meth:`Camera.project`."""
        return self.camera(cam_id).project(points_rig)

    def in_frame(self, R: Any, t: Any, frame: str | None = None) -> "Rig":
        """The same physical rig described in a new rig frame ``X_new = R X_old + t``.

        Each camera's extrinsics become ``cam_from_new = cam_from_old o old_from_new``;
        rays of the new rig are the old rays mapped by ``(R, t)``. ``frame`` labels the new
        frame (:attr:`frame`); default ``"custom (X = R X_<old frame> + t)"``.
        """
        Rm = check_rotation("in_frame: R", R)  # checked once, not once per camera
        tv = check_vector3("in_frame: t", t)
        label = f"custom (X = R X_{self.frame} + t)" if frame is None else frame
        return Rig(tuple(c.in_frame(Rm, tv) for c in self.cameras), self.calibration_std,
                   frame=label)
