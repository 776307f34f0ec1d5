"""The minimal 5+1 solver of thesis ch. 7: 5 points in one camera, 1 point for the scale.

A 5+1 sample is five intra-camera correspondences of one camera ``a`` and one
correspondence of another camera (or a cross-camera one). The five give the
rotation and the line of translations ``t(lam) = t0 + lam w`` through the
5-point solver (:func:`mcgeom.estimators.essential.essential_motions`); the
sixth fixes ``lam`` by eq. 7.4. In our convention (docs/architecture.md §3,
``X2 = R X1 + t``), substituting ``t(lam)`` into the generalized epipolar
constraint of a correspondence ``(d1, m1) <-> (d2, m2)`` gives ``e(lam) = a +
lam b`` with

    a = d2^T [t0]x R d1 + d2^T R m1 + m2^T R d1,    b = d2^T [w]x R d1,

so ``lam = -a / b`` from one correspondence (the thesis's ``x'^T A x + lam x'^T
B x = 0``). :func:`minimal_solutions` is the minimal solver and
:func:`sample_five_plus_one` the sampler that :mod:`mcgeom.robust` drives
(see the contract in :mod:`mcgeom.registry`); :func:`critical_angles` reports
the critical angle of ch. 7.5.2 per camera.
"""

from __future__ import annotations

import numpy as np

from .. import _core
from ..errors import DegenerateError
from ..geometry import count_in_front, displacements, rcross
from ..types import RayPairs
from ._common import intra_counts
from .essential import bearings_planar, essential_motions

__all__ = ["scale_terms", "critical_angles", "minimal_solutions", "sample_five_plus_one"]


# ------------------------------------------------------------- 1 point: scale

def scale_terms(rays: RayPairs, R: np.ndarray, t0: np.ndarray,
                w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Coefficients of eq. 7.4: the epipolar residual of each correspondence is
    ``a + lam b`` for the translation ``t0 + lam w`` (unit directions, so ``a``
    and ``b`` are in metres)."""
    d1 = rays.dirs1 / np.linalg.norm(rays.dirs1, axis=1, keepdims=True)
    d2 = rays.dirs2 / np.linalg.norm(rays.dirs2, axis=1, keepdims=True)
    rd1 = d1 @ R.T
    m1 = rcross(rays.origins1, d1)
    m2 = rcross(rays.origins2, d2)
    a = (np.einsum("ij,ij->i", d2, rcross(t0, rd1)) + np.einsum("ij,ij->i", d2, m1 @ R.T)
         + np.einsum("ij,ij->i", m2, rd1))
    b = np.einsum("ij,ij->i", d2, rcross(w, rd1))
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
    out = np.arctan2(np.linalg.norm(rcross(da, disp), axis=1), disp @ da)
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
    the critical configuration for this sample) are dropped. Of the rest only
    those that put the most of the six correspondences in front of the cameras
    (:func:`_most_in_front`) are returned: every candidate satisfies the six
    epipolar constraints exactly, so a scorer cannot tell them apart on the
    sample, and the 5-point decomposition checked cheirality only for the
    unscaled translation of its own camera.
    """
    five, a, rest, centres = _split_sample(sample)
    five = five[:5]
    out = []
    if rest.size == 0:
        return out
    six = sample.take(np.concatenate([five, rest[:1]]))
    # five bearings in one plane through the centre (to rounding: points on a
    # line) admit a one-parameter family of essential matrices: no solution
    if bearings_planar(sample.dirs1[five], sample.dirs2[five], 1e-9):
        return out
    for R, t0, w in essential_motions(sample, five, centres[a]):
        ra, rb = scale_terms(sample.take(rest[:1]), R, t0, w)
        if not abs(rb[0]) > 1e-12 * (1.0 + abs(ra[0])):
            continue
        out.append(_polish(six, R, t0 - (ra[0] / rb[0]) * w))
    return _most_in_front(six, out)


def _most_in_front(six: RayPairs, sols: list) -> list:
    """The solutions ``(R, t)`` under which the most correspondences of ``six``
    triangulate in front of both cameras (mid-point of the two rays).

    The scale of eq. 7.4 can turn a translation that satisfies cheirality for
    the 5-point camera's unit direction into one whose sixth ray, or even the
    five, meet behind the cameras (a negative ``lam`` reverses the travel);
    several 5-point solutions then fit the sample exactly and only cheirality
    tells the physical one (measured: the façades kept a wrong one on 54-65 %
    of noise-free minimal problems; ``mcgeom experiment minimal_5p1``).
    """
    if len(sols) < 2:
        return sols
    counts = [count_in_front(six, R, t) for R, t in sols]
    best = max(counts)
    return [s for s, c in zip(sols, counts) if c == best]


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


# ------------------------------------------- exactly minimal input: all of them

#: two exact solutions are the same motion when they agree to this (rotation in
#: radians, translation relative): the 6 x 6 polish converges to rounding
_SAME = 1e-9
#: an exact solution's largest Sampson angular residual (radians) on the six
_EXACT = 1e-9

#: the rule that picks the primary among the exact candidates (documented in
#: the verdict and ``info["primary_rule"]``)
PRIMARY_RULE = ("largest cheirality margin: the largest smallest depth (metres) of the six "
                "points along their twelve rays")


#: fixed rotations (about the axes (1, 2, 3) and (-3, 1, 2), by 1 and 2 rad) of
#: the extra frames in which :func:`_essentials` runs the 5-point solver
_FRAMES = tuple(
    np.cos(th) * np.eye(3) + np.sin(th) * np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]],
                                                    [-k[1], k[0], 0.0]])
    + (1.0 - np.cos(th)) * np.outer(k, k)
    for k, th in ((np.array([1.0, 2.0, 3.0]) / np.sqrt(14.0), 1.0),
                  (np.array([-3.0, 1.0, 2.0]) / np.sqrt(14.0), 2.0)))


def _essentials(d1: np.ndarray, d2: np.ndarray) -> list[np.ndarray]:
    """The real essential matrices of five bearing pairs (rig axes), from
    Nistér's solver (``_core.essential5``) run in the rig axes and in the
    :data:`_FRAMES` (each result rotated back; duplicates are merged later).

    Why several frames: the solver's elimination loses real roots on some
    configurations depending on the coordinate frame (measured: configuration
    209 of ``mcgeom experiment minimal_5p1`` seed 0 gives 4 solutions without
    the true one in the rig axes, 6 with it, to 5e-11, in each of five
    rotated frames); a root lost in one frame is found in another.
    """
    out = list(_core.essential5(d1, d2))
    for Q in _FRAMES:
        out += [Q.T @ E @ Q for E in _core.essential5(d1 @ Q.T, d2 @ Q.T)]
    return out


def _depths(six: RayPairs, R: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(2N,) depths (metres, along the unit bearings) of the mid-point
    triangulation of every correspondence of ``six`` under ``(R, t)``: ``s1``
    on the time-1 ray moved into the time-2 rig frame, ``s2`` on the time-2
    ray; negative = behind; -inf for parallel rays (no point)."""
    a = six.dirs1 @ R.T
    a = a / np.linalg.norm(a, axis=1, keepdims=True)
    b = six.dirs2 / np.linalg.norm(six.dirs2, axis=1, keepdims=True)
    w = six.origins2 - (six.origins1 @ R.T + t)
    ab = np.einsum("ij,ij->i", a, b)
    aw, bw = np.einsum("ij,ij->i", a, w), np.einsum("ij,ij->i", b, w)
    den = 1.0 - ab * ab
    ok = den > 1e-14
    den = np.where(ok, den, 1.0)
    # closest points of p + s1 a and o2 + s2 b (w = o2 - p)
    s1 = np.where(ok, (aw - ab * bw) / den, -np.inf)
    s2 = np.where(ok, (ab * aw - bw) / den, -np.inf)
    return np.concatenate([s1, s2])


def _rotations(E: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
    """The two rotations of an essential matrix ``E = [u]x R`` and its unit
    ``u`` (sign arbitrary), by the SVD (Hartley and Zisserman, Result 9.19)."""
    U, _, Vt = np.linalg.svd(E)
    U = U if np.linalg.det(U) > 0 else -U
    Vt = Vt if np.linalg.det(Vt) > 0 else -Vt
    W = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    return [U @ W @ Vt, U @ W.T @ Vt], U[:, 2]


def exact_candidates(rays: RayPairs) -> list[dict]:
    """Every rig motion that fits an exactly minimal 5+1 set exactly and puts
    all its points in front of the cameras, primary first.

    ``rays``: 6 correspondences (rig frame, metres), 5 intra-camera ones of
    one camera ``a`` and one other. Each real essential matrix of the five
    (``_core.essential5``, Nistér's solver on the bearings in rig axes: for
    camera ``a``, ``d2^T [u]x R d1 = 0`` with ``u = t + R c_a - c_a``) gives
    two rotations (the solver runs in three frames: :func:`_essentials`);
    for each, eq. 7.4 on the sixth correspondence fixes ``t =
    t0 + lam u`` (whatever the sign of ``lam``: both travel senses are
    tried), the 6 x 6 Gauss-Newton polish removes the solver's rounding, and
    the motion is kept when its largest Sampson residual is below 1e-9 rad
    and all twelve mid-point depths are positive (cheirality of ch. 7 for
    the metric ``t``, not only for camera ``a``'s unit direction).
    Duplicates (1e-9) are merged.

    Each candidate is a dict: ``R``, ``t`` (metres, rig2_from_rig1),
    ``min_depth`` (metres: the cheirality margin), ``max_residual``
    (radians) and ``why`` (a sentence). Sorted by :data:`PRIMARY_RULE`
    (measured on noise-free configurations of ``mcgeom experiment
    minimal_5p1``: it picks the truth in ~82 % of the ambiguous ones; the
    smallest rotation 73 %, the smallest |t| 19 %). Empty when the set is not
    a 5+1 set (e.g. all six in one camera) or no solution passes.
    """
    if len(rays) != 6:
        raise ValueError(f"exact_candidates needs exactly 6 correspondences, got {len(rays)}")
    try:
        five, a, rest, centres = _split_sample(rays)
    except ValueError:
        return []
    if five.size != 5 or rest.size != 1:
        return []
    six = rays.take(np.concatenate([five, rest]))
    sixth = rays.take(rest)
    found: list = []
    for E in _essentials(rays.dirs1[five], rays.dirs2[five]):
        Rs, u = _rotations(E)
        for R in Rs:
            t0 = centres[a] - R @ centres[a]
            sa, sb = scale_terms(sixth, R, t0, u)
            if not abs(sb[0]) > 1e-12 * (1.0 + abs(sa[0])):
                continue   # the sixth ray cannot fix the scale of this rotation
            R2, t2 = _polish(six, R, t0 - (sa[0] / sb[0]) * u)
            res = float(np.max(np.abs(_core.gec_residuals(
                six.origins1, six.dirs1, six.origins2, six.dirs2, R2, t2))))
            depth = _depths(six, R2, t2)
            if not (res <= _EXACT and np.all(depth > 0.0)):
                continue
            if any(np.linalg.norm(R2 - c["R"]) < _SAME and
                   np.linalg.norm(t2 - c["t"]) < _SAME * (1.0 + np.linalg.norm(c["t"]))
                   for c in found):
                continue
            found.append({"R": R2, "t": t2, "min_depth": float(depth.min()),
                          "max_residual": res})
    found.sort(key=lambda c: -c["min_depth"])
    for k, c in enumerate(found):
        c["why"] = (f"fits the 6 correspondences exactly (largest residual "
                    f"{c['max_residual']:.1e} rad) and puts all 6 points in front of both "
                    f"cameras (smallest depth {c['min_depth']:.3g} m)"
                    + ("; primary: largest cheirality margin" if k == 0 else ""))
    return found
