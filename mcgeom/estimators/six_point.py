"""``six_point``: the generic minimal generalized relative pose from 6 correspondences.

Six correspondences of any cameras -- intra- or cross-camera, any mix --
determine the motion of a generalized camera up to a finite set of
solutions, 64 complex ones for generic data (Stewenius, Nister, Oskarsson,
Astrom, OMNIVIS 2005). No camera needs the 5 correspondences that 5+1 asks
for, so it suits rigs with many cameras and few matches each, and matches
that are mostly cross-camera.

* :func:`minimal_solutions` -- the minimal solver (``csrc/sixpt.c``: a
  parameter homotopy from a tabulated generic complex problem, every real
  solution checked against the six constraints; see its header for the
  method and its miss rate), the hook :mod:`mcgeom.robust` drives
  (``robust.ransac(rays, "six_point")``);
* :func:`six_point` -- the estimator on all correspondences: the real
  solutions of a 6-sample spread over the correspondences, ranked by a
  robust (Cauchy) cost on all of them, then the joint refinement of the two
  best and the scale verdict (:func:`._finish.refine_and_report`), and the
  shared static-rig test.

Frames and units (docs/architecture.md §3): rays in the rig frame (metres),
``X2 = R X1 + t`` with ``t`` in metres; residuals in radians.
"""

from __future__ import annotations

import numpy as np

from .. import _core
from ..errors import DegenerateError
from ..geometry import count_in_front
from ..registry import register
from ..types import RayPairs, RigMotion
from ._finish import refine_and_report
from ._static import check_static
from .five_plus_one import five_plus_one
from .linear17 import linear17_start

__all__ = ["six_point", "minimal_solutions"]

#: scale (radians) of the Cauchy cost that ranks the candidates: a few pixels
#: at typical focal lengths, so that outliers do not decide the ranking
_RANK_SCALE = 2e-3
#: 6-samples tried, in turn, until a candidate explains _ENOUGH of the
#: correspondences within _RANK_SCALE
_SAMPLES = 4
#: fraction of the correspondences a candidate must explain to end the sampling
#: (a spurious solution can explain half: e.g. one turned by ~180 degrees fits
#: the rays of some cameras of a stereo head, seen in the property suite)
_ENOUGH = 0.8


def minimal_solutions(sample: RayPairs) -> list[tuple[np.ndarray, np.ndarray]]:
    """Every motion ``(R, t)`` (rig2_from_rig1, metres) of 6 correspondences (up to 64).

    ``sample``: exactly 6 correspondences of any cameras (rig frames,
    metres). Each returned motion satisfies the six generalized epipolar
    constraints (to 1e-10 on the normalised rays) and is isolated, so its
    metric scale is fixed by the sample. Degenerate samples (e.g. all rays
    from one centre: a central camera has no metric scale; no rotation with
    intra-camera rays only, thesis ch. 7.3.2) give ``[]``.
    """
    if len(sample) != 6:
        raise ValueError(f"six_point: a minimal sample has 6 correspondences, got {len(sample)}")
    Rs, ts = _core.sixpt(sample.origins1, sample.dirs1, sample.origins2, sample.dirs2)
    return [(Rs[k], ts[k]) for k in range(len(Rs))]


def _samples(rays: RayPairs):
    """6-samples spread over the correspondences, in a canonical order so that
    the result depends neither on the order the caller gave them in nor on the
    rig frame: sorted by the cosine between the unit directions d1 and d2 (a
    change of rig frame turns both alike), ties by the distance between the
    origins; sample j takes the rows j + k n / 6 (k = 0..5) of that order."""
    n = len(rays)
    d1 = rays.dirs1 / np.linalg.norm(rays.dirs1, axis=1, keepdims=True)
    d2 = rays.dirs2 / np.linalg.norm(rays.dirs2, axis=1, keepdims=True)
    cos = np.einsum("ij,ij->i", d1, d2)
    base = np.linalg.norm(rays.origins2 - rays.origins1, axis=1)
    order = np.lexsort((base, cos))
    for j in range(min(_SAMPLES, max(n // 6, 1))):
        idx = order[(j + (n * np.arange(6)) // 6) % n]
        if len(set(idx.tolist())) == 6:
            yield idx


def _explained(rays: RayPairs, R: np.ndarray, t: np.ndarray) -> float:
    """Fraction of the correspondences within _RANK_SCALE of (R, t) whose rays
    meet in front of both cameras: cheirality rejects the spurious solutions
    that fit the constraints, e.g. the twisted pair (R turned by 180 degrees
    about t) with a huge t, which fits every camera's rays like a central
    camera's essential matrix."""
    r = _core.gec_residuals(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, R, t)
    return count_in_front(rays, R, t, np.abs(r) <= _RANK_SCALE) / len(rays)


def _cauchy_cost(rays: RayPairs, R: np.ndarray, t: np.ndarray) -> float:
    r = _core.gec_residuals(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, R, t)
    return float(np.sum(np.log1p((r / _RANK_SCALE) ** 2)))


def _other_estimate(rays: RayPairs):
    """``(name, (R, t))`` of linear17 (>= 17 correspondences), else of
    five_plus_one (a camera with 5), unrefined; None when neither applies."""
    for name, fn, need in (("linear17", lambda: linear17_start(rays), 17),
                           ("five_plus_one", lambda: five_plus_one(rays), 6)):
        if len(rays) < need:
            continue
        try:
            m = fn()
        except (DegenerateError, ValueError):
            continue
        return name, (m.R, m.t)
    return None


def _six_point(rays: RayPairs, max_scale_rel_std: float) -> RigMotion:
    cands: list = []
    used = 0
    found = False
    for idx in _samples(rays):
        used += 1
        cands += minimal_solutions(rays.take(idx))
        # a sample can miss the motion (a degenerate or ill-conditioned sample,
        # or a homotopy path lost: csrc/sixpt.c): the next one is tried unless
        # some candidate already explains most of the correspondences
        found = any(_explained(rays, R, t) >= _ENOUGH for R, t in cands)
        if found:
            break
    source = "six_point"
    other = _other_estimate(rays)
    if not found and other is not None:
        # No sample's solution explains the data: they are degenerate for the
        # minimal problem, whose true solution is then not isolated (critical
        # motion, ch. 7.3.2: no rotation with intra-camera rays leaves |t|
        # free; one centre, a central camera) and only spurious ones remain;
        # or ill-conditioned (a stereo head's intra-camera rays: 3e-4 rad of
        # noise moves the minimal solutions by 0.1 rad). The estimate of
        # linear17 or 5+1, which handle those kinds, joins the candidates;
        # the verdict then says whether the scale is observable.
        cands.append(other[1])
        source = f"six_point + {other[0]} (no sample explains 80 %)"
    if not cands:
        raise DegenerateError(f"six_point: the motion is not determined by the data: no "
                              f"6-sample ({used} tried) has an isolated real solution "
                              "(degenerate data, e.g. every ray from one centre, or no "
                              "rotation with intra-camera rays only)")
    # most correspondences explained in front first, then the Cauchy cost
    key = [(-_explained(rays, R, t), _cauchy_cost(rays, R, t)) for R, t in cands]
    starts = [cands[k] for k in sorted(range(len(cands)), key=lambda k: key[k])[:2]]
    if found and other is not None:
        # A spurious solution with a tiny t can explain 80 % too where the
        # parallax is small (seen: the critical motion of ch. 7.3.2 on a
        # 2-camera head, noise-free: R 7.6e-4 rad off, |t| 1.5e-4 of 0.5 m,
        # every ray within 2e-3 rad), and the refinement stalls there (at a
        # near-zero t the Sampson cost hardly depends on R). The other
        # estimator's start is refined as well; the least final cost wins.
        starts.append(other[1])
    info: dict = {"candidates": len(cands), "samples_tried": used, "start": source}
    return refine_and_report(rays, starts, "six_point", max_scale_rel_std, info)


@register(
    "six_point",
    min_sample=6,
    camera_kinds=("most-general", "locally-central", "axial", "locally-central-and-axial"),
    family="minimal",
    needs_rotation=False,
    recovers_scale=True,
    description="generic minimal generalized relative pose from 6 correspondences of any "
                "cameras (Stewenius et al. 2005; parameter homotopy over its 64 solutions), "
                "ranked by a robust cost on all, joint refinement",
    options={"max_scale_rel_std": "relative std of |t| above which the scale is reported "
                                  "unobservable (0.1)"},
    minimal_solver=minimal_solutions,
)
def six_point(rays: RayPairs, *, max_scale_rel_std: float = 0.1) -> RigMotion:
    """Rig motion rig2_from_rig1 (R, t in metres) from >= 6 correspondences of any cameras.

    ``rays`` in the rig frame (origins at the camera centres, metres), any mix
    of intra- and cross-camera correspondences. The real solutions of the
    minimal 6-point problem on 6-samples spread over the correspondences (the
    next of up to four samples until a solution explains 80 % of them within
    2e-3 rad and in front of both
    cameras) are ranked by that fraction, then by a Cauchy cost (scale
    2e-3 rad) of the Sampson angular residuals on all of them;
    the two best are refined jointly on all (Sampson angular error) and the
    lower final cost wins. The scale verdict rests on the covariance and
    profile of that cost; a static rig gets ``t = 0`` and "no translation
    detected". Where no sample's solution explains 80 % of the
    correspondences (degenerate or ill-conditioned data, e.g. the critical
    motion of ch. 7.3.2),
    linear17's estimate (>= 17 correspondences), else five_plus_one's, joins
    the candidates (``info["start"]`` says so). ``info``: ``candidates``,
    ``samples_tried``, ``start``, ``t_metric``. Raises ValueError for bad
    input, DegenerateError when no motion is found.
    """
    if not isinstance(rays, RayPairs):
        raise TypeError(f"rays must be a RayPairs, got {type(rays).__name__}")
    if len(rays) < 6:
        raise ValueError(f"too few correspondences: six_point needs at least 6, got {len(rays)}")
    if not (np.isfinite(max_scale_rel_std) and max_scale_rel_std > 0):
        raise ValueError(f"max_scale_rel_std must be a positive number, got {max_scale_rel_std}")
    rays.check_finite()
    try:
        # refine_and_report runs the shared static-rig test on the motion found
        return _six_point(rays, max_scale_rel_std)
    except DegenerateError:
        # no motion with a translation: the static answer when a pure
        # rotation explains the data (the shared test), else the error
        still = check_static(rays, "six_point")
        if still is None:
            raise
        return still
