"""The demo's renderer (mcgeom.experiments.render, .world): determinism, geometry
against the camera model (distortion included), the written folder, bad input."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

import mcgeom
from mcgeom.experiments import render, world
from mcgeom.rig import Camera, Rig
from mcgeom.synth import look_at_camera, rotation_about


@pytest.fixture(scope="module")
def scene() -> world.Scene:
    return world.courtyard(0)


def small_rig() -> Rig:
    return render.surround_rig(96, 72)


def pose(yaw_deg: float = 0.0, t=(0.0, 0.0, 0.0)) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = rotation_about((0, 0, 1), math.radians(yaw_deg))
    T[:3, 3] = t
    return T


# --------------------------------------------------------------------------- determinism

def test_same_seed_same_bytes(scene, tmp_path):
    again = world.courtyard(0)
    assert all(np.array_equal(p.texture, q.texture) for p, q in zip(scene.planes, again.planes))
    other = world.courtyard(1)
    assert not np.array_equal(scene.planes[1].texture, other.planes[1].texture)
    rig = small_rig()
    T = world.loop_path(90)[20]
    first = render.Renderer(scene, rig).render_frame(T)
    second = render.Renderer(again, rig).render_frame(T)
    assert all(a.dtype == np.uint8 and a.shape == (72, 96) for a in first)
    assert all(np.array_equal(a, b) for a, b in zip(first, second))
    assert not np.array_equal(first[0], render.Renderer(other, rig).render_frame(T)[0])
    s1 = render.render_sequence(tmp_path / "a", n_frames=3, rig=rig)
    s2 = render.render_sequence(tmp_path / "b", n_frames=3, rig=rig)
    for name in rig.names:
        for p, q in zip(s1.images[name], s2.images[name]):
            assert p.read_bytes() == q.read_bytes()
    assert s1.groundtruth_path.read_bytes() == s2.groundtruth_path.read_bytes()


def test_images_are_textured_not_blank(scene):
    imgs = render.Renderer(scene, small_rig()).render_frame(np.eye(4))
    for img in imgs:
        assert img.std() > 20        # the texture has contrast everywhere


# --------------------------------------------------------------------------- geometry

def _dot_scene(centre: tuple[float, float, float]) -> tuple[world.Scene, np.ndarray]:
    """A black wall facing -x through ``centre`` with one bright Gaussian dot at
    ``centre`` (sigma 4 texels of 2 cm): the dot's world point is known exactly."""
    n = 401
    r = np.arange(n) - 200.0
    tex = 255.0 * np.exp(-(r[None, :] ** 2 + r[:, None] ** 2) / (2 * 4.0 ** 2))
    texel = 0.02
    u, v = np.array([0.0, -1.0, 0.0]), np.array([0.0, 0.0, -1.0])
    origin = np.asarray(centre) - texel * 200.5 * (u + v)
    plane = world.Plane("wall", origin, u, v, np.rint(tex).astype(np.uint8), texel)
    point = plane.point(200, 200)
    assert np.allclose(point, centre)
    return world.Scene((plane,), sky=0), point


def _blob_centre(img: np.ndarray, near: np.ndarray, half: int = 8) -> np.ndarray:
    x0, y0 = (int(round(c)) for c in near)
    win = img[y0 - half:y0 + half + 1, x0 - half:x0 + half + 1].astype(np.float64)
    ys, xs = np.mgrid[y0 - half:y0 + half + 1, x0 - half:x0 + half + 1]
    return np.array([(win * xs).sum(), (win * ys).sum()]) / win.sum()


@pytest.mark.parametrize("T", [pose(0.0), pose(8.0, (0.5, -0.3, 0.1)), pose(-6.0, (1.0, 0.4, 0))])
def test_rendered_dot_at_projected_pixel(T):
    """The dot shows at Camera.project (cv2.projectPoints, the forward model) of its
    world point, with the camera's distortion, for several rig poses."""
    cam = look_at_camera("cam", (0.3, 0.1, 0.0), (1.0, -0.25, -0.15), f=120.0, width=200,
                         height=150, dist=(-0.12, 0.02, 0.0, 0.0, 0.0))
    rig = Rig((cam,))
    dot = (8.0, 2.2, 1.1)
    scene, X = _dot_scene(dot)
    X_rig = (np.linalg.inv(T) @ np.append(X, 1.0))[:3]
    px, vis = cam.project(X_rig[None])
    assert vis[0]
    plain = Camera("plain", cam.K, [], "pinhole", cam.R, cam.t, 200, 150)
    px_plain, _ = plain.project(X_rig[None])
    assert np.linalg.norm(px_plain[0] - px[0]) > 2.0      # distortion matters here
    img = render.Renderer(scene, rig).render(T, "cam")
    found = _blob_centre(img, px[0])
    assert np.linalg.norm(found - px[0]) < 0.1, (found, px[0])


def test_distortion_is_the_camera_model(scene):
    """The distorted camera's image is the pinhole camera's image resampled through
    the lens model (within interpolation), and not the pinhole image itself."""
    K = np.array([[60.0, 0, 59.5], [0, 60.0, 44.5], [0, 0, 1]])
    dist = np.array([-0.15, 0.03, 0.0, 0.0, 0.0])
    R = look_at_camera("x", (1.9, 0, 0), (1, 0, -0.05)).R
    t = -R @ np.array([1.9, 0.0, 0.0])
    distorted = Camera("d", K, dist, "pinhole", R, t, 120, 90)
    # a larger pinhole image (same focal length, margin 40 px) covers the barrel's corners
    K_big = K.copy()
    K_big[0, 2] += 40
    K_big[1, 2] += 40
    plain = Camera("p", K_big, [], "pinhole", R, t, 200, 170)
    T = world.loop_path(90)[5]
    ren = render.Renderer(scene, Rig((distorted, plain)))
    img_d, img_p = ren.render_frame(T)
    u, v = np.meshgrid(np.arange(120.0), np.arange(90.0))
    xy = cv2.undistortPoints(np.column_stack([u.ravel(), v.ravel()]).reshape(-1, 1, 2), K, dist,
                             criteria=(cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12))
    xy = xy.reshape(90, 120, 2)
    mx = (K_big[0, 0] * xy[..., 0] + K_big[0, 2]).astype(np.float32)
    my = (K_big[1, 1] * xy[..., 1] + K_big[1, 2]).astype(np.float32)
    warped = cv2.remap(img_p, mx, my, cv2.INTER_LINEAR).astype(np.float64)
    ignored = cv2.remap(img_p, (u + 40).astype(np.float32), (v + 40).astype(np.float32),
                        cv2.INTER_LINEAR).astype(np.float64)
    err = np.abs(warped - img_d)
    err_ignored = np.abs(ignored - img_d)
    assert np.median(err) < 3.0 and err.mean() < 6.0, (np.median(err), err.mean())
    assert err.mean() < 0.5 * err_ignored.mean(), (err.mean(), err_ignored.mean())


def test_cameras_agree_through_the_known_pose(scene):
    """A wall point seen in frame 0 by the front camera appears, in frame 1, where
    the true motion projects it: the images of two poses are consistent."""
    rig = render.surround_rig(240, 180)
    ren = render.Renderer(scene, rig)
    path = world.loop_path(90)
    img0, img1 = ren.render(path[0], "front"), ren.render(path[1], "front")
    cam = rig.cameras[0]
    # the front camera sees the courtyard's far wall: x = 14 + 7 m from the block centre
    lay = world.CourtyardLayout()
    wall_x = lay.straight_x / 2 + lay.turn_radius + lay.outer_offset
    px0 = np.array([[150.0, 70.0], [90.0, 60.0], [120.0, 80.0]])
    d = cam.pixels_to_bearings(px0)
    s = (wall_x - cam.centre[0]) / d[:, 0]
    X_world = cam.centre + s[:, None] * d          # world = rig of frame 0
    X_rig1 = (np.linalg.inv(path[1]) @ np.column_stack([X_world, np.ones(3)]).T).T[:, :3]
    px1, vis = cam.project(X_rig1)
    assert vis.all()
    for p0, p1 in zip(px0, px1):
        a = cv2.getRectSubPix(img0, (15, 15), tuple(p0)).astype(np.float64)
        b = cv2.getRectSubPix(img1, (15, 15), tuple(p1)).astype(np.float64)
        shifted = cv2.getRectSubPix(img1, (15, 15), tuple(p1 + [4.0, 0.0])).astype(np.float64)
        assert np.abs(a - b).mean() < 4.0
        assert np.abs(a - b).mean() < 0.5 * np.abs(a - shifted).mean()


# --------------------------------------------------------------------------- path

def test_loop_path_is_closed_with_equal_steps():
    lay = world.CourtyardLayout()
    poses = world.loop_path(90)
    assert np.array_equal(poses[0], np.eye(4))
    assert np.allclose(poses[:, 2, 3], 0.0) and np.allclose(poses[:, :3, 2], [0, 0, 1])
    ring = np.concatenate([poses, poses[:1]])
    chords = np.linalg.norm(np.diff(ring[:, :3, 3], axis=0), axis=1)
    step = lay.length / 90
    assert np.all(chords <= step + 1e-9) and np.all(chords > 0.99 * step)
    yaw = np.unwrap(np.arctan2(ring[:, 1, 0], ring[:, 0, 0]))
    assert yaw[-1] - yaw[0] == pytest.approx(2 * np.pi)
    assert np.all(np.diff(yaw) >= -1e-12)                 # counter-clockwise throughout
    # straight stretches (no rotation) and turns both occur
    turn = np.diff(yaw)
    assert (turn < 1e-9).sum() > 30 and (turn > 0.1).sum() > 20
    # the forward axis is the direction of travel
    fwd = ring[:-1, :3, 0]
    travel = np.diff(ring[:, :3, 3], axis=0) / chords[:, None]
    assert np.all(np.sum(fwd * travel, axis=1) > np.cos(np.radians(12)))


def test_start_offset_and_step():
    p = world.loop_path(4, step=0.5, start=3.0)
    assert np.allclose(p[:, 0, 3], [3.0, 3.5, 4.0, 4.5]) and np.allclose(p[:, 1, 3], 0)


# --------------------------------------------------------------------------- files

def _quat_to_R(q):
    x, y, z, w = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def test_written_layout(tmp_path):
    rig = small_rig()
    seq = render.render_sequence(tmp_path / "out", n_frames=4, step=3.0, start=10.0, rig=rig)
    images = tmp_path / "out" / "images"
    assert sorted(p.name for p in images.iterdir()) == sorted(rig.names)
    for name in rig.names:
        files = sorted(p.name for p in (images / name).iterdir())
        assert files == [f"{k:06d}.png" for k in range(4)]
        img = cv2.imread(str(images / name / "000002.png"), cv2.IMREAD_UNCHANGED)
        assert img.dtype == np.uint8 and img.shape == (72, 96)
        assert seq.images[name][2] == images / name / "000002.png"
    loaded = mcgeom.load_rig(seq.rig_path)
    assert loaded.names == rig.names
    assert all(a == b for a, b in zip(loaded.cameras, rig.cameras))
    rows = np.loadtxt(seq.groundtruth_path)
    assert rows.shape == (4, 8) and np.array_equal(rows[:, 0], np.arange(4))
    assert np.allclose(rows[0, 1:], [0, 0, 0, 0, 0, 0, 1])
    scene_poses = world.loop_path(4, step=3.0, start=10.0)
    for k, row in enumerate(rows):
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = _quat_to_R(row[4:]), row[1:4]
        assert np.allclose(T, seq.poses[k], atol=1e-8)
        # the world of the file is the rig frame of frame 0
        assert np.allclose(scene_poses[0] @ T, scene_poses[k], atol=1e-8)
    # a shorter run in the same folder leaves no stale frame behind
    render.render_sequence(tmp_path / "out", n_frames=2, rig=rig)
    assert sorted(p.name for p in (images / rig.names[0]).iterdir()) == ["000000.png", "000001.png"]
    assert np.loadtxt(tmp_path / "out" / "groundtruth_tum.txt").shape == (2, 8)


def test_progress_wraps_the_frames(tmp_path):
    seen = []

    def progress(it, total=None, desc=None):
        seen.append(total)
        return it
    render.render_sequence(tmp_path, n_frames=2, rig=small_rig(), progress=progress)
    assert seen == [2]


# --------------------------------------------------------------------------- bad input

@pytest.mark.parametrize("kwargs, match", [
    ({"n_frames": 1}, "n_frames must be at least 2"),
    ({"n_frames": 2.5}, "n_frames must be an integer"),
    ({"n_frames": "3"}, "n_frames must be an integer"),
    ({"seed": -1}, "seed must be non-negative"),
    ({"step": 0.0}, "step must be positive"),
    ({"step": float("nan")}, "step must be positive"),
    ({"start": "a"}, "start must be a number"),
    ({"rig": "rig.json"}, "rig must be a mcgeom.rig.Rig"),
    ({"progress": 5}, "progress must be callable"),
    ({"layout": {"straight_x": 3}}, "layout must be a CourtyardLayout"),
])
def test_bad_arguments(tmp_path, kwargs, match):
    args = {"n_frames": 2, "rig": small_rig(), **kwargs}
    with pytest.raises(ValueError, match=match):
        render.render_sequence(tmp_path / "out", **args)
    assert not (tmp_path / "out").exists()           # nothing written


def test_bad_out_dir(tmp_path):
    f = tmp_path / "file"
    f.write_text("x")
    with pytest.raises(ValueError, match="exists and is not a folder"):
        render.render_sequence(f, n_frames=2, rig=small_rig())
    (tmp_path / "o" / "images" / "cam9").mkdir(parents=True)
    with pytest.raises(ValueError, match="not cameras of the rig.*cam9"):
        render.render_sequence(tmp_path / "o", n_frames=2, rig=small_rig())
    (tmp_path / "p" / "images" / "front").mkdir(parents=True)
    (tmp_path / "p" / "images" / "front" / "notes.txt").write_text("mine")
    with pytest.raises(ValueError, match="not rendered frames.*notes.txt"):
        render.render_sequence(tmp_path / "p", n_frames=2, rig=small_rig())
    assert (tmp_path / "p" / "images" / "front" / "notes.txt").exists()


def test_bad_renderer_input(scene):
    ren = render.Renderer(scene, small_rig())
    with pytest.raises(ValueError, match="no camera named 'top'"):
        ren.render(np.eye(4), "top")
    with pytest.raises(ValueError, match="camera id"):
        ren.render(np.eye(4), 7)
    with pytest.raises(ValueError, match="4x4"):
        ren.render_frame(np.eye(3))
    with pytest.raises(ValueError, match="rigid transform"):
        ren.render_frame(2 * np.eye(4))
    with pytest.raises(ValueError, match="non-finite"):
        ren.render_frame(np.full((4, 4), np.nan))
    with pytest.raises(ValueError, match="scene must be"):
        render.Renderer("courtyard", small_rig())
    with pytest.raises(ValueError, match="image size"):
        render.surround_rig(8, 8)
    with pytest.raises(ValueError, match="orthonormal"):
        world.Plane("p", (0, 0, 0), (1, 0, 0), (1, 0, 0), np.zeros((4, 4), np.uint8), 0.1)
    with pytest.raises(ValueError, match="uint8"):
        world.Plane("p", (0, 0, 0), (1, 0, 0), (0, 1, 0), np.zeros((4, 4)), 0.1)
    with pytest.raises(ValueError, match="non-empty sequence of Plane"):
        world.Scene(())


# --------------------------------------------------------------------------- usefulness

def test_sift_matches_consecutive_frames(tmp_path):
    """The rendering serves a feature-based front end: SIFT matches between two
    consecutive default frames of the front camera agree with the true motion."""
    rig = Rig((render.surround_rig().cameras[0],))
    seq = render.render_sequence(tmp_path, n_frames=2, step=world.CourtyardLayout().length / 90,
                                 rig=rig)
    (st,) = render.match_statistics(seq, [("front", 0, "front", 1)])
    assert st.consistent >= 200 and st.consistent >= 0.8 * st.matches, st
