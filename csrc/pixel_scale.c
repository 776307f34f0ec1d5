/*
 * pixel_scale.c -- pixels per radian of each pair's Sampson angular residual
 * at a motion, for pinhole cameras: the weights that turn the angular
 * Sampson error of mcg_gec_residuals into the image-plane Sampson error
 * (thesis eq. 8.15 with isotropic pixel noise propagated to first order),
 * the hot loop of the final refinement of mcgeom.cv.
 *
 * With unit bearings a = R d1, d2, the pair's baseline c = t + R o1 - o2 and
 * the tangent gradients of e = d2 . (c x a),
 *     g1 = P(a) (d2 x c),   g2 = P(d2) (c x a),   P(v) = I - v v^T,
 * the angular residual is e / sqrt(|g1|^2 + |g2|^2); unit pixel noise in
 * camera k (focal f_k, optical axis z_k, cos theta_k = bearing . z_k) moves a
 * bearing by cos^2 / f radially and cos / f tangentially, hence e by the
 * variance V = sum_k (cos_k / f_k)^2 (|g_k|^2 - (g_k . z_k)^2); the pixel
 * residual is e / sqrt(V), and the scale sqrt((|g1|^2 + |g2|^2) / V).
 */
#include "mcgeom.h"
#include "internal.h"

#include <math.h>
#include <stddef.h>

#define MAX_PAIRS (1 << 26)
#define DIR2_MIN 1e-100 /* smallest squared length of a direction */

/* (MCG_AVX2_CLONE, internal.h: the same bits, a quarter fewer instructions
 * on an AVX2 CPU; issue 19. Static behind the plain public function: a
 * cloned public function would export its ifunc resolver too, and
 * libmcgeom.so exports the functions of mcgeom.h only, .ci/c_checks.) */
MCG_AVX2_CLONE
static int pixel_scale(int n, const double *o1, const double *d1, const double *o2,
                       const double *d2, const double R[9], const double t[3],
                       const double *axis1, const double *axis2, const double *f1,
                       const double *f2, double min_var_ratio, double *scale)
{
    int k, i;
    if (!o1 || !d1 || !o2 || !d2 || !R || !t || !axis1 || !axis2 || !f1 || !f2 || !scale)
        return MCG_EINVAL;
    if (n < 0 || n > MAX_PAIRS)
        return MCG_EINVAL;
    if (!all_finite(R, 9) || !all_finite(t, 3) || !(isfinite(min_var_ratio) &&
                                                    min_var_ratio >= 0.0))
        return MCG_EINVAL;
    for (k = 0; k < n; k++) {
        const double *u1 = d1 + 3 * k, *u2 = d2 + 3 * k, *z1 = axis1 + 3 * k, *z2 = axis2 + 3 * k;
        double a[3], b[3], p1[3], c[3], g1[3], g2[3], rz1[3], n1, n2, m1, m2, var, x;
        if (!all_finite(o1 + 3 * k, 3) || !all_finite(u1, 3) || !all_finite(o2 + 3 * k, 3) ||
            !all_finite(u2, 3) || !all_finite(z1, 3) || !all_finite(z2, 3))
            return MCG_EINVAL;
        if (!(isfinite(f1[k]) && f1[k] > 0.0 && isfinite(f2[k]) && f2[k] > 0.0))
            return MCG_EINVAL;
        m1 = dot3(u1, u1);
        m2 = dot3(u2, u2);
        if (!(m1 >= DIR2_MIN && m2 >= DIR2_MIN) || !isfinite(m1) || !isfinite(m2))
            return MCG_EINVAL;
        m1 = 1.0 / sqrt(m1);
        m2 = 1.0 / sqrt(m2);
        mat_vec(R, u1, a);
        mat_vec(R, o1 + 3 * k, p1);
        for (i = 0; i < 3; i++) {
            a[i] *= m1;
            b[i] = u2[i] * m2;
            c[i] = t[i] + p1[i] - o2[3 * k + i];
        }
        cross3(c, a, g2); /* tangent gradient at d2 */
        x = dot3(g2, b);
        for (i = 0; i < 3; i++)
            g2[i] -= x * b[i];
        cross3(b, c, g1); /* tangent gradient at a */
        x = dot3(g1, a);
        for (i = 0; i < 3; i++)
            g1[i] -= x * a[i];
        mat_vec(R, z1, rz1);
        n1 = dot3(g1, g1);
        n2 = dot3(g2, g2);
        {
            double c1 = dot3(a, rz1) / f1[k], c2 = dot3(b, z2) / f2[k];
            double q1 = dot3(g1, rz1), q2 = dot3(g2, z2);
            var = c1 * c1 * (n1 - q1 * q1) + c2 * c2 * (n2 - q2 * q2);
        }
        x = n1 + n2 + var;
        if (!isfinite(x))
            return MCG_EINVAL;
        /* 0: no first-order constraint (the caller substitutes its own),
         * also where V is so small against the gradient that the ratio
         * overflows (min_var_ratio = 0 lets any V > 0 through) */
        x = (n1 + n2) / var;
        scale[k] = var > min_var_ratio * (n1 + n2) && isfinite(x) ? sqrt(x) : 0.0;
    }
    return MCG_OK;
}

int mcg_sampson_pixel_scale(int n, const double *o1, const double *d1, const double *o2,
                            const double *d2, const double R[9], const double t[3],
                            const double *axis1, const double *axis2, const double *f1,
                            const double *f2, double min_var_ratio, double *scale)
{
    return pixel_scale(n, o1, d1, o2, d2, R, t, axis1, axis2, f1, f2, min_var_ratio, scale);
}
