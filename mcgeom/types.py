"""Data types shared by every layer: ray correspondences and rig motions.

Frames and units follow docs/architecture.md §3: rays are expressed in the rig frame
(metres), a motion is rig2_from_rig1, ``X_rig2 = R @ X_rig1 + t``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Optional

import numpy as np

from .validation import (as_camera_ids, as_vectors, check_directions, check_origins,
                         check_rotation, check_vector3)

__all__ = ["RayPairs", "ScaleVerdict", "RigMotion", "MotionFocal", "make_scale_verdict",
           "make_rig_motion"]


@dataclass(frozen=True)
class RayPairs:
    """N ray correspondences between two instants of a rig, in the rig frame.

    Ray k at time 1 starts at ``origins1[k]`` (metres, rig frame at time 1) and
    points along ``dirs1[k]``; ray k at time 2 likewise in the rig frame at
    time 2. Both rays see the same scene point. Origins should be the camera
    centres (required for the axial generalized-camera cases). Directions need
    not be unit length. ``cam1``/``cam2`` optionally give the camera ids, used
    for diagnostics and for sampling across cameras.
    """

    origins1: np.ndarray
    dirs1: np.ndarray
    origins2: np.ndarray
    dirs2: np.ndarray
    cam1: Optional[np.ndarray] = None
    cam2: Optional[np.ndarray] = None

    def __post_init__(self) -> None:
        o1 = as_vectors("origins1", self.origins1)
        n = o1.shape[0]
        object.__setattr__(self, "origins1", o1)
        object.__setattr__(self, "dirs1", as_vectors("dirs1", self.dirs1, n))
        object.__setattr__(self, "origins2", as_vectors("origins2", self.origins2, n))
        object.__setattr__(self, "dirs2", as_vectors("dirs2", self.dirs2, n))
        object.__setattr__(self, "cam1", as_camera_ids("cam1", self.cam1, n))
        object.__setattr__(self, "cam2", as_camera_ids("cam2", self.cam2, n))

    @classmethod
    def prechecked(cls, origins1: np.ndarray, dirs1: np.ndarray, origins2: np.ndarray,
                   dirs2: np.ndarray, cam1: Optional[np.ndarray] = None,
                   cam2: Optional[np.ndarray] = None) -> "RayPairs":
        """A RayPairs of arrays that already pass the checks of ``__init__``,
        without checking them again (the caller's to guarantee): four (N, 3)
        float64 C-contiguous arrays (metres, rig frame), ``cam1``/``cam2``
        None or (N,) int64 ids in ``0 .. 2^20 - 1``. For producers that made
        the arrays themselves (:meth:`mcgeom.rig.Rig.ray_pairs_prechecked`):
        the checks of ``__init__`` cost about as much as the bearings at a
        few hundred correspondences (issue 19)."""
        out = object.__new__(cls)
        for name, a in (("origins1", origins1), ("dirs1", dirs1), ("origins2", origins2),
                        ("dirs2", dirs2), ("cam1", cam1), ("cam2", cam2)):
            object.__setattr__(out, name, a)
        return out

    def __len__(self) -> int:
        return self.origins1.shape[0]

    def check_finite(self) -> None:
        """Raise ValueError naming the first array that holds NaN or inf, an
        origin coordinate beyond :data:`mcgeom.validation.MAX_ORIGIN` (1e150 m)
        or a direction of zero length (the C kernels check these themselves;
        estimators that do numpy work before reaching them call this: a zero
        direction would otherwise become NaN bearings deep inside them, and a
        far origin overflow there)."""
        for name in ("origins1", "dirs1", "origins2", "dirs2"):
            if not np.all(np.isfinite(getattr(self, name))):
                raise ValueError(f"rays.{name} contains NaN or inf")
        for name in ("origins1", "origins2"):
            check_origins(f"rays.{name}", getattr(self, name))
        for name in ("dirs1", "dirs2"):
            check_directions(f"rays.{name}", getattr(self, name))

    def n_distinct(self, at_least: Optional[int] = None) -> int:
        """Number of distinct correspondences (exact repeats of all six arrays'
        rows counted once). With ``at_least``, returns as soon as the first
        ``4 * at_least`` rows hold that many: the common case costs a sort of
        a few rows, not of all of them."""
        def rows(stop: Optional[int]) -> np.ndarray:
            cols = [a[:stop] for a in (self.origins1, self.dirs1, self.origins2, self.dirs2)]
            cols += [ids[:stop, None].astype(np.float64) for ids in (self.cam1, self.cam2)
                     if ids is not None]
            return np.ascontiguousarray(np.concatenate(cols, axis=1))

        def distinct(r: np.ndarray) -> int:
            # rows sorted lexicographically, then the changes between neighbours
            # counted (np.unique(axis=0) sorts a byte view of the rows and costs
            # ~0.2 ms even for a few rows: the robust pipeline asks this of every
            # problem)
            if len(r) == 0:
                return 0
            s = r[np.lexsort(r.T[::-1])]
            return 1 + int(np.count_nonzero(np.any(s[1:] != s[:-1], axis=1)))

        if at_least is not None and len(self) > 4 * at_least:
            k = distinct(rows(4 * at_least))
            if k >= at_least:
                return k
        return distinct(rows(None))

    def canonical_order(self) -> np.ndarray:
        """A permutation that sorts the correspondences by quantities that do
        not depend on their order nor on the rig frame or unit: the camera
        ids, then the angle between the two bearings. Estimators that process
        rays in this order give the same answer for any input order (bit for
        bit) and keep their invariance to the frame (their random samples see
        the rays in the same order in every frame)."""
        d1 = self.dirs1 / np.linalg.norm(self.dirs1, axis=1, keepdims=True)
        d2 = self.dirs2 / np.linalg.norm(self.dirs2, axis=1, keepdims=True)
        angle = np.arctan2(np.linalg.norm(np.cross(d1, d2), axis=1), np.einsum("ij,ij->i", d1, d2))
        keys = [angle]
        if self.cam1 is not None and self.cam2 is not None:
            keys += [self.cam2, self.cam1]
        return np.lexsort(keys)

    def take(self, index: Any) -> "RayPairs":
        """Subset (or permutation) of the correspondences by an index array or mask."""
        idx = np.asarray(index)
        if idx.size == 0:
            idx = idx.astype(np.int64)
        if idx.dtype != bool and idx.dtype.kind not in "iu":
            raise ValueError(f"index must be integers or a boolean mask, got dtype {idx.dtype}")
        if idx.dtype == bool and idx.ndim == 1 and idx.shape[0] == len(self):
            # a mask selects the same rows of six arrays: find them once
            idx = np.flatnonzero(idx)
        # fancy indexing of validated arrays keeps them valid (float64, C order,
        # N x 3): skip the checks of __init__, this is on the robust hot path
        out = object.__new__(RayPairs)
        for name in ("origins1", "dirs1", "origins2", "dirs2"):
            object.__setattr__(out, name, getattr(self, name)[idx].reshape(-1, 3))
        for name in ("cam1", "cam2"):
            ids = getattr(self, name)
            object.__setattr__(out, name, None if ids is None else ids[idx].reshape(-1))
        return out

    def swapped(self) -> "RayPairs":
        """The same correspondences with time 1 and time 2 exchanged."""
        return RayPairs(self.origins2, self.dirs2, self.origins1, self.dirs1, self.cam2, self.cam1)

    def in_frame(self, R: np.ndarray, t: np.ndarray) -> "RayPairs":
        """Re-express the rays in a new rig frame ``X_new = R @ X_old + t``
        (``R`` a rotation, ``t`` in metres; ValueError otherwise)."""
        R = check_rotation("in_frame: R", R)
        t = check_vector3("in_frame: t", t)
        return RayPairs(
            self.origins1 @ R.T + t, self.dirs1 @ R.T,
            self.origins2 @ R.T + t, self.dirs2 @ R.T,
            self.cam1, self.cam2,
        )

    def is_locally_central(self) -> Optional[bool]:
        """True if every correspondence is seen by the same camera at both times."""
        if self.cam1 is None or self.cam2 is None:
            return None
        return bool(np.all(self.cam1 == self.cam2))


@dataclass(frozen=True)
class ScaleVerdict:
    """Whether the metric scale of ``t`` is determined by the data, and why.

    ``conditioning`` is in [0, 1]: how strongly the data constrain the length of
    ``t`` relative to its best-constrained direction (0 = not at all, the
    critical configuration of thesis ch. 7.3.2). ``rel_std`` is the first-order
    relative standard deviation of ``|t|`` estimated from the residuals.
    ``critical_angle`` (radians) is filled by the methods of ch. 7.
    """

    observable: bool
    reason: str
    conditioning: float = float("nan")
    rel_std: float = float("nan")
    critical_angle: float = float("nan")


@dataclass(frozen=True)
class RigMotion:
    """A relative rig motion rig2_from_rig1: ``X_rig2 = R @ X_rig1 + t``.

    ``R`` is a 3x3 rotation, ``t`` the translation in metres (the unit of the
    rig extrinsics). When ``scale.observable`` is False, ``t`` is still the
    maximum-likelihood metric estimate where the data define a scale at all
    (``scale.rel_std`` says how loosely; the 5+1 pipeline sets
    ``info['scale_determined']``), and has unit norm, only its direction
    meaningful, where they do not (exactly critical motion, one camera). ``t``
    is zero when no translation was detected. ``residual_rms`` is the RMS residual of
    the method's own cost (documented by each estimator in ``info``),
    ``inliers`` a boolean mask where the method is robust, ``info`` holds
    method-specific diagnostics (detected camera case, ranks, iterations...).
    """

    R: np.ndarray
    t: np.ndarray
    scale: ScaleVerdict
    method: str
    residual_rms: float = float("nan")
    inliers: Optional[np.ndarray] = None
    info: dict = field(default_factory=dict)

    @property
    def T(self) -> np.ndarray:
        """4x4 homogeneous matrix of rig2_from_rig1."""
        T = np.eye(4)
        T[:3, :3] = self.R
        T[:3, 3] = self.t
        return T

    def inverse(self) -> "RigMotion":
        """rig1_from_rig2 with the same verdict and diagnostics."""
        return RigMotion(self.R.T.copy(), -self.R.T @ self.t, self.scale, self.method,
                         self.residual_rms, self.inliers, dict(self.info))


#: ``motion_focal(rays, R, t)``: (N,) pixels per radian of each residual at the
#: motion ``X2 = R X1 + t`` (rig frame, ``t`` in metres); made by the rig's
#: pixel-noise model (:func:`mcgeom.pixel_noise.sampson_pixel_scale`), called by
#: :func:`mcgeom.robust.ransac`: a type both layers share, so it lives here
MotionFocal = Callable[[RayPairs, np.ndarray, np.ndarray], np.ndarray]


# ------------------------------------------------- hot-path constructors
# (public so that estimators may use them: the same objects as the
# constructors make, for an estimator's per-call path)
# A frozen dataclass's __init__ sets each field through object.__setattr__
# (about 0.7 us for ScaleVerdict and RigMotion each, issue 22: a tenth of the
# Python time of mcgeom.estimate(rays, "linear17") at 100 rays). Neither
# class has __post_init__ or validation, so filling the instance's __dict__
# makes the same object; the check below makes a later field or
# __post_init__ fail at import instead of silently skipping it.
if ([f.name for f in ScaleVerdict.__dataclass_fields__.values()] !=
        ["observable", "reason", "conditioning", "rel_std", "critical_angle"] or
        [f.name for f in RigMotion.__dataclass_fields__.values()] !=
        ["R", "t", "scale", "method", "residual_rms", "inliers", "info"] or
        hasattr(ScaleVerdict, "__post_init__") or hasattr(RigMotion, "__post_init__")):
    raise RuntimeError("mcgeom.types: update make_scale_verdict and make_rig_motion to "
                       "the fields of ScaleVerdict and RigMotion")
#: the default critical_angle object itself (nan): fields compare equal to
#: those of ScaleVerdict(...) (tuple equality tests identity before ==)
_NO_CRITICAL_ANGLE = ScaleVerdict.__dataclass_fields__["critical_angle"].default
_new = object.__new__


def make_scale_verdict(observable: bool, reason: str, conditioning: float,
                       rel_std: float) -> ScaleVerdict:
    """``ScaleVerdict(observable, reason, conditioning, rel_std)`` (no
    critical angle), without the frozen dataclass's per-field setattr."""
    v = _new(ScaleVerdict)
    d = v.__dict__
    d["observable"] = observable
    d["reason"] = reason
    d["conditioning"] = conditioning
    d["rel_std"] = rel_std
    d["critical_angle"] = _NO_CRITICAL_ANGLE
    return v


def make_rig_motion(R: np.ndarray, t: np.ndarray, scale: ScaleVerdict, method: str,
                    residual_rms: float, inliers: Optional[np.ndarray], info: dict) -> RigMotion:
    """``RigMotion(R, t, scale, method, residual_rms, inliers, info)`` (R 3x3,
    t metres, rig2_from_rig1), without the frozen dataclass's per-field
    setattr."""
    m = _new(RigMotion)
    d = m.__dict__
    d["R"] = R
    d["t"] = t
    d["scale"] = scale
    d["method"] = method
    d["residual_rms"] = residual_rms
    d["inliers"] = inliers
    d["info"] = info
    return m
