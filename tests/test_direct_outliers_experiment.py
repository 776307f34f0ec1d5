"""``mcgeom experiment direct_outliers`` at small sizes: its cells, its
counts and its printed summary."""

from __future__ import annotations

import argparse

import numpy as np
import pytest

from mcgeom.experiments import direct_outliers as ex


def test_cells_count_every_problem():
    cells = ex.sweep(["five_plus_one", "linear17"], sizes=[60], noises=[1e-3],
                     fractions=[0.0, 0.02], problems=4)
    assert len(cells) == 2 * 4 * 2   # estimators x kinds x fractions
    for c in cells:
        assert c.metric + c.not_metric + c.failed == 4
        assert c.wrong == len(c.worst) <= c.metric
        assert c.n == 60   # (twice the minimal sample is below 60 for both)
    assert all(c.wrong == 0 for c in cells)


def test_wrong_metric_rule():
    t = np.array([1.0, 0.0, 0.0])
    assert ex.wrong_metric(1.05 * t, t, 0.02) is None          # within 10 %
    assert ex.wrong_metric(1.15 * t, t, 0.05) is None          # within 4 stds
    assert ex.wrong_metric(1.15 * t, t, 0.02) == pytest.approx(0.15)


def test_cli_prints_the_summary(capsys):
    ap = argparse.ArgumentParser()
    ex.add_arguments(ap)
    args = ap.parse_args(["--problems", "2", "--estimators", "known_rotation_translation",
                          "--sizes", "60", "--noise", "1e-3", "--fractions", "0", "0.02"])
    assert ex.run_cli(args) == 0
    out = capsys.readouterr().out
    assert "outliers 0.00: 0 of 4 cells with a wrong metric estimate" in out
    assert "outliers 0.02:" in out
    with pytest.raises(SystemExit, match="unknown estimator"):
        ex.run_cli(ap.parse_args(["--estimators", "nope"]))


def test_robust_rows():
    cells = ex.sweep([ex.ROBUST], sizes=[60], noises=[1e-3], fractions=[0.3], problems=3)
    assert len(cells) == 4 and all(c.estimator == ex.ROBUST for c in cells)
    for c in cells:
        assert c.metric + c.not_metric + c.failed == 3
        assert len(c.z) == c.metric and all(np.isfinite(c.z))
    ap = argparse.ArgumentParser()
    ex.add_arguments(ap)
    with pytest.raises(SystemExit, match="not a sampler of the robust estimate"):
        ex.run_cli(ap.parse_args(["--robust", "--estimators", "known_rotation_translation"]))


def test_robust_rows_of_other_samplers():
    """--robust --estimators names the robust estimate's samplers; the
    upright one is given the true vertical."""
    name = ex.ROBUST + ":upright_four_point"
    cells = ex.sweep([name], sizes=[60], noises=[1e-3], fractions=[0.3], problems=2)
    assert len(cells) == 4 and all(c.estimator == name for c in cells)
    assert sum(c.failed for c in cells) == 0
    assert sum(c.metric for c in cells) > 0 and sum(c.wrong for c in cells) == 0
