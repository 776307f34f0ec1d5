"""Synthetic sequences of views with known rotations and short tracks (thesis
ch. 6.5.1, Fig. 6.2), and the similarity alignment used to score them. Seeded.

Conventions of :mod:`mcgeom.multiview`: ``rotations[i]`` is view_from_world,
bearings are in the view frame, centres in the world frame.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np

from .rig import Rig
from .synth import RngLike, as_rng, perturb_directions, random_rotation, rotation_about

__all__ = ["ViewSequence", "circle_sequence", "rig_drive_sequence", "similarity_align",
           "spiral_measure"]


@dataclass(frozen=True)
class ViewSequence:
    """Observations ``track``, ``view``, ``bearings`` (view frame, unit) of
    ``points`` (world) by views with ``rotations`` (view_from_world) and
    ``centres`` (world); ``origins`` (view frame) when the views are rigs."""

    centres: np.ndarray
    rotations: np.ndarray
    points: np.ndarray
    track: np.ndarray
    view: np.ndarray
    bearings: np.ndarray
    origins: Optional[np.ndarray] = None


def circle_sequence(n_views: int = 101, n_points: int = 1000, radius: float = 100.0,
                    visible_range: float = 50.0, max_track: int = 3, sigma: float = 0.0,
                    rng: RngLike = None, cameras: Optional[np.ndarray] = None,
                    closed_loop: bool = False, track_views: str = "consecutive") -> ViewSequence:
    """Views on a circle of ``radius`` in the plane z = 0 (one turn), random
    known rotations, ``n_points`` uniform in [-radius, radius]^3; a view sees
    the points within ``visible_range``; each point's run of views is cut into
    tracks of at most ``max_track`` consecutive views (thesis ch. 6.5.1);
    bearings get angular noise ``sigma`` (radians). The views are an image
    sequence: a track follows the capture order, so no track links the last
    view to the first although they are neighbours on the circle (the open
    chain of the thesis, whose plain-SVD failures are spirals, Figs. 6.3 and
    6.5); ``closed_loop=True`` lets tracks run on across that closure (a
    ring: far more rigid). ``track_views="any"``: each track's views are
    drawn at random among all views that see the point instead (the point's
    views split into random groups of at most ``max_track``): wide triangles,
    a rigid problem without the spirals. With ``cameras`` (K, 3):
    each view is a rig of K cameras at these rig-frame centres, and a point is
    seen by the camera of the rig nearest to it (origins filled)."""
    gen = as_rng(rng)
    if track_views not in ("consecutive", "any"):
        raise ValueError(f"circle_sequence: track_views must be 'consecutive' or 'any', "
                         f"got {track_views!r}")
    if n_views < 2 or n_points < 1 or max_track < 2 or not visible_range > 0:
        raise ValueError("circle_sequence: need n_views >= 2, n_points >= 1, max_track >= 2, "
                         "visible_range > 0")
    ang = 2.0 * np.pi * np.arange(n_views) / n_views
    centres = radius * np.c_[np.cos(ang), np.sin(ang), np.zeros(n_views)]
    rotations = np.array([random_rotation(gen) for _ in range(n_views)])
    points = gen.uniform(-radius, radius, size=(n_points, 3))
    sees = np.linalg.norm(points[None, :, :] - centres[:, None, :], axis=2) <= visible_range
    track, view, pts = [], [], []
    next_id = 0
    for p in range(n_points):
        vs = np.flatnonzero(sees[:, p])
        if vs.size < 2:
            continue
        # runs of consecutive views; with closed_loop the run through view
        # m - 1 continues at view 0
        runs = np.split(vs, np.flatnonzero(np.diff(vs) > 1) + 1)
        if (closed_loop and len(runs) > 1 and runs[0][0] == 0
                and runs[-1][-1] == n_views - 1):
            runs = [np.r_[runs[-1], runs[0]]] + runs[1:-1]
        if track_views == "any":
            # each track: up to max_track views drawn among all that see the point
            groups = -(-vs.size // max_track)
            runs = [np.sort(g) for g in np.array_split(gen.permutation(vs), groups)]
        for run in runs:
            if track_views == "any":
                if run.size >= 2:
                    track += [next_id] * run.size
                    view += list(run)
                    pts += [p] * run.size
                    next_id += 1
                continue
            start = int(gen.integers(0, max_track)) if run.size > max_track else 0
            pieces = [run[:start]] if start >= 2 else []
            pieces += [run[s:s + max_track] for s in range(start, run.size, max_track)]
            for piece in pieces:
                if piece.size >= 2:
                    track += [next_id] * piece.size
                    view += list(piece)
                    pts += [p] * piece.size
                    next_id += 1
    track, view, pts = np.array(track), np.array(view), np.array(pts)
    origins = None
    offs = np.zeros((len(view), 3))
    if cameras is not None:
        cams = np.asarray(cameras, dtype=np.float64)
        # rig-frame positions of the points, camera nearest to each
        Xv = np.einsum("kij,kj->ki", rotations[view], points[pts] - centres[view])
        k = np.argmin(np.linalg.norm(Xv[:, None, :] - cams[None, :, :], axis=2), axis=1)
        origins = cams[k]
        offs = np.einsum("kji,kj->ki", rotations[view], origins)
    d_world = points[pts] - centres[view] - offs
    bearings = np.einsum("kij,kj->ki", rotations[view], d_world)
    bearings /= np.linalg.norm(bearings, axis=1, keepdims=True)
    if sigma > 0:
        bearings = perturb_directions(bearings, sigma, gen)
    return ViewSequence(centres, rotations, points, track, view, bearings, origins)


def rig_drive_sequence(rig: Rig, yaws_deg, step: float = 1.0, n_points: int = 1500,
                       sigma_px: float = 0.5, rng: RngLike = None) -> ViewSequence:
    """A rig driving forward on the ground plane: ``step`` metres per frame
    along its x axis (z up), turning by ``yaws_deg[k]`` degrees during step k
    (the step is the chord of the turn), through ``n_points`` random points
    25 m around the path, between 4 m below and 6 m above it and at least 3 m
    from it. Each camera of ``rig`` that sees a point makes it a track of its
    own (intra-camera tracks only: without overlap, the critical case of
    thesis ch. 7.3.2 when the rig does not turn), its pixels perturbed by
    ``sigma_px`` (Gaussian per coordinate). Bearings and ``origins`` are in
    the rig frame (view frame), ``rotations`` view_from_world, ``centres``
    world (frame 0 at the origin), metres."""
    gen = as_rng(rng)
    R, c, yaw = [np.eye(3)], [np.zeros(3)], 0.0
    for dy in yaws_deg:
        mid = np.radians(yaw + 0.5 * dy)
        yaw += float(dy)
        c.append(c[-1] + step * np.array([np.cos(mid), np.sin(mid), 0.0]))
        R.append(rotation_about((0.0, 0.0, 1.0), np.radians(yaw)))    # world_from_rig
    R, c = np.array(R), np.array(c)
    lo, hi = c.min(axis=0) - 25.0, c.max(axis=0) + 25.0
    pts = gen.uniform([lo[0], lo[1], -4.0], [hi[0], hi[1], 6.0], size=(4 * n_points, 3))
    near = np.min(np.linalg.norm(pts[:, None, :2] - c[None, :, :2], axis=2), axis=1)
    pts = pts[near > 3.0][:n_points]
    n_cams = len(rig.cameras)
    track, view, bearings, origins = [], [], [], []
    for k in range(len(c)):
        x_rig = (pts - c[k]) @ R[k]                      # R^T (X - c), row-wise
        for i in range(n_cams):
            px, vis = rig.project(i, x_rig)
            idx = np.flatnonzero(vis)
            noisy = px[idx] + sigma_px * gen.standard_normal((len(idx), 2))
            o, d = rig.rays(np.full(len(idx), i), noisy)
            track.append(n_cams * idx + i)
            view.append(np.full(len(idx), k))
            bearings.append(d)
            origins.append(o)
    return ViewSequence(c, np.transpose(R, (0, 2, 1)), pts, np.concatenate(track),
                        np.concatenate(view), np.concatenate(bearings), np.concatenate(origins))


def similarity_align(est: np.ndarray, true: np.ndarray) -> tuple[np.ndarray, float]:
    """``est`` (m, 3) mapped by the similarity (scale, rotation, translation)
    that best fits ``true`` in least squares (Umeyama); returns the aligned
    centres and the RMS distance to ``true`` (units of ``true``)."""
    mu_e, mu_t = est.mean(0), true.mean(0)
    E, T = est - mu_e, true - mu_t
    U, S, Vt = np.linalg.svd(T.T @ E)
    D = np.eye(3)
    D[2, 2] = np.sign(np.linalg.det(U @ Vt)) or 1.0
    Rm = U @ D @ Vt
    var = np.sum(E ** 2)
    s = float(np.trace(np.diag(S) @ D) / var) if var > 0 else 0.0
    aligned = s * E @ Rm.T + mu_t
    return aligned, float(np.sqrt(np.mean(np.sum((aligned - true) ** 2, axis=1))))


def spiral_measure(aligned: np.ndarray, true: np.ndarray) -> float:
    """Largest angle (radians) between an estimated step c_{i+1} - c_i and the
    true one: spirals and jumps (thesis Figs. 6.3, 6.5) make it large."""
    a, t = np.diff(aligned, axis=0), np.diff(true, axis=0)
    cos = np.einsum("ij,ij->i", a, t)
    sin = np.linalg.norm(np.cross(a, t), axis=1)
    return float(np.max(np.arctan2(sin, cos)))
