"""The robust pipeline on a few real frame pairs (mcgeom experiment real_data does them all).

Skipped when the recordings (../shared/data relative to the repository) are absent.
The pairs, features and threshold are those of the evaluation, so every case here
is a row of its table. Only what must hold is asserted:

* rotations within 1 deg of the ground truth on KITTI (raw stereo and the GTSAM tracks)
  and on the moving DGP surround-rig scene; the direction of travel within 10 deg
  (the returned unit ``t`` is documented as meaningful also when the scale is not);
* with the stereo (cross-camera) correspondences the KITTI scale is observable and
  within 10 % of the ground truth (the OXTS poses jitter by ~5 %);
* never a confident wrong scale: an "observable" verdict on a moving rig is within 10 %
  of the ground truth (a critical motion from intra-camera correspondences only must be
  reported unobservable rather than scaled wrongly; DGP's cross-camera data, with their
  calibration errors, give 6 %);
* a static rig (EuRoC clip with the MAV standing still, DGP parked car) keeps its
  rotation and is never reported as a confident metric translation: the verdict is
  "unobservable", or the metric |t| is below a few centimetres.

Known weaknesses of the estimator found on these data are marked ``xfail`` on exactly
the failing rows, with the diagnosis: they stay visible in the summary (``-ra``: XFAIL,
or XPASS once fixed -- then remove the marker so that a regression fails again).
"""

from __future__ import annotations

import numpy as np
import pytest

import mcgeom.experiments.real_data as ev

if not ev.data_available():
    pytest.skip(f"real recordings not found under {ev.DATA_ROOT}", allow_module_level=True)
if ev.cv2 is None:  # pragma: no cover
    pytest.skip("OpenCV (cv2) is not installed", allow_module_level=True)

#: a few pairs per data set (about 30 s on two cores, mostly SIFT on the DGP images)
SUBSET = {
    "kitti_raw": [(0, 1), (2, 3), (3, 4)],
    "kitti00_tracks": [(20, 21), (50, 51)],
    "dgp_scene_02": [(0, 1)],
    "euroc": [(0, 1), (12, 13), (22, 23)],
    "dgp_scene_01": [(0, 1)],
}
MOVING = ("kitti_raw", "kitti00_tracks", "dgp_scene_02")
STATIC = ("euroc", "dgp_scene_01")
STEREO = ("kitti_raw", "kitti00_tracks")
MAX_ROT_ERR_DEG = 1.0
MAX_TDIR_ERR_DEG = 10.0
MAX_SCALE_ERR = 0.10
#: a static rig may come out "observable" only with |t| below this (metres)
MAX_STATIC_T = 0.03

#: (key, pair, mode, check) -> diagnosis of a known weakness (none open). Fixed so far:
#: KITTI raw 2-3 intra-only, where the refinement slid |t| to 4.5 mm and the rotation-
#: induced shift of the camera centres turned the reported direction by 131 deg (now the
#: direction of travel of the cameras is reported, mcgeom.observability.travel_direction).
KNOWN: dict = {}


def _cases(keys, modes, check):
    out = []
    for key in keys:
        for pair in SUBSET[key]:
            for mode in modes:
                why = KNOWN.get((key, pair, mode, check))
                marks = [pytest.mark.xfail(strict=False, reason=why)] if why else []
                out.append(pytest.param(key, pair, mode, marks=marks,
                                        id="%s-%d-%d-%s" % (key, *pair, mode)))
    return out


@pytest.fixture(scope="module")
def results() -> dict:
    ev.cv2.setNumThreads(2)
    seqs = ev.load_sequences(tuple(SUBSET), pairs=SUBSET)
    out = {}
    for seq in seqs:
        feats = ev.Features(seq.nfeatures) if seq.kind == "images" else None
        for k1, k2 in seq.pairs:
            corr = ev.correspondences(seq, k1, k2, feats)
            for mode in ev.MODES:
                out[seq.key, (k1, k2), mode] = ev.evaluate_pair(seq, corr, k1, k2, mode)
    return out


def _describe(r: dict) -> str:
    if not r["ok"]:
        return "%s %d-%d %s: FAILED %s" % (r["key"], *r["pair"], r["mode"], r["error"])
    return ("%s %d-%d %s: rot err %.3f deg, t dir err %.2f deg, |t_est| %.4f m (GT %.4f), "
            "%s" % (r["key"], *r["pair"], r["mode"], r["rot_err"], r["tdir_err"], r["t_est"],
                    r["t_gt"], r["reason"]))


def _row(results: dict, key: str, pair: tuple, mode: str) -> dict:
    r = results[key, pair, mode]
    assert r["ok"], _describe(r)
    return r


@pytest.mark.parametrize("key, pair, mode", _cases(MOVING, ev.MODES, "rotation"))
def test_rotation_close_to_ground_truth(results, key, pair, mode):
    r = _row(results, key, pair, mode)
    assert r["rot_err"] < MAX_ROT_ERR_DEG, _describe(r)


@pytest.mark.parametrize("key, pair, mode", _cases(MOVING, ev.MODES, "direction"))
def test_direction_of_travel(results, key, pair, mode):
    r = _row(results, key, pair, mode)
    assert r["tdir_err"] < MAX_TDIR_ERR_DEG, _describe(r)


@pytest.mark.parametrize("key, pair, mode", _cases(STEREO, ["intra+cross"], "scale"))
def test_stereo_rig_gives_metric_scale(results, key, pair, mode):
    r = _row(results, key, pair, mode)
    assert r["observable"], _describe(r)
    assert r["scale_err"] < MAX_SCALE_ERR, _describe(r)


@pytest.mark.parametrize("key, pair, mode", _cases(MOVING, ev.MODES, "confident"))
def test_observable_verdict_has_the_right_scale(results, key, pair, mode):
    r = _row(results, key, pair, mode)
    if r["observable"]:
        assert r["scale_err"] < MAX_SCALE_ERR, _describe(r)


@pytest.mark.parametrize("key, pair, mode", _cases(STATIC, ev.MODES, "static"))
def test_static_rig_is_not_a_confident_metric_translation(results, key, pair, mode):
    r = _row(results, key, pair, mode)
    assert r["rot_err"] < MAX_ROT_ERR_DEG, _describe(r)
    if r["observable"]:
        assert np.linalg.norm(r["motion"].t) < MAX_STATIC_T, _describe(r)


def test_ground_truth_convention():
    """inv(relative_pose) is rig2_from_rig1: tracked stereo correspondences fit it to a
    pixel, and cross-camera ones do not fit the opposite convention."""
    seq = ev.load_sequences(("kitti00_tracks",), pairs={"kitti00_tracks": [(30, 31)]})[0]
    corr = ev.correspondences(seq, 30, 31)
    g = ev.gt_check(seq, corr, 30, 31)
    assert g["intra_med"] < 1.0 and g["cross_med"] < 1.0, g
    assert g["cross_med_wrong"] > 3 * g["cross_med"], g


def test_kitti_raw_vertical_from_the_ins_and_the_upright_sampler_on_it():
    """KITTI raw's vertical (OXTS roll and pitch, ``Sequence.vertical``) is the
    same physical direction at both frames under the ground-truth motion, and
    the façade given it runs the upright sampler with 5+1's answer: the
    rotation within 0.05 deg of it, intra-camera only not observable (driving
    straight), with the stereo pairs metric within 10 % of the truth."""
    seq = ev.load_sequences(("kitti_raw",), pairs={"kitti_raw": [(2, 3)]})[0]
    assert seq.vertical is not None and "OXTS" in seq.vertical_name
    g1, g2 = seq.vertical(2), seq.vertical(3)
    R_gt, _ = seq.gt_motion(2, 3)
    np.testing.assert_allclose(np.linalg.norm(g1), 1.0, atol=1e-12)
    np.testing.assert_allclose(R_gt @ g1, g2, atol=1e-9)
    corr = ev.correspondences(seq, 2, 3, ev.Features(seq.nfeatures))
    for mode in ev.MODES:
        up = ev.evaluate_pair(seq, corr, 2, 3, mode, gravity1=g1, gravity2=g2)
        ref = ev.evaluate_pair(seq, corr, 2, 3, mode)
        assert up["ok"] and up["sampler"] == "upright_four_point", _describe(up)
        assert ref["sampler"] == "five_plus_one"
        assert abs(up["rot_err"] - ref["rot_err"]) < 0.05, (_describe(up), _describe(ref))
        assert up["observable"] == (mode == "intra+cross"), _describe(up)
        if up["observable"]:
            assert up["scale_err"] < MAX_SCALE_ERR, _describe(up)
