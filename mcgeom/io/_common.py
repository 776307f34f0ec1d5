"""Helpers every calibration format uses: file text, messages, checked values.

Every message is ``"<file>: <entry>: <problem>"``; the checks themselves are
:mod:`mcgeom.validation`'s and :class:`mcgeom.rig.Camera`'s, only re-worded with the file
and the entry here.
"""

from __future__ import annotations

import os
from dataclasses import replace
from typing import Any

import numpy as np

from mcgeom.rig import Camera, Rig
from mcgeom.validation import check_int, check_rotation, numeric


def describe_path(path: Any) -> str:
    """The file name as messages show it."""
    return os.fspath(path)


def read_text(path: Any) -> str:
    """The file's text (UTF-8, optional BOM); ValueError naming the file if not text."""
    with open(path, "rb") as fh:
        raw = fh.read()
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ValueError(f"{describe_path(path)}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None


def make_camera(where: str, entry: str, **fields: Any) -> Camera:
    """A Camera, with Camera's own checks reported as '<file>: <entry>: <problem>'."""
    try:
        return Camera(**fields)
    except ValueError as exc:
        raise ValueError(f"{where}: {entry}: {exc}") from None


def make_rig(where: str, cameras: list[Camera], frame: str | None = None) -> Rig:
    """A Rig, with Rig's own checks (unique names, ...) reported as '<file>: <problem>'.

    ``frame``: the rig frame's label (:attr:`mcgeom.rig.Rig.frame`); None when the format
    does not say: ``"camera:<name>"`` if a camera's extrinsics are the identity (that
    camera's frame is the rig frame), else ``"body"``.
    """
    try:
        rig = Rig(tuple(cameras))
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None
    if frame is None:
        at_origin = rig.camera_at_origin()
        frame = "body" if at_origin is None else f"camera:{at_origin}"
    return replace(rig, frame=frame)


def vector(where: str, what: str, value: Any, n: int | None = None) -> np.ndarray:
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


def rotation(where: str, what: str, value: Any) -> np.ndarray:
    """:func:`mcgeom.validation.check_rotation` with the file in the message."""
    try:
        return check_rotation(what, value)
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None


def integer(where: str, what: str, value: Any) -> int:
    """:func:`mcgeom.validation.check_int` with the file in the message."""
    try:
        return check_int(what, value)
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None


# The identity rigid transform (R, t): a camera that defines the rig frame.
IDENTITY_POSE = (np.eye(3), np.zeros(3))
