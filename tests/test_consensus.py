"""_core.consensus_check (csrc/consensus.c) against an independent reference:
the same rules written here in numpy on the public kernels (leverage_stats,
refine_motion), as mcgeom.robust._verdict ran them in Python before session
38, on the final refinements of robust estimates with 0-50 % random time-2
bearings (their weights captured from the robust search, with the checks
the robust call ran itself), and on fits built to take each branch; its
refusals of bad input."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import mcgeom
import mcgeom.robust._c_search as c_search
from mcgeom import _core
from mcgeom.errors import DegenerateError
from mcgeom.synth_kinds import KIND_SETUPS, outlier_problem


def _reference(rays, weights, R, t, rel_std, cal, max_rel):
    """(reason, rel_std, dropped) of the checks, in numpy."""
    a = (rays.origins1, rays.dirs1, rays.origins2, rays.dirs2)
    st = _core.leverage_stats(*a, R, t, weights=weights)
    if st is None:
        return "metric", rel_std, []
    reason = "metric"
    if not st["max_leverage"] > 0.9 and st["max_influence_stds"] > 4.0 and \
            st["max_influence"] > max_rel:
        reason = "one_pair"
    hc = st["travel_std_hc"] / st["travel"] if st["travel"] > 0 else None
    rel, dropped = rel_std, []
    if st["max_leverage"] > 0.5 and (reason == "metric" or st["max_leverage"] > 0.9):
        lev = np.empty(len(rays))
        _core.leverage_stats(*a, R, t, weights=weights, leverages=lev)
        used = np.flatnonzero(weights > 0)
        o1, d1, o2, d2 = (x[used] for x in a)
        c = 0.5 * (o1.sum(0) + o2.sum(0)) / len(used)
        o1, o2 = o1 - c, o2 - c
        w, lev = weights[used].copy(), lev[used]
        Rk, tc = R, t + R @ c - c
        before = np.linalg.norm(tc)
        refit_rel, strong, ok = math.nan, False, True
        for _ in range(3):
            k = int(np.argmax(lev))
            if not lev[k] > 0.5:
                break
            strong = strong or lev[k] > 0.9
            dropped.append(int(used[k]))
            w[k] = 0.0
            try:
                fit = _core.refine_motion(o1, d1, o2, d2, Rk, tc, weights=w,
                                          cost_tolerance=1e-3 / len(used))
            except (ValueError, DegenerateError):
                ok = False
                break
            Rk, tc, refit_rel = fit["R"], fit["t"], fit["scale_rel_std"]
            s2 = _core.leverage_stats(o1, d1, o2, d2, Rk, tc, weights=w, leverages=lev)
            if s2 is None:
                ok = False
                break
        if dropped:
            if strong and (not ok or s2["max_leverage"] > 0.9):
                return "undetermined", rel_std, dropped
            if ok:
                move = abs(np.linalg.norm(tc) / before - 1.0)
                if strong and not refit_rel <= max_rel:
                    return "lever_std", rel_std, dropped
                if move > 3.0 * rel_std:
                    if move > max_rel:
                        return "lever_move", rel_std, dropped
                    rel = math.hypot(rel, move)
                rel = max(rel, refit_rel)
                if not rel <= max_rel:
                    return "widened_std", rel, dropped
    if reason == "metric" and hc is not None:
        hc_total = math.hypot(hc, cal)
        if hc_total > 1.25 * rel:
            rel = hc_total
            if not hc_total <= max_rel:
                reason = "residuals_std"
    return reason, rel, dropped


def _captured_fits(monkeypatch, fractions=(0.0, 0.1, 0.3, 0.5), problems=6):
    """(rays, weights, R, t, rel_std, the call's own checks) of the final
    refinements of robust estimates whose scale the C verdict called
    observable (the robust call then ran the checks itself)."""
    seen = []
    orig = c_search._checked

    def capture(m, res, rays, weights, options, method):
        if res.have_consensus:
            rel = math.hypot(res.scale.rel_std_noise, res.scale.rel_std_calibration)
            seen.append((rays, weights.copy(), np.array(list(res.R)).reshape(3, 3),
                         np.array(list(res.t)), rel, _core.consensus_dict(res.consensus)))
        return orig(m, res, rays, weights, options, method)

    monkeypatch.setattr(c_search, "_checked", capture)
    for kind in KIND_SETUPS:
        for frac in fractions:
            for n in (60, 200):
                for s in range(problems):
                    p, rays, _ = outlier_problem(kind, s, n, 1e-3, frac)
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        mcgeom.robust.ransac(rays, "five_plus_one", threshold=3e-3, seed=s)
    return seen


def test_against_the_numpy_reference(monkeypatch):
    """The robust call's own checks, and mcg_consensus_check called alone at
    two limits, against the reference."""
    fits = _captured_fits(monkeypatch)
    assert len(fits) > 150
    reasons = set()
    for rays, w, R, t, rel, in_call in fits:
        want = _reference(rays, w, R, t, rel, 0.0, 0.1)
        assert (in_call["reason"], in_call["dropped"]) == (want[0], want[2])
        assert in_call["rel_std"] == pytest.approx(want[1], rel=1e-6)
        for max_rel in (0.1, 0.01):
            got = _core.consensus_check(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2,
                                        w, R, t, rel, 0.0, max_rel)
            want = _reference(rays, w, R, t, rel, 0.0, max_rel)
            assert (got["reason"], got["dropped"]) == (want[0], want[2])
            assert got["rel_std"] == pytest.approx(want[1], rel=1e-6)
            reasons.add(got["reason"])
    # (the captured fits take the common branches; the rest are built below)
    assert {"metric", "one_pair", "lever_std", "lever_move", "widened_std",
            "residuals_std"} <= reasons


def test_each_branch():
    """Fits built to take the branches: a clean fit (metric, no pair dropped);
    a gross outlier among the pairs that fix the scale (a pair with leverage
    above 0.9, the refit without it); a calibration part that makes the std
    too large only through the residuals' std."""
    p, rays, _ = outlier_problem("axial", 3, 60, 1e-3, 0.0)
    a = (rays.origins1, rays.dirs1, rays.origins2, rays.dirs2)
    w = np.ones(len(rays))
    fit = _core.refine_motion(*a, p.R, p.t)
    rel = fit["scale_rel_std"]
    c = _core.consensus_check(*a, w, fit["R"], fit["t"], rel, 0.0, 0.1)
    assert c["reason"] == "metric" and c["dropped"] == [] and c["stats"] is not None
    assert c["rel_std"] >= rel and c["lever_move"] is None
    # the residuals' std with a calibration part beyond max_rel_std
    c2 = _core.consensus_check(*a, w, fit["R"], fit["t"], rel, 0.5, 0.1)
    assert c2["reason"] == "residuals_std" and c2["rel_std"] > 0.5
    # a gross outlier: one cross-camera bearing turned away, refitted
    cross = np.flatnonzero(rays.cam1 != rays.cam2)
    d2 = rays.dirs2.copy()
    d2[cross[0]] = d2[cross[0]] + np.array([0.3, -0.2, 0.1])
    a2 = (rays.origins1, rays.dirs1, rays.origins2, d2)
    fit2 = _core.refine_motion(*a2, p.R, p.t)
    rays2 = mcgeom.RayPairs(*a2, rays.cam1, rays.cam2)
    got = _core.consensus_check(*a2, w, fit2["R"], fit2["t"], fit2["scale_rel_std"], 0.0, 0.1)
    want = _reference(rays2, w, fit2["R"], fit2["t"], fit2["scale_rel_std"], 0.0, 0.1)
    assert got["reason"] == want[0] and got["dropped"] == want[2]
    assert got["reason"] != "metric"


def test_bad_input():
    p, rays, _ = outlier_problem("axial", 3, 30, 1e-3, 0.0)
    a = (rays.origins1, rays.dirs1, rays.origins2, rays.dirs2)
    w = np.ones(len(rays))
    for bad in ((-0.1, 0.0, 0.1), (math.nan, 0.0, 0.1), (0.01, -1.0, 0.1), (0.01, 0.0, 0.0),
                (0.01, 0.0, math.inf)):
        with pytest.raises(ValueError, match="mcg_consensus_check"):
            _core.consensus_check(*a, w, p.R, p.t, *bad)
    w[3] = -1.0
    with pytest.raises(ValueError, match="mcg_consensus_check"):
        _core.consensus_check(*a, w, p.R, p.t, 0.01, 0.0, 0.1)
    # a singular fit (every pair from one centre: |t| free): nothing decided
    o = np.zeros_like(rays.origins1)
    c = _core.consensus_check(o, rays.dirs1, o, rays.dirs2, np.ones(len(rays)), p.R, p.t,
                              0.01, 0.0, 0.1)
    assert c["reason"] == "metric" and c["stats"] is None and c["rel_std"] == 0.01
