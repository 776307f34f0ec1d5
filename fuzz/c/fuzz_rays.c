/*
 * fuzz_rays.c -- libFuzzer harness of the per-ray geometry: Pluecker rays
 * (mcg_plucker_from_points), generalized epipolar rows (mcg_gec_rows, thesis
 * eq. 8.16), Sampson angular residuals (mcg_gec_residuals, eq. 8.15) and the
 * wedge normals of two error cones (mcg_wedge_normals, eqs. 10.9-10.12).
 *
 * Invariants (on MCG_OK): finite outputs; rays have |d| = 1 and d . m = 0;
 * row k . (vec E, vec R) equals the constraint d2^T E d1 + d2^T R m1 +
 * m2^T R d1 evaluated directly; residuals lie in [-pi/2, pi/2] and vanish
 * for exact correspondences under the true motion; wedge normals are unit
 * and every translation t = l' u' - l u with u, u' inside the two error
 * cones satisfies n1 . t >= 0 and n2 . t >= 0. Non-finite inputs and bad
 * sizes give MCG_EINVAL.
 */
#include "fuzz_input.h"
#include "mcgeom.h"

/* routines selected by the first input byte (fuzz/make_corpus.py writes
 * seeds for each) */
#define FUZZ_MODES 3

#define MAXN 40
#define HALF_PI 1.5707963267948966

static void fuzz_plucker_rows(fz_in *in)
{
    int valid, st, k, i, j;
    int n = fz_size(in, 1, MAXN, &valid);
    double o1[3 * MAXN], d1[3 * MAXN], o2[3 * MAXN], d2[3 * MAXN];
    double r1[6 * MAXN], r2[6 * MAXN], rows[18 * MAXN], R[9], E[9], t[3];
    if (!valid) {
        double dummy[18] = {0};
        FZ_CHECK(mcg_plucker_from_points(n, dummy, dummy, dummy) == MCG_EINVAL,
                 "plucker_from_points(n = %d) accepted", n);
        FZ_CHECK(mcg_gec_rows(n, dummy, dummy, dummy) == MCG_EINVAL, "gec_rows(n = %d) accepted",
                 n);
        return;
    }
    if (fz_u8(in) & 1) {
        fz_matrix(in, o1, (size_t)n, 3);
        fz_matrix(in, d1, (size_t)n, 3);
        fz_matrix(in, o2, (size_t)n, 3);
        fz_matrix(in, d2, (size_t)n, 3);
    } else {
        fz_rotation(in, R);
        for (i = 0; i < 3; ++i)
            t[i] = fz_range(in, -2.0, 2.0);
        fz_scene(in, n, fz_int(in, 1, 8), 1, R, t, o1, d1, o2, d2, NULL);
    }
    st = mcg_plucker_from_points(n, o1, d1, r1);
    FZ_CHECK(fz_status_known(st), "plucker status %d", st);
    if (!fz_all_finite(o1, 3 * (size_t)n) || !fz_all_finite(d1, 3 * (size_t)n))
        FZ_CHECK(st == MCG_EINVAL, "plucker_from_points of non-finite input: %d", st);
    if (st != MCG_OK)
        return;
    FZ_CHECK(fz_all_finite(r1, 6 * (size_t)n), "plucker: non-finite ray");
    for (k = 0; k < n; ++k) {
        const double *r = r1 + 6 * k;
        double om = 2.0 * fz_maxabs(o1 + 3 * k, 3); /* no underflow */
        FZ_CHECK(fabs(fz_dot3(r, r) - 1.0) <= 1e-14, "plucker: |d| = %g", sqrt(fz_dot3(r, r)));
        FZ_CHECK(fabs(fz_dot3(r, r + 3)) <= 1e-14 * (om + 1e-300) + 1e-300, "plucker: d . m = %g",
                 fz_dot3(r, r + 3));
    }
    if (mcg_plucker_from_points(n, o2, d2, r2) != MCG_OK)
        return;
    st = mcg_gec_rows(n, r1, r2, rows);
    FZ_CHECK(st == MCG_OK || st == MCG_EINVAL, "gec_rows status %d", st);
    if (st != MCG_OK)
        return;
    FZ_CHECK(fz_all_finite(rows, 18 * (size_t)n), "gec_rows: non-finite row");
    /* the row against the constraint evaluated at a decoded (E, R) */
    fz_rotation(in, R);
    for (i = 0; i < 9; ++i)
        E[i] = fz_range(in, -1.0, 1.0);
    for (k = 0; k < n; ++k) {
        const double *a1 = r1 + 6 * k, *a2 = r2 + 6 * k, *row = rows + 18 * k;
        double lhs = 0.0, rhs = 0.0, mag = 0.0;
        for (i = 0; i < 9; ++i) {
            lhs += row[i] * E[i] + row[9 + i] * R[i];
            mag += fabs(row[i]) + fabs(row[9 + i]);
        }
        for (i = 0; i < 3; ++i)
            for (j = 0; j < 3; ++j)
                rhs += a2[i] * E[3 * i + j] * a1[j] + a2[i] * R[3 * i + j] * a1[3 + j] +
                       a2[3 + i] * R[3 * i + j] * a1[j];
        if (!isfinite(mag) || !isfinite(lhs) || !isfinite(rhs))
            continue; /* rows near DBL_MAX: the check's own sums overflow */
        FZ_CHECK(fabs(lhs - rhs) <= 1e-13 * (mag + 1e-300), "gec_rows: row %d gives %g, direct %g",
                 k, lhs, rhs);
    }
}

static void fuzz_residuals(fz_in *in)
{
    int valid, st, k, i, exact = 0, structured = fz_u8(in) & 1;
    int n = fz_size(in, 0, MAXN, &valid);
    double o1[3 * MAXN], d1[3 * MAXN], o2[3 * MAXN], d2[3 * MAXN], R[9], t[3], res[MAXN];
    if (n == (1 << 21))
        n = (1 << 26) + 1; /* the limit of mcg_gec_residuals is 2^26 rays */
    if (!valid) {
        double dummy[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
        FZ_CHECK(mcg_gec_residuals(n, dummy, dummy, dummy, dummy, dummy, dummy, dummy) ==
                     MCG_EINVAL,
                 "gec_residuals(n = %d) accepted", n);
        return;
    }
    if (structured) {
        fz_rotation(in, R);
        for (i = 0; i < 3; ++i)
            t[i] = fz_range(in, -2.0, 2.0);
        exact = fz_scene(in, n, fz_int(in, 1, 8), 1, R, t, o1, d1, o2, d2, NULL);
    } else {
        fz_matrix(in, o1, (size_t)n, 3);
        fz_matrix(in, d1, (size_t)n, 3);
        fz_matrix(in, o2, (size_t)n, 3);
        fz_matrix(in, d2, (size_t)n, 3);
        fz_doubles(in, R, 9);
        fz_doubles(in, t, 3);
    }
    st = mcg_gec_residuals(n, o1, d1, o2, d2, R, t, res);
    FZ_CHECK(st == MCG_OK || st == MCG_EINVAL, "gec_residuals status %d", st);
    if (!fz_all_finite(o1, 3 * (size_t)n) || !fz_all_finite(d1, 3 * (size_t)n) ||
        !fz_all_finite(o2, 3 * (size_t)n) || !fz_all_finite(d2, 3 * (size_t)n) ||
        !fz_all_finite(R, 9) || !fz_all_finite(t, 3))
        FZ_CHECK(st == MCG_EINVAL, "gec_residuals of non-finite input: %d", st);
    if (st != MCG_OK)
        return;
    for (k = 0; k < n; ++k) {
        FZ_CHECK(isfinite(res[k]) && fabs(res[k]) <= HALF_PI * (1.0 + 1e-15),
                 "gec_residuals: res[%d] = %g", k, res[k]);
        if (exact) {
            /* bearings of at least 1e-3 m: the rounding of the synthetic
             * data is then far below the tolerance */
            double l1 = sqrt(fz_dot3(d1 + 3 * k, d1 + 3 * k)), l2 = sqrt(fz_dot3(d2 + 3 * k, d2 + 3 * k));
            if (l1 > 1e-3 && l2 > 1e-3)
                FZ_CHECK(fabs(res[k]) <= 1e-8, "gec_residuals: exact pair %d has residual %g", k,
                         res[k]);
        }
    }
}

/* a unit vector within angle a of the unit vector c, towards p */
static void tilt(const double c[3], const double p[3], double a, double out[3])
{
    double q[3], nq;
    int i;
    for (i = 0; i < 3; ++i)
        q[i] = p[i] - fz_dot3(p, c) * c[i];
    nq = sqrt(fz_dot3(q, q));
    if (!(nq > 1e-6)) {
        for (i = 0; i < 3; ++i)
            out[i] = c[i];
        return;
    }
    for (i = 0; i < 3; ++i)
        out[i] = cos(a) * c[i] + sin(a) * q[i] / nq;
}

static void fuzz_wedge(fz_in *in)
{
    double v[3], vp[3], n1[3], n2[3], eps, epsp;
    int st, i, s;
    if (fz_u8(in) & 1) {
        fz_doubles(in, v, 3);
        fz_doubles(in, vp, 3);
        eps = fz_double(in);
        epsp = fz_double(in);
    } else {
        for (i = 0; i < 3; ++i) {
            v[i] = fz_range(in, -1.0, 1.0);
            vp[i] = fz_range(in, -1.0, 1.0);
        }
        eps = fz_range(in, 0.0, 0.8);
        epsp = fz_range(in, 0.0, 0.8);
    }
    st = mcg_wedge_normals(v, vp, eps, epsp, n1, n2);
    FZ_CHECK(st == MCG_OK || st == MCG_EINVAL || st == MCG_EDEGENERATE, "wedge status %d", st);
    if (!fz_all_finite(v, 3) || !fz_all_finite(vp, 3) || !(eps >= 0.0 && eps < HALF_PI) ||
        !(epsp >= 0.0 && epsp < HALF_PI))
        FZ_CHECK(st == MCG_EINVAL, "wedge_normals of invalid input: %d", st);
    if (st != MCG_OK)
        return;
    FZ_CHECK(fz_all_finite(n1, 3) && fz_all_finite(n2, 3), "wedge: non-finite normal");
    FZ_CHECK(fabs(fz_dot3(n1, n1) - 1.0) <= 1e-9 && fabs(fz_dot3(n2, n2) - 1.0) <= 1e-9,
             "wedge: normals not unit (%g, %g)", fz_dot3(n1, n1), fz_dot3(n2, n2));
    {
        double vh[3], vph[3], nv = sqrt(fz_dot3(v, v)), nvp = sqrt(fz_dot3(vp, vp));
        if (!(nv > 0.0) || !(nvp > 0.0) || !isfinite(nv) || !isfinite(nvp))
            return; /* |v|^2 under- or overflows here: the kernel scales */
        for (i = 0; i < 3; ++i) {
            vh[i] = v[i] / nv;
            vph[i] = vp[i] / nvp;
        }
        for (s = 0; s < 4; ++s) {
            double p[3], pp[3], u[3], up[3], tt[3], l, lp;
            for (i = 0; i < 3; ++i) {
                p[i] = fz_range(in, -1.0, 1.0);
                pp[i] = fz_range(in, -1.0, 1.0);
            }
            tilt(vh, p, eps * fz_range(in, 0.0, 1.0), u);
            tilt(vph, pp, epsp * fz_range(in, 0.0, 1.0), up);
            l = fz_range(in, 0.01, 10.0);
            lp = fz_range(in, 0.01, 10.0);
            for (i = 0; i < 3; ++i)
                tt[i] = lp * up[i] - l * u[i];
            FZ_CHECK(fz_dot3(n1, tt) >= -1e-9 * (l + lp) && fz_dot3(n2, tt) >= -1e-9 * (l + lp),
                     "wedge: t in the cones violates a plane (n1.t %g, n2.t %g)", fz_dot3(n1, tt),
                     fz_dot3(n2, tt));
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in = fz_make(data, size);
    switch (fz_u8(&in) % FUZZ_MODES) {
    case 0:
        fuzz_plucker_rows(&in);
        break;
    case 1:
        fuzz_residuals(&in);
        break;
    default:
        fuzz_wedge(&in);
        break;
    }
    return 0;
}
