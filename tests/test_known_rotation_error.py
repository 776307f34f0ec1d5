"""known_rotation_translation propagates the error of the given rotation into
its verdict (issue 18: on DDAD scene_02 pair 1-2, intra-camera, the
ground-truth rotation "known" exactly gave |t| 0.025 m against 1.265 m with
an observable verdict)."""

from __future__ import annotations

import numpy as np
import pytest

import mcgeom
from mcgeom import synth
from mcgeom.estimators.known_rotation_translation import DEFAULT_ROTATION_STD


def _forward_intra(seed: int):
    """The 8-camera car rig driving 1 m forward with a 0.5 deg yaw: intra-camera
    rays only, near the critical motion (thesis ch. 7.3.2)."""
    rng = np.random.default_rng(seed)
    rig = synth.vehicle8()
    R = synth.rotation_about([0, 0, 1], np.radians(0.5))
    t = np.array([1.0, 0.0, 0.0])
    return synth.make_problem(rig, R, t, 320, rng, angular_noise=np.radians(0.02)), R, t


def test_rotation_error_widens_the_interval_and_can_withdraw_the_scale():
    rng = np.random.default_rng(0)
    rig = synth.generic_rig(4, rng)
    R, t = synth.random_motion(rng, max_angle=0.3, t_norm=0.5)
    p = synth.make_problem(rig, R, t, 200, rng, angular_noise=np.radians(0.02))
    exact = mcgeom.estimate(p.rays, "known_rotation_translation", rotation=R, rotation_std=0.0)
    default = mcgeom.estimate(p.rays, "known_rotation_translation", rotation=R)
    loose = mcgeom.estimate(p.rays, "known_rotation_translation", rotation=R,
                            rotation_std=np.radians(3.0))
    assert exact.scale.observable and default.scale.observable
    assert default.scale.rel_std > exact.scale.rel_std
    assert not loose.scale.observable
    assert "rotation_std" in loose.scale.reason
    assert np.isclose(np.linalg.norm(loose.t), 1.0)


def test_near_critical_motion_is_not_metric_with_the_default_rotation_error():
    p, R, _ = _forward_intra(0)
    m = mcgeom.estimate(p.rays, "known_rotation_translation", rotation=R)
    assert not m.scale.observable
    assert np.isclose(np.linalg.norm(m.t), 1.0)


def test_the_propagated_std_matches_the_spread_under_rotation_error():
    # Monte Carlo: rotations drawn with DEFAULT_ROTATION_STD per axis move |t|
    # by about the propagated std (first order; a factor 2 either way)
    rng = np.random.default_rng(1)
    rig = synth.generic_rig(4, rng)
    R, t = synth.random_motion(rng, max_angle=0.3, t_norm=0.5)
    p = synth.make_problem(rig, R, t, 200, rng)
    m0 = mcgeom.estimate(p.rays, "known_rotation_translation", rotation=R, rotation_std=0.0)
    m = mcgeom.estimate(p.rays, "known_rotation_translation", rotation=R)
    rel_rot = np.sqrt(max(m.scale.rel_std ** 2 - m0.scale.rel_std ** 2, 0.0))
    lengths = []
    for _ in range(60):
        dR = mcgeom._core.rot_from_angle_axis(rng.normal(size=3) * DEFAULT_ROTATION_STD)
        mk = mcgeom.estimate(p.rays, "known_rotation_translation", rotation=R @ dR,
                             rotation_std=0.0)
        lengths.append(np.linalg.norm(mk.info["t_metric"]))
    spread = np.std(lengths) / np.linalg.norm(m0.t)
    assert 0.5 * spread < rel_rot < 2.0 * spread


@pytest.mark.parametrize("bad", [-1e-3, 0.2, float("nan"), "x", True])
def test_bad_rotation_std_is_named(bad):
    p, R, _ = _forward_intra(2)
    with pytest.raises(ValueError, match="rotation_std"):
        mcgeom.estimate(p.rays, "known_rotation_translation", rotation=R, rotation_std=bad)
