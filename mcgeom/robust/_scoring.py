"""Scoring of motions on all correspondences (MSAC of the Sampson angular
residual), the samples across cameras, the adaptive stop and the local
optimisation of the Python search (:class:`Scorer`)."""

from __future__ import annotations

from typing import Optional, Union

import numpy as np

from .. import _core
from ..geometry import refine_centred
from ..types import MotionFocal, RayPairs
from ._options import RansacOptions, focal_array


def residuals(rays: RayPairs, R: np.ndarray, t: np.ndarray,
              focal: Union[None, float, np.ndarray] = None) -> np.ndarray:
    """Absolute Sampson angular residual of every correspondence for motion (R, t).

    Radians on the unit sphere, or pixels (radians x ``focal``) when ``focal``
    is given.
    """
    return _residuals(rays, R, t, focal_array(focal, len(rays)))


def _residuals(rays: RayPairs, R: np.ndarray, t: np.ndarray,
               focal: Optional[np.ndarray]) -> np.ndarray:
    """:func:`residuals` with ``focal`` already validated (the scoring hot path)."""
    r = np.abs(_core.gec_residuals(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2,
                                   np.asarray(R, dtype=np.float64),
                                   np.asarray(t, dtype=np.float64)))
    return r if focal is None else r * focal


def adaptive_iterations(inlier_ratio: float, sample_size: int, prob: float,
                        max_iters: int) -> int:
    """Iterations after which an all-inlier sample was drawn with probability ``prob``."""
    w = float(np.clip(inlier_ratio, 0.0, 1.0)) ** sample_size
    if w <= 0.0:
        return int(max_iters)
    if w >= 1.0:
        return 1
    k = np.log1p(-prob) / np.log1p(-w)
    return int(min(max_iters, np.ceil(k)))


def sample_across_cameras(rays: RayPairs, size: int, rng: np.random.Generator) -> np.ndarray:
    """``size`` distinct correspondences spread over the camera pairs.

    A uniform draw with at most ``ceil(size / G)`` correspondences of each of
    the G camera pairs (cam1, cam2) (raised round by round only when the
    others cannot fill the sample): no camera dominates the sample (drawing
    uniformly from all correspondences would give samples from the one
    camera that has most of them), and no camera pair is forced into it.
    Visiting every pair once per round did force them: with a sample as
    large as the pairs (17 correspondences over 16 camera pairs), every
    sample held each one-correspondence pair, and where that one was an
    outlier no sample was clean (a generic 4-camera rig, 150 pairs, 20 %
    outliers: the eigensolver's RANSAC found no consensus in 1000 samples).
    Indices into ``rays``, in the order drawn.
    """
    n = len(rays)
    if size > n:
        raise ValueError(f"too few correspondences: a sample needs {size}, got {n}")
    if rays.cam1 is None or rays.cam2 is None:
        return rng.choice(n, size, replace=False)
    key = rays.cam1 * (int(rays.cam2.max(initial=0)) + 1) + rays.cam2
    _, group = np.unique(key, return_inverse=True)
    group = group.ravel()
    perm = rng.permutation(n)
    g = group[perm]
    # rank of each drawn correspondence among those of its camera pair drawn
    # before it: round r of the draw holds ranks [r cap, (r + 1) cap)
    counts = np.bincount(g)
    by_group = np.argsort(g, kind="stable")
    rank = np.empty(n, dtype=np.int64)
    rank[by_group] = np.arange(n) - np.repeat(np.cumsum(counts) - counts, counts)
    cap = -(-size // len(counts))
    take = np.argsort((rank // cap) * n + np.arange(n), kind="stable")[:size]
    return perm[take].astype(np.int64)


def _msac(r: np.ndarray, thr: float) -> float:
    return float(np.minimum(r * r, thr * thr).sum())


def true_fraction(mask: np.ndarray) -> float:
    """Fraction of True in a boolean mask (``mask.mean()`` without its overhead)."""
    return np.count_nonzero(mask) / mask.size


class Scorer:
    """Scores motions on all correspondences and runs the local optimisation."""

    def __init__(self, rays: RayPairs, thr: float, focal: Optional[np.ndarray],
                 opts: RansacOptions, motion_focal: Optional[MotionFocal] = None):
        self.rays, self.thr, self.focal, self.opts = rays, thr, focal, opts
        self.motion_focal = motion_focal
        # Per-correspondence focal lengths (pixels per radian of residual)
        # also weight the least squares: a residual of r radians is r * f_i
        # pixels, so its variance under pixel noise is ~ 1 / f_i^2.
        med = None if focal is None else np.median(focal)   # one median serves both
        self.weights = None if focal is None or np.ptp(focal) == 0 else (focal / med) ** 2
        # loss scale in radians (the threshold, converted from pixels if needed)
        self.loss_scale = thr if focal is None else thr / float(med)
        self.best: Optional[tuple[np.ndarray, np.ndarray]] = None
        self.best_score = np.inf
        self.best_inliers = np.zeros(len(rays), bool)
        # residuals of ``best`` on all correspondences (the final stage starts from them)
        self.best_residuals: Optional[np.ndarray] = None
        self.n_hyp = 0
        self.n_lo = 0
        self.lo_rounds = opts.lo_max_rounds

    def residuals(self, R: np.ndarray, t: np.ndarray) -> np.ndarray:
        return _residuals(self.rays, R, t, self.focal)

    def offer(self, R: np.ndarray, t: np.ndarray) -> bool:
        """Score a hypothesis; keep (and locally optimise) it if it is the best so far."""
        self.n_hyp += 1
        if not (np.all(np.isfinite(R)) and np.all(np.isfinite(t))):
            return False
        r = self.residuals(R, t)
        score = _msac(r, self.thr)
        if score >= self.best_score:
            return False
        self.best, self.best_score, self.best_inliers = (R, t), score, r < self.thr
        self.best_residuals = r
        if self.opts.local_optimization:
            self._local_optimise()
        return True

    def _local_optimise(self) -> None:
        """Re-estimate from the inliers by robust least squares while the score improves."""
        for _ in range(self.lo_rounds):
            inl = self.best_inliers
            if inl.sum() < 6:
                return
            R, t = self.best
            self.n_lo += 1
            try:
                # the length of the centroid's translation is held: LO is
                # about the inlier set, and near the critical motion a free
                # fit slides |t| towards infinity (the final stage frees it)
                out = refine_fit(self.rays.take(inl), R, t, self.loss_scale, "cauchy",
                                 self._w(inl), fix_scale=True)
            except (ValueError, ArithmeticError):
                return
            r = self.residuals(out["R"], out["t"])
            score = _msac(r, self.thr)
            if not score < self.best_score * (1.0 - 1e-9):
                return
            same = np.array_equal(r < self.thr, inl)
            self.best, self.best_score, self.best_inliers = (out["R"], out["t"]), score, r < self.thr
            self.best_residuals = r
            if same:   # the same inliers would give the same fit again
                return

    def _w(self, mask: np.ndarray) -> Optional[np.ndarray]:
        return None if self.weights is None else self.weights[mask]

    def scaling_at(self, R: np.ndarray, t: np.ndarray
                   ) -> tuple[Optional[np.ndarray], Optional[np.ndarray], float]:
        """Pixel scaling of the residuals at motion (R, t): focal, weights, loss scale.

        Without ``motion_focal`` it is the fixed one the scoring uses. With it,
        each residual is scaled by its own pixels per radian at this motion, so
        that the weighted residuals and the loss are those of the image-plane
        Sampson error (thesis eq. 8.15 with the pixel noise propagated to first order):
        the isotropic per-correspondence focal misweighs a correspondence
        whose epipolar gradient points radially (measured on a 4-camera ring at
        0.1 px: rotation median 0.0034 -> 0.0033 deg, the optimum of the
        image-plane Sampson cost).
        """
        if self.motion_focal is None:
            return self.focal, self.weights, self.loss_scale
        f = np.asarray(self.motion_focal(self.rays, R, t), dtype=np.float64)
        med = float(np.median(f))
        return f, (f / med) ** 2, self.thr / med


#: fewest correspondences the final refinement (``refine_centred``) can fit
MIN_REFIT = 6


#: the final refinement fits the correspondences within this many thresholds
#: (csrc/robust_internal.h WIDE; the confidence counts them as the consensus)
WIDE = 2.0


def refine_fit(rays: RayPairs, R: np.ndarray, t: np.ndarray, loss_scale: float, loss: str,
               weights: Optional[np.ndarray] = None, fix_scale: bool = False) -> dict:
    """:func:`mcgeom.geometry.refine_centred` of (R, t) on ``rays`` (rig frame;
    ``loss_scale`` in radians; ``fix_scale`` holds the centroid's |t|)."""
    return refine_centred(rays, R, t, loss=loss, loss_scale=loss_scale, weights=weights,
                          fix_scale=fix_scale)
