"""Issue-3 targets, checked on small runs of the experiment scripts (the full
runs print the tables: ``mcgeom experiment ch7 --trials 200``,
``mcgeom experiment minimal_5p1 --trials 10000``,
``mcgeom experiment robust_vs_poselib``). Only what must hold is
asserted, never a timing."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pytest

from mcgeom.experiments import ch7 as experiment_ch7
from mcgeom.experiments import minimal_5p1 as experiment_minimal_5p1
from mcgeom.experiments.common import fraction


@pytest.mark.parametrize("cross", [0.0, 0.1])
def test_scale_verdict_on_the_vehicle_rig(cross):
    """Forward motion, yaw under 2 deg, 1 px noise: observable verdicts have a
    median scale error <= 5 %, and >= 90 % of the estimates off by more than
    30 % are reported unobservable (intra-camera only: no scale at all)."""
    rows = experiment_ch7.run(40, seed=1, cross=cross)
    s = experiment_ch7.summary(rows)
    print(s)
    assert s["bad_flagged_fraction"] >= 0.9
    if cross == 0.0:
        assert s["observable"] <= 2          # critical motion: (almost) never observable
    else:
        assert s["observable"] >= 15         # cross-camera rays fix the scale
        assert s["median_err_observable"] <= 0.05
    assert s["median_rot_err_deg"] < 0.1


def test_wrong_scale_near_the_critical_motion_is_flagged():
    """The draw where a wrong-scale hypothesis won the search with 10 %
    cross-camera pairs and 1 of 4 estimates off by more than 30 % was called
    observable (bad_flagged_fraction 0.75 before the final scale search and
    the widened local optimisation of csrc/robust_lo.c)."""
    s = experiment_ch7.summary(experiment_ch7.run(40, seed=8, cross=0.1))
    print(s)
    assert s["bad_flagged_fraction"] >= 0.9
    assert s["bad"] <= 2


@pytest.mark.parametrize("trial", [1089, 381, 1023])
def test_final_scale_search_compares_scales_on_equal_terms(trial):
    """Trial 1089 of ``mcgeom experiment ch7 --trials 1200 --seed 10 --cross 0.1``
    (tests/data/synthetic: its pixels, ids, threshold and seed, and the true
    motion): the search's best had |t| 1.08 m (the truth 1.18 m) and the
    final scale search proposed 0.02 m. Locally optimised with |t| held, the
    best kept the rotation error that compensated its scale error while the
    proposal's optimisation refitted the rotation, so the proposal won; the
    final refinement then settled at 0.188 m on 348 pairs (the truth has
    356) and the verdict called it observable (relative std 0.076). Both
    optimised with |t| free, the best wins and the estimate is the truth.
    Trial 381: the same from 1.72 m (the truth 1.84 m) to a proposal of 0.11 m
    once the scale search tried every proposal. Trial 1023: the search's best
    (0.16 m, the truth 1.05 m) had a rotation at which the cross-camera pairs
    pointed to no other scale; refined, it stayed at 0.209 m with 22 of them
    as inliers, and at the refined rotation 35 point to 1.04 m: the scale is
    now searched again after the refinement."""
    from mcgeom import synth
    from mcgeom.cv import estimate
    d = np.load(Path(__file__).parent / "data" / "synthetic" / f"ch7_cross01_trial{trial}.npz")
    m = estimate(d["pixels1"], d["pixels2"], d["cam1"], d["cam2"], synth.vehicle8(),
                 threshold=float(d["threshold"]), seed=int(d["seed"]))
    assert m.scale.observable
    assert abs(np.linalg.norm(m.info["t_metric"]) / np.linalg.norm(d["t"]) - 1.0) < 0.02


def test_upright_rows_and_the_unflagged_count():
    """``--vertical-error-deg`` runs the upright sampler on the same trials;
    ``unflagged_bad`` counts the bad estimates called observable."""
    rows = experiment_ch7.run(6, seed=3, cross=0.1, vertical_error_deg=0.2)
    s = experiment_ch7.summary(rows)
    assert s["trials"] == 6 and s["median_rot_err_deg"] < 0.1
    assert s["unflagged_bad"] == sum(r["scale_err"] > 0.3 and r["observable"] for r in rows)
    assert fraction("0.3") == 0.3
    with pytest.raises(argparse.ArgumentTypeError, match="fraction"):
        fraction("1.5")


def test_minimal_5p1_recovers_noise_free_motion():
    """Target 99.9 % over 10,000 configurations (measured: 99.92 %); 300 here."""
    s = experiment_minimal_5p1.run(300, seed=3, with_poselib=False)
    assert s["mcgeom_success"] >= 0.99


def test_robust_pipeline_matches_poselib_accuracy():
    pytest.importorskip("poselib")
    from mcgeom.experiments import robust_vs_poselib as b
    res = b.run(trials=8, seed=2, cases={k: b.CASES[k] for k in list(b.CASES)[:2]})
    print("\n" + b.table(res))
    for case, methods in res.items():
        ours, peer = methods["mcgeom"][0], methods["poselib"][0]
        assert np.mean((ours[:, 0] > 1.0) | (ours[:, 1] > 10.0)) <= np.mean(
            (peer[:, 0] > 1.0) | (peer[:, 1] > 10.0))
        assert np.median(ours[:, 0]) < 1.5 * np.median(peer[:, 0]) + 1e-3
