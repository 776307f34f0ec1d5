"""Centres of many views with known rotations from short tracks (thesis ch. 6).

Conventions. View ``i`` has a known rotation ``rotations[i]`` = view_from_world
(``X_view = R_i (X_world - c_i)``, the ``P = R [I | -C]`` of thesis eq. 6.1)
and an unknown centre ``c_i`` (world frame). An observation is a bearing in
the view frame; with ``origins`` it is a ray from the point ``origins[k]`` of
the view frame (a camera of a rig, its centre in the rig frame, ch. 4.2
Fig. 4.2), otherwise from the view centre (an omnidirectional camera, ch. 6).
Bearings are de-rotated into the world frame, ``x = R_i^T b`` (ch. 6.1), so
that the relations are linear in the centres:

* bilinear (eq. 6.5) for each pair of observations of a track;
* trilinear (eq. 6.11) for each triple (all three choices of the reference
  view are stacked: the rows then do not depend on the order of the views).

Relations are grouped in blocks (one per view pair or triple: the S_ij /
S_ijk of eqs. 6.13 and 6.17). The C kernels accumulate each block's Gram
matrix; they are scattered into N = G^T A^T A G and L = G^T G in skyline
storage (the view graph of a sequence is banded), never forming A or G.

Solvers (gauge: the first view of the solved component at the origin):

* ``"svd"`` (Kaucic et al., ch. 6.2.4): min |E c| s.t. |c| = 1, the last
  right singular vector of E once view 0's columns are removed. E has an
  exact 3-dim null space (all centres translated alike), so "the last column
  of V" of the full E is a translation; fixing c_0 = 0 is the gauge of the
  thesis's plots (Figs. 6.3, 6.5: circles through the origin of diameter
  2 / sqrt(2 m) = 0.14 for m = 101 views, as sum |c_i - c_0|^2 = 1 gives);
* ``"constrained"`` (ch. 6.3, Algorithm 1): min |A G c| s.t. |G c| = 1, the
  smallest eigenpair of the pencil (N, L); L is the Laplacian of the block
  graph (each block counts once per view pair it contains) times I_3: up
  to a factor the |G c|^2 of eq. 6.19, whose x = G c holds the entries of
  the F_ji = [c_j - c_i]x (|F|^2 = 2 |t|^2) or of the trifocal tensors of
  eq. 6.9 for the three reference views that the trilinear blocks stack
  (sum 5 x the Laplacian; tests/test_ch6_thesis_form.py). Why it helps: the
  expected noise part of E^T E is close to a multiple of G^T G (within a
  factor 6.5-11 over all directions on the ch. 6.5.1 sequence), but spans
  four orders of magnitude against |c|^2 (``mcgeom experiment ch6
  --noise-metric``), so the plain solution is pulled toward small baselines
  far from view 0 -- the spirals of Figs. 6.3 and 6.5.

Without ``origins`` the result has no scale: it is normalised so that
``sum_i |c_i|^2 = 1`` (both solvers) with the sign that puts the
triangulated points in front of the views. With ``origins`` (a rig) the
system is inhomogeneous and the centres are metric (least squares of the
algebraic residuals), unless the data leave the scale free (e.g. pure
translation with intra-camera tracks, ch. 7.3.2): then the homogeneous
solution is returned, normalised as above, and ``scale.observable`` is False.

With ``origins`` the algebraic centres are then refined by a bundle
adjustment of the centres and the tracks' points on angular residuals, the
rotations held (:mod:`mcgeom.multiview_refine`), and the scale verdict is read
from that fit's covariance: the algebraic least squares weigh each relation by
the size of its coefficients, not by its noise, and its centres came out
6-98 % short at a first-order relative std of 0.1-5 % (see that module and
``mcgeom experiment ch6_rig_scale``).
"""

from __future__ import annotations

import itertools
import math
import time
from dataclasses import dataclass, field
from typing import Any, Optional

import numpy as np

from . import _core
from .multiview_refine import covisible_profile, refine_centres
from .types import ScaleVerdict

__all__ = ["TranslationResult", "translations_from_tracks", "RELATIONS", "SOLVERS", "PAIRS"]

RELATIONS = ("bilinear", "trilinear")
SOLVERS = ("svd", "constrained")
PAIRS = ("all", "window")


@dataclass(frozen=True)
class TranslationResult:
    """Centres of the views (world frame) and the evidence behind them.

    ``centres[i]`` is NaN for a view outside the solved component
    (``unconnected_views``). ``components`` lists the connected components of
    the view graph (views linked by at least one relation), largest first.
    ``eigenvalues`` are the smallest generalized eigenvalues of the solver's
    pencil (N, L) or (N, I), relative to its mean eigenvalue trace(N)/trace(B);
    ``eigen_ratio`` = lambda_1 / lambda_2 and ``rigidity`` = lambda_2 (relative):
    a rigidity near 0 (or a ratio near 1 with noise) means the relative scales
    of parts of the sequence are not fixed by the data. ``residual_rms`` is the
    RMS algebraic residual of the relation rows at the returned centres.
    ``timing`` holds seconds per stage. ``refinement`` (rig views, when the
    bundle adjustment ran): ``iterations``, ``converged``, ``rms`` (angular
    residual, radians), ``n_observations`` and ``n_points`` used, and
    ``algebraic_rel_std``, ``algebraic_travel`` (the algebraic solution's
    relative std and its travelled distance |G c| relative to the refined one),
    and with ``rotation_std`` the rotations' part ``rotation_rel_std`` of the
    scale's relative std (the verdict's ``rel_std`` combines it with the noise's).
    """

    centres: np.ndarray
    connected: np.ndarray
    unconnected_views: tuple
    components: tuple
    scale: ScaleVerdict
    residual_rms: float
    eigenvalues: np.ndarray
    eigen_ratio: float
    rigidity: float
    converged: bool
    iterations: int
    relation: str
    solver: str
    pairs: str
    n_relations: int
    n_blocks: int
    timing: dict = field(default_factory=dict)
    refinement: Optional[dict] = None


def _check_inputs(track, view, bearings, rotations, origins):
    R = np.asarray(rotations, dtype=np.float64)
    if R.ndim != 3 or R.shape[1:] != (3, 3) or R.shape[0] < 2:
        raise ValueError(f"rotations must have shape (m, 3, 3) with m >= 2, got {R.shape}")
    if not np.isfinite(R).all():
        raise ValueError("rotations contain NaN or inf")
    orth = np.abs(np.einsum("mji,mjk->mik", R, R) - np.eye(3)).max(axis=(1, 2))
    det = np.linalg.det(R)
    bad = np.flatnonzero((orth > 1e-6) | (det < 0))
    if bad.size:
        raise ValueError(f"rotations[{int(bad[0])}] is not a rotation matrix")
    b = np.ascontiguousarray(bearings, dtype=np.float64)
    if b.ndim != 2 or b.shape[1] != 3:
        raise ValueError(f"bearings must have shape (N, 3), got {b.shape}")
    n = b.shape[0]
    if not np.isfinite(b).all():
        raise ValueError("bearings contain NaN or inf")
    norms = np.linalg.norm(b, axis=1)
    if n and norms.min() == 0.0:
        raise ValueError(f"bearings[{int(np.argmin(norms))}] has zero length")
    ids = []
    for name, a in (("track", track), ("view", view)):
        a = np.asarray(a)
        if a.shape != (n,):
            raise ValueError(f"{name} must have shape ({n},), got {a.shape}")
        if n and a.dtype.kind not in "iu":
            raise ValueError(f"{name} must hold integers, got dtype {a.dtype}")
        ids.append(a.astype(np.int64))
    if n and (ids[1].min() < 0 or ids[1].max() >= R.shape[0]):
        raise ValueError(f"view ids must be in [0, {R.shape[0]}), got "
                         f"[{ids[1].min()}, {ids[1].max()}]")
    o = None
    if origins is not None:
        o = np.ascontiguousarray(origins, dtype=np.float64)
        if o.shape != (n, 3):
            raise ValueError(f"origins must have shape ({n}, 3), got {o.shape}")
        if not np.isfinite(o).all():
            raise ValueError("origins contain NaN or inf")
    return ids[0], ids[1], b / norms[:, None] if n else b, R, o


#: cap on the observation subsets enumerated from the tracks (memory guard)
MAX_RELATIONS = 20_000_000


def _n_choose(n: int, k: int) -> int:
    return 0 if n < k else (n * (n - 1) // 2 if k == 2 else n * (n - 1) * (n - 2) // 6)


def relations(track: np.ndarray, view: np.ndarray, q: int, pairs: str,
              window: int) -> np.ndarray:
    """Index tuples (K, q) of the observations of each relation, sorted by view
    inside each relation: every q-subset of a track's observations in q
    distinct views (within ``window`` views of each other for "window").

    ``track`` and ``view`` (N,) give each observation's track and view index;
    ``q`` is 2 (bilinear, eq. 6.5) or 3 (trilinear, eq. 6.11); ``pairs`` is
    one of :data:`PAIRS`. The returned int array indexes the observations.
    """
    order = np.lexsort((view, track))
    t_sorted = track[order]
    starts = np.flatnonzero(np.r_[True, t_sorted[1:] != t_sorted[:-1]])
    lengths = np.diff(np.r_[starts, len(order)])
    out = []
    total = sum(int(np.count_nonzero(lengths == L)) * _n_choose(int(L), q)
                for L in np.unique(lengths))
    if total > MAX_RELATIONS:
        raise ValueError(f"the tracks give {total} {q}-view combinations (more than "
                         f"{MAX_RELATIONS}): split long tracks")
    for length in np.unique(lengths):
        if length < q:
            continue
        combos = np.array(list(itertools.combinations(range(int(length)), q)), dtype=np.int64)
        s = starts[lengths == length]
        idx = order[s[:, None, None] + combos[None, :, :]].reshape(-1, q)
        out.append(idx)
    if not out:
        return np.zeros((0, q), dtype=np.int64)
    idx = np.concatenate(out)
    v = view[idx]
    keep = np.all(np.diff(v, axis=1) > 0, axis=1)  # distinct views (sorted)
    if pairs == "window":
        keep &= (v[:, -1] - v[:, 0]) <= window
    return idx[keep]


def _blocks(v: np.ndarray, m: int) -> tuple[np.ndarray, np.ndarray]:
    """The distinct view tuples (K, q) of the relations ``v`` (N, q), sorted,
    and each relation's block index (N,). The tuples are coded as one integer
    (base m, same order) so that the sort is 1-D: np.unique over rows sorts
    them as records, 30x slower on a real sequence's million relations."""
    q = v.shape[1]
    if m ** q >= 2 ** 62:   # the code would overflow int64 (m > 1.6e6 views)
        keys, block = np.unique(v, axis=0, return_inverse=True)
        return keys, block.reshape(-1)
    code = v @ (m ** np.arange(q - 1, -1, -1, dtype=np.int64))
    ucode, block = np.unique(code, return_inverse=True)
    keys = np.stack([(ucode // m ** (q - 1 - a)) % m for a in range(q)], axis=1)
    return keys, block.reshape(-1)


def _components(m: int, blocks: np.ndarray) -> list:
    """Connected components of the view graph (label propagation), largest
    first, ties by lowest view; views without relations are singletons."""
    label = np.arange(m)
    while True:
        low = label[blocks].min(axis=1)
        new = label.copy()
        np.minimum.at(new, blocks.reshape(-1), np.repeat(low, blocks.shape[1]))
        new = new[new]  # pointer jumping
        if np.array_equal(new, label):
            break
        label = new
    comps = [np.flatnonzero(label == r) for r in np.unique(label)]
    comps.sort(key=lambda c: (-len(c), c[0]))
    return comps


def _skyline_profile(pos_blocks: np.ndarray, n_views: int):
    """first/ptr of the 3 (n_views - 1) unknowns (view positions 1..; 0 is the
    gauge) coupled as in ``pos_blocks`` (K, q) of view positions."""
    minpos = np.arange(n_views)
    low = np.where(pos_blocks == 0, n_views, pos_blocks).min(axis=1)
    np.minimum.at(minpos, pos_blocks.reshape(-1), np.repeat(low, pos_blocks.shape[1]))
    n = 3 * (n_views - 1)
    first = np.repeat(3 * (minpos[1:] - 1), 3).astype(np.int32)
    ptr = np.zeros(n + 1, dtype=np.int64)
    ptr[1:] = np.cumsum(np.arange(n) - first + 1)
    return first, ptr.astype(np.int32), n


def _scatter_indices(pos_blocks, first, ptr):
    """For every block, every (row, col) entry of its 3q x 3q Gram that falls in
    the lower envelope of the unknowns: (block, a, b, env index)."""
    K, q = pos_blocks.shape
    comp = np.arange(3 * q)
    va, vb = comp[:, None] // 3, comp[None, :] // 3
    shape = (K, 3 * q, 3 * q)
    pa = np.broadcast_to(pos_blocks[:, va], shape)
    pb = np.broadcast_to(pos_blocks[:, vb], shape)
    r = 3 * (pa - 1) + (comp[:, None] % 3)[None]
    c = 3 * (pb - 1) + (comp[None, :] % 3)[None]
    ok = (pa > 0) & (pb > 0) & (r >= c)
    kk, aa, bb = np.nonzero(ok)
    rr, cc = r[ok], c[ok]
    return kk, aa, bb, ptr[rr] + cc - first[rr]


def _laplacian_grams(q: int) -> np.ndarray:
    """(3q, 3q) metric of one block: sum over its view pairs of |c_j - c_i|^2."""
    lap = q * np.eye(q) - np.ones((q, q))
    return np.kron(lap, np.eye(3))


def _cheirality_sign(x, w, c_obs, idx) -> int:
    """+1 or -1: the sign of the centres that puts more triangulated points in
    front of both views of each relation pair (first two observations)."""
    i, j = idx[:, 0], idx[:, 1]
    xi, xj = x[i], x[j]
    base = (c_obs[j] + w[j]) - (c_obs[i] + w[i])
    # lambda x_i - mu x_j = base in least squares (2 x 2 normal equations)
    a11 = np.einsum("ij,ij->i", xi, xi)
    a22 = np.einsum("ij,ij->i", xj, xj)
    a12 = -np.einsum("ij,ij->i", xi, xj)
    b1 = np.einsum("ij,ij->i", xi, base)
    b2 = -np.einsum("ij,ij->i", xj, base)
    det = a11 * a22 - a12 * a12
    ok = det > 1e-12 * a11 * a22
    lam = (a22 * b1 - a12 * b2)[ok] / det[ok]
    mu = (a11 * b2 - a12 * b1)[ok] / det[ok]
    pos = np.count_nonzero((lam > 0) & (mu > 0))
    neg = np.count_nonzero((lam < 0) & (mu < 0))
    return -1 if neg > pos else 1


def translations_from_tracks(track: Any, view: Any, bearings: Any, rotations: Any, *,
                             origins: Any = None, relation: str = "bilinear",
                             solver: str = "constrained", pairs: str = "all",
                             window: Optional[int] = None, max_rel_std: float = 0.1,
                             max_iter: int = 500, tol: float = 1e-13,
                             refine: bool = True, rotation_std: float = 0.0
                             ) -> TranslationResult:
    """Centres of m views with known rotations from tracks (thesis ch. 6).

    ``track`` (N,) and ``view`` (N,) label each observation; ``bearings`` (N, 3)
    are directions in the view frame (any length); ``rotations`` (m, 3, 3)
    view_from_world. ``origins`` (N, 3): ray origins in the view frame (metres;
    rig cameras), None for central views. ``relation``: "bilinear" (eq. 6.5)
    or "trilinear" (eq. 6.11); ``solver``: "svd" (plain, Kaucic) or
    "constrained" (Algorithm 1); ``pairs``: "all" relations of every track, or
    "window": only views at most ``window`` apart (default 1 bilinear, 2
    trilinear; ch. 6.2.3). Only the component of the view graph that contains
    view 0 is solved (the largest one if view 0 has no relation); view 0 (or
    that component's first view) is at the origin. ``max_rel_std``: relative
    standard deviation of the metric scale above which a rig's scale is
    reported unobservable. ``max_iter``/``tol`` bound the eigen-solver.
    ``refine`` (rig views only): refine the algebraic centres by the bundle
    adjustment of :func:`mcgeom.multiview_refine.refine_centres` and judge the
    scale from its covariance (False: the algebraic solution and its
    first-order std, which is over-confident; for callers that refine
    themselves). ``rotation_std`` (radians, with ``refine``): the standard
    deviation of each view's rotation error (independent per view, about
    every axis); its first-order effect on the travelled distance (the
    bundle adjustment's sensitivity to the rotations) is added to the scale's
    std. At 0 the rotations are taken as exact: rotations off by 0.01 deg
    already put a few scales beyond 3 of their stds (see
    :mod:`mcgeom.multiview_refine`); pass the rotations' error when they are
    estimated.

    Long real tracks: the algebraic residual of a relation between views far
    apart carries the noise of its coefficients times the long baseline, so
    with "all" such relations dominate and the metric solution shrinks. On
    the KITTI-00 stereo tracks (64 views, tracks up to 26 frames) "all" gave
    a path 2.5-4 % short, the consecutive window 1.1-1.6 % (mcgeom experiment ch6_kitti).
    """
    t_start = time.perf_counter()
    if relation not in RELATIONS:
        raise ValueError(f"relation must be one of {RELATIONS}, got {relation!r}")
    if solver not in SOLVERS:
        raise ValueError(f"solver must be one of {SOLVERS}, got {solver!r}")
    if pairs not in PAIRS:
        raise ValueError(f"pairs must be one of {PAIRS}, got {pairs!r}")
    if not (isinstance(rotation_std, (int, float)) and math.isfinite(rotation_std)
            and rotation_std >= 0.0):
        raise ValueError(f"rotation_std must be a finite number >= 0 (radians), got "
                         f"{rotation_std!r}")
    if rotation_std > 0.0 and not refine:
        raise ValueError("rotation_std needs the bundle adjustment (refine=True): the "
                         "algebraic solution has no sensitivity to the rotations")
    q = 2 if relation == "bilinear" else 3
    if window is None:
        window = q - 1
    if int(window) < q - 1:
        raise ValueError(f"window must be >= {q - 1} for {relation} relations, got {window}")
    track, view, b, R, origins = _check_inputs(track, view, bearings, rotations, origins)
    m = R.shape[0]
    # de-rotated bearings and offsets (ch. 6.1): x = R_i^T b
    x = np.einsum("kji,kj->ki", R[view], b)
    w = None if origins is None else np.einsum("kji,kj->ki", R[view], origins)
    idx = relations(track, view, q, pairs, int(window))
    if len(idx) == 0:
        raise ValueError(f"no {relation} relation: every track needs observations in "
                         f"{q} distinct views" + (f" within {window} views" if pairs == "window"
                                                  else ""))
    keys, block = _blocks(view[idx], m)
    t_rel = time.perf_counter()
    grams = _core.relation_grams(x[idx], None if w is None else w[idx], block, len(keys))
    t_gram = time.perf_counter()

    comps = _components(m, keys)
    solved = next((c for c in comps if c[0] == 0 and len(c) > 1), comps[0])
    if len(solved) < 2:
        raise ValueError("no two views are linked by a relation")
    pos = np.full(m, -1)
    pos[solved] = np.arange(len(solved))
    in_comp = pos[keys[:, 0]] >= 0
    pk, gk = pos[keys[in_comp]], grams[in_comp]
    first, ptr, n = _skyline_profile(pk, len(solved))
    kk, aa, bb, ei = _scatter_indices(pk, first, ptr)
    env = int(ptr[-1])
    d = 3 * q
    N = np.bincount(ei, weights=gk[kk, aa, bb], minlength=env)
    if solver == "constrained":
        B = np.bincount(ei, weights=_laplacian_grams(q)[aa, bb], minlength=env)
    else:
        B = np.zeros(env)
        B[ptr[1:] - 1] = 1.0
    # linear term of the inhomogeneous (rig) system: sum 2 c^T g
    unknown = (3 * (pk - 1))[:, :, None] + np.arange(3)[None, None, :]      # (K, q, 3)
    gvec = np.zeros(n)
    live = (pk > 0)[:, :, None].repeat(3, axis=2)
    np.add.at(gvec, unknown[live], gk[:, :d, d].reshape(-1, q, 3)[live])
    const = float(gk[:, d, d].sum())
    n_rows = int(np.count_nonzero(in_comp[block])) * (1 if q == 2 else 27)
    t_asm = time.perf_counter()

    scale_ref = N[ptr[1:] - 1].sum() / B[ptr[1:] - 1].sum()
    if not scale_ref > 0:
        raise ValueError("the relations carry no information (parallel bearings?)")
    p = min(4, n)
    eig = _core.skyline_eig(first, ptr, N, B, shift=1e-10 * scale_ref, p=p,
                            max_iter=max_iter, tol=tol)
    rel_vals = eig["vals"] / scale_ref
    converged = bool(np.all(eig["resid"][:min(2, p)] <= tol))
    lam1, lam2 = rel_vals[0], rel_vals[1] if p > 1 else np.inf
    c_hom = eig["vecs"][0]

    shift = None
    if w is not None:  # mean world-aligned offset of each solved view's rays
        cnt = np.maximum(np.bincount(view, minlength=m), 1)[:, None]
        wbar = np.stack([np.bincount(view, weights=w[:, a], minlength=m) for a in range(3)], 1)
        wbar = wbar / cnt
        shift = (wbar[solved[1:]] - wbar[solved[0]]).reshape(-1)
    refiner = _bundle_adjuster(track, view, x, w, pos, solved) if refine and w is not None \
        else None
    verdict, c_unknown, metric, refinement = _choose(origins, N, gvec, const, first, ptr,
                                                     c_hom, lam1, n_rows, n, pk, max_rel_std,
                                                     shift, refiner, float(rotation_std))
    t_solve = time.perf_counter()

    centres = np.full((m, 3), np.nan)
    centres[solved[0]] = 0.0
    centres[solved[1:]] = c_unknown.reshape(-1, 3)
    if not metric:
        centres[solved] /= np.sqrt(np.sum(centres[solved] ** 2))
        c_obs = np.nan_to_num(centres[view])
        use = idx[in_comp[block]]
        wz = np.zeros_like(x) if w is None else w
        if _cheirality_sign(x, wz, c_obs, use) < 0:
            centres[solved] *= -1.0
    cu = centres[solved[1:]].reshape(-1)
    quad = cu @ _sky_matvec(N, first, ptr, cu)
    res2 = quad + (2.0 * gvec @ cu + const if metric else 0.0)
    connected = np.zeros(m, bool)
    connected[solved] = True
    return TranslationResult(
        centres=centres, connected=connected,
        unconnected_views=tuple(int(v) for v in np.flatnonzero(~connected)),
        components=tuple(tuple(int(v) for v in c) for c in comps),
        scale=verdict, residual_rms=float(np.sqrt(max(res2, 0.0) / max(n_rows, 1))),
        eigenvalues=rel_vals, eigen_ratio=float(lam1 / lam2) if lam2 > 0 else float("nan"),
        rigidity=float(lam2), converged=converged, iterations=eig["iters"],
        relation=relation, solver=solver, pairs=pairs, n_relations=int(len(idx)),
        n_blocks=int(len(keys)),
        timing={"relations": t_rel - t_start, "grams": t_gram - t_rel,
                "assembly": t_asm - t_gram, "solve": t_solve - t_asm,
                "total": time.perf_counter() - t_start},
        refinement=refinement)


def _bundle_adjuster(track, view, x, w, pos, solved):
    """``refiner(c)`` of :func:`_choose`: the bundle adjustment of the solved
    views' centres from the algebraic unknowns c (the gauge view at 0)."""
    def refiner(c_unknown):
        c0 = np.vstack([np.zeros(3), c_unknown.reshape(-1, 3)])
        profile = covisible_profile(track, view, pos, len(solved))
        return refine_centres(track, view, x, w, c0, solved, *profile)
    return refiner


def _sky_matvec(a: np.ndarray, first: np.ndarray, ptr: np.ndarray, x: np.ndarray) -> np.ndarray:
    """y = A x for the symmetric skyline matrix A (numpy; used once per solve)."""
    n = len(first)
    rows = np.repeat(np.arange(n), np.diff(ptr))
    cols = first[rows] + (np.arange(int(ptr[-1])) - ptr[rows])
    y = np.bincount(rows, weights=a * x[cols], minlength=n)
    off = cols != rows
    y += np.bincount(cols[off], weights=a[off] * x[rows[off]], minlength=n)
    return y


def _choose(origins, N, gvec, const, first, ptr, c_hom, lam1, n_rows, n, pk, max_rel_std,
            shift, refiner=None, rotation_std=0.0):
    """The centres (unknowns), whether they are metric, the scale verdict and
    the refinement's summary (None without one). ``shift``: per unknown, the
    mean offset of the view's rays relative to the gauge view's (the scale
    evidence is the distance travelled by the cameras' centroids, which does
    not depend on where the rig frame's origin is). ``refiner(c) ->
    CentresFit or None``: the bundle adjustment from the algebraic unknowns
    c, whose covariance (and ``rotation_std``'s effect, radians per view)
    then decides the verdict."""
    cond = float(np.sqrt(max(lam1, 0.0)))
    if origins is None:
        return (ScaleVerdict(False, "central views: the scale of the centres is not "
                             "observable (normalised to sum |c_i|^2 = 1)", conditioning=cond),
                c_hom, False, None)
    if lam1 < 1e-10 or not np.any(gvec):
        return (ScaleVerdict(False, "critical configuration: a scaled family of centres fits "
                             "the data (e.g. no rotation and only intra-camera tracks, "
                             "thesis ch. 7.3.2); scale not observable", conditioning=cond),
                c_hom, False, None)
    try:
        fac = _core.skyline_cholesky(first, ptr, N)
    except ArithmeticError:
        return (ScaleVerdict(False, "the metric system is singular: scale not observable",
                             conditioning=cond), c_hom, False, None)
    c = _core.skyline_solve(first, ptr, fac, -gvec)
    # first-order std of the travelled distance |G c| (frame-independent). The
    # residual comes from the Gram expansion c^T N c + 2 g^T c + const, whose
    # terms cancel: it is known only to about 1e-13 of their size. A nearly
    # singular N (one camera, a central rig: a line of solutions) makes c and
    # the terms huge and the difference meaningless (even negative); the floor
    # then keeps the noise estimate, and with it rel_std, from reading zero.
    cnc, gc = float(c @ _sky_matvec(N, first, ptr, c)), float(2.0 * gvec @ c)
    res2 = max(cnc + gc + const, 1e-13 * (abs(cnc) + abs(gc) + abs(const)))
    lap = _laplacian_env(first, ptr, pk)
    travel = _travel_std(lap, first, ptr, c + shift, res2 / max(n_rows - n, 1),
                         lambda g: _core.skyline_solve(first, ptr, fac, g))
    if travel is None:
        return (ScaleVerdict(False, "no translation detected: scale not observable",
                             conditioning=cond, rel_std=float("inf")), c_hom, False, None)
    rel, s_alg, _ = travel
    summary = None
    if refiner is not None:
        try:
            fit = refiner(c)
        except ValueError as exc:   # too long tracks for its memory guard
            return (ScaleVerdict(False, f"metric centres not verified: {exc} (refine=False "
                                 "gives the algebraic ones, whose std is over-confident)",
                                 conditioning=cond, rel_std=float("inf")), c_hom, False, None)
        if fit is None:
            return (ScaleVerdict(False, "the bundle adjustment of the centres has no "
                                 "redundancy left to estimate the noise from, or a singular "
                                 "information: scale not observable",
                                 conditioning=cond, rel_std=float("inf")), c_hom, False, None)
        c = fit.centres[1:].reshape(-1)
        travel = _travel_std(lap, fit.first, fit.ptr, c + shift, fit.sigma2,
                             lambda g: _core.skyline_solve(fit.first, fit.ptr, fit.chol, g),
                             first, ptr)
        summary = {"iterations": fit.iterations, "converged": fit.converged, "rms": fit.rms,
                   "n_observations": fit.n_observations, "n_points": fit.n_points,
                   "algebraic_rel_std": rel}
        if travel is None:
            return (ScaleVerdict(False, "no translation detected: scale not observable",
                                 conditioning=cond, rel_std=float("inf")), c_hom, False, summary)
        rel, s_fit, y = travel
        summary["algebraic_travel"] = s_alg / s_fit
        if rotation_std > 0.0:
            # ds = -(G^T S^-1 g) . dw: the rotations' share of the std
            rot = rotation_std * float(np.linalg.norm(fit.rotation_term(y))) / s_fit
            summary["rotation_rel_std"] = rot
            rel = math.hypot(rel, rot)
        if not fit.converged:
            return (ScaleVerdict(False, f"the bundle adjustment of the centres did not "
                                 f"converge in {fit.iterations} iterations: metric centres not "
                                 f"verified (relative std {rel:.3g} at its last step)",
                                 conditioning=cond, rel_std=rel), c_hom, False, summary)
    if rel <= max_rel_std:
        how = "bundle adjustment" if summary else "algebraic least squares"
        return (ScaleVerdict(True, f"metric scale fixed by the rig's camera offsets "
                             f"(relative std {rel:.3g} of the travelled distance, {how})",
                             conditioning=cond, rel_std=rel), c, True, summary)
    return (ScaleVerdict(False, f"scale too uncertain: relative std {rel:.3g} of the "
                         "travelled distance (near-critical configuration)",
                         conditioning=cond, rel_std=rel), c_hom, False, summary)


def _travel_std(lap, first, ptr, c, sigma2, solve, lap_first=None, lap_ptr=None):
    """(relative std, length, S^-1 g) of the travelled distance |G c| = sqrt(c^T L c)
    of the unknowns ``c`` (the cameras' centroids: the shift included), L =
    ``lap`` in the skyline profile (``lap_first``, ``lap_ptr``; default
    ``first``, ``ptr``), whose covariance is ``sigma2`` times the inverse that
    ``solve`` applies; None when the length is 0 (no translation)."""
    lf, lp = (first, ptr) if lap_first is None else (lap_first, lap_ptr)
    Lc = _sky_matvec(lap, lf, lp, c)
    s2 = float(c @ Lc)
    if not s2 > 0:
        return None
    g = Lc / np.sqrt(s2)
    y = solve(g)
    return float(np.sqrt(max(sigma2 * float(g @ y), 0.0)) / np.sqrt(s2)), float(np.sqrt(s2)), y


def _laplacian_env(first, ptr, pk):
    """L = G^T G of the blocks ``pk`` in the skyline storage of (first, ptr)."""
    kk, aa, bb, ei = _scatter_indices(pk, first, ptr)
    q = pk.shape[1]
    return np.bincount(ei, weights=_laplacian_grams(q)[aa, bb], minlength=int(ptr[-1]))
