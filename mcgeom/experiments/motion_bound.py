"""The Cramer-Rao bound of a synthetic two-frame problem: how well ANY
unbiased estimator can know the rig motion from its noisy correspondences.

Used by ``mcgeom experiment linear17_accuracy`` to put each case's errors
next to what the data allow (issue 22 asks for median scale errors at or
below figures measured on another generator; the bound says whether a
figure is reachable on ours at all).

The model is the full two-view bundle adjustment of the problem's own
geometry: the unknowns are the motion rig2_from_rig1 -- a rotation
increment w (radians, rig-2 axes: R = exp([w]x) R_true, so |w| is the
rotation error of :func:`mcgeom.metrics.rotation_error`) and t (metres,
rig-2 frame) -- and every scene point X_k (metres, rig-1 frame); the
measurements are both observations of each point:

- pixel noise (``pixel_noise`` px, i.i.d. Gaussian on each pixel
  coordinate, as :func:`mcgeom.synth.make_problem` adds it): the pixels of
  X_k in camera ``cam1[k]`` and of R X_k + t in camera ``cam2[k]``
  (:meth:`mcgeom.rig.Camera.project`, distortion included);
- angular noise (``angular_noise`` rad, :func:`mcgeom.synth.perturb_directions`:
  a N(0, sigma) turn about a random axis perpendicular to the ray): the two
  tangent coordinates of each ray's direction, of covariance sigma^2 / 2 each.
  That noise is not Gaussian (its turn angle is), so the bound here is the
  one for Gaussian noise of the same covariance: the first-order covariance
  that least squares attains whatever the distribution, and an upper bound on
  the exact Cramer-Rao bound of this noise.

The Fisher information J^T J of the whitened measurements is reduced to the
motion by eliminating each point (its 3 x 3 block: the Schur complement, as in
bundle adjustment, Triggs et al. 2000, sec. 6.1); its inverse bounds the
covariance of (w, t). Derivatives are central differences of the
measurement functions (the projections are smooth at the truth).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Optional

import numpy as np

from mcgeom.synth import SyntheticProblem

from .bench.linear17_numpy import exp_so3

__all__ = ["MotionBound", "motion_bound", "median_abs_error"]

_STEP = 1e-6          # relative central-difference step


@dataclass(frozen=True)
class MotionBound:
    """The Cramer-Rao bound of one problem.

    ``covariance``: 6 x 6 over (w [rad], t [m]) as in the module docstring;
    ``scale_rel_std``: the std of |t| over |t_true| (first order:
    u^T cov_tt u / |t|^2, u = t / |t|)."""

    covariance: np.ndarray
    scale_rel_std: float

    def rotation_errors_deg(self, draws: int, rng: np.random.Generator) -> np.ndarray:
        """``draws`` rotation error angles (degrees) drawn from the bound's
        3 x 3 rotation block: their median over many problems pooled is what
        an efficient estimator's median rotation error would be."""
        w = rng.multivariate_normal(np.zeros(3), self.covariance[:3, :3], size=draws)
        return np.degrees(np.linalg.norm(w, axis=1))


def _tangent_bases(u: np.ndarray) -> np.ndarray:
    """(N, 3, 2): an orthonormal basis of each unit row's normal plane."""
    a = np.where(np.abs(u[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    b1 = np.cross(u, a)
    b1 /= np.linalg.norm(b1, axis=1, keepdims=True)
    b2 = np.cross(u, b1)
    return np.stack([b1, b2], axis=2)


class _Measurements:
    """Whitened measurement functions of a problem: (N, 4) from the points
    (N, 3, rig-1 frame) and the motion (w, t)."""

    def __init__(self, p: SyntheticProblem, pixel_noise: float, angular_noise: float):
        if (pixel_noise > 0) == (angular_noise > 0):
            raise ValueError("give exactly one of pixel_noise (px) and angular_noise (rad), "
                             f"positive; got {pixel_noise!r} and {angular_noise!r}")
        self.p = p
        self.pixel = pixel_noise > 0
        self.sigma = pixel_noise if self.pixel else angular_noise / math.sqrt(2.0)
        if not self.pixel:
            cams = p.rig.cameras
            self.o1 = np.array([cams[i].centre for i in p.cam1])
            self.o2 = np.array([cams[i].centre for i in p.cam2])
            self.B1 = _tangent_bases(self._unit(p.points - self.o1))
            self.B2 = _tangent_bases(self._unit(p.points @ p.R.T + p.t - self.o2))

    @staticmethod
    def _unit(v: np.ndarray) -> np.ndarray:
        return v / np.linalg.norm(v, axis=1, keepdims=True)

    def _pixels(self, ids: np.ndarray, X: np.ndarray) -> np.ndarray:
        out = np.empty((len(X), 2))
        for cam in np.unique(ids):
            sel = ids == cam
            out[sel] = self.p.rig.camera(int(cam)).project(X[sel])[0]
        return out

    def __call__(self, X: np.ndarray, w: np.ndarray, t: np.ndarray) -> np.ndarray:
        X2 = X @ (exp_so3(w) @ self.p.R).T + t
        if self.pixel:
            m = np.hstack([self._pixels(self.p.cam1, X), self._pixels(self.p.cam2, X2)])
        else:
            u1, u2 = self._unit(X - self.o1), self._unit(X2 - self.o2)
            m = np.hstack([np.einsum("ni,nij->nj", u1, self.B1),
                           np.einsum("ni,nij->nj", u2, self.B2)])
        return m / self.sigma


def motion_bound(p: SyntheticProblem, pixel_noise: float = 0.0,
                 angular_noise: float = 0.0, use: Optional[np.ndarray] = None) -> MotionBound:
    """The Cramer-Rao bound of the motion of ``p`` under ``pixel_noise`` (px)
    or ``angular_noise`` (rad, the model of :func:`mcgeom.synth.make_problem`;
    exactly one positive), from the correspondences ``use`` selects (a
    boolean mask; None: all), e.g. ``p.inlier``: the bound of an estimator
    told which pairs are the outliers, which no robust one can beat.

    Raises ValueError when the noise is not given as above, or when the
    points do not fix the motion (a singular reduced information: e.g. a
    single camera, whose |t| no data fix)."""
    if use is not None:
        use = np.asarray(use, bool)
        if use.shape != (len(p),):
            raise ValueError(f"use must be a boolean mask of the {len(p)} correspondences, "
                             f"got shape {use.shape}")
        p = replace(p, points=p.points[use], cam1=p.cam1[use], cam2=p.cam2[use],
                    pixels1=p.pixels1[use], pixels2=p.pixels2[use], rays=p.rays.take(use),
                    inlier=p.inlier[use])
    f = _Measurements(p, float(pixel_noise), float(angular_noise))
    X0, w0, t0 = np.asarray(p.points, float), np.zeros(3), np.asarray(p.t, float)
    n = len(X0)
    hx = _STEP * max(1.0, float(np.abs(X0).max()))
    Jx = np.empty((n, 4, 3))
    for i in range(3):
        d = np.zeros(3)
        d[i] = hx
        Jx[:, :, i] = (f(X0 + d, w0, t0) - f(X0 - d, w0, t0)) / (2 * hx)
    Jm = np.empty((n, 4, 6))
    ht = _STEP * max(1.0, float(np.linalg.norm(t0)))
    for i in range(6):
        d = np.zeros(6)
        h = _STEP if i < 3 else ht
        d[i] = h
        Jm[:, :, i] = (f(X0, w0 + d[:3], t0 + d[3:]) - f(X0, w0 - d[:3], t0 - d[3:])) / (2 * h)
    if not (np.isfinite(Jx).all() and np.isfinite(Jm).all()):
        raise ValueError("a point projects behind its camera at the true motion: "
                         "no bound for such a problem")
    # Schur complement of the point blocks (each point sees only its 4 rows)
    Fxx = np.einsum("nki,nkj->nij", Jx, Jx)
    Fmx = np.einsum("nki,nkj->nij", Jm, Jx)
    S = np.einsum("nki,nkj->ij", Jm, Jm) - np.einsum(
        "nij,njk,nlk->il", Fmx, np.linalg.inv(Fxx), Fmx)
    S = 0.5 * (S + S.T)
    # rank on the unit-diagonal scaling (radians and metres differ by the
    # scene's size): a central camera's |t| gives ~1e-14 (rounding), the
    # near-critical car rig of `mcgeom bench robust` 3e-4 at worst
    d = np.diag(S)
    ev = np.linalg.eigvalsh(S / np.sqrt(np.outer(d, d))) if (d > 0).all() else np.zeros(1)
    if not ev[0] > 1e-10 * ev[-1]:
        raise ValueError("the correspondences do not fix the motion (singular "
                         f"information: scaled eigenvalues {ev[0]:.3g} .. {ev[-1]:.3g})")
    cov = np.linalg.inv(S)
    u = t0 / np.linalg.norm(t0)
    return MotionBound(cov, float(math.sqrt(u @ cov[3:, 3:] @ u) / np.linalg.norm(t0)))


def median_abs_error(stds: np.ndarray) -> float:
    """The median of |e| over problems whose errors e are N(0, std_k^2), one
    problem each drawn alike: m with mean_k P(|e_k| < m) = 1/2 (bisection).
    What an efficient estimator's median |scale error| would be over them.
    An infinite std (a problem that does not fix the quantity) counts as an
    error above any m; inf when half of them are."""
    s = np.asarray(stds, float)
    if s.size == 0 or not (s > 0).all():       # (NaN fails the test too)
        raise ValueError("stds must be a non-empty array of positive numbers (inf allowed)")
    if np.count_nonzero(np.isfinite(s)) * 2 <= s.size:
        return float("inf")

    def below(m: float) -> float:
        return float(np.mean([math.erf(m / (sk * math.sqrt(2.0))) for sk in s]))

    lo, hi = 0.0, float(s[np.isfinite(s)].max()) * 5.0
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if below(mid) < 0.5 else (lo, mid)
    return 0.5 * (lo + hi)
