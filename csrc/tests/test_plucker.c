/*
 * test_plucker.c -- plain-C checks of csrc/plucker.c:
 *   - Pluecker rays: |d| = 1, d parallel to the direction, m = o x d,
 *     d . m = 0, and m does not depend on which point of the ray is used;
 *   - generalized epipolar rows (thesis eqs. 8.15-8.16, row-major vec):
 *     each row dotted with (vec E, vec R) equals the bilinear form
 *     d2^T E d1 + d2^T R m1 + m2^T R d1 for arbitrary E, R; the rows vanish
 *     on the true (E = [t]x R, R) for rays that meet at a scene point under
 *     the motion X_rig2 = R X_rig1 + t, and not for a wrong motion; with
 *     30 non-central rays the null space of the rows is exactly that vector;
 *     central rays (m = 0) give zero R coefficients;
 *   - status codes of invalid inputs.
 * Exit status 0 iff every check passes.
 */
#include "mcgeom.h"

#define TEST_SEED 0x243f6a8885a308d3ULL
#include "testutil.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#define NPTS 30

static void cross(const double a[3], const double b[3], double c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

/* rotation from a unit quaternion, written out independently of linalg.c */
static void rot_from_unit_quat(double w, double x, double y, double z,
                               double r[9])
{
    r[0] = w * w + x * x - y * y - z * z;
    r[1] = 2 * (x * y - w * z);
    r[2] = 2 * (x * z + w * y);
    r[3] = 2 * (x * y + w * z);
    r[4] = w * w - x * x + y * y - z * z;
    r[5] = 2 * (y * z - w * x);
    r[6] = 2 * (x * z - w * y);
    r[7] = 2 * (y * z + w * x);
    r[8] = w * w - x * x - y * y + z * z;
}

static void rand_rotation(double r[9])
{
    double q[4], n = 0.0;
    int i;
    for (i = 0; i < 4; ++i) {
        q[i] = nrand();
        n += q[i] * q[i];
    }
    n = sqrt(n);
    rot_from_unit_quat(q[0] / n, q[1] / n, q[2] / n, q[3] / n, r);
}

static void matvec3(const double r[9], const double x[3], double y[3])
{
    int i;
    for (i = 0; i < 3; ++i)
        y[i] = r[3 * i] * x[0] + r[3 * i + 1] * x[1] + r[3 * i + 2] * x[2];
}

/* x = (vec E, vec R), row-major, E = [t]x R */
static void motion_vector(const double r[9], const double t[3], double x[18])
{
    int i, j;
    double tx[9] = {0, -t[2], t[1], t[2], 0, -t[0], -t[1], t[0], 0};
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j)
            x[3 * i + j] = tx[3 * i] * r[j] + tx[3 * i + 1] * r[3 + j] +
                           tx[3 * i + 2] * r[6 + j];
    for (i = 0; i < 9; ++i)
        x[9 + i] = r[i];
}

/* Synthetic correspondences: points X (rig1 frame), ray 1 from o1 (rig1) to
 * X, ray 2 from o2 (rig2) to R X + t. central: all origins at 0. */
static void synth(int n, const double r[9], const double t[3], int central,
                  double *o1, double *d1, double *o2, double *d2)
{
    int k, i;
    for (k = 0; k < n; ++k) {
        double x[3], x2[3];
        for (i = 0; i < 3; ++i) {
            x[i] = 4.0 * nrand();
            o1[3 * k + i] = central ? 0.0 : 0.5 * nrand();
            o2[3 * k + i] = central ? 0.0 : 0.5 * nrand();
        }
        x[2] += 10.0;
        matvec3(r, x, x2);
        for (i = 0; i < 3; ++i) {
            x2[i] += t[i];
            /* arbitrary positive scale: directions need not be unit */
            d1[3 * k + i] = 3.0 * (x[i] - o1[3 * k + i]);
            d2[3 * k + i] = 0.25 * (x2[i] - o2[3 * k + i]);
        }
    }
}

static double dot18(const double *a, const double *b)
{
    double acc = 0.0;
    int i;
    for (i = 0; i < 18; ++i)
        acc += a[i] * b[i];
    return acc;
}

static void test_plucker_rays(void)
{
    double o[3 * NPTS], d[3 * NPTS], o2[3 * NPTS], rays[6 * NPTS],
        rays2[6 * NPTS];
    double e_unit = 0, e_par = 0, e_mom = 0, e_perp = 0, e_inv = 0;
    int k, i, st;
    for (k = 0; k < 3 * NPTS; ++k) {
        o[k] = nrand();
        d[k] = nrand() * (k % 2 ? 1e-3 : 1e3); /* any non-zero length */
    }
    st = mcg_plucker_from_points(NPTS, o, d, rays);
    check_status(st, MCG_OK, "plucker_from_points status");
    /* another point on each ray: o + lambda d */
    for (k = 0; k < NPTS; ++k)
        for (i = 0; i < 3; ++i)
            o2[3 * k + i] = o[3 * k + i] + (double)(k - 7) * 0.37 * d[3 * k + i];
    mcg_plucker_from_points(NPTS, o2, d, rays2);
    for (k = 0; k < NPTS; ++k) {
        const double *L = rays + 6 * k;
        double m[3], nd, c[3], dn[3];
        nd = sqrt(d[3 * k] * d[3 * k] + d[3 * k + 1] * d[3 * k + 1] +
                  d[3 * k + 2] * d[3 * k + 2]);
        e_unit = fmax(e_unit, fabs(L[0] * L[0] + L[1] * L[1] + L[2] * L[2] - 1));
        for (i = 0; i < 3; ++i)
            dn[i] = d[3 * k + i] / nd;
        cross(dn, L, c); /* d x d_hat = 0 and same orientation */
        e_par = fmax(e_par, fabs(c[0]) + fabs(c[1]) + fabs(c[2]));
        e_par = fmax(e_par, fabs(dn[0] * L[0] + dn[1] * L[1] + dn[2] * L[2] - 1));
        cross(o + 3 * k, L, m);
        for (i = 0; i < 3; ++i) {
            e_mom = fmax(e_mom, fabs(m[i] - L[3 + i]));
            /* rounding of o2 x d is relative to |o2| */
            e_inv = fmax(e_inv, fabs(rays2[6 * k + 3 + i] - L[3 + i]) /
                                    (1.0 + fabs(o2[3 * k]) + fabs(o2[3 * k + 1]) +
                                     fabs(o2[3 * k + 2])));
        }
        e_perp = fmax(e_perp, fabs(L[0] * L[3] + L[1] * L[4] + L[2] * L[5]));
    }
    check(e_unit < 1e-15, "rays: |d| = 1", e_unit, 1e-15);
    check(e_par < 1e-15, "rays: d = dir / |dir| (same orientation)", e_par,
          1e-15);
    check(e_mom < 1e-15, "rays: m = o x d", e_mom, 1e-15);
    check(e_perp < 1e-14, "rays: d . m = 0", e_perp, 1e-14);
    check(e_inv < 1e-15, "rays: m independent of the point (rel. to |o|)",
          e_inv, 1e-15);
}

static void test_gec(void)
{
    double r[9], t[3] = {0.3, -0.1, 0.2}, x[18], xw[18];
    double o1[3 * NPTS], d1[3 * NPTS], o2[3 * NPTS], d2[3 * NPTS];
    double L1[6 * NPTS], L2[6 * NPTS], rows[18 * NPTS];
    double e = 0.0, wrong = 0.0, scale;
    int k, i, j, st;

    /* bilinear identity for arbitrary rays and arbitrary (E, R) */
    for (k = 0; k < 6 * NPTS; ++k) {
        L1[k] = nrand();
        L2[k] = nrand();
    }
    for (i = 0; i < 18; ++i)
        x[i] = nrand();
    st = mcg_gec_rows(NPTS, L1, L2, rows);
    check_status(st, MCG_OK, "gec_rows status");
    for (k = 0; k < NPTS; ++k) {
        const double *a1 = L1 + 6 * k, *a2 = L2 + 6 * k;
        double val = 0.0, ref;
        /* d2^T E d1 + d2^T R m1 + m2^T R d1, E = x[0:9], R = x[9:18] */
        for (i = 0; i < 3; ++i)
            for (j = 0; j < 3; ++j)
                val += a2[i] * x[3 * i + j] * a1[j] +
                       a2[i] * x[9 + 3 * i + j] * a1[3 + j] +
                       a2[3 + i] * x[9 + 3 * i + j] * a1[j];
        ref = dot18(rows + 18 * k, x);
        e = fmax(e, fabs(val - ref) / (1.0 + fabs(val)));
    }
    check(e < 1e-14, "gec rows . (vecE, vecR) = bilinear form (eq. 8.15)", e,
          1e-14);
    /* explicit index convention (row-major vec) on one row */
    {
        const double *a1 = L1, *a2 = L2;
        double mx = 0.0;
        for (i = 0; i < 3; ++i)
            for (j = 0; j < 3; ++j) {
                mx = fmax(mx, fabs(rows[3 * i + j] - a2[i] * a1[j]));
                mx = fmax(mx, fabs(rows[9 + 3 * i + j] -
                                   (a2[i] * a1[3 + j] + a2[3 + i] * a1[j])));
            }
        check(mx == 0.0, "gec coef(E_ij) at 3i+j, coef(R_ij) at 9+3i+j", mx,
              0.0);
    }

    /* intersecting rays under a known motion: rows vanish on the truth */
    rand_rotation(r);
    motion_vector(r, t, x);
    synth(NPTS, r, t, 0, o1, d1, o2, d2);
    mcg_plucker_from_points(NPTS, o1, d1, L1);
    mcg_plucker_from_points(NPTS, o2, d2, L2);
    st = mcg_gec_rows(NPTS, L1, L2, rows);
    scale = sqrt(dot18(x, x));
    e = 0.0;
    for (k = 0; k < NPTS; ++k) {
        double rn = sqrt(dot18(rows + 18 * k, rows + 18 * k));
        e = fmax(e, fabs(dot18(rows + 18 * k, x)) / (rn * scale));
    }
    check(st == MCG_OK && e < 1e-14,
          "gec rows vanish on the true motion (non-central rig)", e, 1e-14);
    /* a wrong motion (t perturbed) does not satisfy them */
    {
        double t2[3] = {t[0] + 0.05, t[1], t[2]};
        motion_vector(r, t2, xw);
        for (k = 0; k < NPTS; ++k) {
            double rn = sqrt(dot18(rows + 18 * k, rows + 18 * k));
            wrong = fmax(wrong, fabs(dot18(rows + 18 * k, xw)) / (rn * scale));
        }
        check(wrong > 1e-4, "gec rows do not vanish on a wrong translation",
              wrong, 1e-4);
    }
    /* most-general rig, 30 rays: one-dimensional null space = (E, R) */
    {
        static double u[18 * NPTS], s[18], v[18 * 18], work[4096];
        double cosang = 0.0;
        st = mcg_svd(NPTS, 18, rows, u, s, v, work, sizeof work / sizeof work[0]);
        for (i = 0; i < 18; ++i)
            cosang += v[i * 18 + 17] * x[i];
        cosang = fabs(cosang) / scale;
        check(st == MCG_OK && fabs(1.0 - cosang) < 1e-12,
              "gec null vector of 30 rows is +-(vec E, vec R)",
              fabs(1.0 - cosang), 1e-12);
        check(s[17] / s[0] < 1e-14 && s[16] / s[0] > 1e-6,
              "gec rows: rank 17 (s17 ~ 0, s16 > 0)", s[17] / s[0], 1e-14);
    }
    /* central rig: m = 0 so every R coefficient is 0 */
    synth(NPTS, r, t, 1, o1, d1, o2, d2);
    mcg_plucker_from_points(NPTS, o1, d1, L1);
    mcg_plucker_from_points(NPTS, o2, d2, L2);
    mcg_gec_rows(NPTS, L1, L2, rows);
    e = 0.0;
    wrong = 0.0;
    for (k = 0; k < NPTS; ++k) {
        for (i = 9; i < 18; ++i)
            e = fmax(e, fabs(rows[18 * k + i]));
        /* and d2^T E d1 = 0 is the classical epipolar constraint */
        wrong = fmax(wrong, fabs(dot18(rows + 18 * k, x)) / scale);
    }
    check(e == 0.0, "gec central rig: R coefficients are 0", e, 0.0);
    check(wrong < 1e-14, "gec central rig: classical d2^T E d1 = 0", wrong,
          1e-14);
}

static void test_invalid(void)
{
    double o[6] = {0, 0, 0, 1, 1, 1}, d[6] = {0, 0, 1, 0, 0, 0}, rays[12],
           rows[36];
    check_status(mcg_plucker_from_points(2, o, d, rays), MCG_EINVAL,
                 "plucker zero direction -> EINVAL");
    d[5] = 1;
    check_status(mcg_plucker_from_points(2, o, d, rays), MCG_OK,
                 "plucker valid input");
    check_status(mcg_plucker_from_points(0, o, d, rays), MCG_EINVAL,
                 "plucker n = 0");
    check_status(mcg_plucker_from_points(-3, o, d, rays), MCG_EINVAL,
                 "plucker n < 0");
    check_status(mcg_plucker_from_points(2, NULL, d, rays), MCG_EINVAL,
                 "plucker origins = NULL");
    check_status(mcg_plucker_from_points(2, o, d, NULL), MCG_EINVAL,
                 "plucker rays = NULL");
    o[4] = NAN;
    check_status(mcg_plucker_from_points(2, o, d, rays), MCG_EINVAL,
                 "plucker NaN origin");
    o[4] = 1;
    d[1] = INFINITY;
    check_status(mcg_plucker_from_points(2, o, d, rays), MCG_EINVAL,
                 "plucker inf direction");
    d[1] = 0;
    mcg_plucker_from_points(2, o, d, rays);
    check_status(mcg_gec_rows(2, rays, rays, rows), MCG_OK, "gec valid input");
    check_status(mcg_gec_rows(0, rays, rays, rows), MCG_EINVAL, "gec n = 0");
    check_status(mcg_gec_rows(2, rays, NULL, rows), MCG_EINVAL,
                 "gec rays2 = NULL");
    check_status(mcg_gec_rows(2, rays, rays, NULL), MCG_EINVAL,
                 "gec rows = NULL");
    rays[7] = NAN;
    check_status(mcg_gec_rows(2, rays, rays, rows), MCG_EINVAL, "gec NaN");
    rays[7] = 1e300;
    check_status(mcg_gec_rows(2, rays, rays, rows), MCG_EINVAL,
                 "gec overflowing products -> EINVAL");
}

int main(void)
{
    test_plucker_rays();
    test_gec();
    test_invalid();
    printf("%s: %d checks, %d failed\n", n_failed ? "FAILED" : "PASSED",
           n_checks, n_failed);
    return n_failed ? 1 : 0;
}
