"""The shared static-rig test (mcgeom.estimators._static), the best-start
chooser (mcgeom.estimators._start), e_socp's cross-camera cones and the
honesty experiment's evaluation (issue 18)."""

from __future__ import annotations

import argparse

import numpy as np
import pytest

import mcgeom
from mcgeom import synth
from mcgeom.errors import DegenerateError
from mcgeom.estimators import _start, _static
from mcgeom.experiments import EXPERIMENTS, honesty
from problems import make, rot_err


def _moving(seed, noise=3e-4, cross=0.0, t_norm=0.5):
    return make("locally-central" if cross == 0.0 else "most-general", seed, n=80,
                angular_noise=noise, t_norm=t_norm)


@pytest.mark.parametrize("seed", range(6))
def test_a_moving_rig_is_not_static(seed):
    """The noise level comes from the per-camera fit, not from a |t| an
    estimate slid to: a moving rig never passes for a static one."""
    p = _moving(seed)
    level = _static.noise_level_of(p.rays, p.R)
    assert level < 10 * _static.NOISE_FACTOR * 3e-4
    assert not _static.static_test(p.rays, level).static
    # a wrong rotation must not make the rig look static either (the smaller
    # noise of the given and the best pure rotation is used)
    wrong = synth.random_rotation(np.random.default_rng(seed), 0.2) @ p.R
    assert _static.check_static(p.rays, "x", rotation=wrong) is None


def test_static_answer_and_noise_level_do_not_depend_on_the_world_scale():
    rng = np.random.default_rng(3)
    p = synth.make_problem(synth.generic_rig(4, rng), np.eye(3), np.zeros(3), 80, rng,
                           angular_noise=3e-4, require_visible=False)
    a = _static.check_static(p.rays, "x")
    scaled = mcgeom.RayPairs(1e3 * p.rays.origins1, p.rays.dirs1, 1e3 * p.rays.origins2,
                             p.rays.dirs2, cam1=p.rays.cam1, cam2=p.rays.cam2)
    b = _static.check_static(scaled, "x")
    assert a is not None and b is not None
    assert rot_err(a.R, b.R) < 1e-12
    assert a.info["static_test"]["noise_level"] == pytest.approx(
        b.info["static_test"]["noise_level"], rel=1e-9)
    assert a.scale.reason.startswith("no translation detected")
    assert np.array_equal(a.t, np.zeros(3)) and a.info["translation_detected"] is False


def test_static_test_needs_a_positive_noise_level():
    p = _moving(0)
    with pytest.raises(ValueError, match="noise_level"):
        _static.static_test(p.rays, 0.0)


def _euroc_near_static():
    """The EuRoC hovering pair (0.9 mm between the frames): its rays and 5+1's
    full estimate before the static test."""
    from pathlib import Path

    from mcgeom.estimators.five_plus_one import _five_plus_one
    from mcgeom.experiments.make_real_fixtures import load_fixture
    f = load_fixture(Path(__file__).parent / "data" / "real" / "euroc_static.npz")
    rays = f["rig"].ray_pairs(f["pixels1"], f["pixels2"], f["cam1"], f["cam2"])
    return rays, _five_plus_one(rays, None, True, 0.1)


def test_near_static_rig_is_judged_at_the_estimates_own_rotation():
    """Issue 18, EuRoC hovering: the full estimate's tiny t trades against its
    rotation, whose per-camera fit gives the (smaller) noise level; the
    rotation-only angles at the best pure rotation exceed 1.5 levels, those at
    the estimate's own rotation do not: no translation detected, t = 0."""
    rays, full = _euroc_near_static()
    from mcgeom.geometry import rotation_fit, same_camera
    R0 = rotation_fit(rays, same_camera(rays))[0]
    levels = _static._noise_levels(rays, (full.R, R0))
    assert levels[0] < levels[1]
    assert not _static.static_test(rays, levels[0]).static          # angles at R0
    assert _static.static_test(rays, levels[0], rotation=full.R).static
    m = _static.check_static(rays, "x", full)
    assert m is not None and np.array_equal(m.t, np.zeros(3))
    assert "estimate's rotation" in m.info["static_test"]["noise_source"]
    assert rot_err(m.R, full.R) < 1e-15


def test_linear17_on_a_static_rig_does_not_raise():
    """E = 0 used to raise DegenerateError ("matches no generalized-camera
    kind"); docs/bad_input.md promises R = I with an unobservable scale."""
    rng = np.random.default_rng(1)
    p = synth.make_problem(synth.generic_rig(4, rng), np.eye(3), np.zeros(3), 60, rng,
                           require_visible=False)
    m = mcgeom.estimate(p.rays, "linear17")
    assert rot_err(m.R, np.eye(3)) < 1e-9 and not m.scale.observable
    assert np.array_equal(m.t, np.zeros(3))


def test_linear17_still_raises_on_degenerate_data_that_is_not_static():
    """Too few rays for the kind is no static rig: the error stays."""
    p = _moving(2)
    with pytest.raises((DegenerateError, ValueError)):
        mcgeom.estimate(p.rays.take(np.arange(15)), "linear17")


def test_best_start_keeps_the_lower_robust_cost():
    p = _moving(4, noise=1e-3)
    m, report = _start.best_start(p.rays, 5e-3)
    assert set(report["costs"]) == {"five_plus_one", "linear17"}
    assert report["costs"][report["chosen"]] == min(report["costs"].values())
    assert _start.robust_cost(p.rays, m.R, _start.metric_translation(m), 5e-3) == \
        pytest.approx(report["costs"][report["chosen"]])
    # refine starts from it and says so
    r = mcgeom.estimate(p.rays, "refine")
    assert r.info["initial_method"] == report["chosen"]
    assert r.info["start_costs"]["costs"] == report["costs"]


def test_best_start_skips_a_candidate_that_cannot_run():
    """No camera with 5 intra-camera correspondences: 5+1 cannot start, linear17 can."""
    p = make("most-general", 5, n=60)
    cross = np.flatnonzero(p.rays.cam1 != p.rays.cam2)
    m, report = _start.best_start(p.rays.take(cross), 5e-3)
    assert report["chosen"] == "linear17" and "five_plus_one" in report["errors"]
    assert rot_err(m.R, p.R) < 1e-8


def test_best_start_bad_arguments_name_themselves():
    p = _moving(0)
    with pytest.raises(ValueError, match="loss_scale"):
        _start.best_start(p.rays, -1.0)
    with pytest.raises(ValueError, match="candidates"):
        _start.best_start(p.rays, 5e-3, candidates="linear17")
    with pytest.raises(ValueError, match="unknown estimator"):
        _start.best_start(p.rays, 5e-3, candidates=("nope",))


@pytest.mark.parametrize("seed", range(4))
def test_e_socp_cross_camera_cones_fix_the_scale_without_rotation(seed):
    """No rotation: the intra-camera cones share their apex and leave |t|
    free (ch. 9.5); a cross-camera pair's cone has its apex at c_b - c_a and
    fixes it (the data used decide the verdict)."""
    rng = np.random.default_rng(seed)
    t = rng.normal(size=3)
    t *= 0.5 / np.linalg.norm(t)
    p = make("most-general", seed, n=160, R=np.eye(3), t=t)
    m = mcgeom.estimate(p.rays, "e_socp", robust_threshold=None)
    assert m.info["cross_pairs"]
    assert m.scale.observable
    assert np.linalg.norm(m.t - t) < 1e-7
    intra = p.rays.take(np.flatnonzero(p.rays.cam1 == p.rays.cam2))
    m0 = mcgeom.estimate(intra, "e_socp", robust_threshold=None)
    assert not m0.scale.observable and m0.info["cross_pairs"] == []


def test_e_socp_verdict_uses_the_least_squares_evidence_of_its_data():
    p = make("most-general", 7, n=160, angular_noise=3e-4)
    m = mcgeom.estimate(p.rays, "e_socp", robust_threshold=None)
    ratio, rel_ls = m.info["scale_ls_ratio"], m.info["scale_rel_std_ls"]
    assert m.scale.rel_std == pytest.approx(np.hypot(rel_ls, ratio - 1.0))
    if m.scale.observable:
        assert abs(np.linalg.norm(m.t) / np.linalg.norm(p.t) - 1.0) < 5 * m.scale.rel_std


def test_honesty_evaluate_flags_a_confident_wrong_scale():
    """The experiment's row logic on synthetic rays (no recordings needed)."""
    p = make("most-general", 8, n=80, angular_noise=1e-4)
    good = honesty.evaluate(p.rays, "refine", p.R, p.t)
    assert good["ok"] and good["verdict"] == "OBS" and not good["confident_wrong"]
    assert good["rot_err"] < 0.05
    # the same answer against a truth twice as long is confident and wrong
    bad = honesty.evaluate(p.rays, "refine", p.R, 2.0 * p.t)
    assert bad["confident_wrong"]
    failed = honesty.evaluate(p.rays.take(np.arange(5)), "linear17", p.R, p.t)
    assert not failed["ok"] and "ValueError" in failed["error"]
    assert "FAILED" in honesty.format_row("syn", (0, 1), "intra", "linear17", 5, failed)


def test_honesty_is_registered_and_names_a_bad_estimator():
    assert EXPERIMENTS["honesty"][0] == "honesty"
    ap = argparse.ArgumentParser()
    honesty.add_arguments(ap)
    args = ap.parse_args(["--estimators", "linear17", "nope"])
    with pytest.raises(ValueError, match="--estimators"):
        honesty.run_cli(args)


def test_oxts_gravity_follows_roll_and_pitch():
    """KITTI raw's vertical from an OXTS packet (x forward, y left, z up; roll
    positive = left side up, pitch positive = front down): level gives
    (0, 0, -1), front down tips gravity forward, left side up tips it right."""
    from mcgeom.experiments.real_data import oxts_gravity
    packet = np.zeros(30)
    np.testing.assert_allclose(oxts_gravity(packet), [0.0, 0.0, -1.0])
    packet[4] = 0.1                                   # pitch: front down
    g = oxts_gravity(packet)
    assert g[0] > 0 and abs(g[1]) < 1e-15 and np.isclose(np.linalg.norm(g), 1.0)
    packet[3], packet[4] = 0.1, 0.0                   # roll: left side up
    g = oxts_gravity(packet)
    assert g[1] < 0 and abs(g[0]) < 1e-15


def test_honesty_gives_the_vertical_to_the_estimator_that_takes_it():
    """upright_four_point takes the vertical (and is skipped on recordings
    without one); evaluate passes it on, and the motion comes out right."""
    assert honesty.needs_vertical("upright_four_point")
    assert not honesty.needs_vertical("linear17")
    assert "upright_four_point" in honesty.DEFAULT_ESTIMATORS
    rng = np.random.default_rng(3)
    rig = synth.generic_rig(4, rng)
    R = synth.rotation_about([0, 0, 1], 0.2) @ synth.rotation_about([1, 0, 0], 0.05)
    t = np.array([0.4, 0.1, 0.02])
    p = synth.make_problem(rig, R, t, 120, rng, angular_noise=1e-4, require_visible=False)
    g1 = synth.GRAVITY
    r = honesty.evaluate(p.rays, "upright_four_point", R, t, vertical=(g1, R @ g1))
    assert r["ok"] and r["rot_err"] < 0.05, r
    assert not honesty.evaluate(p.rays, "upright_four_point", R, t)["ok"]   # needs it


def test_metric_t_of_a_static_answer_is_zero():
    """real_data.metric_t: the returned t when observable, zero for "no
    translation detected" (not the free refinement's slide), else the
    metric guess t_metric."""
    from types import SimpleNamespace
    from mcgeom.experiments.real_data import metric_t
    slid = np.array([300.0, 1.0, 0.0])
    static = SimpleNamespace(scale=SimpleNamespace(observable=False), t=np.zeros(3),
                             info={"translation_detected": False, "t_metric": slid})
    np.testing.assert_array_equal(metric_t(static), np.zeros(3))
    unobs = SimpleNamespace(scale=SimpleNamespace(observable=False), t=np.array([1.0, 0, 0]),
                            info={"translation_detected": True, "t_metric": slid})
    np.testing.assert_array_equal(metric_t(unobs), slid)
    obs = SimpleNamespace(scale=SimpleNamespace(observable=True), t=np.array([0.9, 0, 0]),
                          info={"t_metric": slid})
    np.testing.assert_array_equal(metric_t(obs), [0.9, 0, 0])
