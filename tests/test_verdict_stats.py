"""The verdict's evidence in C (csrc/verdict.c, ``_core.verdict_stats``) against the
numpy functions of mcgeom.observability / mcgeom.geometry, and the verdict of the
C robust path (``scale_verdict_stats``) against the numpy verdict (issue 19)."""

from __future__ import annotations

import re

import numpy as np
import pytest

from mcgeom import _core, robust, synth
from mcgeom.estimators._common import travel_direction
from mcgeom.geometry import count_in_front, rotation_fit, same_camera
from mcgeom.observability import (NO_PARALLAX_FACTOR, ZERO_FACTOR, _centres_with_intra,
                                  rig_critical_angle, scale_profile, scale_verdict,
                                  scale_verdict_stats)
from mcgeom.pixel_noise import camera_table, pixels_per_radian
from problems import turning_motion


def _problem(seed, n=200, outliers=0.3, cross=0.2, rig=None, motion=None):
    rng = np.random.default_rng(seed)
    rig = synth.ladybug2() if rig is None else rig
    R, t = turning_motion(rng) if motion is None else motion(rng)
    p = synth.make_problem(rig, R, t, n, rng, pixel_noise=0.5, outlier_fraction=outliers,
                           cross_fraction=cross)
    return rig, p, R, t, rng


def _stats(rays, inl, R, t, still, m=None):
    m = int(max(rays.cam1.max(), rays.cam2.max())) + 1 if m is None else m
    return _core.verdict_stats(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, rays.cam1,
                               rays.cam2, m, inl, R, t, still)


#: the critical angle's digits in a verdict's reason
_CRIT_DIGITS = re.compile(r"critical angle \S+ deg")


def _forward(rng):
    return np.eye(3), np.array([rng.uniform(0.5, 2.0), 0.0, 0.0])


def _yawing(rng):
    # driving forward 0.5-2 m while turning by 1-3 deg (rig2_from_rig1)
    Rw = synth.rotation_about([0, 0, 1], np.radians(rng.uniform(1.0, 3.0) * rng.choice([-1, 1])))
    return Rw.T, -Rw.T @ np.array([rng.uniform(0.5, 2.0), 0.0, 0.0])


@pytest.mark.parametrize("seed, cross, motion", [(0, 0.2, None), (1, 0.0, None),
                                                 (2, 0.5, None), (3, 0.0, _forward)])
def test_evidence_matches_numpy(seed, cross, motion):
    rig, p, R, t, rng = _problem(seed, cross=cross, motion=motion)
    rays = p.rays
    # a perturbed motion (the estimate's) and a random inlier mask
    Re = synth.random_rotation(rng, 1e-3) @ R
    te = t + rng.normal(scale=0.01, size=3)
    inl = rng.random(len(rays)) < 0.8
    noise = 2e-3
    s = _stats(rays, inl, Re, te, NO_PARALLAX_FACTOR * noise)
    same = same_camera(rays)
    assert s["n_inliers"] == inl.sum()
    assert s["n_intra"] == (inl & same).sum() and s["n_cross"] == (inl & ~same).sum()
    Rf, ang = rotation_fit(rays, inl & same)
    assert s["fit_ok"] and np.abs(s["R_fit"] - Rf).max() < 1e-12
    assert s["n_still"] == np.count_nonzero(ang < NO_PARALLAX_FACTOR * noise)
    centres, n_cross = _centres_with_intra(rays, inl, same)
    assert s["n_cameras_intra"] == len(centres) and s["n_cross"] == n_cross
    assert s["critical_angle"] == pytest.approx(rig_critical_angle(Re, te, centres),
                                                abs=1e-12)
    assert s["n_in_front"] == count_in_front(rays, Re, te, inl)
    assert np.abs(s["t_direction"] - travel_direction(rays, inl, Re, te)).max() < 1e-12


def test_pure_rotation_is_still_and_degenerate_inputs():
    rig, p, R, t, rng = _problem(4, outliers=0.0, cross=0.0)
    rays = p.rays
    # time-2 bearings of a pure rotation: every angle at the rounding level
    d2 = rays.dirs1 @ R.T
    from mcgeom.types import RayPairs
    still = RayPairs(rays.origins1, rays.dirs1, rays.origins2, d2, rays.cam1, rays.cam2)
    s = _stats(still, np.ones(len(rays), bool), R, np.zeros(3), 1e-9)
    assert s["fit_ok"] and np.abs(s["R_fit"] - R).max() < 1e-12
    assert s["n_still"] == s["n_intra"] == len(rays)
    # no inliers: nothing counted, identity fit, t's own direction
    s = _stats(rays, np.zeros(len(rays), bool), R, t, 1e-3)
    assert (s["n_inliers"], s["n_intra"], s["n_still"], s["n_in_front"]) == (0, 0, 0, 0)
    assert not s["fit_ok"] and np.array_equal(s["R_fit"], np.eye(3))
    assert s["critical_angle"] == 0.0


def test_bad_arguments_are_named():
    rig, p, R, t, rng = _problem(5, n=40)
    r, inl = p.rays, np.ones(40, bool)
    with pytest.raises(ValueError, match="inliers"):
        _stats(r, np.ones(39, bool), R, t, 1e-3)
    with pytest.raises(ValueError, match="still_angle"):
        _stats(r, inl, R, t, -1.0)
    with pytest.raises(ValueError, match=r"cam1 holds camera ids outside \[0, 2\)"):
        _stats(r, inl, R, t, 1e-3, m=2)
    d = r.dirs1.copy()
    d[3] = np.nan
    with pytest.raises(ValueError, match="dirs1"):
        _core.verdict_stats(r.origins1, d, r.origins2, r.dirs2, r.cam1, r.cam2, 6, inl, R, t,
                            1e-3)
    with pytest.raises(ValueError, match="t"):
        _stats(r, inl, R, [0, np.inf, 0], 1e-3)


@pytest.mark.parametrize("seed, motion", [(6, None), (7, _forward), (8, None)])
def test_verdict_from_c_evidence_equals_numpy_verdict(seed, motion):
    rig, p, R, t, rng = _problem(seed, n=300, cross=0.0 if motion else 0.2, motion=motion)
    f = pixels_per_radian(rig, p.rays)
    m = robust.ransac(p.rays, threshold=1.0, focal=f, seed=seed)
    rays, inl = p.rays, m.inliers
    Rm, tm = m.R, m.info["t_metric"]
    rel = m.scale.rel_std
    noise = 1.0 / float(np.median(f))
    prof = m.info.get("scale_profile", float("nan"))
    a = scale_verdict(rays, inl, Rm, tm, rel, 0.1, noise_level=noise, profile=prof)
    b, direction = scale_verdict_stats(rays, rays.cam1, rays.cam2, 6, inl, Rm, tm, rel, 0.1,
                                       noise_level=noise, profile=prof)
    ra, rb = a.reason, b.reason
    tol = 1e-12
    if max(a.critical_angle, b.critical_angle) < 1e-9:
        # a critical angle at rounding level: the forward drive's free fit
        # slid to R = I within ~1e-11 rad (seed 7), where the angle comes from
        # displacement differences R c + t - c of ~1e-12 m and C and numpy,
        # summing in another order, agree only to ~1e-11 rad; its printed
        # digits are then noise, the decision is not
        tol = 1e-10
        ra, rb = (_CRIT_DIGITS.sub("critical angle ~0 deg", r) for r in (ra, rb))
    assert (a.observable, ra) == (b.observable, rb)
    assert a.critical_angle == pytest.approx(b.critical_angle, abs=tol)
    assert np.abs(direction - travel_direction(rays, inl, Rm, tm)).max() < 1e-12
    if m.info.get("t_slid"):
        # the pipeline judged the refined motion, which crossed |t| = 0 (the
        # forward drive's flat valley, seed 7); t_metric is the hypothesis'
        # length along the travel instead: the same decision, another motion
        assert not m.scale.observable and not b.observable
    else:
        assert (m.scale.observable, m.scale.reason) == (b.observable, b.reason)


def test_static_rig_gets_the_numpy_static_verdict():
    rig, p, R, t, rng = _problem(9, outliers=0.0)
    rays = p.rays
    from mcgeom.types import RayPairs
    d2 = rays.dirs1 @ R.T + rng.normal(scale=1e-4, size=rays.dirs1.shape)
    still = RayPairs(rays.origins1, rays.dirs1, rays.origins2, d2, rays.cam1, rays.cam2)
    inl = np.ones(len(rays), bool)
    a = scale_verdict(still, inl, R, t, 0.05, noise_level=1e-3)
    b, _ = scale_verdict_stats(still, rays.cam1, rays.cam2, 6, inl, R, t, 0.05,
                               noise_level=1e-3)
    assert a.reason.startswith("no translation detected") and (a.reason, a.observable) == \
        (b.reason, b.observable)


def test_robust_c_zero_profile_and_inlier_rms():
    """The C result's zero-factor profile is an upper bound of
    observability.scale_profile at ZERO_FACTOR (so the C constant is the
    Python one) on the same side of 9 (the only use of it:
    observability.scale_determined), and its RMS the inliers' residuals
    recomputed in numpy."""
    seen = 0
    # the exactly critical straight drive (|t| mostly undetermined) and a
    # slight turn (yaw 1-3 deg: scale_rel_std ~0.1-0.25, where the zero
    # profile is computed)
    for seed, motion in [(s, _forward) for s in range(4)] + [(s, _yawing) for s in range(4)]:
        rig, p, R, t, rng = _problem(20 + seed, n=320, outliers=0.0, cross=0.0,
                                     rig=synth.vehicle8(), motion=motion)
        rays = p.rays
        f = pixels_per_radian(rig, rays)
        axes_f, axes = camera_table(rig)
        out = _core.robust_rig_motion(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2,
                                      rays.cam1, rays.cam2, 8, focal=f, cam_axes=axes,
                                      cam_focal=axes_f, threshold=1.0, seed=seed,
                                      max_scale_rel_std=0.1)
        r = np.abs(_core.gec_residuals(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2,
                                       out["R"], out["t"])) * f
        inl = out["inliers"]
        assert out["inlier_rms"] == pytest.approx(np.sqrt(np.mean(r[inl] ** 2)), rel=1e-9)
        ref = out["refinement"]
        srs = ref["scale_rel_std"]
        wanted = srs <= 1.0 and (srs > 0.1 or not out["scale_profile"] >= 9.0)
        assert np.isfinite(out["zero_profile"]) == wanted
        if wanted:
            seen += 1
            used = out["used"]
            py = scale_profile(rays.take(used), out["R"], out["t"], ref["final_cost"],
                               ref["sigma2"], (ZERO_FACTOR,), "cauchy", out["loss_scale"],
                               out["weights"][used])
            # an upper bound on the same side of 9, the bound of
            # scale_determined (the C fit stops once under it, or once
            # evidently above it: mcg_refine_motion_until)
            assert out["zero_profile"] >= py * (1 - 1e-3) - 1e-6
            assert (out["zero_profile"] < 9.0) == (py < 9.0)
    assert seen > 0, "no problem reached the zero profile's branch"


@pytest.mark.parametrize("x", [1e-160, 1.0])
def test_travel_direction_of_a_tiny_t_is_unit(x):
    # fuzz finding 23: where the centroid's travel t + R c - c is exactly 0
    # the direction is t's own, and t / |t| of a t ~ 1e-161 (|t|^2
    # subnormal) was 1e-5 off unit length, in C and numpy alike. One inlier
    # at c = (x, 0, 0), t = -(R c - c): exact in both.
    rig, p, R, _, _ = _problem(5, outliers=0.0)
    rays = p.rays
    R = synth.rotation_about([0, 0, 1], 0.5)
    o1, o2 = rays.origins1.copy(), rays.origins2.copy()
    o1[0] = o2[0] = (x, 0.0, 0.0)
    rays = type(rays)(o1, rays.dirs1, o2, rays.dirs2, rays.cam1, rays.cam2)
    inl = np.zeros(len(rays), bool)
    inl[0] = True
    c = np.array([x, 0.0, 0.0])
    t = -(R[:, 0] * x - c)
    s = _stats(rays, inl.astype(np.uint8), R, t, 1e-3)
    py = travel_direction(rays, inl, R, t)
    for u in (s["t_direction"], py):
        assert abs(np.linalg.norm(u) - 1.0) < 1e-12
    assert np.abs(s["t_direction"] - py).max() < 1e-12
