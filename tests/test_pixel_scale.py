"""``_core.sampson_pixel_scale`` (csrc/pixel_scale.c), the pixels per radian of each
Sampson residual that ``mcgeom.pixel_noise.sampson_pixel_scale`` returns, against the numpy
implementation it replaced (tests/test_motion_focal.py checks the result against
the image-plane Sampson error itself)."""

from __future__ import annotations

import numpy as np
import pytest

from mcgeom import _core, synth
from mcgeom.pixel_noise import pixels_per_radian, sampson_pixel_scale


def _rows(a, b):
    return np.einsum("ij,ij->i", a, b)


def _reference(rig, rays, R, t):
    """The numpy version of ``sampson_pixel_scale(rig)(rays, R, t)`` (unit bearings)."""
    Ks = rig.intrinsics
    focal = 0.5 * (Ks[:, 0, 0] + Ks[:, 1, 1])
    axes = rig.rotations[:, 2, :]
    a = rays.dirs1 @ R.T
    c = t + rays.origins1 @ R.T - rays.origins2
    d2 = rays.dirs2
    g2 = np.cross(c, a)
    g2 -= _rows(g2, d2)[:, None] * d2
    g1 = np.cross(d2, c)
    g1 -= _rows(g1, a)[:, None] * a
    ax1, ax2 = axes[rays.cam1] @ R.T, axes[rays.cam2]
    n1, n2 = _rows(g1, g1), _rows(g2, g2)
    var = ((_rows(a, ax1) / focal[rays.cam1]) ** 2 * (n1 - _rows(g1, ax1) ** 2) +
           (_rows(d2, ax2) / focal[rays.cam2]) ** 2 * (n2 - _rows(g2, ax2) ** 2))
    ok = var > 1e-12 * (n1 + n2) / np.square(focal).max()
    f = np.sqrt((n1 + n2) / np.where(ok, var, 1.0))
    f[~ok] = pixels_per_radian(rig, rays)[~ok]
    return f


@pytest.mark.parametrize("seed", range(6))
def test_matches_numpy_reference(seed):
    rng = np.random.default_rng(seed)
    rig = synth.ladybug2() if seed % 2 else synth.generic_rig(4, rng)
    R = synth.random_rotation(rng, 0.3)
    t = rng.normal(size=3)
    p = synth.make_problem(rig, R, t, 200, rng, pixel_noise=1.0, outlier_fraction=0.2)
    rays = rig.ray_pairs(p.pixels1, p.pixels2, p.cam1, p.cam2)
    got = sampson_pixel_scale(rig)(rays, R, t)
    np.testing.assert_allclose(got, _reference(rig, rays, R, t), rtol=1e-10)


def test_static_camera_falls_back_to_the_effective_focal():
    """R = I, t = 0: no pair constrains the motion; the lens' average is kept."""
    rng = np.random.default_rng(7)
    rig = synth.ladybug2()
    p = synth.make_problem(rig, np.eye(3), np.array([0.0, 0.0, 1.0]), 60, rng)
    rays = rig.ray_pairs(p.pixels1, p.pixels2, p.cam1, p.cam2)
    intra = rays.take(rays.cam1 == rays.cam2)
    got = sampson_pixel_scale(rig)(intra, np.eye(3), np.zeros(3))
    np.testing.assert_array_equal(got, pixels_per_radian(rig, intra))


def test_bad_input_names_the_problem():
    rng = np.random.default_rng(1)
    o = rng.normal(size=(5, 3))
    d = rng.normal(size=(5, 3))
    z = np.tile([0.0, 0.0, 1.0], (5, 1))
    f = np.full(5, 500.0)
    args = [o, d, o, d, np.eye(3), np.ones(3), z, z, f, f]
    bad = list(args)
    bad[8] = np.r_[f[:4], 0.0]
    with pytest.raises(ValueError, match="focal1"):
        _core.sampson_pixel_scale(*bad)
    bad = list(args)
    bad[6] = z.copy()
    bad[6][2, 1] = np.nan
    with pytest.raises(ValueError, match="axes1 contains NaN"):
        _core.sampson_pixel_scale(*bad)
    with pytest.raises(ValueError, match="min_var_ratio"):
        _core.sampson_pixel_scale(*args, min_var_ratio=-1.0)
    with pytest.raises(ValueError, match="shape"):
        _core.sampson_pixel_scale(*args[:8], f[:4], f)
