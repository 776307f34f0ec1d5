"""The minimal solvers of the C robust search (issue 21): the façade's choice
(upright with a vertical prior, 5+1 when a camera has 5 intra-camera
correspondences, else the generic 6-point, its samples solved by the local
search or the homotopy), ``info["sampler"]``,
``robust.ransac`` running all three in C, and their argument checks."""

from __future__ import annotations

import numpy as np
import pytest

from mcgeom import _core, cv, metrics, robust, synth


def _rot_deg(A: np.ndarray, B: np.ndarray) -> float:
    return float(np.degrees(metrics.rotation_error(A, B)))


def _car(seed: int, outliers: float = 0.3):
    rng = np.random.default_rng(seed)
    rig = synth.vehicle8()
    R = synth.rotation_about([0.0, 0.0, 1.0], 0.12)
    t = np.array([0.9, 0.05, 0.01])
    p = synth.make_problem(rig, R, t, 320, rng, pixel_noise=0.5, outlier_fraction=outliers)
    return rig, R, t, p


def _ring12(seed: int):
    """12 cameras, 8 correspondences each, half cross-camera, 10 % outliers (few
    samples: the 6-point solver takes ~0.1 s each):
    no camera has 5 intra-camera correspondences."""
    rng = np.random.default_rng(seed)
    rig = synth.ring_rig(12, 0.6, 500.0)
    R = synth.rotation_about([0.1, 0.3, 1.0], 0.2)
    t = np.array([0.5, -0.3, 0.2])
    p = synth.make_problem(rig, R, t, 96, rng, pixel_noise=0.3, outlier_fraction=0.1,
                           cross_fraction=0.5, require_visible=False)
    return rig, R, t, p


def test_choose_sampler_counts_intra_camera_correspondences():
    assert cv.choose_sampler(np.array([0, 0, 0, 0, 0, 1]), np.array([0, 0, 0, 0, 0, 1])) \
        == "five_plus_one"
    # five of camera 0, but one is cross-camera: four intra-camera only
    assert cv.choose_sampler(np.array([0, 0, 0, 0, 0, 1]), np.array([0, 0, 0, 0, 1, 1])) \
        == "six_point"
    # too few for any sample: 5+1, whose checks say so
    assert cv.choose_sampler(np.zeros(0, int), np.zeros(0, int)) == "five_plus_one"
    assert cv.choose_sampler(np.arange(5), np.arange(5)) == "five_plus_one"


def test_facade_reports_the_sampler_it_chose():
    rig, R, t, p = _car(3)
    m = cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, rig)
    assert m.info["sampler"] == "five_plus_one"
    g1 = np.array([0.0, 0.0, -1.0])
    mu = cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, rig, gravity1=g1, gravity2=R @ g1)
    assert mu.info["sampler"] == "upright_four_point"
    assert _rot_deg(mu.R, R) < 0.1
    # the vertical known: 3+1 samples, far fewer drawn than 5+1's at 30 % outliers
    assert m.info["sample_size"] == 5 and mu.info["sample_size"] == 3
    assert mu.info["iterations"] < m.info["iterations"]


def test_upright_sampler_draws_3_plus_1_where_a_camera_has_3_intra_camera_pairs():
    """The upright sampler's samples (issue 21): 3 intra-camera pairs of one
    camera solved with the vertical (its rotation and direction of travel)
    and a fourth pair for the scale where some camera has 3 of them
    (``info["sample_size"]`` 3), else 4 pairs of any cameras (4); both find
    the motion."""
    rig, R, t, p = _ring12(1)
    g1 = np.array([0.0, 0.0, -1.0])
    up = {"gravity1": g1, "gravity2": R @ g1}
    m3 = cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, rig, **up)
    # at most 2 intra-camera correspondences per camera, all cross-camera ones
    intra = p.cam1 == p.cam2
    rank = np.array([np.count_nonzero(intra[:k] & (p.cam1[:k] == p.cam1[k]))
                     for k in range(len(p.cam1))])
    keep = ~intra | (rank < 2)
    m4 = cv.estimate(p.pixels1[keep], p.pixels2[keep], p.cam1[keep], p.cam2[keep], rig, **up)
    assert np.bincount(p.cam1[keep & intra]).max() == 2
    assert m3.info["sampler"] == m4.info["sampler"] == "upright_four_point"
    assert m3.info["sample_size"] == 3 and m4.info["sample_size"] == 4
    for m in (m3, m4):
        assert _rot_deg(m.R, R) < 0.2
        assert abs(np.linalg.norm(m.info["t_metric"]) / np.linalg.norm(t) - 1) < 0.05


def test_upright_with_a_level_vertical_is_not_the_static_rig():
    """g1 = g2 (no tilt, a car on flat ground) and intra-camera pairs only: the
    static rig solves every upright sample and zeroes every residual; the C
    search must not take it."""
    rig, R, t, p = _car(4)
    g = np.array([0.0, 0.0, 1.0])
    m = cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, rig, gravity1=g, gravity2=g)
    assert _rot_deg(m.R, R) < 0.1
    assert np.linalg.norm(m.info["t_metric"]) > 0.5
    assert m.inliers.mean() < 0.8        # 30 % outliers are not explained


def test_facade_takes_six_point_without_a_five_point_camera():
    rig, R, t, p = _ring12(5)
    intra = p.cam1 == p.cam2
    assert np.bincount(p.cam1[intra]).max() < 5
    m = cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, rig)
    assert m.info["sampler"] == "six_point"
    assert m.method == "ransac[six_point]"
    assert _rot_deg(m.R, R) < 0.2
    assert abs(np.linalg.norm(m.info["t_metric"]) / np.linalg.norm(t) - 1.0) < 0.1
    forced = cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, rig, method=cv.RIG_6PT_RANSAC)
    assert forced.info["sampler"] == "six_point" and np.allclose(forced.R, m.R)
    # 5+1 cannot sample these data: forced by name it says why
    with pytest.raises(ValueError, match="5 intra-camera"):
        cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, rig, method="ransac:five_plus_one")


def test_ransac_runs_six_point_in_c():
    rig, R, t, p = _ring12(6)
    m = robust.ransac(p.rays, "six_point", threshold=2e-3)
    assert m.info["sampler"] == "six_point" and "c_seconds" in m.info
    assert _rot_deg(m.R, R) < 0.2


def test_six_point_local_search_measures_its_rate_of_success():
    """The 6-point samples are solved by the local search by default
    (mcg_sixpt_local): it may miss an all-inlier sample's motion, so the
    search measures how often it finds its consensus' motion (found_rate, in
    (0, 1)) and its stop and confidence count with it; solver="homotopy"
    solves them completely (found_rate 1) and both reach the same motion."""
    rig, R, t, p = _ring12(6)
    local = robust.ransac(p.rays, "six_point", threshold=2e-3, seed=1)
    assert local.info["six_point_solver"] == "local"
    assert 0.0 < local.info["found_rate"] < 1.0
    assert local.info["stop"] == "confidence" and local.info["confidence"] >= 0.999
    # without the rate the stop would have come after k0 samples at the
    # consensus' fraction w; with it, after more
    w = np.count_nonzero(local.inliers) / len(p.rays)
    k0 = robust.adaptive_iterations(w, 6, 0.999, 10 ** 6)
    # (seed 1: found_rate 0.44, 27 samples where the rate-blind stop takes 10)
    assert local.info["found_rate"] < 0.5 and local.info["iterations"] >= 2 * k0
    complete = robust.ransac(p.rays, "six_point", threshold=2e-3, seed=1,
                             solver_options={"solver": "homotopy"}, max_iters=20)
    assert complete.info["six_point_solver"] == "homotopy" and complete.info["found_rate"] == 1.0
    assert _rot_deg(local.R, R) < 0.2 and _rot_deg(complete.R, R) < 0.2
    assert _rot_deg(local.R, complete.R) < 0.05
    with pytest.raises(ValueError, match="six_point's solver must be 'local' or 'homotopy'"):
        robust.ransac(p.rays, "six_point", solver_options={"solver": "grobner"})
    # (the Python loop's solver is the homotopy: the option is named, not a TypeError)
    with pytest.raises(ValueError, match=r"solver_options \['solver'\] are not options of "
                                         r"six_point's minimal solver in the Python loop"):
        robust.ransac(p.rays, "six_point", strategy="minimal", solver_options={"solver": "local"})


def test_ransac_upright_in_c_matches_the_python_loop():
    """The C search and the Python minimal-sample loop (strategy='minimal')
    reach the same motion within the noise."""
    rig, R, t, p = _car(8, outliers=0.2)
    g1 = np.array([0.05, -0.02, 1.0])
    g2 = R @ g1
    kw = dict(threshold=1e-3, solver_options={"gravity1": g1, "gravity2": g2})
    mc = robust.ransac(p.rays, "upright_four_point", **kw)
    mp = robust.ransac(p.rays, "upright_four_point", strategy="minimal", **kw)
    assert mc.info["sampler"] == "upright_four_point" and "c_seconds" in mc.info
    assert _rot_deg(mc.R, R) < 0.1 and _rot_deg(mp.R, R) < 0.1
    assert _rot_deg(mc.R, mp.R) < 0.05
    assert np.mean(mc.inliers == mp.inliers) > 0.97


def test_solver_options_are_checked():
    rig, R, t, p = _car(9)
    with pytest.raises(ValueError, match="gravity1 is required"):
        robust.ransac(p.rays, "upright_four_point")
    with pytest.raises(ValueError, match="gravity2 has zero length"):
        robust.ransac(p.rays, "upright_four_point",
                      solver_options={"gravity1": [0, 0, 1], "gravity2": [0, 0, 0]})
    with pytest.raises(ValueError, match=r"solver_options \['gravity1'\] are not options"):
        robust.ransac(p.rays, "five_plus_one", solver_options={"gravity1": [0, 0, 1]})
    with pytest.raises(ValueError, match="sampler must be .auto. or one of"):
        _core.robust_rig_motion(p.rays.origins1, p.rays.dirs1, p.rays.origins2, p.rays.dirs2,
                                p.cam1, p.cam2, 8, sampler="seven_point")
    with pytest.raises(ValueError, match="gravity1/gravity2 are for the upright"):
        _core.robust_rig_motion(p.rays.origins1, p.rays.dirs1, p.rays.origins2, p.rays.dirs2,
                                p.cam1, p.cam2, 8, gravity1=[0, 0, 1], gravity2=[0, 0, 1])
    with pytest.raises(ValueError, match="gravity2 contains NaN"):
        _core.robust_rig_motion(p.rays.origins1, p.rays.dirs1, p.rays.origins2, p.rays.dirs2,
                                p.cam1, p.cam2, 8, sampler="upright_four_point",
                                gravity1=[0, 0, 1], gravity2=[0, np.nan, 1])


def test_upright_with_a_vertical_off_by_a_fifth_of_a_degree():
    """The car rig turning (intra-camera correspondences only), the vertical
    known to 0.2 deg: the upright search must reach 5+1's answer. (Without
    cheirality for the upright solutions a backward t of 4 % of the truth
    won on the first problem: 74 % inliers, 0.14 deg.)"""
    from mcgeom.experiments.peer_solvers import _car_turning
    rng = np.random.default_rng(1)
    rig = synth.vehicle8()
    R, t = _car_turning(rng)
    p = synth.make_problem(rig, R, t, 320, rng, pixel_noise=0.5)
    # the fifth and sixth tilts of this stream are the ones that failed
    g = [synth.tilted(v, deg, rng) for deg in (0.0, 0.05, 0.2)
         for v in (synth.GRAVITY, R @ synth.GRAVITY)]
    g1, g2 = g[4], g[5]
    m5 = cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, rig)
    mu = cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, rig, gravity1=g1, gravity2=g2)
    assert _rot_deg(mu.R, R) < 0.05
    assert mu.inliers.mean() > 0.9
    assert np.mean(mu.inliers == m5.inliers) > 0.95
    assert float(mu.info["t_metric"] @ t) > 0     # forward, not backwards


@pytest.mark.parametrize("k", [3, 11, 154])
def test_upright_is_not_trapped_by_a_locally_optimised_wrong_motion(k):
    """Problems 3, 11 and 154 of peer_solvers' "car8 fwd<=2deg 20%out" (seed
    0, the vertical 0.2 deg off): a near-pure rotation (|t| ~1 cm, 0.2-0.3 of
    the pairs) was locally optimised first, and the hypotheses near the
    truth, each tilted by the vertical's error, lost the MSAC to it: 0.2-0.3
    deg, |t| 98 % off, called observable. The challenge of csrc/robust_offer.c
    (RIVAL_WIDE) lets them win after their own local optimisation: the
    upright estimate matches 5+1's inliers."""
    from mcgeom.experiments.peer_solvers import RANSAC_CASES
    make_rig, n, outl, noise, cross, motion = RANSAC_CASES["car8 fwd<=2deg 20%out"]
    rig, rng = make_rig(), np.random.default_rng(0)
    for _ in range(k + 1):      # the experiment's stream of problems
        R, t = motion(rng)
        p = synth.make_problem(rig, R, t, n, rng, pixel_noise=noise, outlier_fraction=outl,
                               cross_fraction=cross, require_visible=True)
        g1 = synth.tilted(synth.GRAVITY, 0.2, rng)
        g2 = synth.tilted(R @ synth.GRAVITY, 0.2, rng)
    m5 = cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, rig, threshold=1.0)
    mu = cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, rig, threshold=1.0,
                     gravity1=g1, gravity2=g2)
    assert _rot_deg(mu.R, R) < 0.05
    assert mu.info["inlier_ratio"] > m5.info["inlier_ratio"] - 0.02
    assert np.linalg.norm(mu.info["t_metric"]) > 0.3 * np.linalg.norm(t)
