"""Synthetic problems of each generalized-camera kind (thesis ch. 8.3): the
rigs and motions of the shared property suite (``tests/test_estimator_properties.py``)
and of the experiments that sweep the estimators over the kinds
(:mod:`mcgeom.experiments.direct_outliers`), and gross outliers as a matcher
makes them (a random bearing at time 2).

Frames and units (docs/architecture.md §3): rig frames, metres, radians;
``X2 = R X1 + t`` (rig2_from_rig1).
"""

from __future__ import annotations

from typing import Optional

import numpy as np

from . import synth
from .types import RayPairs

__all__ = ["KIND_SETUPS", "near_rig_axis", "kind_problem", "with_random_bearings",
           "outlier_problem"]

#: how to produce data of each kind: (rig factory, cross-camera fraction)
KIND_SETUPS = {
    "locally-central": (lambda rng: synth.generic_rig(4, rng), 0.0),
    "most-general": (lambda rng: synth.generic_rig(4, rng), 0.5),
    "axial": (lambda rng: synth.axial_rig(3), 0.5),
    "locally-central-and-axial": (lambda rng: synth.stereo_head(0.5), 0.0),
}


def near_rig_axis(R: np.ndarray, rig, min_angle_deg: float = 5.0) -> bool:
    """True if the rig's camera centres lie on a line and the rotation axis of
    R is within min_angle_deg of it (the critical motion of an axial rig)."""
    c = np.array([cam.centre for cam in rig.cameras])
    if len(c) < 2:
        return False
    _, s, vt = np.linalg.svd(c - c.mean(axis=0))
    if s[0] == 0.0 or (len(s) > 1 and s[1] > 1e-9 * s[0]):
        return False
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    if not np.linalg.norm(w) > 0.0:
        return False
    cosang = abs(w @ vt[0]) / np.linalg.norm(w)
    return cosang > np.cos(np.radians(min_angle_deg))


def kind_problem(kind: str, seed: int, n: int = 60, angle: tuple = (0.05, 0.5),
                 t_norm: float = 0.5, angular_noise: float = 0.0,
                 R: Optional[np.ndarray] = None, t: Optional[np.ndarray] = None
                 ) -> synth.SyntheticProblem:
    """A problem of ``kind`` (a key of :data:`KIND_SETUPS`) with ``n``
    correspondences: its rig drawn with ``seed``, a random rotation of
    ``angle`` radians (min, max) away from the critical ones and a t of
    length ``t_norm`` metres (or the given R, t), bearings with
    ``angular_noise`` radians of noise."""
    rng = np.random.default_rng(seed)
    rig_factory, cross = KIND_SETUPS[kind]
    rig = rig_factory(rng)
    if R is None:
        R = synth.random_rotation(rng, angle[1])
        # keep the rotation away from zero, and (intra-camera rays of an
        # axial rig) its axis away from the rig axis, so that the scale is
        # observable: a rotation about the rig axis is critical (conditioning
        # 2e-9 at 0.13 deg from it, found by the property suite)
        while (np.arccos(np.clip((np.trace(R) - 1) / 2, -1, 1)) < angle[0]
               or (cross == 0.0 and near_rig_axis(R, rig))):
            R = synth.random_rotation(rng, angle[1])
    if t is None:
        t = rng.normal(size=3)
        t *= t_norm / np.linalg.norm(t)
    return synth.make_problem(rig, R, t, n, rng, cross_fraction=cross,
                              angular_noise=angular_noise, require_visible=False)


def with_random_bearings(rays: RayPairs, fraction: float,
                         rng: np.random.Generator) -> tuple[RayPairs, np.ndarray]:
    """``rays`` with about ``fraction`` of their time-2 bearings replaced by
    random unit directions (gross outliers: a wrong match), and the mask of
    the replaced ones."""
    bad = rng.random(len(rays)) < fraction
    d2 = rays.dirs2.copy()
    d2[bad] = rng.normal(size=(int(bad.sum()), 3))
    d2[bad] /= np.linalg.norm(d2[bad], axis=1, keepdims=True)
    return RayPairs(rays.origins1, rays.dirs1, rays.origins2, d2, rays.cam1, rays.cam2), bad


def outlier_problem(kind: str, seed: int, n: int, angular_noise: float = 1e-3,
                    fraction: float = 0.02) -> tuple[synth.SyntheticProblem, RayPairs, np.ndarray]:
    """Problem ``seed`` of the outlier sweeps: :func:`kind_problem` with seed
    1000 + ``seed`` and ``n`` correspondences, then ``fraction`` of its time-2
    bearings random (:func:`with_random_bearings`, seed 5000 + ``seed``).
    Returns the problem (its truth), the rays and the mask of the replaced
    bearings."""
    p = kind_problem(kind, 1000 + seed, n=n, angular_noise=angular_noise)
    if not fraction > 0:
        return p, p.rays, np.zeros(n, bool)
    rays, bad = with_random_bearings(p.rays, fraction, np.random.default_rng(5000 + seed))
    return p, rays, bad
