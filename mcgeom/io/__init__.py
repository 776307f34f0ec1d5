"""Rig calibration files: one module per format (being split out of opencv_yaml.py)."""

from .opencv_yaml import (FORMATS, OPENCV_RIG_FORMAT, detect_format, load_colmap, load_kalibr,
                          load_mcgeom_json, load_opencv_yaml, load_rig, save_opencv_yaml)

__all__ = ["FORMATS", "OPENCV_RIG_FORMAT", "detect_format", "load_rig", "load_mcgeom_json",
           "load_opencv_yaml", "save_opencv_yaml", "load_kalibr", "load_colmap"]
