/*
 * plucker.c -- Pluecker rays and generalized epipolar rows.
 *
 * Implements the "plucker.c" section of mcgeom.h:
 *   - Pluecker coordinates (d, m), |d| = 1, m = o x d, of rays given by an
 *     origin and a direction (thesis ch. 8.2, Pless' generalized camera);
 *   - the 18 coefficients of the generalized epipolar constraint (thesis
 *     eqs. 8.15-8.16) in this library's convention rig2_from_rig1,
 *         d2^T E d1 + d2^T R m1 + m2^T R d1 = 0,   E = [t]x R,
 *     with ROW-MAJOR vec(): coef(E_ij) = d2_i d1_j at index 3 i + j and
 *     coef(R_ij) = d2_i m1_j + m2_i d1_j at index 9 + 3 i + j. (The thesis
 *     writes vec() column-major; only the ordering of the unknowns differs.)
 */
#include "mcgeom.h"
#include "internal.h"

#include <math.h>
#include <stddef.h>

int mcg_plucker_from_points(int n, const double *origins, const double *dirs,
                            double *rays)
{
    size_t nn, k;
    if (n < 1 || (size_t)n > MAX_ROWS)
        return MCG_EINVAL;
    if (origins == NULL || dirs == NULL || rays == NULL)
        return MCG_EINVAL;
    nn = (size_t)n;
    if (!all_finite(origins, 3 * nn) || !all_finite(dirs, 3 * nn))
        return MCG_EINVAL;
    /* validate every direction before writing anything */
    for (k = 0; k < nn; ++k) {
        const double *d = dirs + 3 * k;
        if (d[0] == 0.0 && d[1] == 0.0 && d[2] == 0.0)
            return MCG_EINVAL;
    }
    for (k = 0; k < nn; ++k) {
        const double *o = origins + 3 * k, *dd = dirs + 3 * k;
        double *ray = rays + 6 * k;
        double mx, d0, d1, d2, len;
        /* normalise through the largest component: no overflow/underflow
         * for directions of any finite, non-zero length */
        mx = fabs(dd[0]);
        if (fabs(dd[1]) > mx)
            mx = fabs(dd[1]);
        if (fabs(dd[2]) > mx)
            mx = fabs(dd[2]);
        d0 = dd[0] / mx;
        d1 = dd[1] / mx;
        d2 = dd[2] / mx;
        len = sqrt(d0 * d0 + d1 * d1 + d2 * d2);
        d0 /= len;
        d1 /= len;
        d2 /= len;
        ray[0] = d0;
        ray[1] = d1;
        ray[2] = d2;
        ray[3] = o[1] * d2 - o[2] * d1;
        ray[4] = o[2] * d0 - o[0] * d2;
        ray[5] = o[0] * d1 - o[1] * d0;
        if (!isfinite(ray[3]) || !isfinite(ray[4]) || !isfinite(ray[5]))
            return MCG_EINVAL; /* origin so far away that m overflows */
    }
    return MCG_OK;
}

int mcg_gec_rows(int n, const double *rays1, const double *rays2,
                 double *rows)
{
    size_t nn, k;
    int i, j;
    if (n < 1 || (size_t)n > MAX_ROWS)
        return MCG_EINVAL;
    if (rays1 == NULL || rays2 == NULL || rows == NULL)
        return MCG_EINVAL;
    nn = (size_t)n;
    if (!all_finite(rays1, 6 * nn) || !all_finite(rays2, 6 * nn))
        return MCG_EINVAL;
    for (k = 0; k < nn; ++k) {
        const double *d1 = rays1 + 6 * k, *m1 = d1 + 3;
        const double *d2 = rays2 + 6 * k, *m2 = d2 + 3;
        double *row = rows + 18 * k;
        for (i = 0; i < 3; ++i)
            for (j = 0; j < 3; ++j) {
                row[3 * i + j] = d2[i] * d1[j];
                row[9 + 3 * i + j] = d2[i] * m1[j] + m2[i] * d1[j];
            }
    }
    /* finite inputs can still overflow in the products (absurd moments) */
    if (!all_finite(rows, 18 * nn))
        return MCG_EINVAL;
    return MCG_OK;
}
