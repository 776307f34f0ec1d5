"""The sequence pipeline: a rig's image sequence to a metric trajectory.

``tracks``: the feature tracks the front end builds and the back end uses;
``trajectory``: the result (poses, steps with their scale status, segments);
``backend``: :func:`estimate_trajectory`, tracks to a trajectory.
"""

from .backend import estimate_trajectory
from .tracks import Tracks
from .trajectory import SCALE_STATUS, Segment, Step, Trajectory

__all__ = ["Tracks", "estimate_trajectory", "Trajectory", "Step", "Segment", "SCALE_STATUS"]
