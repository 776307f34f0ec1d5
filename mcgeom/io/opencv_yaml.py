"""Rig calibration loaders for the formats users have (I/O only: parsing and conventions).

Every loader returns a :class:`mcgeom.rig.Rig` whose cameras carry **cam_from_rig**
extrinsics, ``X_cam = R X_rig + t`` (DESIGN.md section 3), OpenCV lens models
(``"pinhole"``: ``cv2.projectPoints`` coefficients, ``"fisheye"``: ``cv2.fisheye``) and
OpenCV pixel coordinates (centre of the top-left pixel at ``(0, 0)``).

=================  ===========================================================  ==========
format             files                                                        loader
=================  ===========================================================  ==========
``mcgeom-json``    mcgeom's own JSON (``Rig.save_json``)                        :func:`load_mcgeom_json`
``opencv-yaml``    ``cv2.FileStorage`` YAML/XML: mcgeom's multi-camera layout    :func:`load_opencv_yaml`
                   or the stereoCalibrate layout of OpenCV's stereo_calib sample
``kalibr``         Kalibr ``camchain.yaml`` / ``camchain-imucam.yaml``          :func:`load_kalibr`
``colmap``         COLMAP rig config JSON (rig_bundle_adjuster or 3.12+          :func:`load_colmap`
                   rig_configurator) + ``cameras.txt`` (+ ``images.txt``)
=================  ===========================================================  ==========

:func:`load_rig` dispatches on ``format=`` or detects the format from the content
(:func:`detect_format`: a JSON object with ``"format": "mcgeom-rig"``, a JSON list, a
``%YAML`` header or OpenCV XML, a top-level ``cam0:`` key); when nothing fits, the error
lists every format tried and why it was rejected. Any problem with a file -- unreadable
text, truncated or malformed syntax, wrong format, missing key, an extrinsic that is not a
rotation, a singular ``K``, a non-positive image size, a lens model mcgeom cannot
represent, pathological nesting -- is a ``ValueError`` whose message names the file, the
entry and the problem (``OSError`` if the file cannot be opened at all). Camera-level
checks (``K``, distortion length, rotation within 1e-6 of orthonormal, image size) are
:class:`mcgeom.rig.Camera`'s own.

Conventions, and where they were checked
----------------------------------------

**OpenCV FileStorage** (``cv2.FileStorage``; files start with ``%YAML:1.0`` (OpenCV <= 4),
``%YAML 1.2`` (OpenCV 5) or ``<?xml``; matrices are ``!!opencv-matrix`` nodes). Two layouts:

* mcgeom's multi-camera layout (written by :func:`save_opencv_yaml`)::

      %YAML:1.0
      ---
      format: mcgeom-opencv-rig     # optional when reading
      version: 1                    # optional when reading
      cameras:
         - name: front              # optional, default "cam<i>"
           model: pinhole           # or fisheye; see "lens model" below
           image_width: 1280
           image_height: 800
           camera_matrix: !!opencv-matrix {rows: 3, cols: 3, dt: d, data: [...]}   # or K
           distortion_coefficients: !!opencv-matrix {rows: 1, cols: 5, ...}       # or D
           R: !!opencv-matrix {rows: 3, cols: 3, ...}    # cam_from_rig rotation
           T: !!opencv-matrix {rows: 3, cols: 1, ...}    # cam_from_rig translation, metres

  The key names follow OpenCV's calibration samples (``image_width``, ``image_height``,
  ``camera_matrix``, ``distortion_coefficients``; ``K``/``D`` as written for
  ``cv2.fisheye``); ``R``/``T`` are cam_from_rig, as ``R``/``T`` of ``cv2.stereoCalibrate``
  are cam2_from_cam1. Other keys are ignored.

* The stereoCalibrate layout of OpenCV's ``samples/cpp/stereo_calib.cpp``, which writes
  ``intrinsics.yml`` with ``M1 D1 M2 D2`` and ``extrinsics.yml`` with ``R T R1 R2 P1 P2 Q``
  (checked in the sample's source). ``R, T`` "bring points given in the first camera's
  coordinate system to points in the second camera's" (OpenCV's ``stereoCalibrate``
  documentation): ``X_2 = R X_1 + T``. Camera 1 (named ``"cam1"``) defines the rig frame
  (identity extrinsics), camera 2 (``"cam2"``) gets ``(R, T)``. The keys may be in one
  file, or in two: pass ``extrinsics_path=``, or keep the sample's ``extrinsics.yml`` (or
  ``.yaml``/``.xml``) next to the intrinsics file, which is then used when the intrinsics
  file has neither ``R`` nor ``T``. The sample does not save the image size: it is read
  from top-level ``image_width``/``image_height`` if present, else from ``image_size=(w,
  h)``, else it is an error. ``T`` is in the unit of the calibration target (metres if
  the square size was given in metres): mcgeom cannot check this.

* Lens model: ``model`` or ``distortion_model`` (``pinhole``, ``plumb_bob``,
  ``rational_polynomial``, ``radtan`` -> pinhole; ``fisheye``, ``equidistant`` ->
  fisheye), or ``fisheye_model: 0|1`` as written by OpenCV's camera_calibration tutorial,
  or the ``model=`` argument. Without any of these, 0, 5, 8, 12 or 14 coefficients are
  pinhole (``cv2.calibrateCamera`` always returns at least 5), and exactly 4 coefficients
  are ambiguous (``cv2.fisheye`` returns 4; pinhole ``k1 k2 p1 p2`` is also 4) and refused.

**Kalibr** (https://github.com/ethz-asl/kalibr/wiki/yaml-formats and .../supported-models,
checked against ``kalibr_common/ConfigReader.py``): top-level ``cam0, cam1, ...`` each with
``camera_model`` (``pinhole`` only: ``omni``/``ds``/``eucm`` are not OpenCV models and are
refused), ``intrinsics: [fu, fv, pu, pv]``, ``distortion_model`` (``radtan`` ``[k1, k2, r1,
r2]`` -> OpenCV pinhole ``k1 k2 p1 p2``; ``equidistant`` ``[k1..k4]`` -> ``cv2.fisheye``,
the same Kannala-Brandt polynomial; ``none`` -> no distortion; ``fov`` refused),
``resolution: [width, height]``, ``T_cn_cnm1`` ("takes cam n-1 to cam n coordinates":
``X_cn = T_cn_cnm1 X_cnm1``) and ``T_cam_imu`` ("from IMU to camera coordinates":
``X_cam = T_cam_imu X_imu``), both 4x4. The chain is composed as ``T_cn_c0 = T_cn_cnm1
T_cnm1_c0``. ``rig_frame="cam0"`` puts the rig frame on cam0 (a ``T_cn_cnm1`` on cam0,
which Kalibr never writes, is ignored); ``rig_frame="imu"`` on the IMU, with
``T_cam_imu`` as each camera's cam_from_rig; the default is ``"imu"`` when every camera
has ``T_cam_imu`` and ``"cam0"`` otherwise. When a file has both ``T_cn_cnm1`` and
``T_cam_imu`` (Kalibr's camchain-imucam computes one from the other) they must agree to
1e-6 (rotation entries and metres), else the file describes two rigs and is refused.
Pixel coordinates are OpenCV's (Kalibr's corner detection is OpenCV's; its intrinsics are
used unchanged with OpenCV by everyone), so no offset is applied.

Kalibr writes the file with PyYAML's ``yaml.dump``: older PyYAML writes leaf lists in
flow style (``- [0.99, 0.01, ...]``), PyYAML >= 5.1 in block style (``- - 0.99``), both
with PyYAML's *indentless* sequences (``T_cn_cnm1:`` followed by ``- ...`` at the key's
own indentation), and long flow lists wrap over several lines. PyYAML is not a
dependency of mcgeom, and ``cv2.FileStorage`` -- even with a ``%YAML:1.0`` header
prepended -- rejects indentless sequences ("Incorrect indentation"), so this module has
a small strict parser for the YAML subset Kalibr writes: block mappings and sequences
(indentless and compact ``- - x`` too), flow sequences (nested, multi-line), plain and
quoted scalars, comments, one document. Anchors, aliases, tags, flow mappings, block
scalars, duplicate keys and tabs in indentation are refused with the line number.

**COLMAP** rig configuration (JSON, a list of rigs) together with COLMAP's ``cameras.txt``:

* rig_bundle_adjuster (COLMAP <= 3.11, ``src/exe/sfm.cc`` / ``colmap.cc``):
  ``[{"ref_camera_id": 1, "cameras": [{"camera_id": 1, "image_prefix": "...",
  "rel_tvec": [x, y, z], "rel_qvec": [w, x, y, z]}, ...]}]``. COLMAP's comment: "The
  relative extrinsics rel_qvec and rel_tvec transform coordinates from rig to camera
  coordinate space", and ``CameraRig::ComputeRelativePoses`` sets them to cam_from_ref
  with the reference camera at identity: they are cam_from_rig with the rig frame on the
  reference camera. The reference camera may omit ``rel_*`` (identity); the others must
  have both (COLMAP would otherwise estimate them from a reconstruction).
* rig_configurator (COLMAP >= 3.12, ``doc/rigs.rst`` and ``ReadRigConfig`` in
  ``src/colmap/scene/rig.cc``): ``[{"cameras": [{"image_prefix": "...", "ref_sensor":
  true}, {"image_prefix": "...", "cam_from_rig_rotation": [w, x, y, z],
  "cam_from_rig_translation": [x, y, z]}, ...]}]``: exactly one reference sensor, without
  a pose (identity); optional ``camera_model_name`` + ``camera_params`` override the
  intrinsics of ``cameras.txt`` (as COLMAP does; the image size still comes from
  ``cameras.txt``). Cameras are identified by image name prefix, so the camera id of each
  entry is found in ``images.txt`` (the images whose name starts with the prefix must
  all use one camera, as COLMAP requires); an entry may instead give ``camera_id``
  directly (an mcgeom extension).
* Quaternions are ``(w, x, y, z)``, Hamilton convention (``doc/format.rst``); they are
  normalised, and refused if their norm differs from 1 by more than 1e-3.
* ``cameras.txt`` (``CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]``, ``doc/format.rst``):
  ``SIMPLE_PINHOLE f cx cy``, ``PINHOLE fx fy cx cy``, ``SIMPLE_RADIAL f cx cy k``,
  ``RADIAL f cx cy k1 k2``, ``OPENCV fx fy cx cy k1 k2 p1 p2``, ``OPENCV_FISHEYE fx fy cx
  cy k1 k2 k3 k4``, ``FULL_OPENCV fx fy cx cy k1 k2 p1 p2 k3 k4 k5 k6``; other models are
  refused. COLMAP puts the centre of the top-left pixel at ``(0.5, 0.5)``
  (``doc/database.rst``), OpenCV at ``(0, 0)``: the principal point is shifted by -0.5.
* Cameras appear in the order of the rig config; names are the image prefixes (or
  ``camera_<id>`` for an empty prefix); translations are in the reconstruction's unit.
"""

from __future__ import annotations

import json
import math
import os
import re
from typing import Any, Callable

import cv2
import numpy as np

from mcgeom.rig import RIG_FORMAT, Camera, Rig
from mcgeom.validation import check_int, check_rotation, numeric

__all__ = [
    "FORMATS", "OPENCV_RIG_FORMAT", "detect_format", "load_rig", "load_mcgeom_json",
    "load_opencv_yaml", "save_opencv_yaml", "load_kalibr", "load_colmap",
]

FORMATS = ("mcgeom-json", "opencv-yaml", "kalibr", "colmap")
OPENCV_RIG_FORMAT = "mcgeom-opencv-rig"
OPENCV_RIG_VERSION = 1

_QUAT_NORM_TOL = 1e-3       # |‖q‖ - 1| above this: not a rotation as written
_CHAIN_TOL = 1e-6           # Kalibr T_cn_cnm1 vs T_cam_imu agreement (entries, metres)
_BOTTOM_ROW_TOL = 1e-9      # last row of a 4x4 rigid transform must be [0, 0, 0, 1]


# --------------------------------------------------------------------------- shared helpers

def _where(path: Any) -> str:
    return os.fspath(path)


def _read_text(path: Any) -> str:
    """The file's text (UTF-8, optional BOM); ValueError naming the file if not text."""
    with open(path, "rb") as fh:
        raw = fh.read()
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ValueError(f"{_where(path)}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None


def _make_camera(where: str, entry: str, **fields: Any) -> Camera:
    """A Camera, with Camera's own checks reported as '<file>: <entry>: <problem>'."""
    try:
        return Camera(**fields)
    except ValueError as exc:
        raise ValueError(f"{where}: {entry}: {exc}") from None


def _make_rig(where: str, cameras: list[Camera]) -> Rig:
    try:
        return Rig(tuple(cameras))
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None


def _vector(where: str, what: str, value: Any, n: int | None = None) -> np.ndarray:
    """A finite 1-D float vector (row/column matrices accepted), of length n if given."""
    if value is None:
        raise ValueError(f"{where}: {what} is empty")
    try:
        arr = numeric(what, value)
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None
    if arr.ndim > 2 or (arr.ndim == 2 and 1 not in arr.shape and arr.size != 0):
        raise ValueError(f"{where}: {what} must be a vector, got shape {arr.shape}")
    arr = arr.reshape(-1)
    if n is not None and arr.size != n:
        raise ValueError(f"{where}: {what} must have {n} elements, got {arr.size}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{where}: {what} has non-finite entries")
    return arr


def _matrix(where: str, what: str, value: Any, shape: tuple[int, int]) -> np.ndarray:
    try:
        arr = numeric(what, value)
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None
    if arr.shape != shape:
        raise ValueError(f"{where}: {what} must have shape {shape}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{where}: {what} has non-finite entries")
    return arr


def _rotation(where: str, what: str, value: Any) -> np.ndarray:
    try:
        return check_rotation(what, value)
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None


def _integer(where: str, what: str, value: Any) -> int:
    try:
        return check_int(what, value)
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None


# Rigid transforms as (R, t) with X_a = R X_b + t ("a_from_b").
def _compose(a_from_b: tuple[np.ndarray, np.ndarray],
             b_from_c: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    (R1, t1), (R2, t2) = a_from_b, b_from_c
    return R1 @ R2, R1 @ t2 + t1


def _inverse(a_from_b: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    R, t = a_from_b
    return R.T, -R.T @ t


_IDENTITY_POSE = (np.eye(3), np.zeros(3))


def _quaternion_to_rotation(where: str, what: str, value: Any) -> np.ndarray:
    """Rotation matrix of a (w, x, y, z) Hamilton quaternion (COLMAP's and Eigen's order)."""
    q = _vector(where, what, value, 4)
    norm = float(np.linalg.norm(q))
    if abs(norm - 1.0) > _QUAT_NORM_TOL:
        raise ValueError(f"{where}: {what} is not a rotation: quaternion (w, x, y, z) = "
                         f"{q.tolist()} has norm {norm:.6g}, not 1")
    w, x, y, z = q / norm
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


# --------------------------------------------------------------------------- mcgeom JSON

def load_mcgeom_json(path: Any) -> Rig:
    """Read mcgeom's own JSON rig file (``Rig.load_json``)."""
    try:
        return Rig.load_json(path)
    except RecursionError:
        raise ValueError(f"{_where(path)}: JSON nested too deeply") from None


# --------------------------------------------------------------------------- OpenCV FileStorage

_PINHOLE_NAMES = {"pinhole", "plumb_bob", "rational_polynomial", "radtan", "radial-tangential"}
_FISHEYE_NAMES = {"fisheye", "equidistant", "equi", "kannala_brandt"}
_STEREO_KEYS = ("M1", "D1", "M2", "D2", "R", "T")


def _cv_error_text(exc: BaseException) -> str:
    """The useful part of a cv2.error (possibly wrapped in a SystemError by the bindings)."""
    err = exc.__cause__ if isinstance(exc, SystemError) and exc.__cause__ else exc
    text = str(err).strip().replace("\n", " ")
    m = re.search(r"error: \(-?\d+:([^)]*)\)\s*(.*)", text)
    if m:
        text = f"{m.group(1).strip()}: {m.group(2).strip()}"
    return text or type(err).__name__


def _fs_node_to_python(node: Any, where: str, key: str, depth: int = 0) -> Any:
    """Convert a cv2.FileNode into dict / list / ndarray / int / float / str / None."""
    if depth > _MAX_NESTING:
        raise ValueError(f"{where}: nested more than {_MAX_NESTING} levels deep: not a calibration file")
    if node.isMap():
        keys = node.keys()
        if {"rows", "cols", "dt", "data"} <= set(keys):  # !!opencv-matrix / type_id="opencv-matrix"
            try:
                mat = node.mat()
            except (cv2.error, SystemError) as exc:
                raise ValueError(f"{where}: {key}: malformed matrix ({_cv_error_text(exc)})") from None
            if mat is None:
                rows, cols = node.getNode("rows").real(), node.getNode("cols").real()
                if rows * cols != 0:
                    raise ValueError(f"{where}: {key}: malformed matrix")
                return np.zeros((int(rows), int(cols)))
            return np.asarray(mat, dtype=np.float64)
        return {k: _fs_node_to_python(node.getNode(k), where, f"{key}.{k}" if key else k, depth + 1)
                for k in keys}
    if node.isSeq():
        return [_fs_node_to_python(node.at(i), where, f"{key}[{i}]", depth + 1)
                for i in range(node.size())]
    if node.isInt():
        return int(node.real())
    if node.isReal():
        return float(node.real())
    if node.isString():
        return node.string()
    return None


_MAX_NESTING = 256  # OpenCV's FileStorage parsers recurse without a limit (and crash)
_NEST_RE = re.compile(r"[\[{]|[\]}]|</|/>|<[A-Za-z_]")


def _max_nesting(text: str) -> int:
    """An upper bound on the bracket / XML element nesting depth of ``text``."""
    depth = deepest = 0
    for m in _NEST_RE.finditer(text):
        tok = m.group(0)
        if tok in ("[", "{") or (tok[0] == "<" and tok != "</"):
            depth += 1
            deepest = max(deepest, depth)
        else:
            depth -= 1
    return deepest


def _read_filestorage(path: Any) -> dict:
    where = _where(path)
    text = _read_text(path)
    if _max_nesting(text) > _MAX_NESTING:
        raise ValueError(f"{where}: nested more than {_MAX_NESTING} levels deep: not a calibration "
                         f"file (refused before OpenCV's parser, which does not limit its recursion)")
    head = text.lstrip()[:64]
    if not (head.startswith("%YAML") or head.startswith("<?xml") or head.startswith("<opencv_storage")
            or head.startswith("{")):
        raise ValueError(f"{where}: not an OpenCV FileStorage file (it must start with a "
                         f"'%YAML:1.0' or '%YAML 1.2' header, or '<?xml'; got {head[:20]!r})")
    try:
        fs = cv2.FileStorage(text, cv2.FILE_STORAGE_READ | cv2.FILE_STORAGE_MEMORY)
    except (cv2.error, SystemError) as exc:
        raise ValueError(f"{where}: malformed or truncated OpenCV FileStorage file "
                         f"({_cv_error_text(exc)})") from None
    try:
        if not fs.isOpened():
            raise ValueError(f"{where}: OpenCV could not parse the file")
        root = fs.root()
        if not root.isMap():
            raise ValueError(f"{where}: empty OpenCV FileStorage file (no top-level mapping)")
        return _fs_node_to_python(root, where, "")
    except cv2.error as exc:
        raise ValueError(f"{where}: malformed OpenCV FileStorage file ({_cv_error_text(exc)})") from None
    finally:
        fs.release()


def _opencv_model(where: str, entry: str, d: dict, n_dist: int, default: str | None) -> str:
    """Lens model of one camera entry (rules in the module docstring)."""
    found: list[tuple[str, str]] = []
    for key in ("model", "distortion_model"):
        if key in d:
            name = d[key]
            if not isinstance(name, str):
                raise ValueError(f"{where}: {entry}: {key} must be a string, got {name!r}")
            low = name.lower()
            if low in _PINHOLE_NAMES:
                found.append((key, "pinhole"))
            elif low in _FISHEYE_NAMES:
                found.append((key, "fisheye"))
            else:
                raise ValueError(f"{where}: {entry}: unknown {key} {name!r} (expected 'pinhole' or "
                                 f"'fisheye', or one of {sorted(_PINHOLE_NAMES | _FISHEYE_NAMES)})")
    if "fisheye_model" in d:
        flag = d["fisheye_model"]
        if flag not in (0, 1) or isinstance(flag, (bool, float)):
            raise ValueError(f"{where}: {entry}: fisheye_model must be 0 or 1, got {flag!r}")
        found.append(("fisheye_model", "fisheye" if flag else "pinhole"))
    models = {m for _, m in found}
    if len(models) > 1:
        raise ValueError(f"{where}: {entry}: contradictory lens models: "
                         + ", ".join(f"{k} says {m}" for k, m in found))
    if models:
        return models.pop()
    if default is not None:  # the model= argument covers entries that name no model
        return default
    if n_dist == 4:
        raise ValueError(f"{where}: {entry}: 4 distortion coefficients without a lens model are "
                         f"ambiguous (cv2.fisheye k1..k4 or pinhole k1 k2 p1 p2): add "
                         f"'model: fisheye' or 'model: pinhole', or pass model=")
    return "pinhole"


def _one_of(where: str, entry: str, d: dict, keys: tuple[str, ...]) -> Any:
    present = [k for k in keys if k in d]
    if not present:
        raise ValueError(f"{where}: {entry}: missing key {' or '.join(map(repr, keys))}")
    if len(present) > 1:
        raise ValueError(f"{where}: {entry}: both {present[0]!r} and {present[1]!r} are given")
    return d[present[0]]


def _size_from(where: str, entry: str, d: dict, default: tuple[int, int] | None,
               hint: str) -> tuple[int, int]:
    has = [k for k in ("image_width", "image_height") if k in d]
    if len(has) == 1:
        missing = "image_height" if has[0] == "image_width" else "image_width"
        raise ValueError(f"{where}: {entry}: {has[0]} is given but {missing} is missing")
    if has:
        size = (_integer(where, f"{entry}: image_width", d["image_width"]),
                _integer(where, f"{entry}: image_height", d["image_height"]))
        if default is not None and tuple(default) != size:
            raise ValueError(f"{where}: {entry}: the file's image size {size} differs from "
                             f"image_size={tuple(default)}")
        return size
    if default is None:
        raise ValueError(f"{where}: {entry}: missing image size ({hint})")
    return default


def _check_image_size_arg(image_size: Any) -> tuple[int, int] | None:
    if image_size is None:
        return None
    try:
        w, h = image_size
    except (TypeError, ValueError):
        raise ValueError(f"image_size must be (width, height), got {image_size!r}") from None
    return (check_int("image_size width", w), check_int("image_size height", h))


def _check_model_arg(model: Any) -> str | None:
    if model is None:
        return None
    if model not in ("pinhole", "fisheye"):
        raise ValueError(f"model must be 'pinhole' or 'fisheye', got {model!r}")
    return model


def _opencv_camera(where: str, entry: str, name: str, d: dict, model_arg: str | None,
                   size_arg: tuple[int, int] | None, size_hint: str,
                   K_keys: tuple[str, ...], D_keys: tuple[str, ...],
                   pose: tuple[np.ndarray, np.ndarray]) -> Camera:
    K = _one_of(where, entry, d, K_keys)
    D = _one_of(where, entry, d, D_keys)
    if not isinstance(K, np.ndarray) and not isinstance(K, list):
        raise ValueError(f"{where}: {entry}: {K_keys[0]} must be a matrix, got {K!r}")
    dist = _vector(where, f"{entry}: distortion coefficients", D)
    model = _opencv_model(where, entry, d, dist.size, model_arg)
    width, height = _size_from(where, entry, d, size_arg, size_hint)
    return _make_camera(where, entry, name=name, K=K, dist=dist, model=model,
                        R=pose[0], t=pose[1], width=width, height=height)


def _opencv_pose(where: str, entry: str, R: Any, T: Any) -> tuple[np.ndarray, np.ndarray]:
    if isinstance(R, np.ndarray) and R.shape in ((3, 1), (1, 3)):
        raise ValueError(f"{where}: {entry}: R must be a 3x3 rotation matrix, got a 3-vector "
                         f"(a rotation vector? convert it with cv2.Rodrigues)")
    return (_rotation(where, f"{entry}: R", R), _vector(where, f"{entry}: T", T, 3))


def _opencv_multi(where: str, tree: dict, model: str | None,
                  size: tuple[int, int] | None) -> Rig:
    fmt = tree.get("format", OPENCV_RIG_FORMAT)
    if fmt != OPENCV_RIG_FORMAT:
        raise ValueError(f"{where}: format is {fmt!r}, expected {OPENCV_RIG_FORMAT!r}")
    version = tree.get("version", OPENCV_RIG_VERSION)
    if version != OPENCV_RIG_VERSION or isinstance(version, bool):
        raise ValueError(f"{where}: unsupported version {version!r} of {OPENCV_RIG_FORMAT!r} "
                         f"(this mcgeom reads version {OPENCV_RIG_VERSION})")
    cams = tree["cameras"]
    if not isinstance(cams, list) or not cams:
        raise ValueError(f"{where}: 'cameras' must be a non-empty sequence of camera mappings")
    out = []
    for i, d in enumerate(cams):
        entry = f"cameras[{i}]"
        if not isinstance(d, dict):
            raise ValueError(f"{where}: {entry} must be a mapping, got {type(d).__name__}")
        name = d.get("name", f"cam{i}")
        if not isinstance(name, str):
            raise ValueError(f"{where}: {entry}: name must be a string, got {name!r}")
        entry = f"cameras[{i}] ({name!r})"
        for key in ("R", "T"):
            if key not in d:
                raise ValueError(f"{where}: {entry}: missing key {key!r} (cam_from_rig extrinsics)")
        pose = _opencv_pose(where, entry, d["R"], d["T"])
        out.append(_opencv_camera(where, entry, name, d, model, size,
                                  "add image_width and image_height",
                                  ("camera_matrix", "K"), ("distortion_coefficients", "D"), pose))
    return _make_rig(where, out)


def _sibling_extrinsics(path: Any) -> str | None:
    folder = os.path.dirname(os.fspath(path))
    suffix = os.path.splitext(os.fspath(path))[1]
    for ext in dict.fromkeys((suffix, ".yml", ".yaml", ".xml")):
        candidate = os.path.join(folder, "extrinsics" + ext)
        if ext and os.path.isfile(candidate) and os.path.abspath(candidate) != os.path.abspath(path):
            return candidate
    return None


def _opencv_stereo(path: Any, tree: dict, model: str | None, size: tuple[int, int] | None,
                   extrinsics_path: Any) -> Rig:
    where = _where(path)
    missing = [k for k in ("M1", "D1", "M2", "D2") if k not in tree]
    if missing:
        hint = (" (this looks like stereo_calib's extrinsics.yml: load intrinsics.yml with "
                "extrinsics_path= this file)" if "R" in tree and "T" in tree else "")
        raise ValueError(f"{where}: stereo layout: missing key(s) {', '.join(map(repr, missing))}{hint}")
    ext_tree, ext_where = tree, where
    has_pose = [k for k in ("R", "T") if k in tree]
    if extrinsics_path is not None:
        if has_pose:
            raise ValueError(f"{where}: has {' and '.join(has_pose)} itself, but extrinsics_path= "
                             f"was also given")
        ext_tree, ext_where = _read_filestorage(extrinsics_path), _where(extrinsics_path)
    elif not has_pose:
        sibling = _sibling_extrinsics(path)
        if sibling is None:
            raise ValueError(f"{where}: stereo layout: missing keys 'R' and 'T' (cam2_from_cam1 of "
                             f"cv2.stereoCalibrate), and no extrinsics.yml next to it; pass "
                             f"extrinsics_path=")
        ext_tree, ext_where = _read_filestorage(sibling), sibling
    for key in ("R", "T"):
        if key not in ext_tree:
            raise ValueError(f"{ext_where}: stereo layout: missing key {key!r} (cam2_from_cam1 of "
                             f"cv2.stereoCalibrate)")
    pose2 = _opencv_pose(ext_where, "camera 2", ext_tree["R"], ext_tree["T"])
    hint = ("OpenCV's stereo_calib sample does not save it: add image_width and image_height "
            "or pass image_size=(width, height)")
    size = _size_from(where, "stereo layout", tree, size, hint)
    cams = []
    for k, pose in ((1, _IDENTITY_POSE), (2, pose2)):
        d = {"K": tree[f"M{k}"], "D": tree[f"D{k}"], "image_width": size[0], "image_height": size[1]}
        for key in ("model", "distortion_model", "fisheye_model"):
            if key in tree:
                d[key] = tree[key]
        cams.append(_opencv_camera(where, f"camera {k} (M{k}, D{k})", f"cam{k}", d, model, None, "",
                                   ("K",), ("D",), pose))
    return _make_rig(where, cams)


def load_opencv_yaml(path: Any, *, image_size: Any = None, model: str | None = None,
                     extrinsics_path: Any = None) -> Rig:
    """Read a ``cv2.FileStorage`` YAML/XML rig: multi-camera or stereoCalibrate layout.

    Args:
        path: the file (YAML with a ``%YAML`` header, or XML).
        image_size: ``(width, height)`` for files without ``image_width``/``image_height``
            (OpenCV's stereo_calib sample does not save it).
        model: ``"pinhole"`` or ``"fisheye"`` for cameras whose file entry names no lens
            model (required for 4 coefficients without one).
        extrinsics_path: stereo layout only: the file with ``R`` and ``T`` when ``path``
            holds only ``M1 D1 M2 D2`` (default: ``extrinsics.yml`` next to ``path``).

    Layouts and conventions: see the module docstring.
    """
    where = _where(path)
    size = _check_image_size_arg(image_size)
    model = _check_model_arg(model)
    tree = _read_filestorage(path)
    if "cameras" in tree:
        stray = [k for k in ("M1", "M2") if k in tree]
        if stray:
            raise ValueError(f"{where}: has both a 'cameras' list and stereo keys {stray}: which "
                             f"layout is meant?")
        if extrinsics_path is not None:
            raise ValueError(f"{where}: extrinsics_path= applies to the stereo layout only")
        return _opencv_multi(where, tree, model, size)
    if any(k in tree for k in _STEREO_KEYS):
        return _opencv_stereo(path, tree, model, size, extrinsics_path)
    keys = ", ".join(list(tree)[:8]) or "none"
    raise ValueError(f"{where}: neither a 'cameras' list (mcgeom multi-camera layout) nor the "
                     f"stereoCalibrate keys M1, D1, M2, D2, R, T (top-level keys: {keys})")


def save_opencv_yaml(rig: Rig, path: Any) -> None:
    """Write ``rig`` in the multi-camera ``cv2.FileStorage`` layout (``.xml``: XML, else YAML).

    Doubles are written by OpenCV with 17 significant digits, so :func:`load_opencv_yaml`
    gives back an equal rig.
    """
    if not isinstance(rig, Rig):
        raise ValueError(f"rig must be a mcgeom.rig.Rig, got {type(rig).__name__}")
    target = os.fspath(path)
    fmt = cv2.FILE_STORAGE_FORMAT_XML if target.lower().endswith(".xml") else cv2.FILE_STORAGE_FORMAT_YAML
    with open(target, "w", encoding="utf-8"):
        pass  # a plain OSError (missing folder, permissions) before OpenCV logs its own
    fs = cv2.FileStorage(target, cv2.FILE_STORAGE_WRITE | fmt)
    if not fs.isOpened():
        raise OSError(f"{target}: cannot open for writing")
    try:
        fs.write("format", OPENCV_RIG_FORMAT)
        fs.write("version", OPENCV_RIG_VERSION)
        fs.startWriteStruct("cameras", cv2.FileNode_SEQ)
        for cam in rig.cameras:
            fs.startWriteStruct("", cv2.FileNode_MAP)
            fs.write("name", cam.name)
            fs.write("model", cam.model)
            fs.write("image_width", cam.width)
            fs.write("image_height", cam.height)
            fs.write("camera_matrix", np.array(cam.K))
            fs.write("distortion_coefficients", np.array(cam.dist).reshape(1, -1))
            fs.write("R", np.array(cam.R))
            fs.write("T", np.array(cam.t).reshape(3, 1))
            fs.endWriteStruct()
        fs.endWriteStruct()
    finally:
        fs.release()


# --------------------------------------------------------------------------- YAML subset (Kalibr)

class _YamlError(ValueError):
    pass


_FLOAT_RE = re.compile(r"[-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?$")
_INT_RE = re.compile(r"[-+]?[0-9]+$")
_SPECIAL_FLOATS = {".inf": math.inf, "+.inf": math.inf, "-.inf": -math.inf, ".nan": math.nan,
                   ".Inf": math.inf, "+.Inf": math.inf, "-.Inf": -math.inf, ".NaN": math.nan,
                   ".INF": math.inf, "+.INF": math.inf, "-.INF": -math.inf, ".NAN": math.nan}
_UNSUPPORTED = {"&": "anchors", "*": "aliases", "!": "tags", "|": "block scalars",
                ">": "block scalars", "{": "flow mappings", "?": "complex keys",
                "@": "reserved indicators", "`": "reserved indicators"}


def _strip_comment(s: str) -> str:
    """``s`` without a trailing ``# comment`` (a '#' after whitespace, outside quotes)."""
    i, n, quote = 0, len(s), None
    while i < n:
        ch = s[i]
        if quote == '"':
            if ch == "\\":
                i += 1
            elif ch == '"':
                quote = None
        elif quote == "'":
            if ch == "'" and i + 1 < n and s[i + 1] == "'":
                i += 1  # '' is an escaped quote
            elif ch == "'":
                quote = None
        elif ch in "'\"" and (i == 0 or s[i - 1] in " \t[,:-"):
            quote = ch
        elif ch == "#" and (i == 0 or s[i - 1] in " \t"):
            return s[:i]
        i += 1
    return s


class _YamlSubset:
    """Strict parser for the YAML subset Kalibr (PyYAML ``yaml.dump``) writes."""

    MAX_DEPTH = 64  # nesting limit: a Kalibr file nests 3 deep; no RecursionError on junk

    def __init__(self, text: str, where: str):
        self.where = where
        self.depth = 0
        self.lines: list[list] = []  # [lineno, indent, content]
        started = ended = False
        for lineno, raw in enumerate(text.splitlines(), 1):
            body = _strip_comment(raw).rstrip()
            if not body.strip():
                continue
            stripped = body.lstrip(" ")
            if stripped.startswith("\t") or "\t" in body[: len(body) - len(stripped)]:
                self.fail(lineno, "tab in indentation (YAML allows spaces only)")
            indent = len(body) - len(stripped)
            if ended:
                self.fail(lineno, "content after the end-of-document marker '...'")
            if indent == 0 and re.match(r"---(\s|$)", stripped):
                if started:
                    self.fail(lineno, "a second YAML document ('---'): one document expected")
                started = True
                stripped = stripped[3:].strip()
                if not stripped:
                    continue
            elif indent == 0 and stripped.startswith("%"):
                if started or self.lines:
                    self.fail(lineno, "directive after the start of the document")
                continue
            elif indent == 0 and re.match(r"\.\.\.(\s|$)", stripped):
                ended = True
                continue
            started = True
            self.lines.append([lineno, indent, stripped])

    def fail(self, lineno: int, msg: str) -> None:
        raise _YamlError(f"{self.where}: line {lineno}: {msg}")

    def parse(self) -> Any:
        if not self.lines:
            raise _YamlError(f"{self.where}: empty YAML document")
        value, i = self.block(0, self.lines[0][1])
        if i < len(self.lines):
            lineno, indent, _ = self.lines[i]
            self.fail(lineno, f"content that does not fit the document's top-level "
                              f"{'sequence' if isinstance(value, list) else 'structure'} "
                              f"(indentation {indent})")
        return value

    # -- block structure
    @staticmethod
    def is_item(content: str) -> bool:
        return content == "-" or content.startswith("- ")

    def split_key(self, lineno: int, content: str) -> tuple[str, str] | None:
        """``(key, rest)`` if ``content`` is ``key: rest`` / ``key:``, else None."""
        if content[0] in "\"'":
            close = content.find(content[0], 1)
            if close < 0:
                self.fail(lineno, "unterminated quoted key")
            key = self.scalar(lineno, content[: close + 1])
            after = content[close + 1:]
            if not (after == ":" or after.startswith(": ")):
                return None
            return str(key), after[1:].strip()
        m = re.search(r":(\s|$)", content)
        if m is None:
            return None
        key = content[: m.start()].rstrip()
        if not key or key[0] in "[]{},#" or key.startswith("- "):
            return None
        return key, content[m.end():].strip()

    def nest(self, lineno: int) -> None:
        self.depth += 1
        if self.depth > self.MAX_DEPTH:
            self.fail(lineno, f"nesting deeper than {self.MAX_DEPTH} levels")

    def block(self, i: int, indent: int) -> tuple[Any, int]:
        self.nest(self.lines[i][0])
        try:
            return self._block(i, indent)
        finally:
            self.depth -= 1

    def _block(self, i: int, indent: int) -> tuple[Any, int]:
        lineno, ind, content = self.lines[i]
        if ind != indent:
            self.fail(lineno, f"bad indentation ({ind} spaces, expected {indent})")
        if self.is_item(content):
            return self.sequence(i, indent)
        if content[0] in _UNSUPPORTED:
            self.fail(lineno, f"unsupported YAML feature ({_UNSUPPORTED[content[0]]})")
        if self.split_key(lineno, content) is not None:
            return self.mapping(i, indent)
        value, i = self.inline(i, content, indent)
        return value, i

    def sequence(self, i: int, indent: int) -> tuple[list, int]:
        items = []
        n = len(self.lines)
        while i < n and self.lines[i][1] == indent and self.is_item(self.lines[i][2]):
            lineno, _, content = self.lines[i]
            rest = content[1:].lstrip(" ")
            if not rest:  # "-" alone: the item is the following, more indented block
                if i + 1 >= n or self.lines[i + 1][1] <= indent:
                    items.append(None)
                    i += 1
                    continue
                value, i = self.block(i + 1, self.lines[i + 1][1])
            elif self.is_item(rest) or (rest[0] not in "[\"'" and self.split_key(lineno, rest)):
                # compact nested sequence "- - x" or mapping "- key: v": re-read the rest of
                # the line as a block starting at its own column
                column = indent + len(content) - len(rest)
                self.lines[i] = [lineno, column, rest]
                value, i = self.block(i, column)
            else:
                value, i = self.inline(i, rest, indent)
            items.append(value)
        if i < n and self.lines[i][1] > indent:
            self.fail(self.lines[i][0], "unexpected indentation inside a sequence")
        return items, i

    def mapping(self, i: int, indent: int) -> tuple[dict, int]:
        out: dict = {}
        n = len(self.lines)
        while i < n and self.lines[i][1] == indent:
            lineno, _, content = self.lines[i]
            if self.is_item(content):
                self.fail(lineno, "a sequence item where a 'key: value' was expected")
            kv = self.split_key(lineno, content)
            if kv is None:
                self.fail(lineno, f"expected 'key: value', got {content[:40]!r}")
            key, rest = kv
            if key in out:
                self.fail(lineno, f"duplicate key {key!r}")
            if rest:
                out[key], i = self.inline(i, rest, indent)
            elif i + 1 < n and self.lines[i + 1][1] > indent:
                out[key], i = self.block(i + 1, self.lines[i + 1][1])
            elif i + 1 < n and self.lines[i + 1][1] == indent and self.is_item(self.lines[i + 1][2]):
                out[key], i = self.sequence(i + 1, indent)  # PyYAML's indentless sequence
            else:
                out[key], i = None, i + 1
        if i < n and self.lines[i][1] > indent:
            self.fail(self.lines[i][0], "unexpected indentation (multi-line plain scalars are "
                                        "not supported)")
        return out, i

    # -- inline values: scalars and (possibly multi-line) flow sequences
    def inline(self, i: int, text: str, parent_indent: int) -> tuple[Any, int]:
        lineno = self.lines[i][0]
        if text[0] in _UNSUPPORTED:
            self.fail(lineno, f"unsupported YAML feature ({_UNSUPPORTED[text[0]]})")
        if text[0] != "[":
            if re.search(r":(\s|$)", text) and text[0] not in "\"'":
                self.fail(lineno, f"unexpected ': ' in a plain value {text[:40]!r} (quote it)")
            return self.scalar(lineno, text), i + 1
        j = i + 1
        while not self.flow_closed(text):
            if j >= len(self.lines) or self.lines[j][1] <= parent_indent:
                self.fail(lineno, "unterminated flow sequence '[' (truncated file?)")
            text += " " + self.lines[j][2]
            j += 1
        value, pos = self.flow(lineno, text, 0)
        if text[pos:].strip():
            self.fail(lineno, f"unexpected text after a flow sequence: {text[pos:].strip()[:40]!r}")
        return value, j

    @staticmethod
    def flow_closed(text: str) -> bool:
        depth, quote = 0, None
        k = 0
        while k < len(text):
            ch = text[k]
            if quote == '"':
                if ch == "\\":
                    k += 1
                elif ch == '"':
                    quote = None
            elif quote == "'":
                if ch == "'" and k + 1 < len(text) and text[k + 1] == "'":
                    k += 1
                elif ch == "'":
                    quote = None
            elif ch in "'\"" and text[:k].rstrip()[-1:] in ("[", ","):
                quote = ch  # quotes open a scalar only at the start of an item
            elif ch == "[":
                depth += 1
            elif ch == "]":
                depth -= 1
                if depth == 0:
                    return True
            k += 1
        return False

    def flow(self, lineno: int, text: str, pos: int) -> tuple[list, int]:
        """Parse the flow sequence starting at ``text[pos] == '['``; return (list, end)."""
        self.nest(lineno)
        try:
            return self._flow(lineno, text, pos)
        finally:
            self.depth -= 1

    def _flow(self, lineno: int, text: str, pos: int) -> tuple[list, int]:
        assert text[pos] == "["
        pos += 1
        items: list = []
        expect_item = True
        while True:
            while pos < len(text) and text[pos] == " ":
                pos += 1
            if pos >= len(text):
                self.fail(lineno, "unterminated flow sequence '['")
            ch = text[pos]
            if ch == "]":
                if expect_item and items:
                    self.fail(lineno, "empty item in a flow sequence (',]')")
                return items, pos + 1
            if not expect_item:
                if ch != ",":
                    self.fail(lineno, f"expected ',' or ']' in a flow sequence, got {text[pos:pos + 20]!r}")
                pos += 1
                expect_item = True
                continue
            if ch == ",":
                self.fail(lineno, "empty item in a flow sequence (',,')")
            if ch == "[":
                value, pos = self.flow(lineno, text, pos)
            elif ch in "\"'":
                end = pos + 1
                while True:
                    end = text.find(ch, end)
                    if end < 0:
                        self.fail(lineno, "unterminated quoted string")
                    if ch == '"' and text[end - 1] == "\\" and text[end - 2] != "\\":
                        end += 1
                        continue
                    if ch == "'" and end + 1 < len(text) and text[end + 1] == "'":
                        end += 2
                        continue
                    break
                value, pos = self.scalar(lineno, text[pos:end + 1]), end + 1
            else:
                m = re.compile(r"[^,\[\]]*").match(text, pos)
                token = m.group(0).strip()
                if token and token[0] in _UNSUPPORTED:
                    self.fail(lineno, f"unsupported YAML feature ({_UNSUPPORTED[token[0]]})")
                if re.search(r":(\s|$)", token):
                    self.fail(lineno, "flow mappings inside sequences are not supported")
                value, pos = self.scalar(lineno, token), m.end()
            items.append(value)
            expect_item = False

    def scalar(self, lineno: int, tok: str) -> Any:
        if tok[0] == '"':
            if len(tok) < 2 or tok[-1] != '"':
                self.fail(lineno, f"unterminated quoted string {tok[:40]!r}")
            try:
                return json.loads(tok)
            except json.JSONDecodeError:
                self.fail(lineno, f"unsupported escape in {tok[:40]!r}")
        if tok[0] == "'":
            if len(tok) < 2 or tok[-1] != "'":
                self.fail(lineno, f"unterminated quoted string {tok[:40]!r}")
            return tok[1:-1].replace("''", "'")
        if tok[0] in _UNSUPPORTED:
            self.fail(lineno, f"unsupported YAML feature ({_UNSUPPORTED[tok[0]]})")
        if tok in ("null", "Null", "NULL", "~"):
            return None
        if tok in ("true", "True", "TRUE"):
            return True
        if tok in ("false", "False", "FALSE"):
            return False
        if _INT_RE.match(tok):
            return int(tok)
        if _FLOAT_RE.match(tok):
            return float(tok)
        if tok in _SPECIAL_FLOATS:
            return _SPECIAL_FLOATS[tok]
        return tok


def _parse_yaml_subset(text: str, where: str) -> Any:
    return _YamlSubset(text, where).parse()


# --------------------------------------------------------------------------- Kalibr

_KALIBR_OTHER_MODELS = {"omni": "omnidirectional (Mei)", "ds": "double sphere",
                        "eucm": "extended unified"}
_KALIBR_DIST = {"radtan": ("pinhole", 4), "equidistant": ("fisheye", 4), "none": ("pinhole", 0)}


def _kalibr_numbers(where: str, entry: str, cam: dict, key: str, n: int | None) -> np.ndarray:
    if key not in cam:
        raise ValueError(f"{where}: {entry}: missing key {key!r}")
    value = cam[key]
    if not isinstance(value, list):
        raise ValueError(f"{where}: {entry}: {key} must be a list, got {value!r}")
    for v in value:
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise ValueError(f"{where}: {entry}: {key} must hold numbers, got {v!r}")
    return _vector(where, f"{entry}: {key}", value if value else np.zeros(0), n)


def _kalibr_transform(where: str, entry: str, key: str, value: Any) -> tuple[np.ndarray, np.ndarray]:
    """A Kalibr 4x4 homogeneous rigid transform as (R, t)."""
    what = f"{entry}: {key}"
    if not isinstance(value, list) or any(not isinstance(r, list) for r in value):
        raise ValueError(f"{where}: {what} must be a 4x4 matrix (a list of 4 rows), got {value!r}"[:300])
    T = _matrix(where, what, value, (4, 4))
    if np.max(np.abs(T[3] - [0, 0, 0, 1])) > _BOTTOM_ROW_TOL:
        raise ValueError(f"{where}: {what} is not a rigid transform: last row is {T[3].tolist()}, "
                         f"expected [0, 0, 0, 1]")
    return _rotation(where, what, T[:3, :3]), T[:3, 3].copy()


def _kalibr_camera(where: str, key: str, cam: Any) -> dict:
    if not isinstance(cam, dict):
        raise ValueError(f"{where}: {key} must be a mapping, got {cam!r}"[:300])
    cm = cam.get("camera_model")
    if cm is None:
        raise ValueError(f"{where}: {key}: missing key 'camera_model'")
    if cm in _KALIBR_OTHER_MODELS:
        raise ValueError(f"{where}: {key}: camera_model {cm!r} ({_KALIBR_OTHER_MODELS[cm]}) is not "
                         f"supported: mcgeom handles OpenCV pinhole and fisheye lenses only")
    if cm != "pinhole":
        raise ValueError(f"{where}: {key}: unknown camera_model {cm!r} (expected 'pinhole')")
    fu, fv, pu, pv = _kalibr_numbers(where, key, cam, "intrinsics", 4)
    dm = cam.get("distortion_model")
    if dm is None:
        raise ValueError(f"{where}: {key}: missing key 'distortion_model'")
    if dm not in _KALIBR_DIST:
        extra = " (the FOV model has no OpenCV equivalent)" if dm == "fov" else ""
        raise ValueError(f"{where}: {key}: distortion_model {dm!r} is not supported{extra}; "
                         f"expected one of {sorted(_KALIBR_DIST)}")
    model, n_coeffs = _KALIBR_DIST[dm]
    if "distortion_coeffs" not in cam and dm == "none":
        dist = np.zeros(0)
    else:
        dist = _kalibr_numbers(where, key, cam, "distortion_coeffs", n_coeffs)
    res = cam.get("resolution")
    if res is None:
        raise ValueError(f"{where}: {key}: missing key 'resolution'")
    if not isinstance(res, list) or len(res) != 2:
        raise ValueError(f"{where}: {key}: resolution must be [width, height], got {res!r}")
    width = _integer(where, f"{key}: resolution width", res[0])
    height = _integer(where, f"{key}: resolution height", res[1])
    K = np.array([[fu, 0.0, pu], [0.0, fv, pv], [0.0, 0.0, 1.0]])
    out = {"name": key, "K": K, "dist": dist, "model": model, "width": width, "height": height}
    for tkey in ("T_cn_cnm1", "T_cam_imu"):
        if tkey in cam:
            out[tkey] = _kalibr_transform(where, key, tkey, cam[tkey])
    return out


def load_kalibr(path: Any, *, rig_frame: str | None = None) -> Rig:
    """Read a Kalibr ``camchain.yaml`` / ``camchain-imucam.yaml``.

    Args:
        path: the camchain file.
        rig_frame: ``"cam0"`` (rig frame = cam0's frame) or ``"imu"`` (the IMU frame; every
            camera needs ``T_cam_imu``). Default: ``"imu"`` if every camera has
            ``T_cam_imu``, else ``"cam0"``.

    Cameras are named ``cam0, cam1, ...`` as in the file. Conventions: module docstring.
    """
    where = _where(path)
    if rig_frame not in (None, "cam0", "imu"):
        raise ValueError(f"rig_frame must be 'cam0' or 'imu', got {rig_frame!r}")
    doc = _parse_yaml_subset(_read_text(path), where)
    if not isinstance(doc, dict):
        raise ValueError(f"{where}: not a Kalibr camchain: the top level must be a mapping "
                         f"cam0, cam1, ..., got {type(doc).__name__}")
    indices = sorted(int(m.group(1)) for k in doc if isinstance(k, str)
                     for m in [re.fullmatch(r"cam(0|[1-9][0-9]*)", k)] if m)
    if not indices or indices[0] != 0:
        raise ValueError(f"{where}: not a Kalibr camchain: no top-level 'cam0' "
                         f"(top-level keys: {', '.join(map(str, list(doc)[:8]))})")
    gaps = [i for i in range(indices[-1] + 1) if i not in indices]
    if gaps:
        raise ValueError(f"{where}: cam{gaps[0]} is missing but cam{indices[-1]} is present")
    cams = [_kalibr_camera(where, f"cam{i}", doc[f"cam{i}"]) for i in indices]

    all_imu = all("T_cam_imu" in c for c in cams)
    frame = rig_frame or ("imu" if all_imu else "cam0")
    if frame == "imu" and not all_imu:
        lacking = next(c["name"] for c in cams if "T_cam_imu" not in c)
        raise ValueError(f"{where}: {lacking}: missing key 'T_cam_imu', needed for rig_frame='imu'")

    # Kalibr's two descriptions of one rig must agree (camchain-imucam derives one from
    # the other): T_cn_cnm1 == T_cn_imu T_cnm1_imu^-1.
    for n in range(1, len(cams)):
        cn, cp = cams[n], cams[n - 1]
        if "T_cn_cnm1" in cn and "T_cam_imu" in cn and "T_cam_imu" in cp:
            R_p, t_p = _compose(cn["T_cam_imu"], _inverse(cp["T_cam_imu"]))
            R_g, t_g = cn["T_cn_cnm1"]
            gap = max(float(np.max(np.abs(R_p - R_g))), float(np.max(np.abs(t_p - t_g))))
            if gap > _CHAIN_TOL:
                raise ValueError(f"{where}: cam{n}: T_cn_cnm1 disagrees with T_cam_imu of cam{n} "
                                 f"and cam{n - 1} (max difference {gap:.3g}): the file describes "
                                 f"two different rigs")

    poses: list[tuple[np.ndarray, np.ndarray]] = []
    for n, c in enumerate(cams):
        if frame == "imu":
            poses.append(c["T_cam_imu"])                  # X_cam = T_cam_imu X_imu
        elif n == 0:
            poses.append(_IDENTITY_POSE)                  # rig frame = cam0
        else:
            if "T_cn_cnm1" in c:
                step = c["T_cn_cnm1"]                     # X_cn = T_cn_cnm1 X_cnm1
            elif "T_cam_imu" in c and "T_cam_imu" in cams[n - 1]:
                step = _compose(c["T_cam_imu"], _inverse(cams[n - 1]["T_cam_imu"]))
            else:
                raise ValueError(f"{where}: cam{n}: missing key 'T_cn_cnm1' (pose of cam{n} "
                                 f"relative to cam{n - 1})")
            poses.append(_compose(step, poses[n - 1]))    # T_cn_c0 = T_cn_cnm1 T_cnm1_c0
    out = []
    for c, (R, t) in zip(cams, poses):
        out.append(_make_camera(where, c["name"], name=c["name"], K=c["K"], dist=c["dist"],
                                model=c["model"], R=R, t=t, width=c["width"], height=c["height"]))
    return _make_rig(where, out)


# --------------------------------------------------------------------------- COLMAP

# model name -> (number of params, builder(params) -> (fx, fy, cx, cy, dist, lens model))
_COLMAP_MODELS: dict[str, tuple[int, Callable[[np.ndarray], tuple]]] = {
    "SIMPLE_PINHOLE": (3, lambda p: (p[0], p[0], p[1], p[2], [], "pinhole")),
    "PINHOLE": (4, lambda p: (p[0], p[1], p[2], p[3], [], "pinhole")),
    "SIMPLE_RADIAL": (4, lambda p: (p[0], p[0], p[1], p[2], [p[3], 0.0, 0.0, 0.0], "pinhole")),
    "RADIAL": (5, lambda p: (p[0], p[0], p[1], p[2], [p[3], p[4], 0.0, 0.0], "pinhole")),
    "OPENCV": (8, lambda p: (p[0], p[1], p[2], p[3], list(p[4:8]), "pinhole")),
    "OPENCV_FISHEYE": (8, lambda p: (p[0], p[1], p[2], p[3], list(p[4:8]), "fisheye")),
    # k1 k2 p1 p2 k3 k4 k5 k6: OpenCV's 8-coefficient rational model, same order
    "FULL_OPENCV": (12, lambda p: (p[0], p[1], p[2], p[3], list(p[4:12]), "pinhole")),
}


def _colmap_intrinsics(where: str, entry: str, model: str,
                       params: Any) -> tuple[np.ndarray, np.ndarray, str]:
    if model not in _COLMAP_MODELS:
        raise ValueError(f"{where}: {entry}: COLMAP camera model {model!r} is not supported "
                         f"(supported: {', '.join(_COLMAP_MODELS)})")
    n, build = _COLMAP_MODELS[model]
    p = _vector(where, f"{entry}: {model} parameters", params)
    if p.size != n:
        raise ValueError(f"{where}: {entry}: COLMAP model {model} has {n} parameters, got {p.size}")
    fx, fy, cx, cy, dist, lens = build(p)
    # COLMAP: centre of the top-left pixel at (0.5, 0.5); OpenCV/mcgeom: at (0, 0).
    K = np.array([[fx, 0.0, cx - 0.5], [0.0, fy, cy - 0.5], [0.0, 0.0, 1.0]])
    return K, np.asarray(dist, dtype=np.float64), lens


def _parse_colmap_cameras(path: Any) -> dict[int, tuple[str, int, int, list[float], int]]:
    """cameras.txt: {camera_id: (model, width, height, params, lineno)}."""
    where = _where(path)
    cams: dict[int, tuple[str, int, int, list[float], int]] = {}
    for lineno, raw in enumerate(_read_text(path).splitlines(), 1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        tok = line.split()
        if len(tok) < 4:
            raise ValueError(f"{where}: line {lineno}: expected 'CAMERA_ID MODEL WIDTH HEIGHT "
                             f"PARAMS[]', got {line[:60]!r}")
        try:
            cid, width, height = int(tok[0]), int(tok[2]), int(tok[3])
        except ValueError:
            raise ValueError(f"{where}: line {lineno}: CAMERA_ID, WIDTH and HEIGHT must be integers, "
                             f"got {' '.join(tok[:4])!r}") from None
        try:
            params = [float(x) for x in tok[4:]]
        except ValueError:
            raise ValueError(f"{where}: line {lineno}: camera {cid}: parameters must be numbers, "
                             f"got {' '.join(tok[4:])[:60]!r}") from None
        if cid in cams:
            raise ValueError(f"{where}: line {lineno}: camera {cid} is defined twice (first on "
                             f"line {cams[cid][4]})")
        cams[cid] = (tok[1], width, height, params, lineno)
    if not cams:
        raise ValueError(f"{where}: no camera in the file (empty or truncated cameras.txt)")
    return cams


def _parse_colmap_images(path: Any) -> list[tuple[str, int]]:
    """images.txt: [(image name, camera_id)] (every other data line is a POINTS2D line)."""
    where = _where(path)
    out = []
    lines = [(n, ln) for n, ln in enumerate(_read_text(path).splitlines(), 1)
             if not ln.startswith("#")]
    k = 0
    while k < len(lines):
        lineno, line = lines[k]
        if not line.strip():
            k += 1
            continue
        tok = line.split(None, 9)
        if len(tok) < 10:
            raise ValueError(f"{where}: line {lineno}: expected 'IMAGE_ID QW QX QY QZ TX TY TZ "
                             f"CAMERA_ID NAME', got {line[:60]!r}")
        try:
            cid = int(tok[8])
        except ValueError:
            raise ValueError(f"{where}: line {lineno}: CAMERA_ID must be an integer, "
                             f"got {tok[8]!r}") from None
        out.append((tok[9].strip(), cid))
        k += 2  # skip the POINTS2D line (possibly empty)
    return out


def _json_file(path: Any) -> Any:
    where = _where(path)
    try:
        return json.loads(_read_text(path))
    except RecursionError:
        raise ValueError(f"{where}: JSON nested too deeply") from None
    except json.JSONDecodeError as exc:
        raise ValueError(f"{where}: not valid JSON ({exc.msg} at line {exc.lineno} column "
                         f"{exc.colno}; truncated?)") from None


def _json_int(where: str, what: str, value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise ValueError(f"{where}: {what} must be an integer, got {value!r}")
    return value


def load_colmap(path: Any, *, cameras_txt: Any = None, images_txt: Any = None,
                rig_index: int | None = None) -> Rig:
    """Read a COLMAP rig configuration (``rig_config.json``) with COLMAP's ``cameras.txt``.

    Args:
        path: the rig config JSON: a list of rigs, in the rig_bundle_adjuster format
            (``ref_camera_id``, ``camera_id``, ``rel_qvec``, ``rel_tvec``) or the COLMAP
            3.12+ rig_configurator format (``ref_sensor``, ``cam_from_rig_rotation``,
            ``cam_from_rig_translation``).
        cameras_txt: COLMAP's ``cameras.txt`` (default: next to ``path``).
        images_txt: COLMAP's ``images.txt``, used by the 3.12+ format to find the camera of
            each image prefix (default: next to ``cameras_txt``).
        rig_index: which rig of the list (0-based); may be omitted when there is one rig.

    Conventions: module docstring.
    """
    where = _where(path)
    data = _json_file(path)
    if not isinstance(data, list) or not data:
        raise ValueError(f"{where}: not a COLMAP rig config: expected a non-empty JSON list of "
                         f"rigs, got {type(data).__name__}")
    if rig_index is None:
        if len(data) != 1:
            raise ValueError(f"{where}: the file has {len(data)} rigs: pass rig_index= (0..{len(data) - 1})")
        rig_index = 0
    if isinstance(rig_index, bool) or not isinstance(rig_index, int) or not 0 <= rig_index < len(data):
        raise ValueError(f"{where}: rig_index must be an integer in 0..{len(data) - 1}, got {rig_index!r}")
    rig = data[rig_index]
    rwhere = f"rig {rig_index}"
    if not isinstance(rig, dict) or "cameras" not in rig:
        raise ValueError(f"{where}: {rwhere}: must be a JSON object with a 'cameras' list")
    entries = rig["cameras"]
    if not isinstance(entries, list) or not entries:
        raise ValueError(f"{where}: {rwhere}: 'cameras' must be a non-empty list")
    for k, e in enumerate(entries):
        if not isinstance(e, dict):
            raise ValueError(f"{where}: {rwhere}: cameras[{k}] must be a JSON object")
        if "image_prefix" not in e:
            raise ValueError(f"{where}: {rwhere}: cameras[{k}]: missing key 'image_prefix'")
        if not isinstance(e["image_prefix"], str):
            raise ValueError(f"{where}: {rwhere}: cameras[{k}]: image_prefix must be a string")
    legacy = "ref_camera_id" in rig
    if legacy and any(k in e for e in entries
                      for k in ("ref_sensor", "cam_from_rig_rotation", "cam_from_rig_translation")):
        raise ValueError(f"{where}: {rwhere}: mixes the rig_bundle_adjuster format (ref_camera_id) "
                         f"with the 3.12+ format (ref_sensor, cam_from_rig_*)")

    cams_path = cameras_txt if cameras_txt is not None else os.path.join(
        os.path.dirname(os.fspath(path)), "cameras.txt")
    colmap_cams = _parse_colmap_cameras(cams_path)
    cwhere = _where(cams_path)

    poses: list[tuple[np.ndarray, np.ndarray]] = []
    ids: list[int] = []
    overrides: list[tuple[str, Any] | None] = []
    if legacy:
        ref = _json_int(where, f"{rwhere}: ref_camera_id", rig["ref_camera_id"])
        for k, e in enumerate(entries):
            entry = f"{rwhere}: cameras[{k}] ({e['image_prefix']!r})"
            if "camera_id" not in e:
                raise ValueError(f"{where}: {entry}: missing key 'camera_id'")
            cid = _json_int(where, f"{entry}: camera_id", e["camera_id"])
            has = [key for key in ("rel_qvec", "rel_tvec") if key in e]
            if len(has) == 2:
                poses.append((_quaternion_to_rotation(where, f"{entry}: rel_qvec", e["rel_qvec"]),
                              _vector(where, f"{entry}: rel_tvec", e["rel_tvec"], 3)))
            elif cid == ref and not has:
                poses.append(_IDENTITY_POSE)
            else:
                lacking = [key for key in ("rel_qvec", "rel_tvec") if key not in e]
                raise ValueError(f"{where}: {entry}: missing key {lacking[0]!r} (COLMAP would "
                                 f"estimate it from a reconstruction; mcgeom needs the extrinsics)")
            ids.append(cid)
            overrides.append(None)
        if ref not in ids:
            raise ValueError(f"{where}: {rwhere}: ref_camera_id {ref} is not one of the rig's "
                             f"camera_ids {ids}")
    else:
        refs = [k for k, e in enumerate(entries) if e.get("ref_sensor") is True]
        if len(refs) != 1:
            raise ValueError(f"{where}: {rwhere}: a rig needs exactly one camera with "
                             f"\"ref_sensor\": true (or, in the older format, ref_camera_id); "
                             f"found {len(refs)}")
        image_list = None
        for k, e in enumerate(entries):
            entry = f"{rwhere}: cameras[{k}] ({e['image_prefix']!r})"
            if "ref_sensor" in e and not isinstance(e["ref_sensor"], bool):
                raise ValueError(f"{where}: {entry}: ref_sensor must be true or false")
            has = [key for key in ("cam_from_rig_rotation", "cam_from_rig_translation") if key in e]
            if k == refs[0]:
                if has:
                    raise ValueError(f"{where}: {entry}: the reference sensor must not have "
                                     f"{has[0]} (its pose is the identity)")
                poses.append(_IDENTITY_POSE)
            elif len(has) == 2:
                poses.append((_quaternion_to_rotation(where, f"{entry}: cam_from_rig_rotation",
                                                      e["cam_from_rig_rotation"]),
                              _vector(where, f"{entry}: cam_from_rig_translation",
                                      e["cam_from_rig_translation"], 3)))
            else:
                lacking = [key for key in ("cam_from_rig_rotation", "cam_from_rig_translation")
                           if key not in e]
                raise ValueError(f"{where}: {entry}: missing key {lacking[0]!r} (COLMAP would "
                                 f"derive it from a reconstruction; mcgeom needs the extrinsics)")
            if "camera_id" in e:
                ids.append(_json_int(where, f"{entry}: camera_id", e["camera_id"]))
            else:
                if image_list is None:
                    img_path = images_txt if images_txt is not None else os.path.join(
                        os.path.dirname(os.fspath(cams_path)), "images.txt")
                    image_list = (_where(img_path), _parse_colmap_images(img_path))
                iwhere, images = image_list
                found = {cid for name, cid in images if name.startswith(e["image_prefix"])}
                if not found:
                    raise ValueError(f"{where}: {entry}: no image of {iwhere} has a name starting "
                                     f"with {e['image_prefix']!r}")
                if len(found) > 1:
                    raise ValueError(f"{where}: {entry}: the images of {iwhere} with this prefix use "
                                     f"several cameras {sorted(found)} (COLMAP requires one)")
                ids.append(found.pop())
            has_model = [key for key in ("camera_model_name", "camera_params") if key in e]
            if len(has_model) == 1:
                other = "camera_params" if has_model[0] == "camera_model_name" else "camera_model_name"
                raise ValueError(f"{where}: {entry}: {has_model[0]} given without {other}")
            overrides.append((e["camera_model_name"], e["camera_params"]) if has_model else None)

    dupes = sorted({c for c in ids if ids.count(c) > 1})
    if dupes:
        raise ValueError(f"{where}: {rwhere}: camera_id {dupes[0]} is used by several entries of "
                         f"the rig (each rig camera needs its own COLMAP camera)")
    out = []
    for k, (e, cid, pose, override) in enumerate(zip(entries, ids, poses, overrides)):
        prefix = e["image_prefix"]
        name = prefix if prefix else f"camera_{cid}"
        if cid not in colmap_cams:
            raise ValueError(f"{where}: {rwhere}: cameras[{k}] ({prefix!r}): camera_id {cid} is "
                             f"not in {cwhere}")
        model, width, height, params, lineno = colmap_cams[cid]
        entry = f"{rwhere}: cameras[{k}] ({prefix!r}, camera_id {cid} of {cwhere} line {lineno})"
        if override is not None:
            if not isinstance(override[0], str):
                raise ValueError(f"{where}: {entry}: camera_model_name must be a string")
            K, dist, lens = _colmap_intrinsics(where, f"{entry}: camera_params", override[0], override[1])
        else:
            K, dist, lens = _colmap_intrinsics(cwhere, f"line {lineno} (camera {cid})", model, params)
        out.append(_make_camera(where, entry, name=name, K=K, dist=dist, model=lens,
                                R=pose[0], t=pose[1], width=width, height=height))
    return _make_rig(where, out)


# --------------------------------------------------------------------------- detection

def _sniff(path: Any) -> tuple[str | None, str, dict[str, str]]:
    """(format or None, why it was chosen, why each format was rejected).

    Detection is by signature, not by a full parse, so that a damaged file of a
    recognisable format gets that format's precise error message.
    """
    text = _read_text(path)
    head = text.lstrip()
    reasons: dict[str, str] = {}
    if head.startswith("{"):
        reasons["colmap"] = "a JSON object, not a list of rigs"
        reasons["kalibr"] = "JSON text, not a Kalibr camchain YAML"
        reasons["opencv-yaml"] = ("JSON text (OpenCV FileStorage JSON is read only with "
                                  "format='opencv-yaml')")
        try:
            data = json.loads(text)
        except (json.JSONDecodeError, RecursionError) as exc:
            if re.search(r'"format"\s*:\s*"' + re.escape(RIG_FORMAT) + '"', text):
                return "mcgeom-json", f'a JSON object with "format": "{RIG_FORMAT}"', reasons
            detail = (f"{exc.msg} at line {exc.lineno}; truncated?"
                      if isinstance(exc, json.JSONDecodeError) else "nested too deeply")
            reasons["mcgeom-json"] = f"a JSON object that does not parse ({detail}) and names no format"
            return None, "", reasons
        fmt = data.get("format") if isinstance(data, dict) else None
        if fmt == RIG_FORMAT:
            return "mcgeom-json", f'a JSON object with "format": "{RIG_FORMAT}"', reasons
        reasons["mcgeom-json"] = f"a JSON object whose 'format' is {fmt!r}, not {RIG_FORMAT!r}"
        return None, "", reasons
    if head.startswith("["):
        return "colmap", "a JSON list (of rigs)", reasons
    reasons["mcgeom-json"] = "not a JSON object"
    reasons["colmap"] = "not a JSON list of rigs"
    if head.startswith(("%YAML", "<?xml", "<opencv_storage")):
        return "opencv-yaml", "an OpenCV FileStorage header", reasons
    reasons["opencv-yaml"] = "no '%YAML:1.0' / '%YAML 1.2' header and not OpenCV XML"
    if re.search(r"(?m)^cam0\s*:", text):
        return "kalibr", "a top-level 'cam0:' key", reasons
    reasons["kalibr"] = "no top-level 'cam0:' key"
    return None, "", reasons


def detect_format(path: Any) -> str:
    """The calibration format of a file, one of :data:`FORMATS`, from its content.

    Signatures: a JSON object with ``"format": "mcgeom-rig"`` (mcgeom-json), a JSON list
    (colmap), a ``%YAML`` header or OpenCV XML (opencv-yaml), a top-level ``cam0:`` key
    (kalibr). The file is not validated here: the loader does that.

    Raises:
        ValueError: no format fits; the message lists each format tried and why it was
            rejected.
    """
    fmt, _, reasons = _sniff(path)
    if fmt is None:
        tried = "; ".join(f"{f}: {reasons.get(f, 'rejected')}" for f in FORMATS)
        raise ValueError(f"{_where(path)}: cannot tell the calibration format. Tried {tried}. "
                         f"Pass format= one of {', '.join(FORMATS)}")
    return fmt


_LOADERS: dict[str, Callable[..., Rig]] = {
    "mcgeom-json": load_mcgeom_json,
    "opencv-yaml": load_opencv_yaml,
    "kalibr": load_kalibr,
    "colmap": load_colmap,
}
_OPTIONS = {
    "mcgeom-json": (),
    "opencv-yaml": ("image_size", "model", "extrinsics_path"),
    "kalibr": ("rig_frame",),
    "colmap": ("cameras_txt", "images_txt", "rig_index"),
}


def load_rig(path: Any, format: str | None = None, **options: Any) -> Rig:
    """Load a rig calibration in any supported format.

    Args:
        path: the calibration file.
        format: one of ``"mcgeom-json"``, ``"opencv-yaml"``, ``"kalibr"``, ``"colmap"``;
            None detects it from the content (:func:`detect_format`).
        **options: the chosen loader's keyword options: ``image_size``, ``model``,
            ``extrinsics_path`` (opencv-yaml); ``rig_frame`` (kalibr); ``cameras_txt``,
            ``images_txt``, ``rig_index`` (colmap).

    Returns:
        A :class:`mcgeom.rig.Rig` with cam_from_rig extrinsics.

    Raises:
        OSError: the file cannot be opened.
        ValueError: anything wrong with the file (message names file, entry, problem).
        TypeError: an option that the format does not take.
    """
    if format is not None and format not in _LOADERS:
        raise ValueError(f"unknown format {format!r}; expected one of {', '.join(FORMATS)} or None")
    if format is not None:
        fmt, why = format, ""
    else:
        fmt, why, _ = _sniff(path)
        if fmt is None:
            detect_format(path)  # raises, listing every format tried
    bad = [k for k in options if k not in _OPTIONS[fmt]]
    if bad:
        takes = ", ".join(_OPTIONS[fmt]) or "no options"
        raise TypeError(f"format {fmt!r} does not take option(s) {', '.join(bad)} (it takes {takes})")
    try:
        return _LOADERS[fmt](path, **options)
    except ValueError as exc:
        if not why:
            raise
        raise ValueError(f"{exc} [format {fmt!r} detected from the content: {why}; pass "
                         f"format= to override]") from None
