"""Helpers shared by several estimators (and by :mod:`mcgeom.robust`).

* camera grouping: :func:`camera_ids`, :func:`intra_counts` (the 5+1 method of
  thesis ch. 7 and E+SOCP of ch. 9 both work camera by camera);
* the direction of travel reported when ``|t|`` is not observable:
  :func:`travel_direction` (any rig) and :func:`central_travel` (rays from one
  centre).

:mod:`mcgeom.robust` imports :func:`travel_direction` from here: it finishes
the hypotheses of any estimator and must report the same direction an
estimator does when the verdict says the scale is not observable. No
estimator imports :mod:`mcgeom.robust` (it drives them through the registry),
so the import stays one-way. The row-wise geometry that the scale verdict
needs too (cheirality counts, rotation fit, centred refinement) is in
:mod:`mcgeom.geometry`, below both.

Frames and units (docs/architecture.md §3): rays in the rig frame (origins in
metres), ``X2 = R X1 + t`` with ``t`` in metres.
"""

from __future__ import annotations

import math

import numpy as np

from ..geometry import counts_in_front, rcross, unit_rows, unit_vector
from ..types import RayPairs

__all__ = ["camera_ids", "intra_counts", "travel_direction", "in_mirrored_minimum",
           "central_travel"]


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


def intra_counts(rays: RayPairs
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`camera_ids` plus the intra-camera mask (same camera at both times)
    and the number of intra-camera correspondences of every camera:
    ``(cam1, cam2, centres, intra, counts)``."""
    cam1, cam2, centres = camera_ids(rays)
    intra = cam1 == cam2
    return cam1, cam2, centres, intra, np.bincount(cam1[intra], minlength=len(centres))


# ------------------------------------------- direction when |t| is not observable

def travel_direction(rays: RayPairs, mask: np.ndarray, R: np.ndarray,
                     t: np.ndarray) -> np.ndarray:
    """Unit direction of travel when ``|t|`` is not observable.

    Near the critical motion the data fix R and the direction in which the
    cameras translate, ``tau = t + R c - c`` (the same for all cameras when the
    motion is critical), but not its length; a refinement may then slide |t|
    to a few mm, where ``t`` itself is dominated by the rotation-induced part
    ``R c - c`` and points anywhere (seen on KITTI: 130 deg off). The
    translation of the centroid ``c`` of the cameras with inliers is the
    meaningful direction; it differs from the direction of ``t`` by at most
    the rotation times the centroid's distance from the rig origin over |t|.
    It is used when |t| is under 20x that part; otherwise t's own direction.
    The sign is chosen by cheirality at a length where the rotation-induced
    part is negligible.
    """
    sel = np.flatnonzero(np.asarray(mask, bool))
    # the selected rays are gathered once (centroid, spread and cheirality use them)
    o1, d1, o2, d2 = (rays.origins1[sel], rays.dirs1[sel], rays.origins2[sel],
                      rays.dirs2[sel])
    any_sel = len(o1) > 0
    c = 0.5 * (o1.mean(axis=0) + o2.mean(axis=0)) if any_sel else np.zeros(3)
    shift = R @ c - c
    # where |t| dwarfs the rotation-induced shift, t's own direction is the
    # better estimate (the centroid's motion differs from it by that shift)
    tau = t if np.linalg.norm(t) >= 20.0 * np.linalg.norm(shift) else t + shift
    u = unit_vector(tau)
    if u is None:
        ut = unit_vector(t)
        return np.zeros(3) if ut is None else ut
    spread = np.sqrt(np.mean(np.sum((o1 - c) ** 2, axis=1))) if any_sel else 1.0
    L = max(1.0, 100.0 * spread, 100.0 * np.linalg.norm(shift))
    plus, minus = counts_in_front(o1, d1, o2, d2, R, -shift, (L * u, -L * u))
    return u if plus >= minus else -u


def in_mirrored_minimum(direction: np.ndarray, t: np.ndarray) -> bool:
    """Does ``t`` (metres) lie within ~25 deg of the opposite of ``direction``,
    the unit travel direction that cheirality picks (:func:`travel_direction`)?
    Near the critical motion a refinement can cross |t| = 0 into the mirrored
    minimum, where the epipolar constraint fits as well (with no rotation and
    intra-camera rays it cannot tell t from -t): such a t is no metric
    estimate (car rig driving forward, 20 % outliers: t = +0.06 m for a true
    -0.54 m; a 5+1 t_metric 1.7 cm backwards on tests/test_refine.py's
    critical motion)."""
    # (on Python floats: numpy's calls on 3-vectors cost more, on every estimate)
    d0, d1, d2 = np.asarray(direction, float).reshape(3).tolist()
    t0, t1, t2 = np.asarray(t, float).reshape(3).tolist()
    return d0 * t0 + d1 * t1 + d2 * t2 < -0.9 * math.hypot(t0, t1, t2)


def central_travel(rays: RayPairs, R: np.ndarray) -> np.ndarray | None:
    """Travel direction of the common centre of central rays, or None if not central.

    When every ray starts at one centre ``c`` (one camera, or a rig whose
    cameras share their centre) the data fix R and the direction ``u`` in
    which ``c`` moves, ``t = lam u + c - R c``, and nothing else: each
    correspondence then reads ``lam u . (R d1 x d2) = 0`` (the essential
    matrix of thesis ch. 2.3 about ``c``), so ``u`` is the least-squares null
    vector of the rows ``R d1 x d2``; its sign is chosen by cheirality (as in
    :func:`travel_direction`). Returns the unit ``u``.
    """
    o = np.concatenate([rays.origins1, rays.origins2])
    if len(o) == 0:
        return None
    c = o.mean(axis=0)
    if np.abs(o - c).max() > 1e-9 * (1.0 + np.abs(c).max()):
        return None
    a = rcross(unit_rows(rays.dirs1) @ R.T, unit_rows(rays.dirs2))
    u = np.linalg.eigh(a.T @ a)[1][:, 0]
    shift = R @ c - c
    L = max(1.0, 100.0 * np.linalg.norm(shift))
    plus, minus = counts_in_front(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, R,
                                  -shift, (L * u, -L * u))
    return u if plus >= minus else -u
