"""The sequence pipeline: a rig's image sequence to a metric trajectory.

``tracks``: the feature tracks the front end builds and the back end uses.
``frontend`` (with ``features``): images to tracks with OpenCV.
"""

from .frontend import FrontEnd, build_tracks, overlapping_pairs, tracks_from_images
from .tracks import Tracks

__all__ = ["Tracks", "FrontEnd", "build_tracks", "tracks_from_images", "overlapping_pairs"]
