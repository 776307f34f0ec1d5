"""Issue-3 targets, checked on small runs of the experiment scripts (the full
runs print the tables: ``mcgeom experiment ch7 --trials 200``,
``mcgeom experiment minimal_5p1 --trials 10000``,
``mcgeom experiment robust_vs_poselib``). Only what must hold is
asserted, never a timing."""

from __future__ import annotations

import argparse

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
    the widened local optimisation of csrc/robust.c)."""
    s = experiment_ch7.summary(experiment_ch7.run(40, seed=8, cross=0.1))
    print(s)
    assert s["bad_flagged_fraction"] >= 0.9
    assert s["bad"] <= 2


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
