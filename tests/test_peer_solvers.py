"""The peer_solvers experiment at small sizes: its minimal part finds the truth
on every noise-free generic configuration and none on the critical one."""

from __future__ import annotations

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
