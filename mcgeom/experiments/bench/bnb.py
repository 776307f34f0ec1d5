"""``mcgeom bench bnb``: the branch and bound of thesis ch. 10 (csrc/bnb.c).

The ch. 10.5.1 set-up: cameras on a ring looking outward, ``pts`` points per
camera, Gaussian pixel noise, a random motion of 5-20 deg; the search to a
rotation resolution (default 1e-4 rad) from the ``refine`` estimate. Printed:
median search time (the C call, with and without the final polish), the CPU
time of the whole estimator call (``bnb_lp`` with its polish, Python included;
process time, so other load on the machine does not inflate it), blocks,
LPs and time per LP; the same search with the GLPK backend (same start, same
decisions) and the time ratio GLPK / native; and how the time grows with the
number of points and of cameras. The thesis's figure for 4 cameras x 50
points: about 3.5 s (C++ and GLPK, Core 2).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Optional

import numpy as np

from mcgeom import estimate, registry, synth

from ..common import Progress, no_progress

__all__ = ["BnbTiming", "bench_bnb", "growth"]


@dataclass(frozen=True)
class BnbTiming:
    cams: int
    pts: int
    search_s: float          # median C time of the search, polish off
    total_s: float           # median C time with the polish
    blocks: float
    lps: float
    us_per_lp: float
    glpk_s: Optional[float]  # median C time of the same search with GLPK
    estimator_cpu_s: float = float("nan")  # median CPU time of the estimator call

    @property
    def glpk_ratio(self) -> Optional[float]:
        return None if self.glpk_s is None else self.glpk_s / self.search_s


def _problems(cams: int, pts: int, noise: float, n: int, seed: int):
    rig = synth.ring_rig(cams)
    rng = np.random.default_rng(seed)
    for _ in range(n):
        R, t = synth.random_motion_between(rng, np.radians(5), np.radians(20), 0.5, 1.5)
        yield synth.make_problem(rig, R, t, cams * pts, rng, pixel_noise=noise)


def bench_bnb(cams: int = 4, pts: int = 50, noise: float = 0.5, problems: int = 10,
              resolution: float = 1e-4, glpk: bool = True, seed: int = 0,
              progress: Progress = no_progress) -> BnbTiming:
    """Medians over ``problems`` problems (see the module docstring); ``noise`` in
    pixels, ``resolution`` in radians, times in seconds."""
    rows = []
    use_glpk = glpk and "glpk" in registry.lp_backends()
    for p in progress(_problems(cams, pts, noise, problems, seed), total=problems,
                      desc=f"bnb {cams} cams x {pts} pts"):
        start = estimate(p.rays, "refine")
        kw = dict(initial=start, resolution=resolution)
        a = estimate(p.rays, "bnb_lp", polish=False, lp_backend="native", **kw).info
        c0 = time.process_time()
        b = estimate(p.rays, "bnb_lp", polish=True, lp_backend="native", **kw).info
        cpu = time.process_time() - c0
        g = (estimate(p.rays, "bnb_lp", polish=False, lp_backend="glpk", **kw).info
             if use_glpk else None)
        lps = a["lps_2var"] + a["lps_3var"]
        rows.append((a["seconds"], b["seconds"], a["blocks"], lps,
                     1e6 * a["seconds"] / max(lps, 1), g["seconds"] if g else np.nan, cpu))
    r = np.array(rows)
    med = np.median(r, axis=0)
    return BnbTiming(cams, pts, med[0], med[1], med[2], med[3], med[4],
                     None if not use_glpk else float(med[5]), float(med[6]))


def growth(points=(25, 50, 100, 200), cameras=(2, 4, 6, 8), problems: int = 5,
           noise: float = 0.5, resolution: float = 1e-4,
           progress: Progress = no_progress) -> list[BnbTiming]:
    """Search times for 4 cameras x ``points`` and for ``cameras`` x 50 points."""
    out = [bench_bnb(4, n, noise, problems, resolution, glpk=False, progress=progress)
           for n in points]
    out += [bench_bnb(m, 50, noise, problems, resolution, glpk=False, progress=progress)
            for m in cameras if m != 4]
    return out
