"""COLMAP rig configurations (``rig_config.json`` + ``cameras.txt`` / ``images.txt``): load.

Conventions, and where they were checked
----------------------------------------

A COLMAP rig configuration (JSON, a list of rigs) together with COLMAP's ``cameras.txt``:

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
* The rig frame is the reference camera's (``Rig.frame == "camera:<its name>"``); COLMAP
  has no body frame. :func:`mcgeom.load_rig`'s ``frame=`` chooses another camera or an
  explicit transform (:mod:`mcgeom.io.frame`).
"""

from __future__ import annotations

import json
import os
from typing import Any, Callable

import numpy as np

from mcgeom.io._common import IDENTITY_POSE, make_camera, make_rig, read_text, vector, describe_path
from mcgeom.rig import Rig

__all__ = ["load_colmap"]

_QUAT_NORM_TOL = 1e-3       # |‖q‖ - 1| above this: not a rotation as written


def _quaternion_to_rotation(where: str, what: str, value: Any) -> np.ndarray:
    """Rotation matrix of a (w, x, y, z) Hamilton quaternion (COLMAP's and Eigen's order)."""
    q = vector(where, what, value, 4)
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
    p = vector(where, f"{entry}: {model} parameters", params)
    if p.size != n:
        raise ValueError(f"{where}: {entry}: COLMAP model {model} has {n} parameters, got {p.size}")
    fx, fy, cx, cy, dist, lens = build(p)
    # COLMAP: centre of the top-left pixel at (0.5, 0.5); OpenCV/mcgeom: at (0, 0).
    K = np.array([[fx, 0.0, cx - 0.5], [0.0, fy, cy - 0.5], [0.0, 0.0, 1.0]])
    return K, np.asarray(dist, dtype=np.float64), lens


def _parse_colmap_cameras(path: Any) -> dict[int, tuple[str, int, int, list[float], int]]:
    """cameras.txt: {camera_id: (model, width, height, params, lineno)}."""
    where = describe_path(path)
    cams: dict[int, tuple[str, int, int, list[float], int]] = {}
    for lineno, raw in enumerate(read_text(path).splitlines(), 1):
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
    where = describe_path(path)
    out = []
    lines = [(n, ln) for n, ln in enumerate(read_text(path).splitlines(), 1)
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
    where = describe_path(path)
    try:
        return json.loads(read_text(path))
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
    where = describe_path(path)
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
    cwhere = describe_path(cams_path)

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
                              vector(where, f"{entry}: rel_tvec", e["rel_tvec"], 3)))
            elif cid == ref and not has:
                poses.append(IDENTITY_POSE)
            else:
                lacking = [key for key in ("rel_qvec", "rel_tvec") if key not in e]
                raise ValueError(f"{where}: {entry}: missing key {lacking[0]!r} (COLMAP would "
                                 f"estimate it from a reconstruction; mcgeom needs the extrinsics)")
            ids.append(cid)
            overrides.append(None)
        if ref not in ids:
            raise ValueError(f"{where}: {rwhere}: ref_camera_id {ref} is not one of the rig's "
                             f"camera_ids {ids}")
        ref_k = ids.index(ref)
    else:
        refs = [k for k, e in enumerate(entries) if e.get("ref_sensor") is True]
        if len(refs) != 1:
            raise ValueError(f"{where}: {rwhere}: a rig needs exactly one camera with "
                             f"\"ref_sensor\": true (or, in the older format, ref_camera_id); "
                             f"found {len(refs)}")
        ref_k = refs[0]
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
                poses.append(IDENTITY_POSE)
            elif len(has) == 2:
                poses.append((_quaternion_to_rotation(where, f"{entry}: cam_from_rig_rotation",
                                                      e["cam_from_rig_rotation"]),
                              vector(where, f"{entry}: cam_from_rig_translation",
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
                    image_list = (describe_path(img_path), _parse_colmap_images(img_path))
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
        out.append(make_camera(where, entry, name=name, K=K, dist=dist, model=lens,
                                R=pose[0], t=pose[1], width=width, height=height))
    return make_rig(where, out, frame=f"camera:{out[ref_k].name}")  # rig frame = reference camera
