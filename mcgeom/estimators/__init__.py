"""Built-in estimator plugins; importing this package registers them all."""

from . import linear17  # noqa: F401  (registers "linear17")
from . import refine  # noqa: F401  (registers "refine")

__all__ = ["linear17", "refine"]
