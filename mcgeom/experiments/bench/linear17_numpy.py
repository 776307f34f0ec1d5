"""A straightforward numpy implementation of the linear 17-point method.

The same algorithm as ``csrc/linear17.c`` (thesis Algorithm 2 with Algorithm 4,
eq. 8.15 for t, then the refinement of ch. 8.4.3 taken to the geometric
optimum: Levenberg-Marquardt on the Sampson angular error), written the obvious
way with the explicit N x 18 matrix A, numpy.linalg and a central-difference
Jacobian (the C kernel differentiates analytically). It is the baseline of
``mcgeom bench linear17`` and an independent cross-check in the tests; it is
not used by the library itself.
"""

from __future__ import annotations

import numpy as np

__all__ = ["linear17_numpy", "skew", "exp_so3"]

_W = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


def skew(v: np.ndarray) -> np.ndarray:
    """[v]x, the 3 x 3 matrix of the cross product with v."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def exp_so3(w: np.ndarray) -> np.ndarray:
    """The rotation exp([w]x) (Rodrigues; w in radians)."""
    th = np.linalg.norm(w)
    if th < 1e-300:
        return np.eye(3)
    k = skew(w / th)
    return np.eye(3) + np.sin(th) * k + (1.0 - np.cos(th)) * k @ k


def _rows(d1, m1, d2, m2):
    n = d1.shape[0]
    ae = (d2[:, :, None] * d1[:, None, :]).reshape(n, 9)
    ar = (d2[:, :, None] * m1[:, None, :] + m2[:, :, None] * d1[:, None, :]).reshape(n, 9)
    return np.hstack([ae, ar])


def _x(R, t):
    return np.concatenate([(skew(t) @ R).ravel(), R.ravel()])


def _solve_t(A, R):
    # A x(R, t) = J t - b with J_k = A_E vec([e_k]x R), b = -A_R vec(R)  (eq. 8.15)
    J = np.stack([A[:, :9] @ (skew(e) @ R).ravel() for e in np.eye(3)], axis=1)
    b = -A[:, 9:] @ R.ravel()
    t = np.linalg.lstsq(J, b, rcond=None)[0]
    return t, float(np.sum((J @ t - b) ** 2))


def linear17_numpy(o1, d1, o2, d2, refine=True, max_iterations=100, tolerance=1e-10,
                   rank_rtol=1e-10):
    """Return (R, t, iterations) for ray correspondences in the rig frame."""
    n = o1.shape[0]
    o = (o1.sum(0) + o2.sum(0)) / (2 * n)
    rms = np.sqrt(np.mean(np.concatenate([((o1 - o) ** 2).sum(1), ((o2 - o) ** 2).sum(1)])))
    s = 1.0 / rms if rms > 1e-12 * (1 + np.linalg.norm(o)) else 1.0
    d1 = d1 / np.linalg.norm(d1, axis=1, keepdims=True)
    d2 = d2 / np.linalg.norm(d2, axis=1, keepdims=True)
    m1 = np.cross(s * (o1 - o), d1)
    m2 = np.cross(s * (o2 - o), d2)
    A = _rows(d1, m1, d2, m2)
    AE, AR = A[:, :9], A[:, 9:]
    sv = np.linalg.svd(AR, compute_uv=False)
    nullity = int(np.sum(sv ** 2 <= rank_rtol * sv[0] ** 2))
    if nullity == 0:
        x = np.linalg.svd(A, full_matrices=False)[2][-1]          # plain SVD, most-general case
        e = x[:9]
    else:                                    # Algorithm 4 / eq. 8.36
        # (A_R A_R^+ - I) A_E, applied without forming the N x N projector
        App = AR @ (np.linalg.pinv(AR, rcond=np.sqrt(rank_rtol)) @ AE) - AE
        e = np.linalg.svd(App, full_matrices=False)[2][-1]
    U, _, Vt = np.linalg.svd(e.reshape(3, 3))
    cands = []
    for W in (_W, _W.T):
        R = U @ W @ Vt
        cands.append(R if np.linalg.det(R) > 0 else -R)
    best = min(((R,) + _solve_t(A, R) for R in cands), key=lambda c: c[2])
    R, t, cost = best
    it = 0
    if refine:
        R, t, it = _refine_sampson(R, t, d1, s * (o1 - o), d2, s * (o2 - o), max_iterations,
                                   tolerance)
    t_rig = t / s + o - R @ o
    return R, t_rig, it


def _sampson(R, t, a, p, b, q):
    """Sampson angular errors (radians) of the generalized epipolar constraint
    for unit bearings a, b at origins p, q (one frame): e / sqrt(D) with
    e = b.(c x Ra), c = t + R p - q, D the squared gradient of e on both
    bearing spheres."""
    A = a @ R.T
    c = t + p @ R.T - q
    ca = np.cross(c, A)
    e = np.einsum("ij,ij->i", b, ca)
    F1 = ca - b * e[:, None]                        # P(b) F a
    F2 = np.cross(b, c) - A * e[:, None]            # R P(a) F^T b
    D = np.einsum("ij,ij->i", F1, F1) + np.einsum("ij,ij->i", F2, F2)
    return e / np.sqrt(np.maximum(D, 1e-300))


def _refine_sampson(R, t, a, p, b, q, max_iterations, tolerance):
    """Levenberg-Marquardt on the summed squared Sampson errors over
    (R <- exp([w]x) R, t <- t + dt), from (R, t); the Jacobian by central
    differences."""
    def resid(x, R0):
        return _sampson(exp_so3(x[:3]) @ R0, x[3:], a, p, b, q)

    x = np.concatenate([np.zeros(3), t])
    r = resid(x, R)
    cost, lam, it = float(r @ r), 1e-8, 0
    for it in range(1, max_iterations + 1):
        J = np.empty((len(r), 6))
        for k in range(6):
            h = np.zeros(6)
            h[k] = 1e-6 * (1.0 if k < 3 else max(1.0, np.linalg.norm(x[3:])))
            J[:, k] = (resid(x + h, R) - resid(x - h, R)) / (2 * h[k])
        H = J.T @ J
        d = np.linalg.solve(H + lam * np.diag(np.diag(H)), -J.T @ r)
        xn = x + d
        rn = resid(xn, R)
        cn = float(rn @ rn)
        if cn <= cost:
            R = exp_so3(xn[:3]) @ R
            x = np.concatenate([np.zeros(3), xn[3:]])
            dec, cost, r = cost - cn, cn, rn
            lam = max(lam * 0.1, 1e-12)
            if dec <= tolerance * cost or np.linalg.norm(d) <= 1e-12 * (1 + np.linalg.norm(x[3:])):
                break
        else:
            lam = max(lam * 10.0, 1e-6)
    return R, x[3:], it
