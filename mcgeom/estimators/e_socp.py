"""``e_socp``: per-camera essential matrices, then L-infinity triangulation (thesis ch. 9).

Each camera ``i`` with enough intra-camera correspondences gives, through its
essential matrix (OpenCV's 5-point solver with RANSAC, the same code as the 5+1
method), the rig rotation ``R_i`` and a half-line of possible rig translations.
In our convention (docs/architecture.md §3, ``X2 = R X1 + t``) camera ``i``'s centre
``c_i`` moves to ``R^T (c_i - t)`` and its own translation direction is ``w_i``:

    t = t0_i + lam_i w_i,   t0_i = c_i - R c_i,   lam_i >= 0,

which is eq. 9.2 written for ``t`` rather than for the first camera's new
centre (the two differ by a known rigid map). The rotations are averaged
(chordal L2 mean projected onto SO(3)); ``t`` is then the point that
minimises the largest angle between ``t - t0_i`` and ``w_i`` (eq. 9.3): the
L-infinity triangulation, solved exactly by cone bisection in C
(``csrc/cone.c``).

Cross-camera correspondences (camera ``a`` at time 1, ``b`` at time 2) give
one more cone per camera pair, of the same form with apex ``c_b - R c_a`` (see
:func:`_cross_cones`): ch. 9's triangulation with the pair's baseline in place
of a camera's own translation.

Near-zero rotation makes every intra-camera apex ``t0_i`` collapse to the
origin: without a cross-camera pair all half-lines then share their apex and
the scale is free (ch. 9.5). The verdict says so, with the SOCP residual and
the rotation angle in ``info`` so that a caller can reject such frames as
ch. 9.5 suggests. Where the scale is fixed, its relative std is that of the
correspondences the cones came from (least squares) combined with the distance
of the L-infinity |t| from their optimum: the verdict reflects the data used.
"""

from __future__ import annotations

from typing import Optional

import numpy as np

from .. import _core
from ..errors import DegenerateError, InfeasibleError
from ..geometry import centroid_travel, rcross, refine_centred, unit_rows
from ..observability import scale_verdict
from ..registry import register
from ..types import RayPairs, RigMotion
from ._common import camera_ids, intra_counts
from ._static import with_static_check
from .essential import LEAST_SQUARES, essential_motions

__all__ = ["e_socp", "average_rotations"]


def average_rotations(Rs: np.ndarray, weights: Optional[np.ndarray] = None
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Chordal L2 mean of rotations (the SO(3) projection of their weighted sum)
    and the angle (radians) of each rotation from it."""
    Rs = np.asarray(Rs, dtype=np.float64)
    w = np.ones(len(Rs)) if weights is None else np.asarray(weights, dtype=np.float64)
    M = np.einsum("k,kij->ij", w, Rs)
    u, _, vt = np.linalg.svd(M)
    R = u @ np.diag([1.0, 1.0, np.linalg.det(u @ vt)]) @ vt
    cos = np.clip((np.einsum("kij,ij->k", Rs, R) - 1.0) / 2.0, -1.0, 1.0)
    return R, np.arccos(cos)


def _per_camera(rays: RayPairs, robust_threshold: Optional[float], prob: float):
    """(camera, R_i, t0_i, w_i, n_i) for every camera whose essential matrix was found."""
    import cv2
    cam1, cam2, centres, intra, counts = intra_counts(rays)
    out, failures = [], []
    for a in np.flatnonzero(counts >= 5):
        own = np.flatnonzero(intra & (cam1 == a))
        method = LEAST_SQUARES if robust_threshold is None or len(own) < 8 else cv2.USAC_DEFAULT
        try:
            cands = essential_motions(rays, own, centres[a], method=method,
                                      threshold=robust_threshold or 1e-3, prob=prob)
        except DegenerateError as e:
            failures.append(f"camera {a}: {e}")
            continue
        if not cands:
            failures.append(f"camera {a}: the 5-point solver found no motion")
            continue
        R, t0, w = cands[0]
        if len(own) >= 6:
            R, w = _refine_camera(rays.take(own), centres[a], R, w, robust_threshold)
            t0 = centres[a] - R @ centres[a]
        out.append((int(a), R, t0, w, len(own)))
    if not out and failures:
        # cameras with enough correspondences, none of them usable: say why
        raise DegenerateError("e_socp: no camera's essential matrix is determined (" +
                              "; ".join(failures) + ")")
    return out, centres


def _refine_camera(sub: RayPairs, c: np.ndarray, R: np.ndarray, w: np.ndarray,
                   robust_threshold: Optional[float]) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares (Sampson) rotation and translation direction of one camera.

    The 5-point solution fits 5 points exactly and the others not at all; the
    per-camera essential matrix of ch. 9 is the estimate from all of them. In a
    frame centred on the camera its motion is ``(R, lam w)``; one camera cannot
    see ``lam``, so the refinement holds ``|t| = 1`` there and returns the
    unit direction ``w`` (independent of the world's scale and origin).
    """
    centred = sub.in_frame(np.eye(3), -c)
    loss = "none" if robust_threshold is None else "cauchy"
    out = _core.refine_motion(centred.origins1, centred.dirs1, centred.origins2,
                              centred.dirs2, R, w, loss=loss,
                              loss_scale=robust_threshold or 1e-3, fix_scale=True,
                              max_iterations=100, cost_tolerance=1e-15, step_tolerance=1e-13)
    return out["R"], out["t"] / np.linalg.norm(out["t"])


@register(
    "e_socp",
    min_sample=10,
    camera_kinds=("locally-central", "locally-central-and-axial"),
    family="globally-optimal",
    needs_rotation=False,
    recovers_scale=True,
    description="E+SOCP: per-camera essential matrices, rotation averaging and L-infinity "
                "triangulation of the translation by cone bisection (thesis ch. 9)",
    options={"robust_threshold": "RANSAC threshold of each camera's 5-point search, radians "
                                 "(default 1e-3; None: outlier-free data, least squares)",
             "tolerance": "bisection tolerance on the L-infinity angle, radians (1e-12)",
             "max_scale_rel_std": "relative std of |t| above which the scale is reported "
                                  "unobservable (0.1)"},
)
def e_socp(rays: RayPairs, *, robust_threshold: Optional[float] = 1e-3, prob: float = 0.999,
           tolerance: float = 1e-12, max_scale_rel_std: float = 0.1) -> RigMotion:
    """Rig motion rig2_from_rig1 by E+SOCP (thesis ch. 9).

    ``rays`` in the rig frame, origins at the camera centres. The rotation is
    the mean of the rotations of the cameras with 5 intra-camera
    correspondences; each such camera, and each cross-camera pair (camera a
    at time 1, b at time 2) with 5 correspondences, is a cone on ``t``
    (:func:`_cross_cones`); ``t`` is their L-infinity intersection (eq. 9.3).
    The metric scale needs two cameras with enough rotation or a cross-camera
    pair. The verdict rests on the correspondences the cones were built from:
    the relative std of |t| is that of their least-squares optimum combined
    with the relative distance of the L-infinity |t| from it (observable when
    at most ``max_scale_rel_std``).
    ``info``: per-camera rotations' spread from their mean (radians), the SOCP
    residual (the optimal L-infinity angle, radians), the frame-to-frame
    rotation angle (radians), the cameras and cross pairs used, the active
    cones, ``scale_ls_ratio`` (L-infinity over least-squares |t|) and
    ``scale_rel_std_ls`` (the least-squares relative std alone).
    """
    if not isinstance(rays, RayPairs):
        raise TypeError(f"rays must be a RayPairs, got {type(rays).__name__}")
    if robust_threshold is not None and (
            isinstance(robust_threshold, (bool, np.bool_))
            or not isinstance(robust_threshold, (int, float, np.number))
            or not (np.isfinite(robust_threshold) and robust_threshold > 0)):
        # 0 would silently mean the 1e-3 default below, -1 fail as "loss_scale"
        raise ValueError(f"robust_threshold must be None (least squares) or a finite angle "
                         f"> 0 (radians), got {robust_threshold!r}")
    rays.check_finite()
    # one order for any input order: the per-camera searches and the
    # bisections then give the same answer bit for bit
    rays = rays.take(rays.canonical_order())
    # no camera's essential matrix (DegenerateError): a static rig has none (E
    # = 0); or its cameras' noise directions admit no common point (InfeasibleError)
    return with_static_check(rays, "e_socp", lambda: _e_socp(
        rays, robust_threshold, prob, tolerance, max_scale_rel_std),
        errors=(DegenerateError, InfeasibleError))


def _e_socp(rays: RayPairs, robust_threshold: Optional[float], prob: float, tolerance: float,
            max_scale_rel_std: float) -> RigMotion:
    """:func:`e_socp` on checked, canonically ordered rays, without the static-rig test."""
    per, centres = _per_camera(rays, robust_threshold, prob)
    if not per:
        raise ValueError("too few correspondences: e_socp needs 5 intra-camera "
                         "correspondences in at least one camera")
    R, spread = average_rotations(np.stack([p[1] for p in per]),
                                  np.array([p[4] for p in per], dtype=float))
    cross = _cross_cones(rays, R, centres, robust_threshold)
    # the cones: camera i's own half-line t = c_i - R c_i + lam w_i (eq. 9.2,
    # mean R) and each cross-camera pair's t = c_b - R c_a + lam w_ab
    apex = np.stack([centres[p[0]] - R @ centres[p[0]] for p in per] +
                    [q[2] for q in cross])
    axis = np.stack([p[3] for p in per] + [q[3] for q in cross])
    names = [p[0] for p in per] + [(q[0], q[1]) for q in cross]
    used = np.zeros(len(rays), bool)
    cam1, cam2 = camera_ids(rays)[:2]
    for p in per:
        used |= (cam1 == p[0]) & (cam2 == p[0])
    for q in cross:
        used[q[4]] = True
    info = {"cameras": [p[0] for p in per], "cross_pairs": [(q[0], q[1]) for q in cross],
            "rotation_spread": spread, "n_used": int(np.count_nonzero(used)),
            "n_cross_used": int(sum(len(q[4]) for q in cross)),
            "rotation_angle": float(np.arccos(np.clip((np.trace(R) - 1) / 2, -1, 1)))}
    degenerate_scale = len(apex) == 1
    if len(apex) == 1:
        t = axis[0] + apex[0]
        info["socp_residual"] = 0.0
    else:
        sol = _core.cone_linf(apex, axis, tolerance=tolerance)
        t = np.asarray(sol["X"], dtype=np.float64)
        info["socp_residual"] = float(sol["gamma"])
        info["socp_lower_bound"] = float(sol["gamma_lower"])
        info["active_cones"] = [names[k] for k in sol["active"]]
        # all apexes equal (no rotation, no cross-camera pair) or parallel
        # half-lines: |t| is free
        degenerate_scale = bool(sol["coincident_apexes"] or sol["at_infinity"])
    rel_ls, ratio = _scale_evidence(rays.take(np.flatnonzero(used)), R, t, degenerate_scale)
    info["scale_ls_ratio"] = ratio
    info["scale_rel_std_ls"] = rel_ls
    # the uncertainty of the |t| returned: the least-squares one of the same
    # data plus how far the L-infinity solution lies from that optimum (the
    # L-infinity estimate is the less efficient one; a |t| several std from
    # the data's optimum must not be reported with the optimum's std)
    rel = float(np.hypot(rel_ls, ratio - 1.0)) if np.isfinite(ratio) else float("inf")
    verdict = scale_verdict(rays, used, R, t, rel, max_scale_rel_std, degenerate_scale)
    info["t_metric"] = np.array(t)
    if not verdict.observable:
        t = t / max(np.linalg.norm(t), 1e-300)
    r = np.abs(_core.gec_residuals(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, R, t))
    return RigMotion(R, t, verdict, "e_socp", float(np.sqrt(np.mean(r ** 2))), None, info)


#: fewest correspondences of a cross-camera pair (camera a at time 1, b at
#: time 2) that make a cone: 5, as a camera's own essential matrix
_MIN_CROSS = 5


def _cross_cones(rays: RayPairs, R: np.ndarray, centres: np.ndarray,
                 robust_threshold: Optional[float] = None) -> list:
    """One cone per cross-camera pair ``(a, b)`` with at least 5 correspondences.

    With the rotation known, camera ``b`` at time 2 sits at ``R^T (c_b - t)``
    in the time-1 rig frame; its baseline from camera ``a`` at time 1,
    ``B = R^T (c_b - t) - c_a``, is coplanar with every pair of rays ``d1``,
    ``R^T d2`` of the pair (the epipolar constraint of the two views, thesis
    ch. 2.3): ``B . (d1 x R^T d2) = 0``. Its direction ``b`` is the
    least-squares null vector of these rows (sign by cheirality), so that
    ``t = c_b - R c_a - lam R b``, ``lam >= 0``: a half-line exactly like a
    camera's own (eq. 9.2 with ``c_a`` at time 1 and ``c_b`` at time 2), and
    its cone enters the same L-infinity problem (eq. 9.3). The apex ``c_b - R
    c_a`` differs from the intra-camera apexes ``c_i - R c_i`` even without
    rotation: the cross-camera pairs fix the scale where the intra-camera ones
    cannot (ch. 7.3.2). With ``robust_threshold`` (radians) the direction is
    found by a 2-point RANSAC on the Sampson angular residuals and refitted
    on its inliers (an L-infinity solution follows any outlier). Returns
    ``[(a, b, apex, axis, indices used)]``.
    """
    cam1, cam2 = camera_ids(rays)[:2]
    sel = np.flatnonzero(cam1 != cam2)
    out = []
    if sel.size < _MIN_CROSS:
        return out
    keys = np.unique(np.stack([cam1[sel], cam2[sel]], axis=1), axis=0)
    for a, b in keys:
        idx = sel[(cam1[sel] == a) & (cam2[sel] == b)]
        if idx.size < _MIN_CROSS:
            continue
        d1 = unit_rows(rays.dirs1[idx])
        d2 = unit_rows(rays.dirs2[idx]) @ R          # rows R^T d2: time-1 rig frame
        rows = rcross(d1, d2)
        sub = rays.take(idx)

        def residuals(u: np.ndarray) -> np.ndarray:
            # Sampson angular residuals of the pair for the baseline u (unit
            # length: one pair of centres does not see the length)
            return np.abs(_core.gec_residuals(sub.origins1, sub.dirs1, sub.origins2, sub.dirs2,
                                              R, centres[b] - R @ (centres[a] + u)))

        keep = np.ones(idx.size, bool)
        if robust_threshold is not None:
            keep = _robust_direction(rows, residuals, robust_threshold)
            if np.count_nonzero(keep) < _MIN_CROSS:
                continue
        w, v = np.linalg.eigh(rows[keep].T @ rows[keep])
        if not w[1] > 1e-12 * max(w[2], 1e-300):
            continue   # the rows do not fix a direction (all rays in one plane)
        u = v[:, 0]
        # cheirality: with B = +u the rays meet in front of both cameras
        # (s1 d1 - s2 d2 = B by least squares, row by row)
        dd = np.einsum("ij,ij->i", d1, d2)[keep]
        den = 1.0 - dd * dd
        ok = den > 1e-12
        bu1, bu2 = d1[keep] @ u, d2[keep] @ u
        s1 = (bu1 - dd * bu2) / np.where(ok, den, 1.0)
        s2 = (dd * bu1 - bu2) / np.where(ok, den, 1.0)
        plus = np.count_nonzero(ok & (s1 > 0) & (s2 > 0))
        minus = np.count_nonzero(ok & (s1 < 0) & (s2 < 0))
        if minus > plus:
            u = -u
        apex = centres[b] - R @ centres[a]
        out.append((int(a), int(b), apex, -(R @ u), idx[keep]))
    return out


def _robust_direction(rows: np.ndarray, residuals, threshold: float,
                      samples: int = 64) -> np.ndarray:
    """Inlier mask of a baseline direction by 2-point RANSAC: two rows fix
    the direction (their cross product), the one with most residuals under
    ``threshold`` (radians) wins, then its least-squares refit's inliers. The
    samples are the first pairs of a fixed pseudo-random order, so the result
    depends on the (canonically ordered) data only."""
    n = len(rows)
    rng = np.random.default_rng(n)
    best, best_count = np.ones(n, bool), -1
    for _ in range(samples):
        i, j = rng.choice(n, 2, replace=False)
        u = np.cross(rows[i], rows[j])
        nu = np.linalg.norm(u)
        if not nu > 0:
            continue
        inl = residuals(u / nu) < threshold
        c = int(np.count_nonzero(inl))
        if c > best_count:
            best, best_count = inl, c
    if best_count < 2:
        return best
    u = np.linalg.eigh(rows[best].T @ rows[best])[1][:, 0]
    return residuals(u) < threshold


def _scale_evidence(used: RayPairs, R: np.ndarray, t: np.ndarray,
                    degenerate: bool) -> tuple[float, float]:
    """Relative std of |t| from the correspondences the cones were built from,
    and the ratio of the L-infinity |t| to their least-squares optimum's.

    The std is that of the Sampson least-squares optimum (first order, the
    information matrix of :func:`mcgeom.geometry.refine_centred` started at
    the cone solution); the ratio says whether the cone solution is where
    these data put |t| (inf, nan when the data do not fix it).
    """
    if degenerate or len(used) < 6:
        return float("inf"), float("nan")
    try:
        ls = refine_centred(used, R, t, max_iterations=50)
    except (ValueError, DegenerateError):
        return float("inf"), float("nan")
    rel = float(ls["scale_rel_std"])
    tau = centroid_travel(used, R, t)
    tau_ls = centroid_travel(used, ls["R"], ls["t"])
    return rel, (tau / tau_ls if tau_ls > 0 else float("inf"))
