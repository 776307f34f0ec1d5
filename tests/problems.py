"""Synthetic problems for each generalized-camera kind (thesis ch. 8.3), shared
by the property suite and the other tests."""

from __future__ import annotations

import numpy as np

from mcgeom import metrics, synth, synth_kinds
from mcgeom.types import RayPairs

#: how to produce data of each kind, and the problems (mcgeom.synth_kinds)
KIND_SETUPS = synth_kinds.KIND_SETUPS
make = synth_kinds.kind_problem


def rigid(rng: np.random.Generator):
    """A random rigid transform (R, t) with |t| ~ 1 m."""
    R = synth.random_rotation(rng, np.pi)
    return R, rng.normal(size=3)


rot_err = metrics.rotation_error  # angle (rad) between two rotations, accurate near zero


def generic_outlier_problem(seed: int):
    """A generic 4-camera rig (random cameras), 150 correspondences, half of
    them cross-camera, 1e-4 rad noise, 20 % outliers, one fixed motion
    (|t| 0.50 m): the RANSAC problem of the 17-pair C searches' tests. Seed 3 has
    16 camera pairs, two of them a single outlier each."""
    rng = np.random.default_rng(seed)
    rig = synth.generic_rig(4, rng)
    R = synth.rotation_about([0.2, 1.0, 0.1], 0.3)
    t = np.array([0.4, 0.05, 0.3])
    return synth.make_problem(rig, R, t, 150, rng, cross_fraction=0.5, angular_noise=1e-4,
                              outlier_fraction=0.2, require_visible=False)


def turning_motion(rng: np.random.Generator, max_angle: float = 0.3,
                   min_angle: float = 0.1) -> tuple[np.ndarray, np.ndarray]:
    """A motion that is far from the critical one: a random rotation of at
    least ``min_angle`` radians (drawn up to ``max_angle``) and a unit t."""
    R = synth.random_rotation(rng, max_angle)
    while metrics.rotation_error(R, np.eye(3)) < min_angle:
        R = synth.random_rotation(rng, max_angle)
    t = rng.normal(size=3)
    return R, t / np.linalg.norm(t)



def assert_unconfirmed_partial_fit(partial, full, samples: int, sample_size: int) -> None:
    """``partial``, a robust search that its cap of ``samples`` samples of
    ``sample_size`` ended on a partial fit, reports no scale: its verdict says
    the consensus is not confirmed, ``t`` is a unit direction and
    ``info['t_metric']`` keeps the fit; it explains less than half of what
    ``full`` (the uncapped search) does."""
    assert np.count_nonzero(partial.inliers) < 0.5 * np.count_nonzero(full.inliers)
    assert not partial.scale.observable
    assert partial.scale.reason.startswith(
        f"consensus not confirmed: the search reached its sample cap after {samples} samples "
        f"of {sample_size}")
    assert abs(np.linalg.norm(partial.t) - 1.0) < 1e-9
    assert np.linalg.norm(partial.info["t_metric"]) > 0.0


def ring_intra_problem(rng: np.random.Generator, n: int = 300, outliers: float = 0.0):
    """Intra-camera rays of a 4-camera ring (radius 0.25 m, cameras looking
    out) turning 3-17 deg and travelling 1 m, bearings with 1e-3 rad noise
    (0.5 px at f = 500 px); points 2-20 m away; ``outliers`` of them with a
    random time-2 bearing."""
    R = synth.random_rotation(rng, 0.3)
    while np.degrees(np.arccos((np.trace(R) - 1) / 2)) < 3:
        R = synth.random_rotation(rng, 0.3)
    t = rng.normal(size=3)
    t /= np.linalg.norm(t)
    yaw = np.arange(4) * np.pi / 2
    axes = np.stack([np.cos(yaw), np.sin(yaw), np.zeros(4)], axis=1)
    cam = np.arange(n) % 4
    o = 0.25 * axes[cam]
    d = axes[cam] + rng.uniform(-0.5, 0.5, size=(n, 3)) * np.array([1.0, 1.0, 0.6])
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    X2 = (o + d * rng.uniform(2.0, 20.0, size=(n, 1))) @ R.T + t
    d2 = X2 - o
    d2 /= np.linalg.norm(d2, axis=1, keepdims=True)
    d1 = d + rng.normal(scale=1e-3, size=(n, 3))
    d2 = d2 + rng.normal(scale=1e-3, size=(n, 3))
    if outliers > 0:   # (drawn last: the problems without outliers stay the same)
        bad = rng.random(n) < outliers
        d2[bad] = rng.normal(size=(int(bad.sum()), 3))
    return RayPairs(o, d1, o.copy(), d2, cam, cam), R, t
