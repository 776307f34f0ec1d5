"""Tests of mcgeom.io: rig loaders for mcgeom JSON, OpenCV FileStorage, Kalibr, COLMAP.

The sample files under tests/data/calibration/ describe two physical rigs:

* rig A, a stereo head with an IMU: kalibr/camchain-imucam-radtan.yaml (Kalibr, radtan,
  old PyYAML flow style), opencv/stereo_calib.yml and opencv/stereo_calib/{intrinsics,
  extrinsics}.yml (the layout of OpenCV's stereo_calib sample);
* rig B, four cameras around a car (rig frame = front camera): colmap/rig_config_legacy.json
  (rig_bundle_adjuster format, rig 0; rig 1 is another rig), colmap/rig_config.json (COLMAP
  3.12+ format) with colmap/cameras.txt and colmap/images.txt, opencv/rig4.yml (mcgeom's
  multi-camera FileStorage layout) and mcgeom/rig4.json;

plus kalibr/camchain-equidistant.yaml, a 3-camera fisheye chain (PyYAML >= 5.1 block style).
Expected values below are copied from the files or worked out by hand from them.
"""

from __future__ import annotations

import json
import math
import shutil
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from mcgeom import io as C
from mcgeom.io._safe_yaml import MAX_DEPTH, load_yaml
from mcgeom.rig import Camera, Rig

DATA = Path(__file__).parent / "data" / "calibration"
RADTAN = DATA / "kalibr" / "camchain-imucam-radtan.yaml"
EQUI = DATA / "kalibr" / "camchain-equidistant.yaml"
STEREO = DATA / "opencv" / "stereo_calib.yml"
STEREO_INTR = DATA / "opencv" / "stereo_calib" / "intrinsics.yml"
STEREO_EXTR = DATA / "opencv" / "stereo_calib" / "extrinsics.yml"
RIG4_YML = DATA / "opencv" / "rig4.yml"
RIG4_JSON = DATA / "mcgeom" / "rig4.json"
COLMAP_NEW = DATA / "colmap" / "rig_config.json"
COLMAP_OLD = DATA / "colmap" / "rig_config_legacy.json"
COLMAP_CAMS = DATA / "colmap" / "cameras.txt"
COLMAP_IMGS = DATA / "colmap" / "images.txt"

# From camchain-imucam-radtan.yaml (cam1.T_cn_cnm1, cam0.T_cam_imu)
T_C1_C0 = np.array([
    [0.999801981909377, -0.000973989309466651, 0.019875822370579044, -0.11006954605490935],
    [0.0010134941654512918, 0.999997530946501, -0.0019776072609217826, 0.0002891265570733347],
    [-0.01987384712777981, 0.0019973596889141026, 0.9998005004772775, 0.001335560968351994],
    [0.0, 0.0, 0.0, 1.0]])
T_C0_IMU = np.array([
    [-0.014104310536892399, -0.9998914843355765, 0.00425299629395241, -0.0216401454975],
    [-0.002851923471874001, -0.004213174031778666, -0.9999870577647936, -0.064676986768],
    [0.9998964621183483, -0.014116257215544522, -0.002792190078613384, 0.00981073058949],
    [0.0, 0.0, 0.0, 1.0]])
# cam1's centre in cam0's frame, as designed when the file was written
C1_IN_C0 = np.array([0.110074, -0.000399, 0.000853])


# --------------------------------------------------------------------------- helpers

def variant(tmp_path: Path, src: Path, old: str, new: str, name: str | None = None) -> Path:
    """A copy of a sample file with one exact, unique substring replaced."""
    text = src.read_text()
    assert text.count(old) == 1, f"{old!r} occurs {text.count(old)} times in {src.name}"
    out = tmp_path / (name or src.name)
    out.write_text(text.replace(old, new))
    return out


def assert_same_rig(a: Rig, b: Rig, tol: float = 1e-12, names: bool = True) -> None:
    """Same cameras up to ``tol``; distortion vectors compared after zero padding."""
    assert len(a) == len(b)
    for ca, cb in zip(a.cameras, b.cameras):
        if names:
            assert ca.name == cb.name
        assert (ca.model, ca.width, ca.height) == (cb.model, cb.width, cb.height), ca.name
        n = max(ca.dist.size, cb.dist.size)
        da, db = np.zeros(n), np.zeros(n)
        da[: ca.dist.size], db[: cb.dist.size] = ca.dist, cb.dist
        for what, x, y in (("K", ca.K, cb.K), ("dist", da, db), ("R", ca.R, cb.R), ("t", ca.t, cb.t)):
            np.testing.assert_allclose(x, y, rtol=0, atol=tol, err_msg=f"{ca.name}: {what}")


def rotation_from_quaternion_wxyz(q) -> np.ndarray:
    """Independent route (axis-angle + cv2.Rodrigues) from a (w, x, y, z) quaternion."""
    q = np.asarray(q, float) / np.linalg.norm(q)
    angle = 2 * math.atan2(np.linalg.norm(q[1:]), q[0])
    axis = q[1:] / np.linalg.norm(q[1:]) if np.linalg.norm(q[1:]) > 0 else np.zeros(3)
    return cv2.Rodrigues(axis * angle)[0]


def principal_ray(rig: Rig, i: int) -> tuple[np.ndarray, np.ndarray]:
    """Rig-frame ray of camera i's principal point (undistortion leaves it in place)."""
    K = rig.cameras[i].K
    o, d = rig.rays([i], [[K[0, 2], K[1, 2]]])
    return o[0], d[0]


def raises(match: str, fn, *args, **kwargs) -> str:
    with pytest.raises(ValueError) as info:
        fn(*args, **kwargs)
    msg = str(info.value)
    for part in match.split("|"):
        assert part in msg, f"{part!r} not in {msg!r}"
    return msg


# --------------------------------------------------------------------------- Kalibr

def test_kalibr_radtan_cam0_frame():
    rig = C.load_kalibr(RADTAN, rig_frame="cam0")
    assert rig.names == ("cam0", "cam1")
    c0, c1 = rig.cameras
    np.testing.assert_array_equal(c0.K, [[458.654, 0, 367.215], [0, 457.296, 248.375], [0, 0, 1]])
    np.testing.assert_array_equal(c1.K, [[457.587, 0, 379.999], [0, 456.134, 255.238], [0, 0, 1]])
    # radtan [k1, k2, r1, r2] == OpenCV (k1, k2, p1, p2)
    np.testing.assert_array_equal(c0.dist, [-0.28340811217029355, 0.07395907389290132,
                                            0.00019359502856909603, 1.7618711454538528e-05])
    np.testing.assert_array_equal(c1.dist, [-0.28368365, 0.07451284, -0.00010473, -3.555907e-05])
    assert (c0.model, c0.width, c0.height) == ("pinhole", 752, 480)
    np.testing.assert_array_equal(c0.R, np.eye(3))
    np.testing.assert_array_equal(c0.t, np.zeros(3))
    # X_c1 = T_c1_c0 X_c0 and the rig frame is cam0: cam_from_rig of cam1 is T_cn_cnm1
    np.testing.assert_array_equal(c1.R, T_C1_C0[:3, :3])
    np.testing.assert_array_equal(c1.t, T_C1_C0[:3, 3])
    np.testing.assert_allclose(rig.centres[1], C1_IN_C0, atol=1e-12)


def test_kalibr_default_frame_is_imu_when_every_camera_has_T_cam_imu():
    rig = C.load_rig(RADTAN)
    c0 = rig.cameras[0]
    np.testing.assert_array_equal(c0.R, T_C0_IMU[:3, :3])
    np.testing.assert_array_equal(c0.t, T_C0_IMU[:3, 3])
    origin, d = principal_ray(rig, 0)
    # the optical axis of cam0 in the IMU frame is the third row of R_c0_imu
    np.testing.assert_allclose(d, T_C0_IMU[2, :3], atol=1e-12)
    np.testing.assert_allclose(origin, -T_C0_IMU[:3, :3].T @ T_C0_IMU[:3, 3], atol=1e-15)
    # cam1 from the file's T_cam_imu equals the chain T_c1_c0 T_c0_imu (the file is consistent)
    chained = T_C1_C0 @ T_C0_IMU
    np.testing.assert_allclose(rig.cameras[1].R, chained[:3, :3], atol=1e-15)
    np.testing.assert_allclose(rig.cameras[1].t, chained[:3, 3], atol=1e-15)
    assert_same_rig(C.load_kalibr(RADTAN, rig_frame="imu"), rig, tol=0)


def test_kalibr_imu_and_cam0_frames_describe_one_rig():
    imu = C.load_kalibr(RADTAN, rig_frame="imu")
    cam0 = C.load_kalibr(RADTAN, rig_frame="cam0")
    # re-express the IMU-frame rig in cam0's frame: X_c0 = T_c0_imu X_imu
    assert_same_rig(imu.in_frame(T_C0_IMU[:3, :3], T_C0_IMU[:3, 3]), cam0)


def test_kalibr_equidistant_chain_of_three():
    rig = C.load_rig(EQUI)  # no T_cam_imu: rig frame = cam0
    assert rig.names == ("cam0", "cam1", "cam2")
    assert all(c.model == "fisheye" and (c.width, c.height) == (1024, 1024) for c in rig.cameras)
    np.testing.assert_array_equal(rig.cameras[2].dist, [0.012, -0.011, 0.0061, -0.0017])
    np.testing.assert_array_equal(rig.cameras[2].K, [[381.5, 0, 512.0], [0, 381.25, 511.75], [0, 0, 1]])
    text = EQUI.read_text()
    # the two T_cn_cnm1 of the file, read back by hand from its block-style rows
    blocks = text.split("T_cn_cnm1:\n")[1:]
    T = []
    for b in blocks:
        nums = [float(line.split("- ")[-1]) for line in b.splitlines()[:16]]
        T.append(np.array(nums).reshape(4, 4))
    T_c1_c0, T_c2_c1 = T
    T_c2_c0 = T_c2_c1 @ T_c1_c0  # X_c2 = T_c2_c1 X_c1 = T_c2_c1 T_c1_c0 X_c0
    np.testing.assert_allclose(rig.cameras[1].R, T_c1_c0[:3, :3], atol=0)
    np.testing.assert_allclose(rig.cameras[2].R, T_c2_c0[:3, :3], atol=1e-15)
    np.testing.assert_allclose(rig.cameras[2].t, T_c2_c0[:3, 3], atol=1e-15)
    # designed: cam1 centre (0.1008, 0.0002, -0.0011) in cam0; cam2 centre (0.05, 0, -0.05) in
    # cam1 and cam2 looking along cam1's +x
    np.testing.assert_allclose(rig.centres[1], [0.1008, 0.0002, -0.0011], atol=1e-12)
    np.testing.assert_allclose(rig.centres[2], rig.centres[1] + T_c1_c0[:3, :3].T @ [0.05, 0, -0.05],
                               atol=1e-12)
    _, d = principal_ray(rig, 2)
    np.testing.assert_allclose(d, T_c1_c0[0, :3], atol=1e-12)  # cam1's x axis in cam0 frame


def test_kalibr_yaml_is_pyyaml_safe_load():
    # the restricted loader gives the same data as PyYAML's (Kalibr's own reader)
    import yaml
    samples = [RADTAN.read_text(), EQUI.read_text(),
               "a: [it's, 'b''c', \"d]\"]  # comment\nb:\n- - 1\n  - 2\n- [3,\n   4]\nc: ~\n",
               "---\n- k: v\n  w: [1.0e-05, -.inf]\n- - x\n...\n"]
    for text in samples:
        assert load_yaml(text, "sample") == yaml.safe_load(text)
    # ... but for numbers with an exponent and no '.', which YAML 1.1 reads as strings
    assert load_yaml("a: [1e-05, -2E+3, .5e1]\n", "sample") == {"a": [1e-05, -2000.0, 5.0]}


@pytest.mark.parametrize("text,line,message", [
    ("cam0: &a [1, 2]\ncam1: *a\n", 1, "anchors (&a) are not allowed"),
    ("cam0: [1, 2]\ncam1: *a\n", 2, "aliases (*a) are not allowed"),
    # billion laughs: refused at the first anchor, before anything is expanded
    ("a: &a [x, x, x, x, x, x, x, x, x]\nb: &b [*a, *a, *a, *a, *a, *a, *a, *a, *a]\n"
     "c: &c [*b, *b, *b, *b, *b, *b, *b, *b, *b]\ncam0: [*c, *c, *c, *c, *c, *c, *c, *c, *c]\n",
     1, "anchors (&a) are not allowed"),
    ("cam0: !!python/object/apply:os.system ['echo pwned']\n", 1,
     "tags are not allowed (tag:yaml.org,2002:python/object/apply:os.system)"),
    ("cam0:\n  camera_model: !!python/name:builtins.print ''\n", 2, "tags are not allowed"),
    ("cam0: !!str pinhole\n", 1, "tags are not allowed"),
    ("cam0: " + "[" * (MAX_DEPTH + 1) + "]" * (MAX_DEPTH + 1) + "\n", 1,
     f"nesting deeper than {MAX_DEPTH} levels"),
    ("cam0:\n" + "  " + "- " * (MAX_DEPTH + 1) + "1\n", 2, f"nesting deeper than {MAX_DEPTH} levels"),
    ("cam0: {a: 1, a: 2}\n", 1, "duplicate key 'a'"),
    ("cam0: 1\n---\ncam0: 2\n", 2, "expected a single document"),
    ("cam0: [1, 2\n", 2, "(while parsing a flow sequence at line 1; truncated file?)"),
    ("cam0: 1\ncam1: \x07\n", 2, "character U+0007 is not allowed in YAML"),
    pytest.param("cam0:\n  resolution: [" + "9" * 5000 + ", 1]\n", 2, "Exceeds the limit (4300 digits)",
                 marks=pytest.mark.skipif(not hasattr(sys, "get_int_max_str_digits"),
                                          reason="Python without the int digit limit")),
], ids=["anchor", "alias", "billion-laughs", "python-tag", "python-name", "str-tag", "deep-flow",
        "deep-block", "duplicate-key", "two-documents", "truncated", "control-character",
        "huge-integer"])
def test_kalibr_yaml_refusals(tmp_path, text, line, message):
    path = tmp_path / "camchain.yaml"
    path.write_text(text)
    raises(f"{path}: line {line}: |{message}", C.load_kalibr, path)
    raises(f"{path}: line {line}: |{message}|format 'kalibr' detected from the content", C.load_rig, path)


def test_kalibr_yaml_nesting_at_the_limit_is_read(tmp_path):
    path = tmp_path / "camchain.yaml"
    path.write_text("cam1: " + "[" * (MAX_DEPTH - 1) + "]" * (MAX_DEPTH - 1) + "\n")
    raises(f"{path}|no top-level 'cam0'", C.load_kalibr, path)  # parsed: the depth is allowed


def test_kalibr_missing_T_cn_cnm1_derived_from_T_cam_imu(tmp_path):
    lines = RADTAN.read_text().split("\n")
    k = lines.index("  T_cn_cnm1:")
    path = tmp_path / "no_chain.yaml"
    path.write_text("\n".join(lines[:k] + lines[k + 5:]))
    assert_same_rig(C.load_kalibr(path, rig_frame="cam0"), C.load_kalibr(RADTAN, rig_frame="cam0"),
                    tol=1e-15)


# --------------------------------------------------------------------------- OpenCV FileStorage

def test_opencv_stereo_calib_single_file():
    rig = C.load_rig(STEREO)
    assert rig.names == ("cam1", "cam2")
    c1, c2 = rig.cameras
    np.testing.assert_array_equal(c1.K, [[458.654, 0, 367.215], [0, 457.296, 248.375], [0, 0, 1]])
    np.testing.assert_array_equal(c2.dist, [-0.28368365, 0.07451284, -0.00010473, -3.555907e-05, 0.0])
    assert all((c.model, c.width, c.height) == ("pinhole", 752, 480) for c in rig.cameras)
    np.testing.assert_array_equal(c1.R, np.eye(3))
    # stereoCalibrate: X_2 = R X_1 + T, camera 1 = rig frame
    np.testing.assert_allclose(c2.R, T_C1_C0[:3, :3], atol=1e-16)
    np.testing.assert_allclose(c2.t, T_C1_C0[:3, 3], atol=1e-16)
    np.testing.assert_allclose(rig.centres[1], C1_IN_C0, atol=1e-12)


def test_kalibr_and_opencv_stereo_files_of_one_rig_agree():
    # rig A written by Kalibr (radtan, T_cn_cnm1) and in stereo_calib's layout (D with k3 = 0,
    # stereoCalibrate's R, T): one rig, once the conventions are converted
    kalibr = C.load_kalibr(RADTAN, rig_frame="cam0")
    opencv = C.load_rig(STEREO)
    assert_same_rig(kalibr, opencv, names=False)
    pixels = np.array([[10.0, 20.0], [376.0, 240.0], [700.0, 450.0]])
    for cam in (0, 1):
        for a, b in zip(kalibr.rays([cam] * 3, pixels), opencv.rays([cam] * 3, pixels)):
            np.testing.assert_allclose(a, b, atol=1e-12)


def test_opencv_stereo_calib_sample_pair_of_files(tmp_path):
    single = C.load_rig(STEREO)
    # sibling extrinsics.yml found next to intrinsics.yml; the sample saves no image size
    pair = C.load_opencv_yaml(STEREO_INTR, image_size=(752, 480))
    assert_same_rig(pair, single, tol=0)
    explicit = C.load_rig(STEREO_INTR, "opencv-yaml", image_size=(752, 480),
                          extrinsics_path=STEREO_EXTR)
    assert_same_rig(explicit, single, tol=0)
    raises(f"{STEREO_INTR}|image_size=", C.load_opencv_yaml, STEREO_INTR)
    raises(f"{STEREO_EXTR}|extrinsics_path=", C.load_opencv_yaml, STEREO_EXTR)
    lonely = tmp_path / "intrinsics.yml"
    shutil.copy(STEREO_INTR, lonely)
    raises(f"{lonely}|'R' and 'T'|extrinsics_path=", C.load_opencv_yaml, lonely, image_size=(752, 480))
    raises("differs from image_size", C.load_opencv_yaml, STEREO, image_size=(640, 480))


def test_opencv_multi_camera_layout():
    rig = C.load_rig(RIG4_YML)
    assert rig.names == ("front", "right", "back", "left")
    assert [c.model for c in rig.cameras] == ["pinhole", "pinhole", "fisheye", "pinhole"]
    front, right, back, left = rig.cameras
    np.testing.assert_array_equal(front.K, [[1210.5, 0, 960.0], [0, 1208.25, 600.0], [0, 0, 1]])
    np.testing.assert_array_equal(front.dist, [-0.11, 0.023, 0.0004, -0.0002])
    assert right.dist.size == 0 and (right.width, right.height) == (1280, 800)
    np.testing.assert_allclose(rig.centres, [[0, 0, 0], [0.95, 0.1, -1.6], [0, 0.05, -3.8],
                                             [-0.95, 0.1, -1.6]], atol=1e-15)
    for i, axis in ((0, [0, 0, 1]), (1, [1, 0, 0]), (3, [-1, 0, 0]),
                    (2, [0, math.sin(0.17), -math.cos(0.17)])):
        origin, d = principal_ray(rig, i)
        np.testing.assert_allclose(d, axis, atol=1e-12)
        np.testing.assert_allclose(origin, rig.centres[i], atol=0)


@pytest.mark.parametrize("suffix", [".yml", ".xml"])
@pytest.mark.parametrize("source", [RIG4_YML, EQUI, STEREO, COLMAP_NEW])
def test_save_opencv_yaml_round_trips_exactly(tmp_path, source, suffix):
    rig = C.load_rig(source)
    out = tmp_path / f"rig{suffix}"
    C.save_opencv_yaml(rig, out)
    back = C.load_rig(out)
    assert back == rig  # Rig equality: exact arrays, names, models, sizes
    assert C.detect_format(out) == "opencv-yaml"


def test_save_opencv_yaml_unwritable_path(tmp_path):
    with pytest.raises(OSError):
        C.save_opencv_yaml(C.load_rig(RIG4_YML), tmp_path / "missing" / "rig.yml")
    with pytest.raises(ValueError, match="Rig"):
        C.save_opencv_yaml("not a rig", tmp_path / "rig.yml")


def test_save_opencv_yaml_keeps_skew_and_long_distortion(tmp_path):
    gen = np.random.default_rng(7)
    cams = []
    for i, n in enumerate((0, 4, 5, 8, 12, 14)):
        R = cv2.Rodrigues(gen.standard_normal(3))[0]
        K = [[700 + gen.random(), 0.37 * i, 640.25], [0, 690 + gen.random(), 400.125], [0, 0, 1]]
        cams.append(Camera(f"c{i}", K, 1e-3 * gen.standard_normal(n), "pinhole", R,
                           gen.standard_normal(3), 1280, 800))
    rig = Rig(tuple(cams))
    C.save_opencv_yaml(rig, tmp_path / "r.yaml")
    assert C.load_opencv_yaml(tmp_path / "r.yaml") == rig


def test_opencv_file_of_one_matrix(tmp_path):
    """A FileStorage document whose root is a single !!opencv-matrix (fuzz_calibration:
    the error's listing of the top-level keys raised a TypeError on it)."""
    mat = tmp_path / "K.yml"
    mat.write_text("%YAML:1.0\n---\n!!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n"
                   "   data: [ 1210., 0., 960., 0., 1208., 600., 0., 0., 1. ]\n")
    for load in (C.load_opencv_yaml, C.load_rig):
        raises(f"{mat}: the top level is a single matrix, not named entries", load, mat)


def test_opencv_lens_model_rules(tmp_path):
    # 4 coefficients without a model name are ambiguous ...
    four = variant(tmp_path, RIG4_YML, "      model: fisheye\n", "")
    raises(f"{four}|cameras[2] ('back')|ambiguous", C.load_opencv_yaml, four)
    # ... and model= resolves them for the entries that name none
    rig = C.load_opencv_yaml(four, model="fisheye")
    assert_same_rig(rig, C.load_rig(RIG4_YML), tol=0)
    # the OpenCV tutorial's fisheye_model flag
    flag = variant(tmp_path, RIG4_YML, "      model: fisheye\n", "      fisheye_model: 1\n", "flag.yml")
    assert_same_rig(C.load_opencv_yaml(flag), C.load_rig(RIG4_YML), tol=0)
    clash = variant(tmp_path, RIG4_YML, "      model: fisheye\n",
                    "      model: fisheye\n      fisheye_model: 0\n", "clash.yml")
    raises(f"{clash}|cameras[2] ('back')|contradictory", C.load_opencv_yaml, clash)


# --------------------------------------------------------------------------- COLMAP

def test_colmap_legacy_rig_bundle_adjuster_config():
    rig = C.load_colmap(COLMAP_OLD, rig_index=0)
    assert rig.names == ("rig1/front/", "rig1/right/", "rig1/back/", "rig1/left/")
    front, right, back, left = rig.cameras
    # cameras.txt: "1 OPENCV 1920 1200 1210.5 1208.25 960.5 600.5 ..."; COLMAP's pixel centres
    # are at +0.5 from OpenCV's
    np.testing.assert_array_equal(front.K, [[1210.5, 0, 960.0], [0, 1208.25, 600.0], [0, 0, 1]])
    np.testing.assert_array_equal(front.dist, [-0.11, 0.023, 0.0004, -0.0002])
    assert (front.width, front.height) == (1920, 1200)
    # "4 SIMPLE_RADIAL 1280 800 805.0 639.5 400.5 -0.0125" -> f, cx, cy, k
    np.testing.assert_array_equal(left.K, [[805.0, 0, 639.0], [0, 805.0, 400.0], [0, 0, 1]])
    np.testing.assert_array_equal(left.dist, [-0.0125, 0, 0, 0])
    assert back.model == "fisheye"
    np.testing.assert_array_equal(back.dist, [0.041, -0.012, 0.0031, -0.0007])
    # rel_qvec (w, x, y, z) = (1/sqrt2, 0, -1/sqrt2, 0): rotation of -90 deg about y,
    # R = [[c, 0, s], [0, 1, 0], [-s, 0, c]] with s = -1
    np.testing.assert_allclose(right.R, [[0, 0, -1], [0, 1, 0], [1, 0, 0]], atol=1e-15)
    # back: rel_qvec = q_x(0.17) * q_y(pi) = (0, 0, cos 0.085, sin 0.085) up to sign
    q_back = json.loads(COLMAP_OLD.read_text())[0]["cameras"][2]["rel_qvec"]
    np.testing.assert_allclose(np.abs(q_back), [0, 0, math.cos(0.085), math.sin(0.085)], atol=1e-15)
    np.testing.assert_allclose(back.R, rotation_from_quaternion_wxyz(q_back), atol=1e-15)
    np.testing.assert_array_equal(front.R, np.eye(3))
    np.testing.assert_allclose(rig.centres, [[0, 0, 0], [0.95, 0.1, -1.6], [0, 0.05, -3.8],
                                             [-0.95, 0.1, -1.6]], atol=1e-15)
    # the principal point of cameras.txt, converted to OpenCV pixels, is the optical axis ...
    o, d = rig.rays([1], [[640.0 - 0.5, 400.0 - 0.5]])
    np.testing.assert_allclose(d[0], [1, 0, 0], atol=1e-15)
    np.testing.assert_allclose(o[0], [0.95, 0.1, -1.6], atol=1e-15)
    # ... and taken unconverted it is half a pixel off
    _, d = rig.rays([1], [[640.0, 400.0]])
    assert np.degrees(np.arccos(min(1.0, d[0] @ [1, 0, 0]))) > 0.02


def test_colmap_legacy_second_rig_and_remaining_models():
    rig = C.load_rig(COLMAP_OLD, rig_index=1)
    assert rig.names == ("rig2/a/", "rig2/b/", "rig2/c/")
    a, b, c = rig.cameras
    # FULL_OPENCV fx fy cx cy k1 k2 p1 p2 k3 k4 k5 k6 == OpenCV's 8-coefficient order
    np.testing.assert_array_equal(a.K, [[500.0, 0, 320.0], [0, 501.0, 240.0], [0, 0, 1]])
    np.testing.assert_array_equal(a.dist, [0.1, -0.05, 0.001, 0.0005, 0.01, 0.2, -0.03, 0.004])
    # RADIAL f cx cy k1 k2; the reference camera (id 6) has no rel_*: identity
    np.testing.assert_array_equal(b.K, [[498.0, 0, 319.0], [0, 498.0, 240.5], [0, 0, 1]])
    np.testing.assert_array_equal(b.dist, [-0.08, 0.01, 0, 0])
    np.testing.assert_array_equal(b.R, np.eye(3))
    np.testing.assert_array_equal(b.t, np.zeros(3))
    # SIMPLE_PINHOLE f cx cy
    np.testing.assert_array_equal(c.K, [[499.0, 0, 319.5], [0, 499.0, 239.5], [0, 0, 1]])
    assert c.dist.size == 0
    # rel_qvec (cos 1deg, 0, -sin 1deg, 0), rel_tvec (0.3, 0, 0): centre -R^T t
    R = rotation_from_quaternion_wxyz([math.cos(math.radians(1)), 0, -math.sin(math.radians(1)), 0])
    np.testing.assert_allclose(c.R, R, atol=1e-15)
    np.testing.assert_allclose(rig.centres[2], -R.T @ [0.3, 0, 0], atol=1e-15)


def test_colmap_312_format_matches_legacy_and_other_formats(tmp_path):
    new = C.load_rig(COLMAP_NEW)  # cameras.txt and images.txt found next to it
    old = C.load_rig(COLMAP_OLD, rig_index=0)
    assert_same_rig(new, old, tol=0)
    # the same physical rig in three other files
    assert_same_rig(C.load_rig(RIG4_YML), new, names=False)
    assert_same_rig(C.load_rig(RIG4_JSON), new, names=False)
    assert_same_rig(C.load_rig(RIG4_JSON), C.load_rig(RIG4_YML), tol=0)
    # explicit companion files, under other names and folders
    elsewhere = tmp_path / "model"
    elsewhere.mkdir()
    shutil.copy(COLMAP_CAMS, elsewhere / "cams.txt")
    shutil.copy(COLMAP_IMGS, elsewhere / "imgs.txt")
    cfg = tmp_path / "cfg.json"
    shutil.copy(COLMAP_NEW, cfg)
    with pytest.raises(OSError):  # no cameras.txt next to it
        C.load_colmap(cfg)
    rig = C.load_rig(cfg, "colmap", cameras_txt=elsewhere / "cams.txt",
                     images_txt=elsewhere / "imgs.txt")
    assert_same_rig(rig, new, tol=0)


def test_colmap_camera_model_override_and_camera_id_extension(tmp_path):
    cfg = variant(tmp_path, COLMAP_NEW, '"image_prefix": "rig1/right/",',
                  '"image_prefix": "rig1/right/", "camera_model_name": "OPENCV", '
                  '"camera_params": [810.0, 811.0, 640.5, 400.5, -0.1, 0.01, 0.0, 0.0],')
    shutil.copy(COLMAP_CAMS, tmp_path / "cameras.txt")
    shutil.copy(COLMAP_IMGS, tmp_path / "images.txt")
    right = C.load_colmap(cfg).cameras[1]
    np.testing.assert_array_equal(right.K, [[810.0, 0, 640.0], [0, 811.0, 400.0], [0, 0, 1]])
    np.testing.assert_array_equal(right.dist, [-0.1, 0.01, 0, 0])
    assert (right.width, right.height) == (1280, 800)  # size still from cameras.txt
    # "camera_id" in an entry replaces the images.txt look-up
    ids = variant(tmp_path, COLMAP_NEW, '"image_prefix": "rig1/back/",',
                  '"image_prefix": "rig1/back/", "camera_id": 3,', "ids.json")
    (tmp_path / "images.txt").unlink()
    with pytest.raises(OSError):  # the other entries still need images.txt
        C.load_colmap(ids)
    shutil.copy(COLMAP_IMGS, tmp_path / "images.txt")
    assert_same_rig(C.load_colmap(ids), C.load_rig(COLMAP_NEW), tol=0)


def test_colmap_rig_index():
    raises(f"{COLMAP_OLD}|2 rigs|rig_index=", C.load_rig, COLMAP_OLD)
    raises("rig_index must be", C.load_colmap, COLMAP_OLD, rig_index=2)
    raises("rig_index must be", C.load_colmap, COLMAP_OLD, rig_index=True)


# --------------------------------------------------------------------------- detection, dispatch

SAMPLES = [(RADTAN, "kalibr"), (EQUI, "kalibr"), (STEREO, "opencv-yaml"), (RIG4_YML, "opencv-yaml"),
           (RIG4_JSON, "mcgeom-json"), (COLMAP_NEW, "colmap")]


@pytest.mark.parametrize("path,fmt", SAMPLES, ids=[p.name for p, _ in SAMPLES])
def test_detect_format_and_dispatch(path, fmt):
    assert C.detect_format(path) == fmt
    assert C.load_rig(path) == C.load_rig(path, format=fmt)


#: every file under tests/data/calibration: how it is loaded, or which file reads it
EVERY_FILE = {
    "kalibr/camchain-imucam-radtan.yaml": {}, "kalibr/camchain-equidistant.yaml": {},
    "opencv/rig4.yml": {}, "opencv/stereo_calib.yml": {},
    "opencv/stereo_calib/intrinsics.yml": {"image_size": (752, 480)},
    "opencv/stereo_calib/extrinsics.yml": "opencv/stereo_calib/intrinsics.yml",
    "mcgeom/rig4.json": {}, "colmap/rig_config.json": {},
    "colmap/rig_config_legacy.json": {"rig_index": 0},
    "colmap/cameras.txt": "colmap/rig_config.json", "colmap/images.txt": "colmap/rig_config.json",
}


def test_every_calibration_sample_loads():
    found = {p.relative_to(DATA).as_posix() for p in DATA.rglob("*") if p.is_file()}
    assert found == set(EVERY_FILE)
    for rel, how in EVERY_FILE.items():
        if isinstance(how, dict):
            rig = C.load_rig(DATA / rel, **how)
            assert len(rig) >= 2, rel


def test_mcgeom_json_dispatches_to_load_mcgeom_json(tmp_path):
    rig = C.load_mcgeom_json(RIG4_JSON)
    assert C.load_rig(RIG4_JSON) == rig
    C.save_mcgeom_json(rig, tmp_path / "rig.json")
    assert C.load_rig(tmp_path / "rig.json") == rig
    with pytest.raises(ValueError, match="Rig"):
        C.save_mcgeom_json("not a rig", tmp_path / "rig.json")


def test_undetectable_file_lists_every_format_tried(tmp_path):
    path = tmp_path / "notes.txt"
    path.write_text("just some words\n")
    msg = raises(f"{path}|cannot tell", C.load_rig, path)
    for fmt in C.FORMATS:
        assert f"{fmt}:" in msg
    assert "not a JSON object" in msg and "not a JSON list" in msg
    assert "'%YAML" in msg and "no top-level 'cam0:' key" in msg
    other = tmp_path / "other.json"
    other.write_text('{"format": "something-else", "cameras": []}')
    raises("'something-else', not 'mcgeom-rig'|not a list of rigs", C.detect_format, other)


def test_load_rig_arguments(tmp_path):
    with pytest.raises(TypeError, match="rig_frame"):
        C.load_rig(COLMAP_NEW, rig_frame="imu")
    raises("unknown format", C.load_rig, RADTAN, format="yaml")
    raises("rig_frame must be", C.load_kalibr, RADTAN, rig_frame="body")
    raises("model must be", C.load_opencv_yaml, RIG4_YML, model="omni")
    raises("image_size must be", C.load_opencv_yaml, STEREO, image_size=752)


# --------------------------------------------------------------------------- bad files

@pytest.mark.parametrize("src,fmt,marker,keep,expect", [
    (RADTAN, "kalibr", "0.07451284, -0.00010", True,
     "line 29: expected ',' or ']', but got '<stream end>' (while parsing a flow sequence; "
     "truncated file?)"),
    (RADTAN, "kalibr", "  resolution: [752, 480]\n  rostopic: /cam1", False,
     "cam1: missing key 'resolution'"),
    (EQUI, "kalibr", "  intrinsics:\n  - 381.5\n  - 381.25\n", True,
     "cam2: intrinsics must have 4 elements, got 2"),
    (STEREO, "opencv-yaml", "2.5523800000000000e+02", True, "malformed or truncated"),
    (RIG4_JSON, "mcgeom-json", '"K": [', True, "not valid JSON"),
    (COLMAP_OLD, "colmap", '"rel_qvec": [', True, "not valid JSON"),
], ids=["kalibr-mid-list", "kalibr-at-line", "kalibr-block", "opencv", "mcgeom", "colmap"])
def test_truncated_files(tmp_path, src, fmt, marker, keep, expect):
    text = src.read_text()
    k = text.index(marker) + (len(marker) if keep else 0)
    path = tmp_path / src.name
    path.write_text(text[:k])
    raises(f"{path}|{expect}", C.load_rig, path, format=fmt)
    # a damaged file of a recognisable format gets that format's message, not a guess list
    raises(f"{path}|{expect}|format {fmt!r} detected from the content", C.load_rig, path)


def test_truncated_colmap_cameras_txt(tmp_path):
    shutil.copy(COLMAP_OLD, tmp_path / "rig.json")
    text = COLMAP_CAMS.read_text()
    (tmp_path / "cameras.txt").write_text(text[: text.index("639.5 400.5 -0.0125") + 5])
    raises(f"{tmp_path / 'cameras.txt'}|line 7 (camera 4)|SIMPLE_RADIAL has 4 parameters, got 2",
           C.load_colmap, tmp_path / "rig.json", rig_index=0)
    (tmp_path / "cameras.txt").write_text("# Camera list with one line of data per camera:\n")
    raises("no camera in the file", C.load_colmap, tmp_path / "rig.json", rig_index=0)


def test_malformed_files(tmp_path):
    tab = variant(tmp_path, RADTAN, "  camera_model: pinhole\n  distortion_coeffs: [-0.28368365",
                  "\tcamera_model: pinhole\n  distortion_coeffs: [-0.28368365")
    raises(f"{tab}: line 28: found character '\\t' that cannot start any token", C.load_rig, tab,
           format="kalibr")
    dup = variant(tmp_path, RADTAN, "  rostopic: /cam1/image_raw\n",
                  "  rostopic: /cam1/image_raw\n  resolution: [752, 480]\n", "dup.yaml")
    raises(f"{dup}|duplicate key 'resolution'", C.load_kalibr, dup)
    anchor = variant(tmp_path, EQUI, "  intrinsics:\n  - 381.5", "  intrinsics: &k\n  - 381.5", "a.yaml")
    raises(f"{anchor}|anchors", C.load_kalibr, anchor)
    shutil.copy(COLMAP_OLD, tmp_path / "rig.json")
    bad_cams = variant(tmp_path, COLMAP_CAMS, "800.0 801.5", "800.0 eight", "cameras.txt")
    raises(f"{bad_cams}|line 5|camera 2: parameters must be numbers", C.load_colmap,
           tmp_path / "rig.json", rig_index=0)
    shutil.copy(COLMAP_CAMS, tmp_path / "cameras.txt")
    shutil.copy(COLMAP_NEW, tmp_path / "new.json")
    imgs = variant(tmp_path, COLMAP_IMGS, "0 0 -0.5 3 rig1/back/000001.jpg", "0 0 -0.5 3", "images.txt")
    raises(f"{imgs}|line 9|IMAGE_ID", C.load_colmap, tmp_path / "new.json")
    mat = variant(tmp_path, RIG4_YML, "         cols: 0\n", "         cols: 2\n", "m.yml")
    raises(f"{mat}|malformed", C.load_opencv_yaml, mat)
    binary = tmp_path / "b.yaml"
    binary.write_bytes(b"cam0:\n  camera_model: \xff\xfe\n")
    raises(f"{binary}|not UTF-8", C.load_rig, binary)
    empty = tmp_path / "e.yaml"
    empty.write_text("")
    raises(f"{empty}|cannot tell", C.load_rig, empty)
    raises(f"{empty}|empty YAML document", C.load_kalibr, empty)


def test_wrong_format(tmp_path):
    # OpenCV's "%YAML:1.0" header is no YAML directive
    raises(f"{STEREO}: line 1: |while scanning a directive", C.load_rig, STEREO, format="kalibr")
    raises(f"{RADTAN}|not an OpenCV FileStorage file", C.load_rig, RADTAN, format="opencv-yaml")
    raises(f"{RADTAN}|not valid JSON", C.load_rig, RADTAN, format="colmap")
    raises(f"{COLMAP_NEW}|must be a JSON object", C.load_rig, COLMAP_NEW, format="mcgeom-json")
    raises(f"{RIG4_JSON}|not a COLMAP rig config", C.load_rig, RIG4_JSON, format="colmap")
    raises(f"{STEREO_EXTR}|M1", C.load_rig, STEREO_EXTR)  # half of the stereo_calib pair
    other = tmp_path / "other.yml"
    other.write_text("%YAML:1.0\n---\nfoo: 1\n")
    raises(f"{other}|neither a 'cameras' list", C.load_opencv_yaml, other)
    imu_yaml = tmp_path / "imu.yaml"
    imu_yaml.write_text("imu0:\n  rostopic: /imu0\n  update_rate: 200.0\n")
    raises(f"{imu_yaml}|no top-level 'cam0'", C.load_kalibr, imu_yaml)


def test_missing_keys(tmp_path):
    k = variant(tmp_path, EQUI, "  intrinsics:\n  - 381.5\n  - 381.25\n  - 512.0\n  - 511.75\n", "")
    raises(f"{k}|cam2: missing key 'intrinsics'", C.load_kalibr, k)
    gap = variant(tmp_path, EQUI, "cam1:\n", "cam5:\n", "gap.yaml")
    raises(f"{gap}|cam1 is missing but cam5 is present", C.load_kalibr, gap)
    chain = variant(tmp_path, EQUI, "cam2:\n  T_cn_cnm1:", "cam2:\n  T_other:", "chain.yaml")
    raises(f"{chain}|cam2: missing key 'T_cn_cnm1'", C.load_kalibr, chain)
    k_right = ("!!opencv-matrix\n         rows: 3\n         cols: 3\n"
               "         dt: d\n         data: [ 8.0000000000000000e+02")
    o = variant(tmp_path, RIG4_YML, "      camera_matrix: " + k_right, "      other: " + k_right)
    raises(f"{o}|cameras[1] ('right')|missing key 'camera_matrix' or 'K'", C.load_opencv_yaml, o)
    r = tmp_path / "r.yml"
    text = RIG4_YML.read_text()
    r.write_text(text[: text.rindex("      R: !!opencv-matrix")])
    raises(f"{r}|cameras[3] ('left')|missing key 'R'", C.load_opencv_yaml, r)
    s = variant(tmp_path, STEREO, "D2: !!opencv-matrix", "D3: !!opencv-matrix", "s.yml")
    raises(f"{s}|missing key(s) 'D2'", C.load_opencv_yaml, s)
    shutil.copy(COLMAP_CAMS, tmp_path / "cameras.txt")
    shutil.copy(COLMAP_IMGS, tmp_path / "images.txt")
    right = '"camera_id": 2,\n        "image_prefix": "rig1/right/",\n        '
    q = variant(tmp_path, COLMAP_OLD, right + '"rel_tvec"', right + '"tvec"', "q.json")
    raises(f"{q}|rig 0: cameras[1] ('rig1/right/')|missing key 'rel_tvec'", C.load_colmap, q, rig_index=0)
    text = COLMAP_NEW.read_text()
    n = tmp_path / "n.json"
    n.write_text(text[: text.rindex('"cam_from_rig_translation"')] + '"translation"'
                 + text[text.rindex('"cam_from_rig_translation"') + 26:])
    raises(f"{n}|cameras[3] ('rig1/left/')|missing key 'cam_from_rig_translation'", C.load_colmap, n)
    ref = variant(tmp_path, COLMAP_NEW, '"ref_sensor": true', '"ref_sensor": false', "ref.json")
    raises(f"{ref}|exactly one camera with", C.load_colmap, ref)
    ghost = variant(tmp_path, COLMAP_OLD, '"camera_id": 7,', '"camera_id": 9,', "ghost.json")
    raises(f"{ghost}|camera_id 9 is not in|cameras.txt", C.load_colmap, ghost, rig_index=1)
    prefix = variant(tmp_path, COLMAP_NEW, '"rig1/back/"', '"rig1/rear/"', "prefix.json")
    raises(f"{prefix}|cameras[2] ('rig1/rear/')|no image of", C.load_colmap, prefix)


def test_non_rotation_extrinsics(tmp_path):
    k = variant(tmp_path, RADTAN, "- [0.999801981909377,", "- [1.999801981909377,")
    raises(f"{k}|cam1: T_cn_cnm1 is not a rotation|not orthonormal", C.load_kalibr, k, rig_frame="cam0")
    tail = "    - 1.0\n  cam_overlaps:\n  - 0\n  - 1\n"
    row = variant(tmp_path, EQUI, "  - - 0.0\n    - 0.0\n    - 0.0\n" + tail,
                  "  - - 0.0\n    - 0.0\n    - 0.5\n" + tail, "row.yaml")
    raises(f"{row}|cam2: T_cn_cnm1 is not a rigid transform|last row", C.load_kalibr, row)
    text = RIG4_YML.read_text()
    start = text.index("      R: !!opencv-matrix", text.index("name: right"))
    head, tail = text[:start], text[start:]
    flipped = tail.replace("1.0000000000000000e+00,", "-1.0000000000000000e+00,", 1)
    o = tmp_path / "o.yml"
    o.write_text(head + flipped)
    raises(f"{o}|cameras[1] ('right'): R is not a rotation|det", C.load_opencv_yaml, o)
    shutil.copy(COLMAP_CAMS, tmp_path / "cameras.txt")
    q = variant(tmp_path, COLMAP_OLD, '"rel_qvec": [\n          1.0,', '"rel_qvec": [\n          2.0,',
                "q.json")
    raises(f"{q}|cameras[0] ('rig1/front/'): rel_qvec is not a rotation|norm 2", C.load_colmap, q,
           rig_index=0)
    z = variant(tmp_path, COLMAP_NEW, '[\n                    0.7071067811865476,\n'
                '                    0.0,\n                    -0.7071067811865476,',
                '[\n                    0.0,\n                    0.0,\n                    0.0,',
                "z.json")
    shutil.copy(COLMAP_IMGS, tmp_path / "images.txt")
    raises(f"{z}|cameras[1] ('rig1/right/')|cam_from_rig_rotation is not a rotation", C.load_colmap, z)
    # Kalibr's two descriptions of one rig must agree
    imu = variant(tmp_path, RADTAN, "-0.13144741537991428]", "-0.23144741537991428]", "imu.yaml")
    raises(f"{imu}|cam1: T_cn_cnm1 disagrees with T_cam_imu", C.load_kalibr, imu)


def test_singular_K(tmp_path):
    k = variant(tmp_path, EQUI, "  - 381.5\n  - 381.25\n", "  - 0.0\n  - 381.25\n")
    raises(f"{k}|cam2|positive focal lengths", C.load_kalibr, k)
    o = variant(tmp_path, RIG4_YML, "data: [ 1.2105000000000000e+03,", "data: [ 0.,", "o.yml")
    raises(f"{o}|cameras[0] ('front')|positive focal lengths", C.load_opencv_yaml, o)
    shutil.copy(COLMAP_OLD, tmp_path / "rig.json")
    variant(tmp_path, COLMAP_CAMS, "2 PINHOLE 1280 800 800.0", "2 PINHOLE 1280 800 0.0", "cameras.txt")
    raises(f"{tmp_path / 'rig.json'}|cameras.txt line 5|positive focal lengths", C.load_colmap,
           tmp_path / "rig.json", rig_index=0)


def test_bad_image_size(tmp_path):
    k = variant(tmp_path, RADTAN, "  resolution: [752, 480]\n  rostopic: /cam1",
                "  resolution: [752, 0]\n  rostopic: /cam1")
    raises(f"{k}|cam1|height must be positive", C.load_kalibr, k)
    f = variant(tmp_path, RADTAN, "  resolution: [752, 480]\n  rostopic: /cam1",
                "  resolution: [752.0, 480]\n  rostopic: /cam1", "f.yaml")
    raises(f"{f}|cam1: resolution width must be an integer", C.load_kalibr, f)
    o = variant(tmp_path, RIG4_YML, "image_width: 1280\n      image_height: 960", "image_width: -1280\n"
                "      image_height: 960", "o.yml")
    raises(f"{o}|cameras[2] ('back')|width must be positive", C.load_opencv_yaml, o)
    shutil.copy(COLMAP_OLD, tmp_path / "rig.json")
    variant(tmp_path, COLMAP_CAMS, "3 OPENCV_FISHEYE 1280 960", "3 OPENCV_FISHEYE 0 960", "cameras.txt")
    raises(f"{tmp_path / 'rig.json'}|camera_id 3|width must be positive", C.load_colmap,
           tmp_path / "rig.json", rig_index=0)


def test_unsupported_lens_models(tmp_path):
    omni = tmp_path / "omni.yaml"
    text = EQUI.read_text()
    i = text.index("camera_model: pinhole", text.index("cam1:"))
    omni.write_text(text[:i] + "camera_model: omni" + text[i + len("camera_model: pinhole"):])
    raises(f"{omni}|cam1: camera_model 'omni'|not supported", C.load_kalibr, omni)
    fov = variant(tmp_path, RADTAN, "  distortion_model: radtan\n  intrinsics: [457.587",
                  "  distortion_model: fov\n  intrinsics: [457.587", "fov.yaml")
    raises(f"{fov}|cam1: distortion_model 'fov'|no OpenCV equivalent", C.load_kalibr, fov)
    shutil.copy(COLMAP_OLD, tmp_path / "rig.json")
    variant(tmp_path, COLMAP_CAMS, "6 RADIAL 640 480 498.0 319.5 241.0 -0.08 0.01",
            "6 FOV 640 480 498.0 498.0 319.5 241.0 0.9", "cameras.txt")
    raises(f"{tmp_path / 'cameras.txt'}|camera 6|'FOV' is not supported", C.load_colmap,
           tmp_path / "rig.json", rig_index=1)


def test_kalibr_model_names_must_be_strings(tmp_path):
    # a list or mapping (YAML flow collections) where a name belongs: ValueError, not TypeError
    lst = variant(tmp_path, EQUI, "camera_model: pinhole\n  distortion_coeffs:\n  - 0.012",
                  "camera_model: [pinhole]\n  distortion_coeffs:\n  - 0.012", "lst.yaml")
    raises(f"{lst}|cam2: camera_model must be a string, got ['pinhole']", C.load_kalibr, lst)
    text = EQUI.read_text()
    i = text.index("distortion_model: equidistant")
    mapping = tmp_path / "map.yaml"
    mapping.write_text(text[:i] + "distortion_model: {equidistant: 1}"
                       + text[i + len("distortion_model: equidistant"):])
    raises(f"{mapping}|cam0: distortion_model must be a string", C.load_kalibr, mapping)


def test_rig_frame_imu_needs_T_cam_imu():
    raises(f"{EQUI}|cam0: missing key 'T_cam_imu'|rig_frame='imu'", C.load_kalibr, EQUI, rig_frame="imu")


@pytest.mark.parametrize("name,text", [
    ("deep.yaml", "cam0: " + "[" * 5000 + "]" * 5000 + "\n"),
    ("deep2.yaml", "cam0:\n" + "- " * 3000 + "1\n"),
    ("deep.json", "[" * 100000 + "]" * 100000),
    ("deep2.json", '{"format": "mcgeom-rig", "a":' + '{"a":' * 100000 + "1" + "}" * 100001),
    ("deep.yml", "%YAML:1.0\n---\na: " + "[" * 100000 + "]" * 100000 + "\n"),
    ("deep.xml", '<?xml version="1.0"?>\n<opencv_storage>\n' + "<a>" * 100000 + "1" + "</a>" * 100000
     + "</opencv_storage>\n"),
], ids=["yaml-flow", "yaml-block", "json-list", "json-object", "opencv-yaml", "opencv-xml"])
def test_pathological_nesting_is_a_value_error_not_a_crash(tmp_path, name, text):
    # OpenCV's FileStorage parsers recurse without limit (they segfault on these files) and
    # Python's json raises RecursionError: both are refused as ValueError
    path = tmp_path / name
    path.write_text(text)
    for fmt in (None,) + C.FORMATS:
        raises(str(path), C.load_rig, path, format=fmt)


#: fuzz_calibration's finding in CI (fuzz/README.md, finding 17), reduced: two
#: flow sequences over several lines, then a sequence item indented less than
#: the mapping before it. OpenCV's FileStorage parser never returns on it.
_OPENCV_HANG = ("%YAML:1.0\n"
                "         data: [ -2.2204460492503131e-16, 0., -1.0000000000000002e+00, 0.,\n"
                "             -2.2204460492503131e-16 ]\n"
                "         datb: [ -1.6000000000000003e+00, -1.0000000000000001e-01,\n"
                "             -9.5000000000000051e-01 ]\n"
                "   -\n"
                "      name: back\n")


def test_yaml_that_hangs_opencvs_parser_is_refused_by_line(tmp_path):
    """Refused with the line PyYAML stopped at, before OpenCV sees it (in a
    child process with a time limit: the unfixed loader never returns)."""
    import subprocess
    path = tmp_path / "hang.yml"
    path.write_text(_OPENCV_HANG)
    code = ("import sys\nfrom mcgeom import io as C\n"
            "try:\n    C.load_rig(sys.argv[1])\nexcept ValueError as e:\n    print(e)\n")
    out = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True,
                         text=True, timeout=120, cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert f"{path}: line 6: malformed or truncated YAML" in out.stdout
