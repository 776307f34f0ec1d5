"""Kalibr camera chains (``camchain.yaml`` / ``camchain-imucam.yaml``): load.

Conventions, and where they were checked
----------------------------------------

Sources: https://github.com/ethz-asl/kalibr/wiki/yaml-formats and .../supported-models,
checked against ``kalibr_common/ConfigReader.py``.

Top-level ``cam0, cam1, ...`` each with ``camera_model`` (``pinhole`` only:
``omni``/``ds``/``eucm`` are not OpenCV models and are refused), ``intrinsics: [fu, fv, pu, pv]``, ``distortion_model`` (``radtan`` ``[k1, k2, r1,
r2]`` -> OpenCV pinhole ``k1 k2 p1 p2``; ``equidistant`` ``[k1..k4]`` -> ``cv2.fisheye``,
the same Kannala-Brandt polynomial; ``none`` -> no distortion; ``fov`` refused),
``resolution: [width, height]``, ``T_cn_cnm1`` ("takes cam n-1 to cam n coordinates":
``X_cn = T_cn_cnm1 X_cnm1``) and ``T_cam_imu`` ("from IMU to camera coordinates":
``X_cam = T_cam_imu X_imu``), both 4x4. The chain is composed as ``T_cn_c0 = T_cn_cnm1
T_cnm1_c0``. ``rig_frame="cam0"`` puts the rig frame on cam0 (a ``T_cn_cnm1`` on cam0,
which Kalibr never writes, is ignored); ``rig_frame="imu"`` on the IMU, with
``T_cam_imu`` as each camera's cam_from_rig; the default is ``"imu"`` when every camera
has ``T_cam_imu`` and ``"cam0"`` otherwise. The rig reports it as ``frame="body"`` (IMU)
or ``"camera:cam0"``; :func:`mcgeom.load_rig`'s ``frame=`` chooses any camera or an
explicit transform as well (:mod:`mcgeom.io.frame`). When a file has both ``T_cn_cnm1`` and
``T_cam_imu`` (Kalibr's camchain-imucam computes one from the other) they must agree to
1e-6 (rotation entries and metres), else the file describes two rigs and is refused.
Pixel coordinates are OpenCV's (Kalibr's corner detection is OpenCV's; its intrinsics are
used unchanged with OpenCV by everyone), so no offset is applied.

Kalibr writes the file with PyYAML's ``yaml.dump`` and reads it back with PyYAML: older
PyYAML writes leaf lists in flow style (``- [0.99, 0.01, ...]``), PyYAML >= 5.1 in block
style (``- - 0.99``), both with PyYAML's *indentless* sequences (``T_cn_cnm1:`` followed by
``- ...`` at the key's own indentation), and long flow lists wrap over several lines.
``cv2.FileStorage`` -- even with a ``%YAML:1.0`` header prepended -- rejects indentless
sequences ("Incorrect indentation"), so the file is read with PyYAML's safe loader,
restricted to plain data (:mod:`mcgeom.io._safe_yaml`): one document; anchors, aliases,
tags, duplicate keys and nesting deeper than 64 levels are refused with the line number.
"""

from __future__ import annotations

import re
from typing import Any

import numpy as np

from mcgeom.io._common import (IDENTITY_POSE, integer, make_camera, make_rig, read_text,
                               rotation, vector, describe_path)
from mcgeom.io._safe_yaml import load_yaml
from mcgeom.rig import Rig
from mcgeom.validation import numeric

__all__ = ["load_kalibr"]

_CHAIN_TOL = 1e-6           # Kalibr T_cn_cnm1 vs T_cam_imu agreement (entries, metres)
_BOTTOM_ROW_TOL = 1e-9      # last row of a 4x4 rigid transform must be [0, 0, 0, 1]


# Rigid transforms as (R, t) with X_a = R X_b + t ("a_from_b").
def _compose(a_from_b: tuple[np.ndarray, np.ndarray],
             b_from_c: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    (R1, t1), (R2, t2) = a_from_b, b_from_c
    return R1 @ R2, R1 @ t2 + t1


def _inverse(a_from_b: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    R, t = a_from_b
    return R.T, -R.T @ t


def _matrix(where: str, what: str, value: Any, shape: tuple[int, int]) -> np.ndarray:
    """A finite float matrix of the given shape."""
    try:
        arr = numeric(what, value)
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None
    if arr.shape != shape:
        raise ValueError(f"{where}: {what} must have shape {shape}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{where}: {what} has non-finite entries")
    return arr


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
    return vector(where, f"{entry}: {key}", value if value else np.zeros(0), n)


def _kalibr_transform(where: str, entry: str, key: str, value: Any) -> tuple[np.ndarray, np.ndarray]:
    """A Kalibr 4x4 homogeneous rigid transform as (R, t)."""
    what = f"{entry}: {key}"
    if not isinstance(value, list) or any(not isinstance(r, list) for r in value):
        raise ValueError(f"{where}: {what} must be a 4x4 matrix (a list of 4 rows), got {value!r}"[:300])
    T = _matrix(where, what, value, (4, 4))
    if np.max(np.abs(T[3] - [0, 0, 0, 1])) > _BOTTOM_ROW_TOL:
        raise ValueError(f"{where}: {what} is not a rigid transform: last row is {T[3].tolist()}, "
                         f"expected [0, 0, 0, 1]")
    return rotation(where, what, T[:3, :3]), T[:3, 3].copy()


def _kalibr_camera(where: str, key: str, cam: Any) -> dict:
    if not isinstance(cam, dict):
        raise ValueError(f"{where}: {key} must be a mapping, got {cam!r}"[:300])
    cm = cam.get("camera_model")
    if cm is None:
        raise ValueError(f"{where}: {key}: missing key 'camera_model'")
    if not isinstance(cm, str):  # a list or mapping would not even be a dict key below
        raise ValueError(f"{where}: {key}: camera_model must be a string, got {cm!r}"[:300])
    if cm in _KALIBR_OTHER_MODELS:
        raise ValueError(f"{where}: {key}: camera_model {cm!r} ({_KALIBR_OTHER_MODELS[cm]}) is not "
                         f"supported: mcgeom handles OpenCV pinhole and fisheye lenses only")
    if cm != "pinhole":
        raise ValueError(f"{where}: {key}: unknown camera_model {cm!r} (expected 'pinhole')")
    fu, fv, pu, pv = _kalibr_numbers(where, key, cam, "intrinsics", 4)
    dm = cam.get("distortion_model")
    if dm is None:
        raise ValueError(f"{where}: {key}: missing key 'distortion_model'")
    if not isinstance(dm, str):
        raise ValueError(f"{where}: {key}: distortion_model must be a string, got {dm!r}"[:300])
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
    width = integer(where, f"{key}: resolution width", res[0])
    height = integer(where, f"{key}: resolution height", res[1])
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
    where = describe_path(path)
    if rig_frame not in (None, "cam0", "imu"):
        raise ValueError(f"rig_frame must be 'cam0' or 'imu', got {rig_frame!r}")
    doc = load_yaml(read_text(path), where)
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
            poses.append(IDENTITY_POSE)                  # rig frame = cam0
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
        out.append(make_camera(where, c["name"], name=c["name"], K=c["K"], dist=c["dist"],
                                model=c["model"], R=R, t=t, width=c["width"], height=c["height"]))
    return make_rig(where, out, frame="body" if frame == "imu" else "camera:cam0")
