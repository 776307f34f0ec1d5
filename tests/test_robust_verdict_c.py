"""The scale verdict in C (csrc/robust_verdict.c, issue 19) is the Python one.

The robust search now decides the verdict itself (``res.scale``) and the façade
only words it (:func:`mcgeom.robust._verdict.conclude_c`); the Python verdict
(:func:`mcgeom.robust._verdict.conclude`) still decides the static and undecided
cases, and every search outside C. Checked here:

* the same RigMotion from both, bit for bit in R, t, inliers and the verdict, on
  problems of every verdict: observable, too uncertain, critical, one camera,
  unconfirmed (a sample cap), static (the Python fallback), with and without a
  calibration error -- through the pixel entry point and the general path;
* the pixel entry point (``mcg_robust_rig_motion_pinhole``) against the two
  calls it replaces (``pinhole_ray_pairs`` and the search on the rays), and
  the split of both calls' C time into stages (``info["c_stage_seconds"]``);
* ``observability._verdict`` (whose rule is now ``mcg_scale_reason``) against
  the rule written out here, on random evidence;
* the constants the C verdict copies from Python;
* a bad calibration table is a ValueError naming it.
"""

from __future__ import annotations

import math
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from mcgeom import _core, cv, synth
from mcgeom.experiments.bench.robust import CASES
from mcgeom.observability import (NO_PARALLAX_FRACTION, NO_PARALLAX_MIN, _MOTION_DOF,
                                  _verdict)
from mcgeom.pixel_noise import camera_table, pinhole_ray_pairs, sampson_pixel_scale
from mcgeom.rig import Rig
from mcgeom.robust import _c_search, ransac_options, ransac_prechecked
from mcgeom.robust._verdict import CONFIRMED

SOURCE = Path(__file__).resolve().parents[1] / "csrc" / "robust_verdict.c"



def _motions(a, b, ctx: str) -> None:
    assert np.array_equal(a.R, b.R), ctx
    assert np.array_equal(a.t, b.t), ctx
    assert np.array_equal(a.inliers, b.inliers), ctx
    assert a.method == b.method and a.residual_rms == b.residual_rms, ctx
    sa, sb = a.scale, b.scale
    assert (sa.observable, sa.reason, sa.critical_angle) == \
        (sb.observable, sb.reason, sb.critical_angle), ctx
    assert sa.rel_std == sb.rel_std, ctx
    keys = set(a.info) - {"time_s", "c_seconds", "c_stage_seconds"}
    assert keys == set(b.info) - {"time_s", "c_seconds", "c_stage_seconds"}, ctx
    for k in keys:
        x, y = a.info[k], b.info[k]
        if isinstance(x, np.ndarray):
            assert np.array_equal(x, y, equal_nan=True), (ctx, k)
        elif isinstance(x, float) and math.isnan(x):
            assert math.isnan(y), (ctx, k)
        else:
            assert x == y, (ctx, k)


def _both(monkeypatch, call):
    """(the C-worded RigMotion, the Python-decided one) of ``call``."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fast = call()
        monkeypatch.setattr(_c_search, "C_WORDED", frozenset())
        slow = call()
        monkeypatch.undo()
    return fast, slow


def test_c_verdict_is_the_python_one(monkeypatch):
    reasons = set()
    for case, calibrated in [(c, k) for c in CASES for k in (False, True)]:
        make_rig, n, outl, noise, motion = CASES[case]
        rig = make_rig()
        if calibrated:        # the default extrinsic error of every camera
            rig = Rig(rig.cameras, None)
        rng = np.random.default_rng(11)
        for i in range(12):
            R, t = motion(rng)
            if i == 0:   # a static rig (the Python fallback; R = I: a rig turning
                R, t = np.eye(3), 0.0 * t   # about its origin moves its cameras)
            p = synth.make_problem(rig, R, t, n, rng, pixel_noise=noise,
                                   outlier_fraction=outl)
            cap = 2 if i == 1 else 1000         # a search its cap ends
            fast, slow = _both(monkeypatch, lambda: cv.estimate(
                p.pixels1, p.pixels2, p.cam1, p.cam2, rig, threshold=1.0, seed=i,
                maxIters=cap))
            _motions(fast, slow, f"{case} problem {i}")
            reasons.add(fast.scale.reason.split(":")[0].split(";")[0])
            if i % 4 == 2:   # the general path (a mask, a calibration override)
                keep = np.ones(len(p.pixels1), bool)
                keep[0] = False
                fast, slow = _both(monkeypatch, lambda: cv.estimate(
                    p.pixels1, p.pixels2, p.cam1, p.cam2, rig, threshold=1.0, seed=i,
                    mask=keep, calibration_std=(0.004, 0.002)))
                _motions(fast, slow, f"{case} problem {i}, general path")
    assert {"scale observable", "scale too uncertain for the noise (near-critical motion)",
            "no translation detected"} <= reasons, reasons


def test_c_verdict_one_camera_and_large_calibration(monkeypatch):
    """One camera (no scale), and a calibration error that alone makes the
    scale too uncertain (the zero profile that C then computes itself)."""
    seen = set()
    for i in range(8):
        rng = np.random.default_rng(40 + i)
        rig = Rig(synth.ladybug2().cameras, (0.02 * (1 + i % 4), 0.004))
        R, t = synth.random_motion(rng, max_angle=0.3, t_norm=0.6 + 0.3 * (i % 3))
        p = synth.make_problem(rig, R, t, 300, rng, pixel_noise=0.5, outlier_fraction=0.1,
                               cross_fraction=0.2 * (i % 2))
        fast, slow = _both(monkeypatch, lambda: cv.estimate(
            p.pixels1, p.pixels2, p.cam1, p.cam2, rig, threshold=1.0, seed=i))
        _motions(fast, slow, f"calibrated ladybug {i}")
        seen.add(fast.scale.reason.split(";")[0].split(":")[0])
        one = p.cam1 == 0
        fast, slow = _both(monkeypatch, lambda: cv.estimate(
            p.pixels1[one], p.pixels2[one], p.cam1[one], p.cam2[one], rig, threshold=1.0,
            seed=i))
        _motions(fast, slow, f"one camera {i}")
        seen.add(fast.scale.reason.split(";")[0])
    assert "one camera only and no cross-camera correspondence" in seen
    assert "scale too uncertain for the noise (near-critical motion)" in seen


@pytest.mark.parametrize("vertical", [False, True])
def test_pixel_entry_is_the_rays_search(vertical):
    """``estimate_pinhole_c`` (pixels in, one C call) gives what the rays of
    ``pinhole_ray_pairs`` through ``ransac_prechecked`` give, bit for bit --
    with the vertical known too (the upright sampler)."""
    make_rig, n, outl, noise, motion = CASES["ladybug6 300c 30%out"]
    rig = Rig(make_rig().cameras, None)
    rng = np.random.default_rng(5)
    for i in range(6):
        R, t = motion(rng)
        p = synth.make_problem(rig, R, t, n, rng, pixel_noise=noise, outlier_fraction=outl)
        opts = ransac_options(1.0, 0.999, 1000, i)
        g = {"gravity1": np.array([0.0, 0.0, 1.0]), "gravity2": R[:, 2]} if vertical else None
        a = _c_search.estimate_pinhole_c(rig.pinhole_tables, p.pixels1, p.pixels2, p.cam1,
                                         p.cam2, opts, rig.calibration_error, g)
        rays, ppr = pinhole_ray_pairs(rig, p.pixels1, p.pixels2, p.cam1, p.cam2)
        b = ransac_prechecked(rays, "upright_four_point" if vertical else "five_plus_one", opts,
                              ppr, sampson_pixel_scale(rig), rig.calibration_error,
                              camera_table(rig), g)
        assert a is not None and b is not None
        assert a.info["sampler"] == b.info["sampler"]
        _motions(a, b, f"problem {i}")
        # where the C time went: the stages sum to c_seconds; the rays' only
        # on the pixel entry point; the verdict's in both (the façade asks)
        for m, rays_in_c in ((a, True), (b, False)):
            stages = m.info["c_stage_seconds"]
            assert set(stages) == {"rays", "search", "final", "verdict"}
            assert (stages["rays"] > 0) == rays_in_c
            assert stages["search"] > 0 and stages["final"] > 0 and stages["verdict"] > 0
            assert sum(stages.values()) == pytest.approx(m.info["c_seconds"], rel=1e-12)


def _reference_verdict(n_in, n_cross, n_centres, crit, rel, max_rel, profile, front):
    """The rule of the verdict as it was written in Python (session 18 on)."""
    if n_in <= 6:
        return "no redundancy"
    if not math.isfinite(rel) or rel > max_rel or (math.isfinite(profile) and profile < 9.0):
        if n_cross == 0 and n_centres < 2:
            return "one camera only"
        if n_cross == 0 and crit < math.radians(0.05):
            return "critical motion"
        return "scale too uncertain"
    return "cheirality fails" if front / n_in < 0.5 else "scale observable"


@settings(max_examples=300, deadline=None)
@given(n_in=st.integers(0, 60), n_cross=st.integers(0, 3), n_centres=st.integers(0, 4),
       crit=st.sampled_from([0.0, math.radians(0.0499), math.radians(0.05), 0.1]),
       rel=st.sampled_from([0.0, 0.05, 0.1, 0.1000001, 2.0, math.inf, math.nan]),
       profile=st.sampled_from([math.nan, 0.0, 8.999, 9.0, 50.0]),
       front_frac=st.floats(0.0, 1.0))
def test_verdict_rule_is_the_written_one(n_in, n_cross, n_centres, crit, rel, profile,
                                         front_frac):
    front = int(round(front_frac * n_in))
    asked = []

    def in_front():
        asked.append(1)
        return front

    v = _verdict(n_in, n_cross, n_centres, crit, rel, 0.1, False, profile, in_front)
    want = _reference_verdict(n_in, n_cross, n_centres, crit, rel, 0.1, profile, front)
    assert v.reason.startswith(want), (v.reason, want)
    assert v.observable == (want == "scale observable")
    # cheirality is asked only when nothing else decides
    assert bool(asked) == (want in ("cheirality fails", "scale observable"))


def test_c_constants_are_the_python_ones():
    text = SOURCE.read_text()
    defines = dict(re.findall(r"#define (\w+) ([0-9.]+)", text))
    assert float(defines["NO_PARALLAX_FRACTION"]) == NO_PARALLAX_FRACTION
    assert int(defines["NO_PARALLAX_MIN"]) == NO_PARALLAX_MIN
    assert int(defines["MOTION_DOF"]) == _MOTION_DOF
    assert float(defines["CONFIRMED"]) == CONFIRMED


def test_bad_calibration_table_is_named():
    make_rig, n, outl, noise, motion = CASES["ring4 4x50 0.5px"]
    rig = make_rig()
    rng = np.random.default_rng(0)
    R, t = motion(rng)
    p = synth.make_problem(rig, R, t, n, rng, pixel_noise=noise)
    rays, ppr = pinhole_ray_pairs(rig, p.pixels1, p.pixels2, p.cam1, p.cam2)
    ext = np.full((len(rig), 2), 1e-3)
    ext[1, 0] = -1.0
    with pytest.raises(ValueError, match="extrinsic_std"):
        _core.robust_rig_motion(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, rays.cam1,
                                rays.cam2, len(rig), focal=ppr, threshold=1.0,
                                verdict_still_factor=1.5, extrinsic_std=ext)
    with pytest.raises(ValueError, match="extrinsic_std"):
        _core.robust_rig_motion(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, rays.cam1,
                                rays.cam2, len(rig), focal=ppr, threshold=1.0,
                                extrinsic_std=np.ones((len(rig) + 1, 2)))
