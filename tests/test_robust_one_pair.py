"""The robust estimate does not call a scale metric that rests on one
correspondence of its consensus (mcgeom.robust._verdict.one_pair_checked):
a wrong match with the leverage to pull the final refinement onto itself
leaves every residual small. Problems of the property suite's rig kinds
(mcgeom.synth_kinds), 1e-3 rad noise, random time-2 bearings, robust.ransac
at 3e-3 rad."""

from __future__ import annotations

import numpy as np
import pytest

from mcgeom import cv, robust, synth
from mcgeom.experiments.direct_outliers import wrong_metric
from mcgeom.synth_kinds import KIND_SETUPS, outlier_problem


def _case(kind: str, n: int, fraction: float, s: int):
    p, rays, bad = outlier_problem(kind, s, n, 1e-3, fraction)
    return p, rays, bad, robust.ransac(rays, threshold=3e-3, seed=s)


def test_an_outlier_of_leverage_one_is_not_metric():
    """2-camera stereo head, 60 correspondences, 30 % outliers, problem 5:
    three wrong matches in the consensus, |t| 73 % off at a reported std of
    4.9 % before."""
    p, rays, bad, m = _case("locally-central-and-axial", 60, 0.3, 5)
    assert not m.scale.observable
    assert "leverage above" in m.scale.reason
    assert m.info["max_leverage"] > 0.9
    assert abs(np.linalg.norm(m.t) - 1.0) < 1e-12
    assert np.linalg.norm(m.info["t_metric"]) > 0


def test_the_refit_without_it_moves_the_travel():
    """Axial 3-camera rig, 60 correspondences, 30 % outliers, problem 5: one
    wrong match of leverage 0.999 in a consensus of 29; |t| 20 % off at a
    reported std of 3.3 % before. Its linearised deletion moves the travel
    by 2.3 stds only; the refit without it by 20 %."""
    p, rays, bad, m = _case("axial", 60, 0.3, 5)
    assert not m.scale.observable
    assert "travelled distance moves by" in m.scale.reason
    assert m.info["lever_pairs_move"] > 0.15


def test_masking_wrong_matches_are_refitted_without_together():
    """Stereo head, 200 correspondences, 50 % outliers, problem 12: two
    wrong matches of leverage 0.82 and 0.79 in a consensus of 107 (below
    the one-pair rules) left |t| 24 % off at a reported std of 3.0 % before
    session 36; the refit without both moves the travel by 16 %."""
    p, rays, bad, m = _case("locally-central-and-axial", 200, 0.5, 12)
    assert not m.scale.observable
    assert "leverage above 0.5" in m.scale.reason
    assert m.info["lever_pairs_move"] > 0.1


@pytest.mark.parametrize("kind, n, fraction, s", [("axial", 60, 0.3, 18),
                                                  ("locally-central", 60, 0.5, 19)])
def test_a_move_within_the_tolerance_widens_the_std(kind, n, fraction, s):
    """One wrong match of leverage 0.98 / 0.997 in the consensus: |t| 10.2 /
    10.4 % off at a reported std of 0.36 / 1.0 % before session 36. The
    refit without it moves the travel by 8.4 / 9.9 %, more than 3 stds but
    within max_scale_rel_std: the scale stays metric with the move in its
    std, which then covers the error."""
    p, rays, bad, m = _case(kind, n, fraction, s)
    assert m.scale.observable
    move = m.info["lever_pairs_move"]
    assert m.info["scale_rel_std_consensus"] == m.scale.rel_std >= move > 0.05
    assert "without the correspondences of leverage above 0.5" in m.scale.reason
    assert wrong_metric(m.t, p.t, m.scale.rel_std) is None


def test_the_std_is_that_of_the_consensus_without_its_uncontrolled_pairs():
    """Stereo head, 200 correspondences, 30 % outliers, problem 48: two wrong
    matches of leverage 0.93 and 0.90 in a consensus of 141, |t| 13 % off at
    a reported std of 2.0 % before session 36. Without them the travel
    hardly moves, but the rest of the consensus fixes |t| to 6.1 % only."""
    p, rays, bad, m = _case("locally-central-and-axial", 200, 0.3, 48)
    assert m.scale.rel_std > 0.05
    if m.scale.observable:
        assert wrong_metric(m.t, p.t, m.scale.rel_std) is None


@pytest.mark.parametrize("kind", list(KIND_SETUPS))
def test_clean_consensus_keeps_its_verdicts(kind):
    """Without outliers no metric estimate is refused by the check (the
    refit without pairs of leverage above 0.5 may widen a std: most-general
    kind, problem 0, 0.46 -> 1.5 %, still metric)."""
    for s in range(10):
        p, rays, bad, m = _case(kind, 60, 0.0, s)
        assert "scale not confirmed" not in m.scale.reason, (s, m.scale.reason)
        assert "not supported by the bulk" not in m.scale.reason, (s, m.scale.reason)
        if m.scale.observable:
            assert wrong_metric(m.t, p.t, m.scale.rel_std) is None


def test_the_pixel_path_runs_the_check():
    """cv.estimate's one C call from the pixels (estimate_pinhole_c) checks
    its metric estimates too."""
    rng = np.random.default_rng(4)
    rig = synth.ring_rig(4)
    R = synth.rotation_about([0.1, 0.2, 1.0], 0.2)
    t = np.array([0.8, 0.3, 0.05])
    p = synth.make_problem(rig, R, t, 200, rng, pixel_noise=0.5, outlier_fraction=0.2)
    m = cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, rig, threshold=1.0)
    assert m.scale.observable
    assert 0.0 < m.info["max_leverage"] < 0.9
