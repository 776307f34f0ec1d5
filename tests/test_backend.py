"""mcgeom.sequence.estimate_trajectory: the scale status of the steps, the
propagation of an observed scale through the tracks, determinism, scale
covariance and bad input, on synthetic tracks of a rig moving through
random 3-D points."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, HealthCheck
from hypothesis import strategies as st

from mcgeom import synth
from mcgeom.rig import Camera, Rig
from mcgeom.sequence import Tracks, estimate_trajectory

# 4 outward cameras, 90 deg apart with a 65 deg field of view: no two views
# overlap, so every track is intra-camera (thesis ch. 7.3.2, Theorem 3)
RING = synth.ring_rig(4, radius=0.5, f=800.0)


def _rz(deg: float) -> np.ndarray:
    return synth.rotation_about((0.0, 0.0, 1.0), np.radians(deg))


def _path(yaws_per_step: list, step_length: float = 1.0) -> np.ndarray:
    """world_from_rig poses (F, 4, 4): the rig drives along its x axis (x
    forward, z up), turning by ``yaws_per_step[k]`` degrees during step k."""
    poses = [np.eye(4)]
    yaw = 0.0
    for dyaw in yaws_per_step:
        # the chord of the turn: half the turn before the step, half after
        yaw_mid = yaw + 0.5 * dyaw
        T = np.eye(4)
        yaw += dyaw
        T[:3, :3] = _rz(yaw)
        T[:3, 3] = poses[-1][:3, 3] + step_length * np.array(
            [np.cos(np.radians(yaw_mid)), np.sin(np.radians(yaw_mid)), 0.0])
        poses.append(T)
    return np.array(poses)


def _scene(poses: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    """Random points around the path, at least 3 m from every rig position."""
    c = poses[:, :3, 3]
    lo, hi = c.min(axis=0) - 25.0, c.max(axis=0) + 25.0
    pts = np.column_stack([rng.uniform(lo[0], hi[0], 4 * n), rng.uniform(lo[1], hi[1], 4 * n),
                           rng.uniform(-4.0, 6.0, 4 * n)])
    d = np.min(np.linalg.norm(pts[:, None, :2] - c[None, :, :2], axis=2), axis=1)
    return pts[d > 3.0][:n]


def _tracks(rig: Rig, poses: np.ndarray, points: np.ndarray, sigma: float,
            rng: np.random.Generator, cross: bool = False) -> Tracks:
    """Intra-camera tracks only: a point seen by camera i is track
    ``point * n_cams + i`` (no cross-camera matches), raw pixels + noise;
    with ``cross`` a point is one track in every camera that sees it."""
    n_cams = len(rig.cameras)
    track, frame, cam, px = [], [], [], []
    for k, T in enumerate(poses):
        X_rig = (points - T[:3, 3]) @ T[:3, :3]        # R^T (X - c), row-wise
        for i in range(n_cams):
            p, vis = rig.project(i, X_rig)
            idx = np.flatnonzero(vis)
            track.append(idx if cross else idx * n_cams + i)
            frame.append(np.full(len(idx), k))
            cam.append(np.full(len(idx), i))
            px.append(p[idx] + sigma * rng.standard_normal((len(idx), 2)))
    return Tracks(np.concatenate(track), np.concatenate(frame), np.concatenate(cam),
                  np.concatenate(px), len(poses))


def _sequence(yaws: list, seed: int = 1, sigma: float = 0.2, rig: Rig = RING,
              n_points: int = 3000, step_length: float = 1.0, cross: bool = False):
    rng = np.random.default_rng(seed)
    poses = _path(yaws, step_length)
    return poses, _tracks(rig, poses, _scene(poses, n_points, rng), sigma, rng, cross)


def _true_lengths(poses: np.ndarray) -> np.ndarray:
    return np.linalg.norm(np.diff(poses[:, :3, 3], axis=0), axis=1)


def test_straight_without_overlap_never_invents_a_scale():
    poses, tracks = _sequence([0.0] * 6)
    traj = estimate_trajectory(RING, tracks)
    assert set(traj.status) <= {"unknown", "carried"}
    assert "carried" not in traj.status          # nothing observed: nothing to carry
    # no metric position beyond frame 0, and every segment is direction-only
    assert traj.known.tolist() == [True] + [False] * 6
    assert not any(s.metric for s in traj.segments)
    assert all(np.isnan(s.length) for s in traj.steps)
    assert traj.status_counts == {"metric": 0, "carried": 0, "unknown": 6}
    assert traj.metric_path_length == 0.0
    # the directions are still right: the rig drives along its x axis. Each
    # step's direction is its two-frame estimate's (within 0.05 deg on 20
    # such sequences); the tracks' own shape bent steps by 7.9 deg on
    # average (median 2.4, up to 94), and passed 0.99 (8 deg) here by luck
    seg = traj.segments[0]
    d = np.diff(seg.poses[:, :3, 3], axis=0)
    assert np.all(d[:, 0] / np.linalg.norm(d, axis=1) > np.cos(np.radians(0.5)))
    assert np.isclose(np.linalg.norm(d, axis=1).sum(), 1.0)   # normalised, no unit


def test_turn_carries_the_scale_through_the_straight_stretches():
    yaws = [0.0] * 4 + [15.0] * 3 + [0.0] * 4
    poses, tracks = _sequence(yaws, seed=2)
    traj = estimate_trajectory(RING, tracks)
    status = traj.status
    straight = [k for k, y in enumerate(yaws) if y == 0.0]
    # the straight steps cannot observe the scale on their own ...
    assert all(status[k] == "carried" for k in straight), status
    assert "metric" in status and "unknown" not in status
    # ... but their lengths come out within a few % of the truth
    est = np.array([s.length for s in traj.steps])
    np.testing.assert_allclose(est, _true_lengths(poses), rtol=0.04)
    assert traj.known.all() and len(traj.segments) == 1
    assert traj.status_counts == {"metric": 3, "carried": 8, "unknown": 0}
    np.testing.assert_allclose(traj.metric_path_length, est.sum())
    err = np.linalg.norm(traj.centres - poses[:, :3, 3], axis=1)
    assert err.max() < 0.04 * 11.0     # 4 % of the 11 m path


def test_one_observed_step_fixes_the_whole_segment():
    # scale propagation: a single turning step among straight ones
    yaws = [0.0] * 3 + [20.0] + [0.0] * 3
    poses, tracks = _sequence(yaws, seed=3)
    traj = estimate_trajectory(RING, tracks, metric_from="steps")
    assert traj.status.count("metric") >= 1
    assert traj.status.count("unknown") == 0
    carried = [s for s in traj.steps if s.status == "carried"]
    assert len(carried) >= 5 and all("carried" in s.reason for s in carried)
    np.testing.assert_allclose([s.length for s in traj.steps], _true_lengths(poses),
                               rtol=0.05)


def test_unlinked_steps_split_segments_and_are_never_stitched():
    # frames 0-3 straight, then every track is cut between frames 3 and 4 and
    # 4-6 see new tracks only: steps 2 and 3 share no track of three frames
    poses, tracks = _sequence([0.0] * 6, seed=4)
    late = tracks.frame >= 4
    cut = Tracks(np.where(late, tracks.track + 10 ** 7, tracks.track), tracks.frame,
                 tracks.camera, tracks.pixels, tracks.n_frames)
    traj = estimate_trajectory(RING, cut)
    assert len(traj.segments) >= 2
    assert traj.segments[0].frames[-1] == traj.segments[1].frames[0]
    assert not traj.known[1:].any()


def test_deterministic():
    _, tracks = _sequence([0.0] * 2 + [15.0] * 2 + [0.0] * 2, seed=5)
    a = estimate_trajectory(RING, tracks)
    b = estimate_trajectory(RING, tracks)
    np.testing.assert_array_equal(a.poses, b.poses)
    assert a.status == b.status
    for sa, sb in zip(a.steps, b.steps):
        np.testing.assert_array_equal(sa.motion.inliers, sb.motion.inliers)


def _scaled_rig(rig: Rig, s: float) -> Rig:
    return Rig(tuple(Camera(c.name, c.K, c.dist, c.model, c.R, s * c.t, c.width, c.height)
                     for c in rig.cameras))


_TURN = _sequence([0.0] * 2 + [15.0] * 2 + [0.0] * 2, seed=6)


@settings(max_examples=3, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.floats(min_value=0.05, max_value=20.0))
def test_scaling_world_and_rig_scales_the_trajectory(s):
    # the same pixels seen by a rig s times larger in a world s times larger
    poses, tracks = _TURN
    ref = estimate_trajectory(RING, tracks)
    big = estimate_trajectory(_scaled_rig(RING, s), tracks)
    assert big.status == ref.status
    # equal up to the refinements' convergence tolerance: the C search's LM stops
    # on a relative decrease, so positions agree to ~2e-6 of the path's extent
    extent = float(np.abs(ref.centres).max())
    np.testing.assert_allclose(big.centres, s * ref.centres, rtol=0, atol=1e-5 * s * extent)
    np.testing.assert_allclose(big.poses[:, :3, :3], ref.poses[:, :3, :3], atol=1e-7)


def test_outlier_observations_are_rejected():
    """10 % random outlier pixels: the two-frame inliers drop all but a few,
    the triangulation check the rest (4 left of 1,433 bent the solve)."""
    poses, tracks = _sequence([0.0] * 2 + [15.0] * 2 + [0.0] * 2, seed=7)
    rng = np.random.default_rng(0)
    px = tracks.pixels.copy()
    bad = rng.random(len(px)) < 0.1
    px[bad] = rng.uniform([0, 0], [1023, 767], (int(bad.sum()), 2))
    traj = estimate_trajectory(RING, Tracks(tracks.track, tracks.frame, tracks.camera, px,
                                            tracks.n_frames))
    assert traj.known.all()
    err = np.linalg.norm(traj.centres - poses[:, :3, 3], axis=1)
    assert err.max() < 0.2


def test_static_rig_is_metric_zero_only_with_cross_camera_inliers():
    """A parked rig: "no translation detected" is metric (0 m) when
    cross-camera inliers at the rig's baseline bound the translation; without
    them (a scene at infinity would look the same) it stays unknown."""
    stereo = Rig([synth.look_at_camera(n, (0.0, y, 0.0), (1.0, 0.0, 0.0), f=600.0)
                  for n, y in (("left", 0.25), ("right", -0.25))])
    poses, tracks = _sequence([0.0] * 3, seed=11, rig=stereo, step_length=0.0, cross=True)
    assert np.any(tracks.correspondences(0, 1)[2] != tracks.correspondences(0, 1)[3])
    traj = estimate_trajectory(stereo, tracks)
    assert traj.status == ("metric",) * 3 and traj.known.all()
    assert np.abs(traj.centres).max() == 0.0
    poses, tracks = _sequence([0.0] * 3, seed=11, step_length=0.0)
    traj = estimate_trajectory(RING, tracks)
    assert traj.status == ("unknown",) * 3 and not traj.known[1:].any()


def test_bad_input_is_a_value_error():
    _, tracks = _sequence([0.0] * 2, seed=8, n_points=500)
    one = tracks.in_frames(0, 0)
    with pytest.raises(ValueError, match="at least 2 frames"):
        estimate_trajectory(RING, one)
    with pytest.raises(ValueError, match="camera id 3"):
        estimate_trajectory(synth.ring_rig(3, radius=0.5, f=800.0), tracks)
    with pytest.raises(ValueError, match="Rig"):
        estimate_trajectory("rig.yaml", tracks)
    with pytest.raises(ValueError, match="Tracks"):
        estimate_trajectory(RING, tracks.pixels)
    with pytest.raises(ValueError, match="window"):
        estimate_trajectory(RING, tracks, window=1)
    with pytest.raises(ValueError, match="metric_from"):
        estimate_trajectory(RING, tracks, metric_from="guess")
    with pytest.raises(ValueError, match="threshold"):
        estimate_trajectory(RING, tracks, threshold=-1.0)


def test_metric_steps_of_a_rig_with_a_calibration_error_are_checked_by_sampling():
    """A rig that states its extrinsic error: every metric step's calibration
    part is checked against rigs drawn with it (calibration_check="sampled",
    the default); where the estimate is linear in the extrinsics (a turning
    ring) the sampled figure is the first-order one and the steps stay
    metric. "first_order" skips the check."""
    rig = Rig(RING.cameras, calibration_std=(2e-3, np.radians(0.1)))
    poses, tracks = _sequence([10.0, -12.0], seed=3, n_points=1500)
    tr = estimate_trajectory(rig, tracks)
    assert [s.status for s in tr.steps] == ["metric", "metric"]
    for s in tr.steps:
        info = s.motion.info
        ratio = info["scale_rel_std_calibration_sampled"] / info["scale_rel_std_calibration"]
        assert 0.7 < ratio < 1.4
    plain = estimate_trajectory(rig, tracks, calibration_check="first_order")
    assert all("scale_rel_std_calibration_sampled" not in s.motion.info for s in plain.steps)
    with pytest.raises(ValueError, match="calibration_check"):
        estimate_trajectory(rig, tracks, calibration_check="none")
