"""LP feasibility backends (csrc/lp_*.c) through mcgeom._core.lp_feasible.

The C test (csrc/tests/test_lp.c) checks the native solver against brute-force
vertex enumeration; here the Python wrapper is checked against an independent
reference (scipy's HiGHS when available) on random instances, plus the
wrapper's argument checks.
"""

from __future__ import annotations

import numpy as np
import pytest

from mcgeom import _core


def _margin_lp(A, b):
    """max delta s.t. A_k x >= b_k + delta |A_k|, delta <= 1 (scipy HiGHS)."""
    linprog = pytest.importorskip("scipy.optimize").linprog
    m, d = A.shape
    nrm = np.linalg.norm(A, axis=1)
    # variables (x, delta): minimise -delta; -A x + |A| delta <= -b
    res = linprog(np.r_[np.zeros(d), -1.0], A_ub=np.c_[-A, nrm], b_ub=-b,
                  bounds=[(-1e6, 1e6)] * d + [(None, 1.0)], method="highs")
    assert res.status == 0
    return -res.fun


@pytest.mark.parametrize("d", [2, 3])
def test_random_against_reference(d):
    rng = np.random.default_rng(d)
    n_feas = n_checked = 0
    for trial in range(300):
        m = int(rng.integers(1, 40))
        A = rng.normal(size=(m, d))
        x0 = rng.normal(size=d)
        b = A @ x0 + rng.normal(size=m) * 0.5 - 0.4
        x = _core.lp_feasible(A, b)
        margin = _margin_lp(A, b)
        if abs(margin) < 1e-6:
            continue
        n_checked += 1
        assert (x is not None) == (margin > 0), (trial, margin)
        if x is not None:
            n_feas += 1
            S = max(1.0, np.max(np.abs(b) / np.linalg.norm(A, axis=1)))
            assert np.all(A @ x >= b - 2.001e-9 * S * np.linalg.norm(A, axis=1))
    assert 0.2 * n_checked < n_feas < 0.8 * n_checked


def test_known_and_invalid():
    assert _core.lp_feasible(np.zeros((0, 3)), np.zeros(0)) is not None
    assert _core.lp_feasible([[1.0, 0.0], [-1.0, 0.0]], [1.0, 0.0]) is None
    x = _core.lp_feasible([[1.0, 0.0, 0.0]], [1.0])
    assert x is not None and x[0] >= 1.0 - 1e-8
    with pytest.raises(ValueError):
        _core.lp_feasible(np.ones((2, 4)), np.ones(2))
    with pytest.raises(ValueError):
        _core.lp_feasible([[np.nan, 0.0]], [1.0])
    with pytest.raises(ValueError):
        _core.lp_feasible([[1.0, 0.0]], [1.0, 2.0])
    with pytest.raises(ValueError):
        _core.lp_feasible([[1.0, 0.0]], [1.0], backend="nope")


@pytest.mark.skipif("glpk" not in _core.LP_BACKENDS, reason="built without GLPK")
@pytest.mark.parametrize("d", [2, 3])
def test_glpk_agrees_with_native(d):
    rng = np.random.default_rng(10 + d)
    for _ in range(300):
        m = int(rng.integers(1, 60))
        A = rng.normal(size=(m, d))
        b = A @ rng.normal(size=d) + rng.normal(size=m) * 0.5 - 0.4
        if abs(_margin_lp(A, b)) < 1e-6:
            continue
        xn = _core.lp_feasible(A, b)
        xg = _core.lp_feasible(A, b, backend="glpk")
        assert (xn is None) == (xg is None)
