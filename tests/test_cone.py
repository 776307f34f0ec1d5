"""mcgeom.cone_linf (csrc/cone.c, thesis eq. 9.3) against an independent
reference: bisection on the bound gamma in which clarabel (a general conic
interior-point solver, used only in tests and benchmarks) decides feasibility
of the second-order-cone problem of each step.

Reference SOCP at a fixed gamma (normalised coordinates x = (X - m) / L, m the
apex centroid, L the RMS apex distance -- the scaling of the problem, not of
an algorithm): minimise tau subject to, for every cone,
    || cos(gamma) [e1.(x - c_i), e2.(x - c_i)] || <= sin(gamma) v_i.(x - c_i) + tau
(e1, e2 an orthonormal basis of v_i's normal plane) and ||x|| <= R (the same
search ball as the kernel). gamma is feasible iff tau* < 0.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from mcgeom import _core
from mcgeom.errors import InfeasibleError

clarabel = pytest.importorskip("clarabel")
sparse = pytest.importorskip("scipy.sparse")

RADIUS = 1e6


def _angles(C, V, X):
    W = X - C
    Vn = V / np.linalg.norm(V, axis=1, keepdims=True)
    vw = (W * Vn).sum(1)
    p = np.linalg.norm(W - vw[:, None] * Vn, axis=1)
    return np.arctan2(p, vw)


def _frame(C):
    m = C.mean(0)
    L = math.sqrt(((C - m) ** 2).sum(1).mean())
    return m, (L if L > 0 else 1.0)


class ClarabelReference:
    """min_X max_i angle by bisection with clarabel deciding each step."""

    def __init__(self, C, V, radius=RADIUS):
        self.C, self.V = C, V
        self.m, self.L = _frame(C)
        self.c = (C - self.m) / self.L
        self.v = V / np.linalg.norm(V, axis=1, keepdims=True)
        n = len(C)
        # orthonormal bases of the normal planes
        a = np.where(np.abs(self.v[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
        e1 = np.cross(self.v, a)
        e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
        e2 = np.cross(self.v, e1)
        self.e1, self.e2, self.n, self.R = e1, e2, n, radius
        self.settings = clarabel.DefaultSettings()
        self.settings.verbose = False
        self.settings.tol_gap_abs = 1e-12
        self.settings.tol_gap_rel = 1e-12
        self.settings.tol_feas = 1e-12
        self.settings.max_iter = 200

    def tau(self, gamma):
        """(tau*, x*) of the feasibility SOCP at gamma."""
        cg, sg = math.cos(gamma), math.sin(gamma)
        n = self.n
        A = np.zeros((3 * n + 4, 4))
        b = np.zeros(3 * n + 4)
        for i in range(n):
            r = 3 * i
            A[r, :3], A[r, 3], b[r] = -sg * self.v[i], -1.0, -sg * self.v[i] @ self.c[i]
            A[r + 1, :3], b[r + 1] = -cg * self.e1[i], -cg * self.e1[i] @ self.c[i]
            A[r + 2, :3], b[r + 2] = -cg * self.e2[i], -cg * self.e2[i] @ self.c[i]
        A[3 * n, :], b[3 * n] = 0.0, self.R
        A[3 * n + 1:, :3] = -np.eye(3)
        P = sparse.csc_matrix((4, 4))
        q = np.array([0.0, 0.0, 0.0, 1.0])
        cones = [clarabel.SecondOrderConeT(3)] * n + [clarabel.SecondOrderConeT(4)]
        sol = clarabel.DefaultSolver(P, q, sparse.csc_matrix(A), b, cones, self.settings).solve()
        if str(sol.status) not in ("Solved", "AlmostSolved"):
            return math.nan, np.zeros(3)
        z = np.array(sol.x)
        return z[3], z[:3]

    def f(self, x):
        return _angles(self.c, self.v, x).max()

    def solve(self, tol=1e-10, max_iter=100):
        """(gamma, X, lower): bisection; the upper bound is the largest angle
        at the clarabel point of each feasible step."""
        lo, x = 0.0, np.zeros(3)
        hi = self.f(x)
        if hi >= math.pi / 2:
            t, x = self.tau(math.pi / 2)
            if t >= 0:
                return None
            hi = self.f(x)
        best = x
        for _ in range(max_iter):
            if hi - lo <= tol * max(hi, 0.01):
                break
            mid = 0.5 * (lo + hi)
            t, x = self.tau(mid)
            if t < 0:
                f = self.f(x)
                if f < hi:
                    hi, best = f, x
                else:
                    hi = mid
            else:
                lo = mid
        return hi, self.m + self.L * best, lo


def _instance(rng, n, kind):
    """Random cones: rays through a noisy common point (the usual case of
    eq. 9.2), nearly parallel axes, or nearly coincident apexes."""
    P = rng.normal(size=3)
    d = rng.uniform(0.5, 5.0, size=n)
    U = rng.normal(size=(n, 3))
    if kind == "parallel":
        U = np.array([0.0, 0.0, 1.0]) + 1e-3 * U
    noise = rng.choice([1e-4, 1e-2, 0.1])
    C = P - d[:, None] * U
    if kind == "coincident":
        C = P + 1e-6 * rng.normal(size=(n, 3))
    V = U + noise * rng.normal(size=(n, 3))
    V *= rng.uniform(0.1, 10.0, size=(n, 1))  # axes of any length
    scale = 10.0 ** rng.uniform(-3, 3)
    return scale * C, V


def test_against_clarabel_bisection():
    """Full independent bisection on 1,000 instances: bound and point."""
    rng = np.random.default_rng(1)
    worst_g = worst_x = 0.0
    count = nx = contradicted = 0
    for k in range(1000):
        n = int(rng.integers(2, 25))
        C, V = _instance(rng, n, "generic")
        ref = ClarabelReference(C, V).solve()
        try:
            r = _core.cone_linf(C, V)
        except InfeasibleError:
            assert ref is None
            continue
        assert ref is not None
        g_ref, X_ref, lo_ref = ref
        count += 1
        # the kernel's bound is attained at its point, above its own certificate
        assert abs(_angles(C, V, r["X"]).max() - r["gamma"]) <= 1e-12 * max(1.0, r["gamma"])
        assert r["gamma_lower"] <= r["gamma"]
        # the kernel is never worse than the reference point beyond the two
        # bisection tolerances (1e-10 relative each)
        assert r["gamma"] <= g_ref * (1 + 1e-9) + 1e-12
        if lo_ref > g_ref * (1 + 1e-9):
            # clarabel contradicted itself: it called a bound infeasible above
            # the value its own point attains (2 of 1,000 with clarabel
            # 0.11.1, at gamma ~ 3e-5 rad). The reference is wrong there, so
            # only the one-sided check above applies.
            contradicted += 1
            continue
        rel = abs(r["gamma"] - g_ref) / max(g_ref, 1e-3)
        worst_g = max(worst_g, rel)
        assert rel <= 1e-7, (k, r["gamma"], g_ref)
        if not r["nonunique"]:
            nx += 1
            _, L = _frame(C)
            dx = np.linalg.norm(r["X"] - X_ref) / L
            worst_x = max(worst_x, dx)
            assert dx <= 1e-6, (k, r["X"], X_ref)
    assert contradicted <= 10, contradicted  # the reference is right on >= 99 %
    print(f"clarabel bisection: {count} instances ({contradicted} where clarabel "
          f"contradicted itself), worst relative gamma "
          f"difference {worst_g:.2e}, worst X difference {worst_x:.2e} L "
          f"over the {nx} with a unique optimum")


@pytest.mark.parametrize("kind", ["generic", "parallel", "coincident"])
def test_bracket_certified_by_clarabel(kind):
    """Thousands of instances, n = 1..100: clarabel finds the cones disjoint
    just below the kernel's bound and intersecting just above it."""
    rng = np.random.default_rng({"generic": 2, "parallel": 3, "coincident": 4}[kind])
    n_inst = {"generic": 1200, "parallel": 300, "coincident": 300}[kind]
    checked = 0
    worst_rel = 0.0
    for k in range(n_inst):
        n = int(rng.integers(1, 101)) if k % 4 else int(rng.integers(1, 8))
        C, V = _instance(rng, n, kind)
        try:
            r = _core.cone_linf(C, V)
        except InfeasibleError:
            ref = ClarabelReference(C, V)
            t, _ = ref.tau(math.pi / 2 - 1e-9)
            assert t > 0, k
            continue
        g = r["gamma"]
        assert g >= r["gamma_lower"] >= 0.0 and r["converged"], k
        # gamma is the largest angle at the returned X (to the rounding of X
        # relative to its distance from the apexes)
        dist = np.linalg.norm(r["X"] - C, axis=1).min()
        cond = 1e-15 * max(np.abs(C).max(), np.abs(r["X"]).max()) / max(dist, 1e-300)
        assert (abs(_angles(C, V, r["X"]).max() - g) <= 1e-12 + cond
                or r["coincident_apexes"] or n == 1)
        if n == 1:
            assert g == 0.0 and r["nonunique"]
            continue
        if r["coincident_apexes"]:
            # the kernel solves the homogeneous (common-apex) problem exactly;
            # the SOC reference would return the apex itself (angle 0)
            continue
        m, L = _frame(C)
        # clarabel loses accuracy with a ball of 1e6 scene sizes when the
        # axes are nearly parallel (tau off by O(10)); where the kernel's
        # point is within 100 sizes a ball of 1e4 leaves the minimum unchanged
        near = np.linalg.norm(r["X"] - m) / L < 100
        ref = ClarabelReference(C, V, radius=1e4 if near else RADIUS)
        band = 1e-7 * g + 1e-10
        if r["at_infinity"]:
            # X on the search ball (|x| = 1e6 scene sizes): the sign of tau is
            # beyond clarabel's accuracy at that scale; its best point asked
            # for a bound below gamma must not achieve it
            _, x_lo = ref.tau(max(g - band, 0.0))
            assert ref.f(x_lo) >= g - band, (k, n, g, ref.f(x_lo))
            checked += 1
            continue
        if g - band > 0:
            t_lo, _ = ref.tau(g - band)
            assert t_lo > 0, (k, n, g, t_lo)
        t_hi, x_hi = ref.tau(min(g + band, math.pi / 2))
        assert t_hi < 0, (k, n, g, t_hi)
        worst_rel = max(worst_rel, (g - ref.f(x_hi)) / max(g, 1e-3))
        checked += 1
    assert worst_rel <= 1e-7
    print(f"{kind}: {checked} instances bracketed to 1e-7 relative by clarabel")


def test_known_answers():
    # rays through one point
    rng = np.random.default_rng(5)
    P = np.array([1.0, -2.0, 3.0])
    U = rng.normal(size=(7, 3))
    r = _core.cone_linf(P - 2.0 * U, U)
    assert r["gamma"] < 1e-9 and np.linalg.norm(r["X"] - P) < 1e-7
    # two skew rays: X* = (e^2, e^2, 0), tan gamma* = e / sqrt(1 + e^2)
    e = 0.7
    r = _core.cone_linf([[-1, 0, -e], [0, -1, e]], [[1, 0, 0], [0, 2, 0]])
    assert abs(r["gamma"] - math.atan(e / math.sqrt(1 + e * e))) < 1e-10
    assert np.linalg.norm(r["X"] - [e * e, e * e, 0]) < 1e-6
    assert sorted(r["active"]) == [0, 1] and not r["nonunique"]
    # n = 1
    r = _core.cone_linf([[1, 2, 3]], [[0, 0, 2]])
    assert r["gamma"] == 0 and np.allclose(r["X"], [1, 2, 4]) and r["nonunique"]
    # parallel axes: infimum at infinity
    r = _core.cone_linf([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 0, 1]] * 3)
    assert r["at_infinity"] and r["nonunique"] and r["gamma"] < 1e-5
    # coincident apexes: smallest cap around the axes
    a = 0.2
    V = [[math.sin(a) * math.cos(p), math.sin(a) * math.sin(p), math.cos(a)]
         for p in (0, 2.0943951023931953, 4.1887902047863905)]
    r = _core.cone_linf([[1, 1, 1]] * 3, V)
    assert r["coincident_apexes"] and abs(r["gamma"] - a) < 1e-9
    assert np.allclose(r["X"], [1, 1, 2], atol=1e-7)


def test_errors():
    with pytest.raises(InfeasibleError):
        _core.cone_linf([[0, 0, 0], [-10, 0, 0]], [[1, 0, 0], [-1, 0, 0]])
    with pytest.raises(ValueError, match="apexes"):
        _core.cone_linf(np.zeros((0, 3)), np.zeros((0, 3)))
    with pytest.raises(ValueError, match="apexes"):
        _core.cone_linf([[0, 0, np.nan]], [[1, 0, 0]])
    with pytest.raises(ValueError, match="axes"):
        _core.cone_linf([[0, 0, 0]], [[1, 0]])
    with pytest.raises(ValueError, match=r"axes\[1\]"):
        _core.cone_linf([[0, 0, 0], [1, 0, 0]], [[1, 0, 0], [0, 0, 0]])
    with pytest.raises(ValueError, match="axes"):
        _core.cone_linf([[0, 0, 0]], [[np.inf, 0, 0]])
    with pytest.raises(ValueError, match="max_iterations"):
        _core.cone_linf([[0, 0, 0]], [[1, 0, 0]], max_iterations=0)
    r = _core.cone_linf([[0, 0, 0], [1, 0, 0]], [[0, 0, 1], [0, 1, 1]], max_iterations=2)
    assert r["iterations"] <= 2 and not r["converged"]
