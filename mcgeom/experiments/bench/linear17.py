"""``mcgeom bench linear17``: time the C estimator against the numpy reference.

Both run the same algorithm on the same synthetic problems (a 4-camera
non-axial rig, intra-camera correspondences, 0.05 deg angular noise) for each
N; the mcgeom time is the full Python API call (RayPairs in, RigMotion out).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mcgeom import estimate, synth
from ..common import Progress, no_progress
from .linear17_numpy import linear17_numpy
from .timing import best_of

__all__ = ["Linear17Timing", "bench_linear17"]


@dataclass(frozen=True)
class Linear17Timing:
    n: int
    mcgeom_us: float
    numpy_us: float
    iterations: int

    @property
    def ratio(self) -> float:
        return self.numpy_us / self.mcgeom_us


def bench_linear17(sizes=(17, 100, 1000, 10000), seed: int = 0, budget_s: float = 0.5,
                   progress: Progress = no_progress) -> list[Linear17Timing]:
    """Time linear17 (C, via the Python API) and the numpy reference for each N
    (microseconds per call, best of batches; ``budget_s`` seconds per timing)."""
    rng = np.random.default_rng(seed)
    rig = synth.generic_rig(4, rng)
    out = []
    for n in progress(sizes, total=len(sizes), desc="linear17"):
        R, t = synth.random_motion(rng, max_angle=0.3, t_norm=0.5)
        prob = synth.make_problem(rig, R, t, n, rng, angular_noise=np.deg2rad(0.05),
                                  require_visible=False)
        rays = prob.rays
        m = estimate(rays, "linear17")
        c_once = best_of(lambda: estimate(rays, "linear17"), 1, 3)
        number = max(1, int(budget_s / 5 / max(c_once, 1e-7)))
        c_t = best_of(lambda: estimate(rays, "linear17"), 5, number)
        args = (rays.origins1, rays.dirs1, rays.origins2, rays.dirs2)
        np_once = best_of(lambda: linear17_numpy(*args), 1, 1)
        number = max(1, int(budget_s / 5 / np_once))
        np_t = best_of(lambda: linear17_numpy(*args), 5, number)
        out.append(Linear17Timing(n, c_t * 1e6, np_t * 1e6, m.info["iterations"]))
    return out
