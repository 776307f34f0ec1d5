"""Hypothesis profiles for the whole suite.

``ci`` (the default): every run draws the same examples (derandomised from
each test's name and source), so a failure is reproducible from the commit
alone and a green run stays green until the code changes. ``explore``: fresh
random examples on every run (set ``MCGEOM_HYPOTHESIS_PROFILE=explore``); run
it while developing to search further, and keep what it finds as
``@example`` cases (e.g. ``test_critical_motion_reported``).
"""

import os

from hypothesis import settings

settings.register_profile("ci", derandomize=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("MCGEOM_HYPOTHESIS_PROFILE", "ci"))
