"""Thesis ch. 6 on the real KITTI-00 stereo tracks (mcgeom experiment ch6_kitti
runs frames 13-76): a shorter stretch here. Skipped without the recordings.

With known rotations and the stereo rig's offsets the translation must come
out metric, and close to the ground truth without any alignment. Measured on
frames 13-40 (28 views, 25.3 m; ``mcgeom experiment ch6_kitti --last
40``): with the consecutive window, RMS centre error 0.24-0.25 m and path
length ratio 0.990-0.993; with every relation of the tracks (up to 26 frames
apart) RMS 0.48-0.58 m and ratio 0.962-0.965 (the algebraic residuals of the
long baselines weigh the noise of their coefficients most: the solution
shrinks). The bundle adjustment that refines the metric centres by default
(mcgeom.multiview_refine) gives RMS 0.248 m and ratio 0.993 with every
relation. The bounds leave room for small changes, not for a wrong scale.
"""

from __future__ import annotations

import numpy as np
import pytest

import mcgeom.experiments.ch6_kitti as ev
import mcgeom.experiments.real_data as erd

if not erd.data_available():
    pytest.skip(f"real recordings not found under {erd.DATA_ROOT}", allow_module_level=True)


@pytest.fixture(scope="module")
def results():
    return ev.evaluate(13, 40, out=lambda *a: None)


def test_every_variant_is_metric_and_near_the_ground_truth(results):
    for name, row in results.items():
        windowed = "window" in name or name == "chained two-view"
        assert row["observable"], name
        assert row["views"] == 28, name
        assert row["rms"] < (0.35 if windowed else 0.8), (name, row)
        assert abs(row["scale"] - 1.0) < (0.02 if windowed else 0.05), (name, row)
        # the shape alone (after a similarity) is closer still
        assert row["rms_sim"] < row["rms"] + 1e-9, (name, row)


def test_bundle_adjustment_is_as_close_as_the_consecutive_window(results):
    """The refined centres do not shrink with the long tracks' relations as the
    algebraic ones of every relation do (0.48-0.58 m there)."""
    ba = results["bundle adjustment"]
    assert ba["observable"]
    assert ba["rms"] < 0.3 and abs(ba["scale"] - 1.0) < 0.015, ba


def test_solver_choice_does_not_change_a_metric_solution(results):
    """The constrained / plain choice normalises the homogeneous solution;
    a metric (inhomogeneous) solve is the same least squares for both."""
    for rel in ("bilinear", "trilinear"):
        for where in ("all", "window 1" if rel == "bilinear" else "window 2"):
            a, b = results[f"{rel} + svd, {where}"], results[f"{rel} + constrained, {where}"]
            assert np.isclose(a["rms"], b["rms"], rtol=1e-6), (rel, where)


def test_constrained_beats_plain_trilinear_on_real_short_tracks():
    """Thesis ch. 6.3 on real noise: cam0 alone (no scale), the tracks cut to
    <= 3 consecutive frames as in ch. 6.5.1. Measured on frames 13-76 (error
    after a similarity, path 59.5 m): trilinear plain SVD 2.01 m, constrained
    0.43 m. (Bilinear relations are near-degenerate for a car driving almost
    straight -- pairwise directions of nearly collinear centres fix no step
    lengths --: 4.0 m plain, 8.8 m constrained, which collapses onto a few
    steps; reported by the evaluation script, not asserted.)"""
    res = ev.evaluate_monocular(13, 76, max_lens=(3,), out=lambda *a: None)
    svd = res["cam0 trilinear + svd, tracks <= 3 frames"]
    con = res["cam0 trilinear + constrained, tracks <= 3 frames"]
    assert not con["observable"] and not svd["observable"]   # one central camera: no scale
    assert con["rms_sim"] < 0.7
    assert con["rms_sim"] < 0.4 * svd["rms_sim"]


def test_cut_tracks_makes_short_consecutive_pieces():
    track = np.array([5, 5, 5, 5, 5, 5, 5, 9, 9])
    view = np.array([0, 1, 2, 3, 4, 6, 7, 2, 3])
    new = ev.cut_tracks(track, view, 3)
    # pieces: {0,1,2}, {3,4}, {6,7} (a gap starts a new piece), {2,3} of track 9
    groups = {tuple(view[new == t]) for t in np.unique(new)}
    assert groups == {(0, 1, 2), (3, 4), (6, 7), (2, 3)}
    assert len(np.unique(new[track == 9])) == 1
