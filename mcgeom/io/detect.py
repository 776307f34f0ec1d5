"""Which calibration format a file is in, and :func:`load_rig`, which dispatches on it.

:func:`detect_format` goes by signature, not by a full parse, so that a damaged file of
a recognisable format gets that format's precise error message: a JSON object with
``"format": "mcgeom-rig"`` (mcgeom-json), a JSON list (colmap), a ``%YAML`` header or
OpenCV XML (opencv-yaml), a top-level ``cam0:`` key (kalibr). When nothing fits, the
error lists every format tried and why it was rejected.
"""

from __future__ import annotations

import json
import re
from typing import Any, Callable

from mcgeom.io._common import read_text, describe_path
from mcgeom.io.colmap import load_colmap
from mcgeom.io.frame import check_frame_spec, select_frame
from mcgeom.io.kalibr import load_kalibr
from mcgeom.io.mcgeom_json import RIG_FORMAT, load_mcgeom_json
from mcgeom.io.opencv_yaml import load_opencv_yaml
from mcgeom.rig import Rig

__all__ = ["FORMATS", "detect_format", "load_rig"]

FORMATS = ("mcgeom-json", "opencv-yaml", "kalibr", "colmap")


def _sniff(path: Any) -> tuple[str | None, str, dict[str, str]]:
    """(format or None, why it was chosen, why each format was rejected).

    Detection is by signature, not by a full parse, so that a damaged file of a
    recognisable format gets that format's precise error message.
    """
    text = read_text(path)
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
        raise ValueError(f"{describe_path(path)}: cannot tell the calibration format. Tried {tried}. "
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


def load_rig(path: Any, format: str | None = None, *, frame: Any = None, **options: Any) -> Rig:
    """Load a rig calibration in any supported format, in the rig frame you choose.

    Args:
        path: the calibration file.
        format: one of ``"mcgeom-json"``, ``"opencv-yaml"``, ``"kalibr"``, ``"colmap"``;
            None detects it from the content (:func:`detect_format`).
        frame: the rig frame of the returned rig (and so of every motion estimated with
            it): None (the format's default, table in :mod:`mcgeom.io.frame`), ``"body"``
            (the body/IMU frame, when the file has one), ``"camera:<name or index>"``
            (that camera's frame), or a 4x4 rigid transform ``T`` with ``X_rig = T[:3, :3]
            X_default + T[:3, 3]`` from the format's default frame. The returned
            :attr:`Rig.frame <mcgeom.rig.Rig.frame>` names it.
        **options: the chosen loader's keyword options: ``image_size``, ``model``,
            ``extrinsics_path`` (opencv-yaml); ``rig_frame`` (kalibr); ``cameras_txt``,
            ``images_txt``, ``rig_index`` (colmap).

    Returns:
        A :class:`mcgeom.rig.Rig` with cam_from_rig extrinsics in the chosen frame.

    Raises:
        OSError: the file cannot be opened.
        ValueError: anything wrong with the file (message names file, entry, problem); a
            ``frame`` that is malformed, names no camera of the rig, or asks for a body
            frame the file does not have (message names ``frame``).
        TypeError: an option that the format does not take.
    """
    spec = check_frame_spec(frame)
    if spec is not None and "rig_frame" in options:
        raise ValueError("pass either frame= or the Kalibr option rig_frame=, not both "
                         "(frame='body' is rig_frame='imu', frame='camera:cam0' is rig_frame='cam0')")
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
        rig = _LOADERS[fmt](path, **options)
    except ValueError as exc:
        if not why:
            raise
        raise ValueError(f"{exc} [format {fmt!r} detected from the content: {why}; pass "
                         f"format= to override]") from None
    return select_frame(rig, spec, describe_path(path), fmt)
