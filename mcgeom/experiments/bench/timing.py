"""Timing helper shared by the benchmarks."""

from __future__ import annotations

import time
from typing import Callable

__all__ = ["best_of"]


def best_of(fn: Callable[[], object], repeat: int, number: int) -> float:
    """Best mean time per call (seconds) over ``repeat`` batches of ``number`` calls."""
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        best = min(best, (time.perf_counter() - t0) / number)
    return best
