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
    """One problem of two cases: every row present; the façade reports the
    sampler it chose; 5+1 and PoseLib cannot sample the 12-camera rig (no
    camera pair with 5 correspondences) and count as failed there, PoseLib
    refusing instead of looping forever."""
    pytest.importorskip("poselib")
    cases = {k: peer_solvers.RANSAC_CASES[k] for k in ("ring4 4x50 0.5px",
                                                       "ring12 12x8 half-cross 40%out")}
    res = peer_solvers.run_ransac(1, 0, cases)
    ring4, ring12 = res["ring4 4x50 0.5px"], res["ring12 12x8 half-cross 40%out"]
    assert ring4["mcgeom façade (auto)"][2] == ["five_plus_one"]
    assert ring4["mcgeom 5+1"][0][0, 0] < 0.1
    assert ring4["mcgeom upright (0.2 deg)"][0][0, 0] < 0.2
    for meth in ("mcgeom 5+1", "poselib min_it=100", "poselib defaults"):
        assert np.isnan(ring12[meth][0][0, 0])
    table = peer_solvers.ransac_table(res)
    assert "vs 17-pt" in table and "upright_four_point" in table
