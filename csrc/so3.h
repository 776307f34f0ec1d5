/*
 * so3.h -- the small 3-vector, 3 x 3 and SO(3) helpers of libmcgeom (not
 * installed, not part of the public API), in one place. Each kernel used to
 * carry its own copy; they are static inline so that no symbol is exported
 * from the shared library and no call is slower than the local copies were.
 *
 * Matrices are row-major 3 x 3 (m[3 i + j]). Every expression keeps the
 * evaluation order of the copies it replaces, so results are bit-for-bit
 * those of before (the library is built with -std=c99, i.e. without
 * floating-point contraction).
 */
#ifndef MCGEOM_SO3_H
#define MCGEOM_SO3_H

#include <math.h>

/* |R R^T - I| (entrywise) accepted as a rotation by the entry points that
 * take a rotation as input (mcg_angle_axis_from_rot, mcg_quat_from_rot,
 * mcg_refine_motion: "R a rotation to 1e-6" in mcgeom.h). */
#define SO3_ROT_TOL 1e-6

/* a . b */
static inline double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* c = a x b (c must not alias a or b) */
static inline void cross3(const double a[3], const double b[3], double c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

/* y = M x (y must not alias x) */
static inline void mat_vec(const double m[9], const double x[3], double y[3])
{
    y[0] = m[0] * x[0] + m[1] * x[1] + m[2] * x[2];
    y[1] = m[3] * x[0] + m[4] * x[1] + m[5] * x[2];
    y[2] = m[6] * x[0] + m[7] * x[1] + m[8] * x[2];
}

/* c = a b (c must not alias a or b) */
static inline void mul33(const double *a, const double *b, double *c)
{
    int i, j;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++)
            c[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] +
                           a[3 * i + 2] * b[6 + j];
}

/* c = a b^T (c must not alias a or b) */
static inline void mul33_abt(const double *a, const double *b, double *c)
{
    int i, j;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++)
            c[3 * i + j] = a[3 * i] * b[3 * j] + a[3 * i + 1] * b[3 * j + 1] +
                           a[3 * i + 2] * b[3 * j + 2];
}

/* det(a), cofactor expansion along the first row */
static inline double det33(const double *a)
{
    return a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) +
           a[2] * (a[3] * a[7] - a[4] * a[6]);
}

/* s = [v]x, the cross-product matrix: [v]x y = v x y */
static inline void skew3(const double v[3], double s[9])
{
    s[0] = 0.0;   s[1] = -v[2]; s[2] = v[1];
    s[3] = v[2];  s[4] = 0.0;   s[5] = -v[0];
    s[6] = -v[1]; s[7] = v[0];  s[8] = 0.0;
}

/* out = [w]x r: e.g. E = [t]x R (thesis eq. 8.18's first block) and the
 * derivative of R along a left increment, d(exp([w]x) R) = [dw]x R */
static inline void skew_times(const double w[3], const double *r, double *out)
{
    double s[9];
    skew3(w, s);
    mul33(s, r, out);
}

/* 1 if r is a rotation to SO3_ROT_TOL: orthonormal rows and det > 0. A NaN
 * entry fails the test (the callers also reject non-finite input first). */
static inline int is_rotation(const double r[9])
{
    int i, j;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) {
            double acc = r[3 * i] * r[3 * j] + r[3 * i + 1] * r[3 * j + 1] +
                         r[3 * i + 2] * r[3 * j + 2];
            if (!(fabs(acc - (i == j ? 1.0 : 0.0)) <= SO3_ROT_TOL))
                return 0;
        }
    return det33(r) > 0.0;
}

#endif /* MCGEOM_SO3_H */
