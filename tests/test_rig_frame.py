"""The rig frame is explicit: each loader reports which frame its extrinsics are in
(``Rig.frame``), and ``load_rig(frame=...)`` re-expresses the rig in the body/IMU frame,
a named or numbered camera's frame, or through an explicit 4x4 transform. One test per
format, on the sample files of tests/data/calibration (see tests/test_calibration.py)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import mcgeom
from mcgeom import io as C
from mcgeom.rig import Rig
# the sample files of the loaders' own tests (tests/ is on the path: pyproject.toml)
from test_calibration import COLMAP_NEW, COLMAP_OLD, EQUI, RADTAN, RIG4_JSON, RIG4_YML, STEREO


def _pose(c) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = c.R, c.t
    return T


def _is_identity(c) -> bool:
    return np.allclose(c.R, np.eye(3), atol=1e-12) and np.allclose(c.t, 0, atol=1e-12)


def _same_physical_rig(a: Rig, b: Rig, b_from_a: np.ndarray) -> None:
    """Every camera's cam_from_rig in ``a`` equals (cam_from_rig in ``b``) b_from_a."""
    for ca, cb in zip(a.cameras, b.cameras):
        np.testing.assert_allclose(_pose(ca), _pose(cb) @ b_from_a, atol=1e-12, err_msg=ca.name)


def _random_rigid(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    q = rng.normal(size=4)
    w, x, y, z = q / np.linalg.norm(q)
    T = np.eye(4)
    T[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                 [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                 [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]
    T[:3, 3] = rng.normal(size=3)
    return T


# ---------------------------------------------------------------- Kalibr

def test_kalibr_default_is_the_imu_body_frame_and_cameras_can_be_chosen():
    body = mcgeom.load_rig(RADTAN)
    assert body.frame == "body"
    assert "frame='body'" in repr(body)
    assert mcgeom.load_rig(RADTAN, frame="body") == body
    cam0 = mcgeom.load_rig(RADTAN, frame="camera:cam0")
    assert cam0.frame == "camera:cam0" and _is_identity(cam0.cameras[0])
    # the same as the Kalibr loader's own rig_frame="cam0" (chained T_cn_cnm1)
    old = C.load_kalibr(RADTAN, rig_frame="cam0")
    assert old.frame == "camera:cam0"
    for a, b in zip(cam0.cameras, old.cameras):
        np.testing.assert_allclose(_pose(a), _pose(b), atol=1e-6)  # file agrees to 1e-6
    by_index = mcgeom.load_rig(RADTAN, frame="camera:1")
    assert by_index.frame == "camera:cam1" and _is_identity(by_index.cameras[1])
    _same_physical_rig(body, by_index, _pose(body.cameras[1]))


def test_kalibr_without_imu_has_no_body_frame():
    rig = mcgeom.load_rig(EQUI)
    assert rig.frame == "camera:cam0"
    with pytest.raises(ValueError, match=r"frame='body'.*no body/IMU frame.*camera:cam0"):
        mcgeom.load_rig(EQUI, frame="body")
    cam2 = mcgeom.load_rig(EQUI, frame="camera:cam2")
    assert cam2.frame == "camera:cam2" and _is_identity(cam2.cameras[2])
    with pytest.raises(ValueError, match="not both"):
        mcgeom.load_rig(RADTAN, frame="body", rig_frame="imu")


# ---------------------------------------------------------------- COLMAP

@pytest.mark.parametrize("path,options", [(COLMAP_NEW, {}), (COLMAP_OLD, {"rig_index": 0})])
def test_colmap_frame_is_the_reference_camera(path, options):
    rig = mcgeom.load_rig(path, **options)
    assert rig.frame.startswith("camera:")
    ref = rig.frame[len("camera:"):]
    assert _is_identity(rig.cameras[rig.names.index(ref)])
    with pytest.raises(ValueError, match=r"frame='body'.*no body/IMU frame"):
        mcgeom.load_rig(path, frame="body", **options)
    other = rig.names[-1]
    moved = mcgeom.load_rig(path, frame=f"camera:{other}", **options)
    assert moved.frame == f"camera:{other}" and _is_identity(moved.cameras[-1])
    _same_physical_rig(rig, moved, _pose(rig.cameras[-1]))


# ---------------------------------------------------------------- OpenCV, mcgeom JSON

def test_opencv_stereo_layout_is_camera_one():
    rig = mcgeom.load_rig(STEREO)
    assert rig.frame == "camera:cam1"
    with pytest.raises(ValueError, match="frame='body'"):
        mcgeom.load_rig(STEREO, frame="body")
    assert mcgeom.load_rig(STEREO, frame="camera:cam2").frame == "camera:cam2"


@pytest.mark.parametrize("path", [RIG4_YML, RIG4_JSON])
def test_mcgeom_layouts_report_the_camera_at_the_origin(path):
    rig = mcgeom.load_rig(path)  # rig B: the rig frame is the front camera's
    assert rig.frame == f"camera:{rig.names[0]}"
    T = _random_rigid(3)
    custom = mcgeom.load_rig(path, frame=T)
    assert custom.frame.startswith("custom") and rig.frame in custom.frame
    # X_custom = T X_default: cam_from_custom = cam_from_default T^-1
    _same_physical_rig(rig, custom, T)


def test_mcgeom_json_round_trips_the_frame(tmp_path):
    rig = mcgeom.load_rig(RIG4_JSON, frame=_random_rigid(5))
    assert rig.camera_at_origin() is None
    C.save_mcgeom_json(rig, tmp_path / "r.json")
    back = mcgeom.load_rig(tmp_path / "r.json")
    assert back.frame == rig.frame and back == rig
    # a file without the key, whose frame no camera defines: the body frame
    d = json.loads((tmp_path / "r.json").read_text())
    del d["frame"]
    (tmp_path / "nokey.json").write_text(json.dumps(d))
    assert mcgeom.load_rig(tmp_path / "nokey.json").frame == "body"
    assert mcgeom.load_rig(tmp_path / "nokey.json", frame="body") == rig
    d["frame"] = 3
    (tmp_path / "bad.json").write_text(json.dumps(d))
    with pytest.raises(ValueError, match="'frame' must be a non-empty string"):
        mcgeom.load_rig(tmp_path / "bad.json")


# ---------------------------------------------------------------- bad frame= values

@pytest.mark.parametrize("bad,match", [
    ("imu", "frame must be 'body'"),
    ("camera:", "frame must be 'body'"),
    (3, "frame must be 'body'"),
    ("camera:nosuch", r"frame='camera:nosuch': no camera named or numbered 'nosuch'.*0: 'front'"),
    ("camera:9", "frame='camera:9': no camera named or numbered '9'"),
    (np.eye(3), "frame: a transform must be a 4x4 matrix"),
    (np.diag([1.0, 1.0, 1.0, 2.0]), "frame: the 4x4 transform is not rigid"),
    (np.diag([1.0, 1.0, -1.0, 1.0]), "frame: the 4x4 transform's rotation block"),
    (np.full((4, 4), np.nan), "frame: the 4x4 transform has non-finite"),
])
def test_bad_frame_names_frame(bad, match):
    with pytest.raises(ValueError, match=match):
        mcgeom.load_rig(RIG4_JSON, frame=bad)


def test_motion_in_the_chosen_frame_is_the_conjugated_motion():
    """The same pixels give the same physical motion: in the camera frame it is the
    body-frame motion conjugated by camera-from-body."""
    rng = np.random.default_rng(0)
    body = mcgeom.load_rig(RADTAN)
    cam1 = mcgeom.load_rig(RADTAN, frame="camera:cam1")
    F = _pose(body.cameras[1])                       # cam1_from_body
    px = rng.uniform([100, 100], [600, 400], size=(20, 2))
    ids = np.arange(20) % 2
    r_body = body.ray_pairs(px, px + 3.0, ids)
    r_cam = cam1.ray_pairs(px, px + 3.0, ids)
    # each ray of the camera-frame rig is the body-frame ray mapped by F
    np.testing.assert_allclose(r_cam.dirs1, r_body.dirs1 @ F[:3, :3].T, atol=1e-12)
    np.testing.assert_allclose(r_cam.origins1, r_body.origins1 @ F[:3, :3].T + F[:3, 3], atol=1e-12)


def test_rig_frame_attribute():
    rig = mcgeom.load_rig(RIG4_JSON)
    assert Rig(rig.cameras).frame == "unspecified"
    assert Rig(rig.cameras) == rig  # the label is metadata, not compared
    with pytest.raises(ValueError, match="frame must be a non-empty string"):
        Rig(rig.cameras, frame="")
    assert rig.in_frame(np.eye(3), np.ones(3)).frame == f"custom (X = R X_{rig.frame} + t)"
    assert rig.in_frame(np.eye(3), np.ones(3), frame="body").frame == "body"
