#!/usr/bin/env python3
"""atheris harness of the rig calibration loaders (mcgeom/io/).

Input: byte 0 picks one of the hand-written calibration files of
tests/data/calibration (fuzz/make_corpus.py's CALIBRATION_FILES, same
order: mcgeom JSON, OpenCV FileStorage YAML multi-camera and stereo, Kalibr
camchains, COLMAP rig JSON and legacy); byte 1 what is mutated (the file
itself, or for COLMAP its cameras.txt / images.txt, for the OpenCV stereo
layout its intrinsics.yml / extrinsics.yml); the rest is the new text. The
seeds are the original files, so libFuzzer mutates real calibrations.
Each input is loaded twice: by ``mcgeom.load_rig`` (format detection) and by
the format's own loader. Outcomes: a Rig whose cameras have finite K and
distortion, rotation extrinsics R and finite t, or ValueError /
McgeomError with a message (OSError only if the file was made unreadable,
which the harness never does, so it is a finding too).
"""
from __future__ import annotations

import os
import shutil
import sys
import tempfile
from pathlib import Path

import atheris

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
with atheris.instrument_imports(include=["mcgeom"]):
    import numpy as np

    import mcgeom
    from mcgeom import io as calibration_io

import _common  # noqa: E402

DATA = Path(__file__).resolve().parents[2] / "tests" / "data" / "calibration"
# (file, loader, format name, siblings that byte 1 may pick instead)
FILES = [
    ("mcgeom/rig4.json", calibration_io.load_mcgeom_json, "mcgeom-json", []),
    ("opencv/rig4.yml", calibration_io.load_opencv_yaml, "opencv-yaml", []),
    ("opencv/stereo_calib.yml", calibration_io.load_opencv_yaml, "opencv-yaml",
     ["opencv/stereo_calib/intrinsics.yml", "opencv/stereo_calib/extrinsics.yml"]),
    ("kalibr/camchain-equidistant.yaml", calibration_io.load_kalibr, "kalibr", []),
    ("kalibr/camchain-imucam-radtan.yaml", calibration_io.load_kalibr, "kalibr", []),
    ("colmap/rig_config.json", calibration_io.load_colmap, "colmap",
     ["colmap/cameras.txt", "colmap/images.txt"]),
    ("colmap/rig_config_legacy.json", calibration_io.load_colmap, "colmap",
     ["colmap/cameras.txt", "colmap/images.txt"]),
]
WORK = Path(tempfile.mkdtemp(prefix="mcgeom-fuzz-calib-"))
CASE = WORK / "case"
shutil.copytree(DATA, CASE)
_last: list[str] = []  # the file the previous input replaced (restored first)


def check_rig(rig, what: str) -> None:
    if not isinstance(rig, mcgeom.rig.Rig) or len(rig.cameras) < 1:
        raise _common.Finding(f"{what}: not a Rig with cameras: {rig!r}")
    for cam in rig.cameras:
        for name in ("K", "dist", "R", "t"):
            v = np.asarray(getattr(cam, name), dtype=float)
            if not np.all(np.isfinite(v)):
                raise _common.Finding(f"{what}: camera {cam.name}: non-finite {name}")
        _common.check_rotation(cam.R, f"{what}: camera {cam.name}")


def TestOneInput(data: bytes) -> None:
    if len(data) < 2:
        return
    rel, loader, fmt, siblings = FILES[data[0] % len(FILES)]
    target = rel
    if siblings and data[1] % 4 >= 2:
        target = siblings[data[1] % len(siblings)]
    # one file differs from the originals at a time: restore the previous
    # input's, write this one's (a copy of the whole tree per input halved
    # the executions)
    for prev in _last:
        shutil.copyfile(DATA / prev, CASE / prev)
    _last[:] = [target]
    (CASE / target).write_bytes(data[2:])
    path = CASE / rel
    for call, what in ((lambda: mcgeom.load_rig(path), f"load_rig({rel})"),
                       (lambda: loader(path), f"{loader.__name__}({rel})")):
        try:
            rig = call()
        except Exception as exc:  # noqa: BLE001 -- the harness classifies every exception
            if _common.allowed(exc):
                continue
            raise
        check_rig(rig, what)


def main() -> None:
    atheris.Setup(sys.argv, TestOneInput)
    atheris.Fuzz()


if __name__ == "__main__":
    main()
