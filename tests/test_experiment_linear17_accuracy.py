"""The linear17_accuracy experiment of issue 22 on a few problems: the
variants run on the same (paired) problems, and the kernel's refinement to
the Sampson optimum gives a lower median scale error than the previous
version's algebraic alternation on the non-overlapping head."""

from __future__ import annotations

import numpy as np
import pytest

from mcgeom.experiments import linear17_accuracy as exp


def test_variants_are_paired_and_the_kernel_beats_the_previous_version():
    case = "2-cam non-overlap (100)"
    res = exp.run(trials=8, seed=3, cases={case: exp.CASES[case]},
                  variants=["previous", "opengv", "kernel"])
    e = res[case]
    assert all(a.shape == (8, 3) for a in e.values())
    assert np.all(np.isfinite(e["kernel"][:, :2]))
    assert np.isnan(e["opengv"][:, 2]).all() and set(e["kernel"][:, 2]) <= {0.0, 1.0}
    assert np.median(e["kernel"][:, 1]) < np.median(e["previous"][:, 1])
    text = exp.paired(res, "previous")
    assert case in text and "previous is more accurate" in text
    assert case in exp.table(res)


def test_bound_of_every_case_and_the_kernel_near_it():
    """Every case declares its noise; on the ring the kernel's medians are
    those of an efficient estimator (the Cramer-Rao bound) within the spread
    of 12 problems, and the table names each case."""
    assert set(exp.NOISE) == set(exp.CASES) == set(exp.ISSUE_OPENGV)
    case = "4 cams x 50, 0.5 px (200)"
    cases = {case: exp.CASES[case]}
    res = exp.run(trials=12, seed=0, cases=cases, variants=["kernel"])
    bnd = exp.bounds(trials=12, seed=0, cases=cases)
    b_scale, b_rot = bnd[case]
    assert 0.01 < b_scale < 0.06 and 0.005 < b_rot < 0.05
    k = res[case]["kernel"]
    assert 0.6 < np.median(k[:, 1]) / b_scale < 1.6
    assert 0.6 < np.median(k[:, 0]) / b_rot < 1.6
    text = exp.bound_table(res, bnd)
    assert case in text and "Cramer-Rao" in text and "target / bound" in text
    # the issue's 4x50 scale target (0.0185) over this bound, as printed
    row = next(line for line in text.splitlines() if line.startswith(case))
    assert float(row.split()[-1]) == pytest.approx(0.0185 / b_scale, abs=0.006)
