"""``mcgeom bench essential5``: the C 5-point solver against OpenCV and PoseLib.

The same random noise-free minimal problems (a camera moving by ``X2 = R X1 +
t``, rotation about 0.2 rad per axis, unit translation, five points 2-10 m in
front of both views) go to ``mcgeom._core.essential5`` (csrc/essential5.c),
OpenCV's ``findEssentialMat`` called with exactly five points (its minimal
5-point solver; image coordinates with K = I) and, when installed,
``poselib.essential_matrix_5pt``. Per solver: the fraction of problems whose
true E is among the solutions (to 1e-6, up to sign and scale), the mean
number of real solutions and the time per call through Python; for mcgeom
also the C kernel's own time (cffi call on preallocated buffers). Times are
CPU time of the process (``time.process_time``; every solver is
single-threaded), so that a loaded machine does not count its waiting.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable, Optional

import cv2
import numpy as np

from ... import _core
from ...geometry import find_essential_mat
from ..common import MissingPeerError, Progress, import_peer, no_progress
from .timing import best_of

__all__ = ["SolverRow", "random_problems", "bench_essential5"]

_CLOCK = time.process_time


@dataclass(frozen=True)
class SolverRow:
    name: str
    found: float  #: fraction of problems whose true E is among the solutions
    mean_solutions: float
    us_per_call: float  #: through Python, microseconds


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def random_problems(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``n`` noise-free minimal problems: unit bearings ``d1``, ``d2`` (n, 5, 3)
    in the camera frames at times 1 and 2, and the true E = [t]x R (n, 3, 3),
    unit Frobenius norm. Every point is in front of both views (z > 0.5 m)."""
    rng = np.random.default_rng(seed)
    d1, d2, E = np.empty((n, 5, 3)), np.empty((n, 5, 3)), np.empty((n, 3, 3))
    k = 0
    while k < n:
        R = cv2.Rodrigues(0.2 * rng.standard_normal(3))[0]
        t = rng.standard_normal(3)
        t /= np.linalg.norm(t)
        X = np.c_[rng.uniform(-2, 2, 5), rng.uniform(-2, 2, 5), rng.uniform(2, 10, 5)]
        X2 = X @ R.T + t
        if not (X2[:, 2] > 0.5).all():
            continue
        d1[k] = X / np.linalg.norm(X, axis=1, keepdims=True)
        d2[k] = X2 / np.linalg.norm(X2, axis=1, keepdims=True)
        e = _skew(t) @ R
        E[k] = e / np.linalg.norm(e)
        k += 1
    return d1, d2, E


def _opencv(a: np.ndarray, b: np.ndarray) -> list:
    p1 = a[:, :2] / a[:, 2:]
    p2 = b[:, :2] / b[:, 2:]
    E, _ = find_essential_mat(p1, p2, np.eye(3), method=cv2.RANSAC, prob=0.999,
                                threshold=1e-3)
    return [] if E is None else list(E.reshape(-1, 3, 3))


def _found(sols: list, Et: np.ndarray, tol: float = 1e-6) -> bool:
    for E in sols:
        E = np.asarray(E) / np.linalg.norm(E)
        if min(np.linalg.norm(E - Et), np.linalg.norm(E + Et)) < tol:
            return True
    return False


def _row(name: str, fn: Callable, d1, d2, Et, budget_s: float, progress: Progress) -> SolverRow:
    n = len(d1)
    found = n_sol = 0
    for k in progress(range(n), total=n, desc=name):
        sols = fn(d1[k], d2[k])
        n_sol += len(sols)
        found += _found(sols, Et[k])
    m = min(n, 200)

    def batch():
        for k in range(m):
            fn(d1[k], d2[k])

    once = best_of(batch, 1, 1, _CLOCK)
    t = best_of(batch, 3, max(1, int(budget_s / 3 / max(once, 1e-9))), _CLOCK)
    return SolverRow(name, found / n, n_sol / n, t / m * 1e6)


def kernel_us(d1: np.ndarray, d2: np.ndarray, budget_s: float = 0.5) -> float:
    """Time of the C kernel alone (microseconds per call): ``mcg_essential5``
    through cffi on preallocated buffers, so only the call overhead of cffi
    (a fraction of a microsecond) is added."""
    lib, ffi = _core.lib, _core.ffi
    m = min(len(d1), 200)
    a = [ffi.from_buffer("double[]", np.ascontiguousarray(d1[k])) for k in range(m)]
    b = [ffi.from_buffer("double[]", np.ascontiguousarray(d2[k])) for k in range(m)]
    E, ns = ffi.new("double[90]"), ffi.new("int *")
    f = lib.mcg_essential5

    def batch():
        for k in range(m):
            f(a[k], b[k], E, ns)

    once = best_of(batch, 1, 1, _CLOCK)
    return best_of(batch, 3, max(1, int(budget_s / 3 / max(once, 1e-9))), _CLOCK) / m * 1e6


def bench_essential5(problems: int = 10000, seed: int = 0, budget_s: float = 0.5,
                     progress: Progress = no_progress) -> tuple[list[SolverRow], float, Optional[str]]:
    """Rows for mcgeom, OpenCV and (if installed) PoseLib on ``problems`` random
    noise-free problems, the C kernel's own time (microseconds per call) and
    a note when PoseLib is missing (None otherwise)."""
    if problems < 1:
        raise ValueError(f"problems must be >= 1, got {problems}")
    d1, d2, Et = random_problems(problems, seed)
    rows = [_row("mcgeom", _core.essential5, d1, d2, Et, budget_s, progress),
            _row("opencv", _opencv, d1, d2, Et, budget_s, progress)]
    note = None
    try:
        poselib = import_peer("poselib", "mcgeom bench essential5")
        rows.append(_row("poselib", poselib.essential_matrix_5pt, d1, d2, Et, budget_s, progress))
    except MissingPeerError as exc:
        note = str(exc)
    return rows, kernel_us(d1, d2, budget_s), note
