"""The rig frame of a loaded calibration: which physical frame the extrinsics are in.

Each format has a natural rig frame (what its loader returns, reported by
:attr:`mcgeom.rig.Rig.frame`):

=================  ============================================  ==========================
format             default rig frame                             ``frame="body"``
=================  ============================================  ==========================
``kalibr``         ``"body"`` (the IMU) when every camera has    needs ``T_cam_imu`` on
                   ``T_cam_imu``, else ``"camera:cam0"``          every camera
``colmap``         ``"camera:<reference camera>"``               refused (no body frame)
``opencv-yaml``    multi-camera layout: as ``mcgeom-json``;      as ``mcgeom-json``;
                   stereo layout: ``"camera:cam1"``              stereo: refused
``mcgeom-json``    the ``"frame"`` the file records; else        the file's frame when no
                   ``"camera:<name>"`` if a camera sits at the   camera sits at its origin
                   origin, else ``"body"``
=================  ============================================  ==========================

:func:`select_frame` re-expresses a loaded rig in the frame the caller asks for
(``frame=`` of :func:`mcgeom.load_rig`, ``--rig-frame`` of ``mcgeom odometry``, the
``rig_frame`` column of a batch manifest): ``"body"``, ``"camera:<name or index>"``, or
an explicit 4x4 rigid transform ``T`` with ``X_rig = T[:3, :3] X_default + T[:3, 3]``
(``rig_from_default``: from the format's default frame above to the wanted one). The
motion estimated with the rig, ``rig2_from_rig1``, is then in that frame
(``R' = R_f R R_f^T``, ``t' = R_f t + (I - R') t_f``: the same physical motion).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mcgeom.rig import Rig
from mcgeom.validation import check_rotation

__all__ = ["select_frame", "check_frame_spec", "FRAME_HELP"]

FRAME_HELP = ("'body' (the body/IMU frame, when the file has one), 'camera:<name or index>' "
              "(that camera's frame), or a 4x4 rigid transform rig_from_default")

_BOTTOM_ROW_TOL = 1e-9


def check_frame_spec(frame: Any) -> Any:
    """``frame`` checked for its form (not against a rig): None, ``"body"``,
    ``"camera:<name or index>"`` or a 4x4 rigid transform (returned as float array).

    Raises:
        ValueError: anything else, naming ``frame``.
    """
    if frame is None:
        return None
    if isinstance(frame, str):
        if frame == "body" or (frame.startswith("camera:") and len(frame) > len("camera:")):
            return frame
        raise ValueError(f"frame must be {FRAME_HELP}; got {frame!r}")
    try:
        T = np.asarray(frame, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"frame must be {FRAME_HELP}; got {type(frame).__name__}") from None
    if T.ndim != 2:
        raise ValueError(f"frame must be {FRAME_HELP}; got {frame!r}"[:300])
    if T.shape != (4, 4):
        raise ValueError(f"frame: a transform must be a 4x4 matrix, got shape {T.shape}")
    if not np.all(np.isfinite(T)):
        raise ValueError("frame: the 4x4 transform has non-finite entries")
    if np.max(np.abs(T[3] - [0.0, 0.0, 0.0, 1.0])) > _BOTTOM_ROW_TOL:
        raise ValueError(f"frame: the 4x4 transform is not rigid: last row is {T[3].tolist()}, "
                         f"expected [0, 0, 0, 1]")
    try:
        check_rotation("frame: the 4x4 transform's rotation block", T[:3, :3])
    except ValueError as exc:
        raise ValueError(str(exc)) from None
    return T


def _camera_index(rig: Rig, spec: str, where: str) -> int:
    key = spec[len("camera:"):]
    if key in rig.names:
        return rig.names.index(key)
    if key.isdigit():
        idx = int(key)
        if idx < len(rig):
            return idx
    raise ValueError(f"{where}frame={spec!r}: no camera named or numbered {key!r}; the rig's "
                     f"cameras are {', '.join(f'{i}: {n!r}' for i, n in enumerate(rig.names))}")


def select_frame(rig: Rig, frame: Any, where: str = "", fmt: str = "") -> Rig:
    """``rig`` (as loaded, in its format's default frame) in the frame ``frame`` asks for.

    Args:
        rig: the rig as its loader returned it (``rig.frame`` names its frame).
        frame: None (keep the default), ``"body"``, ``"camera:<name or index>"`` or a 4x4
            rigid transform ``rig_from_default`` (module docstring).
        where: the file, for messages.
        fmt: the format, for messages.

    Raises:
        ValueError: a malformed ``frame``, an unknown camera, or ``"body"`` for a file that
            has no body frame; the message names ``frame``.
    """
    spec = check_frame_spec(frame)
    pre = f"{where}: " if where else ""
    if spec is None:
        return rig
    if isinstance(spec, np.ndarray):
        return rig.in_frame(spec[:3, :3], spec[:3, 3], frame=f"custom (X = T X_{rig.frame})")
    if spec == "body":
        if rig.frame == "body":
            return rig
        of = f" of format {fmt!r}" if fmt else ""
        raise ValueError(f"{pre}frame='body': the file{of} has no body/IMU frame (its rig frame is "
                         f"{rig.frame!r}); pass frame='camera:<name or index>' or a 4x4 "
                         f"transform rig_from_{rig.frame}")
    cam = rig.cameras[_camera_index(rig, spec, pre)]
    # the new frame is the camera's: X_cam = R_c X_rig + t_c
    return rig.in_frame(cam.R, cam.t, frame=f"camera:{cam.name}")
