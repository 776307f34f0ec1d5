"""``mcgeom bench robust`` on a few problems: both timings (cold: the methods
alternating per problem; warm: blocks of problems per method) for every case
and method, mcgeom's share outside C and its C call's stages, the paired
comparison, the printed table with its ratio columns, and the scaling part
(PoseLib on the same pixels, the search alone, the fit)."""

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
            assert np.isnan(r.time_ratio_ci).all()
            # the C call's stages and the time outside it: medians of parts
            # of the cold time, so their sum is about it
            assert set(r.stages_ms) == {"rays", "search", "final", "verdict", "outside C"}
            assert all(v > 0 for v in r.stages_ms.values())
            assert 0.5 * r.ms < sum(r.stages_ms.values()) < 1.5 * r.ms
            # the bound of 12 problems: mcgeom's medians within their spread of it
            assert 0.5 < r.rot_deg / r.bound_rot_deg < 2.0
            assert 0.0 < r.bound_scale_err < 1.0
        else:
            assert 0.0 <= r.mcgeom_rot_better <= 1.0 and np.isnan(r.outside_c)
            assert np.isnan(r.bound_rot_deg) and np.isnan(r.bound_scale_err)
            for lo, hi in (r.time_ratio_ci, r.rot_ratio_ci, r.scale_ratio_ci):
                assert 0.0 < lo <= hi < np.inf


def test_bench_robust_command_prints_both_ratios(capsys):
    pytest.importorskip("poselib")
    assert cli.main(["bench", "robust", "--problems", "2", "--sizes", "1000"]) == 0
    out = capsys.readouterr().out
    header = next(line for line in out.splitlines() if line.startswith("case"))
    assert "ms cold" in header and "ms warm" in header and header.count("mcgeom/this") == 2
    rows = [line for line in out.splitlines() if "poselib min_it=100" in line
            and not line.startswith(("mcgeom / ", " "))]  # (the intervals, the bound)
    assert len(rows) == 3 and all(line.count("x ") >= 2 for line in rows)
    assert "warm: the same problems in blocks" in out
    intervals = [line for line in out.splitlines() if "time cold" in line]
    assert len(intervals) == 3 and all("scale error" in line and "[" in line
                                       for line in intervals)
    assert "min-max us/corr" in out and "largest / smallest median" not in out  # one size
    stages = [line for line in out.splitlines() if "search" in line and "verdict" in line
              and line.startswith("  ")]
    assert len(stages) == 3 and all("outside C" in line for line in stages)
    # the Cramer-Rao bound of each case, and every method's medians over it
    assert sum(1 for line in out.splitlines() if " bound: rotation " in line) == 3
    assert sum(1 for line in out.splitlines() if line.startswith(" ") and "x, scale" in line) == 9



def test_bench_robust_prints_the_cost_fit_over_sizes(capsys):
    pytest.importorskip("poselib")
    assert cli.main(["bench", "robust", "--problems", "2", "--sizes", "1000,3000"]) == 0
    out = capsys.readouterr().out
    assert "largest / smallest median" in out and "the facade (mcgeom.cv.estimate" in out
    fit = next(line for line in out.splitlines() if line.startswith("fit of the medians"))
    assert "us x N, within" in fit and "of the time at N = 1000" in fit


def test_scaling_rows_are_medians_over_several_problems():
    from mcgeom.experiments.bench.robust_scaling import bench_scaling, scaling_problems
    assert scaling_problems(1000) == 15 and scaling_problems(10 ** 5) == 10 \
        and scaling_problems(10 ** 6) == 3
    try:
        import poselib  # noqa: F401  (a test-only dependency: the rows without it too)
        peer = True
    except ImportError:
        peer = False
    rows = bench_scaling(sizes=(300, 2000), peer=peer)
    for r, n in zip(rows, (300, 2000)):
        assert r.n == n and r.problems == scaling_problems(n) >= 3
        # the median lies within the spread of the problems it is taken over
        assert 0 < r.us_per_corr_min <= r.us_per_corr <= r.us_per_corr_max
        assert r.seconds == pytest.approx(r.us_per_corr * n / 1e6)
        assert 0 < r.c_seconds < r.seconds and r.peak_mb > 0 and r.rot_deg < 0.5
        # the search alone is part of the estimate; PoseLib ran on the same pixels
        assert 0 < r.search_seconds < r.seconds
        if peer:
            assert r.peer_seconds > 0 and r.peer_rot_deg < 0.5
        else:
            assert np.isnan(r.peer_seconds) and np.isnan(r.peer_rot_deg)
        # the façade on the same pixels: its time, its peak over its input
        # (pixels and ids: 48 bytes a correspondence)
        assert r.facade_seconds > 0 and r.facade_peak_mb > r.facade_input_mb > 0
        assert r.facade_input_mb == pytest.approx(48 * n / 1e6)


def test_ring_problem_pixels_are_its_rays():
    """The scaling problem: pixels in the image at both times, its rays those
    of the rig's pixels, the inliers on the true motion (Sampson residuals
    at noise level) and about 20 % outliers off it."""
    from mcgeom.experiments.bench.robust_scaling import ring_problem
    from mcgeom.robust._scoring import residuals
    p = ring_problem(4000, np.random.default_rng(3))
    for px in (p.pixels1, p.pixels2):
        assert px.shape == (4000, 2) and np.all(np.abs(px - [511.5, 383.5]) < [515, 387])
    ref = p.rig.ray_pairs(p.pixels1, p.pixels2, p.cam)
    assert np.array_equal(ref.dirs1, p.rays.dirs1) and np.array_equal(ref.dirs2, p.rays.dirs2)
    assert np.bincount(p.cam).tolist() == [1000] * 4
    res = residuals(p.rays, p.R, p.t) * 500.0   # ~pixels
    off = np.mean(res > 5.0)
    assert 0.15 < off < 0.22 and np.median(res) < 1.0


def test_ring_problem_names_a_motion_that_leaves_nothing_in_view(monkeypatch):
    """A motion that turns every point out of view is a clear error, not an
    endless redraw."""
    from mcgeom import synth
    from mcgeom.experiments.bench import robust_scaling
    monkeypatch.setattr(robust_scaling, "generic_motion", lambda rng: (
        synth.rotation_about([0.0, 0.0, 1.0], np.pi), np.zeros(3)))
    with pytest.raises(RuntimeError, match="camera 0 keeps too few points in view"):
        robust_scaling.ring_problem(100, np.random.default_rng(0))


def test_fixed_and_marginal_cost_fit():
    """The model seconds = fixed + marginal N is recovered from exact rows
    (across three decades, where an unweighted fit would ignore the
    smallest), and refused on one size."""
    from mcgeom.experiments.bench.robust_scaling import ScaleRow, fixed_and_marginal
    rows = [ScaleRow(n, 1.8e-3 + 0.6e-6 * n, 0.0, 0.0, 1.0, 0.0, 0.8)
            for n in (1000, 10000, 100000, 1000000)]
    fixed, marginal = fixed_and_marginal(rows)
    assert fixed == pytest.approx(1.8e-3, rel=1e-9) and marginal == pytest.approx(0.6e-6, rel=1e-9)
    # a noisy smallest size moves the fixed part, not the marginal cost, much
    rows[0] = ScaleRow(1000, 1.1 * rows[0].seconds, 0.0, 0.0, 1.0, 0.0, 0.8)
    fixed, marginal = fixed_and_marginal(rows)
    assert 1.8e-3 < fixed < 2.2e-3 and marginal == pytest.approx(0.6e-6, rel=0.05)
    with pytest.raises(ValueError, match="two sizes"):
        fixed_and_marginal(rows[:1])


def test_ratio_interval_brackets_the_ratio_of_medians():
    """The bootstrap interval of median(a) / median(b) over paired problems:
    it holds the ratio of the full medians, narrows with more problems, and
    is a point where the two samples are the same."""
    from mcgeom.experiments.bench.robust import _ratio_interval
    rng = np.random.default_rng(1)
    b = rng.lognormal(0.0, 0.3, 400)
    a = 0.25 * b * rng.lognormal(0.0, 0.1, 400)     # a quarter of b, paired noise
    lo, hi = _ratio_interval(a, b, np.random.default_rng(0))
    assert lo < np.median(a) / np.median(b) < hi and 0.2 < lo < 0.25 < hi < 0.3
    lo100, hi100 = _ratio_interval(a[:100], b[:100], np.random.default_rng(0))
    assert hi100 - lo100 > hi - lo
    assert _ratio_interval(b, b, np.random.default_rng(0)) == (1.0, 1.0)
