"""Synthetic problems for each generalized-camera kind (thesis ch. 8.3), shared
by the property suite, the experiments and the benchmarks in tests/."""

from __future__ import annotations

import numpy as np

from mcgeom import synth

#: how to produce data of each kind: (rig factory, cross-camera fraction)
KIND_SETUPS = {
    "locally-central": (lambda rng: synth.generic_rig(4, rng), 0.0),
    "most-general": (lambda rng: synth.generic_rig(4, rng), 0.5),
    "axial": (lambda rng: synth.axial_rig(3), 0.5),
    "locally-central-and-axial": (lambda rng: synth.stereo_head(0.5), 0.0),
}


def make(kind: str, seed: int, n: int = 60, angle: tuple = (0.05, 0.5), t_norm: float = 0.5,
         angular_noise: float = 0.0, R=None, t=None):
    """A problem of the given kind with a random motion (or the given R, t)."""
    rng = np.random.default_rng(seed)
    rig_factory, cross = KIND_SETUPS[kind]
    rig = rig_factory(rng)
    if R is None:
        R = synth.random_rotation(rng, angle[1])
        # keep the rotation away from zero so that the scale is observable
        while np.arccos(np.clip((np.trace(R) - 1) / 2, -1, 1)) < angle[0]:
            R = synth.random_rotation(rng, angle[1])
    if t is None:
        t = rng.normal(size=3)
        t *= t_norm / np.linalg.norm(t)
    return synth.make_problem(rig, R, t, n, rng, cross_fraction=cross,
                              angular_noise=angular_noise, require_visible=False)


def rigid(rng: np.random.Generator):
    """A random rigid transform (R, t) with |t| ~ 1 m."""
    R = synth.random_rotation(rng, np.pi)
    return R, rng.normal(size=3)


rot_err = synth.rotation_error  # angle (rad) between two rotations, accurate near zero
