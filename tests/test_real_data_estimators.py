"""Every registered estimator on real data (issue 18): small fixtures of matched pixels.

The fixtures in tests/data/real/ (see its README.md; written by ``mcgeom experiment
make_real_fixtures``) hold 5+1 inlier pixel correspondences of one frame pair of a real
recording, its rig and the ground-truth motion. Every name of the registry is run on
every fixture through ``mcgeom.estimate(rays, name)`` -- a newly registered estimator is
included by itself -- and must be honest there as 5+1 is:

* ``static`` (EuRoC MAV standing still, DDAD parked car): ``t = 0`` with the verdict
  "no translation detected" (not observable), never a raise;
* ``straight_intra`` (KITTI raw 0023 and KITTI-00 driving straight, intra-camera matches
  only: critical motion): the scale is reported not observable;
* ``cross`` (KITTI raw stereo and DDAD surround rig with cross-camera matches): the scale
  is observable and within the stated uncertainty, ``|scale - 1| <= 3 rel_std``;
* wherever 5+1 gets the rotation within 0.05 deg, every estimator gets it within 0.1 deg.

The failures still open are listed in ``KNOWN_FAILURES`` with their diagnosis, as strict
xfails: they stay visible in the summary, and a fix (XPASS) fails until its entry goes.
"""

from __future__ import annotations

import functools
import json
from pathlib import Path

import numpy as np
import pytest

import mcgeom
from mcgeom import registry
from mcgeom.experiments.make_real_fixtures import load_fixture
from mcgeom.experiments.real_data import gec_sampson, rot_angle_deg

DATA = Path(__file__).parent / "data" / "real"
FIXTURES = sorted(p.stem for p in DATA.glob("*.npz"))
KINDS = ("static", "straight_intra", "cross")
#: a fixture must stay small (tens of KB): matched pixels, not images
MAX_FIXTURE_BYTES = 50_000
#: options that keep the run short: bnb_lp's global search is bounded in time
OPTIONS = {"bnb_lp": {"max_seconds": 2.0}}
#: the rotation check applies where 5+1 is within this (degrees) ...
REFERENCE_ROT_DEG = 0.05
#: ... and then every estimator must be within this (degrees)
MAX_ROT_DEG = 0.1
#: "within the stated uncertainty": |scale - 1| <= SIGMAS * rel_std
SIGMAS = 3.0
#: a static rig's t is zero (metres): "no translation detected", not a tiny metric t
ZERO_T = 1e-9
#: the ground truth must explain the pixels (median Sampson error, pixels)
GT_SAMPSON_PX = 2.0


@functools.lru_cache(maxsize=None)
def fixture(name: str) -> dict:
    """The fixture ``name`` with its rays (rig frame, metres)."""
    f = load_fixture(DATA / f"{name}.npz")
    f["rays"] = f["rig"].ray_pairs(f["pixels1"], f["pixels2"], f["cam1"], f["cam2"])
    return f


@functools.lru_cache(maxsize=None)
def run(method: str, name: str):
    """``mcgeom.estimate`` of ``method`` on fixture ``name``: the motion, or the exception
    (a raise on real data is itself a failure of the checks below)."""
    f = fixture(name)
    kw = dict(OPTIONS.get(method, {}))
    if registry.get(method).needs_rotation:
        kw["rotation"] = f["R_gt"]   # as its users would: the rotation is known
    if "gravity1" in registry.get(method).options:
        # an IMU's vertical, consistent with the true rotation (any direction of
        # rig frame 1 and its image under R_gt in rig frame 2)
        kw["gravity1"] = np.array([0.0, -1.0, 0.0])
        kw["gravity2"] = f["R_gt"] @ kw["gravity1"]
    # as its users would: the rig's calibration error in the uncertainty (the
    # fixtures' rigs state none: the documented default, 2 mm and 0.1 deg)
    kw["calibration_std"] = f["rig"].extrinsic_std
    try:
        return mcgeom.estimate(f["rays"], method, **kw)
    except Exception as exc:  # noqa: BLE001 - reported by the check that needed the motion
        return exc


def motion_or_fail(method: str, name: str):
    m = run(method, name)
    if isinstance(m, Exception):
        pytest.fail(f"{method} on {name} raised {type(m).__name__}: {m}")
    return m


def _describe(m, f) -> str:
    t = np.asarray(m.t, float).ravel()
    return (f"|t| = {np.linalg.norm(t):.4g} (truth {np.linalg.norm(f['t_gt']):.4g} m), "
            f"observable={m.scale.observable}, rel_std={m.scale.rel_std:.3g}, "
            f"reason: {m.scale.reason[:160]}")


#: (check, method, fixture) -> diagnosis: the open failures of issue 18, strict
#: xfails so that they stay visible (-ra) and a fix (XPASS) fails until the marker goes
KNOWN_FAILURES = {
    **{("verdict", m, "euroc_static"): (
        "EuRoC's 'static' pair moved 0.9 mm (ground truth): the shared static test, at "
        "the estimate's rotation, finds the per-camera translation model ~10x better "
        "than a pure rotation (noise 5.5e-4 rad against a 6e-4 rad median rotation-only "
        "angle), so it reports a translation whose scale it cannot measure (unit t, "
        "'scale too uncertain') instead of 't = 0'")
       for m in ("bnb_lp", "five_plus_one", "linear17", "refine", "six_point")},
    ("rotation", "eigensolver", "kitti_raw_straight_intra"): (
        "the eigensolver stops 0.119 deg from the truth on this near-critical straight "
        "pair (5+1: 0.002 deg): the smallest eigenvalue is flat along the rotation that "
        "trades against the translation direction"),
}


def _cases(check: str) -> list:
    out = []
    for method in registry.names():
        for name in FIXTURES:
            why = KNOWN_FAILURES.get((check, method, name))
            marks = [pytest.mark.xfail(reason=why, strict=True)] if why else []
            out.append(pytest.param(method, name, id=f"{method}-{name}", marks=marks))
    return out


def test_fixtures_are_small_and_cover_every_kind():
    assert FIXTURES, f"no fixtures in {DATA}"
    kinds = set()
    for name in FIXTURES:
        assert (DATA / f"{name}.npz").stat().st_size < MAX_FIXTURE_BYTES, name
        f = fixture(name)
        kinds.add(f["kind"])
        assert f["kind"] in KINDS, name
        n = len(f["rays"])
        assert n >= 50 and f["cam1"].shape == f["cam2"].shape == (n,), name
        cross = int(np.count_nonzero(f["cam1"] != f["cam2"]))
        assert (cross == 0) == (f["kind"] == "straight_intra"), name
        assert f["meta"]["kind"] == f["kind"] and f["meta"]["kept"] == n, name
    assert kinds == set(KINDS)


@pytest.mark.parametrize("name", FIXTURES)
def test_ground_truth_explains_the_pixels(name):
    """The ground truth is rig2_from_rig1 in the fixture's rig frame: the pixels fit it
    (and, on moving rigs, fit it better than its inverse, the other convention)."""
    f = fixture(name)
    r = f["rays"]
    focal = np.mean([0.5 * (c.K[0, 0] + c.K[1, 1]) for c in f["rig"].cameras])
    err = np.median(gec_sampson(r.origins1, r.dirs1, r.origins2, r.dirs2,
                                f["R_gt"], f["t_gt"])) * focal
    assert err < GT_SAMPSON_PX, (name, err)
    if f["kind"] != "static":
        Ri, ti = f["R_gt"].T, -f["R_gt"].T @ f["t_gt"]
        wrong = np.median(gec_sampson(r.origins1, r.dirs1, r.origins2, r.dirs2, Ri, ti)) * focal
        assert wrong > 2 * err, (name, err, wrong)


@pytest.mark.parametrize("method,name", _cases("verdict"))
def test_verdict_on_real_data(method, name):
    """static: t = 0, no translation detected; straight intra-only: not observable;
    cross-camera: metric within 3 rel_std of the truth."""
    f = fixture(name)
    m = motion_or_fail(method, name)
    what = _describe(m, f)
    if f["kind"] == "static":
        assert not m.scale.observable, f"{method} on static {name}: observable; {what}"
        assert np.linalg.norm(m.t) <= ZERO_T, f"{method} on static {name}: t != 0; {what}"
        assert "no translation detected" in m.scale.reason, f"{method} on {name}: {what}"
    elif f["kind"] == "straight_intra":
        assert not m.scale.observable, (f"{method} on {name} (straight, intra-camera only): "
                                        f"reported observable; {what}")
    else:
        assert m.scale.observable, f"{method} on {name} (cross-camera): not metric; {what}"
        scale = np.linalg.norm(m.t) / np.linalg.norm(f["t_gt"])
        bound = SIGMAS * m.scale.rel_std
        assert abs(scale - 1.0) <= bound, (
            f"{method} on {name}: scale {scale:.4f} x the truth, |scale - 1| = "
            f"{abs(scale - 1):.4f} > {SIGMAS:g} rel_std = {bound:.4f}; {what}")


@pytest.mark.parametrize("method,name", _cases("rotation"))
def test_rotation_on_real_data(method, name):
    """Rotation within 0.1 deg wherever 5+1 is within 0.05 deg."""
    f = fixture(name)
    ref = run("five_plus_one", name)
    if isinstance(ref, Exception) or rot_angle_deg(ref.R @ f["R_gt"].T) > REFERENCE_ROT_DEG:
        pytest.skip(f"5+1 is not within {REFERENCE_ROT_DEG} deg on {name}: no reference")
    m = motion_or_fail(method, name)
    err = rot_angle_deg(np.asarray(m.R) @ f["R_gt"].T)
    assert err <= MAX_ROT_DEG, (f"{method} on {name}: rotation error {err:.3f} deg > "
                                f"{MAX_ROT_DEG} deg (5+1: "
                                f"{rot_angle_deg(ref.R @ f['R_gt'].T):.3f} deg)")


def test_readme_lists_every_fixture():
    text = (DATA / "README.md").read_text(encoding="utf-8")
    for name in FIXTURES:
        assert f"`{name}`" in text, name
        assert json.dumps(fixture(name)["meta"]["recording"])[1:-1] in text, name
