/*
 * pixel_rays.c -- the rays of pixel correspondences of a rig of undistorted
 * pinhole cameras, and the pixels per radian of each pair's Sampson
 * residual: the input stage of the OpenCV-style façade (mcgeom.cv:
 * Rig.ray_pairs_prechecked, then mcgeom.pixel_noise.pixels_per_radian) in
 * one pass over the pairs, without numpy's ~25 array passes and their
 * temporaries (issue 19: ~0.15 ms of a 300-pair estimate outside C).
 *
 * Camera i (cam_from_rig rotation R_i, centre c_i, intrinsics fx, fy, cx,
 * cy, skew): pixel (u, v) has the normalised image point
 *     y = (v - cy) / fy,   x = (u - cx - skew y) / fx,
 * the unit bearing b = (x, y, 1) / |(x, y, 1)| in the camera and
 * R_i^T b in the rig frame (thesis ch. 2: a ray is its centre and its
 * direction). The arithmetic and its order are those of Rig._pinhole_rays
 * (numpy), so the rays are bit-identical to it.
 *
 * Pixels per radian (mcgeom.pixel_noise.pixels_per_radian, thesis eq. 8.15
 * with isotropic pixel noise): a pixel error at angle theta from the axis z_i
 * moves a bearing by cos^2(theta) / f radially and cos(theta) / f
 * tangentially (f = (fx + fy) / 2); the mean of the two directions'
 * variances over both bearings of a pair, var = ((c1^4 + c1^2) / (2 f1^2) +
 * (c2^4 + c2^2) / (2 f2^2)) / 2, gives 1 / sqrt(var), cos clipped to
 * [1e-3, 1]. c^4 is (c^2)^2 here and in the Python reference (numpy's
 * power may use another libm, SVML, on AVX-512 machines).
 */
#include "mcgeom.h"
#include "internal.h"

#include <math.h>
#include <stddef.h>

#define MAX_PAIRS (1 << 26)
#define MAX_CAMERAS (1 << 20)

/* the ray of pixel px of camera cam; 0 when it has no finite bearing */
static int pinhole_ray(const double *intr, const double *rot, const double *centres,
                       long long cam, const double px[2], double o[3], double d[3])
{
    const double *K = intr + 5 * cam, *R = rot + 9 * cam, *c = centres + 3 * cam;
    double x, y, nrm, b[3];
    int i;
    y = (px[1] - K[3]) / K[1];
    x = (px[0] - K[2] - K[4] * y) / K[0];
    /* (x^2 + y^2) + 1, as numpy's norm of the row (x, y, 1) */
    nrm = sqrt(x * x + y * y + 1.0);
    if (!(nrm < HUGE_VAL)) /* overflowed (pixels ~1e300) or NaN */
        return 0;
    b[0] = x / nrm;
    b[1] = y / nrm;
    b[2] = 1.0 / nrm;
    for (i = 0; i < 3; i++) {
        /* R^T b, summed in the order of numpy's einsum("nji,nj->ni") */
        d[i] = R[i] * b[0] + R[3 + i] * b[1] + R[6 + i] * b[2];
        o[i] = c[i];
    }
    /* a table of huge entries (not a rotation) can overflow R^T b: found
     * by fuzz_pixel_rays */
    return all_finite(d, 3);
}

/* half the mean pixel-noise variance (radians^2 per pixel^2) of a bearing d
 * of a camera with optical axis z (rig frame) and mean focal f */
static double bearing_var(const double *d, const double *z, double f)
{
    double cz = z[0] * d[0] + z[1] * d[1] + z[2] * d[2], c2;
    cz = cz > 1e-3 ? cz : 1e-3;
    cz = cz < 1.0 ? cz : 1.0;
    c2 = cz * cz;
    return 0.5 * (c2 * c2 + c2) / (f * f);
}

int mcg_pinhole_ray_pairs(int n, int m, const double *intr, const double *rot,
                          const double *centres, const double *focal, const long long *ids1,
                          const long long *ids2, const double *px1, const double *px2,
                          double *o1, double *d1, double *o2, double *d2, double *ppr,
                          int *bad)
{
    int k, i;
    if (!intr || !rot || !centres || !ids1 || !ids2 || !px1 || !px2 || !o1 || !d1 || !o2 ||
        !d2 || !bad || (ppr && !focal))
        return MCG_EINVAL;
    *bad = -1;
    if (n < 0 || n > MAX_PAIRS || m < 1 || m > MAX_CAMERAS)
        return MCG_EINVAL;
    /* the tables: finite, focal lengths > 0 (a division by fx, fy, f) */
    if (!all_finite(intr, (size_t)5 * m) || !all_finite(rot, (size_t)9 * m) ||
        !all_finite(centres, (size_t)3 * m))
        return MCG_EINVAL;
    for (i = 0; i < m; i++) {
        if (!(intr[5 * i] != 0.0 && intr[5 * i + 1] != 0.0))
            return MCG_EINVAL;
        if (ppr && !(isfinite(focal[i]) && focal[i] > 0.0))
            return MCG_EINVAL;
    }
    for (k = 0; k < n; k++) {
        long long c1 = ids1[k], c2 = ids2[k];
        if (c1 < 0 || c1 >= m || c2 < 0 || c2 >= m || !all_finite(px1 + 2 * k, 2) ||
            !all_finite(px2 + 2 * k, 2))
            return MCG_EINVAL;
        if (!pinhole_ray(intr, rot, centres, c1, px1 + 2 * k, o1 + 3 * k, d1 + 3 * k)) {
            *bad = k;
            return MCG_EINVAL;
        }
        if (!pinhole_ray(intr, rot, centres, c2, px2 + 2 * k, o2 + 3 * k, d2 + 3 * k)) {
            *bad = n + k;
            return MCG_EINVAL;
        }
        if (ppr) {
            /* the optical axis is row 2 of cam_from_rig */
            double v = bearing_var(d1 + 3 * k, rot + 9 * c1 + 6, focal[c1]) +
                       bearing_var(d2 + 3 * k, rot + 9 * c2 + 6, focal[c2]);
            v *= 0.5;
            ppr[k] = 1.0 / sqrt(v);
            /* focal lengths beyond ~1e+-150 px: f^2 overflowed or vanished */
            if (!(ppr[k] > 0.0 && ppr[k] < HUGE_VAL))
                return MCG_EINVAL;
        }
    }
    return MCG_OK;
}
