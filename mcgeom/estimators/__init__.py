"""Built-in estimator plugins; importing this package registers them all."""

from . import linear17  # noqa: F401  (registers "linear17")
from . import refine  # noqa: F401  (registers "refine")
from . import five_plus_one  # noqa: F401  (registers "five_plus_one")
from . import e_socp  # noqa: F401  (registers "e_socp")
from . import bnb_lp  # noqa: F401  (registers "bnb_lp")
from . import known_rotation_translation  # noqa: F401  (registers "known_rotation_translation")

__all__ = ["linear17", "refine", "five_plus_one", "e_socp", "bnb_lp", "known_rotation_translation"]
