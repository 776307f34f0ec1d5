"""``mcgeom bench cone``: time the L-infinity cone kernel (csrc/cone.c, thesis
eq. 9.3) against a bisection whose feasibility steps are solved by clarabel.

Both solve the same instances (rays towards a common point with 0.01 rad of
axis noise, the shape of the thesis's ch. 9 translation problem) to the same
bound tolerance (1e-10 relative); the mcgeom time is the full Python API call
(``mcgeom._core.cone_linf``). clarabel is a test/benchmark dependency only
(``pip install clarabel``), imported lazily here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mcgeom import _core

from ..common import Progress, import_peer, no_progress
from .timing import best_of

__all__ = ["ConeTiming", "bench_cone", "clarabel_cone_linf"]


@dataclass(frozen=True)
class ConeTiming:
    n: int
    mcgeom_us: float
    clarabel_us: float
    gamma_rel_diff: float
    steps_mcgeom: int
    steps_clarabel: int

    @property
    def ratio(self) -> float:
        return self.clarabel_us / self.mcgeom_us


def _import_clarabel():
    # benchmark-only dependencies: a clear MissingPeerError (exit 2 from the CLI)
    clarabel = import_peer("clarabel", "mcgeom bench cone")
    sparse = import_peer("scipy.sparse", "mcgeom bench cone", "scipy")
    return clarabel, sparse


def clarabel_cone_linf(C: np.ndarray, V: np.ndarray, tol: float = 1e-10,
                       radius: float = 1e6, max_iter: int = 100):
    """The same problem by bisection on gamma, clarabel solving at each step
    min tau s.t. |cos(g) P_i (x - c_i)| <= sin(g) v_i.(x - c_i) + tau,
    |x| <= radius (normalised coordinates). Returns (gamma, X, steps)."""
    clarabel, sparse = _import_clarabel()
    m = C.mean(0)
    L = math.sqrt(((C - m) ** 2).sum(1).mean()) or 1.0
    c = (C - m) / L
    v = V / np.linalg.norm(V, axis=1, keepdims=True)
    a = np.where(np.abs(v[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
    e1 = np.cross(v, a)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(v, e1)
    n = len(C)
    st = clarabel.DefaultSettings()
    st.verbose = False
    st.tol_gap_abs = st.tol_gap_rel = st.tol_feas = 1e-12
    P = sparse.csc_matrix((4, 4))
    q = np.array([0.0, 0.0, 0.0, 1.0])
    cones = [clarabel.SecondOrderConeT(3)] * n + [clarabel.SecondOrderConeT(4)]
    vc, e1c, e2c = (v * c).sum(1), (e1 * c).sum(1), (e2 * c).sum(1)

    def f(x):
        W = x - c
        vw = (W * v).sum(1)
        return np.arctan2(np.linalg.norm(W - vw[:, None] * v, axis=1), vw).max()

    def tau(g):
        cg, sg = math.cos(g), math.sin(g)
        A = np.zeros((3 * n + 4, 4))
        b = np.zeros(3 * n + 4)
        A[0:3 * n:3, :3], A[0:3 * n:3, 3], b[0:3 * n:3] = -sg * v, -1.0, -sg * vc
        A[1:3 * n:3, :3], b[1:3 * n:3] = -cg * e1, -cg * e1c
        A[2:3 * n:3, :3], b[2:3 * n:3] = -cg * e2, -cg * e2c
        b[3 * n] = radius
        A[3 * n + 1:, :3] = -np.eye(3)
        sol = clarabel.DefaultSolver(P, q, sparse.csc_matrix(A), b, cones, st).solve()
        z = np.array(sol.x)
        return z[3], z[:3]

    lo, x = 0.0, np.zeros(3)
    hi, best, steps = f(x), x, 0
    if hi >= math.pi / 2:
        t, x = tau(math.pi / 2)
        steps += 1
        if not t < 0:
            return None, None, steps
        hi, best = f(x), x
    while steps < max_iter and hi - lo > tol * max(hi, 0.01):
        mid = 0.5 * (lo + hi)
        t, x = tau(mid)
        steps += 1
        if t < 0:
            fx = f(x)
            if fx < hi:
                hi, best = fx, x
            else:
                hi = mid
        else:
            lo = mid
    return hi, m + L * best, steps


def _instance(rng, n):
    P = rng.normal(size=3)
    U = rng.normal(size=(n, 3))
    C = P - rng.uniform(1.0, 5.0, size=n)[:, None] * U
    V = U + 0.01 * rng.normal(size=(n, 3))
    return C, V


def bench_cone(sizes=(3, 6, 20, 100, 1000), seed: int = 0, budget_s: float = 0.5,
               progress: Progress = no_progress) -> list[ConeTiming]:
    """Time cone_linf (C via the Python API) and the clarabel bisection
    (microseconds per call; ``budget_s`` seconds per timing)."""
    _import_clarabel()
    rng = np.random.default_rng(seed)
    out = []
    for n in progress(sizes, total=len(sizes), desc="cone"):
        C, V = _instance(rng, n)
        r = _core.cone_linf(C, V)
        once = best_of(lambda: _core.cone_linf(C, V), 1, 3)
        number = max(1, int(budget_s / 5 / max(once, 1e-7)))
        c_t = best_of(lambda: _core.cone_linf(C, V), 5, number)
        g_ref, _, steps = clarabel_cone_linf(C, V)
        ref_once = best_of(lambda: clarabel_cone_linf(C, V), 1, 1)
        number = max(1, int(budget_s / 3 / ref_once))
        ref_t = best_of(lambda: clarabel_cone_linf(C, V), 3, number)
        out.append(ConeTiming(n, c_t * 1e6, ref_t * 1e6,
                              abs(r["gamma"] - g_ref) / max(g_ref, 1e-3),
                              r["iterations"], steps))
    return out
