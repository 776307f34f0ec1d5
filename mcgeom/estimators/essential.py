"""The 5-point step of the 5+1 method (thesis ch. 7.2), shared with E+SOCP (ch. 9).

One camera's intra-camera correspondences give, through its essential matrix
(OpenCV's 5-point solver ``cv2.findEssentialMat``, decomposed with the
cheirality check of ``cv2.recoverPose``), the rig rotation and a line of rig
translations. Let ``Q`` rotate rig axes into a local frame of camera ``a``
(origin at its centre ``c_a``, mean viewing direction along +z, so that its
rays project to normalised image points). The 5-point solver returns ``(R_a,
u)`` with ``Y2 = R_a Y1 + lam u`` in that frame, hence (docs/architecture.md §3,
``X2 = R X1 + t``)

    R = Q^T R_a Q,        t(lam) = t0 + lam w,   t0 = c_a - R c_a,  w = Q^T u,

the line along which eq. 7.4 (:mod:`mcgeom.estimators.five_plus_one_minimal`)
or the L-infinity triangulation of eq. 9.3 (:mod:`mcgeom.estimators.e_socp`)
then fixes ``lam``. Outlier-free data use a least-squares choice among 5-point
solutions (:data:`LEAST_SQUARES`), data with outliers OpenCV's USAC
(:data:`USAC_EXPLICIT` or a ``cv2`` flag).
"""

from __future__ import annotations

from typing import Optional

import cv2
import numpy as np

from ..errors import DegenerateError
from ..geometry import find_essential_mat, rcross
from ..types import RayPairs

__all__ = ["LEAST_SQUARES", "USAC_EXPLICIT", "essential_motions", "bearings_planar"]

#: bearings closer than this to the local image plane (|z| small) are not projected
_MIN_Z = 0.05


def _local_frame(dirs: np.ndarray) -> np.ndarray:
    """A rotation Q with Q @ (mean direction of ``dirs``) = +z."""
    u = dirs / np.linalg.norm(dirs, axis=1, keepdims=True)
    z = u.mean(axis=0)
    nz = np.linalg.norm(z)
    if not nz > 1e-6:
        raise DegenerateError("five_plus_one: the rays of the 5-point camera point in all "
                              "directions; no common image plane")
    z /= nz
    x = rcross([0.0, 1.0, 0.0] if abs(z[1]) < 0.9 else [1.0, 0.0, 0.0], z)
    x /= np.linalg.norm(x)
    y = rcross(z, x)
    return np.stack([x, y, z])


def _project(Q: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Normalised image points of rig directions in the local frame, and which are usable."""
    b = d @ Q.T
    b /= np.linalg.norm(b, axis=1, keepdims=True)
    ok = b[:, 2] > _MIN_Z
    z = np.where(ok, b[:, 2], 1.0)
    return np.ascontiguousarray(b[:, :2] / z[:, None]), ok


# --------------------------------------------------- 5 points: R and direction

#: ``method`` of :func:`essential_motions` for outlier-free data: see _least_squares_essential
LEAST_SQUARES = -1
#: ``method`` of :func:`essential_motions`: USAC with the explicit settings of :func:`_usac_params`
USAC_EXPLICIT = -2

_I3 = np.eye(3)
_NO_DISTORTION = np.zeros(5)


def _usac_params(threshold: float, prob: float, max_iters: int) -> "cv2.UsacParams":
    """OpenCV's USAC for the 5-point search, configured explicitly (``cv2.UsacParams``).

    The settings are the documented defaults of the structure (uniform sampler,
    MSAC score, inner local optimisation, covariance-based final polish), set one
    by one. Measured on the Ladybug head's cameras (50 correspondences, 30 %
    outliers): 0.56 ms median and 0.060 deg rotation error against 0.90 ms and
    0.070 deg for the ``cv2.USAC_DEFAULT`` flag (which configures its own
    local optimisation and polish).
    """
    p = cv2.UsacParams()
    p.threshold = float(threshold)
    p.confidence = float(prob)
    p.maxIterations = int(max_iters)
    p.sampler = cv2.SAMPLING_UNIFORM
    p.score = cv2.SCORE_METHOD_MSAC
    p.loMethod = cv2.LOCAL_OPTIM_INNER_LO
    p.loIterations = 5
    p.loSampleSize = 14
    p.final_polisher = cv2.COV_POLISHER
    p.final_polisher_iterations = 3
    return p


def _decompose(E: np.ndarray, x1: np.ndarray, x2: np.ndarray) -> tuple[int, np.ndarray, np.ndarray]:
    """The (R, t) of E's four decompositions (``cv2.decomposeEssentialMat``) that puts
    most points in front of both cameras (mid-point triangulation, ``X2 = R X1 + t``),
    with that count. Same choice as ``cv2.recoverPose`` without its distance cut,
    vectorised over the four candidates."""
    import cv2
    R1, R2, t = cv2.decomposeEssentialMat(E)
    t = t.ravel()
    h1, h2 = _homogeneous(x1), _homogeneous(x2)
    a = np.stack([h1 @ R1.T, h1 @ R2.T])               # R x1 in camera 2, both rotations
    bb = np.einsum("ij,ij->i", h2, h2)
    aa = np.einsum("kij,kij->ki", a, a)
    ab = np.einsum("kij,ij->ki", a, h2)
    den = aa * bb - ab * ab
    ok = den > 1e-14 * aa * bb
    den = np.where(ok, den, 1.0)
    # s1 R x1 + t = s2 x2 (least squares, w = -t); with -t both depths flip
    # sign exactly, so one solve serves t and -t
    aw, bw = -(a @ t), -(h2 @ t)
    s1 = (aw * bb - bw * ab) / den
    s2 = (aw * ab - bw * aa) / den
    front = np.count_nonzero(ok & (s1 > 0) & (s2 > 0), axis=1)
    back = np.count_nonzero(ok & (s1 < 0) & (s2 < 0), axis=1)
    # candidates in the order (R1, t), (R1, -t), (R2, t), (R2, -t); the first
    # with most points in front wins, (R1, t) if none has any
    counts = [int(front[0]), int(back[0]), int(front[1]), int(back[1])]
    k = int(np.argmax(counts))
    if counts[k] == 0:
        return 0, R1, t
    return counts[k], (R1, R2)[k // 2], (t, -t)[k % 2]


def _homogeneous(x: np.ndarray) -> np.ndarray:
    """(N, 2) image points as (N, 3) rows ``[x, y, 1]`` (``np.c_`` without its
    index-trick overhead)."""
    h = np.ones((len(x), 3))
    h[:, :2] = x
    return h


def _sampson_sq(E: np.ndarray, x1: np.ndarray, x2: np.ndarray) -> np.ndarray:
    """Squared Sampson distances of normalised image points under E."""
    h1, h2 = _homogeneous(x1), _homogeneous(x2)
    e1 = h1 @ E.T                       # E x1
    e2 = h2 @ E                         # E^T x2
    num = np.einsum("ij,ij->i", h2, e1) ** 2
    den = e1[:, 0] ** 2 + e1[:, 1] ** 2 + e2[:, 0] ** 2 + e2[:, 1] ** 2
    return num / np.maximum(den, 1e-300)


def _least_squares_essential(x1: np.ndarray, x2: np.ndarray,
                             subsets: int = 8) -> list[np.ndarray]:
    """Essential matrices for outlier-free points: every 5-point solution if there
    are 5 points, else the 5-point solution of a few spread-out 5-subsets with the
    least sum of squared Sampson distances over all points.

    (A median-based search such as LMedS is wrong here: on a handful of points
    a model through 5 of them has a zero median.) The subsets are taken in an
    order fixed by the point coordinates, so that the result does not depend on
    the order of the correspondences.
    """
    import cv2
    m = len(x1)
    if m == 5:
        E, _ = find_essential_mat(x1, x2, np.eye(3), method=cv2.RANSAC, threshold=1e-3)
        return [] if E is None else list(E.reshape(-1, 3, 3))
    # an order invariant to the rig frame (the local image plane's in-plane
    # rotation depends on it): by distance from the image centre
    order = np.lexsort((np.einsum("ij,ij->i", x2, x2), np.einsum("ij,ij->i", x1, x1)))
    step = max(1, m // 5)
    best, best_cost = None, np.inf
    for j in range(min(subsets, m)):
        s = order[(j + step * np.arange(5)) % m]
        if len(np.unique(s)) < 5:
            continue
        E, _ = find_essential_mat(x1[s], x2[s], np.eye(3), method=cv2.RANSAC,
                                    threshold=1e-3)
        if E is None or E.shape[0] % 3:
            continue
        for Ek in E.reshape(-1, 3, 3):
            if not np.all(np.isfinite(Ek)):
                continue
            cost = float(_sampson_sq(Ek, x1, x2).sum())
            if cost < best_cost:
                best, best_cost = Ek, cost
    return [] if best is None else [best]

#: RMS distance (radians) of a camera's bearings from their best-fitting plane
#: through its centre below which its essential matrix is not determined
_PLANAR_BEARINGS = 1e-3


def _check_not_planar(d1: np.ndarray, d2: np.ndarray) -> None:
    """DegenerateError if a camera's bearings at either time lie in one plane
    through its centre (scene points on a line, or on a plane through the
    centre): every rotation about that plane's normal then fits as well, and
    the 5-point solver returns one of them (thesis ch. 2.3, critical surfaces).
    Only for more than 5 outlier-free rays: a minimal sample, and data with
    outliers, are the robust layer's to judge."""
    for when, d in (("time 1", d1), ("time 2", d2)):
        rms = _plane_rms(d)
        if rms < _PLANAR_BEARINGS:
            raise DegenerateError(
                f"five_plus_one: the {len(d)} bearings of the 5-point camera at {when} lie in "
                f"one plane through its centre (RMS {rms:.2g} rad off it: "
                "points on a line or a plane through the camera): its essential matrix is "
                "not determined")


def _plane_rms(d: np.ndarray) -> float:
    """RMS distance (radians, small angles) of the unit bearings ``d`` (N, 3)
    from their best-fitting plane through the camera centre."""
    u = d / np.linalg.norm(d, axis=1, keepdims=True)
    return float(np.linalg.svd(u, compute_uv=False)[-1] / np.sqrt(len(u)))


def essential_motions(rays: RayPairs, index: np.ndarray, centre: np.ndarray,
                      method: int = LEAST_SQUARES, threshold: float = 1e-3,
                      prob: float = 0.999, stats: Optional[dict] = None,
                      max_iters: int = 1000, planar_check: bool = True,
                      ratio_threshold: Optional[float] = None
                      ) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Rig rotations and scale lines from the 5-point solver on one camera's rays.

    ``index`` selects intra-camera correspondences of one camera whose centre
    is ``centre`` (rig frame). With exactly 5 correspondences every solution of
    the 5-point solver is returned; with more, ``LEAST_SQUARES`` (outlier-free
    data) or OpenCV's robust search (``method`` a cv2 flag or ``USAC_EXPLICIT``, ``threshold`` in
    normalised image units, ``prob``) picks one.
    Returns a list of ``(R, t0, w)``: rig rotation and the line ``t(lam) = t0 +
    lam w`` of rig translations (metres per unit ``lam``, ``|w| = 1``).
    ``stats`` (a dict) receives the robust search's ``inlier_ratio``: the
    fraction of its inliers, or (``ratio_threshold`` given, normalised image
    units) the fraction of the points whose Sampson distance under the found
    essential matrix is below ``ratio_threshold``.
    ``planar_check``: raise DegenerateError when more than 5 rays (the robust
    search's inliers) lie in one plane through the centre (see
    :func:`_check_not_planar`); the 5+1 proposer leaves this to the robust
    layer, which scores its hypotheses on every camera.
    """
    d1, d2 = rays.dirs1[index], rays.dirs2[index]
    if planar_check and method == LEAST_SQUARES and len(d1) > 5:  # outlier-free: all count
        _check_not_planar(d1, d2)
    Q = _local_frame(np.concatenate([d1, d2]))
    x1, ok1 = _project(Q, d1)
    x2, ok2 = _project(Q, d2)
    ok = ok1 & ok2
    if ok.sum() < 5:
        return []
    x1, x2 = x1[ok], x2[ok]
    if method == LEAST_SQUARES or len(x1) == 5:
        Es = _least_squares_essential(x1, x2)
    else:
        if method == USAC_EXPLICIT:
            E, mask = find_essential_mat(x1, x2, _I3, _I3, _NO_DISTORTION, _NO_DISTORTION,
                                           _usac_params(threshold, prob, max_iters))
        else:
            E, mask = find_essential_mat(x1, x2, _I3, method=method, prob=prob,
                                           threshold=threshold, maxIters=max_iters)
        if E is None or E.shape[0] % 3 or not np.all(np.isfinite(E)):
            return []
        Es = list(E.reshape(-1, 3, 3))
        if planar_check and mask is not None and np.count_nonzero(mask) > 5:
            inl = np.flatnonzero(ok)[np.asarray(mask).ravel() != 0]
            _check_not_planar(d1[inl], d2[inl])
        if stats is not None and mask is not None:
            if ratio_threshold is None:
                stats["inlier_ratio"] = float(np.count_nonzero(mask)) / len(x1)
            else:
                inside = _sampson_sq(Es[0], x1, x2) < ratio_threshold ** 2
                stats["inlier_ratio"] = float(np.count_nonzero(inside)) / len(x1)
    out = []
    for Ek in Es:
        n_front, Ra, u = _decompose(Ek, x1, x2)
        if n_front == 0:
            continue
        R = Q.T @ Ra @ Q
        t0 = centre - R @ centre
        w = Q.T @ u.ravel()
        out.append((R, t0, w / np.linalg.norm(w)))
    return out


def bearings_planar(d1: np.ndarray, d2: np.ndarray, tol: float) -> bool:
    """True if all bearings at time 1, or all at time 2, lie within ``tol``
    (RMS, radians) of one plane through the camera centre. Tested on every
    ray of the camera, outliers included: if even they fit a plane, so do its
    inliers, and the 5-point problem is degenerate (see :func:`_check_not_planar`)."""
    return _plane_rms(d1) <= tol or _plane_rms(d2) <= tol

