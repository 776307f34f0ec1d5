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
