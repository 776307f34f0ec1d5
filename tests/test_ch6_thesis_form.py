"""The translation solver of thesis ch. 6 against the thesis's own definitions,
written out independently of mcgeom's row code: E = A G with A = diag(S_ij)
and G stacking the fundamental matrices F_ji = [c_j - c_i]x (eqs. 6.3, 6.13,
6.18-6.19; S_ij the rows of the 8-point algorithm), or the trifocal tensors
T_i^jk = delta_i^j b^k - delta_i^k a^j of eq. 6.9 contracted as in eq. 6.10
(S_ijk); the plain variant is the last right singular vector of E once the
first centre is fixed at the origin (ch. 6.2.4), the constrained one
min |A x| s.t. |x| = 1, x = G c by Hartley-Zisserman's algorithm A5.6 (ch. 6.3).

Our trilinear blocks stack all three choices of the reference view (the
result does not depend on the order of the views), so G here stacks the
three tensors of each view triple; then |G c|^2 = 5 x the Laplacian metric
sum |c_j - c_i|^2 over the triple's pairs that mcgeom uses (2 x for the
bilinear F, |[t]x|_F^2 = 2 |t|^2): the same minimiser."""

from __future__ import annotations

import numpy as np
import pytest

from mcgeom import multiview, synth
from mcgeom.experiments.bench.known_rotation_numpy import dense_rows

EPS = np.zeros((3, 3, 3))
for _i, _j, _k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
    EPS[_i, _j, _k], EPS[_i, _k, _j] = 1.0, -1.0


def _views(seed, m=6, n_points=70, sigma=1e-3):
    """Central views with random centres/rotations; each point tracked in three
    random distinct views. Returns track, view, bearings, rotations, centres."""
    rng = np.random.default_rng(seed)
    centres = rng.normal(size=(m, 3)) * 2.0
    rotations = np.array([synth.random_rotation(rng) for _ in range(m)])
    points = rng.normal(size=(n_points, 3)) * 4.0 + np.array([0.0, 0.0, 8.0])
    view = np.concatenate([np.sort(rng.choice(m, 3, replace=False)) for _ in range(n_points)])
    track = np.repeat(np.arange(n_points), 3)
    b = np.einsum("kij,kj->ki", rotations[view], points[track] - centres[view])
    b = synth.perturb_directions(b / np.linalg.norm(b, axis=1, keepdims=True), sigma, rng)
    return track, view, b, rotations, centres


def _skew_map(m, i, j):
    """9 x 3m: c -> vec([c_j - c_i]x) (F_ji of Lemma 1)."""
    g = np.zeros((9, 3 * m))
    for q in range(3):
        e = np.zeros(3)
        e[q] = 1.0
        s = np.cross(e, np.eye(3)).T.reshape(-1)      # vec([e_q]x), row-major
        g[:, 3 * j + q] += s
        g[:, 3 * i + q] -= s
    return g


def _tensor_map(m, ref, o1, o2):
    """27 x 3m: c -> vec(T_i^jk), a = c_o1 - c_ref, b = c_o2 - c_ref (eq. 6.9)."""
    g = np.zeros((27, 3 * m))
    eye = np.eye(3)
    for q in range(3):
        e = eye[q]
        ta = -np.einsum("ik,j->ijk", eye, e).reshape(-1)    # d T / d a_q
        tb = np.einsum("ij,k->ijk", eye, e).reshape(-1)     # d T / d b_q
        g[:, 3 * o1 + q] += ta
        g[:, 3 * o2 + q] += tb
        g[:, 3 * ref + q] -= ta + tb
    return g


def thesis_AG(x, views, m):
    """Rows of A (one block per view pair / triple, stacked per relation) and
    the matching rows of G, as (list of S blocks, list of G blocks)."""
    q = views.shape[1]
    S_blocks, G_blocks = [], []
    for key in np.unique(views, axis=0):
        rel = np.flatnonzero(np.all(views == key, axis=1))
        if q == 2:
            # 8-point rows: x'^T F x = vec(x' x^T) . vec(F) (eq. 6.13)
            S_blocks.append(np.einsum("ka,kb->kab", x[rel, 1], x[rel, 0]).reshape(len(rel), 9))
            G_blocks.append(_skew_map(m, key[0], key[1]))
            continue
        for ref in range(3):
            o1, o2 = (ref + 1) % 3, (ref + 2) % 3
            xi, xj, xk = x[rel, ref], x[rel, o1], x[rel, o2]
            # eq. 6.10: x^i x'^p x''^q eps_pjs eps_qkt T_i^jk = 0_st
            S = np.einsum("ni,np,nq,pjs,qkt->nstijk", xi, xj, xk, EPS, EPS)
            S_blocks.append(S.reshape(-1, 27))
            G_blocks.append(_tensor_map(m, key[ref], key[o1], key[o2]))
    return S_blocks, G_blocks


def _gauge(c):
    c = c - c[0]
    return c / np.sqrt(np.sum(c ** 2))


@pytest.mark.parametrize("relation", multiview.RELATIONS)
def test_N_and_L_are_the_thesis_E_and_G(relation):
    track, view, b, rot, _ = _views(11)
    m, q = len(rot), 2 if relation == "bilinear" else 3
    x = np.einsum("kji,kj->ki", rot[view], b)
    idx = multiview.relations(track, view, q, "all", 1)
    S_blocks, G_blocks = thesis_AG(x[idx], view[idx], m)
    E = np.vstack([S @ G for S, G in zip(S_blocks, G_blocks)])
    GtG = sum(G.T @ G for G in G_blocks)
    E_ours, L_ours = dense_rows(x[idx], view[idx], m)
    N, N_ours = E.T @ E, E_ours.T @ E_ours
    np.testing.assert_allclose(N_ours, N, atol=1e-12 * np.abs(N).max())
    np.testing.assert_allclose((2.0 if q == 2 else 5.0) * L_ours, GtG, atol=1e-12)


@pytest.mark.parametrize("relation", multiview.RELATIONS)
@pytest.mark.parametrize("seed", [3, 4])
def test_solvers_are_kaucic_svd_and_algorithm_1(relation, seed):
    track, view, b, rot, _ = _views(seed)
    m, q = len(rot), 2 if relation == "bilinear" else 3
    x = np.einsum("kji,kj->ki", rot[view], b)
    idx = multiview.relations(track, view, q, "all", 1)
    S_blocks, G_blocks = thesis_AG(x[idx], view[idx], m)
    # gauge: first centre at the origin, i.e. drop its three columns
    E = np.vstack([S @ G for S, G in zip(S_blocks, G_blocks)])[:, 3:]
    plain = np.r_[np.zeros(3), np.linalg.svd(E)[2][-1]].reshape(-1, 3)
    # A5.6: G = U D V^T, x = U y, min |A U y| s.t. |y| = 1, c = V D^-1 y
    A = np.zeros((sum(len(S) for S in S_blocks), sum(S.shape[1] for S in S_blocks)))
    r0 = c0 = 0
    for S in S_blocks:
        A[r0:r0 + len(S), c0:c0 + S.shape[1]] = S
        r0, c0 = r0 + len(S), c0 + S.shape[1]
    G = np.vstack(G_blocks)[:, 3:]
    U, D, Vt = np.linalg.svd(G, full_matrices=False)
    y = np.linalg.svd(A @ U)[2][-1]
    constrained = np.r_[np.zeros(3), Vt.T @ (y / D)].reshape(-1, 3)
    for solver, ref in (("svd", plain), ("constrained", constrained)):
        r = multiview.translations_from_tracks(track, view, b, rot, relation=relation,
                                               solver=solver)
        ref = _gauge(ref)
        ref *= np.sign(np.sum(ref * r.centres))
        np.testing.assert_allclose(r.centres, ref, atol=1e-7)
