/*
 * test_translation.c -- plain-C checks of csrc/translation.c:
 *   - bilinear and trilinear rows (eqs. 6.5, 6.11) vanish on the true
 *     centres of noise-free views (central and with rig offsets) and not on
 *     perturbed ones; row . (c, 1) equals the relation evaluated directly;
 *   - the block Gram of mcg_relation_grams equals the sum of outer products
 *     of the public rows (three reference views for triples);
 *   - skyline Cholesky + solve against a dense residual check;
 *   - mcg_skyline_eig on tridiag(-1, 2, -1) scaled by a diagonal B, whose
 *     generalized eigenvalues are known in closed form;
 *   - status codes of invalid inputs.
 * Exit status 0 iff every check passes.
 */
#include "mcgeom.h"

#define TEST_SEED 0x3c6ef372fe94f82bULL
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NP 25

static void cross(const double a[3], const double b[3], double c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

/* bearings of NP points seen from origins c + w (3 views) */
static void scene(double c[3][3], double w[3][NP * 3], double x[3][NP * 3], int rig)
{
    int v, k, q;
    for (v = 0; v < 3; ++v)
        randn(c[v], 3);
    for (k = 0; k < NP; ++k) {
        double X[3];
        randn(X, 3);
        for (q = 0; q < 3; ++q)
            X[q] *= 5.0;
        for (v = 0; v < 3; ++v) {
            double len = 0.5 + urand(); /* bearings need not be unit */
            for (q = 0; q < 3; ++q) {
                w[v][3 * k + q] = rig ? 0.3 * nrand() : 0.0;
                x[v][3 * k + q] = (X[q] - c[v][q] - w[v][3 * k + q]) * len;
            }
        }
    }
}

static double row_value(const double *row, const double *ci, const double *cj)
{
    int q;
    double s = row[6];
    for (q = 0; q < 3; ++q)
        s += row[q] * ci[q] + row[3 + q] * cj[q];
    return s;
}

static void test_rows(int rig)
{
    double c[3][3], w[3][NP * 3], x[3][NP * 3], rows[NP * 7], tri[NP * 63];
    double worst = 0.0, pert = 0.0, direct = 0.0, a[3], b[3], cbad[3];
    const double *w0 = rig ? w[0] : NULL, *w1 = rig ? w[1] : NULL, *w2 = rig ? w[2] : NULL;
    int k, e, q;
    char what[96];
    scene(c, w, x, rig);
    check_status(mcg_bilinear_rows(NP, x[0], x[1], w0, w1, rows), MCG_OK, "bilinear rows");
    for (q = 0; q < 3; ++q)
        cbad[q] = c[1][q] + 0.1 * nrand();
    for (k = 0; k < NP; ++k) {
        double u[3], d[3], ref = 0.0;
        worst = fmax(worst, fabs(row_value(rows + 7 * k, c[0], c[1])));
        pert = fmax(pert, fabs(row_value(rows + 7 * k, c[0], cbad)));
        cross(x[0] + 3 * k, x[1] + 3 * k, u);
        for (q = 0; q < 3; ++q)
            d[q] = cbad[q] + w[1][3 * k + q] * rig - c[0][q] - w[0][3 * k + q] * rig;
        for (q = 0; q < 3; ++q)
            ref += u[q] * d[q];
        direct = fmax(direct, fabs(ref - row_value(rows + 7 * k, c[0], cbad)));
    }
    snprintf(what, sizeof what, "bilinear rows vanish on the true centres (rig %d)", rig);
    check(worst < 1e-12, what, worst, 1e-12);
    snprintf(what, sizeof what, "bilinear rows do not vanish on wrong centres (rig %d)", rig);
    check(pert > 1e-4, what, pert, 1e-4);
    snprintf(what, sizeof what, "bilinear row = (x1 x x2).(p2 - p1) (rig %d)", rig);
    check(direct < 1e-12, what, direct, 1e-12);

    check_status(mcg_trilinear_rows(NP, x[0], x[1], x[2], w0, w1, w2, tri), MCG_OK,
                 "trilinear rows");
    worst = 0.0;
    pert = 0.0;
    direct = 0.0;
    for (k = 0; k < NP; ++k) {
        double u[3], v[3], A[3], B[3], xa[3], xb[3];
        for (q = 0; q < 3; ++q) {
            a[q] = c[1][q] - c[0][q];
            b[q] = c[2][q] - c[0][q];
        }
        for (e = 0; e < 9; ++e) {
            const double *r = tri + 63 * k + 7 * e;
            double s = r[6], sb = r[6];
            for (q = 0; q < 3; ++q) {
                s += r[q] * a[q] + r[3 + q] * b[q];
                sb += r[q] * (a[q] + 0.1) + r[3 + q] * b[q];
            }
            worst = fmax(worst, fabs(s));
            pert = fmax(pert, fabs(sb));
        }
        /* direct evaluation of eq. 6.11 at the perturbed a */
        cross(x[0] + 3 * k, x[1] + 3 * k, u);
        cross(x[0] + 3 * k, x[2] + 3 * k, v);
        for (q = 0; q < 3; ++q) {
            A[q] = a[q] + 0.1 + rig * (w[1][3 * k + q] - w[0][3 * k + q]);
            B[q] = b[q] + rig * (w[2][3 * k + q] - w[0][3 * k + q]);
        }
        cross(x[2] + 3 * k, B, xb);
        cross(x[1] + 3 * k, A, xa);
        for (e = 0; e < 9; ++e) {
            const double *r = tri + 63 * k + 7 * e;
            int s_ = e / 3, t_ = e % 3;
            double m = u[s_] * xb[t_] - xa[s_] * v[t_], val = r[6];
            for (q = 0; q < 3; ++q)
                val += r[q] * (a[q] + 0.1) + r[3 + q] * b[q];
            direct = fmax(direct, fabs(m - val));
        }
    }
    snprintf(what, sizeof what, "trilinear rows vanish on the true centres (rig %d)", rig);
    check(worst < 1e-11, what, worst, 1e-11);
    snprintf(what, sizeof what, "trilinear rows do not vanish on wrong centres (rig %d)", rig);
    check(pert > 1e-4, what, pert, 1e-4);
    snprintf(what, sizeof what, "trilinear row = eq. 6.11 evaluated directly (rig %d)", rig);
    check(direct < 1e-11, what, direct, 1e-11);
}

static void test_grams(void)
{
    double c[3][3], w[3][NP * 3], x[3][NP * 3];
    double xq[NP * 9], wq[NP * 9], g2[2 * 49], g3[100], ref2[2 * 49], ref3[100];
    int blk[NP], k, q, i, j, ref;
    double err2 = 0.0, err3 = 0.0;
    scene(c, w, x, 1);
    for (k = 0; k < NP; ++k) {
        blk[k] = k % 2;
        for (i = 0; i < 3; ++i)
            for (q = 0; q < 3; ++q) {
                xq[9 * k + 3 * i + q] = x[i][3 * k + q];
                wq[9 * k + 3 * i + q] = w[i][3 * k + q];
            }
    }
    /* q = 2: pack the first two views */
    {
        double x2[NP * 6], w2[NP * 6], row[7];
        for (k = 0; k < NP; ++k)
            for (q = 0; q < 6; ++q) {
                x2[6 * k + q] = xq[9 * k + q];
                w2[6 * k + q] = wq[9 * k + q];
            }
        check_status(mcg_relation_grams(2, NP, x2, w2, blk, 2, g2), MCG_OK, "grams q=2");
        memset(ref2, 0, sizeof ref2);
        for (k = 0; k < NP; ++k) {
            mcg_bilinear_rows(1, x2 + 6 * k, x2 + 6 * k + 3, w2 + 6 * k, w2 + 6 * k + 3, row);
            for (i = 0; i < 7; ++i)
                for (j = 0; j < 7; ++j)
                    ref2[49 * blk[k] + 7 * i + j] += row[i] * row[j];
        }
        for (i = 0; i < 98; ++i)
            err2 = fmax(err2, fabs(g2[i] - ref2[i]));
        check(err2 < 1e-10, "bilinear Gram = sum of row outer products", err2, 1e-10);
    }
    for (k = 0; k < NP; ++k)
        blk[k] = 0;
    check_status(mcg_relation_grams(3, NP, xq, wq, blk, 1, g3), MCG_OK, "grams q=3");
    memset(ref3, 0, sizeof ref3);
    for (k = 0; k < NP; ++k)
        for (ref = 0; ref < 3; ++ref) {
            int o1 = (ref + 1) % 3, o2 = (ref + 2) % 3, e;
            double r9[63];
            mcg_trilinear_rows(1, xq + 9 * k + 3 * ref, xq + 9 * k + 3 * o1,
                               xq + 9 * k + 3 * o2, wq + 9 * k + 3 * ref,
                               wq + 9 * k + 3 * o1, wq + 9 * k + 3 * o2, r9);
            for (e = 0; e < 9; ++e) {
                double row[10];
                for (q = 0; q < 3; ++q) {
                    row[3 * ref + q] = -r9[7 * e + q] - r9[7 * e + 3 + q];
                    row[3 * o1 + q] = r9[7 * e + q];
                    row[3 * o2 + q] = r9[7 * e + 3 + q];
                }
                row[9] = r9[7 * e + 6];
                for (i = 0; i < 10; ++i)
                    for (j = 0; j < 10; ++j)
                        ref3[10 * i + j] += row[i] * row[j];
            }
        }
    {   /* relative to the largest entry: the Gram is summed in closed form,
         * the reference from the explicit rows, so they agree to rounding of
         * the entries' size (here ~3e6) */
        double rmax = 0.0;
        for (i = 0; i < 100; ++i) {
            err3 = fmax(err3, fabs(g3[i] - ref3[i]));
            rmax = fmax(rmax, fabs(ref3[i]));
        }
        err3 /= rmax;
    }
    check(err3 < 1e-13, "trilinear Gram = sum over 3 references of row outer products "
          "(relative)", err3, 1e-13);
    {   /* the Gram annihilates the true centres (with the constant 1) */
        double z[10], worst = 0.0, gmax = 0.0;
        for (i = 0; i < 100; ++i)
            gmax = fmax(gmax, fabs(g3[i]));
        for (i = 0; i < 3; ++i)
            for (q = 0; q < 3; ++q)
                z[3 * i + q] = c[i][q];
        z[9] = 1.0;
        for (i = 0; i < 10; ++i) {
            double s = 0.0;
            for (j = 0; j < 10; ++j)
                s += g3[10 * i + j] * z[j];
            worst = fmax(worst, fabs(s));
        }
        worst /= gmax;
        check(worst < 1e-13, "trilinear Gram annihilates (c1, c2, c3, 1), relative", worst,
              1e-13);
    }
    blk[0] = 5;
    check_status(mcg_relation_grams(3, NP, xq, wq, blk, 1, g3), MCG_EINVAL,
                 "grams: block index out of range");
    check_status(mcg_relation_grams(4, NP, xq, wq, blk, 1, g3), MCG_EINVAL, "grams: q = 4");
}

/* tridiag(-1, 2, -1) of size n scaled as D^1/2 T D^1/2 with B = D */
static void test_skyline(void)
{
    enum { N = 40 };
    int first[N], ptr[N + 1], r, it = 0, j;
    double a[2 * N], bm[2 * N], fac[2 * N], d[N], x[N], rhs[N], vals[4], vecs[4 * N],
        res[4], *work;
    size_t lw;
    double err = 0.0;
    ptr[0] = 0;
    for (r = 0; r < N; ++r) {
        first[r] = r > 0 ? r - 1 : 0;
        ptr[r + 1] = ptr[r] + r - first[r] + 1;
        d[r] = 0.5 + urand();
    }
    for (r = 0; r < N; ++r) {
        double *ar = a + ptr[r] - first[r], *br = bm + ptr[r] - first[r];
        ar[r] = 2.0 * d[r];
        br[r] = d[r];
        if (r > 0) {
            ar[r - 1] = -sqrt(d[r] * d[r - 1]);
            br[r - 1] = 0.0;
        }
    }
    memcpy(fac, a, sizeof(double) * (size_t)ptr[N]);
    check_status(mcg_skyline_cholesky(N, first, ptr, fac), MCG_OK, "skyline Cholesky");
    for (r = 0; r < N; ++r)
        x[r] = rhs[r] = nrand();
    check_status(mcg_skyline_solve(N, first, ptr, fac, x), MCG_OK, "skyline solve");
    for (r = 0; r < N; ++r) { /* residual A x - rhs with A dense-expanded */
        double s = 2.0 * d[r] * x[r];
        if (r > 0)
            s -= sqrt(d[r] * d[r - 1]) * x[r - 1];
        if (r + 1 < N)
            s -= sqrt(d[r] * d[r + 1]) * x[r + 1];
        err = fmax(err, fabs(s - rhs[r]));
    }
    check(err < 1e-10, "skyline solve residual", err, 1e-10);

    lw = mcg_skyline_eig_work_size(N, 4, ptr[N]);
    work = malloc(sizeof(double) * lw);
    check_status(mcg_skyline_eig(N, first, ptr, a, bm, 0.0, 4, 2000, 1e-12, vals, vecs,
                                 res, &it, work, lw),
                 MCG_OK, "skyline eig");
    err = 0.0;
    for (j = 0; j < 2; ++j) {
        double want = 2.0 - 2.0 * cos((j + 1) * 3.141592653589793 / (N + 1));
        err = fmax(err, fabs(vals[j] - want) / want);
    }
    check(err < 1e-9, "two smallest generalized eigenvalues of D^1/2 T D^1/2, D", err, 1e-9);
    check(res[0] < 1e-12 && res[1] < 1e-12, "eig residuals below tolerance",
          fmax(res[0], res[1]), 1e-12);
    check_status(mcg_skyline_eig(N, first, ptr, a, bm, 0.0, 9, 10, 1e-12, vals, vecs, res,
                                 &it, work, lw),
                 MCG_EINVAL, "eig: p = 9");
    check_status(mcg_skyline_eig(N, first, ptr, a, bm, 0.0, 4, 10, 1e-12, vals, vecs, res,
                                 &it, work, lw - 1),
                 MCG_ENOMEM, "eig: workspace too small");
    free(work);
    /* not positive definite */
    memcpy(fac, a, sizeof(double) * (size_t)ptr[N]);
    fac[ptr[N] - 1] = -1.0;
    check_status(mcg_skyline_cholesky(N, first, ptr, fac), MCG_ENUMERIC,
                 "Cholesky of an indefinite matrix");
    first[3] = 4;
    check_status(mcg_skyline_cholesky(N, first, ptr, fac), MCG_EINVAL, "bad profile");
}

int main(void)
{
    double x[6] = {1, 0, 0, 0, 1, 0}, rows[14];
    test_rows(0);
    test_rows(1);
    test_grams();
    test_skyline();
    check_status(mcg_bilinear_rows(0, x, x, NULL, NULL, rows), MCG_EINVAL, "bilinear: n = 0");
    check_status(mcg_bilinear_rows(1, x, NULL, NULL, NULL, rows), MCG_EINVAL,
                 "bilinear: NULL bearing");
    check_status(mcg_bilinear_rows(1, x, x + 3, x, NULL, rows), MCG_EINVAL,
                 "bilinear: one offset array missing");
    x[1] = NAN;
    check_status(mcg_bilinear_rows(1, x, x + 3, NULL, NULL, rows), MCG_EINVAL,
                 "bilinear: NaN bearing");
    printf("%d checks, %d failed\n", n_checks, n_failed);
    return n_failed != 0;
}
