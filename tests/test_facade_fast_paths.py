"""The checked-once paths of the robust façade (issue 19) give what the checked paths give.

``cv.estimate`` calls ``robust.ransac_prechecked`` with the rig's rays, pixel-noise
tables and calibration; ``robust.ransac`` checks everything itself. Same seed, same
answer, bit for bit: R, t, inliers, verdict and its figures. The fast paths inside
(the first rows of ``check_distinct``, the rays of both times sharing the per-camera
rows, the pinhole tables of the rig, the cached camera table) are checked against
the plain computations here.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from mcgeom import cv, registry, robust, synth
from mcgeom.errors import DegenerateError
from mcgeom.pixel_noise import camera_table, pixels_per_radian, sampson_pixel_scale
from mcgeom.types import RayPairs
from problems import turning_motion


def _problem(seed: int, make_rig=synth.ladybug2, n: int = 300, outliers: float = 0.3):
    rng = np.random.default_rng(seed)
    rig = make_rig()
    R, t = turning_motion(rng)
    p = synth.make_problem(rig, R, t, n, rng, pixel_noise=0.5, outlier_fraction=outliers,
                           cross_fraction=0.2)
    return rig, p


def _same(a, b) -> None:
    assert np.array_equal(a.R, b.R) and np.array_equal(a.t, b.t)
    assert np.array_equal(a.inliers, b.inliers)
    assert a.scale == b.scale or (a.scale.reason == b.scale.reason
                                  and a.scale.observable == b.scale.observable)
    for key in ("t_metric", "scale_rel_std_noise", "scale_rel_std_calibration", "covariance"):
        assert np.array_equal(a.info[key], b.info[key], equal_nan=True), key


@pytest.mark.parametrize("seed,make_rig", [(0, synth.ladybug2), (1, synth.vehicle8)])
def test_prechecked_search_is_the_checked_one(seed, make_rig):
    rig, p = _problem(seed, make_rig)
    rays = rig.ray_pairs(p.pixels1, p.pixels2, p.cam1, p.cam2)
    f = pixels_per_radian(rig, rays)
    kw = dict(focal=f, motion_focal=sampson_pixel_scale(rig), calibration_std=rig.extrinsic_std,
              pixel_cameras=camera_table(rig))
    a = robust.ransac(rays, "five_plus_one", threshold=1.0, seed=seed, **kw)
    b = robust.ransac_prechecked(rays, "five_plus_one",
                                 robust.RansacOptions(threshold=1.0, seed=seed), f,
                                 kw["motion_focal"], kw["calibration_std"], kw["pixel_cameras"])
    _same(a, b)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        c = cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, rig, threshold=1.0, seed=seed)
    _same(a, c)


def test_rays_of_both_times_with_the_same_ids_equal_separate_ones():
    rig, p = _problem(2)
    same = rig.ray_pairs(p.pixels1, p.pixels2, p.cam1)              # cam2 = cam1 (shared rows)
    apart = rig.ray_pairs(p.pixels1, p.pixels2, p.cam1, p.cam1.copy())
    for name in ("origins1", "dirs1", "origins2", "dirs2", "cam1", "cam2"):
        assert np.array_equal(getattr(same, name), getattr(apart, name)), name
        assert getattr(same, name).flags.c_contiguous
    assert same.origins1 is not same.origins2 and same.cam1 is not same.cam2
    # the pinhole bearings are those of each camera's own conversion
    for i in range(len(rig)):
        sel = p.cam1 == i
        assert np.allclose(same.dirs1[sel], rig.cameras[i].pixels_to_bearings(p.pixels1[sel]),
                           atol=1e-15)


def test_camera_table_is_the_rigs_read_only():
    rig = synth.vehicle8()
    focal, axes = camera_table(rig)
    assert np.array_equal(focal, 0.5 * (rig.intrinsics[:, 0, 0] + rig.intrinsics[:, 1, 1]))
    assert np.array_equal(axes, rig.rotations[:, 2, :]) and axes.flags.c_contiguous
    with pytest.raises(ValueError):
        axes[0, 0] = 1.0          # shared by every estimate of the rig: not writable


def _rays(rows: np.ndarray) -> RayPairs:
    k = len(rows)
    return RayPairs(rows[:, :3], rows[:, 3:6], rows[:, 6:9], rows[:, 9:12],
                    np.zeros(k, np.int64), np.zeros(k, np.int64))


def test_check_distinct_fast_path_agrees_with_the_count():
    rng = np.random.default_rng(3)
    base = rng.normal(size=(8, 12))
    # repeats among the first six but enough distinct further on: no error
    rows = np.concatenate([base[[0, 0, 1, 1, 2, 2]], base[3:]])
    registry.check_distinct(_rays(rows), 6, "x")
    # five distinct among 30: DegenerateError naming the count
    rows = base[np.arange(30) % 5]
    with pytest.raises(DegenerateError, match="only 5 distinct"):
        registry.check_distinct(_rays(rows), 6, "x")
    # -0.0 and 0.0 are the same value (as the count compares)
    z = np.zeros((6, 12))
    z[::2, 0] = -0.0
    z[:, 1] = [1, 1, 2, 2, 3, 3]
    with pytest.raises(DegenerateError, match="only 3 distinct"):
        registry.check_distinct(_rays(z), 6, "x")


# ---- the C input stage of the façade (csrc/pixel_rays.c, issue 19)

def _ppr_reference(rig, rays) -> np.ndarray:
    """Pixels per radian straight from the model of mcgeom.pixel_noise (an
    independent spelling: the angle to each camera's axis, then cos^4 + cos^2
    per bearing, averaged over both bearings)."""
    focal = 0.5 * (rig.intrinsics[:, 0, 0] + rig.intrinsics[:, 1, 1])
    axes = rig.rotations[:, 2, :]
    var = np.zeros(len(rays))
    for ids, d in ((rays.cam1, rays.dirs1), (rays.cam2, rays.dirs2)):
        theta = np.arccos(np.clip(np.sum(axes[ids] * d, axis=1), -1.0, 1.0))
        c = np.clip(np.cos(theta), 1e-3, 1.0)
        var += (c ** 4 + c ** 2) / (2.0 * focal[ids] ** 2)
    return 1.0 / np.sqrt(var / 2.0)


@pytest.mark.parametrize("seed,make_rig", [(0, synth.ladybug2), (1, synth.vehicle8),
                                           (2, synth.ladybug2), (3, synth.vehicle8)])
@pytest.mark.parametrize("same_ids", [False, True])
def test_c_input_stage_is_the_numpy_one(seed, make_rig, same_ids):
    """One C pass gives the rays of Rig.ray_pairs_prechecked and the pixels per
    radian of pixel_noise.pixels_per_radian bit for bit, and the latter match
    the model spelled independently."""
    from mcgeom.pixel_noise import ray_pairs_per_radian
    rig, p = _problem(seed, make_rig)
    assert rig.pinhole_tables is not None
    px1, px2 = (np.ascontiguousarray(a, dtype=np.float64) for a in (p.pixels1, p.pixels2))
    ids1 = np.asarray(p.cam1, np.int64)
    ids2 = ids1 if same_ids else np.asarray(p.cam2, np.int64)
    if same_ids:   # pixels of the same cameras at both times (cross pairs re-labelled)
        px2 = px2.copy()
    rays, f = ray_pairs_per_radian(rig, px1, px2, ids1, ids2)
    ref = rig.ray_pairs_prechecked(px1, px2, ids1, ids2)
    for name in ("origins1", "dirs1", "origins2", "dirs2", "cam1", "cam2"):
        a, b = getattr(rays, name), getattr(ref, name)
        assert a.dtype == b.dtype and a.flags.c_contiguous and np.array_equal(a, b), name
    assert rays.cam2 is not rays.cam1
    assert np.array_equal(f, pixels_per_radian(rig, ref))
    np.testing.assert_allclose(f, _ppr_reference(rig, ref), rtol=1e-12)


def _distorted(rig):
    """The rig with a small radial distortion on camera 1 (the general path)."""
    from dataclasses import replace
    from mcgeom.rig import Rig
    cams = list(rig.cameras)
    cams[1] = replace(cams[1], dist=np.array([0.01, 0.0, 0.0, 0.0]))
    return Rig(tuple(cams), rig.calibration_std)


def test_distorted_rig_takes_the_general_input_path():
    from mcgeom.pixel_noise import ray_pairs_per_radian
    rig, p = _problem(4)
    drig = _distorted(rig)
    assert drig.pinhole_tables is None
    px1, px2 = (np.ascontiguousarray(a, dtype=np.float64) for a in (p.pixels1, p.pixels2))
    ids1, ids2 = np.asarray(p.cam1, np.int64), np.asarray(p.cam2, np.int64)
    rays, f = ray_pairs_per_radian(drig, px1, px2, ids1, ids2)
    ref = drig.ray_pairs_prechecked(px1, px2, ids1, ids2)
    assert np.array_equal(rays.dirs1, ref.dirs1) and np.array_equal(rays.dirs2, ref.dirs2)
    assert np.array_equal(f, pixels_per_radian(drig, ref))
    # camera 1's bearings are not the pinhole ones: the distortion was applied
    sel = p.cam1 == 1
    assert sel.any() and not np.allclose(rays.dirs1[sel], rig.ray_pairs(
        p.pixels1, p.pixels2, p.cam1, p.cam2).dirs1[sel], atol=1e-9)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, drig, threshold=2.0, seed=0)
    assert m.inliers.sum() > 100


@pytest.mark.parametrize("model", ["pinhole", "fisheye"])
@pytest.mark.parametrize("same_ids", [False, True])
def test_distorted_pairs_in_one_call_per_camera_are_the_per_time_ones(model, same_ids):
    """Rig._distorted_pairs (both times in one OpenCV call per camera) gives
    the bearings of one call per camera and time bit for bit, and a pixel
    without a ray is named as before (the per-time path names it)."""
    from dataclasses import replace
    from mcgeom.rig import Rig
    rig, p = _problem(6)
    dist = np.array([0.004, 0.001, 0.0, 0.0]) if model == "fisheye" else \
        np.array([0.03, -0.01, 0.001, 0.0005, 0.0])
    cams = [c if k == 2 else replace(c, model=model, dist=dist) for k, c in enumerate(rig.cameras)]
    drig = Rig(tuple(cams), rig.calibration_std)
    px1, px2 = (np.ascontiguousarray(a, dtype=np.float64) for a in (p.pixels1, p.pixels2))
    ids1 = np.asarray(p.cam1, np.int64)
    ids2 = ids1 if same_ids else np.asarray(p.cam2, np.int64)
    rays = drig.ray_pairs_prechecked(px1, px2, ids1, ids2)
    o1, d1 = drig._rays_checked(ids1, px1, {})
    o2, d2 = drig._rays_checked(ids2, px2, None)
    for a, b in ((rays.dirs1, d1), (rays.dirs2, d2), (rays.origins1, o1), (rays.origins2, o2)):
        assert a.flags.c_contiguous and np.array_equal(a, b)
    assert rays.cam2 is not rays.cam1 and rays.origins2 is not rays.origins1
    # only the undistorted camera 2 used: the all-at-once pinhole arithmetic
    sel = np.flatnonzero((ids1 == 2) & (ids2 == 2))
    assert sel.size >= 6
    plain = drig.ray_pairs_prechecked(px1[sel], px2[sel], ids1[sel], ids2[sel])
    assert np.array_equal(plain.dirs1, drig._rays_checked(ids1[sel], px1[sel], {})[1])
    far = px2.copy()
    far[9] = (1e300, 1e300) if model == "pinhole" else (1e7, 1e7)
    with pytest.raises(ValueError) as got:
        drig.ray_pairs_prechecked(px1, far, ids1, ids2)
    with pytest.raises(ValueError) as want:
        drig._rays_checked(ids2, far, None)
    assert str(got.value) == str(want.value)


def test_c_input_stage_refuses_what_the_numpy_path_names():
    """Input the C pass refuses (an id outside the rig, a pixel without a
    finite bearing) returns None from _core: the rig's path names it."""
    from mcgeom import _core
    from mcgeom.pixel_noise import ray_pairs_per_radian
    rig, p = _problem(5)
    intr, rot, centres, focal = rig.pinhole_tables
    px1, px2 = (np.ascontiguousarray(a, dtype=np.float64) for a in (p.pixels1, p.pixels2))
    ids = np.asarray(p.cam1, np.int64)
    assert _core.pinhole_ray_pairs(intr, rot, centres, focal, ids, ids, px1, px2) is not None
    bad_ids = ids.copy()
    bad_ids[7] = len(rig)
    assert _core.pinhole_ray_pairs(intr, rot, centres, focal, bad_ids, ids, px1, px2) is None
    huge = px2.copy()
    huge[3] = 1e300
    assert _core.pinhole_ray_pairs(intr, rot, centres, focal, ids, ids, px1, huge) is None
    with pytest.raises(ValueError, match="no finite bearing"):
        ray_pairs_per_radian(rig, px1, huge, ids, ids)
    # without focal: the rays only, the same ones
    o1, d1, o2, d2, none = _core.pinhole_ray_pairs(intr, rot, centres, None, ids, ids, px1, px2)
    assert none is None
    ref = rig.ray_pairs_prechecked(px1, px2, ids, ids)
    assert np.array_equal(d1, ref.dirs1) and np.array_equal(d2, ref.dirs2)
    assert np.array_equal(o1, ref.origins1) and np.array_equal(o2, ref.origins2)


@pytest.mark.parametrize("seed", range(3))
def test_facade_with_mask_and_calibration_is_the_general_path(seed):
    """cv.estimate (C input stage, masked pairs' pixels per radian taken from
    all of them) equals robust.ransac on the rig's rays of the kept pairs."""
    rig, p = _problem(10 + seed)
    mask = np.random.default_rng(seed).random(len(p.cam1)) > 0.25
    cal = (0.002, 0.001)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        c = cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, rig, threshold=1.0, seed=seed,
                        mask=mask, calibration_std=cal)
    rays = rig.ray_pairs(p.pixels1, p.pixels2, p.cam1, p.cam2).take(np.flatnonzero(mask))
    from mcgeom.rig import Rig
    a = robust.ransac(rays, "five_plus_one", threshold=1.0, seed=seed,
                      focal=pixels_per_radian(rig, rays), motion_focal=sampson_pixel_scale(rig),
                      calibration_std=Rig(rig.cameras, cal).extrinsic_std,
                      pixel_cameras=camera_table(rig))
    assert np.array_equal(c.inliers[mask], a.inliers) and not c.inliers[~mask].any()
    assert np.array_equal(a.R, c.R) and np.array_equal(a.t, c.t)
    assert a.scale.observable == c.scale.observable and a.scale.reason == c.scale.reason
    for key in ("t_metric", "scale_rel_std_noise", "scale_rel_std_calibration", "covariance"):
        assert np.array_equal(a.info[key], c.info[key], equal_nan=True), key


@pytest.mark.parametrize("seed,make_rig", [(2, synth.ladybug2), (3, synth.vehicle8)])
def test_plain_input_takes_the_one_call_path_with_the_same_answer(seed, make_rig, monkeypatch):
    """float64 pixels and int64 ids of a pinhole rig go through
    robust.estimate_pinhole_c (one C call, the sampler picked in C); anything else
    (here: ids as lists) through ransac_prechecked. Same answer, bit for bit."""
    rig, p = _problem(seed, make_rig)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        general = cv.estimate(p.pixels1, p.pixels2, list(p.cam1), list(p.cam2), rig,
                              threshold=1.0, seed=seed)
        calls = []
        monkeypatch.setattr(robust, "ransac_prechecked",
                            lambda *a, **k: calls.append(1) or pytest.fail("general path"))
        fast = cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, rig, threshold=1.0, seed=seed)
    assert not calls
    _same(general, fast)
    assert fast.info["sampler"] == general.info["sampler"] == "five_plus_one"


def test_forced_five_plus_one_takes_the_one_call_path_with_the_same_answer(monkeypatch):
    """method='ransac:five_plus_one' (5+1 forced) also runs in one C call,
    with the general path's answer bit for bit; where no camera has 5
    intra-camera correspondences the general path names the problem."""
    rig, p = _problem(6, synth.ladybug2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        general = cv.estimate(p.pixels1, p.pixels2, list(p.cam1), list(p.cam2), rig,
                              method="ransac:five_plus_one", threshold=1.0, seed=6)
        monkeypatch.setattr(robust, "ransac_prechecked",
                            lambda *a, **k: pytest.fail("general path"))
        fast = cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, rig,
                           method="ransac:five_plus_one", threshold=1.0, seed=6)
        monkeypatch.undo()
    _same(general, fast)
    assert fast.info["sampler"] == general.info["sampler"] == "five_plus_one"
    keep = np.concatenate([np.flatnonzero((p.cam1 == k) & (p.cam2 == k))[:4] for k in range(6)])
    with pytest.raises(ValueError, match="5 intra-camera"):
        cv.estimate(p.pixels1[keep], p.pixels2[keep], p.cam1[keep], p.cam2[keep], rig,
                    method="ransac:five_plus_one", threshold=1.0, seed=6)


def test_one_call_path_picks_the_six_point_sampler_as_choose_sampler():
    """Four correspondences per camera: no 5+1 sample; the C search's "auto"
    picks the 6-point solver, as cv.choose_sampler does."""
    rig, p = _problem(4, synth.ladybug2, n=300, outliers=0.0)
    keep = np.concatenate([np.flatnonzero((p.cam1 == k) & (p.cam2 == k))[:4] for k in range(6)]
                          + [np.flatnonzero(p.cam1 != p.cam2)[:20]])
    px1, px2 = p.pixels1[keep], p.pixels2[keep]
    c1, c2 = p.cam1[keep], p.cam2[keep]
    assert cv.choose_sampler(c1, c2) == "six_point"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = cv.estimate(px1, px2, c1, c2, rig, threshold=1.0, seed=1, maxIters=3)
    assert m.info["sampler"] == "six_point"


def test_one_call_path_declines_and_the_general_path_names():
    """A NaN pixel or an id outside the rig in otherwise plain input: the
    ray kernel refuses, and the general path's message names it."""
    rig, p = _problem(6)
    px = p.pixels2.copy()
    px[5] = np.nan
    with pytest.raises(ValueError, match="points2 contains NaN"):
        cv.estimate(p.pixels1, px, p.cam1, p.cam2, rig)
    ids = p.cam2.copy()
    ids[3] = len(rig)
    with pytest.raises(ValueError, match="cameraIds2 holds camera id 6"):
        cv.estimate(p.pixels1, p.pixels2, p.cam1, ids, rig)
    # repeated correspondences: the DegenerateError of check_distinct, as before
    rep = np.zeros(len(p.cam1), np.int64)
    with pytest.raises(DegenerateError, match="distinct"):
        cv.estimate(p.pixels1[rep], p.pixels2[rep], p.cam1[rep], p.cam2[rep], rig)


def test_one_call_path_with_a_vertical_prior_is_the_general_upright_search(monkeypatch):
    """gravity1/gravity2 with plain input: the upright sampler on the one-call
    path, the same answer as the general path; a bad vertical is named."""
    rig, p = _problem(7, synth.vehicle8, n=320, outliers=0.2)
    g1 = np.array([0.0, 0.0, -9.81])
    g2 = g1.copy()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        general = cv.estimate(p.pixels1, p.pixels2, list(p.cam1), list(p.cam2), rig,
                              threshold=1.0, seed=3, gravity1=g1, gravity2=g2)
        monkeypatch.setattr(robust, "ransac_prechecked",
                            lambda *a, **k: pytest.fail("general path"))
        fast = cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, rig, threshold=1.0, seed=3,
                           gravity1=g1, gravity2=g2)
    _same(general, fast)
    assert fast.info["sampler"] == general.info["sampler"] == "upright_four_point"
    with pytest.raises(ValueError, match="gravity2 has zero length"):
        cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, rig, gravity1=g1,
                    gravity2=np.zeros(3))
