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
