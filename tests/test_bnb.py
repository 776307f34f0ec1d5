"""Branch and bound over rotations with LP feasibility (csrc/bnb.c, estimator
``bnb_lp``, thesis ch. 10).

- the error f(R) of the kernel against an independent reference: the same
  wedges (eqs. 10.9-10.13), but the feasibility decided by scipy's HiGHS
  with a margin formulation and the per-camera test as a box LP;
- global optimality on 200 random noisy problems: the returned error is never
  above the error at the true rotation, nor above a dense sampling around the
  optimum followed by a local refinement (Nelder-Mead), and the certified
  lower bound is never above any value of f seen;
- the search gives the same answer with either LP backend, with and without
  the preemptive tests and with and without working sets;
- bad input.
"""

from __future__ import annotations

import numpy as np
import pytest

import mcgeom
from mcgeom import _core, metrics, registry, synth
from mcgeom.estimators.bnb_lp import apex_groups, linf_error

# f values agree to the precision of the LPs and of the bisection
F_TOL = 2e-8


def _problem(seed: int, n_per_cam=(8, 16), noise=(3e-4, 2e-3)):
    rng = np.random.default_rng(seed)
    m = int(rng.integers(2, 5))
    rig = synth.generic_rig(m, rng)
    R = synth.random_rotation(rng, 0.5)
    t = rng.normal(size=3)
    t *= rng.uniform(0.2, 1.0) / np.linalg.norm(t)
    n = int(rng.integers(*n_per_cam)) * m
    return synth.make_problem(rig, R, t, n, rng, angular_noise=float(rng.uniform(*noise)),
                              cross_fraction=0.2 if seed % 3 == 0 else 0.0,
                              require_visible=False)


# ------------------------------------------------------ independent reference

def _reference_feasible(rays, groups, R, eps) -> bool:
    linprog = pytest.importorskip("scipy.optimize").linprog
    rows, rhs, by_group = [], [], {}
    for i in range(len(rays)):
        w = _core.wedge_normals(R @ rays.dirs1[i], rays.dirs2[i], eps, eps)
        if w is None:
            continue
        apex = rays.origins2[i] - R @ rays.origins1[i]
        for n in w:
            rows.append(n)
            rhs.append(n @ apex)
            by_group.setdefault(int(groups[i]), []).append(n)
    # every group's cone holds a non-zero direction: max zbar . b over the box
    for normals in by_group.values():
        if len(normals) < 4:
            continue
        N = np.array(normals)
        zbar = sum((N[k] + N[k + 1]) / np.linalg.norm(N[k] + N[k + 1])
                   for k in range(0, len(N), 2))
        res = linprog(-zbar, A_ub=-N, b_ub=np.zeros(len(N)), bounds=[(-1, 1)] * 3,
                      method="highs")
        if res.status != 0 or -res.fun <= 1e-9:
            return False
    if not rows:
        return True
    A, b = np.array(rows), np.array(rhs)
    # max delta s.t. A t >= b + delta (unit rows), |t_i| <= 1e3
    res = linprog(np.r_[0, 0, 0, -1.0], A_ub=np.c_[-A, np.ones(len(A))], b_ub=-b,
                  bounds=[(-1e3, 1e3)] * 3 + [(None, 1.0)], method="highs")
    return res.status == 0 and -res.fun >= -1e-10


def _reference_f(rays, R) -> float:
    groups = apex_groups(rays)
    lo, hi = 0.0, 1e-3
    while not _reference_feasible(rays, groups, R, hi):
        lo, hi = hi, 2 * hi
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        if _reference_feasible(rays, groups, R, mid):
            hi = mid
        else:
            lo = mid
    return hi


def test_error_at_a_rotation_matches_reference():
    checked = 0
    for seed in range(6):
        p = _problem(seed, n_per_cam=(4, 7))
        rng = np.random.default_rng(100 + seed)
        for delta in (0.0, 1e-3, 1e-2):
            R = p.R @ synth.random_rotation(rng, delta) if delta else p.R
            f, _ = linf_error(p.rays, R, tol=1e-11)
            ref = _reference_f(p.rays, R)
            assert abs(f - ref) < 1e-6 * max(1.0, ref), (seed, delta, f, ref)
            checked += 1
    assert checked == 18


# ------------------------------------------------------------ optimality

def _dense_then_local(rays, R_center, seed):
    minimize = pytest.importorskip("scipy.optimize").minimize

    def f(w):
        return linf_error(rays, _core.rot_from_angle_axis(w), tol=1e-10)[0]

    w0 = _core.angle_axis_from_rot(R_center)
    rng = np.random.default_rng(seed)
    samples = [w0 + rng.normal(size=3) * s for s in (1e-4, 1e-3, 1e-2) for _ in range(4)]
    fs = [f(w) for w in samples]
    best = samples[int(np.argmin(fs))]
    nm = minimize(f, best, method="Nelder-Mead",
                  options={"xatol": 1e-9, "fatol": 1e-11, "maxiter": 100})
    return min(fs), float(nm.fun)


@pytest.mark.slow
def test_global_optimality_200_problems():
    """Never above f at the true rotation, at any sampled rotation, nor above
    the local refinement (Nelder-Mead from the best of the samples around the
    result, 1e-4 to 1e-2 rad away) by more than the precision of f; the
    certified lower bound below every value of f seen. Measured before the
    sequential-LP polish (pattern search + Nelder-Mead): 4 of 200 above the
    refinement by up to 6.6e-7 rad, a second shallow basin 6e-4 rad away;
    now none."""
    stats = []
    for seed in range(200):
        p = _problem(seed, n_per_cam=(5, 11))
        # the search on every correspondence (the outlier guard, which may
        # drop a few of 10-40 rays on a poor start, has its own tests)
        m = mcgeom.estimate(p.rays, "bnb_lp", prune=False)
        info = m.info
        f_true, _ = linf_error(p.rays, p.R, tol=1e-10)
        f_samples, f_local = _dense_then_local(p.rays, m.R, seed + 7)
        linf, lb = info["linf"], info["lower_bound"]
        assert linf <= f_true + F_TOL, (seed, linf, f_true)
        assert linf <= f_samples + F_TOL, (seed, linf, f_samples)
        assert linf <= f_local + F_TOL, (seed, linf, f_local)
        assert lb <= linf + 1e-12
        assert lb <= min(f_true, f_samples, f_local) + 1e-12
        assert abs(linf_error(p.rays, m.R, tol=1e-10)[0] - linf) < F_TOL
        stats.append((f_true - linf, linf - f_local, linf - lb))
    s = np.array(stats)
    above = int(np.sum(s[:, 1] > F_TOL))
    print(f"\nf(R_true) - linf: median {np.median(s[:, 0]):.3g}; linf - local refinement: "
          f"max {s[:, 1].max():.3g}, {above}/200 above {F_TOL:g}; certified gap: median "
          f"{np.median(s[:, 2]):.3g}")
    assert above == 0


def test_returned_translation_is_feasible_at_linf():
    p = _problem(3)
    m = mcgeom.estimate(p.rays, "bnb_lp", prune=False)   # every row checked below
    t = m.info["t_metric"]
    eps = m.info["linf"] + 1e-9
    for i in range(len(p.rays)):
        w = _core.wedge_normals(m.R @ p.rays.dirs1[i], p.rays.dirs2[i], eps, eps)
        if w is None:
            continue
        apex = p.rays.origins2[i] - m.R @ p.rays.origins1[i]
        for n in w:
            assert n @ (t - apex) >= -1e-7 * (1 + np.linalg.norm(t))


# ------------------------------------------------- variants give one answer

def _search(rays, R0, **kw):
    return _core.bnb_linf(rays.dirs1, rays.origins1, rays.dirs2, rays.origins2,
                          apex_groups(rays), R0, **kw)


def test_variants_give_the_same_search():
    p = _problem(11, n_per_cam=(10, 12))
    R0 = mcgeom.estimate(p.rays, "refine").R
    base = _search(p.rays, R0, polish_tol=0.0)
    for kw in ({"preemptive": False}, {"working_sets": False},
               {"preemptive": False, "working_sets": False}):
        other = _search(p.rays, R0, polish_tol=0.0, **kw)
        assert other["blocks"] == base["blocks"], kw
        assert abs(other["linf"] - base["linf"]) < 1e-12, kw
        assert np.allclose(other["R"], base["R"], atol=1e-12), kw


@pytest.mark.skipif("glpk" not in registry.lp_backends(), reason=registry.glpk_status())
def test_glpk_backend_gives_the_same_optimum():
    p = _problem(5, n_per_cam=(6, 8))
    R0 = mcgeom.estimate(p.rays, "refine").R
    native = _search(p.rays, R0, polish_tol=0.0, resolution=1e-3)
    glpk = _search(p.rays, R0, polish_tol=0.0, resolution=1e-3, lp_backend="glpk")
    # same decisions except within ~1e-8 of a feasibility boundary
    assert abs(glpk["linf"] - native["linf"]) < 1e-7
    assert abs(glpk["lower_bound"] - native["lower_bound"]) < 1e-7


def test_backend_chosen_through_the_registry():
    assert "native" in registry.lp_backends()
    p = _problem(2, n_per_cam=(6, 8))
    old = registry.default_lp_backend()
    try:
        for name in registry.lp_backends():
            registry.set_default_lp_backend(name)
            m = mcgeom.estimate(p.rays, "bnb_lp", resolution=1e-3)
            assert m.info["lp_backend"] == name
    finally:
        registry.set_default_lp_backend(old)
    with pytest.raises(ValueError, match="LP backend"):
        registry.set_default_lp_backend("cplex")


def test_certificate_and_counts_reported():
    p = _problem(4)
    m = mcgeom.estimate(p.rays, "bnb_lp", initial="linear17")
    i = m.info
    assert i["initial_method"] == "linear17"
    assert i["lower_bound"] <= i["linf"] <= i["initial_linf"]
    assert i["gap"] == pytest.approx(i["linf"] - i["lower_bound"])
    assert i["blocks"] > 0 and i["lps_2var"] + i["lps_3var"] > 0 and i["seconds"] > 0
    assert i["stop"] == "converged"
    assert m.scale.observable


def test_time_budget_stops_the_search_with_a_certified_bound():
    p = _problem(4)
    m = mcgeom.estimate(p.rays, "bnb_lp", initial="linear17", resolution=1e-7,
                        max_seconds=0.02)
    i = m.info
    assert i["stop"] == "time_limit"
    assert i["lower_bound"] <= i["linf"] <= i["initial_linf"]
    with pytest.raises(ValueError, match="max_seconds"):
        mcgeom.estimate(p.rays, "bnb_lp", max_seconds=-1.0)


def test_mask_selects_inliers():
    p = _problem(6)
    rng = np.random.default_rng(0)
    n = len(p.rays)
    bad = rng.choice(n, size=n // 5, replace=False)
    d2 = p.rays.dirs2.copy()
    d2[bad] = rng.normal(size=(len(bad), 3))
    rays = mcgeom.RayPairs(p.rays.origins1, p.rays.dirs1, p.rays.origins2, d2,
                           p.rays.cam1, p.rays.cam2)
    mask = np.ones(n, np.uint8)
    mask[bad] = 0
    m = mcgeom.estimate(rays, "bnb_lp", mask=mask)
    assert metrics.rotation_error(m.R, p.R) < np.radians(0.5)
    assert m.inliers.sum() == n - len(bad)


# ---------------------------------------------------------------- bad input

def test_bad_input():
    p = _problem(1, n_per_cam=(4, 5))
    r = p.rays
    with pytest.raises(ValueError, match="too few"):
        mcgeom.estimate(r.take(np.arange(5)), "bnb_lp")
    with pytest.raises(ValueError, match="too few"):
        mcgeom.estimate(r, "bnb_lp", mask=np.zeros(len(r), bool))
    with pytest.raises(ValueError, match="mask"):
        mcgeom.estimate(r, "bnb_lp", mask=np.ones(3, bool))
    with pytest.raises(ValueError, match="resolution"):
        mcgeom.estimate(r, "bnb_lp", resolution=0.0)
    with pytest.raises(ValueError, match="LP backend"):
        mcgeom.estimate(r, "bnb_lp", lp_backend="nope")
    d1 = r.dirs1.copy()
    d1[0, 0] = np.nan
    with pytest.raises(ValueError, match="NaN|finite"):
        mcgeom.estimate(mcgeom.RayPairs(r.origins1, d1, r.origins2, r.dirs2), "bnb_lp")
    args = (r.dirs1, r.origins1, r.dirs2, r.origins2)
    g = apex_groups(r)
    with pytest.raises(ValueError, match="group"):
        _core.bnb_linf(*args, g[:-1], np.eye(3))
    with pytest.raises(ValueError, match="group"):
        _core.bnb_linf(*args, -g - 1, np.eye(3))
    with pytest.raises(ValueError, match="zero bearing"):
        z = r.dirs1.copy()
        z[2] = 0.0
        _core.bnb_linf(z, *args[1:], g, np.eye(3))
    with pytest.raises(ValueError, match="invalid options"):
        _core.bnb_linf(*args, g, np.eye(3), grid=0)
    with pytest.raises(ValueError, match="R_init"):
        _core.bnb_linf(*args, g, np.eye(2))


# ------------------------------------------------- the ch. 10.5.1 experiment

@pytest.mark.slow
def test_experiment_ch10_runs():
    from mcgeom.experiments import ch9 as experiment_ch9
    from mcgeom.experiments import ch10 as experiment_ch10
    res = experiment_ch9.run(2, levels=(0.0, 0.5), methods=experiment_ch10.METHODS)
    clean, noisy = res[0.0]["bnb_lp"], res[0.5]["bnb_lp"]
    assert np.all(clean[:, 0] < 1e-5) and np.all(np.abs(clean[:, 2] - 1) < 1e-6)
    assert np.all(noisy[:, 0] < 0.2) and np.all(noisy[:, 1] < 2.0)   # deg
    rows = experiment_ch10.preemption(1, glpk=False)
    print("\n" + experiment_ch10.preemption_table(rows))
    assert {r["working_sets"] for r in rows} == {True, False}
