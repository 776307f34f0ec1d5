"""Timing helper shared by the benchmarks."""

from __future__ import annotations

import time
from typing import Callable

__all__ = ["best_of"]


def best_of(fn: Callable[[], object], repeat: int, number: int,
            clock: Callable[[], float] = time.perf_counter) -> float:
    """Best mean time per call (seconds) over ``repeat`` batches of ``number`` calls.

    ``clock``: wall time by default; ``time.process_time`` (CPU time of this
    process) for single-threaded code on a shared machine, where waiting for
    a core would otherwise count."""
    best = float("inf")
    for _ in range(repeat):
        t0 = clock()
        for _ in range(number):
            fn()
        best = min(best, (clock() - t0) / number)
    return best
