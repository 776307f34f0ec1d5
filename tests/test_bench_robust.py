"""``mcgeom bench robust`` on a few problems: both timings (cold: the methods
alternating per problem; warm: blocks of problems per method) for every case
and method, mcgeom's share outside C, the paired comparison, and the printed
table with its ratio columns."""

from __future__ import annotations

import numpy as np
import pytest

from mcgeom import cli


def test_speed_rows_have_cold_and_warm_times():
    pytest.importorskip("poselib")
    from mcgeom.experiments.bench.robust import CASES, WARM_BLOCK, bench_speed
    rows = bench_speed(problems=WARM_BLOCK + 2)    # two warm blocks, the last one short
    assert [(r.case, r.method) for r in rows][::3] == [(c, "mcgeom") for c in CASES]
    for r in rows:
        assert r.ms > 0 and r.ms_warm > 0
        assert np.isfinite(r.rot_deg) and r.rot_deg < 1.0
        if r.method == "mcgeom":
            assert 0.0 < r.outside_c < 1.0 and np.isnan(r.mcgeom_rot_better)
        else:
            assert 0.0 <= r.mcgeom_rot_better <= 1.0 and np.isnan(r.outside_c)


def test_bench_robust_command_prints_both_ratios(capsys):
    pytest.importorskip("poselib")
    assert cli.main(["bench", "robust", "--problems", "2", "--sizes", "1000"]) == 0
    out = capsys.readouterr().out
    header = next(line for line in out.splitlines() if line.startswith("case"))
    assert "ms cold" in header and "ms warm" in header and header.count("mcgeom/this") == 2
    rows = [line for line in out.splitlines() if "poselib min_it=100" in line]
    assert len(rows) == 3 and all(line.count("x ") >= 2 for line in rows)
    assert "warm: the same problems in blocks" in out
