"""Rig calibration files in the formats users have (I/O only: parsing and conventions).

Every loader returns a :class:`mcgeom.rig.Rig` whose cameras carry **cam_from_rig**
extrinsics, ``X_cam = R X_rig + t`` (docs/architecture.md §3), OpenCV lens models
(``"pinhole"``: ``cv2.projectPoints`` coefficients, ``"fisheye"``: ``cv2.fisheye``) and
OpenCV pixel coordinates (centre of the top-left pixel at ``(0, 0)``). Data flows from
here to :mod:`mcgeom.rig`, never back: ``rig`` knows nothing of files.

=================  ===========================================================  ===============
format             files                                                        module
=================  ===========================================================  ===============
``mcgeom-json``    mcgeom's own JSON (:func:`save_mcgeom_json`)                 :mod:`.mcgeom_json`
``opencv-yaml``    ``cv2.FileStorage`` YAML/XML: mcgeom's multi-camera layout    :mod:`.opencv_yaml`
                   (:func:`save_opencv_yaml`) or the stereoCalibrate layout
                   of OpenCV's stereo_calib sample
``kalibr``         Kalibr ``camchain.yaml`` / ``camchain-imucam.yaml``          :mod:`.kalibr`
``colmap``         COLMAP rig config JSON (rig_bundle_adjuster or 3.12+          :mod:`.colmap`
                   rig_configurator) + ``cameras.txt`` (+ ``images.txt``)
=================  ===========================================================  ===============

Each module's docstring gives its format's conventions and where they were checked.
:func:`load_rig` dispatches on ``format=`` or detects the format from the content
(:func:`detect_format`, in :mod:`.detect`), and returns the rig in the frame chosen with
``frame=`` (``"body"``, ``"camera:<name or index>"`` or a 4x4 transform; each format's
default and choices: :mod:`.frame`); :attr:`mcgeom.rig.Rig.frame` names it. Any problem with a file -- unreadable text,
truncated or malformed syntax, wrong format, missing key, an extrinsic that is not a
rotation, a singular ``K``, a non-positive image size, a lens model mcgeom cannot
represent, pathological nesting -- is a ``ValueError`` whose message names the file, the
entry and the problem (``OSError`` if the file cannot be opened at all). Camera-level
checks (``K``, distortion length, rotation within 1e-6 of orthonormal, image size) are
:class:`mcgeom.rig.Camera`'s own.

Trajectories (world_from_rig poses) are read and written in the TUM and KITTI formats by
:mod:`.trajectory` (:func:`read_tum`, :func:`write_tum`, :func:`read_kitti`,
:func:`write_kitti`), with the same "<file>:<line>: <problem>" errors and atomic writes.
"""

from mcgeom.io.colmap import load_colmap
from mcgeom.io.detect import FORMATS, detect_format, load_rig
from mcgeom.io.frame import select_frame
from mcgeom.io.kalibr import load_kalibr
from mcgeom.io.mcgeom_json import (RIG_FORMAT, RIG_FORMAT_VERSION, load_mcgeom_json,
                                   rig_from_dict, rig_to_dict, save_mcgeom_json)
from mcgeom.io.opencv_yaml import OPENCV_RIG_FORMAT, load_opencv_yaml, save_opencv_yaml
from mcgeom.io.trajectory import read_kitti, read_tum, write_kitti, write_tum

__all__ = [
    "load_rig", "detect_format", "FORMATS", "select_frame",
    "load_mcgeom_json", "save_mcgeom_json", "rig_to_dict", "rig_from_dict",
    "RIG_FORMAT", "RIG_FORMAT_VERSION",
    "load_opencv_yaml", "save_opencv_yaml", "OPENCV_RIG_FORMAT",
    "load_kalibr", "load_colmap",
    "read_tum", "write_tum", "read_kitti", "write_kitti",
]
