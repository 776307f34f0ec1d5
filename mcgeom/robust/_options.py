"""The options of :func:`mcgeom.robust.ransac` and their checks."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any, Optional, Union

import numpy as np

from ..validation import check_seed


#: the estimators whose minimal solver the C entry point samples
#: (``mcg_robust_options.sampler``), with their sample sizes: 5 intra-camera
#: correspondences of one camera and a sixth; 4 of any cameras with the
#: vertical known; 6 not all of one camera; 17 not all of one camera for the
#: eigensolver (Kneip and Li's, from linear17's rotation) and for linear17
#: (its motion, thesis ch. 8)
C_SAMPLERS = {"five_plus_one": 6, "upright_four_point": 4, "six_point": 6, "eigensolver": 17,
              "linear17": 17}


@dataclass(frozen=True)
class RansacOptions:
    """Options of :func:`ransac` (units: radians, or pixels when ``focal`` is given)."""

    threshold: float = 1e-3
    prob: float = 0.999
    max_iters: int = 1000
    min_iters: int = 0
    seed: Optional[int] = 0
    local_optimization: bool = True
    lo_max_rounds: int = 2
    refine: bool = True
    loss: str = "cauchy"            # final refinement (scale: the threshold)
    max_scale_rel_std: float = 0.1
    # "auto": the C entry point (csrc/robust.c) for the estimators whose
    # minimal solver it samples (C_SAMPLERS: five_plus_one,
    # upright_four_point, six_point, eigensolver, linear17), else the
    # estimator's proposer, else its minimal solver; "proposer" and "minimal"
    # force the Python drivers below
    strategy: str = "auto"          # "auto" | "proposer" | "minimal"
    max_seconds: float = 0.0        # wall-time budget of the C search (0: none)

    def __post_init__(self) -> None:
        # numbers only: a string or None would otherwise fail inside numpy
        # with a TypeError that names nothing
        for name, v in (("threshold", self.threshold), ("prob", self.prob),
                        ("maxIters", self.max_iters)):
            if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, float, np.number)):
                raise ValueError(f"{name} must be a number, got {v!r}")
        # (math on Python scalars: numpy's scalar ufuncs cost ~1 us each, and
        # these checks run once per estimate)
        if not (_finite(self.threshold) and self.threshold > 0):
            raise ValueError(f"threshold must be a positive number, got {self.threshold}")
        if not (0.0 < self.prob < 1.0):
            raise ValueError(f"prob must be in (0, 1), got {self.prob}")
        if not (_finite(self.max_iters) and self.max_iters == int(self.max_iters)):
            raise ValueError(f"maxIters must be an integer, got {self.max_iters}")
        if int(self.max_iters) < 1:
            raise ValueError(f"maxIters must be >= 1, got {self.max_iters}")
        object.__setattr__(self, "seed", check_seed(self.seed))
        if isinstance(self.max_seconds, (bool, np.bool_)) or \
                not isinstance(self.max_seconds, (int, float, np.number)) or \
                not (_finite(self.max_seconds) and 0 <= self.max_seconds <= 1e9):
            raise ValueError(f"max_seconds must be a number in [0, 1e9] (0: no limit), got "
                             f"{self.max_seconds!r}")
        if self.strategy not in ("auto", "proposer", "minimal"):
            raise ValueError(f"strategy must be 'auto', 'proposer' or 'minimal', got "
                             f"{self.strategy!r}")

    def with_seed(self, seed: Any) -> "RansacOptions":
        """These options with another ``seed`` (checked as the constructor
        checks it; the other fields were checked when these were made). A
        caller that draws a seed per estimate keeps one checked set of the
        rest (issue 19: the constructor's checks cost ~15 us of a cold
        ~0.45 ms estimate)."""
        out = object.__new__(RansacOptions)
        out.__dict__.update(self.__dict__)
        object.__setattr__(out, "seed", check_seed(seed))
        return out


@functools.lru_cache(maxsize=64, typed=True)
def _checked_options(threshold: Any, prob: Any, max_iters: Any) -> RansacOptions:
    return RansacOptions(threshold=threshold, prob=prob, max_iters=max_iters)


def ransac_options(threshold: Any, prob: Any, max_iters: Any, seed: Any) -> RansacOptions:
    """``RansacOptions(threshold=..., prob=..., max_iters=..., seed=...)``,
    the first three checked once per distinct set (typed: ``True`` is no
    ``1``), the seed -- often a new one per estimate -- set on a copy
    (:meth:`RansacOptions.with_seed`): the constructor's checks cost ~15 us
    of a ~0.5 ms estimate (issue 19). Unhashable arguments are checked
    afresh (and named) every time. The same ValueError as the constructor
    on a bad value."""
    try:
        base = _checked_options(threshold, prob, max_iters)
    except TypeError:           # unhashable: no cache
        return RansacOptions(threshold=threshold, prob=prob, max_iters=max_iters, seed=seed)
    return base if type(seed) is int and seed == base.seed else base.with_seed(seed)


def _finite(v: Any) -> bool:
    """Is the real number ``v`` finite (an int too large for a float is not)?"""
    try:
        return math.isfinite(v)
    except OverflowError:
        return False


def focal_array(focal: Union[None, float, np.ndarray], n: int) -> Optional[np.ndarray]:
    """``focal`` (pixels per radian: one value or ``n``) as ``n`` positive
    finite float64s, C-contiguous; None stays None (radians). ValueError
    otherwise."""
    if focal is None:
        return None
    f = np.asarray(focal, dtype=np.float64)
    if f.ndim == 0:
        f = np.full(n, float(f))
    # min > 0 and max < inf: NaN fails both (two reductions, no temporaries)
    if f.shape != (n,) or (n and not (f.min() > 0 and f.max() < np.inf)):
        raise ValueError(f"focal must be a positive number or {n} positive numbers")
    # (C-contiguous: the C search takes it as it is, prechecked)
    return np.ascontiguousarray(f)
