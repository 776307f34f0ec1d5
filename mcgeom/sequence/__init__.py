"""The sequence pipeline: a rig's image sequence to a metric trajectory.

``tracks``: the feature tracks the front end builds and the back end uses.
"""

from .tracks import Tracks

__all__ = ["Tracks"]
