"""``mcgeom bench known_rotation``: the multi-view translation solver of thesis
ch. 6 (:mod:`mcgeom.multiview`: C rows and Grams, skyline inverse iteration)
against the dense numpy implementation of the same math
(:mod:`mcgeom.experiments.bench.known_rotation_numpy`: E row by row, N = E^T E, dense
eigh), on the circle sequence of ch. 6.5.1 scaled up (same density of views
and points). Times are the best of a few calls, seconds."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np

from mcgeom import multiview
from mcgeom.synth_views import circle_sequence
from ..common import Progress, no_progress
from .known_rotation_numpy import dense_solve
from .timing import best_of

__all__ = ["KnownRotationTiming", "bench_known_rotation"]


@dataclass(frozen=True)
class KnownRotationTiming:
    views: int
    tracks: int
    relations: int
    relation: str
    mcgeom_s: float
    numpy_s: Optional[float]
    max_diff: Optional[float]

    @property
    def ratio(self) -> Optional[float]:
        return None if self.numpy_s is None else self.numpy_s / self.mcgeom_s


def bench_known_rotation(view_counts=(101, 201), dense_up_to: int = 101,
                         repeat: int = 3, progress: Progress = no_progress) -> list:
    """One row per (views, relation), constrained solver, times in seconds; the
    dense reference only up to ``dense_up_to`` views (its memory grows as views^2)."""
    rows = []
    for m in progress(view_counts, total=len(view_counts), desc="known_rotation"):
        f = m / 101.0
        seq = circle_sequence(n_views=m, n_points=int(round(1000 * f ** 3)),
                              radius=100.0 * f, sigma=1e-4, rng=7)
        for rel in multiview.RELATIONS:
            def ours():
                return multiview.translations_from_tracks(seq.track, seq.view, seq.bearings,
                                                          seq.rotations, relation=rel)
            r = ours()
            t_ours = best_of(ours, repeat, 1)
            t_np = diff = None
            if m <= dense_up_to:
                q = 2 if rel == "bilinear" else 3
                x = np.einsum("kji,kj->ki", seq.rotations[seq.view], seq.bearings)
                idx = multiview.relations(seq.track, seq.view, q, "all", 1)

                def dense():
                    return dense_solve(x[idx], seq.view[idx], m, "constrained")
                ref = dense()
                ref *= np.sign(np.sum(ref * r.centres))
                diff = float(np.abs(ref - r.centres).max())
                t_np = best_of(dense, 1, 1)
            rows.append(KnownRotationTiming(m, int(seq.track.max() + 1), r.n_relations, rel,
                                            t_ours, t_np, diff))
    return rows
