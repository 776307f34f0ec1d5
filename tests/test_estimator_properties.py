"""The shared property suite: every registered estimator, every generalized
camera kind it declares (docs/architecture.md §6). A third-party plugin registered
through the ``mcgeom.estimators`` entry points is picked up automatically."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings, strategies as st

import mcgeom
from mcgeom import registry
from problems import KIND_SETUPS, make, rigid, rot_err
from mcgeom import synth

CASES = [(e.name, kind) for e in registry.list_estimators()
         if e.family != "refinement"
         for kind in e.camera_kinds if kind in KIND_SETUPS]
SETTINGS = settings(max_examples=15, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow])
seeds = st.integers(min_value=0, max_value=2**31 - 1)


def _n(name):
    return max(60, 3 * registry.get(name).min_sample)


#: the vertical of the test problems in rig frame 1 (any direction serves)
G1 = np.array([0.3, -0.9, 0.2]) / np.linalg.norm([0.3, -0.9, 0.2])


def _given(name, R, g1=G1):
    """Options of an estimator that needs the rotation: the true one, expressed
    as the test's transformed data require (conjugated, inverted); of one that
    takes the vertical (``gravity1``/``gravity2``, e.g. an IMU's): ``g1`` in rig
    frame 1 (re-expressed likewise) and ``R g1`` in rig frame 2. The rotation
    is exact, and said so where the estimator takes its error (``rotation_std``)."""
    info = registry.get(name)
    out = {"rotation": R} if info.needs_rotation else {}
    if "rotation_std" in info.options:
        out["rotation_std"] = 0.0
    if "gravity1" in info.options:
        out.update(gravity1=g1, gravity2=R @ g1)
    return out


def test_every_estimator_is_covered():
    assert {name for name, _ in CASES} >= {"linear17", "known_rotation_translation"}


@pytest.mark.parametrize("name,kind", CASES)
@SETTINGS
@given(seed=seeds)
def test_exact_recovery_noise_free(name, kind, seed):
    p = make(kind, seed, n=_n(name))
    m = mcgeom.estimate(p.rays, name, **_given(name, p.R))
    assert rot_err(m.R, p.R) < 1e-8
    assert np.linalg.norm(m.t - p.t) < 1e-8 * np.linalg.norm(p.t)
    assert m.scale.observable


def _equally_optimal(name, rays_a, a, b, R_b_in_a):
    """A set-valued global optimum (registry ``objective``): both results are
    optimal within their certified gaps, evaluated in one frame; the
    rotations need only agree to the width of the near-optimal set."""
    f = registry.get(name).objective
    # over the correspondences each result used (bnb_lp's outlier guard may
    # drop a few: its linf is the objective on its inliers)
    used_a = rays_a if a.inliers is None else rays_a.take(np.flatnonzero(a.inliers))
    used_b = rays_a if b.inliers is None else rays_a.take(np.flatnonzero(b.inliers))
    fa, fb = f(used_a, a.R), f(used_b, R_b_in_a)
    assert abs(fa - a.info["linf"]) < 1e-8 and abs(fb - b.info["linf"]) < 1e-8
    slack = a.info["gap"] + b.info["gap"] + 1e-8
    assert fb >= a.info["lower_bound"] - 1e-8 and fa >= b.info["lower_bound"] - 1e-8
    assert abs(fa - fb) <= slack
    assert rot_err(a.R, R_b_in_a) < 1e-2


@pytest.mark.parametrize("name,kind", CASES)
@SETTINGS
@given(seed=seeds)
def test_invariant_to_rig_frame(name, kind, seed):
    """Re-expressing the rig frame by F = (Rf, tf) conjugates the motion."""
    p = make(kind, seed, n=_n(name), angular_noise=3e-4)
    Rf, tf = rigid(np.random.default_rng(seed + 1))
    m = mcgeom.estimate(p.rays, name, **_given(name, p.R))
    mf = mcgeom.estimate(p.rays.in_frame(Rf, tf), name,
                         **_given(name, Rf @ p.R @ Rf.T, Rf @ G1))
    F = np.eye(4)
    F[:3, :3], F[:3, 3] = Rf, tf
    expect = F @ m.T @ np.linalg.inv(F)
    if registry.get(name).objective is not None:
        _equally_optimal(name, p.rays, m, mf, Rf.T @ mf.R @ Rf)
        assert mf.scale.observable == m.scale.observable
        return
    assert rot_err(mf.R, expect[:3, :3]) < 1e-7
    assert mf.scale.observable == m.scale.observable
    if m.scale.observable:  # a unit direction of unknown scale does not conjugate
        assert np.linalg.norm(mf.t - expect[:3, 3]) < 1e-6 * (1 + np.linalg.norm(expect[:3, 3]))


@pytest.mark.parametrize("name,kind", CASES)
@SETTINGS
@given(seed=seeds)
def test_invariant_to_permutation(name, kind, seed):
    p = make(kind, seed, n=_n(name), angular_noise=3e-4)
    perm = np.random.default_rng(seed).permutation(len(p.rays))
    a = mcgeom.estimate(p.rays, name, **_given(name, p.R))
    b = mcgeom.estimate(p.rays.take(perm), name, **_given(name, p.R))
    assert rot_err(a.R, b.R) < 1e-9
    # Refinements solve normal equations: where |t| lies in a flat valley (a
    # scale with a relative std of several %), the summation order moves it
    # by ~cond * eps (3e-8 of |t| at rel_std 0.07, five_plus_one, stereo
    # intra-camera rays). A change below 1e-5 of the estimate's own std is
    # still invariance.
    rel_std = a.scale.rel_std if np.isfinite(a.scale.rel_std) else 0.0
    tol = 1e-8 * (1 + np.linalg.norm(a.t)) + 1e-5 * rel_std * np.linalg.norm(a.t)
    assert np.linalg.norm(a.t - b.t) < tol


@pytest.mark.parametrize("name,kind", CASES)
@SETTINGS
@given(seed=seeds)
def test_swapping_frames_inverts_motion(name, kind, seed):
    p = make(kind, seed, n=_n(name))
    a = mcgeom.estimate(p.rays, name, **_given(name, p.R))
    b = mcgeom.estimate(p.rays.swapped(), name, **_given(name, p.R.T, p.R @ G1))
    inv = a.inverse()
    assert rot_err(b.R, inv.R) < 1e-8
    assert np.linalg.norm(b.t - inv.t) < 1e-8 * (1 + np.linalg.norm(inv.t))


@pytest.mark.parametrize("name,kind", CASES)
@SETTINGS
@given(seed=seeds, log_s=st.floats(min_value=-3, max_value=3))
def test_scaling_world_scales_t(name, kind, seed, log_s):
    s = 10.0 ** log_s
    p = make(kind, seed, n=_n(name), angular_noise=3e-4)
    r = p.rays
    scaled = mcgeom.RayPairs(s * r.origins1, r.dirs1, s * r.origins2, r.dirs2, r.cam1, r.cam2)
    a = mcgeom.estimate(r, name, **_given(name, p.R))
    b = mcgeom.estimate(scaled, name, **_given(name, p.R))
    if registry.get(name).objective is not None:
        _equally_optimal(name, r, a, b, b.R)
        assert a.scale.observable == b.scale.observable
        return
    assert rot_err(a.R, b.R) < 1e-8
    assert a.scale.observable == b.scale.observable
    # a metric t (observable, or the ML estimate where the scale is determined
    # but loose: issue 18) scales with the world; a unit direction does not
    metric = [m.scale.observable or (isinstance(m.info, dict) and
                                     bool(m.info.get("scale_determined", False)))
              for m in (a, b)]
    assert metric[0] == metric[1]
    if metric[0]:
        assert np.linalg.norm(b.t - s * a.t) < 1e-7 * s * (1 + np.linalg.norm(a.t))
    else:
        assert np.linalg.norm(b.t - a.t) < 1e-7


SCALE_CASES = [(e.name, kind) for e in registry.list_estimators()
               if e.recovers_scale and e.family != "refinement"
               for kind in ("locally-central", "locally-central-and-axial")
               if kind in e.camera_kinds]


@pytest.mark.parametrize("name,kind", SCALE_CASES)
@SETTINGS
@given(seed=seeds)
# six_point, 2-camera head: a spurious minimal solution with a tiny t explained
# every ray and the refinement stalled there (CI, 2026-12-02)
@example(seed=233693993)
def test_critical_motion_reported(name, kind, seed):
    """No rotation and only intra-camera rays: |t| is not observable (ch. 7.3.2);
    the rotation and the direction of t must still be right."""
    rng = np.random.default_rng(seed)
    t = rng.normal(size=3)
    t *= 0.5 / np.linalg.norm(t)
    p = make(kind, seed, n=_n(name), R=np.eye(3), t=t)
    m = mcgeom.estimate(p.rays, name, **_given(name, np.eye(3)))
    assert not m.scale.observable
    assert "critical" in m.scale.reason or "scale" in m.scale.reason
    assert rot_err(m.R, np.eye(3)) < 1e-8
    assert abs(np.linalg.norm(m.t) - 1.0) < 1e-9
    assert np.dot(m.t, t / np.linalg.norm(t)) > 1 - 1e-8


@pytest.mark.parametrize("name", [e.name for e in registry.list_estimators()
                                  if "most-general" in e.camera_kinds and e.recovers_scale])
@SETTINGS
@given(seed=seeds)
def test_cross_camera_rays_fix_scale_without_rotation(name, seed):
    rng = np.random.default_rng(seed)
    t = rng.normal(size=3)
    t *= 0.5 / np.linalg.norm(t)
    p = make("most-general", seed, n=_n(name), R=np.eye(3), t=t)
    m = mcgeom.estimate(p.rays, name, **_given(name, np.eye(3)))
    assert m.scale.observable
    assert np.linalg.norm(m.t - t) < 1e-8


@pytest.mark.parametrize("name", [e.name for e in registry.list_estimators()])
@pytest.mark.parametrize("cross", [0.0, 0.5])
@pytest.mark.parametrize("noise", [0.0, 3e-4])
@settings(max_examples=5, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=seeds)
@example(seed=23129)  # Wahba's rotation of the 30 intra pairs 3.35e-4 rad off (cross 0.5)
def test_static_rig_reports_no_translation(name, cross, noise, seed):
    """A rig that did not move (R = I, t = 0), noise-free or with angular noise
    (radians), with and without cross-camera rays: every estimator returns the
    rotation within the noise, t = 0 and the verdict "no translation detected"
    (issue 18; as the robust pipeline does). Never a DegenerateError, never a
    metric |t|."""
    rng = np.random.default_rng(seed)
    p = synth.make_problem(synth.generic_rig(4, rng), np.eye(3), np.zeros(3), _n(name), rng,
                           cross_fraction=cross, angular_noise=noise, require_visible=False)
    m = mcgeom.estimate(p.rays, name, **_given(name, np.eye(3)))
    # The static answer's rotation is fitted to the n intra-camera pairs. With
    # angular noise sigma on each bearing, each pair fixes two of the three
    # axes to ~sigma sqrt(2): per axis the error is ~sigma sqrt(3 / n). Bound
    # at 6 per-axis standard deviations (the chi tail beyond is ~1e-7; the
    # old bound, sigma, was 3.5 of them at n = 30 and failed on an unlucky
    # draw under the explore profile: seed 23129, Wahba's own rotation of the
    # 30 pairs 3.35e-4 rad off). A rotation from a minimal sample, or from
    # fewer pairs, is several times worse and still fails.
    n_intra = int(np.count_nonzero(p.rays.cam1 == p.rays.cam2))
    assert rot_err(m.R, np.eye(3)) < 1e-8 + 6 * noise * np.sqrt(3 / n_intra)
    assert np.array_equal(m.t, np.zeros(3))
    assert not m.scale.observable
    assert m.scale.reason.startswith("no translation detected")
    assert m.info["translation_detected"] is False
