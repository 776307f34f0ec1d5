"""mcgeom's own rig file: JSON, format ``"mcgeom-rig"`` version 1.

Layout (written by :func:`save_mcgeom_json`, read by :func:`load_mcgeom_json`)::

    {
      "format": "mcgeom-rig",
      "version": 1,
      "frame": "body",                     # optional: the rig frame (mcgeom.rig.Rig.frame)
      "cameras": [
        {
          "name": "front",                 # unique within the rig
          "model": "pinhole",              # or "fisheye"
          "width": 1024, "height": 768,    # pixels
          "K": [[fx, s, cx], [0, fy, cy], [0, 0, 1]],
          "dist": [k1, k2, p1, p2, k3],    # OpenCV order; fisheye: [k1, k2, k3, k4]
          "R_cam_from_rig": [[...], [...], [...]],
          "t_cam_from_rig": [tx, ty, tz],  # metres
          "extrinsic_std_mm": 1.0,         # optional: 1-sigma centre error per axis, mm
          "extrinsic_std_deg": 0.05        # optional: 1-sigma rotation error per axis, deg
        }
      ]
    }

The two optional ``extrinsic_std_*`` keys state the calibration's accuracy
(:attr:`mcgeom.rig.Rig.calibration_std`); they go together, on every camera
or on none (then :data:`mcgeom.rig.DEFAULT_EXTRINSIC_STD` applies, and they
are not written).

The values are a :class:`mcgeom.rig.Camera`'s fields unchanged: cam_from_rig extrinsics
``X_cam = R X_rig + t`` (metres), OpenCV lens models and OpenCV pixel coordinates (see
:mod:`mcgeom.rig`). Keys other than these are ignored (room for comments and metadata); a
missing key, a wrong ``format``/``version`` or a malformed value is a ``ValueError`` that
names it. Floats are written by ``json`` with ``repr`` precision, so a rig round-trips
exactly.
"""

from __future__ import annotations

import json
import os
from dataclasses import replace
from typing import Any, Union

import numpy as np

from mcgeom.io._common import describe_path
from mcgeom.rig import Camera, Rig

__all__ = ["RIG_FORMAT", "RIG_FORMAT_VERSION", "rig_to_dict", "rig_from_dict",
           "load_mcgeom_json", "save_mcgeom_json"]

RIG_FORMAT = "mcgeom-rig"
RIG_FORMAT_VERSION = 1

PathLike = Union[str, "os.PathLike[str]"]

_CAMERA_KEYS = ("name", "model", "width", "height", "K", "dist", "R_cam_from_rig",
                "t_cam_from_rig")


def _camera_to_dict(cam: Camera) -> dict:
    """JSON-ready dict of one camera (one entry of the rig file's ``cameras``)."""
    return {
        "name": cam.name, "model": cam.model,
        "width": cam.width, "height": cam.height,
        "K": cam.K.tolist(), "dist": cam.dist.tolist(),
        "R_cam_from_rig": cam.R.tolist(), "t_cam_from_rig": cam.t.tolist(),
    }


def _camera_from_dict(d: Any, where: str) -> Camera:
    """Camera from a rig-file entry; ValueError naming ``where`` and the problem."""
    if not isinstance(d, dict):
        raise ValueError(f"{where} must be a JSON object, got {type(d).__name__}")
    missing = [k for k in _CAMERA_KEYS if k not in d]
    if missing:
        raise ValueError(f"{where}: missing key(s) {', '.join(map(repr, missing))}")
    try:
        return Camera(name=d["name"], K=d["K"], dist=d["dist"], model=d["model"],
                      R=d["R_cam_from_rig"], t=d["t_cam_from_rig"],
                      width=d["width"], height=d["height"])
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None


_STD_KEYS = ("extrinsic_std_mm", "extrinsic_std_deg")


def rig_to_dict(rig: Rig) -> dict:
    """JSON-ready dict of ``rig`` in the ``mcgeom-rig`` version 1 format (module docstring)."""
    cams = [_camera_to_dict(c) for c in rig.cameras]
    if rig.calibration_std is not None:
        for d, (pos, rot) in zip(cams, rig.calibration_std):
            d[_STD_KEYS[0]], d[_STD_KEYS[1]] = 1e3 * pos, float(np.degrees(rot))
    return {"format": RIG_FORMAT, "version": RIG_FORMAT_VERSION, "frame": rig.frame,
            "cameras": cams}


def _calibration_std(cams: list) -> Any:
    """The per-camera (metres, radians) of the optional ``extrinsic_std_*`` keys, or None."""
    have = [[k in c for k in _STD_KEYS] for c in cams if isinstance(c, dict)]
    if not any(any(h) for h in have):
        return None
    if not all(all(h) for h in have):
        raise ValueError(f"rig description: {_STD_KEYS[0]!r} and {_STD_KEYS[1]!r} must be "
                         "given together on every camera, or on none")
    out = []
    for i, c in enumerate(cams):
        vals = []
        for k in _STD_KEYS:
            v = c[k]
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not (
                    np.isfinite(v) and v >= 0):
                raise ValueError(f"cameras[{i}]: {k!r} must be a number >= 0, got {v!r}")
            vals.append(float(v))
        out.append((1e-3 * vals[0], float(np.radians(vals[1]))))
    return out


def rig_from_dict(d: Any) -> Rig:
    """Rig from an ``mcgeom-rig`` dict (parsed JSON); ValueError naming what is wrong."""
    if not isinstance(d, dict):
        raise ValueError(f"a rig description must be a JSON object, got {type(d).__name__}")
    for key in ("format", "version", "cameras"):
        if key not in d:
            raise ValueError(f"rig description: missing key {key!r}")
    if d["format"] != RIG_FORMAT:
        raise ValueError(f"rig description: format is {d['format']!r}, expected {RIG_FORMAT!r}")
    if d["version"] != RIG_FORMAT_VERSION or isinstance(d["version"], bool):
        raise ValueError(f"rig description: unsupported version {d['version']!r} "
                         f"(this mcgeom reads version {RIG_FORMAT_VERSION})")
    cams = d["cameras"]
    if not isinstance(cams, list):
        raise ValueError(f"rig description: 'cameras' must be a list, got {type(cams).__name__}")
    frame = d.get("frame")
    if frame is not None and (not isinstance(frame, str) or not frame):
        raise ValueError(f"rig description: 'frame' must be a non-empty string naming the rig "
                         f"frame, got {frame!r}")
    rig = Rig(tuple(_camera_from_dict(c, f"cameras[{i}]") for i, c in enumerate(cams)),
              calibration_std=_calibration_std(cams))
    if frame is None or frame == "unspecified":
        # a file without the label (or written from a rig built in code): say what
        # the extrinsics show -- a camera at the origin defines the frame
        at_origin = rig.camera_at_origin()
        frame = "body" if at_origin is None else f"camera:{at_origin}"
    return replace(rig, frame=frame)


def save_mcgeom_json(rig: Rig, path: PathLike) -> None:
    """Write ``rig`` to ``path`` as ``mcgeom-rig`` JSON (floats round-trip exactly).

    Raises:
        ValueError: ``rig`` is not a :class:`mcgeom.rig.Rig`.
        OSError: the file cannot be written.
    """
    if not isinstance(rig, Rig):
        raise ValueError(f"rig must be a mcgeom.rig.Rig, got {type(rig).__name__}")
    with open(path, "w", encoding="utf-8") as fh:
        json.dump(rig_to_dict(rig), fh, indent=2)
        fh.write("\n")


def load_mcgeom_json(path: PathLike) -> Rig:
    """Read an ``mcgeom-rig`` JSON file (layout in the module docstring).

    Returns:
        A :class:`mcgeom.rig.Rig` with cam_from_rig extrinsics (metres).

    Raises:
        OSError: the file cannot be read.
        ValueError: not JSON (truncated, malformed, nested too deeply), or not a valid rig
            description; the message names the file and the problem.
    """
    where = describe_path(path)
    with open(path, "rb") as fh:
        raw = fh.read()
    try:
        d = json.loads(raw.decode("utf-8"))
    except UnicodeDecodeError as exc:
        raise ValueError(f"{where}: not UTF-8 text ({exc.reason})") from None
    except json.JSONDecodeError as exc:
        raise ValueError(f"{where}: not valid JSON ({exc.msg} at line "
                         f"{exc.lineno} column {exc.colno})") from None
    except RecursionError:
        raise ValueError(f"{where}: JSON nested too deeply") from None
    try:
        return rig_from_dict(d)
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None
