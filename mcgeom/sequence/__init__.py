"""The sequence pipeline: a rig's image sequence to a metric trajectory.

``frontend`` (with ``features``): images to tracks with OpenCV;
``tracks``: the feature tracks the front end builds and the back end uses;
``backend``: :func:`estimate_trajectory`, tracks to a trajectory;
``trajectory``: the result (poses, steps with their scale status, segments).
"""

from .backend import estimate_trajectory
from .frontend import FrontEnd, build_tracks, overlapping_pairs, tracks_from_images
from .tracks import Tracks
from .trajectory import SCALE_STATUS, Segment, Step, Trajectory

__all__ = ["Tracks", "FrontEnd", "build_tracks", "tracks_from_images", "overlapping_pairs",
           "estimate_trajectory", "Trajectory", "Step", "Segment", "SCALE_STATUS"]
