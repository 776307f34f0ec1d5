"""Thesis ch. 10.5.1 (Figs. 10.4-10.5): B&B+LP against E+SOCP, and the effect
of the preemptive per-camera test.

Set-up of ch. 10.5.1 (the same as mcgeom.experiments.ch9): four cameras, 50
points each, a random rigid motion, Gaussian pixel noise sigma from 0 to
0.5 px, ``runs`` problems per level (the thesis used 10). Printed per level
and method: mean rotation error (deg), translation-direction error (deg),
scale ratio |t_est| / |t_true| and the distance between the estimated and the
true final centre of the first camera (m): the four panels of Fig. 10.4, and
the comparison of Fig. 10.5.

Preemption (ch. 10.3, "Feasibility test"; the thesis: 90x): on the 0.5 px
problems, the search time with and without the per-camera tests, in one run,
for the thesis's set-up (GLPK, every LP on all its rows) and for ours (native
backend, working sets), with the number of LPs of each kind.
``mcgeom experiment ch10 --runs 10``
"""

from __future__ import annotations

import argparse

import numpy as np

import mcgeom
from mcgeom import registry

from . import ch9
from .common import Progress, add_count_and_seed, no_progress

METHODS = ("bnb_lp", "e_socp")


def preemption(runs: int = 5, sigma: float = 0.5, seed: int = 0, glpk: bool = True,
               progress: Progress = no_progress) -> list[dict]:
    """Search times (s) with and without the preemptive test, same problems,
    same start, per LP backend: one row per problem and backend."""
    configs = [("native", True), ("native", False)]
    if glpk and "glpk" in registry.lp_backends():
        configs += [("glpk", False)]
    rows = []
    for R, t, p in progress(ch9.problems(runs, sigma, seed), total=runs, desc="preemption"):
        start = mcgeom.estimate(p.rays, "refine")
        for backend, ws in configs:
            out = {}
            for pre in (True, False):
                m = mcgeom.estimate(p.rays, "bnb_lp", initial=start, lp_backend=backend,
                                    working_sets=ws, preemptive=pre)
                out[pre] = m.info
            assert abs(out[True]["linf"] - out[False]["linf"]) < 1e-12
            rows.append({"backend": backend, "working_sets": ws,
                         "with": out[True], "without": out[False]})
    return rows


def preemption_table(rows: list[dict]) -> str:
    """Medians of :func:`preemption`'s rows per backend: seconds and LP counts."""
    lines = [f"{'backend':<8} {'LPs':<12} {'with s':>8} {'without s':>9} {'ratio':>6} "
             f"{'2-var/3-var LPs with':>22} {'without':>16}"]
    keys = sorted({(r["backend"], r["working_sets"]) for r in rows})
    for backend, ws in keys:
        sel = [r for r in rows if r["backend"] == backend and r["working_sets"] == ws]
        tw = np.array([r["with"]["seconds"] for r in sel])
        to = np.array([r["without"]["seconds"] for r in sel])
        lw = np.median([[r["with"]["lps_2var"], r["with"]["lps_3var"]] for r in sel], axis=0)
        lo = np.median([[r["without"]["lps_2var"], r["without"]["lps_3var"]] for r in sel], axis=0)
        lines.append(f"{backend:<8} {'working sets' if ws else 'all rows':<12} "
                     f"{np.median(tw):8.3f} {np.median(to):9.3f} {np.median(to / tw):6.2f} "
                     f"{lw[0]:>11.0f}/{lw[1]:<10.0f} {lo[0]:>7.0f}/{lo[1]:<8.0f}")
    return "\n".join(lines)


def add_arguments(ap: argparse.ArgumentParser) -> None:
    """The options of ``mcgeom experiment ch10``."""
    add_count_and_seed(ap, "--runs", 10,
                       "problems per noise level (the preemption table: at most 5)")


def run_cli(args: argparse.Namespace, progress: Progress = no_progress) -> int:
    """Print the Fig. 10.4-10.5 table and the preemption table."""
    runs = args.runs
    print("Fig. 10.4-10.5: mean errors over", runs, "problems per level")
    print(ch9.table(ch9.run(runs, args.seed, methods=METHODS, progress=progress)))
    print("\npreemptive per-camera test (median over", min(runs, 5), "problems at 0.5 px)")
    print(preemption_table(preemption(min(runs, 5), seed=args.seed, progress=progress)))
    return 0
