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
from ..observability import orient_by_cheirality
from ..registry import register
from ..types import RayPairs, RigMotion, ScaleVerdict

__all__ = [
    "five_plus_one", "camera_ids", "essential_motions", "scale_terms",
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


def _local_frame(dirs: np.ndarray) -> np.ndarray:
    """A rotation Q with Q @ (mean direction of ``dirs``) = +z."""
    u = dirs / np.linalg.norm(dirs, axis=1, keepdims=True)
    z = u.mean(axis=0)
    nz = np.linalg.norm(z)
    if not nz > 1e-6:
        raise DegenerateError("five_plus_one: the rays of the 5-point camera point in all "
                              "directions; no common image plane")
    z /= nz
    x = np.cross([0.0, 1.0, 0.0] if abs(z[1]) < 0.9 else [1.0, 0.0, 0.0], z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
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


def _sampson_sq(E: np.ndarray, x1: np.ndarray, x2: np.ndarray) -> np.ndarray:
    """Squared Sampson distances of normalised image points under E."""
    h1 = np.c_[x1, np.ones(len(x1))]
    h2 = np.c_[x2, np.ones(len(x2))]
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
    order = np.lexsort((x2[:, 1], x2[:, 0], x1[:, 1], x1[:, 0]))
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

def essential_motions(rays: RayPairs, index: np.ndarray, centre: np.ndarray,
                      method: int = LEAST_SQUARES, threshold: float = 1e-3,
                      prob: float = 0.999) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Rig rotations and scale lines from the 5-point solver on one camera's rays.

    ``index`` selects intra-camera correspondences of one camera whose centre
    is ``centre`` (rig frame). With exactly 5 correspondences every solution of
    the 5-point solver is returned; with more, ``LEAST_SQUARES`` (outlier-free
    data) or OpenCV's robust search (``method`` a cv2 flag, ``threshold`` in
    normalised image units, ``prob``) picks one.
    Returns a list of ``(R, t0, w)``: rig rotation and the line ``t(lam) = t0 +
    lam w`` of rig translations (metres per unit ``lam``, ``|w| = 1``).
    """
    d1, d2 = rays.dirs1[index], rays.dirs2[index]
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
        E, _ = cv2.findEssentialMat(x1, x2, np.eye(3), method=method, prob=prob,
                                    threshold=threshold)
        if E is None or E.shape[0] % 3 or not np.all(np.isfinite(E)):
            return []
        Es = list(E.reshape(-1, 3, 3))
    out = []
    for Ek in Es:
        n_front, Ra, u, _ = cv2.recoverPose(Ek, x1, x2, np.eye(3))
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
    m1 = np.cross(rays.origins1, d1)
    m2 = np.cross(rays.origins2, d2)
    a = (np.einsum("ij,ij->i", d2, np.cross(t0, rd1)) + np.einsum("ij,ij->i", d2, m1 @ R.T)
         + np.einsum("ij,ij->i", m2, rd1))
    b = np.einsum("ij,ij->i", d2, np.cross(w, rd1))
    return a, b


def critical_angles(R: np.ndarray, t: np.ndarray, centres: np.ndarray,
                    five_camera: int) -> np.ndarray:
    """Critical angle (radians) of every camera w.r.t. the 5-point camera (ch. 7.5.2).

    The angle between the displacements ``R^T (c - t) - c`` of the two camera
    centres (in the time-1 rig frame); 0 means the scale cannot be fixed from
    that camera's intra-camera correspondences (Theorem 3). NaN for cameras
    without a centre and for the 5-point camera itself.
    """
    disp = (centres - t) @ R - centres          # rows: R^T (c - t) - c
    da = disp[five_camera]
    na = np.linalg.norm(da)
    out = np.full(len(centres), np.nan)
    for k in range(len(centres)):
        if k == five_camera or not np.all(np.isfinite(centres[k])):
            continue
        nb = np.linalg.norm(disp[k])
        if na > 0 and nb > 0:
            c = np.linalg.norm(np.cross(da, disp[k])) / (na * nb)
            out[k] = float(np.arctan2(c, np.dot(da, disp[k]) / (na * nb)))
        else:
            out[k] = 0.0
    return out


# ------------------------------------------------------------ minimal solver

def _split_sample(rays: RayPairs) -> tuple[np.ndarray, int, np.ndarray, np.ndarray]:
    """Indices of the 5 rays of the 5-point camera and the rest, the camera, centres."""
    cam1, cam2, centres = camera_ids(rays)
    intra = cam1 == cam2
    counts = np.bincount(cam1[intra], minlength=len(centres))
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
    for R, t0, w in essential_motions(sample, five, centres[a]):
        if rest.size == 0:
            continue
        ra, rb = scale_terms(sample.take(rest[:1]), R, t0, w)
        if not abs(rb[0]) > 1e-12 * (1.0 + abs(ra[0])):
            continue
        out.append((R, t0 - (ra[0] / rb[0]) * w))
    return out


def sample_five_plus_one(rays: RayPairs, rng: np.random.Generator) -> np.ndarray:
    """Draw 5 intra-camera correspondences of a random camera and 1 of another camera.

    The 5-point camera is drawn with probability proportional to its number of
    intra-camera correspondences (among cameras with at least 5); the sixth
    correspondence uniformly among those not of that camera, so that every
    camera takes part in the samples.
    """
    cam1, cam2, centres = camera_ids(rays)
    intra = cam1 == cam2
    counts = np.bincount(cam1[intra], minlength=len(centres)).astype(float)
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
    cam1, cam2, centres = camera_ids(rays)
    intra = cam1 == cam2
    counts = np.bincount(cam1[intra], minlength=len(centres))
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


def _verdict(sol: dict, rel_std: float, max_rel_std: float, fixed: bool) -> ScaleVerdict:
    ang = sol["critical_angles"]
    crit = float(np.nanmax(ang)) if np.any(np.isfinite(ang)) else float("nan")
    if sol["n_scale"] == 0:
        return ScaleVerdict(False, "only one camera has correspondences: the scale needs a "
                                   "correspondence of another camera (thesis ch. 7.3)",
                            0.0, float("inf"), crit)
    if fixed or not np.isfinite(rel_std) or rel_std > max_rel_std:
        why = ("critical configuration: the camera displacements are parallel (no rotation, "
               "thesis ch. 7.3.2, Theorem 3)" if not crit > 1e-3 else
               "scale too uncertain for the noise level (near-critical motion)")
        return ScaleVerdict(False, f"{why}; relative std of |t| {rel_std:.3g}, critical angle "
                                   f"{np.degrees(crit):.3g} deg", float("nan"), rel_std, crit)
    return ScaleVerdict(True, f"scale fixed: relative std {rel_std:.3g}, critical angle "
                              f"{np.degrees(crit):.3g} deg", float("nan"), rel_std, crit)


def _refine_all(rays: RayPairs, R: np.ndarray, t: np.ndarray, fix_scale: bool) -> dict:
    return _core.refine_motion(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, R, t,
                               loss="none", fix_scale=fix_scale)


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
    for name in ("origins1", "dirs1", "origins2", "dirs2"):
        if not np.all(np.isfinite(getattr(rays, name))):
            raise ValueError(f"rays.{name} contains NaN or inf")
    sol = solve(rays, five_camera)
    R, t, rel = sol["R"], sol["t"], sol["scale_rel_std"]
    info = {"five_camera": sol["five_camera"], "critical_angles": sol["critical_angles"],
            "scale_linear": sol["lam"], "scale_rel_std_linear": rel,
            "n_scale_correspondences": sol["n_scale"]}
    fixed = sol["n_scale"] == 0 or not sol["scale_determined"]
    if refine and len(rays) > 6:
        out = _refine_all(rays, R, t, fixed)
        if not fixed and not out["scale_rel_std"] <= max_scale_rel_std:
            out2 = _refine_all(rays, out["R"], out["t"], True)
            info["refinement_unfixed"] = out
            out, fixed = out2, True
        R, t = out["R"], out["t"]
        rel = float(out["scale_rel_std"]) if not fixed else float("inf")
        info["refinement"] = {k: out[k] for k in ("iterations", "converged") if k in out}
    elif refine:
        out = _refine_all(rays, R, t, fixed)  # square system: polish the minimal solution
        R, t = out["R"], out["t"]
    sol["critical_angles"] = critical_angles(R, t, camera_ids(rays)[2], sol["five_camera"])
    info["critical_angles"] = sol["critical_angles"]
    verdict = _verdict(sol, rel, max_scale_rel_std, fixed)
    if not verdict.observable:
        t = orient_by_cheirality(rays, R, t / np.linalg.norm(t))
    r = np.abs(_core.gec_residuals(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, R, t))
    return RigMotion(R, t, verdict, "five_plus_one", float(np.sqrt(np.mean(r ** 2))), None, info)


def propose(rays: RayPairs, threshold: float, prob: float, rng: np.random.Generator,
            max_cameras: int = 2, scale_samples: int = 64) -> list[tuple[np.ndarray, np.ndarray]]:
    """Two-stage robust hypotheses of thesis ch. 7.4 (Fig. 7.6), spread over cameras.

    For each of the ``max_cameras`` cameras with most intra-camera
    correspondences: the essential matrix by OpenCV's robust 5-point search
    (USAC, ``threshold`` radians ~ normalised image units), then the scale by a
    1-point RANSAC over the correspondences of all other cameras (eq. 7.4 from
    each of up to ``scale_samples`` of them, scored by MSAC on all of them).
    Returns the motions found (the caller scores and refines them).
    """
    import cv2  # noqa: F401  (documented dependency of this path)
    cam1, cam2, centres = camera_ids(rays)
    intra = cam1 == cam2
    counts = np.bincount(cam1[intra], minlength=len(centres))
    order = [int(k) for k in np.argsort(-counts, kind="stable") if counts[k] >= 8][:max_cameras]
    out = []
    for a in order:
        own = np.flatnonzero(intra & (cam1 == a))
        try:
            cands = essential_motions(rays, own, centres[a], method=cv2.USAC_DEFAULT,
                                      threshold=threshold, prob=prob)
        except (DegenerateError, cv2.error):
            continue
        others = np.flatnonzero(~(intra & (cam1 == a)))
        if others.size == 0:
            continue
        sub = rays.take(others)
        for R, t0, w in cands:
            sa, sb = scale_terms(sub, R, t0, w)
            ok = np.flatnonzero(np.abs(sb) > 1e-9 * (1.0 + np.abs(sa)))
            if ok.size == 0:
                continue
            pick = rng.choice(ok, min(scale_samples, ok.size), replace=False)
            best, best_score = None, np.inf
            for i in pick:
                lam = -sa[i] / sb[i]
                r = np.abs(_core.gec_residuals(sub.origins1, sub.dirs1, sub.origins2, sub.dirs2,
                                               R, t0 + lam * w))
                score = float(np.minimum(r * r, threshold * threshold).sum())
                if score < best_score:
                    best, best_score = lam, score
            out.append((R, t0 + best * w))
    return out
