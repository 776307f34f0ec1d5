"""mcgeom.pixel_noise.sampson_pixel_scale: pixels per radian of each correspondence's Sampson
residual at a motion, so that the final refinement of the robust pipeline
weighs residuals as the image-plane Sampson error (the first-order maximum
likelihood residual for isotropic pixel noise). Checked against that error
computed independently: the epipolar constraint of each pair differentiated
numerically with respect to the four pixel coordinates."""

from __future__ import annotations

import numpy as np

from mcgeom import _core, synth
from mcgeom.pixel_noise import sampson_pixel_scale


def _image_sampson(rig, px1, px2, c1, c2, R, t, h=1e-4):
    """|e| / |de/dpixels| per correspondence, e = d2^T [t + R o1 - o2]x R d1."""
    def e(q1, q2):
        r = rig.ray_pairs(q1, q2, c1, c2)
        a = r.dirs1 @ R.T
        base = t + r.origins1 @ R.T - r.origins2
        return np.einsum("ij,ij->i", r.dirs2, np.cross(base, a))

    e0 = e(px1, px2)
    grad2 = np.zeros(len(px1))
    for which in (0, 1):
        for k in (0, 1):
            q = [px1.copy(), px2.copy()]
            q[which][:, k] += h
            plus = e(*q)
            q[which][:, k] -= 2 * h
            minus = e(*q)
            grad2 += ((plus - minus) / (2 * h)) ** 2
    return np.abs(e0) / np.sqrt(grad2)


def test_motion_focal_gives_the_image_plane_sampson_error():
    rng = np.random.default_rng(3)
    rig = synth.generic_rig(4, rng)
    R = synth.random_rotation(rng, 0.3)
    t = np.array([0.3, -0.1, 0.2])
    p = synth.make_problem(rig, R, t, 120, rng, pixel_noise=0.5, cross_fraction=0.3)
    r = rig.ray_pairs(p.pixels1, p.pixels2, p.cam1, p.cam2)
    ang = np.abs(_core.gec_residuals(r.origins1, r.dirs1, r.origins2, r.dirs2, R, t))
    f = sampson_pixel_scale(rig)(r, R, t)
    ref = _image_sampson(rig, p.pixels1, p.pixels2, p.cam1, p.cam2, R, t)
    ok = ref > 1e-3  # away from zero residuals, where the ratio is ill-conditioned
    assert ok.sum() > 100
    rel = np.abs(f[ok] * ang[ok] - ref[ok]) / ref[ok]
    assert np.median(rel) < 1e-3 and rel.max() < 2e-2, (np.median(rel), rel.max())
