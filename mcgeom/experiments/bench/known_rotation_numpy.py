"""Dense numpy implementation of the translation solver of thesis ch. 6 (the
same math as :mod:`mcgeom.multiview`, no structure exploited): the matrix E = A G
of eqs. 6.15/6.18 row by row, N = E^T E, L = G^T G, and the smallest
(generalized) eigenvector by numpy's dense symmetric eigensolver. The
reference of ``mcgeom bench known_rotation`` and of the tests."""

from __future__ import annotations

import numpy as np

__all__ = ["dense_rows", "dense_solve"]


def _cross(a, b):
    return np.cross(a, b)


def dense_rows(x: np.ndarray, views: np.ndarray, m: int) -> tuple[np.ndarray, np.ndarray]:
    """E (rows x 3m) of central relations ``x`` (K, q, 3) between ``views`` (K, q),
    and G^T G (3m x 3m); trilinear rows for all three reference views."""
    K, q = views.shape
    if q == 2:
        u = _cross(x[:, 0], x[:, 1])
        E = np.zeros((K, 3 * m))
        for s in range(3):
            np.add.at(E, (np.arange(K), 3 * views[:, 0] + s), -u[:, s])
            np.add.at(E, (np.arange(K), 3 * views[:, 1] + s), u[:, s])
        pairs = [(0, 1)]
    else:
        blocks = []
        for ref in range(3):
            o1, o2 = (ref + 1) % 3, (ref + 2) % 3
            xi, xj, xk = x[:, ref], x[:, o1], x[:, o2]
            u, v = _cross(xi, xj), _cross(xi, xk)
            Ek = np.zeros((K, 9, 3 * m))
            for qd in range(3):
                e = np.zeros(3)
                e[qd] = 1.0
                # M(a, b) = u (x_k x b)^T - (x_j x a) v^T, a = c_o1 - c_ref, b = c_o2 - c_ref
                Ma = -np.einsum("ks,kt->kst", _cross(xj, np.broadcast_to(e, xj.shape)), v)
                Mb = np.einsum("ks,kt->kst", u, _cross(xk, np.broadcast_to(e, xk.shape)))
                Ma, Mb = Ma.reshape(K, 9), Mb.reshape(K, 9)
                kk, ee = np.arange(K)[:, None], np.arange(9)[None, :]
                for col, val in ((o1, Ma), (o2, Mb), (ref, -(Ma + Mb))):
                    np.add.at(Ek, (kk, ee, (3 * views[:, col] + qd)[:, None]), val)
            blocks.append(Ek.reshape(-1, 3 * m))
        E = np.vstack(blocks)
        pairs = [(0, 1), (0, 2), (1, 2)]
    keys = np.unique(views, axis=0)
    L = np.zeros((m, m))
    for a, b in pairs:
        i, j = keys[:, a], keys[:, b]
        np.add.at(L, (i, i), 1.0)
        np.add.at(L, (j, j), 1.0)
        np.add.at(L, (i, j), -1.0)
        np.add.at(L, (j, i), -1.0)
    return E, np.kron(L, np.eye(3))


def dense_solve(x: np.ndarray, views: np.ndarray, m: int, solver: str) -> np.ndarray:
    """Centres (m, 3) with c_0 = 0, sum |c_i|^2 = 1 (sign not fixed)."""
    E, L = dense_rows(x, views, m)
    N = E.T @ E
    N, L = N[3:, 3:], L[3:, 3:]
    if solver == "svd":
        w, V = np.linalg.eigh(N)
        c = V[:, 0]
    else:
        C = np.linalg.cholesky(L)
        Ci = np.linalg.inv(C)
        w, V = np.linalg.eigh(Ci @ N @ Ci.T)
        c = Ci.T @ V[:, 0]
    out = np.vstack([np.zeros(3), c.reshape(-1, 3)])
    return out / np.sqrt(np.sum(out ** 2))
