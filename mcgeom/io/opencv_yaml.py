"""OpenCV FileStorage rig files (``cv2.FileStorage`` YAML/XML): load and save.

Read and written by OpenCV itself (``cv2.FileStorage``); this module maps the layouts
below to :class:`mcgeom.rig.Rig` (cam_from_rig extrinsics, metres, OpenCV lens models
and pixels).

Conventions, and where they were checked
----------------------------------------

Files start with ``%YAML:1.0`` (OpenCV <= 4), ``%YAML 1.2`` (OpenCV 5) or ``<?xml``;
matrices are ``!!opencv-matrix`` nodes. Two layouts:

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
"""

from __future__ import annotations

import os
import re
from typing import Any

import cv2
import numpy as np
import yaml

from mcgeom.io._common import (IDENTITY_POSE, integer, make_camera, make_rig, read_text,
                               rotation, vector, describe_path)
from mcgeom.rig import Camera, Rig
from mcgeom.validation import check_int

__all__ = ["OPENCV_RIG_FORMAT", "OPENCV_RIG_VERSION", "load_opencv_yaml", "save_opencv_yaml"]

OPENCV_RIG_FORMAT = "mcgeom-opencv-rig"
OPENCV_RIG_VERSION = 1

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


_YAML_DIRECTIVE = re.compile(r"\A\s*%YAML[^\n]*(\n|\Z)")


def _check_yaml_syntax(text: str, where: str) -> None:
    """ValueError naming the line when PyYAML cannot read the YAML structure.

    OpenCV's FileStorage parser can loop forever on malformed YAML (found by
    fuzz_calibration in CI: two flow sequences spread over several lines,
    then a sequence item indented less than the mapping before it; the call
    never returns). The structure is read by PyYAML first (``compose``:
    nodes only, so tags such as ``!!opencv-matrix`` need no constructor),
    and a file it cannot read never reaches OpenCV. The ``%YAML:1.0``
    directive, which PyYAML does not know, is left out."""
    m = _YAML_DIRECTIVE.match(text)
    skipped = text[:m.end()].count("\n") if m else 0
    try:
        for _ in yaml.compose_all(text[m.end():] if m else text, Loader=yaml.SafeLoader):
            pass
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        at = f"line {mark.line + 1 + skipped}: " if mark is not None else ""
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise ValueError(f"{where}: {at}malformed or truncated YAML ({problem})") from None
    except RecursionError:
        raise ValueError(f"{where}: YAML nested too deeply to be a calibration file") from None


def _read_filestorage(path: Any) -> dict:
    where = describe_path(path)
    text = read_text(path)
    if _max_nesting(text) > _MAX_NESTING:
        raise ValueError(f"{where}: nested more than {_MAX_NESTING} levels deep: not a calibration "
                         f"file (refused before OpenCV's parser, which does not limit its recursion)")
    head = text.lstrip()[:64]
    if not (head.startswith("%YAML") or head.startswith("<?xml") or head.startswith("<opencv_storage")
            or head.startswith("{")):
        raise ValueError(f"{where}: not an OpenCV FileStorage file (it must start with a "
                         f"'%YAML:1.0' or '%YAML 1.2' header, or '<?xml'; got {head[:20]!r})")
    if head.startswith("%YAML"):
        _check_yaml_syntax(text, where)
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
        tree = _fs_node_to_python(root, where, "")
        if not isinstance(tree, dict):
            # a document whose root is tagged !!opencv-matrix (found by
            # fuzz_calibration: the key listing of the error below then failed
            # with a TypeError)
            kind = "matrix" if isinstance(tree, np.ndarray) else type(tree).__name__
            raise ValueError(f"{where}: the top level is a single {kind}, not named entries "
                             "(a 'cameras' list, or M1, D1, M2, D2, R, T)")
        return tree
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
        size = (integer(where, f"{entry}: image_width", d["image_width"]),
                integer(where, f"{entry}: image_height", d["image_height"]))
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
    dist = vector(where, f"{entry}: distortion coefficients", D)
    model = _opencv_model(where, entry, d, dist.size, model_arg)
    width, height = _size_from(where, entry, d, size_arg, size_hint)
    return make_camera(where, entry, name=name, K=K, dist=dist, model=model,
                        R=pose[0], t=pose[1], width=width, height=height)


def _opencv_pose(where: str, entry: str, R: Any, T: Any) -> tuple[np.ndarray, np.ndarray]:
    if isinstance(R, np.ndarray) and R.shape in ((3, 1), (1, 3)):
        raise ValueError(f"{where}: {entry}: R must be a 3x3 rotation matrix, got a 3-vector "
                         f"(a rotation vector? convert it with cv2.Rodrigues)")
    return (rotation(where, f"{entry}: R", R), vector(where, f"{entry}: T", T, 3))


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
    return make_rig(where, out)


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
    where = describe_path(path)
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
        ext_tree, ext_where = _read_filestorage(extrinsics_path), describe_path(extrinsics_path)
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
    for k, pose in ((1, IDENTITY_POSE), (2, pose2)):
        d = {"K": tree[f"M{k}"], "D": tree[f"D{k}"], "image_width": size[0], "image_height": size[1]}
        for key in ("model", "distortion_model", "fisheye_model"):
            if key in tree:
                d[key] = tree[key]
        cams.append(_opencv_camera(where, f"camera {k} (M{k}, D{k})", f"cam{k}", d, model, None, "",
                                   ("K",), ("D",), pose))
    return make_rig(where, cams, frame="camera:cam1")  # cam2_from_cam1: the rig frame is cam1's


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
    where = describe_path(path)
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
