"""Tests of mcgeom.synth: rigs, motions, paths and synthetic problems."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from mcgeom import metrics, synth
from mcgeom.rig import Rig
from mcgeom.types import RayPairs


def epipolar_residuals(rays: RayPairs, R: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Generalized epipolar residual (docs/architecture.md §3) of each correspondence:
    d2^T [t]x R d1 + d2^T R m1 + m2^T R d1 with unit d and m = origin x d."""
    d1 = rays.dirs1 / np.linalg.norm(rays.dirs1, axis=1, keepdims=True)
    d2 = rays.dirs2 / np.linalg.norm(rays.dirs2, axis=1, keepdims=True)
    m1, m2 = np.cross(rays.origins1, d1), np.cross(rays.origins2, d2)
    Rd1 = d1 @ R.T
    return (np.sum(d2 * np.cross(t, Rd1), axis=1) + np.sum(d2 * (m1 @ R.T), axis=1)
            + np.sum(m2 * Rd1, axis=1))


def distorted_rig() -> Rig:
    """Vehicle-like rig with distorted pinhole and fisheye cameras (not in synth)."""
    cams = (synth.look_at_camera("front", (0.5, 0.0, 0.0), (1, 0, 0), f=500.0,
                                 dist=(-0.2, 0.05, 0.001, -0.001, 0.0)),
            synth.look_at_camera("left", (0.0, 0.5, 0.0), (0, 1, 0), f=400.0,
                                 dist=(0.02, -0.004, 0.0005, -0.00003), model="fisheye"),
            synth.look_at_camera("back", (-0.5, 0.0, 0.1), (-1, 0.3, 0), f=550.0,
                                 dist=(0.1, -0.02, 0.0, 0.0, 0.0, 0.05, 0.0, 0.0)))
    return Rig(cams)


RIGS = {
    "stereo_head": synth.stereo_head(),
    "axial_rig": synth.axial_rig(),
    "ladybug2": synth.ladybug2(),
    "vehicle8": synth.vehicle8(),
    "generic_rig": synth.generic_rig(4, rng=11),
    "distorted": distorted_rig(),
}
# rigs whose views overlap enough after a moderate motion for visible cross-camera pairs
OVERLAPPING = {"ladybug2", "vehicle8", "generic_rig", "distorted"}


def motion_for(name: str, seed: int = 0):
    if name in ("ladybug2", "vehicle8", "distorted"):
        # the rig moves forward and turns (the vehicle drives, the Ladybug walks)
        return synth.rotation_about((0, 0.1, 1), 0.4), np.array([0.8, 0.1, 0.02])
    return synth.random_motion(seed, max_angle=0.3, t_norm=1.0)


# --------------------------------------------------------------------------- rigs

def test_rig_shapes():
    assert len(synth.stereo_head()) == 2
    assert len(synth.axial_rig(5)) == 5
    lb = synth.ladybug2()
    assert len(lb) == 6 and all((c.width, c.height) == (1024, 768) for c in lb.cameras)
    veh = synth.vehicle8()
    assert len(veh) == 8 and all((c.width, c.height) == (1024, 768) for c in veh.cameras)
    assert len(synth.generic_rig(6, 0)) == 6
    for rig in RIGS.values():
        assert len(set(rig.names)) == len(rig)


def test_stereo_head_geometry_and_no_overlap():
    rig = synth.stereo_head(baseline=0.7)
    np.testing.assert_allclose(np.linalg.norm(rig.centres[0] - rig.centres[1]), 0.7)
    # optical axes (third rows of cam_from_rig) point opposite ways, sideways
    np.testing.assert_allclose(rig.cameras[0].R[2], [0, 1, 0], atol=1e-15)
    np.testing.assert_allclose(rig.cameras[1].R[2], [0, -1, 0], atol=1e-15)
    # nothing that one camera sees (0.5 .. 100 m away) is seen by the other
    gen = np.random.default_rng(0)
    px = gen.uniform(0, 999, (2000, 2))
    for i in (0, 1):
        o, d = rig.rays(i, px)
        P = o + gen.uniform(0.5, 100, (2000, 1)) * d
        assert not rig.cameras[1 - i].project(P)[1].any()


def test_axial_rig_is_axial():
    rig = synth.axial_rig(4, spacing=0.25)
    C = rig.centres - rig.centres.mean(axis=0)
    s = np.linalg.svd(C, compute_uv=False)
    assert s[1] < 1e-12 and s[0] > 0.1
    np.testing.assert_allclose(np.linalg.norm(np.diff(rig.centres, axis=0), axis=1), 0.25)
    axes = np.array([c.R[2] for c in rig.cameras])
    cos = axes @ axes.T - 2 * np.eye(4)
    assert cos.max() < 0.99  # all viewing directions differ


def test_ladybug2_geometry():
    rig = synth.ladybug2()
    ring = rig.centres[:5]
    np.testing.assert_allclose(np.linalg.norm(ring[:, :2], axis=1), 0.04)
    np.testing.assert_allclose(ring[:, 2], 0.0)
    axes = np.array([c.R[2] for c in rig.cameras])
    np.testing.assert_allclose(axes[:5] @ axes[0], np.cos(np.deg2rad(72 * np.arange(5))), atol=1e-12)
    np.testing.assert_allclose(axes[5], [0, 0, 1], atol=1e-15)
    assert all(c.K[0, 0] == 400.0 for c in rig.cameras)


def test_vehicle8_geometry():
    rig = synth.vehicle8()
    left, right = rig.centres[:4], rig.centres[4:]
    np.testing.assert_allclose(left[:, 1], 0.95)
    np.testing.assert_allclose(right[:, 1], -0.95)
    axes = np.array([c.R[2] for c in rig.cameras])
    assert axes[0, 0] < -0.8 and axes[1, 1] > 0.99 and axes[2, 0] > 0.8 and axes[3, 2] > 0.9
    assert axes[4, 0] < -0.8 and axes[5, 1] < -0.99 and axes[6, 0] > 0.8 and axes[7, 2] > 0.9


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(3, 8))
def test_generic_rig_is_non_axial(seed, n):
    rig = synth.generic_rig(n, seed)
    s = np.linalg.svd(rig.centres - rig.centres.mean(axis=0), compute_uv=False)
    assert s[1] > 0.05 * np.sqrt(n)
    assert np.all(np.abs(rig.centres) <= 0.5)
    assert synth.generic_rig(n, seed) == rig


# --------------------------------------------------------------------------- motions

@settings(max_examples=50, deadline=None)
@given(st.integers(0, 2**32 - 1), st.floats(0.0, np.pi))
def test_random_rotation(seed, max_angle):
    R = synth.random_rotation(seed, max_angle)
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)
    assert np.linalg.det(R) > 0
    assert metrics.rotation_error(R, np.eye(3)) <= max_angle + 1e-9


def test_random_motion():
    R, t = synth.random_motion(3, max_angle=0.2, t_norm=2.5)
    np.testing.assert_allclose(np.linalg.norm(t), 2.5)
    assert metrics.rotation_error(R, np.eye(3)) <= 0.2
    R2, t2 = synth.random_motion(np.random.default_rng(3), max_angle=0.2, t_norm=2.5)
    np.testing.assert_array_equal(R, R2)
    np.testing.assert_array_equal(t, t2)


def test_error_helpers():
    R = synth.rotation_about((1, 2, 3), 0.3)
    assert metrics.rotation_error(R, np.eye(3)) == pytest.approx(0.3, abs=1e-14)
    assert metrics.rotation_error(R, R) == 0.0
    tiny = synth.rotation_about((0, 0, 1), 1e-9)
    assert metrics.rotation_error(tiny, np.eye(3)) == pytest.approx(1e-9, rel=1e-6)
    assert metrics.rotation_error(synth.rotation_about((0, 1, 0), np.pi), np.eye(3)) == pytest.approx(np.pi)
    ang, ratio = metrics.translation_errors([2.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    assert ang == pytest.approx(np.pi / 2) and ratio == pytest.approx(2.0)
    ang, ratio = metrics.translation_errors([0.0, 0.5, 0.0], [0.0, 1.0, 0.0])
    assert ang == 0.0 and ratio == 0.5
    assert all(np.isnan(metrics.translation_errors([1.0, 0, 0], [0.0, 0, 0])))


def test_figure_eight_path():
    poses = synth.figure_eight_path()
    assert len(poses) == 108
    P = np.array([T[:3, 3] for T in poses])
    steps = np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1)  # includes last -> first
    assert 0.03 < steps.min() and steps.max() < 0.10  # several cm
    assert steps.max() - steps.min() < 0.01 * steps.mean()  # equally spaced, closed
    assert np.allclose(P[:, 2], 0.0)
    yaw = []
    for k, T in enumerate(poses):
        Rw = T[:3, :3]
        np.testing.assert_allclose(Rw.T @ Rw, np.eye(3), atol=1e-12)
        np.testing.assert_allclose(Rw[:, 2], [0, 0, 1], atol=1e-12)  # rig up = world up
        # heading tangent: the next position lies ahead along the rig's x axis
        ahead = Rw.T @ (P[(k + 1) % 108] - P[k])
        assert ahead[0] > 0.99 * np.linalg.norm(ahead)
        yaw.append(np.arctan2(Rw[1, 0], Rw[0, 0]))
    # an ∞: the path crosses itself at the origin, and the rig turns both ways
    assert np.min(np.linalg.norm(P[:, :2], axis=1)) < 0.05
    turn = np.angle(np.exp(1j * np.diff(np.r_[yaw, yaw[0]])))
    assert turn.max() > 0.05 and turn.min() < -0.05


def test_relative_motion_between_poses():
    poses = synth.figure_eight_path(20, size=3.0)
    R, t = synth.relative_motion(poses[3], poses[4])
    X_rig1 = np.array([1.0, 2.0, 0.5])
    X_world = poses[3][:3, :3] @ X_rig1 + poses[3][:3, 3]
    X_rig2 = np.linalg.solve(poses[4][:3, :3], X_world - poses[4][:3, 3])
    np.testing.assert_allclose(R @ X_rig1 + t, X_rig2, atol=1e-12)


# --------------------------------------------------------------------------- problems

@pytest.mark.parametrize("name", sorted(RIGS))
def test_noise_free_problem_satisfies_generalized_epipolar_constraint(name):
    rig = RIGS[name]
    R, t = motion_for(name)
    p = synth.make_problem(rig, R, t, 120, rng=1)
    assert len(p) == 120 and np.all(p.cam1 == p.cam2) and p.inlier.all()
    assert np.abs(epipolar_residuals(p.rays, R, t)).max() < 1e-10
    assert np.bincount(p.cam1, minlength=len(rig)).min() >= 120 // len(rig)  # spread
    # visible mode: inside the image at both times, and the pixels are the projections
    for k in range(len(p)):
        for cam_id, px, P in ((p.cam1[k], p.pixels1[k], p.points[k]),
                              (p.cam2[k], p.pixels2[k], R @ p.points[k] + t)):
            proj, vis = rig.cameras[cam_id].project(P[None])
            assert vis[0]
            np.testing.assert_allclose(proj[0], px, atol=1e-6)


@pytest.mark.parametrize("name, visible", [
    (name, visible) for name in sorted(RIGS) for visible in (True, False)
    if name in OVERLAPPING or not visible])  # the others: test_impossible_visibility_...
def test_cross_camera_problem_satisfies_constraint(name, visible):
    rig = RIGS[name]
    R, t = motion_for(name)
    if name == "stereo_head":  # raw rays: opposite cameras meet only after a half turn
        R = synth.rotation_about((0, 0, 1), 2.0)
    p = synth.make_problem(rig, R, t, 100, rng=2, cross_fraction=0.4, require_visible=visible)
    assert np.sum(p.cam1 != p.cam2) == 40
    assert not p.rays.is_locally_central()
    assert np.abs(epipolar_residuals(p.rays, R, t)).max() < 1e-10
    d = p.points - rig.centres[p.cam1]  # the rays pass through the points
    np.testing.assert_allclose(d / np.linalg.norm(d, axis=1, keepdims=True), p.rays.dirs1, atol=1e-9)


@settings(max_examples=20, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_generic_rig_problems_property(seed):
    gen = np.random.default_rng(seed)
    rig = synth.generic_rig(int(gen.integers(3, 7)), gen)
    R, t = synth.random_motion(gen, max_angle=0.3, t_norm=gen.uniform(0.1, 2.0))
    p = synth.make_problem(rig, R, t, 40, gen, cross_fraction=0.3, require_visible=False)
    assert np.abs(epipolar_residuals(p.rays, R, t)).max() < 1e-10


def test_raw_mode_rays_leave_the_image():
    rig = synth.axial_rig()
    R, t = synth.random_motion(5)
    p = synth.make_problem(rig, R, t, 300, rng=5, require_visible=False)
    inside = np.concatenate([rig.cameras[c].in_image(px[None]) for c, px in zip(p.cam1, p.pixels1)])
    assert not inside.all()  # 85 deg half-angle: many virtual pixels off the image
    assert np.abs(epipolar_residuals(p.rays, R, t)).max() < 1e-10


def test_determinism():
    rig = synth.vehicle8()
    R, t = motion_for("vehicle8")
    kw = dict(cross_fraction=0.2, pixel_noise=0.5, angular_noise=1e-3, outlier_fraction=0.1)
    a = synth.make_problem(rig, R, t, 80, 42, **kw)
    b = synth.make_problem(rig, R, t, 80, np.random.default_rng(42), **kw)
    c = synth.make_problem(rig, R, t, 80, 43, **kw)
    for f in ("points", "cam1", "cam2", "pixels1", "pixels2", "inlier"):
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f))
    for f in ("origins1", "dirs1", "origins2", "dirs2"):
        np.testing.assert_array_equal(getattr(a.rays, f), getattr(b.rays, f))
    assert not np.array_equal(a.points, c.points)
    assert synth.generic_rig(5, 9) == synth.generic_rig(5, 9)
    assert synth.generic_rig(5, 9) != synth.generic_rig(5, 10)


def test_pixel_noise_is_gaussian_with_given_sigma():
    rig = synth.ladybug2()
    R, t = motion_for("ladybug2")
    clean = synth.make_problem(rig, R, t, 2000, 8)
    noisy = synth.make_problem(rig, R, t, 2000, 8, pixel_noise=0.7)
    np.testing.assert_array_equal(clean.points, noisy.points)  # noise drawn after the scene
    err = np.concatenate([noisy.pixels1 - clean.pixels1, noisy.pixels2 - clean.pixels2])
    assert np.std(err) == pytest.approx(0.7, rel=0.05)
    assert abs(np.mean(err)) < 0.05
    assert np.abs(epipolar_residuals(noisy.rays, R, t)).max() > 1e-6


def test_angular_noise_rotates_rays_by_sigma():
    rig = synth.generic_rig(4, 1)
    R, t = synth.random_motion(1)
    sigma = np.deg2rad(0.05)  # thesis ch. 8.5.1
    clean = synth.make_problem(rig, R, t, 3000, 8, require_visible=False)
    noisy = synth.make_problem(rig, R, t, 3000, 8, angular_noise=sigma, require_visible=False)
    np.testing.assert_array_equal(clean.rays.origins1, noisy.rays.origins1)
    np.testing.assert_array_equal(clean.pixels1, noisy.pixels1)  # pixels are not perturbed
    np.testing.assert_allclose(np.linalg.norm(noisy.rays.dirs1, axis=1), 1.0, atol=1e-15)
    cosang = np.sum(clean.rays.dirs1 * noisy.rays.dirs1, axis=1)
    ang = np.arctan2(np.linalg.norm(np.cross(clean.rays.dirs1, noisy.rays.dirs1), axis=1), cosang)
    assert np.sqrt(np.mean(ang**2)) == pytest.approx(sigma, rel=0.05)


def test_perturb_directions_axis_is_perpendicular():
    gen = np.random.default_rng(0)
    d = synth._random_unit(gen, 1000)
    out = synth.perturb_directions(d, 0.1, gen)
    # rotation about an axis ⟂ d: the angle between d and d' is |angle|
    ang = np.arccos(np.clip(np.sum(d * out, axis=1), -1, 1))
    assert np.sqrt(np.mean(ang**2)) == pytest.approx(0.1, rel=0.1)


def test_outliers():
    rig = synth.vehicle8()
    R, t = motion_for("vehicle8")
    p = synth.make_problem(rig, R, t, 200, 4, outlier_fraction=0.25)
    assert np.sum(~p.inlier) == 50
    res = np.abs(epipolar_residuals(p.rays, R, t))
    assert res[p.inlier].max() < 1e-10
    assert np.median(res[~p.inlier]) > 1e-3
    np.testing.assert_array_equal(p.cam1, p.cam2)  # outliers stay in their camera
    for c, px in zip(p.cam2[~p.inlier], p.pixels2[~p.inlier]):
        assert rig.cameras[c].in_image(px[None])[0]
    raw = synth.make_problem(synth.axial_rig(), R, t, 100, 4, outlier_fraction=0.5,
                             require_visible=False)
    assert np.sum(~raw.inlier) == 50


def test_problem_fields():
    rig = synth.ladybug2()
    R, t = motion_for("ladybug2")
    p = synth.make_problem(rig, R, t, 30, 0)
    assert p.rig is rig and p.points.shape == (30, 3) and p.pixels2.shape == (30, 2)
    assert p.cam1.dtype.kind == "i" and p.inlier.dtype == bool
    np.testing.assert_array_equal(p.T[:3, :3], R)
    np.testing.assert_array_equal(p.rays.cam1, p.cam1)
    np.testing.assert_array_equal(p.rays.origins1, rig.centres[p.cam1])
    depth = np.linalg.norm(p.points - rig.centres[p.cam1], axis=1)
    assert depth.min() >= 2.0 and depth.max() <= 20.0


def test_impossible_visibility_raises_clear_errors():
    rig = synth.stereo_head()
    R, t = synth.random_motion(0, max_angle=0.1)
    with pytest.raises(ValueError, match="cross-camera correspondences.*require_visible=False"):
        synth.make_problem(rig, R, t, 20, 0, cross_fraction=0.5)
    # a half turn: nothing either camera saw is in its own view afterwards
    half = synth.rotation_about((0, 0, 1), np.pi)
    with pytest.raises(ValueError, match=r"camera 0 \('left'\) yielded only 0 of 10 intra-camera"):
        synth.make_problem(rig, half, np.zeros(3), 20, 0)


@pytest.mark.parametrize("kwargs, message", [
    (dict(n_points=0), "n_points must be at least 1"),
    (dict(n_points=2.5), "n_points must be an integer"),
    (dict(cross_fraction=1.5), "cross_fraction must be in [0, 1]"),
    (dict(outlier_fraction=-0.1), "outlier_fraction must be in [0, 1]"),
    (dict(pixel_noise=-1.0), "pixel_noise must be a finite non-negative"),
    (dict(angular_noise=np.nan), "angular_noise must be a finite non-negative"),
    (dict(depth_range=(5.0, 1.0)), "depth_range must satisfy 0 < near <= far"),
    (dict(depth_range=(0.0, 1.0)), "depth_range must satisfy 0 < near <= far"),
    (dict(depth_range=3.0), "depth_range must be a pair"),
    (dict(R=np.diag([1.0, 1.0, -1.0])), "R is not a rotation"),
    (dict(R=np.eye(2)), "R must be a finite 3x3 rotation"),
    (dict(t=np.zeros(2)), "t must be a finite 3-vector"),
    (dict(rng="seed"), "rng must be a numpy Generator"),
])
def test_make_problem_bad_arguments(kwargs, message):
    args = dict(rig=synth.axial_rig(), R=np.eye(3), t=np.array([0.1, 0.0, 0.0]), n_points=10, rng=0)
    args.update(kwargs)
    with pytest.raises(ValueError) as err:
        synth.make_problem(**args)
    assert message in str(err.value)


def test_cross_needs_two_cameras():
    rig = Rig(synth.stereo_head().cameras[:1])
    with pytest.raises(ValueError, match="at least 2 cameras"):
        synth.make_problem(rig, np.eye(3), np.array([0.1, 0, 0]), 10, 0, cross_fraction=0.1)


@pytest.mark.parametrize("call, message", [
    (lambda: synth.random_rotation(0, 4.0), "max_angle must be in [0, pi]"),
    (lambda: synth.rotation_about((0, 0, 0), 1.0), "non-zero 3-vector"),
    (lambda: synth.axial_rig(0), "n_cameras must be at least 1"),
    (lambda: synth.generic_rig(0, 1), "n_cameras must be at least 1"),
    (lambda: synth.stereo_head(0.0), "baseline must be positive"),
    (lambda: synth.figure_eight_path(1), "n_positions must be at least 2"),
    (lambda: synth.figure_eight_path(10, size=-1.0), "size must be positive"),
    (lambda: synth.look_at_camera("sky", (0, 0, 0), (0, 0, 1)), "'up' is parallel"),
    (lambda: synth.as_rng(True), "rng must be"),
])
def test_bad_arguments_elsewhere(call, message):
    with pytest.raises(ValueError) as err:
        call()
    assert message in str(err.value)
