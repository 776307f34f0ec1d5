/*
 * rotations.c -- the rotation helpers of libmcgeom (declared in the linalg.c
 * section of mcgeom.h): Rodrigues' angle-axis map and its inverse,
 * Hamilton unit quaternions, and the projection of a 3 x 3 matrix onto SO(3)
 * (the nearest rotation in the Frobenius norm, from its SVD: the step after
 * the E / R decomposition of thesis ch. 8.4). Row-major, no allocation.
 */
#include "mcgeom.h"
#include "internal.h"

#include <float.h>
#include <math.h>
#include <string.h>

int mcg_rot_from_angle_axis(const double w[3], double r[9])
{
    double theta, k[3], c, s, h;
    size_t i, j;
    if (w == NULL || r == NULL || !all_finite(w, 3))
        return MCG_EINVAL;
    theta = norm_scaled(w, 3);
    if (!isfinite(theta))
        return MCG_EINVAL; /* |w| > DBL_MAX: the angle overflows (found by fuzz_linalg) */
    if (theta == 0.0) {
        for (i = 0; i < 9; ++i)
            r[i] = (i % 4 == 0) ? 1.0 : 0.0;
        return MCG_OK;
    }
    for (i = 0; i < 3; ++i)
        k[i] = w[i] / theta; /* accurate unit axis even for tiny theta */
    /* Rodrigues: R = cos t I + sin t [k]x + (1 - cos t) k k^T, with
     * 1 - cos t = 2 sin^2(t/2) to avoid cancellation for small angles */
    c = cos(theta);
    s = sin(theta);
    h = 2.0 * sin(0.5 * theta) * sin(0.5 * theta);
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j)
            r[i * 3 + j] = h * k[i] * k[j] + (i == j ? c : 0.0);
    r[1] -= s * k[2];
    r[2] += s * k[1];
    r[3] += s * k[2];
    r[5] -= s * k[0];
    r[6] -= s * k[1];
    r[7] += s * k[0];
    return MCG_OK;
}

/* Quaternion of a rotation by Shepperd's / Markley's method: build the
 * candidate from the largest of (trace, r00, r11, r22), which is never small,
 * so the result is accurate for every angle including 0 and pi. */
static void quat_of_rotation(const double r[9], double q[4])
{
    double tr = r[0] + r[4] + r[8], nq;
    size_t i;
    if (tr >= r[0] && tr >= r[4] && tr >= r[8]) {
        q[0] = 1.0 + tr;
        q[1] = r[7] - r[5];
        q[2] = r[2] - r[6];
        q[3] = r[3] - r[1];
    } else if (r[0] >= r[4] && r[0] >= r[8]) {
        q[0] = r[7] - r[5];
        q[1] = 1.0 + 2.0 * r[0] - tr;
        q[2] = r[1] + r[3];
        q[3] = r[2] + r[6];
    } else if (r[4] >= r[8]) {
        q[0] = r[2] - r[6];
        q[1] = r[1] + r[3];
        q[2] = 1.0 + 2.0 * r[4] - tr;
        q[3] = r[5] + r[7];
    } else {
        q[0] = r[3] - r[1];
        q[1] = r[2] + r[6];
        q[2] = r[5] + r[7];
        q[3] = 1.0 + 2.0 * r[8] - tr;
    }
    nq = norm_scaled(q, 4); /* >= 1 for a rotation: the chosen entry is */
    if (q[0] < 0.0)
        nq = -nq;
    for (i = 0; i < 4; ++i)
        q[i] /= nq;
}

int mcg_angle_axis_from_rot(const double r[9], double w[3])
{
    double q[4], nv, f;
    size_t i;
    if (r == NULL || w == NULL || !all_finite(r, 9))
        return MCG_EINVAL;
    if (!is_rotation(r))
        return MCG_EINVAL;
    quat_of_rotation(r, q);
    /* angle = 2 atan2(|v|, q0) is well conditioned everywhere (unlike acos
     * near 0 or asin near pi); q0 >= 0 gives angle in [0, pi] */
    nv = norm_scaled(q + 1, 3);
    if (nv == 0.0) {
        w[0] = w[1] = w[2] = 0.0;
        return MCG_OK;
    }
    f = 2.0 * atan2(nv, q[0]) / nv;
    for (i = 0; i < 3; ++i)
        w[i] = f * q[i + 1];
    return MCG_OK;
}

int mcg_rot_from_quat(const double q[4], double r[9])
{
    double nq, w, x, y, z;
    if (q == NULL || r == NULL || !all_finite(q, 4))
        return MCG_EINVAL;
    /* normalised through q / max|q_i| (exact ratios, all <= 1): dividing by
     * the norm itself would round it to a denormal for a denormal q, and the
     * matrix would be orthogonal only to that precision (fuzz finding 12) */
    nq = max_abs(q, 4);
    if (nq == 0.0)
        return MCG_EINVAL;
    w = q[0] / nq;
    x = q[1] / nq;
    y = q[2] / nq;
    z = q[3] / nq;
    nq = sqrt(w * w + x * x + y * y + z * z); /* in [1, 2] */
    w /= nq;
    x /= nq;
    y /= nq;
    z /= nq;
    r[0] = 1.0 - 2.0 * (y * y + z * z);
    r[1] = 2.0 * (x * y - w * z);
    r[2] = 2.0 * (x * z + w * y);
    r[3] = 2.0 * (x * y + w * z);
    r[4] = 1.0 - 2.0 * (x * x + z * z);
    r[5] = 2.0 * (y * z - w * x);
    r[6] = 2.0 * (x * z - w * y);
    r[7] = 2.0 * (y * z + w * x);
    r[8] = 1.0 - 2.0 * (x * x + y * y);
    return MCG_OK;
}

int mcg_quat_from_rot(const double r[9], double q[4])
{
    if (r == NULL || q == NULL || !all_finite(r, 9))
        return MCG_EINVAL;
    if (!is_rotation(r))
        return MCG_EINVAL;
    quat_of_rotation(r, q);
    return MCG_OK;
}

int mcg_project_so3(const double m[9], double r[9])
{
    double u[9], s[3], v[9], work[64], d;
    size_t i, j;
    int st;
    if (m == NULL || r == NULL || !all_finite(m, 9))
        return MCG_EINVAL;
    if (mcg_svd_work_size(3, 3) > sizeof work / sizeof work[0])
        return MCG_ENOMEM; /* cannot happen; keeps the stack bound honest */
    st = mcg_svd(3, 3, m, u, s, v, work, sizeof work / sizeof work[0]);
    if (st != MCG_OK)
        return st;
    /* With rank >= 2 the polar factor with det +1, U diag(1, 1, d) V^T, is
     * unique; with rank <= 1 a whole family of rotations is equally near. */
    if (!(s[1] > 4.0 * DBL_EPSILON * s[0]))
        return MCG_EDEGENERATE;
    d = (det33(u) * det33(v) < 0.0) ? -1.0 : 1.0;
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j)
            r[i * 3 + j] = u[i * 3 + 0] * v[j * 3 + 0] +
                           u[i * 3 + 1] * v[j * 3 + 1] +
                           d * u[i * 3 + 2] * v[j * 3 + 2];
    return MCG_OK;
}
