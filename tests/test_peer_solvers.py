"""The peer_solvers experiment at small sizes: its minimal part finds the truth
on every noise-free generic configuration and none on the critical one."""

from __future__ import annotations

import numpy as np
import pytest

from mcgeom.experiments import peer_solvers


def test_minimal_part_small():
    pytest.importorskip("poselib")
    res = peer_solvers.run_minimal(60, 0, families=("generic 4-cam, mixed",
                                                    "no yaw, intra (critical)"))
    ours = res["generic 4-cam, mixed"]["mcgeom upright4"]
    assert ours[0] == 1.0 and 1.0 <= ours[1] <= 8.0 and ours[2] > 0.0
    assert res["no yaw, intra (critical)"]["mcgeom upright4"][0] == 0.0
    table = peer_solvers.minimal_table(res)
    assert "poselib upright_4pt" in table and "100.00%" in table


def test_ransac_part_small():
    """One problem of ring4: every row present but the 6-point one (run only
    where the façade chooses it); the façade reports its sampler and the 5+1
    row reuses its run; the eigensolver row runs the C search."""
    pytest.importorskip("poselib")
    res = peer_solvers.run_ransac(1, 0, {"ring4 4x50 0.5px":
                                         peer_solvers.RANSAC_CASES["ring4 4x50 0.5px"]})
    ring4 = res["ring4 4x50 0.5px"]
    assert ring4["mcgeom façade (auto)"][2] == ["five_plus_one"]
    assert "mcgeom 6-pt" not in ring4
    assert ring4["mcgeom 5+1"][0][0, 0] == ring4["mcgeom façade (auto)"][0][0, 0] < 0.1
    assert ring4["mcgeom upright (0.2 deg)"][0][0, 0] < 0.2
    table = peer_solvers.ransac_table(res)
    assert ring4["mcgeom upright (0.2 deg)"][3][0] > 0 and np.isnan(ring4["poselib defaults"][3][0])
    # samples drawn by the C search (an integer >= 1), none for PoseLib
    assert ring4["mcgeom upright (0.2 deg)"][4][0] >= 1 and np.isnan(ring4["poselib defaults"][4][0])
    # ring4's cameras have 50 intra-camera correspondences each: 3+1 samples
    assert ring4["mcgeom upright (0.2 deg)"][2] == ["upright 3+1"]
    # the eigensolver's 17-pair samples run in the C search as well
    assert ring4["mcgeom eigensolver"][2] == ["eigensolver"]
    assert ring4["mcgeom eigensolver"][0][0, 0] < 0.1 and ring4["mcgeom eigensolver"][3][0] > 0
    assert "vs 17-pt" in table and "C vs 5+1" in table and "upright 3+1" in table
    assert "samples" in table and "C final" in table
    # the C call's final stage (refinement, profiles, verdict): part of its
    # time for every mcgeom row, none for PoseLib
    for meth in ("mcgeom façade (auto)", "mcgeom 5+1", "mcgeom upright (0.2 deg)"):
        assert 0 < ring4[meth][5][0] < ring4[meth][3][0]
    assert np.isnan(ring4["poselib defaults"][5][0])


def test_poselib_refuses_data_it_cannot_sample():
    """The 12-camera rig with 8 correspondences per camera: no camera pair has
    the 5 matches of PoseLib's 5+1 sample, where it would loop forever."""
    pytest.importorskip("poselib")
    from mcgeom import synth
    from mcgeom.experiments.poselib_peer import poselib_motion
    rng = np.random.default_rng(0)
    rig = peer_solvers.rig12()
    p = synth.make_problem(rig, synth.rotation_about([0, 0, 1], 0.2), np.array([0.5, 0, 0]),
                           96, rng, cross_fraction=0.5, require_visible=False)
    with pytest.raises(ValueError, match="no camera pair has 5 matches"):
        poselib_motion(rig, p)


def test_with_outliers_renames_and_overrides_the_fraction():
    """``--outliers``: each case once per fraction, the fraction in its name
    (the case's own one dropped) and in its entry; a fraction of 1 (no
    inlier left) is refused by name."""
    cases = {k: peer_solvers.RANSAC_CASES[k] for k in ("ladybug6 300c 30%out",
                                                       "car8 320c turning <=10deg")}
    out = peer_solvers.with_outliers(cases, [0.5, 0.6])
    assert list(out) == ["ladybug6 300c @50%out", "ladybug6 300c @60%out",
                         "car8 320c turning <=10deg @50%out",
                         "car8 320c turning <=10deg @60%out"]
    assert [v[2] for v in out.values()] == [0.5, 0.6, 0.5, 0.6]
    # everything else is the case's own
    assert out["ladybug6 300c @50%out"][:2] == cases["ladybug6 300c 30%out"][:2]
    assert out["ladybug6 300c @50%out"][3:] == cases["ladybug6 300c 30%out"][3:]
    with pytest.raises(ValueError, match="outlier fraction must be in"):
        peer_solvers.with_outliers(cases, [1.0])


def _rows(fails: int, secs: float, n: int = 4) -> tuple:
    e = np.full((n, 2), 0.01)
    e[:fails] = np.nan
    return e, np.full(n, secs)


def test_equal_success_takes_the_smallest_cap_that_succeeds_as_often():
    """The façade against the 17-point row with the smallest cap whose
    failures are at most the façade's; a lower bound when no cap gets there."""
    fac = "mcgeom façade (auto)"
    methods = {fac: _rows(0, 1.0), "mcgeom 17-pt": _rows(3, 0.2),
               "mcgeom 17-pt <=5000": _rows(0, 3.0), "mcgeom 17-pt <=20000": _rows(0, 9.0)}
    line = peer_solvers.equal_success(methods)
    assert "failed 0.00, 1000.0 ms" in line
    assert "mcgeom 17-pt <=5000 failed 0.00 in 3000.0 ms: 3.00x faster" in line
    methods["mcgeom 17-pt <=5000"] = _rows(1, 3.0)
    methods["mcgeom 17-pt <=20000"] = _rows(1, 9.0)
    line = peer_solvers.equal_success(methods)
    assert "no cap got there" in line and "mcgeom 17-pt <=20000, failed 0.25" in line
    assert ">= 9.00x faster" in line
    # a façade failing as often as the default cap compares with that cap
    methods[fac] = _rows(3, 1.0)
    assert "mcgeom 17-pt failed 0.75 in 200.0 ms: 0.20x faster" in peer_solvers.equal_success(methods)


def test_ransac_rows_per_17_point_cap():
    """``caps17``: one 17-point row per cap (sorted, the default cap under its
    usual name), each run with that cap; the table's equal-success line."""
    pytest.importorskip("poselib")
    case = {"ring4 4x50 0.5px": peer_solvers.RANSAC_CASES["ring4 4x50 0.5px"]}
    res = peer_solvers.run_ransac(1, 0, case, caps17=(1000, 2))["ring4 4x50 0.5px"]
    rows = [m for m in res if "17-pt" in m]
    assert rows == ["mcgeom 17-pt <=2", "mcgeom 17-pt"]
    # two samples of 17 pairs: at most 2 drawn, the default cap's search stops on its own
    assert 1 <= res["mcgeom 17-pt <=2"][4][0] <= 2 or np.isnan(res["mcgeom 17-pt <=2"][4][0])
    table = peer_solvers.ransac_table({"ring4 4x50 0.5px": res})
    assert "against 17-point RANSAC at equal success" in table
    with pytest.raises(ValueError, match="caps17"):
        peer_solvers.run_ransac(1, 0, case, caps17=())
