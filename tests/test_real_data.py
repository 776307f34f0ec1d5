"""The robust pipeline on a few real frame pairs (tests/eval_real_data.py does them all).

Skipped when the recordings (../shared/data relative to the repository) are absent.
The pairs, features and threshold are those of the evaluation script, so a failure here
is a row of its table. Only what must hold is asserted:

* rotations within 1 deg of the ground truth on KITTI (raw stereo and the GTSAM tracks)
  and on the moving DGP surround-rig scene; the direction of travel within 10 deg;
* with the stereo (cross-camera) correspondences the KITTI scale is observable and
  within 10 % of the ground truth (the OXTS poses jitter by ~5 %);
* a critical motion is never a confident wrong scale: an "observable" verdict from
  intra-camera correspondences only must be within 10 % too;
* a static rig (EuRoC clip with the MAV standing still, DGP parked car) is never
  reported as a confident metric translation: the verdict is "unobservable", or the
  metric |t| is below a few centimetres.

Known weaknesses of the estimator found on these data are marked ``xfail`` with the
diagnosis: they stay visible in the summary (``-ra``: XFAIL, or XPASS once fixed -- then
remove the marker so that a regression fails again).
"""

from __future__ import annotations

import numpy as np
import pytest

import eval_real_data as ev

if not ev.data_available():
    pytest.skip(f"real recordings not found under {ev.DATA_ROOT}", allow_module_level=True)
if ev.cv2 is None:  # pragma: no cover
    pytest.skip("OpenCV (cv2) is not installed", allow_module_level=True)

#: a few pairs per data set (about 30 s on two cores, mostly SIFT on the DGP images)
SUBSET = {
    "kitti_raw": [(0, 1), (3, 4)],
    "kitti00_tracks": [(20, 21), (50, 51)],
    "dgp_scene_02": [(0, 1)],
    "euroc": [(0, 1), (12, 13), (22, 23)],
    "dgp_scene_01": [(0, 1)],
}
MOVING = ("kitti_raw", "kitti00_tracks", "dgp_scene_02")
STEREO = ("kitti_raw", "kitti00_tracks")
MAX_ROT_ERR_DEG = 1.0
MAX_TDIR_ERR_DEG = 10.0
MAX_SCALE_ERR = 0.10
#: a static rig may come out "observable" only with |t| below this (metres)
MAX_STATIC_T = 0.03

_PARKED = (
    "known weakness: parked car, 3 cameras with overlap. Intra-camera data show no "
    "parallax (pure rotation fits to 0.2-0.4 px) but the no-parallax test compares with "
    "the Sampson residual of a free translation (0.03 px, ratio 6-16 > 3) and does not "
    "fire; the verdict then trusts ~200-330 cross-camera inliers with 1-10 px model error "
    "(no distortion in the DGP calibration): 'observable', |t| ~1 m, relative std 1-2 %. "
    "With intra-camera correspondences only the rotation comes out 180 deg off "
    "(twisted pair, |t| ~ 5e4 m, no cheirality check).")


@pytest.fixture(scope="module")
def results() -> dict:
    ev.cv2.setNumThreads(2)
    seqs = ev.load_sequences(tuple(SUBSET), pairs=SUBSET)
    out = {}
    for seq in seqs:
        feats = ev.Features(seq.nfeatures) if seq.kind == "images" else None
        rows = []
        for k1, k2 in seq.pairs:
            corr = ev.correspondences(seq, k1, k2, feats)
            for mode in ev.MODES:
                rows.append(ev.evaluate_pair(seq, corr, k1, k2, mode))
        out[seq.key] = rows
    return out


def _describe(r: dict) -> str:
    if not r["ok"]:
        return "%s %d-%d %s: FAILED %s" % (r["key"], *r["pair"], r["mode"], r["error"])
    return ("%s %d-%d %s: rot err %.3f deg, t dir err %.2f deg, |t_est| %.3f m (GT %.3f), "
            "%s" % (r["key"], *r["pair"], r["mode"], r["rot_err"], r["tdir_err"], r["t_est"],
                    r["t_gt"], r["reason"]))


def _rows(results: dict, key: str, mode: str | None = None) -> list:
    rows = [r for r in results[key] if mode is None or r["mode"] == mode]
    assert rows
    failed = [_describe(r) for r in rows if not r["ok"]]
    assert not failed, "\n".join(failed)
    return rows


def _check(rows: list, bad) -> None:
    """Assert that no row is bad; the message lists every bad row, not just the first."""
    problems = [f"{why}: {_describe(r)}" for r in rows for why in [bad(r)] if why]
    assert not problems, "\n".join(problems)


@pytest.mark.parametrize("key", MOVING)
def test_rotation_close_to_ground_truth(results, key):
    _check(_rows(results, key),
           lambda r: r["rot_err"] >= MAX_ROT_ERR_DEG and "rotation error")


@pytest.mark.parametrize("mode", ev.MODES)
@pytest.mark.parametrize("key", MOVING)
def test_direction_of_travel(results, key, mode):
    _check(_rows(results, key, mode),
           lambda r: not r["tdir_err"] < MAX_TDIR_ERR_DEG and "translation direction error")


@pytest.mark.parametrize("key", STEREO)
def test_stereo_rig_gives_metric_scale(results, key):
    _check(_rows(results, key, "intra+cross"),
           lambda r: (not r["observable"] and "scale not observable")
           or (not r["scale_err"] < MAX_SCALE_ERR and "scale error"))


@pytest.mark.parametrize("key", MOVING)
def test_critical_motion_is_not_a_confident_wrong_scale(results, key):
    _check(_rows(results, key, "intra"),
           lambda r: r["observable"] and not r["scale_err"] < MAX_SCALE_ERR
           and "confident wrong scale")


@pytest.mark.parametrize("key", [
    "euroc", pytest.param("dgp_scene_01", marks=pytest.mark.xfail(strict=False, reason=_PARKED))])
def test_static_rig_is_not_a_confident_metric_translation(results, key):
    _check(_rows(results, key),
           lambda r: (r["rot_err"] >= MAX_ROT_ERR_DEG and "rotation error")
           or (r["observable"] and not np.linalg.norm(r["motion"].t) < MAX_STATIC_T
               and "confident metric translation of a static rig"))


def test_ground_truth_convention():
    """inv(relative_pose) is rig2_from_rig1: tracked stereo correspondences fit it to a
    pixel, and cross-camera ones do not fit the opposite convention."""
    seq = ev.load_sequences(("kitti00_tracks",), pairs={"kitti00_tracks": [(30, 31)]})[0]
    corr = ev.correspondences(seq, 30, 31)
    g = ev.gt_check(seq, corr, 30, 31)
    assert g["intra_med"] < 1.0 and g["cross_med"] < 1.0, g
    assert g["cross_med_wrong"] > 3 * g["cross_med"], g
