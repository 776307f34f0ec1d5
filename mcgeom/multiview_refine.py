"""Maximum-likelihood centres of views with known rotations: the algebraic
solution of thesis ch. 6 refined by a bundle adjustment of the centres and
the tracks' points, the rotations held, on angular residuals.

Why. With a rig's camera offsets (ch. 4.2) the relations of ch. 6 (eqs. 6.5,
6.11) are inhomogeneous and fix the centres in metres, but their least
squares weigh each relation by the size of its coefficients, not by its
noise: the pull toward short translations that the two-view case showed
(``known_rotation_translation``, whose linear |t| came out 6-51 % short).
Measured by ``mcgeom experiment ch6_rig_scale``: a 4-camera ring without
overlap (radius 0.5 m, f = 800 px, 0.5 px noise) driving 6 steps of 1 m,
turning 0.5, 2, 10 or 20 deg per step, 20 sequences each: the algebraic
centres' travelled distance came out 94, 50, 8.5 and 6.3 % short (median;
bilinear relations; trilinear 98, 77, 17, 11 %) at first-order relative
stds of 0.07-4.6 %, and all 160 were called metric, every one more than 3
of its stds off. After this refinement the median errors are within 0.9 %,
no answer is more than 3 stds off, and the RMS of error / std is 0.72-1.23.

The refinement minimises the sum over observations of the squared angular
residual between the observed bearing and the direction from the ray's origin
to its track's point (its two tangent-plane components, radians: the
measurement's own error, unlike the algebraic residuals), over the centres of
the views after the gauge view (held where the algebraic solution put it) and
the tracks' points. Levenberg-Marquardt on the normal equations reduced to
the centres by the Schur complement of the points' 3 x 3 blocks (Triggs et
al., "Bundle adjustment -- a modern synthesis", 2000, sec. 6.1); the reduced
system is stored and factored in the skyline form of :mod:`mcgeom.multiview`
(two views are coupled when they see a common track). Its inverse times the
residual variance is the first-order covariance of the centres, from which
the caller judges the metric scale.

The rotations are taken as exact by the covariance itself; their errors
enter through ``CentresFit.rotation_term`` (the centres' first-order shift
per rotation error, by the implicit function theorem at the optimum), which
:func:`mcgeom.multiview.translations_from_tracks` turns into the scale's std
for a given ``rotation_std``. Measured on the ring turning 2 or 10 deg a
step, every view's rotation turned by 0.01 or 0.05 deg about a random axis
(20 sequences each): taken as exact, 3-5 (0.01 deg) and 12-14 (0.05 deg) of
20 were more than 3 stds off, RMS error/std 1.9-2.2 and 7.3-7.6, 5 metric
and wrong at 2 deg / 0.05 deg; with ``rotation_std`` equal to the error,
none, RMS 0.53-0.59 (conservative: the error's std about each axis is
1/sqrt(3) of it). On KITTI-00 with the ground-truth rotations, taken as
exact, the path came out 1.0 % short at a relative std of 0.02 %
(``mcgeom experiment ch6_kitti``).

Tracks are taken as outlier-free (the sequence back end drops the outliers of
each step first). A track whose rays are parallel (no parallax: its point
does not constrain the centres), or whose point falls behind one of its rays
at the starting centres, is left out.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Optional

import numpy as np

from . import _core
from .errors import NumericalError
from .geometry import line_normal_equations

__all__ = ["CentresFit", "refine_centres", "covisible_profile", "MAX_TRACK_PAIRS"]

#: pairs of (track, view) entries of one track (the Schur complement's terms,
#: 8 bytes each) at most, over all tracks: a memory guard
MAX_TRACK_PAIRS = 50_000_000

#: pairs whose 3 x 3 terms are formed at a time (~100 MB of temporaries)
PAIR_CHUNK = 1 << 19

#: a track's rays are parallel (no parallax) when the smallest eigenvalue of
#: sum (I - x x^T) is below this fraction of its largest (two rays ~0.001 deg apart)
PARALLEL_EIG = 1e-10

#: a point's 3 x 3 information gets this fraction of its trace on the
#: diagonal before it is inverted: a point whose rays became parallel during
#: the iterations (depth unconstrained) then moves only where its rays say,
#: and its block stays invertible; 1e-12 changes no well-conditioned point
POINT_RIDGE = 1e-12

#: relative decrease of the cost below which the iterations stop
COST_TOL = 1e-12

#: a fit that reaches max_iterations still counts as converged when its last
#: step lowered the cost by less than STAT_TOL sigma^2 (sigma^2 = 2 cost / dof):
#: the cost's excess over the optimum is then ~sigma^2 |d|^2 / 2 with the
#: distance |d| ~ 1e-3 of a standard deviation. Measured: on the ring turning
#: 20 deg a step, 3 of 40 fits crept on by 1e-12 to 1e-10 of the cost a step
#: up to the 50-step cap, and were refused as unconverged though their stds
#: held (mcgeom experiment ch6_rig_scale)
STAT_TOL = 1e-6


@dataclass(frozen=True)
class CentresFit:
    """The refined centres and their information.

    ``centres`` (ms, 3): world frame, metres, in the order of the solved
    views (the first, the gauge view, where it was given). ``first``/``ptr``/
    ``chol``: the skyline Cholesky factor of the reduced information matrix
    (undamped, at the optimum) of the 3 (ms - 1) unknown centre coordinates
    (view position 1.., then x y z), so that ``sigma2`` times its inverse is
    their covariance (metres^2). ``sigma2``: residual variance per angular
    component (rad^2) over ``dof`` = 2 n_observations - 3 n_points - 3 (ms - 1)
    degrees of freedom; ``rms`` the RMS angular component (radians).
    ``points`` (n_points, 3): the tracks' points (world frame, metres) of the
    track labels ``point_tracks``. ``rotation_term(y)``: for a vector y of the
    unknown centre coordinates, G^T y (ms, 3), where -S^-1 G is the first-order
    shift of the centres per rotation error of each view (radians about the
    world axes, applied to its bearings and offsets): the derivative of a
    function of the centres with gradient g is -(G^T S^-1 g) per view and axis.
    """
    centres: np.ndarray
    points: np.ndarray
    point_tracks: np.ndarray
    first: np.ndarray
    ptr: np.ndarray
    chol: np.ndarray
    sigma2: float
    rms: float
    iterations: int
    converged: bool
    n_observations: int
    n_points: int
    dof: int
    rotation_term: Callable[[np.ndarray], np.ndarray] = field(repr=False, compare=False,
                                                              default=None)


def _tangent_bases(x: np.ndarray) -> np.ndarray:
    """(K, 2, 3): two unit vectors orthogonal to each unit bearing (rows)."""
    axis = np.zeros_like(x)
    axis[np.arange(len(x)), np.argmin(np.abs(x), axis=1)] = 1.0
    b1 = np.cross(axis, x)
    b1 /= np.linalg.norm(b1, axis=1, keepdims=True)
    return np.stack([b1, np.cross(x, b1)], axis=1)


def _sum_by(index: np.ndarray, values: np.ndarray, size: int) -> np.ndarray:
    """Sums of ``values`` (K, ...) grouped by ``index`` (K,) into ``size`` rows."""
    flat = values.reshape(len(values), -1)
    out = np.empty((size, flat.shape[1]))
    for j in range(flat.shape[1]):
        out[:, j] = np.bincount(index, weights=flat[:, j], minlength=size)
    return out.reshape((size,) + values.shape[1:])


def _lower_pairs(group: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The pairs (i, j) of entries of one group (``group`` sorted), i at or
    after j: the lower triangle of each group's block, the diagonal included
    (int32 indices)."""
    starts = np.flatnonzero(np.r_[True, group[1:] != group[:-1]])
    lengths = np.diff(np.r_[starts, len(group)])
    total = int(np.sum(lengths.astype(np.int64) * (lengths + 1) // 2))
    if total > MAX_TRACK_PAIRS:
        raise ValueError(f"the tracks give {total} pairs of views (more than "
                         f"{MAX_TRACK_PAIRS}) for the bundle adjustment: split long tracks")
    a, b = [], []
    for length in np.unique(lengths):
        i, j = np.tril_indices(int(length))
        s = starts[lengths == length].astype(np.int32)
        a.append((s[:, None] + i[None, :].astype(np.int32)).reshape(-1))
        b.append((s[:, None] + j[None, :].astype(np.int32)).reshape(-1))
    return np.concatenate(a), np.concatenate(b)


def _triangulate(x: np.ndarray, a: np.ndarray, tid: np.ndarray, n_points: int
                 ) -> tuple[np.ndarray, np.ndarray]:
    """The least-squares point of the rays ``a + s x`` of each track (nearest to
    them all) and whether it is usable: rays not parallel, point in front of
    every ray."""
    A, rhs = line_normal_equations(tid, a, x, n_points)
    ev = np.linalg.eigvalsh(A)
    ok = ev[:, 0] > PARALLEL_EIG * ev[:, 2]
    X = np.zeros((n_points, 3))
    X[ok] = np.linalg.solve(A[ok], rhs[ok][:, :, None])[:, :, 0]
    depth = np.einsum("ki,ki->k", X[tid] - a, x)
    behind = np.bincount(tid, weights=(depth <= 0.0).astype(float), minlength=n_points)
    return X, ok & (behind == 0)


class _Structure:
    """The fixed structure of one refinement: the observations used, their
    (track, view) entries and the envelope positions of the Schur terms."""

    def __init__(self, tid, vp, x, w, ms, first, ptr):
        self.tid, self.vp, self.w, self.ms = tid, vp, w, ms
        self.first, self.ptr = first, ptr
        self.n_pts = int(tid.max()) + 1
        self.B = _tangent_bases(x)
        # (track, view) entries: a point seen by several cameras of one view
        # couples that view once
        key = tid * ms + vp
        ukey, self.entry = np.unique(key, return_inverse=True)
        self.n_entries = len(ukey)
        self.e_track, e_view = ukey // ms, ukey % ms
        self.e_unknown = e_view - 1          # -1: the gauge view
        # (the entries are sorted by track, then view: a pair's first entry
        # is the later view, so its block lies in the lower envelope)
        e1, e2 = _lower_pairs(self.e_track)
        free = (self.e_unknown[e1] >= 0) & (self.e_unknown[e2] >= 0)
        self.e1, self.e2 = e1[free], e2[free]
        u = 3 * np.arange(ms - 1)
        # env index of entry (3 u1 + a, 3 u2 + b): row_base[u1, a] + 3 u2 + b
        self.row_base = np.stack([ptr[u + a] - first[u + a] for a in range(3)], axis=1)
        low = 3 * self.e_unknown[self.e2]
        if np.any(low < first[3 * self.e_unknown[self.e1]]):
            raise ValueError("the skyline profile misses a pair of views that share a track")
        self.env = int(ptr[-1])

    def residuals(self, c: np.ndarray, X: np.ndarray):
        """Angular residuals (K, 2), unit directions and distances to the points."""
        d = X[self.tid] - c[self.vp] - self.w
        rho = np.linalg.norm(d, axis=1)
        u = d / rho[:, None]
        return (self.B @ u[:, :, None])[:, :, 0], u, rho

    def jacobian(self, u, rho):
        """A = d r / d X = -d r / d c = B (I - u u^T) / rho per observation (K, 2, 3)."""
        # (matmul on the stacks: numpy's einsum takes several times as long)
        return (self.B - (self.B @ u[:, :, None]) * u[:, None, :]) / rho[:, None, None]

    def normal_terms(self, r, A):
        """Per (track, view) entry M = sum A^T A, h = sum A^T r (A of
        :meth:`jacobian`), and per point V = sum M, gX = sum h."""
        At = A.transpose(0, 2, 1)
        M = _sum_by(self.entry, At @ A, self.n_entries)
        h = _sum_by(self.entry, (At @ r[:, :, None])[:, :, 0], self.n_entries)
        return M, h, _sum_by(self.e_track, M, self.n_pts), _sum_by(self.e_track, h, self.n_pts)

    def reduced(self, M, h, V, gX, mu):
        """The Schur complement S = U - W V^-1 W^T (envelope) and its right-hand
        side, with the Marquardt damping mu (diagonals times 1 + mu), and V^-1."""
        Vd = V * (1.0 + mu * np.eye(3))[None] if mu else V
        Vinv = np.linalg.inv(Vd + POINT_RIDGE * np.trace(V, axis1=1, axis2=2)[:, None, None]
                             * np.eye(3)[None])
        Q = M @ Vinv[self.e_track]                                  # M_e V_p^-1
        S = np.zeros(self.env)
        for k in range(0, len(self.e1), PAIR_CHUNK):
            e1, e2 = self.e1[k:k + PAIR_CHUNK], self.e2[k:k + PAIR_CHUNK]
            blk = -(Q[e1] @ M[e2])
            u1, u2 = self.e_unknown[e1], self.e_unknown[e2]
            col = 3 * u2
            off = u1 != u2           # (a diagonal block: its lower triangle)
            idx, wts = [], []
            for a in range(3):
                base = self.row_base[u1, a] + col
                for b in range(3):
                    sel = off if b > a else slice(None)
                    idx.append((base + b)[sel])
                    wts.append(blk[:, a, b][sel])
            S += np.bincount(np.concatenate(idx), weights=np.concatenate(wts),
                             minlength=self.env)
        free = self.e_unknown >= 0
        U = _sum_by(self.e_unknown[free], M[free], self.ms - 1)
        if mu:
            U = U * (1.0 + mu * np.eye(3))[None]
        blocks = 3 * np.arange(self.ms - 1)
        for a in range(3):
            for b in range(a + 1):
                row = blocks + a
                S[self.ptr[row] + blocks + b - self.first[row]] += U[:, a, b]
        rhs = _sum_by(self.e_unknown[free],
                      (h - (Q @ gX[self.e_track][:, :, None])[:, :, 0])[free], self.ms - 1)
        return S, rhs.reshape(-1), Vinv

    def point_step(self, M, gX, Vinv, dc):
        """dX_p = V_p^-1 (-gX_p + sum_e M_e dc_view(e))."""
        dcv = np.vstack([np.zeros(3), dc.reshape(-1, 3)])
        back = _sum_by(self.e_track, (M @ dcv[self.e_unknown + 1][:, :, None])[:, :, 0],
                       self.n_pts)
        return (Vinv @ (back - gX)[:, :, None])[:, :, 0], dcv


def _usable_observations(track, view, solved):
    """Observations of the solved views whose track is seen from at least two of
    them: (mask, view positions of all observations)."""
    pos = np.full(int(max(view.max(), solved.max())) + 1, -1)
    pos[solved] = np.arange(len(solved))
    keep = pos[view] >= 0
    tv = np.unique(np.stack([track[keep], pos[view[keep]]], axis=1), axis=0)
    ids, n_views = np.unique(tv[:, 0], return_counts=True)
    return keep & np.isin(track, ids[n_views >= 2]), pos


def refine_centres(track: np.ndarray, view: np.ndarray, x: np.ndarray, w: np.ndarray,
                   centres: np.ndarray, solved: np.ndarray, first: np.ndarray,
                   ptr: np.ndarray, max_iterations: int = 50) -> Optional[CentresFit]:
    """Bundle adjustment of the centres of the views ``solved`` (the first held)
    and of the tracks' points, the rotations known.

    ``track``, ``view`` (N,) label the observations; ``x`` (N, 3) unit
    bearings and ``w`` (N, 3) ray origins relative to the view centre, both
    in world axes (the view's rotation undone: ``R_v^T b``, ``R_v^T o``;
    metres); ``centres`` (ms, 3) the starting centres of ``solved`` (world
    frame, metres; the first, the gauge, stays). ``first``/``ptr``: a skyline
    profile of the 3 (ms - 1) unknowns that couples every two views sharing a
    track (:func:`covisible_profile`). Returns None when no redundancy is
    left to estimate the noise from (or the information is singular), else
    the :class:`CentresFit`.
    """
    solved = np.asarray(solved)
    ms = len(solved)
    keep, pos = _usable_observations(track, view, solved)
    labels, tid = np.unique(track[keep], return_inverse=True)
    vp, xk, wk = pos[view[keep]], x[keep], w[keep]
    c = np.array(centres, dtype=np.float64)
    if len(tid) == 0:
        return None
    X, usable = _triangulate(xk, c[vp] + wk, tid, int(tid.max()) + 1)
    sel = usable[tid]
    if not np.any(sel):
        return None
    X, labels = X[usable], labels[usable]
    tid = np.cumsum(usable)[tid[sel]] - 1
    vp, xk, wk = vp[sel], xk[sel], wk[sel]
    n_obs, n_pts = len(tid), len(X)
    dof = 2 * n_obs - 3 * n_pts - 3 * (ms - 1)
    if dof <= 0:
        return None
    st = _Structure(tid, vp, xk, wk, ms, first, ptr)
    r, u, rho = st.residuals(c, X)
    cost = 0.5 * float(np.sum(r * r))
    mu, converged, settled, it = 1e-4, False, False, 0
    for it in range(1, max_iterations + 1):
        M, h, V, gX = st.normal_terms(r, st.jacobian(u, rho))
        stepped = False
        while not stepped and mu < 1e16:
            S, rhs, Vinv = st.reduced(M, h, V, gX, mu)
            try:
                fac = _core.skyline_cholesky(first, ptr, S)
            except (ArithmeticError, NumericalError):
                mu *= 10.0
                continue
            dc = _core.skyline_solve(first, ptr, fac, rhs)
            dX, dcv = st.point_step(M, gX, Vinv, dc)
            r1, u1, rho1 = st.residuals(c + dcv, X + dX)
            cost1 = 0.5 * float(np.sum(r1 * r1))
            if cost1 < cost:
                stepped = True
                converged = cost - cost1 <= COST_TOL * cost1
                settled = cost - cost1 <= STAT_TOL * 2.0 * cost1 / dof
                c, X, r, u, rho, cost = c + dcv, X + dX, r1, u1, rho1, cost1
                mu = max(mu / 10.0, 1e-12)
            else:
                mu *= 10.0
        if converged or not stepped:
            # (no step lowers the cost: a minimum to the precision of the cost)
            converged = True
            break
    converged = converged or settled
    A = st.jacobian(u, rho)
    M, h, V, gX = st.normal_terms(r, A)
    try:
        S, _, Vinv = st.reduced(M, h, V, gX, 0.0)
        fac = _core.skyline_cholesky(first, ptr, S)
    except (ArithmeticError, NumericalError, np.linalg.LinAlgError):
        return None
    return CentresFit(c, X, labels, first, ptr, fac, 2.0 * cost / dof,
                      float(np.sqrt(cost / n_obs)), it, converged, n_obs, n_pts, dof,
                      _rotation_term(st, u, A, M, Vinv))


def _rotation_term(st: "_Structure", u: np.ndarray, A: np.ndarray, M: np.ndarray,
                   Vinv: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """G^T y of :class:`CentresFit` at the optimum. A rotation error dw of a
    view turns its bearing x and offset w alike (x + dw x x, w + dw x w); the
    residual r = B^T u (B turning with x) moves by D dw, D's rows b_i x u +
    a_i x w (b_i, a_i the rows of B and of A = d r / d X). With the centres
    moved by y and the points re-optimised for them (dX_p = V_p^-1 sum M y),
    the residuals move by q_k = A_k (dX_p - y_v), and G^T y = sum_k D_k^T q_k
    per view (the implicit function theorem at the optimum)."""
    D = np.cross(st.B, u[:, None, :]) + np.cross(A, st.w[:, None, :])
    view_of_entry = st.e_unknown + 1

    def rotation_term(y: np.ndarray) -> np.ndarray:
        yv = np.vstack([np.zeros(3), np.asarray(y, float).reshape(-1, 3)])
        dX = (Vinv @ _sum_by(st.e_track, (M @ yv[view_of_entry][:, :, None])[:, :, 0],
                             st.n_pts)[:, :, None])[:, :, 0]
        q = (A @ (dX[st.tid] - yv[st.vp])[:, :, None])[:, :, 0]
        return _sum_by(st.vp, np.einsum("kai,ka->ki", D, q), st.ms)

    return rotation_term


def covisible_profile(track: np.ndarray, view: np.ndarray, pos: np.ndarray, n_views: int
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Skyline profile (first, ptr) of the 3 (n_views - 1) unknown centres in
    which every two solved views that see a common track are coupled
    (``pos[v]``: view v's position among the solved views, 0 the gauge, -1
    not solved)."""
    keep = pos[view] >= 0
    _, t = np.unique(track[keep], return_inverse=True)
    p = pos[view[keep]]
    # the lowest unknown view of each track couples to all of its others
    low = np.full(int(t.max()) + 1 if len(t) else 1, n_views)
    np.minimum.at(low, t, np.where(p == 0, n_views, p))
    minpos = np.arange(n_views)
    np.minimum.at(minpos, p, np.minimum(low[t], p))
    n = 3 * (n_views - 1)
    first = np.repeat(3 * (minpos[1:] - 1), 3).astype(np.int32)
    ptr = np.zeros(n + 1, dtype=np.int64)
    ptr[1:] = np.cumsum(np.arange(n) - first + 1)
    return first, ptr.astype(np.int32)
