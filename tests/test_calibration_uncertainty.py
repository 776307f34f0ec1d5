"""Issue 18: the relative std of |t| includes the rig's calibration error
(mcgeom.observability.calibration_scale_std), is carried by the rig
(Rig.calibration_std, mcgeom JSON), and is calibrated: the 3-sigma interval
of |t| contains the truth when the extrinsics are off by the stated error."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import mcgeom
from mcgeom import _core, synth
from mcgeom.cv import estimate as cv_estimate
from mcgeom.experiments import calibration_coverage
from mcgeom.io.mcgeom_json import rig_from_dict, rig_to_dict
from mcgeom.observability import (calibration_scale_std, sampled_calibration_scale_std,
                                  with_sampled_calibration)
from mcgeom.rig import DEFAULT_EXTRINSIC_STD, Rig


def test_three_sigma_interval_covers_the_truth_with_perturbed_extrinsics():
    res = calibration_coverage.run(trials=40, seed=1, std_mm=1.0, std_deg=0.05, noise=0.5)
    assert res["coverage_3sigma"] >= 0.95
    # without the calibration term the interval is too narrow (the "before")
    assert res["coverage_3sigma_noise_only"] < res["coverage_3sigma"]


def test_first_order_calibration_std_matches_monte_carlo():
    """The propagated std against the spread of the non-robust 5+1 estimate
    over rigs perturbed by the stated error (noise-free pixels)."""
    rng = np.random.default_rng(2)
    rig = synth.vehicle8()
    std = (2e-3, np.radians(0.1))
    Rw = synth.rotation_about([0, 0, 1], np.radians(10))
    R, t = Rw.T, -Rw.T @ np.array([1.0, 0.0, 0.0])
    p = synth.make_problem(rig, R, t, 300, rng, cross_fraction=0.1)
    scales = []
    for _ in range(40):
        wrong = calibration_coverage.perturbed_rig(rig, *std, rng)
        rays = wrong.ray_pairs(p.pixels1, p.pixels2, p.cam1, p.cam2)
        m = mcgeom.estimate(rays, "five_plus_one")
        scales.append(np.linalg.norm(m.info["t_metric"]) / np.linalg.norm(t))
    predicted, cov = calibration_scale_std(p.rays, R, t, std)
    assert cov.shape == (6, 6)
    assert 0.6 < np.std(scales) / predicted < 1.6


def test_calibration_std_zero_and_scaling():
    rng = np.random.default_rng(3)
    rig = synth.vehicle8()
    Rw = synth.rotation_about([0, 0, 1], np.radians(10))
    R, t = Rw.T, -Rw.T @ np.array([1.0, 0.0, 0.0])
    p = synth.make_problem(rig, R, t, 200, rng, cross_fraction=0.1)
    assert calibration_scale_std(p.rays, R, t, (0.0, 0.0))[0] == 0.0
    a = calibration_scale_std(p.rays, R, t, (1e-3, 0.0))[0]
    b = calibration_scale_std(p.rays, R, t, (2e-3, 0.0))[0]
    assert a > 0 and b == pytest.approx(2 * a, rel=1e-3)   # first order: linear in the std


def test_rig_default_override_and_json_round_trip():
    cams = synth.vehicle8().cameras
    rig = Rig(cams)
    assert rig.calibration_std is None
    assert np.allclose(rig.extrinsic_std, np.tile(DEFAULT_EXTRINSIC_STD, (8, 1)))
    assert np.all(synth.vehicle8().extrinsic_std == 0)
    per = [(1e-3 * (k + 1), np.radians(0.01 * (k + 1))) for k in range(8)]
    rig2 = Rig(cams, calibration_std=per)
    back = rig_from_dict(rig_to_dict(rig2))
    assert np.allclose(back.extrinsic_std, rig2.extrinsic_std, rtol=1e-12, atol=0)
    assert rig_from_dict(rig_to_dict(rig)).calibration_std is None
    assert "extrinsic_std_mm" not in rig_to_dict(rig)["cameras"][0]
    assert rig2.in_frame(np.eye(3), np.ones(3)).calibration_std == rig2.calibration_std


@pytest.mark.parametrize("bad,match", [((1.0,), "calibration_std"), ((-1.0, 0.0), ">= 0"),
                                       ("x", "calibration_std"), ((np.nan, 0.0), ">= 0")])
def test_bad_calibration_std_names_it(bad, match):
    with pytest.raises(ValueError, match=match):
        Rig(synth.vehicle8().cameras, calibration_std=bad)


def test_bad_json_std_names_the_key():
    d = rig_to_dict(Rig(synth.stereo_head().cameras, calibration_std=(1e-3, 1e-3)))
    del d["cameras"][1]["extrinsic_std_deg"]
    with pytest.raises(ValueError, match="extrinsic_std_deg"):
        rig_from_dict(d)
    d = rig_to_dict(Rig(synth.stereo_head().cameras, calibration_std=(1e-3, 1e-3)))
    d["cameras"][0]["extrinsic_std_mm"] = -2
    with pytest.raises(ValueError, match="extrinsic_std_mm"):
        rig_from_dict(d)


def _turning_car(seed: int):
    """The 8-camera car rig turning 10 deg while driving 1 m, 400 correspondences
    (10 % cross-camera), 0.5 px: a metric scale the data fix."""
    rng = np.random.default_rng(seed)
    rig = synth.vehicle8()
    Rw = synth.rotation_about([0, 0, 1], np.radians(10))
    R, t = Rw.T, -Rw.T @ np.array([1.0, 0.0, 0.0])
    return rig, synth.make_problem(rig, R, t, 400, rng, pixel_noise=0.5, cross_fraction=0.1)


def test_facade_override_enters_rel_std_and_the_verdict():
    rig, p = _turning_car(4)
    exact = cv_estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, rig)
    assert exact.info["scale_rel_std_calibration"] == 0.0 and exact.scale.observable
    loose = cv_estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, rig,
                        calibration_std=(0.05, np.radians(2.0)))
    assert loose.scale.rel_std > exact.scale.rel_std
    assert loose.info["scale_rel_std_calibration"] > 0.1 and not loose.scale.observable
    assert loose.info["covariance"].shape == (6, 6)
    with pytest.raises(ValueError, match="calibration_std"):
        cv_estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, rig, calibration_std=(1.0, 2.0, 3.0))


def test_with_calibration_reason_quotes_the_total_rel_std():
    # the verdict's reason must quote the rel_std the user reads in scale.rel_std,
    # not the estimator's noise-only figure
    from mcgeom import estimate
    from mcgeom.observability import with_calibration
    _, p = _turning_car(5)
    m = estimate(p.rays, "linear17")
    assert m.scale.observable and "scale_rel_std_calibration" not in m.info
    c = with_calibration(m, p.rays, (2e-3, np.radians(0.1)))
    assert c.scale.observable and c.scale.rel_std > m.scale.rel_std
    assert f"{c.scale.rel_std:.3g}" in c.scale.reason
    assert f"{m.scale.rel_std:.3g}" in c.scale.reason   # the noise part is still named


def _refit_tau(rays, R, t, c, cam, kind, axis, delta):
    """The least-squares motion of ``rays`` refitted after camera ``cam``'s
    centre moved (kind 0) or the camera turned about its centre (kind 1) by
    ``delta`` along/about ``axis``: (rotation vector of R' R^T, tau' = t' +
    R' c - c) -- the definition the first-order propagation approximates."""
    o1, d1, o2, d2 = (np.array(a, dtype=float) for a in
                      (rays.origins1, rays.dirs1, rays.origins2, rays.dirs2))
    s1, s2 = rays.cam1 == cam, rays.cam2 == cam
    e = np.zeros(3)
    e[axis] = delta
    if kind == 0:
        o1[s1] += e
        o2[s2] += e
    else:
        turn = synth.rotation_about(np.eye(3)[axis], delta)
        d1[s1] = d1[s1] @ turn.T
        d2[s2] = d2[s2] @ turn.T
    out = _core.refine_motion(o1, d1, o2, d2, R, t, max_iterations=200,
                              cost_tolerance=1e-30, step_tolerance=1e-16)
    Rr, tr = out["R"], out["t"]
    dR = Rr @ R.T
    w = 0.5 * np.array([dR[2, 1] - dR[1, 2], dR[0, 2] - dR[2, 0], dR[1, 0] - dR[0, 1]])
    return np.concatenate([w, tr + Rr @ c - c])


@pytest.mark.parametrize("kind", [0, 1])
def test_c_propagation_matches_refitting_with_moved_extrinsics(kind):
    """mcg_calibration_scale_std against the definition it linearises:
    refit the motion of exact data after one camera's extrinsics moved by
    +-delta about each axis (central differences of the refitted theta);
    sum sigma^2 G G^T over the axes is the covariance it reports."""
    rng = np.random.default_rng(7 + kind)
    rig = synth.vehicle8()
    Rw = synth.rotation_about([0, 0, 1], np.radians(12))
    R, t = Rw.T, -Rw.T @ np.array([1.2, 0.1, 0.0])
    p = synth.make_problem(rig, R, t, 240, rng, cross_fraction=0.15)
    rays = p.rays
    c = 0.5 * (rays.origins1.mean(axis=0) + rays.origins2.mean(axis=0))
    cam, sigma, delta = 3, (2e-3 if kind == 0 else np.radians(0.1)), 1e-5
    std = np.zeros((len(rig.cameras), 2))
    std[cam, kind] = sigma
    rel, cov = _core.calibration_scale_std(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2,
                                           rays.cam1, rays.cam2, std, R, t)
    G = np.stack([(_refit_tau(rays, R, t, c, cam, kind, k, delta)
                   - _refit_tau(rays, R, t, c, cam, kind, k, -delta)) / (2 * delta)
                  for k in range(3)], axis=1)
    ref = sigma ** 2 * G @ G.T
    tau = t + R @ c - c
    u = tau / np.linalg.norm(tau)
    rel_ref = np.sqrt(u @ ref[3:, 3:] @ u) / np.linalg.norm(tau)
    assert rel > 0
    assert rel == pytest.approx(rel_ref, rel=1e-3)
    np.testing.assert_allclose(cov, ref, rtol=0, atol=1e-3 * np.abs(ref).max())


def test_c_propagation_refuses_bad_input_by_name():
    rng = np.random.default_rng(4)
    rig = synth.vehicle8()
    p = synth.make_problem(rig, np.eye(3), np.array([1.0, 0.0, 0.0]), 60, rng)
    r = p.rays
    std = np.full((8, 2), 1e-3)
    args = [r.origins1, r.dirs1, r.origins2, r.dirs2, r.cam1, r.cam2]
    with pytest.raises(ValueError, match="cam1"):
        _core.calibration_scale_std(*args[:4], np.full(60, 9), r.cam2, std, np.eye(3), np.ones(3))
    with pytest.raises(ValueError, match="extrinsic_std"):
        _core.calibration_scale_std(*args, -std, np.eye(3), np.ones(3))
    with pytest.raises(ValueError, match="t contains NaN"):
        _core.calibration_scale_std(*args, std, np.eye(3), np.array([np.nan, 0, 0]))
    bad = r.dirs2.copy()
    bad[5] = 0.0
    with pytest.raises(ValueError, match="dirs2"):
        _core.calibration_scale_std(*args[:3], bad, *args[4:], std, np.eye(3), np.ones(3))
    with pytest.raises(ValueError, match="loss"):
        _core.calibration_scale_std(*args, std, np.eye(3), np.ones(3), loss="l7")


def _differenced_covariance(rays, R, t, std, weights, loss_scale):
    """The covariance of mcg_calibration_scale_std rebuilt from central
    differences of _core.gec_residuals (steps 1e-6): J by turning R and
    moving tau, and dr/dp by moving each camera's origins and turning its
    bearings; Cauchy IRLS weights times ``weights``. An independent
    reference for the kernel's analytic derivatives."""
    o1, d1, o2, d2 = (np.array(a, dtype=float) for a in
                      (rays.origins1, rays.dirs1, rays.origins2, rays.dirs2))
    c = 0.5 * (o1.mean(axis=0) + o2.mean(axis=0))
    tau = t + R @ c - c
    h = 1e-6

    def res(Rm=R, tv=tau, a1=o1, b1=d1, a2=o2, b2=d2):
        return _core.gec_residuals(a1 - c, b1, a2 - c, b2, Rm, tv)

    def diff(f):
        return np.stack([(f(k, h) - f(k, -h)) / (2 * h) for k in range(3)], axis=1)

    def turned(k, s):
        return synth.rotation_about(np.eye(3)[k], s)

    J = np.hstack([diff(lambda k, s: res(Rm=turned(k, s) @ R)),
                   diff(lambda k, s: res(tv=tau + s * np.eye(3)[k]))])
    r0 = res()
    W = weights / (1.0 + (r0 / loss_scale) ** 2)
    Hinv = np.linalg.inv(J.T @ (W[:, None] * J))
    cov = np.zeros((6, 6))
    for cam in range(std.shape[0]):
        s1, s2 = (rays.cam1 == cam)[:, None], (rays.cam2 == cam)[:, None]
        moved = diff(lambda k, s: res(a1=o1 + s1 * s * np.eye(3)[k],
                                      a2=o2 + s2 * s * np.eye(3)[k]))
        turns = diff(lambda k, s: res(b1=np.where(s1, d1 @ turned(k, s).T, d1),
                                      b2=np.where(s2, d2 @ turned(k, s).T, d2)))
        for dp, sigma in ((moved, std[cam, 0]), (turns, std[cam, 1])):
            G = -Hinv @ (J.T @ (W[:, None] * dp))
            cov += sigma ** 2 * G @ G.T
    return cov


def test_c_derivatives_match_central_differences():
    """The kernel's analytic Jacobian and per-camera derivatives (intra- and
    cross-camera pairs, user weights, Cauchy loss on noisy rays) against
    central differences of the residuals: agreement to the differences'
    own error, far tighter than the refit test above."""
    rng = np.random.default_rng(11)
    rig = synth.vehicle8()
    Rw = synth.rotation_about([0.2, 0.1, 1.0], np.radians(9))
    R, t = Rw.T, np.array([0.9, -0.3, 0.1])
    p = synth.make_problem(rig, R, t, 300, rng, cross_fraction=0.3, pixel_noise=0.5)
    std = np.abs(rng.normal(size=(len(rig.cameras), 2))) * np.array([2e-3, np.radians(0.1)])
    weights = rng.uniform(0.5, 2.0, len(p.rays))
    rays = p.rays
    rel, cov = _core.calibration_scale_std(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2,
                                           rays.cam1, rays.cam2, std, R, t, weights, "cauchy",
                                           2e-3)
    ref = _differenced_covariance(rays, R, t, std, weights, 2e-3)
    assert rel > 0
    np.testing.assert_allclose(cov, ref, rtol=0, atol=1e-6 * np.abs(ref).max())


def test_sampled_calibration_std_matches_the_first_order_one_where_linear():
    """sampled_calibration_scale_std (the check of the first-order figure by
    rigs drawn with the stated error) against calibration_scale_std on a
    turning car rig, where the estimate is linear in the extrinsics over
    their error; and at a tenth of the error it scales with it."""
    rng = np.random.default_rng(4)
    rig = synth.vehicle8()
    std = np.array([2e-3, np.radians(0.1)])
    Rw = synth.rotation_about([0, 0, 1], np.radians(10))
    R, t = Rw.T, -Rw.T @ np.array([1.0, 0.0, 0.0])
    p = synth.make_problem(rig, R, t, 300, rng, pixel_noise=0.5, cross_fraction=0.1)
    first = calibration_scale_std(p.rays, R, t, std)[0]
    sampled = sampled_calibration_scale_std(p.rays, R, t, std, draws=128, seed=1)
    assert 0.8 < sampled / first < 1.25
    small = sampled_calibration_scale_std(p.rays, R, t, std / 10, draws=128, seed=1)
    assert small / sampled == pytest.approx(0.1, rel=0.1)
    assert sampled_calibration_scale_std(p.rays, R, t, (0.0, 0.0)) == 0.0


@pytest.mark.parametrize("draws", [0, 3, 2.0, "64"])
def test_sampled_calibration_std_bad_draws_name_it(draws):
    rng = np.random.default_rng(5)
    rig = synth.vehicle8()
    Rw = synth.rotation_about([0, 0, 1], np.radians(10))
    R, t = Rw.T, -Rw.T @ np.array([1.0, 0.0, 0.0])
    p = synth.make_problem(rig, R, t, 50, rng, cross_fraction=0.1)
    with pytest.raises(ValueError, match="draws"):
        sampled_calibration_scale_std(p.rays, R, t, (1e-3, 1e-3), draws=draws)
    with pytest.raises(ValueError, match="calibration_std"):
        sampled_calibration_scale_std(p.rays, R, t, np.ones((2, 2)))
    for bad in [(np.nan, 1e-3), (-1e-3, 1e-3)]:
        with pytest.raises(ValueError, match="finite values >= 0"):
            sampled_calibration_scale_std(p.rays, R, t, bad)
        with pytest.raises(ValueError, match="finite values >= 0"):
            calibration_scale_std(p.rays, R, t, bad)
    with pytest.raises(ValueError, match="finite"):
        sampled_calibration_scale_std(p.rays, R, np.array([np.nan, 0.0, 0.0]), (1e-3, 1e-3))
    with pytest.raises(ValueError, match="max_intra"):
        sampled_calibration_scale_std(p.rays, R, t, (1e-3, 1e-3), max_intra=0)


def _turning_motion(seed: int, n: int = 200):
    rng = np.random.default_rng(seed)
    rig = Rig(synth.vehicle8().cameras, calibration_std=(2e-3, np.radians(0.1)))
    Rw = synth.rotation_about([0, 0, 1], np.radians(10))
    R, t = Rw.T, -Rw.T @ np.array([1.0, 0.0, 0.0])
    p = synth.make_problem(rig, R, t, n, rng, pixel_noise=0.5, cross_fraction=0.1)
    m = cv_estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, rig, threshold=1.0)
    return rig, rig.ray_pairs(p.pixels1, p.pixels2, p.cam1, p.cam2), m


def test_with_sampled_calibration_keeps_a_linear_metric_estimate():
    rig, rays, m = _turning_motion(6)
    assert m.scale.observable
    out = with_sampled_calibration(m, rays, rig.extrinsic_std)
    assert out.scale.observable
    s = out.info["scale_rel_std_calibration_sampled"]
    assert 0.7 < s / m.info["scale_rel_std_calibration"] < 1.4
    assert out.scale.rel_std >= m.scale.rel_std
    # a motion that is not metric is returned as it is
    not_metric = replace(m, scale=replace(m.scale, observable=False))
    assert with_sampled_calibration(not_metric, rays, rig.extrinsic_std) is not_metric
    with pytest.raises(ValueError, match="weights"):
        with_sampled_calibration(m, rays, rig.extrinsic_std, weights=np.ones(3))


def test_with_sampled_calibration_failed_refit_is_not_metric(monkeypatch):
    rig, rays, m = _turning_motion(7)
    assert m.scale.observable

    def fail(*args, **kwargs):
        raise mcgeom.errors.DegenerateError("nothing constrains the motion")
    monkeypatch.setattr(_core, "refine_motion", fail)
    out = with_sampled_calibration(m, rays, rig.extrinsic_std)
    assert not out.scale.observable
    assert "not confirmed" in out.scale.reason and "nothing constrains" in out.scale.reason
