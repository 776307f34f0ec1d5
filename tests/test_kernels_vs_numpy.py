"""The C kernels of linalg.c, plucker.c and cls.c against numpy references.

Each kernel is compared with an independent route: numpy.linalg (qr, svd,
pinv, eigh, solve), closed forms written here in numpy (Rodrigues, Hamilton
quaternions, Pluecker coordinates, the generalized epipolar rows of thesis
eq. 8.16), and for the constrained least squares (thesis Algorithms 3-4,
eq. 8.36, ch. 6.3) a second algorithm built from numpy's SVD. Matrices are
random (hypothesis-driven shapes and seeds) and deliberately ill-conditioned
(U diag(s) V^T with s from 1 down to 1e-12).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mcgeom import _core
from mcgeom.errors import DegenerateError, NumericalError

EPS = np.finfo(float).eps
SETTINGS = settings(max_examples=40, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow])

seeds = st.integers(min_value=0, max_value=2**32 - 1)
dims = st.integers(min_value=1, max_value=24)


def _rng(seed: int) -> np.random.Generator:
    return np.random.default_rng(seed)


def _orth(rng: np.random.Generator, n: int) -> np.ndarray:
    q, r = np.linalg.qr(rng.standard_normal((n, n)))
    return q * np.sign(np.diag(r))


def _with_spectrum(rng: np.random.Generator, m: int, n: int, s: np.ndarray) -> np.ndarray:
    k = min(m, n)
    return (_orth(rng, m)[:, :k] * s[:k]) @ _orth(rng, n)[:, :k].T


def _np_pinv(a: np.ndarray, rtol: float) -> np.ndarray:
    try:
        return np.linalg.pinv(a, rtol=rtol)
    except TypeError:  # numpy < 2.0
        return np.linalg.pinv(a, rcond=rtol)


def _same_up_to_sign(x: np.ndarray, y: np.ndarray) -> float:
    """max |x - sign * y| with the sign that aligns y with x."""
    sgn = 1.0 if float(x @ y) >= 0 else -1.0
    return float(np.max(np.abs(x - sgn * y)))


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def _rodrigues(w: np.ndarray) -> np.ndarray:
    th = np.linalg.norm(w)
    if th == 0:
        return np.eye(3)
    k = _skew(w / th)
    return np.eye(3) + np.sin(th) * k + (1 - np.cos(th)) * (k @ k)


def _quat_matrix(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def _random_rotation(rng: np.random.Generator) -> np.ndarray:
    return _quat_matrix(rng.standard_normal(4))


# ------------------------------------------------------------------ QR / SVD

@SETTINGS
@given(m=dims, n=dims, seed=seeds)
def test_qr_matches_numpy(m, n, seed):
    if m < n:
        m, n = n, m
    a = _rng(seed).standard_normal((m, n))
    q, r = _core.qr(a)
    assert np.abs(q @ r - a).max() <= 1e-14 * np.sqrt(m) * np.abs(a).max()
    assert np.abs(q.T @ q - np.eye(n)).max() <= 1e-14 * np.sqrt(m)
    assert np.all(np.tril(r, -1) == 0)
    q_np, r_np = np.linalg.qr(a)
    # unique up to the signs of the columns of q / rows of r (full rank)
    d = np.sign(np.diag(r)) * np.sign(np.diag(r_np))
    assert np.abs(r * d[:, None] - r_np).max() <= 1e-13 * np.abs(r_np).max()
    assert np.abs(q * d - q_np).max() <= 1e-12


def _check_svd(a: np.ndarray):
    m, n = a.shape
    k = min(m, n)
    u, s, v = _core.svd(a)
    assert u.shape == (m, k) and s.shape == (n,) and v.shape == (n, n)
    smax = max(float(s[0]), 1e-300)
    assert np.all(np.diff(s) <= 0) and np.all(s >= 0) and np.all(s[k:] == 0)
    assert np.abs((u * s[:k]) @ v[:, :k].T - a).max() <= 2e-14 * np.sqrt(m + n) * smax
    assert np.abs(u.T @ u - np.eye(k)).max() <= 2e-14 * np.sqrt(m)
    assert np.abs(v.T @ v - np.eye(n)).max() <= 2e-14 * np.sqrt(n)
    if m < n:  # the extra columns of v span the null space of a
        assert np.abs(a @ v[:, m:]).max() <= 2e-14 * np.sqrt(n) * smax
    return u, s, v


@SETTINGS
@given(m=dims, n=dims, seed=seeds)
def test_svd_random_matches_numpy(m, n, seed):
    a = _rng(seed).standard_normal((m, n))
    u, s, v = _check_svd(a)
    s_np = np.linalg.svd(a, compute_uv=False)
    k = min(m, n)
    assert np.abs(s[:k] - s_np).max() <= 4e-15 * np.sqrt(m + n) * s_np[0]


@SETTINGS
@given(m=st.integers(2, 40), n=st.integers(2, 40), seed=seeds)
def test_svd_ill_conditioned_matches_numpy(m, n, seed):
    rng = _rng(seed)
    k = min(m, n)
    s_true = np.logspace(0, -12, k)
    a = _with_spectrum(rng, m, n, s_true)
    u, s, v = _check_svd(a)
    _, s_np, vt_np = np.linalg.svd(a)
    # every singular value, the 1e-12 ones included, to ~1e-15 of s_max
    assert np.abs(s[:k] - s_np).max() <= 2e-15 * np.sqrt(k) * s_np[0]
    assert np.abs(s[:k] - s_true).max() <= 4e-15 * np.sqrt(k)
    # the leading right singular vectors (gap >= 1e-4 s_max) agree up to sign
    gaps = -np.diff(np.concatenate([[np.inf], s_np, [0.0]]))
    for j in range(k):
        gap = min(gaps[j], gaps[j + 1])
        if gap > 1e-4:
            assert _same_up_to_sign(v[:, j], vt_np[j]) <= 1e-14 / gap * np.sqrt(k)


@SETTINGS
@given(m=st.integers(3, 30), n=st.integers(3, 30), seed=seeds)
def test_svd_rank_deficient(m, n, seed):
    rng = _rng(seed)
    r = min(m, n) // 2
    a = rng.standard_normal((m, r)) @ rng.standard_normal((r, n))
    u, s, v = _check_svd(a)
    s_np = np.linalg.svd(a, compute_uv=False)
    assert np.abs(s[:min(m, n)] - s_np).max() <= 4e-15 * np.sqrt(m + n) * s_np[0]
    assert s[r:].max() <= 1e-14 * s[0]
    # null space: columns r: of v
    assert np.abs(a @ v[:, r:]).max() <= 1e-13 * s[0]


# ---------------------------------------------------------------------- pinv

@SETTINGS
@given(m=dims, n=dims, seed=seeds, deficient=st.booleans())
def test_pinv_matches_numpy(m, n, seed, deficient):
    rng = _rng(seed)
    if deficient and min(m, n) >= 2:
        r = min(m, n) - 1
        a = rng.standard_normal((m, r)) @ rng.standard_normal((r, n))
    else:
        r = min(m, n)
        a = rng.standard_normal((m, n))
    rtol = 1e-10
    x, rank = _core.pinv(a, rcond=rtol)
    assert rank == r == np.linalg.matrix_rank(a, rtol=rtol)
    x_np = _np_pinv(a, rtol)
    s_np = np.linalg.svd(a, compute_uv=False)
    cond = s_np[0] / s_np[r - 1]  # of the retained part
    k = max(m, n)
    # A^+ is determined to relative accuracy ~ eps cond(A)
    assert np.abs(x - x_np).max() <= 1e-14 * k * cond * np.abs(x_np).max()
    # Moore-Penrose conditions, relative to |A| |A^+| (= cond)
    na, nx = np.abs(a).max(), np.abs(x).max()
    tol = 1e-14 * k * na * nx
    assert np.abs(a @ x @ a - a).max() <= tol * na
    assert np.abs(x @ a @ x - x).max() <= tol * nx
    assert np.abs((a @ x).T - a @ x).max() <= tol
    assert np.abs((x @ a).T - x @ a).max() <= tol
    # default rcond = max(m, n) eps
    x0, rank0 = _core.pinv(a)
    assert rank0 == np.linalg.matrix_rank(a) or deficient


# ------------------------------------------------------------------- sym_eig

@SETTINGS
@given(n=st.integers(1, 20), seed=seeds, kind=st.sampled_from(["gauss", "psd", "clustered"]),
       method=st.sampled_from(["jacobi", "tridiag"]))
def test_sym_eig_matches_eigh(n, seed, kind, method):
    rng = _rng(seed)
    if kind == "gauss":
        b = rng.standard_normal((n, n))
        a = b + b.T
    elif kind == "psd":  # A^T A with a null space, as in the estimator
        b = rng.standard_normal((max(1, n // 2), n))
        a = b.T @ b
    else:
        w0 = np.repeat([-2.0, 1e-9, 3.0], n)[:n]
        q = _orth(rng, n)
        a = (q * w0) @ q.T
        a = 0.5 * (a + a.T)
    w, v = _core.sym_eig(a, method)
    w_np, v_np = np.linalg.eigh(a)
    na = np.abs(a).max()
    assert np.all(np.diff(w) >= 0)
    assert np.abs(w - w_np).max() <= 1e-14 * n * na
    assert np.abs(a @ v - v * w).max() <= 1e-14 * n * na
    assert np.abs(v.T @ v - np.eye(n)).max() <= 1e-14 * n
    # eigenvectors of well separated eigenvalues agree up to sign
    gaps = np.diff(np.concatenate([[-np.inf], w_np, [np.inf]]))
    for j in range(n):
        gap = min(gaps[j], gaps[j + 1])
        if gap > 1e-3 * na:
            assert _same_up_to_sign(v[:, j], v_np[:, j]) <= 1e-13 * n * na / gap


@pytest.mark.parametrize("method", ["jacobi", "tridiag"])
def test_sym_eig_uses_the_symmetric_part(method):
    rng = _rng(5)
    b = rng.standard_normal((9, 9))
    w, _ = _core.sym_eig(b, method)
    assert np.allclose(w, np.linalg.eigvalsh(0.5 * (b + b.T)), atol=1e-13)


@SETTINGS
@given(n=st.integers(1, 64), seed=seeds)
def test_spd_solve_matches_numpy(n, seed):
    rng = _rng(seed)
    b = rng.standard_normal((n, n))
    a = b.T @ b + 0.1 * np.eye(n)
    rhs = rng.standard_normal(n)
    x = _core.spd_solve(a, rhs)
    x_np = np.linalg.solve(a, rhs)
    assert np.abs(x - x_np).max() <= 1e-12 * np.linalg.cond(a) * np.abs(x_np).max()


# ----------------------------------------------------------------- rotations

angles = st.one_of(
    st.floats(0.0, np.pi),
    st.sampled_from([0.0, 1e-300, 1e-12, 1e-8, np.pi - 1e-9, np.pi - 1e-12, np.pi]),
)


@SETTINGS
@given(angle=angles, seed=seeds)
def test_rotation_helpers_vs_closed_forms(angle, seed):
    rng = _rng(seed)
    axis = rng.standard_normal(3)
    axis /= np.linalg.norm(axis)
    w = angle * axis
    R = _core.rot_from_angle_axis(w)
    assert np.abs(R - _rodrigues(w)).max() <= 4e-15
    assert np.abs(R @ R.T - np.eye(3)).max() <= 4e-15
    assert abs(np.linalg.det(R) - 1) <= 4e-15
    # angle-axis round trip; at angle pi, w and -w are the same rotation
    w2 = _core.angle_axis_from_rot(R)
    err = np.abs(w2 - w).max()
    if angle > np.pi - 1e-6:
        err = min(err, np.abs(w2 + w).max())
    assert err <= 1e-13
    assert np.linalg.norm(w2) <= np.pi + 1e-15
    # quaternion (w, x, y, z) Hamilton, q0 >= 0
    q = np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * axis])
    assert np.abs(_core.rot_from_quat(7.0 * q) - _quat_matrix(q)).max() <= 4e-15
    assert np.abs(_core.rot_from_quat(q) - R).max() <= 4e-15
    q2 = _core.quat_from_rot(R)
    assert q2[0] >= 0 and abs(np.linalg.norm(q2) - 1) <= 4e-16 * 4
    err = np.abs(q2 - q).max()
    if angle > np.pi - 1e-6:
        err = min(err, np.abs(q2 + q).max())
    assert err <= 1e-13


def test_quaternion_is_hamilton_active():
    t = 0.7
    Rz = np.array([[np.cos(t), -np.sin(t), 0], [np.sin(t), np.cos(t), 0], [0, 0, 1]])
    q = np.array([np.cos(t / 2), 0, 0, np.sin(t / 2)])
    assert np.abs(_core.rot_from_quat(q) - Rz).max() <= 1e-15
    assert np.abs(_core.rot_from_angle_axis([0, 0, t]) - Rz).max() <= 1e-15


@SETTINGS
@given(seed=seeds, noise=st.floats(0.0, 0.5), flip=st.booleans())
def test_project_so3_vs_numpy_polar(seed, noise, flip):
    rng = _rng(seed)
    M = _random_rotation(rng) + noise * rng.standard_normal((3, 3))
    if flip:
        M = -M
    u, s, vt = np.linalg.svd(M)
    if s[1] <= 1e-12 * s[0]:
        return
    d = np.sign(np.linalg.det(u @ vt))
    ref = u @ np.diag([1, 1, d]) @ vt
    R = _core.project_so3(M)
    assert abs(np.linalg.det(R) - 1) <= 1e-14
    assert np.abs(R @ R.T - np.eye(3)).max() <= 1e-14
    # as near to M as the reference (both are minimisers)
    assert np.linalg.norm(M - R) <= np.linalg.norm(M - ref) + 1e-13
    # and equal to it where the minimiser is unique: for det M > 0 when
    # s1 + s2 > 0, for det M < 0 when s1 > s2 (the flipped direction)
    gap = s[1] + s[2] if d > 0 else s[1] - s[2]
    if gap > 1e-6:
        assert np.abs(R - ref).max() <= 1e-13 / min(1.0, gap)


def test_project_so3_rank_one_is_degenerate():
    with pytest.raises(DegenerateError):
        _core.project_so3(np.outer([1.0, 2.0, 3.0], [0.5, -1.0, 2.0]))


# ------------------------------------------------------------------- plucker

def _synthetic_pairs(rng, n, R, t, central=False):
    X = rng.standard_normal((n, 3)) * 3 + [0, 0, 8]
    o1 = np.zeros((n, 3)) if central else 0.4 * rng.standard_normal((n, 3))
    o2 = np.zeros((n, 3)) if central else 0.4 * rng.standard_normal((n, 3))
    X2 = X @ R.T + t
    return o1, (X - o1) * rng.uniform(0.1, 10, (n, 1)), o2, X2 - o2


@SETTINGS
@given(n=st.integers(1, 50), seed=seeds)
def test_plucker_and_gec_rows_vs_numpy(n, seed):
    rng = _rng(seed)
    o = rng.standard_normal((n, 3))
    d = rng.standard_normal((n, 3)) * 10.0 ** rng.uniform(-3, 3, (n, 1))
    rays = _core.plucker_from_points(o, d)
    dn = d / np.linalg.norm(d, axis=1, keepdims=True)
    assert np.abs(rays[:, :3] - dn).max() <= 4e-16 * 4
    assert np.abs(rays[:, 3:] - np.cross(o, dn)).max() <= 1e-15 * 4 * (1 + np.abs(o).max())
    rays2 = _core.plucker_from_points(rng.standard_normal((n, 3)), rng.standard_normal((n, 3)))
    rows = _core.gec_rows(rays, rays2)
    d1, m1, d2, m2 = rays[:, :3], rays[:, 3:], rays2[:, :3], rays2[:, 3:]
    ref_e = np.einsum("ki,kj->kij", d2, d1).reshape(n, 9)
    ref_r = (np.einsum("ki,kj->kij", d2, m1) + np.einsum("ki,kj->kij", m2, d1)).reshape(n, 9)
    assert np.abs(rows - np.hstack([ref_e, ref_r])).max() <= 1e-15 * 8


@SETTINGS
@given(seed=seeds)
def test_gec_rows_vanish_on_the_true_motion(seed):
    rng = _rng(seed)
    R = _random_rotation(rng)
    t = rng.standard_normal(3) * 0.3
    o1, d1, o2, d2 = _synthetic_pairs(rng, 30, R, t)
    rows = _core.gec_rows(_core.plucker_from_points(o1, d1), _core.plucker_from_points(o2, d2))
    x = np.concatenate([(_skew(t) @ R).ravel(), R.ravel()])  # row-major vec
    res = rows @ x / (np.linalg.norm(rows, axis=1) * np.linalg.norm(x))
    assert np.abs(res).max() <= 1e-14
    # and the null space of the 30 x 18 system is exactly that vector
    _, s, v = _core.svd(rows)
    assert s[17] <= 1e-14 * s[0] < s[16]
    assert abs(abs(v[:, 17] @ x) / np.linalg.norm(x) - 1) <= 1e-12


# ----------------------------------------------------------------------- cls

@SETTINGS
@given(m=st.integers(8, 30), n=st.integers(2, 8), seed=seeds)
def test_cls_general_invertible_c_vs_substitution(m, n, seed):
    """C invertible: y = C x turns the problem into min |A C^-1 y|, |y| = 1."""
    rng = _rng(seed)
    A = rng.standard_normal((m, n))
    C = rng.standard_normal((n, n)) + 2 * np.eye(n)
    x, resid = _core.cls_general(A, C)
    B = A @ np.linalg.inv(C)
    _, s, vt = np.linalg.svd(B)
    y = vt[-1]
    x_ref = np.linalg.solve(C, y)
    assert abs(np.linalg.norm(C @ x) - 1) <= 1e-13
    assert abs(resid - np.linalg.norm(A @ x)) <= 1e-14 * (1 + resid)
    assert abs(resid - s[-1]) <= 1e-12 * s[0]
    gap = s[-2] - s[-1]
    assert _same_up_to_sign(x, x_ref) <= 1e-12 * s[0] / gap * np.abs(x_ref).max()


@SETTINGS
@given(m=st.integers(10, 30), n=st.integers(3, 8), k=st.integers(1, 8), seed=seeds)
def test_cls_general_wide_c_vs_generalized_eigenproblem(m, n, k, seed):
    """|A x| min on |C x| = 1 (A full column rank): resid^2 = 1 / lambda_max
    of L^-1 C^T C L^-T with A^T A = L L^T, an independent route."""
    rng = _rng(seed)
    A = rng.standard_normal((m, n))
    C = rng.standard_normal((k, n))
    x, resid = _core.cls_general(A, C)
    L = np.linalg.cholesky(A.T @ A)
    Li = np.linalg.inv(L)
    lam = np.linalg.eigvalsh(Li @ C.T @ C @ Li.T)[-1]
    assert abs(np.linalg.norm(C @ x) - 1) <= 1e-12
    assert abs(resid - 1 / np.sqrt(lam)) <= 1e-10 * resid
    # first-order optimality: A^T A x = resid^2 C^T C x; x = V_K S_K^-1 w
    # (cls.c, step 6) is accurate to ~ eps cond(C)
    sc = np.linalg.svd(C, compute_uv=False)
    cond_c = sc[0] / sc[min(k, n) - 1]
    g = A.T @ (A @ x) - resid**2 * C.T @ (C @ x)
    assert np.abs(g).max() <= 1e-14 * cond_c * m * np.abs(A).max() ** 2 * np.abs(x).max()


@SETTINGS
@given(m=st.integers(8, 30), n=st.integers(2, 8), log_d=st.floats(-15.0, -9.0), seed=seeds)
def test_cls_general_nearly_singular_c_vs_null_space_reference(m, n, log_d, seed):
    """C with one singular value d << 1 (above the rank cut): a feasible x
    gains nothing from that direction (it would need a component ~ 1 / d),
    so the minimum equals, to O(d^2), that of the problem with the direction
    moved into C's null space, which numpy solves with no small divisor.
    Found by fuzz_cls: dividing A V's columns by d (Algorithm 3 as written)
    lost up to 45 % of the minimum to the SVD's eps s_max accuracy."""
    rng = _rng(seed)
    A = rng.standard_normal((m, n))
    U, _ = np.linalg.qr(rng.standard_normal((n, n)))
    V, _ = np.linalg.qr(rng.standard_normal((n, n)))
    d = rng.uniform(0.5, 1.0, n)
    d[-1] = 10.0**log_d
    C = U @ np.diag(d) @ V.T
    x, resid = _core.cls_general(A, C)
    # reference: x = W a + v b with |diag(d[:-1]) a| = 1, b free
    W, v = V[:, :-1], V[:, -1:]
    Av = A @ v
    P = np.eye(m) - Av @ np.linalg.pinv(Av)  # (I - A v (A v)^+)
    s = np.linalg.svd(P @ A @ W / d[:-1], compute_uv=False)
    assert abs(np.linalg.norm(C @ x) - 1) <= 1e-12 * (1 + np.linalg.norm(x))
    assert abs(resid - np.linalg.norm(A @ x)) <= 1e-14 * (1 + resid) * np.linalg.norm(x)
    assert abs(resid - s[-1]) <= 1e-10 * s[0]


def test_cls_general_zero_c_is_degenerate():
    with pytest.raises(DegenerateError):
        _core.cls_general(np.ones((5, 3)), np.zeros((2, 3)))


def _partial_ref(A, p, rtol):
    """Eq. 8.36 with numpy: x1 minimises |(A2 A2^+ - I) A1 x1|, x2 = -A2^+ A1 x1."""
    A1, A2 = A[:, :p], A[:, p:]
    if A2.shape[1] == 0:
        _, s, vt = np.linalg.svd(A1)
        return vt[-1], s, 0
    A2p = _np_pinv(A2, rtol)
    M = (A2 @ A2p - np.eye(A.shape[0])) @ A1
    _, s, vt = np.linalg.svd(M)
    if M.shape[0] < p:
        s = np.concatenate([s, np.zeros(p - M.shape[0])])
    x1 = vt[-1]
    return np.concatenate([x1, -A2p @ (A1 @ x1)]), s, np.linalg.matrix_rank(A2, rtol=rtol)


@SETTINGS
@given(m=st.integers(12, 40), seed=seeds, deficient=st.integers(0, 4))
def test_cls_partial_vs_eq_8_36(m, seed, deficient):
    rng = _rng(seed)
    A = rng.standard_normal((m, 18))
    if deficient:  # A_2 = A[:, 9:] of rank 9 - deficient
        r = 9 - deficient
        A[:, 9:] = rng.standard_normal((m, r)) @ rng.standard_normal((r, 9))
    x, resid, rank2 = _core.cls_partial(A, 9)
    x_ref, s, rank_ref = _partial_ref(A, 9, 1e-10)
    assert rank2 == rank_ref == 9 - deficient
    assert abs(np.linalg.norm(x[:9]) - 1) <= 1e-14
    assert abs(resid - np.linalg.norm(A @ x)) <= 1e-14 * (1 + resid)
    assert abs(resid - np.linalg.norm(A @ x_ref)) <= 1e-12 * np.abs(A).max()
    gap = max(s[-2] - s[-1], 1e-300)
    assert _same_up_to_sign(x, x_ref) <= 1e-11 * np.abs(A).max() / gap * np.abs(x_ref).max()


def test_cls_partial_rcond_and_full_p():
    rng = _rng(11)
    A = rng.standard_normal((30, 18))
    q, _ = np.linalg.qr(rng.standard_normal((30, 9)))
    A[:, 9:] = q * np.array([1, 0.3, 0.1, 3e-2, 1e-2, 3e-3, 1e-3, 1e-4, 1e-8])
    assert _core.cls_partial(A, 9)[2] == 9
    assert _core.cls_partial(A, 9, rcond=1e-6)[2] == 8
    x, resid, _ = _core.cls_partial(A, 9, rcond=1e-6)
    x_ref, _, _ = _partial_ref(A, 9, 1e-6)
    assert _same_up_to_sign(x, x_ref) <= 1e-9
    # p = n: plain min |A x| on the unit sphere
    x, resid, rank2 = _core.cls_partial(A, 18)
    assert rank2 == 0 and abs(resid - np.linalg.svd(A, compute_uv=False)[-1]) <= 1e-13


@SETTINGS
@given(seed=seeds)
def test_cls_partial_solves_the_generalized_epipolar_system(seed):
    rng = _rng(seed)
    R = _random_rotation(rng)
    t = rng.standard_normal(3) * 0.3
    o1, d1, o2, d2 = _synthetic_pairs(rng, 40, R, t)
    rows = _core.gec_rows(_core.plucker_from_points(o1, d1), _core.plucker_from_points(o2, d2))
    x, resid, rank2 = _core.cls_partial(rows, 9)
    E = _skew(t) @ R
    x_true = np.concatenate([E.ravel(), R.ravel()]) / np.linalg.norm(E)
    assert rank2 == 9 and resid <= 1e-12
    assert _same_up_to_sign(x, x_true) <= 1e-9 / min(1.0, np.linalg.norm(t))


@SETTINGS
@given(m=st.integers(2, 30), n=st.integers(2, 12), r=st.integers(1, 14), seed=seeds,
       rank_def=st.booleans())
def test_cls_range_vs_numpy(m, n, r, seed, rank_def):
    rng = _rng(seed)
    A = rng.standard_normal((m, n))
    G = rng.standard_normal((n, r))
    if rank_def and min(n, r) >= 2:
        k = min(n, r) - 1
        G = rng.standard_normal((n, k)) @ rng.standard_normal((k, r))
    x, resid = _core.cls_range(A, G)
    u, s, _ = np.linalg.svd(G, full_matrices=False)
    U = u[:, s > 1e-12 * s[0]]
    B = A @ U
    _, sb, vt = np.linalg.svd(B)
    y = vt[-1]
    if B.shape[0] < B.shape[1]:
        sb = np.concatenate([sb, np.zeros(B.shape[1] - B.shape[0])])
    x_ref = U @ y
    assert abs(np.linalg.norm(x) - 1) <= 1e-14
    assert np.abs(U @ (U.T @ x) - x).max() <= 1e-13  # x in range(G)
    assert abs(resid - np.linalg.norm(A @ x)) <= 1e-14 * (1 + resid)
    assert abs(resid - sb[-1]) <= 1e-13 * max(1.0, sb[0])
    if len(sb) >= 2:
        gap = sb[-2] - sb[-1]
        if gap > 1e-8:
            assert _same_up_to_sign(x, x_ref) <= 1e-13 * max(1.0, sb[0]) / gap


# ------------------------------------------------------------- bad inputs

@pytest.mark.parametrize("call", [
    lambda: _core.svd(np.array([[1.0, np.nan]])),
    lambda: _core.qr(np.ones((2, 3))),                      # m < n
    lambda: _core.pinv(np.ones((2, 2)), rcond=np.nan),
    lambda: _core.sym_eig(np.array([[1.0, np.inf], [0.0, 1.0]])),
    lambda: _core.spd_solve(np.eye(65), np.ones(65)),        # n > 64
    lambda: _core.rot_from_quat(np.zeros(4)),
    lambda: _core.angle_axis_from_rot(np.diag([1.0, 1.0, 1.1])),  # not a rotation
    lambda: _core.quat_from_rot(np.diag([1.0, 1.0, -1.0])),  # det -1
    lambda: _core.plucker_from_points(np.zeros((2, 3)), np.array([[0, 0, 1.0], [0, 0, 0]])),
    lambda: _core.gec_rows(np.full((2, 6), 1e200), np.full((2, 6), 1e200)),  # overflow
    lambda: _core.cls_general(np.ones((4, 3)), np.array([[np.nan, 1, 1]])),
    lambda: _core.cls_partial(np.ones((4, 3)), 0),
    lambda: _core.cls_partial(np.ones((4, 3)), 2, rcond=np.inf),
    lambda: _core.cls_range(np.ones((4, 3)), np.full((3, 2), np.inf)),
    lambda: _core.cls_range(np.ones((4, 3)), np.zeros((3, 2))),  # G = 0
])
def test_bad_input_raises_value_error(call):
    with pytest.raises(ValueError):
        call()


def test_numerical_failures_raise_numerical_error():
    with pytest.raises(NumericalError):
        _core.spd_solve(np.array([[1.0, 2.0], [2.0, 1.0]]), np.ones(2))  # indefinite
    with pytest.raises(NumericalError):
        _core.svd(np.full((3, 3), np.finfo(float).max))  # s_max overflows
