"""Tests of mcgeom.rig: cameras, pixels -> bearings -> rays, frames; and mcgeom's JSON rig
files (mcgeom.io.mcgeom_json)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from mcgeom.io import load_mcgeom_json, rig_from_dict, rig_to_dict, save_mcgeom_json
from mcgeom.rig import Camera, Rig
from mcgeom.types import RayPairs

SETTINGS = settings(max_examples=40, deadline=None)


# --------------------------------------------------------------------------- helpers

def rot(axis, angle):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    S = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(angle) * S + (1 - np.cos(angle)) * S @ S


def random_rotation(gen):
    q = gen.standard_normal(4)
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


K0 = np.array([[600.0, 0.0, 499.5], [0.0, 620.0, 380.0], [0.0, 0.0, 1.0]])
DISTS = {
    "pinhole0": ("pinhole", []),
    "pinhole4": ("pinhole", [-0.12, 0.03, 0.001, -0.0007]),
    "pinhole5": ("pinhole", [-0.25, 0.08, 0.0005, 0.0002, -0.01]),
    "pinhole8": ("pinhole", [0.3, -0.1, 0.001, 0.0005, 0.02, 0.4, -0.05, 0.01]),
    "pinhole12": ("pinhole", [-0.1, 0.02, 0.001, 0.0, 0.0, 0.0, 0.0, 0.0, 0.001, 0.0, -0.001, 0.0]),
    "pinhole14": ("pinhole", [-0.1, 0.02, 0.001, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
                              0.01, -0.005]),
    "fisheye": ("fisheye", [0.05, -0.01, 0.002, -0.0003]),
}


def make_camera(name="cam", model="pinhole", dist=(), R=None, t=(0.1, -0.2, 0.3), K=K0,
                width=1000, height=760):
    return Camera(name=name, K=K, dist=dist, model=model,
                  R=np.eye(3) if R is None else R, t=t, width=width, height=height)


def two_camera_rig():
    return Rig((make_camera("a", R=rot([0, 1, 0], 0.3), t=[0.2, 0.0, 0.1]),
                make_camera("b", "fisheye", DISTS["fisheye"][1], R=rot([1, 1, 0], 2.0),
                            t=[-0.5, 0.1, 0.0])))


def kinv_bearings(K, R, pixels):
    h = np.column_stack([pixels, np.ones(len(pixels))]) @ np.linalg.inv(K).T
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    return h @ R  # R^T h row-wise


# --------------------------------------------------------------------------- Camera

def test_camera_stores_readonly_float64_copies():
    K = K0.copy()
    cam = make_camera(K=K, dist=np.array([[0.1, 0.0, 0.0, 0.0, 0.0]]), t=np.array([[1.0], [2.0], [3.0]]))
    K[0, 0] = 1.0  # the camera owns a copy
    assert cam.K[0, 0] == 600.0
    for a, shape in ((cam.K, (3, 3)), (cam.dist, (5,)), (cam.R, (3, 3)), (cam.t, (3,))):
        assert a.dtype == np.float64 and a.flags.c_contiguous and not a.flags.writeable
        assert a.shape == shape
    with pytest.raises(ValueError):
        cam.K[0, 0] = 3.0
    assert cam.dist.shape == (5,) and cam.width == 1000 and isinstance(cam.width, int)


def test_camera_none_dist_means_no_distortion():
    cam = make_camera(dist=None)
    assert cam.dist.shape == (0,) and not cam.has_distortion


def test_centre_is_minus_Rt_t():
    R = rot([1, 2, 3], 0.7)
    t = np.array([0.3, -1.0, 2.0])
    cam = make_camera(R=R, t=t)
    np.testing.assert_allclose(cam.centre, -R.T @ t, atol=1e-15)
    np.testing.assert_allclose(R @ cam.centre + t, 0.0, atol=1e-15)


def test_camera_value_semantics():
    a, b = make_camera(), make_camera()
    assert a == b and hash(a) == hash(b)
    assert a != make_camera(t=(0.1, -0.2, 0.31))
    assert len({a, b}) == 1


BAD_CAMERAS = [
    (dict(name=""), "non-empty"),
    (dict(model="kannala"), "unknown model 'kannala'"),
    (dict(K=np.eye(2)), "K must have shape (3, 3)"),
    (dict(K=np.array([[600, 0, 500], [0, 600, np.nan], [0, 0, 1.0]])), "K has non-finite"),
    (dict(K=np.array([[600, 0, 500], [1, 600, 400], [0, 0, 1.0]])), "upper triangular"),
    (dict(K=np.array([[-600, 0, 500], [0, 600, 400], [0, 0, 1.0]])), "positive focal"),
    (dict(K=np.array([[600, 0, 500], [0, 0, 400], [0, 0, 1.0]])), "positive focal"),
    (dict(K=np.array([[600, 0, 500], [0, 600, 400], [0, 0, 2.0]])), "K[2,2] must be 1"),
    (dict(K=[["a", "b", "c"]] * 3), "numeric"),
    (dict(dist=[0.1, 0.2, 0.3]), "pinhole camera needs (0, 4, 5, 8, 12, 14)"),
    (dict(model="fisheye", dist=[0.1, 0.0, 0.0, 0.0, 0.0]), "fisheye camera needs (4,)"),
    (dict(model="fisheye", dist=[]), "fisheye camera needs (4,)"),
    (dict(dist=[0.1, np.inf, 0.0, 0.0]), "dist has non-finite"),
    (dict(dist=np.zeros((2, 4))), "dist must be a 1-D array"),
    (dict(R=np.diag([1.0, 1.0, -1.0])), "extrinsic R is not a rotation (det = -1.0)"),
    (dict(R=np.diag([1.0, 1.0, 1.1])), "extrinsic R is not a rotation (not orthonormal"),
    (dict(R=np.full((3, 3), np.nan)), "extrinsic R is not a rotation (non-finite"),
    (dict(R=np.eye(4)), "extrinsic R must have shape (3, 3)"),
    (dict(t=[1.0, 2.0]), "extrinsic t must have 3 elements"),
    (dict(t=[1.0, np.nan, 2.0]), "extrinsic t has non-finite"),
    (dict(width=0), "width must be positive"),
    (dict(height=-5), "height must be positive"),
    (dict(width=640.5), "width must be an integer"),
    (dict(height=True), "height must be an integer"),
]


@pytest.mark.parametrize("kwargs, message", BAD_CAMERAS)
def test_bad_camera_raises_value_error_naming_problem(kwargs, message):
    args = dict(name="cam2")
    args.update(kwargs)
    with pytest.raises(ValueError) as err:
        make_camera(**args)
    assert message in str(err.value)
    if args["name"]:
        assert "camera 'cam2'" in str(err.value)


def test_rotation_message_matches_documented_example():
    with pytest.raises(ValueError, match=r"^camera 'cam2': extrinsic R is not a rotation \(det = -1\.0\)$"):
        make_camera("cam2", R=-np.eye(3))


# --------------------------------------------------------------------------- bearings

@SETTINGS
@given(st.integers(0, 2**32 - 1))
def test_bearings_equal_Kinv_without_distortion(seed):
    gen = np.random.default_rng(seed)
    f = gen.uniform(200, 2000)
    K = np.array([[f, gen.uniform(-2, 2), gen.uniform(300, 700)],
                  [0.0, f * gen.uniform(0.9, 1.1), gen.uniform(200, 500)], [0.0, 0.0, 1.0]])
    R = random_rotation(gen)
    cam = make_camera(K=K, R=R, t=gen.normal(size=3))
    px = gen.uniform(-200, 1200, size=(50, 2))  # off-image pixels are fine too
    d = cam.pixels_to_bearings(px)
    assert d.shape == (50, 3) and d.dtype == np.float64
    np.testing.assert_allclose(d, kinv_bearings(K, R, px), atol=1e-12, rtol=0)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-15)


@pytest.mark.parametrize("kind", sorted(DISTS))
def test_project_then_bearings_round_trip(kind):
    model, dist = DISTS[kind]
    gen = np.random.default_rng(7)
    R, t = rot([0.2, 1, -0.3], 0.8), np.array([0.3, -0.1, 0.5])
    cam = make_camera(model=model, dist=dist, R=R, t=t,
                      K=np.array([[500.0, 0.8, 499.5], [0.0, 505.0, 379.5], [0.0, 0.0, 1.0]]))
    # points in front of the camera within ~45 deg of the axis, in the rig frame
    X_cam = np.column_stack([gen.uniform(-0.8, 0.8, (300, 2)), np.ones(300)]) * gen.uniform(1, 30, (300, 1))
    X_rig = (X_cam - t) @ R
    px, visible = cam.project(X_rig)
    assert visible.sum() > 150
    d = cam.pixels_to_bearings(px[visible])
    truth = X_rig[visible] - cam.centre
    truth /= np.linalg.norm(truth, axis=1, keepdims=True)
    np.testing.assert_allclose(d, truth, atol=1e-10, rtol=0)


def test_project_matches_opencv_with_real_K():
    import cv2
    model, dist = DISTS["pinhole5"]
    R, t = rot([1, 0, 0], 0.2), np.array([0.1, 0.2, 0.3])
    cam = make_camera(dist=dist, R=R, t=t)
    P = np.array([[0.1, 0.2, 3.0], [-0.4, 0.1, 5.0], [0.3, -0.3, 2.0]])
    ref, _ = cv2.projectPoints(P.reshape(-1, 1, 3), cv2.Rodrigues(R)[0], t, K0, np.asarray(dist))
    np.testing.assert_allclose(cam.project(P)[0], ref.reshape(-1, 2), atol=1e-9)


def test_fisheye_bearings_beyond_90_degrees():
    # OpenCV's fisheye undistortion cannot represent rays at >= 90 deg; we re-solve them.
    k = np.array([0.02, -0.004, 0.0005, -0.00003])
    cam = make_camera(model="fisheye", dist=k, t=(0.0, 0.0, 0.0))
    theta = np.array([0.0, 0.3, 1.2, 1.5, 1.6, 1.8, 2.0])
    phi = np.array([0.0, 1.0, 2.0, -1.0, 0.4, 3.0, -2.5])
    t2 = theta**2
    theta_d = theta * (1 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))))
    xy = theta_d[:, None] * np.column_stack([np.cos(phi), np.sin(phi)])
    px = np.column_stack([K0[0, 0] * xy[:, 0] + K0[0, 2], K0[1, 1] * xy[:, 1] + K0[1, 2]])
    d = cam.pixels_to_bearings(px)
    truth = np.column_stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])
    np.testing.assert_allclose(d, truth, atol=1e-10)


def test_fisheye_uninvertible_pixel_raises():
    # theta_d(theta) = theta (1 - 0.3 theta^2) peaks at theta_d ~ 0.61: beyond it, no ray
    cam = make_camera("fe", model="fisheye", dist=[-0.3, 0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="camera 'fe'.*fisheye distortion can be inverted"):
        cam.pixels_to_bearings([[K0[0, 2] + 0.9 * K0[0, 0], K0[1, 2]]])


def test_project_never_raises_past_the_fisheye_peak():
    # theta_d = theta (1 - 0.6 theta^2) peaks at theta = 0.745 rad (theta_d = 0.497):
    # at 1.2 rad the pixel maps back to another ray; at 1.5 rad theta_d = -0.525, whose
    # magnitude exceeds the peak, so the pixel has no ray at all (must not raise here).
    cam = make_camera(model="fisheye", dist=[-0.6, 0.0, 0.0, 0.0], t=(0.0, 0.0, 0.0),
                      K=np.array([[200.0, 0, 499.5], [0, 200.0, 379.5], [0, 0, 1.0]]))
    theta = np.array([0.2, 0.6, 1.2, 1.5])
    P = np.column_stack([np.sin(theta), np.zeros(4), np.cos(theta)])
    px, vis = cam.project(P)
    assert vis.tolist() == [True, True, False, False]
    assert cam.in_image(px).all()  # the folded ones do land inside the image


def test_project_visibility():
    cam = make_camera(t=(0.0, 0.0, 0.0))  # camera frame = rig frame
    P = np.array([[0.0, 0.0, 5.0],      # centre: visible
                  [0.0, 0.0, -5.0],     # behind
                  [0.0, 0.0, 0.0],      # at the centre
                  [10.0, 0.0, 1.0],     # in front, outside the image
                  [-0.8, -0.6, 1.0]])   # (u, v) = (19.5, 8): inside
    px, vis = cam.project(P)
    assert vis.tolist() == [True, False, False, False, True]
    assert np.all(np.isnan(px[1:3])) and np.all(np.isfinite(px[[0, 3, 4]]))
    np.testing.assert_allclose(px[0], K0[:2, 2])
    # image area is [-0.5, w - 0.5) x [-0.5, h - 0.5)
    assert cam.in_image([[-0.5, -0.5], [999.49, 759.49]]).all()
    assert not cam.in_image([[-0.51, 0.0], [0.0, 759.5]]).any()


def test_project_rejects_distortion_fold_over():
    # k1 = -0.5: r_d = r (1 - 0.5 r^2) folds back beyond r = 0.816; a point at r = 1.4
    # lands near the image centre but is not really seen there.
    cam = make_camera(dist=[-0.5, 0.0, 0.0, 0.0], t=(0.0, 0.0, 0.0))
    px, vis = cam.project(np.array([[1.4, 0.0, 1.0], [0.3, 0.0, 1.0]]))
    assert cam.in_image(px[:1]).all()
    assert vis.tolist() == [False, True]


def test_empty_inputs():
    cam = make_camera(dist=DISTS["pinhole5"][1])
    assert cam.pixels_to_bearings(np.zeros((0, 2))).shape == (0, 3)
    px, vis = cam.project(np.zeros((0, 3)))
    assert px.shape == (0, 2) and vis.shape == (0,)
    o, d = two_camera_rig().rays(np.zeros(0, int), np.zeros((0, 2)))
    assert o.shape == d.shape == (0, 3)


@pytest.mark.parametrize("pixels, message", [
    (np.zeros((4, 3)), "shape (N, 2)"),
    (np.zeros(2), "shape (N, 2)"),
    (np.array([[1.0, np.nan]]), "non-finite"),
    (np.array([[1.0, 2.0], [np.inf, 0.0]]), "non-finite row(s) (first: row 1)"),
    (np.array([["a", "b"]]), "numeric"),
])
def test_bad_pixels(pixels, message):
    cam = make_camera("c0")
    with pytest.raises(ValueError) as err:
        cam.pixels_to_bearings(pixels)
    assert message in str(err.value) and "camera 'c0'" in str(err.value)
    with pytest.raises(ValueError, match="pixels"):
        two_camera_rig().rays(np.zeros(len(np.atleast_2d(pixels)), int), pixels)


@pytest.mark.parametrize("points, message", [
    (np.zeros((4, 2)), "shape (N, 3)"),
    (np.array([[1.0, np.nan, 2.0]]), "non-finite"),
])
def test_bad_points(points, message):
    with pytest.raises(ValueError, match="points_rig") as err:
        make_camera().project(points)
    assert message in str(err.value)


# --------------------------------------------------------------------------- Rig

def test_rig_basics():
    rig = two_camera_rig()
    assert len(rig) == 2 and rig.names == ("a", "b")
    np.testing.assert_allclose(rig.centres, [c.centre for c in rig.cameras])
    assert rig.centres.shape == (2, 3) and not rig.centres.flags.writeable
    assert rig.camera(1) is rig.cameras[1] and rig.camera(np.int64(0)) is rig.cameras[0]
    assert Rig([*rig.cameras]) == rig and hash(Rig(rig.cameras)) == hash(rig)


@pytest.mark.parametrize("cameras, message", [
    ((), "at least one camera"),
    ([], "at least one camera"),
    ((make_camera("x"), make_camera("x")), "unique; repeated: 'x'"),
    ((make_camera("x"), "y"), "cameras[1] is a str"),
    (make_camera("x"), "sequence of Camera"),
])
def test_bad_rig(cameras, message):
    with pytest.raises(ValueError) as err:
        Rig(cameras)
    assert message in str(err.value)


def test_unknown_camera_id_message():
    cams = tuple(make_camera(f"c{i}") for i in range(6))
    rig = Rig(cams)
    with pytest.raises(ValueError, match=r"^unknown camera id 7: rig has cameras 0\.\.5$"):
        rig.camera(7)
    for bad in (-1, 6):
        with pytest.raises(ValueError, match="unknown camera id"):
            rig.camera(bad)
    for bad in ("c0", 1.0, True, None):
        with pytest.raises(ValueError, match="camera id must be an integer"):
            rig.camera(bad)


def test_rays_are_vectorised_per_camera():
    rig = two_camera_rig()
    gen = np.random.default_rng(3)
    ids = gen.integers(0, 2, 40)
    px = gen.uniform(0, 700, (40, 2))
    o, d = rig.rays(ids, px)
    for k in range(40):
        np.testing.assert_array_equal(o[k], rig.centres[ids[k]])
        np.testing.assert_allclose(d[k], rig.cameras[ids[k]].pixels_to_bearings(px[k:k + 1])[0],
                                   atol=1e-15)
    o1, d1 = rig.rays(1, px)  # one id for all
    np.testing.assert_allclose(d1, rig.cameras[1].pixels_to_bearings(px), atol=1e-15)
    o2, d2 = rig.rays(ids.astype(float), px)  # integral floats are accepted
    np.testing.assert_array_equal(d2, d)


@pytest.mark.parametrize("ids, message", [
    (np.zeros(3, int), "cam_ids has 3 ids but there are 4 pixels"),
    (np.zeros((4, 1), int), "cam_ids must have shape (N,)"),
    (np.array([0, 1, 2, 0]), "unknown camera id 2: rig has cameras 0..1"),
    (np.array([0, -1, 0, 0]), "unknown camera id -1"),
    (np.array([0.0, 0.5, 0.0, 0.0]), "integer camera ids"),
    (np.array(["a"] * 4), "integer camera ids"),
    (7, "unknown camera id 7"),
])
def test_bad_camera_ids(ids, message):
    with pytest.raises(ValueError) as err:
        two_camera_rig().rays(ids, np.zeros((4, 2)))
    assert message in str(err.value)


def test_ray_pairs():
    rig = two_camera_rig()
    gen = np.random.default_rng(5)
    px1, px2 = gen.uniform(0, 700, (10, 2)), gen.uniform(0, 700, (10, 2))
    c1, c2 = gen.integers(0, 2, 10), gen.integers(0, 2, 10)
    rp = rig.ray_pairs(px1, px2, c1, c2)
    assert isinstance(rp, RayPairs) and len(rp) == 10
    o1, d1 = rig.rays(c1, px1)
    o2, d2 = rig.rays(c2, px2)
    for a, b in ((rp.origins1, o1), (rp.dirs1, d1), (rp.origins2, o2), (rp.dirs2, d2)):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(rp.cam1, c1)
    np.testing.assert_array_equal(rp.cam2, c2)
    same = rig.ray_pairs(px1, px2, c1)  # cam2 defaults to cam1
    np.testing.assert_array_equal(same.cam2, c1)
    assert same.is_locally_central()
    with pytest.raises(ValueError, match="pixels2 has 9 rows but pixels1 has 10"):
        rig.ray_pairs(px1, px2[:9], c1, c2)
    with pytest.raises(ValueError, match="cam2 has 9 ids"):
        rig.ray_pairs(px1, px2, c1, c2[:9])
    with pytest.raises(ValueError, match="pixels1 has 1 non-finite"):
        rig.ray_pairs(np.where(np.arange(10)[:, None] == 3, np.nan, px1), px2, c1, c2)


@SETTINGS
@given(st.integers(0, 2**32 - 1))
def test_in_frame_preserves_ray_geometry(seed):
    gen = np.random.default_rng(seed)
    rig = two_camera_rig()
    R, t = random_rotation(gen), gen.normal(size=3) * 2
    moved = rig.in_frame(R, t)
    ids = gen.integers(0, 2, 30)
    px = gen.uniform(0, 700, (30, 2))
    o, d = rig.rays(ids, px)
    o_new, d_new = moved.rays(ids, px)
    # same physical rays: origins and directions mapped by X_new = R X_old + t
    np.testing.assert_allclose(o_new, o @ R.T + t, atol=1e-12)
    np.testing.assert_allclose(d_new, d @ R.T, atol=1e-12)
    # and the same pixels for the same physical points
    P_old = o + gen.uniform(1, 10, (30, 1)) * d
    for i in range(2):
        np.testing.assert_allclose(moved.camera(i).project(P_old @ R.T + t)[0],
                                   rig.camera(i).project(P_old)[0], atol=1e-7)
    # the inverse change of frame gives the rig back
    back = moved.in_frame(R.T, -R.T @ t)
    for a, b in zip(back.cameras, rig.cameras):
        np.testing.assert_allclose(a.R, b.R, atol=1e-12)
        np.testing.assert_allclose(a.t, b.t, atol=1e-12)


def test_in_frame_rejects_bad_transform():
    rig = two_camera_rig()
    with pytest.raises(ValueError, match=r"in_frame: R is not a rotation \(det = -1\.0\)"):
        rig.in_frame(-np.eye(3), np.zeros(3))
    with pytest.raises(ValueError, match="in_frame: t must have 3 elements"):
        rig.in_frame(np.eye(3), np.zeros(4))


# --------------------------------------------------------------------------- JSON

@SETTINGS
@given(st.integers(0, 2**32 - 1))
def test_json_round_trip_is_exact(seed):
    gen = np.random.default_rng(seed)
    cams = []
    for i, kind in enumerate(sorted(DISTS)):
        model, dist = DISTS[kind]
        cams.append(make_camera(f"c{i}", model, np.asarray(dist) * gen.uniform(0.5, 1.5),
                                R=random_rotation(gen), t=gen.normal(size=3),
                                K=np.array([[gen.uniform(100, 900), gen.uniform(-1, 1), 400.1],
                                            [0, gen.uniform(100, 900), 300.2], [0, 0, 1.0]])))
    rig = Rig(tuple(cams))
    d = rig_to_dict(rig)
    assert rig_from_dict(json.loads(json.dumps(d))) == rig


def test_json_file_round_trip_and_format(tmp_path):
    rig = two_camera_rig()
    path = tmp_path / "rig.json"
    save_mcgeom_json(rig, path)
    assert load_mcgeom_json(path) == rig
    assert load_mcgeom_json(str(path)) == rig
    doc = json.loads(path.read_text())
    assert doc["format"] == "mcgeom-rig" and doc["version"] == 1
    assert set(doc["cameras"][0]) == {"name", "model", "width", "height", "K", "dist",
                                      "R_cam_from_rig", "t_cam_from_rig"}
    assert np.asarray(doc["cameras"][0]["K"]).shape == (3, 3)
    assert len(doc["cameras"][1]["dist"]) == 4


def test_json_ignores_extra_keys():
    d = rig_to_dict(two_camera_rig())
    d["comment"] = "calibrated on Tuesday"
    d["cameras"][0]["serial"] = 1234
    assert rig_from_dict(d) == two_camera_rig()


def _with(d, path, value=None, delete=False):
    d = json.loads(json.dumps(d))
    node = d
    for key in path[:-1]:
        node = node[key]
    if delete:
        del node[path[-1]]
    else:
        node[path[-1]] = value
    return d


GOOD = rig_to_dict(two_camera_rig())
BAD_DICTS = [
    ([], "must be a JSON object"),
    (_with(GOOD, ["format"], delete=True), "missing key 'format'"),
    (_with(GOOD, ["format"], "colmap"), "format is 'colmap', expected 'mcgeom-rig'"),
    (_with(GOOD, ["version"], 2), "unsupported version 2"),
    (_with(GOOD, ["version"], True), "unsupported version True"),
    (_with(GOOD, ["cameras"], delete=True), "missing key 'cameras'"),
    (_with(GOOD, ["cameras"], {}), "'cameras' must be a list"),
    (_with(GOOD, ["cameras"], []), "at least one camera"),
    (_with(GOOD, ["cameras", 1], 3), "cameras[1] must be a JSON object"),
    (_with(GOOD, ["cameras", 1, "K"], delete=True), "cameras[1]: missing key(s) 'K'"),
    (_with(GOOD, ["cameras", 0, "K"], [[1, 2], [3]]), "cameras[0]: camera 'a': K must be a numeric array"),
    (_with(GOOD, ["cameras", 0, "K"], [[1, 0, 0], [0, 1, 0]]), "K must have shape (3, 3)"),
    (_with(GOOD, ["cameras", 0, "dist"], ["0.1", "0", "0", "0"]), "dist must be a numeric array"),
    (_with(GOOD, ["cameras", 1, "name"], "a"), "repeated: 'a'"),
    (_with(GOOD, ["cameras", 0, "R_cam_from_rig"], [[1, 0, 0], [0, 1, 0], [0, 0, -1]]),
     "cameras[0]: camera 'a': extrinsic R is not a rotation (det = -1.0)"),
    (_with(GOOD, ["cameras", 0, "width"], "1000"), "width must be an integer"),
    (_with(GOOD, ["cameras", 0, "model"], None), "unknown model None"),
]


@pytest.mark.parametrize("doc, message", BAD_DICTS)
def test_bad_rig_dicts(doc, message):
    with pytest.raises(ValueError) as err:
        rig_from_dict(doc)
    assert message in str(err.value)


@pytest.mark.parametrize("content, message", [
    (b"", "not valid JSON"),
    (json.dumps(GOOD).encode()[:200], "not valid JSON"),  # truncated
    (b"{'format': 'mcgeom-rig'}", "not valid JSON"),
    (b"\xff\xfe\x00garbage", "not UTF-8"),
    (json.dumps(_with(GOOD, ["format"], "other")).encode(), "format is 'other'"),
])
def test_bad_rig_files(tmp_path, content, message):
    path = tmp_path / "bad.json"
    path.write_bytes(content)
    with pytest.raises(ValueError) as err:
        load_mcgeom_json(path)
    assert message in str(err.value) and "bad.json" in str(err.value)


def test_missing_rig_file_is_an_os_error(tmp_path):
    with pytest.raises(FileNotFoundError):
        load_mcgeom_json(tmp_path / "nope.json")


def test_public_accessors_of_the_pixel_noise_model_and_the_prechecked_fast_path():
    """``intrinsics``/``rotations`` stack the cameras' K and R (read-only), and
    ``ray_pairs_prechecked`` gives what ``ray_pairs`` gives for checked input."""
    from mcgeom import synth
    rng = np.random.default_rng(5)
    rig = synth.generic_rig(3, rng)
    np.testing.assert_array_equal(rig.intrinsics, np.stack([c.K for c in rig.cameras]))
    np.testing.assert_array_equal(rig.rotations, np.stack([c.R for c in rig.cameras]))
    assert not rig.intrinsics.flags.writeable and not rig.rotations.flags.writeable
    p = synth.make_problem(rig, synth.random_rotation(rng, 0.2), np.array([0.2, 0.0, 0.1]),
                           40, rng, cross_fraction=0.3)
    px1, px2 = np.asarray(p.pixels1, np.float64), np.asarray(p.pixels2, np.float64)
    c1, c2 = np.asarray(p.cam1, np.int64), np.asarray(p.cam2, np.int64)
    a = rig.ray_pairs(px1, px2, c1, c2)
    b = rig.ray_pairs_prechecked(px1, px2, c1, c2)
    for f in ("origins1", "dirs1", "origins2", "dirs2", "cam1", "cam2"):
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f))
