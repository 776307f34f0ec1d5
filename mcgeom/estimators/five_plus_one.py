"""``five_plus_one``: the 5+1 method of thesis ch. 7 (5 points in one camera, 1 in another).

The rotation and the translation direction come from the essential matrix of one
camera ``a`` (OpenCV's 5-point solver, ``cv2.findEssentialMat``, decomposed with
the cheirality check of ``cv2.recoverPose``); the metric scale from any other
correspondence by eq. 7.4, written here for any camera pair of the rig and for
cross-camera correspondences.

Eq. 7.4 in our convention (DESIGN.md section 3). Let ``Q`` rotate rig axes into a
local frame of camera ``a`` (origin at its centre ``c_a``, mean viewing direction
along +z, so that its rays project to normalised image points). The 5-point
solver returns ``(R_a, u)`` with ``Y2 = R_a Y1 + lam u`` in that frame, hence

    R = Q^T R_a Q,        t(lam) = t0 + lam w,   t0 = c_a - R c_a,  w = Q^T u.

Substituting ``t(lam)`` into the generalized epipolar constraint of any other
correspondence ``(d1, m1) <-> (d2, m2)`` gives ``e(lam) = a + lam b`` with

    a = d2^T [t0]x R d1 + d2^T R m1 + m2^T R d1,    b = d2^T [w]x R d1,

so ``lam = -a / b`` from one correspondence (the thesis's ``x'^T A x + lam x'^T
B x = 0``) and the least-squares ``lam = -sum(a b) / sum(b^2)`` over many.

Critical configuration (ch. 7.3.2, Theorem 3): camera ``b`` can fix the scale
only if the line of its possible positions ``R^T (c_b - t(lam))`` misses its
first position ``c_b``, i.e. unless the displacements ``delta(c) = R^T (c - t) -
c`` of ``c_a`` and ``c_b`` are parallel. The angle between them is the critical
angle of ch. 7.5.2 (zero for a pure translation); it is reported per camera.
Cross-camera correspondences do not have this limitation.
"""

from __future__ import annotations

from typing import Optional, Sequence

import cv2
import numpy as np

from .. import _core
from ..errors import DegenerateError
from ..observability import (displacements, refine_centred, scale_profile, scale_verdict,
                             travel_direction)
from ..observability import rcross as _rcross   # row-wise np.cross without its overhead
from ..registry import register
from ..types import RayPairs, RigMotion

__all__ = [
    "five_plus_one", "camera_ids", "intra_counts", "essential_motions", "scale_terms",
    "critical_angles", "minimal_solutions", "sample_five_plus_one",
]

#: bearings closer than this to the local image plane (|z| small) are not projected
_MIN_Z = 0.05


# ------------------------------------------------------------------ cameras

def camera_ids(rays: RayPairs) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Camera ids of both rays of every correspondence and the camera centres.

    Uses ``rays.cam1``/``rays.cam2`` when present, else groups rays by their
    origin (equal origins = one camera). Returns ``(cam1, cam2, centres)`` with
    ``centres[k]`` the centre (rig frame, metres) of camera ``k``.
    """
    if rays.cam1 is not None and rays.cam2 is not None:
        cam1, cam2 = rays.cam1, rays.cam2
        m = int(max(cam1.max(initial=-1), cam2.max(initial=-1))) + 1
        centres = np.full((m, 3), np.nan)
        centres[cam1] = rays.origins1
        centres[cam2] = rays.origins2
        # the same camera must have one centre at both times
        if (np.abs(centres[cam1] - rays.origins1).max(initial=0.0) > 1e-9 * (
                1.0 + np.abs(rays.origins1).max(initial=0.0))
                or np.abs(centres[cam2] - rays.origins2).max(initial=0.0) > 1e-9 * (
                1.0 + np.abs(rays.origins2).max(initial=0.0))):
            raise ValueError("rays: one camera id has several different origins; origins must "
                             "be the camera centres (rig frame) for five_plus_one")
        return cam1, cam2, centres
    allo = np.concatenate([rays.origins1, rays.origins2])
    centres, inv = np.unique(allo, axis=0, return_inverse=True)
    inv = inv.ravel()
    n = len(rays)
    return inv[:n].astype(np.int64), inv[n:].astype(np.int64), centres


def intra_counts(rays: RayPairs):
    """:func:`camera_ids` plus the intra-camera mask (same camera at both times)
    and the number of intra-camera correspondences of every camera:
    ``(cam1, cam2, centres, intra, counts)``."""
    cam1, cam2, centres = camera_ids(rays)
    intra = cam1 == cam2
    return cam1, cam2, centres, intra, np.bincount(cam1[intra], minlength=len(centres))


def _local_frame(dirs: np.ndarray) -> np.ndarray:
    """A rotation Q with Q @ (mean direction of ``dirs``) = +z."""
    u = dirs / np.linalg.norm(dirs, axis=1, keepdims=True)
    z = u.mean(axis=0)
    nz = np.linalg.norm(z)
    if not nz > 1e-6:
        raise DegenerateError("five_plus_one: the rays of the 5-point camera point in all "
                              "directions; no common image plane")
    z /= nz
    x = _rcross([0.0, 1.0, 0.0] if abs(z[1]) < 0.9 else [1.0, 0.0, 0.0], z)
    x /= np.linalg.norm(x)
    y = _rcross(z, x)
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
        E, _ = cv2.findEssentialMat(x1, x2, np.eye(3), method=cv2.RANSAC, threshold=1e-3)
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
        E, _ = cv2.findEssentialMat(x1[s], x2[s], np.eye(3), method=cv2.RANSAC,
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
            E, mask = cv2.findEssentialMat(x1, x2, _I3, _I3, _NO_DISTORTION, _NO_DISTORTION,
                                           _usac_params(threshold, prob, max_iters))
        else:
            E, mask = cv2.findEssentialMat(x1, x2, _I3, method=method, prob=prob,
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


# ------------------------------------------------------------- 1 point: scale

def scale_terms(rays: RayPairs, R: np.ndarray, t0: np.ndarray,
                w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Coefficients of eq. 7.4: the epipolar residual of each correspondence is
    ``a + lam b`` for the translation ``t0 + lam w`` (unit directions, so ``a``
    and ``b`` are in metres)."""
    d1 = rays.dirs1 / np.linalg.norm(rays.dirs1, axis=1, keepdims=True)
    d2 = rays.dirs2 / np.linalg.norm(rays.dirs2, axis=1, keepdims=True)
    rd1 = d1 @ R.T
    m1 = _rcross(rays.origins1, d1)
    m2 = _rcross(rays.origins2, d2)
    a = (np.einsum("ij,ij->i", d2, _rcross(t0, rd1)) + np.einsum("ij,ij->i", d2, m1 @ R.T)
         + np.einsum("ij,ij->i", m2, rd1))
    b = np.einsum("ij,ij->i", d2, _rcross(w, rd1))
    return a, b


def critical_angles(R: np.ndarray, t: np.ndarray, centres: np.ndarray,
                    five_camera: int) -> np.ndarray:
    """Critical angle (radians) of every camera w.r.t. the 5-point camera (ch. 7.5.2).

    The angle between the displacements ``R^T (c - t) - c`` of the two camera
    centres (in the time-1 rig frame); 0 means the scale cannot be fixed from
    that camera's intra-camera correspondences (Theorem 3). NaN for cameras
    without a centre and for the 5-point camera itself.
    """
    disp = displacements(R, t, centres)
    da = disp[five_camera]
    # atan2(|da x db|, da . db): the angle, accurate near 0; 0 where a
    # displacement vanishes (both terms are then 0)
    out = np.arctan2(np.linalg.norm(_rcross(da, disp), axis=1), disp @ da)
    out[five_camera] = np.nan
    out[~np.all(np.isfinite(centres), axis=1)] = np.nan
    return out


# ------------------------------------------------------------ minimal solver

def _split_sample(rays: RayPairs) -> tuple[np.ndarray, int, np.ndarray, np.ndarray]:
    """Indices of the 5 rays of the 5-point camera and the rest, the camera, centres."""
    cam1, cam2, centres, intra, counts = intra_counts(rays)
    a = int(np.argmax(counts))
    if counts[a] < 5:
        raise ValueError("five_plus_one: need 5 intra-camera correspondences of one camera "
                         f"(most found in one camera: {counts[a]})")
    five = np.flatnonzero(intra & (cam1 == a))
    rest = np.flatnonzero(~(intra & (cam1 == a)))
    return five, a, rest, centres


def minimal_solutions(sample: RayPairs) -> list[tuple[np.ndarray, np.ndarray]]:
    """Every rig motion consistent with a 5+1 sample (5 rays of one camera + 1 other).

    Each 5-point solution is decomposed with the cheirality check and scaled by
    eq. 7.4 from the sixth correspondence; solutions with no scale (``b = 0``,
    the critical configuration for this sample) are dropped.
    """
    five, a, rest, centres = _split_sample(sample)
    five = five[:5]
    out = []
    if rest.size == 0:
        return out
    six = sample.take(np.concatenate([five, rest[:1]]))
    # five bearings in one plane through the centre (to rounding: points on a
    # line) admit a one-parameter family of essential matrices: no solution
    if _bearings_planar(sample.dirs1[five], sample.dirs2[five], 1e-9):
        return out
    for R, t0, w in essential_motions(sample, five, centres[a]):
        ra, rb = scale_terms(sample.take(rest[:1]), R, t0, w)
        if not abs(rb[0]) > 1e-12 * (1.0 + abs(ra[0])):
            continue
        out.append(_polish(six, R, t0 - (ra[0] / rb[0]) * w))
    return out


def _polish(six: RayPairs, R: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Newton-polish a minimal solution on its own 6 correspondences.

    Six residuals, six unknowns: Gauss-Newton converges quadratically to the
    exact solution near it, removing the rounding of the 5-point polynomial
    solver (which alone leaves errors up to ~1e-4 on some configurations).
    Solutions far from consistent (a residual above 1e-2 rad) are left alone.
    """
    r = _core.gec_residuals(six.origins1, six.dirs1, six.origins2, six.dirs2, R, t)
    if not np.all(np.abs(r) < 1e-2) or np.all(r == 0.0):
        return R, t
    try:
        out = _core.refine_motion(six.origins1, six.dirs1, six.origins2, six.dirs2, R, t,
                                  max_iterations=100, cost_tolerance=0.0, step_tolerance=1e-15,
                                  initial_lambda=0.0)
    except (ValueError, DegenerateError):
        return R, t
    return (out["R"], out["t"]) if out["final_cost"] <= out["initial_cost"] else (R, t)


def sample_five_plus_one(rays: RayPairs, rng: np.random.Generator) -> np.ndarray:
    """Draw 5 intra-camera correspondences of a random camera and 1 of another camera.

    The 5-point camera is drawn with probability proportional to its number of
    intra-camera correspondences (among cameras with at least 5); the sixth
    correspondence uniformly among those not of that camera, so that every
    camera takes part in the samples.
    """
    cam1, cam2, centres, intra, counts = intra_counts(rays)
    counts = counts.astype(float)
    counts[counts < 5] = 0.0
    if counts.sum() == 0:
        raise ValueError("five_plus_one: no camera has 5 intra-camera correspondences")
    a = rng.choice(len(counts), p=counts / counts.sum())
    own = np.flatnonzero(intra & (cam1 == a))
    other = np.flatnonzero(~(intra & (cam1 == a)))
    if other.size == 0:
        raise ValueError("five_plus_one: every correspondence is in one camera; the scale "
                         "needs a correspondence of another camera")
    return np.concatenate([rng.choice(own, 5, replace=False), rng.choice(other, 1)])


# -------------------------------------------------------------- estimator

def _choose_camera(rays: RayPairs, five_camera: Optional[int]):
    cam1, cam2, centres, intra, counts = intra_counts(rays)
    if five_camera is None:
        a = int(np.argmax(counts))
    else:
        a = int(five_camera)
        if not 0 <= a < len(counts):
            raise ValueError(f"five_camera {a} is not a camera of these rays (0..{len(counts) - 1})")
    if counts[a] < 5:
        raise ValueError(f"too few correspondences: five_plus_one needs 5 intra-camera "
                         f"correspondences in camera {a}, got {counts[a]}")
    return a, cam1, cam2, centres, np.flatnonzero(intra & (cam1 == a))


def _scale_ls(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """Least-squares scale of eq. 7.4 over many correspondences and its relative std."""
    bb = float(b @ b)
    if not bb > 0.0:
        return float("nan"), float("inf")
    lam = -float(a @ b) / bb
    r = a + lam * b
    dof = max(len(a) - 1, 1)
    sig = np.sqrt(float(r @ r) / dof / bb)
    return lam, (sig / abs(lam) if lam != 0 else float("inf"))


def solve(rays: RayPairs, five_camera: Optional[int] = None,
          essential: Optional[Sequence] = None) -> dict:
    """The linear part of the method on all given correspondences (no refinement).

    Returns a dict with R, t, the 5-point camera, the scale ``lam``, its relative
    std from the residuals of eq. 7.4, the number of scale correspondences and
    the critical angles. ``essential`` may give ``(R, t0, w)`` candidates (e.g.
    from a robust search) instead of running the 5-point solver.
    """
    a, cam1, cam2, centres, own = _choose_camera(rays, five_camera)
    if essential is None:
        essential = essential_motions(rays, own, centres[a])
    if not essential:
        raise DegenerateError(f"five_plus_one: the 5-point solver found no motion in camera {a} "
                              "(too few usable points, or degenerate: no translation)")
    others = np.flatnonzero(~((cam1 == a) & (cam2 == a)))
    best = None
    for R, t0, w in essential:
        if others.size:
            sa, sb = scale_terms(rays.take(others), R, t0, w)
            lam, rel = _scale_ls(sa, sb)
        else:
            lam, rel = float("nan"), float("inf")
        # with no usable scale (critical motion: a ~ 0, lam ~ 0 of random sign)
        # keep the 5-point direction, whose sign the cheirality check fixed
        determined = bool(np.isfinite(lam) and rel <= 1.0)
        t = t0 + (lam if determined else 1.0) * w
        res = np.abs(_core.gec_residuals(rays.origins1, rays.dirs1, rays.origins2,
                                         rays.dirs2, R, t))
        cost = float(np.sum(res ** 2))
        if best is None or cost < best["cost"]:
            best = dict(R=R, t=t, t0=t0, w=w, lam=lam, scale_rel_std=rel, cost=cost,
                        five_camera=a, n_scale=int(others.size), scale_determined=determined)
    best["critical_angles"] = critical_angles(best["R"], best["t"], centres, a)
    return best


def _from_camera(rays: RayPairs, a: int, refine: bool) -> tuple[float, dict, Optional[dict]]:
    """The linear 5+1 solution with camera ``a`` as the 5-point camera, refined
    on all correspondences; returns (final cost, linear solution, refinement)."""
    sol = solve(rays, a)
    if not refine:
        return sol["cost"], sol, None
    # all six degrees of freedom even if |t| is not observable: holding a wrong
    # |t| would bend R and the direction (see mcgeom.robust._finish); with 6
    # rays the square system polishes the minimal solution
    try:
        out = _refine_all(rays, sol["R"], sol["t"], False)
    except DegenerateError:
        out = _refine_all(rays, sol["R"], sol["t"], True)
    return float(out["final_cost"]), sol, out


def _refine_all(rays: RayPairs, R: np.ndarray, t: np.ndarray, fix_scale: bool) -> dict:
    # converged to rounding, not to a relative cost change of 1e-10: the result
    # must not depend on which camera's start won (order, rig frame)
    return refine_centred(rays, R, t, loss="none", fix_scale=fix_scale, max_iterations=100,
                          cost_tolerance=1e-15, step_tolerance=1e-13)


@register(
    "five_plus_one",
    min_sample=6,
    camera_kinds=("most-general", "locally-central", "axial", "locally-central-and-axial"),
    family="minimal",
    needs_rotation=False,
    recovers_scale=True,
    description="5+1 method: 5-point essential matrix in one camera (OpenCV), metric scale "
                "from the other cameras by eq. 7.4, critical angle (thesis ch. 7)",
    options={"five_camera": "camera whose 5-point essential matrix gives R and the direction "
                            "(default: the one with most intra-camera correspondences)",
             "refine": "joint nonlinear refinement on all correspondences (default True)",
             "max_scale_rel_std": "relative std of |t| above which the scale is reported "
                                  "unobservable (0.1)"},
    minimal_solver=minimal_solutions,
    sampler=sample_five_plus_one,
    proposer=lambda rays, thr, prob, rng: propose(rays, thr, prob, rng),
)
def five_plus_one(rays: RayPairs, *, five_camera: Optional[int] = None, refine: bool = True,
                  max_scale_rel_std: float = 0.1) -> RigMotion:
    """Rig motion rig2_from_rig1 (R, t in metres) by the 5+1 method on all correspondences.

    ``rays`` in the rig frame with origins at the camera centres; camera ids
    from ``rays.cam1``/``cam2`` or, if absent, from equal origins. All
    correspondences are taken as inliers (use :func:`mcgeom.robust.ransac` with
    outliers). The scale is the least-squares solution of eq. 7.4 over every
    correspondence not of the 5-point camera, then (``refine``) the motion is
    refined jointly on all correspondences (Sampson angular error). ``info``
    holds the 5-point camera, the critical angles (radians) per camera, the
    linear scale and its relative std. Raises ValueError when no camera has 5
    intra-camera correspondences, DegenerateError when the 5-point solver fails.
    """
    if not isinstance(rays, RayPairs):
        raise TypeError(f"rays must be a RayPairs, got {type(rays).__name__}")
    if len(rays) < 6:
        raise ValueError(f"too few correspondences: five_plus_one needs at least 6, got {len(rays)}")
    rays.check_finite()
    if five_camera is None:
        # every camera that can be the 5-point camera, best final cost wins: the
        # refinement from a single camera's start can stop in a local minimum,
        # and the choice must not depend on the rig frame or the order of rays
        counts = intra_counts(rays)[4]
        cams = [int(k) for k in np.argsort(-counts, kind="stable") if counts[k] >= 5]
        if not cams:
            raise ValueError("too few correspondences: five_plus_one needs 5 intra-camera "
                             f"correspondences in one camera, most found: {int(counts.max())}")
    else:
        cams = [five_camera]
    found, err = [], None
    for a in cams:
        try:
            found.append((a, _from_camera(rays, a, refine)))
        except DegenerateError as e:
            err = e
    if not found:
        raise err if err is not None else DegenerateError("five_plus_one: no motion found")
    # Several starts usually reach the same minimum, equal in cost to rounding;
    # among those take the lowest camera id, so that the end point (equal only
    # to the refinement's tolerance) does not depend on the order of the rays.
    low = min(c[0] for _, c in found)
    _, (_, sol, out) = min((fa for fa in found if fa[1][0] <= low * (1 + 1e-9) + 1e-300),
                           key=lambda fa: fa[0])
    R, t, rel = sol["R"], sol["t"], sol["scale_rel_std"]
    info = {"five_camera": sol["five_camera"], "critical_angles": sol["critical_angles"],
            "scale_linear": sol["lam"], "scale_rel_std_linear": rel,
            "n_scale_correspondences": sol["n_scale"], "cameras_tried": cams}
    # the verdict rests on the refined evidence only (not on which camera's
    # linear start won: several converge to the same minimum)
    fixed = sol["n_scale"] == 0 or (out is None and not sol["scale_determined"])
    if out is not None:
        R, t = out["R"], out["t"]
        if len(rays) > 6:
            rel = float(out["scale_rel_std"]) if not fixed else float("inf")
            info["refinement"] = {k: out[k] for k in ("iterations", "converged") if k in out}
            if rel <= max_scale_rel_std:
                k = 1.0 + 3.0 * max_scale_rel_std
                info["scale_profile"] = scale_profile(rays, R, t, out["final_cost"],
                                                      out["sigma2"], (1.0 / k, k))
                if info["scale_profile"] < 9.0:
                    rel = float("inf")
    sol["critical_angles"] = critical_angles(R, t, camera_ids(rays)[2], sol["five_camera"])
    info["critical_angles"] = sol["critical_angles"]
    verdict = scale_verdict(rays, np.ones(len(rays), bool), R, t, rel, max_scale_rel_std,
                            fixed)
    info["t_metric"] = np.array(t)   # metric estimate, whatever the verdict
    if not verdict.observable:
        nt = np.linalg.norm(t)
        t = travel_direction(rays, np.ones(len(rays), bool), R, t)
        info["t_metric"] = nt * t
    r = np.abs(_core.gec_residuals(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, R, t))
    return RigMotion(R, t, verdict, "five_plus_one", float(np.sqrt(np.mean(r ** 2))), None, info)


#: The 5-point search of :func:`propose` counts inliers within this many
#: thresholds. At 1 threshold it sees ~60 % of a camera's points as inliers at
#: 30 % outliers and 0.5 px noise (the Sampson distance of a true match exceeds
#: 1 px for ~16 % of them), which needs ~60 adaptive USAC iterations; at 2 it sees
#: ~69 % and needs ~27. Measured on the Ladybug head (300 problems): USAC 2.4 ->
#: 1.2 ms per call, rotation median 0.0177 -> 0.0176 deg, scale median 0.182 ->
#: 0.175; the motion is scored and refined on every camera at 1 threshold anyway.
_SEARCH_WIDENING = 2.0


def _bearings_planar(d1: np.ndarray, d2: np.ndarray, tol: float) -> bool:
    """True if all bearings at time 1, or all at time 2, lie within ``tol``
    (RMS, radians) of one plane through the camera centre. Tested on every
    ray of the camera, outliers included: if even they fit a plane, so do its
    inliers, and the 5-point problem is degenerate (see _check_not_planar)."""
    return _plane_rms(d1) <= tol or _plane_rms(d2) <= tol


def propose(rays: RayPairs, threshold: float, prob: float, rng: np.random.Generator,
            max_cameras: int = 3, scale_samples: int = 64):
    """Two-stage robust hypotheses of thesis ch. 7.4 (Fig. 7.6), camera after camera.

    For the cameras in decreasing number of intra-camera correspondences (up
    to ``max_cameras``): the essential matrix by OpenCV's robust 5-point search
    (USAC at ``_SEARCH_WIDENING`` times ``threshold``, radians ~ normalised image
    units), then the scale by a
    1-point RANSAC over the correspondences of all other cameras (eq. 7.4). A
    generator of ``(R, t, expected_inlier_ratio)``, the last being the fraction
    of its camera's points within ``threshold`` of the 5-point search's model: the caller scores each
    motion on all correspondences and stops asking once one explains about
    that fraction everywhere (the usual case: one camera is enough).
    """
    import cv2
    cam1, cam2, centres, intra, counts = intra_counts(rays)
    order = [int(k) for k in np.argsort(-counts, kind="stable") if counts[k] >= 8][:max_cameras]
    for a in order:
        own = np.flatnonzero(intra & (cam1 == a))
        if _bearings_planar(rays.dirs1[own], rays.dirs2[own], threshold):
            continue   # every ray (outliers too) within the threshold of one plane
        stats: dict = {}
        try:
            # 0.99 is enough here: the motion is checked on every camera and the
            # next camera is tried when it falls short
            # (and at most 300 samples: enough up to ~55 % outliers in that
            # camera; beyond, the next camera is tried rather than waiting)
            cands = essential_motions(rays, own, centres[a], method=USAC_EXPLICIT,
                                      threshold=_SEARCH_WIDENING * threshold,
                                      prob=min(prob, 0.99), stats=stats, max_iters=300,
                                      planar_check=False, ratio_threshold=threshold)
        except (DegenerateError, cv2.error):
            continue
        # A correspondence between cameras centred where camera a is (a central
        # rig, coincident centres) has e(lam) = lam b (eq. 7.4 with a = 0): its
        # only root is lam = 0, the trivial motion whose epipolar constraint
        # vanishes for every such ray (zero residuals, a false consensus).
        # Only cameras with another centre can fix the scale.
        here = np.all(np.abs(centres - centres[a]) <= 1e-9 * (1.0 + np.abs(centres[a]).max()),
                      axis=1)
        others = np.flatnonzero(~(here[cam1] & here[cam2]))
        if others.size == 0:   # one camera (or one centre) only: R and the direction, no scale
            for R, t0, w in cands:
                yield R, t0 + w, stats.get("inlier_ratio", 1.0)
            continue
        # Cross-camera correspondences fix the scale whatever the motion, while
        # near the critical motion the intra-camera ones of the other cameras
        # hardly depend on it -- but their thousands of small, model-error-driven
        # slopes can outvote the informative few. Score on the cross ones when
        # there are enough of them.
        cross = np.flatnonzero(~intra)
        sub = rays.take(cross if cross.size >= 20 else others)
        for R, t0, w in cands:
            lam = scale_one_point_ransac(sub, R, t0, w, threshold, rng, scale_samples, prob)
            if lam is not None:
                yield R, t0 + lam * w, stats.get("inlier_ratio", 1.0)


def scale_one_point_ransac(rays: RayPairs, R: np.ndarray, t0: np.ndarray, w: np.ndarray,
                           threshold: float, rng: np.random.Generator,
                           samples: int = 64, prob: float = 0.999) -> Optional[float]:
    """The scale ``lam`` of ``t = t0 + lam w`` by 1-point RANSAC (thesis ch. 7.4).

    Each of up to ``samples`` correspondences, in a random order, proposes
    ``lam = -a / b`` (eq. 7.4); the proposals are scored by MSAC on the Sampson
    angular residuals (``threshold`` radians) of every correspondence, in
    batches of 16 with the adaptive stop of a 1-point sample (``prob``); the
    best is re-estimated by weighted least squares on its inliers
    (``_core.scale_ransac``). Only ``lam > 0`` is considered: the
    5-point camera's cheirality check fixed the sense of its own travel ``lam
    w``, and near the critical motion the Sampson error hardly tells ``lam``
    from ``-lam`` (each camera's epipolar constraint ignores the sign of its
    translation), so a negative proposal often wins by noise -- a reversed
    travel from which the final refinement cannot recover (it slides |t| to
    infinity instead of crossing it; measured: a quarter of the Ladybug
    hypotheses). None if no correspondence proposes a positive scale.
    """
    # The search runs in C (csrc/scale_line.c): the proposals' MSAC scores
    # over every correspondence and the least-squares step were ~0.5 ms of
    # numpy per call, a tenth of a Ladybug problem. The random order is drawn
    # here, among the correspondences that propose a positive scale, as the
    # numpy search did: the same random stream gives the same hypotheses.
    a, b = _scale_line_terms(rays, R, t0, w)
    ok = np.flatnonzero((np.abs(b) > 1e-9 * (1.0 + np.abs(a))) & (a * b < 0.0))
    if ok.size == 0:
        return None
    found = _core.scale_ransac(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, R, t0, w,
                               rng.permutation(ok)[:samples], threshold, prob, samples)
    return None if found is None else found[0]


def _scale_line_terms(rays: RayPairs, R: np.ndarray, t0: np.ndarray,
                      w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The epipolar residual ``a + lam b`` (eq. 7.4) of each correspondence
    along ``t = t0 + lam w``, unit bearings: ``e = d2 . (s x R d1)`` with ``s =
    t0 + lam w + R o1 - o2`` (the numerator of the Sampson residual that
    ``_core.scale_ransac`` scores)."""
    d1 = rays.dirs1 / np.linalg.norm(rays.dirs1, axis=1, keepdims=True)
    d2 = rays.dirs2 / np.linalg.norm(rays.dirs2, axis=1, keepdims=True)
    rd1 = d1 @ R.T
    s0 = t0 + rays.origins1 @ R.T - rays.origins2
    return (np.einsum("ij,ij->i", d2, _rcross(s0, rd1)),
            np.einsum("ij,ij->i", d2, _rcross(w, rd1)))
