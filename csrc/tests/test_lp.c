/*
 * test_lp.c -- plain-C checks of the LP feasibility backends (lp_native.c,
 * and lp_glpk.c when it is built and libglpk loads: MCG_GLPK_LIBRARY): known feasible / infeasible
 * instances (empty, unbounded, redundant, nearly parallel, zero rows),
 * random instances with m <= 8 against brute-force vertex enumeration,
 * large random instances with a known answer, determinism, and the status
 * codes of invalid arguments. Exit status 0 iff every check passes.
 */
#include "mcgeom.h"

#define TEST_SEED 0x1b5eedULL
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define MMAX 200000
#define BIG_BF 1e6

static double A[3 * MMAX], B[MMAX], W[7 * (MMAX + 6) + 16];

static int native(int dim, int m, const double *a, const double *b, double *x)
{
    return mcg_lp_native_feasible(dim, m, a, b, x, W, sizeof W / sizeof W[0]);
}

/* solve the dim x dim system M y = r (Gaussian elimination, partial pivot);
 * 0 if singular */
static int solve_small(int d, double *M, double *r, double *y)
{
    int i, j, k;
    for (k = 0; k < d; ++k) {
        int p = k;
        for (i = k + 1; i < d; ++i)
            if (fabs(M[i * d + k]) > fabs(M[p * d + k]))
                p = i;
        if (fabs(M[p * d + k]) < 1e-12)
            return 0;
        if (p != k) {
            for (j = 0; j < d; ++j) {
                double t = M[k * d + j];
                M[k * d + j] = M[p * d + j];
                M[p * d + j] = t;
            }
            {
                double t = r[k];
                r[k] = r[p];
                r[p] = t;
            }
        }
        for (i = k + 1; i < d; ++i) {
            double f = M[i * d + k] / M[k * d + k];
            for (j = k; j < d; ++j)
                M[i * d + j] -= f * M[k * d + j];
            r[i] -= f * r[k];
        }
    }
    for (i = d - 1; i >= 0; --i) {
        double s = r[i];
        for (j = i + 1; j < d; ++j)
            s -= M[i * d + j] * y[j];
        y[i] = s / M[i * d + i];
    }
    return 1;
}

/* brute force: the rows (unit-normalised, relaxed by delta) plus the box
 * |x_i| <= BIG_BF have a vertex satisfying all of them? */
static int brute(int dim, int m, const double *a, const double *b,
                 double delta)
{
    double ra[40 * 3], rb[40];
    int n = 0, i, k, idx[3];
    for (k = 0; k < m; ++k) {
        double nn = 0;
        for (i = 0; i < dim; ++i)
            nn += a[k * dim + i] * a[k * dim + i];
        nn = sqrt(nn);
        for (i = 0; i < dim; ++i)
            ra[n * dim + i] = a[k * dim + i] / nn;
        rb[n++] = b[k] / nn - delta;
    }
    for (i = 0; i < dim; ++i) {
        int j;
        for (j = 0; j < dim; ++j) {
            ra[n * dim + j] = (i == j);
            ra[(n + 1) * dim + j] = -(double)(i == j);
        }
        rb[n] = -BIG_BF;
        rb[n + 1] = -BIG_BF;
        n += 2;
    }
    for (idx[0] = 0; idx[0] < n; ++idx[0])
        for (idx[1] = idx[0] + 1; idx[1] < n; ++idx[1])
            for (idx[2] = (dim == 3 ? idx[1] + 1 : 0);
                 idx[2] < (dim == 3 ? n : 1); ++idx[2]) {
                double M[9], r[3], y[3];
                int ok = 1;
                for (k = 0; k < dim; ++k) {
                    for (i = 0; i < dim; ++i)
                        M[k * dim + i] = ra[idx[k] * dim + i];
                    r[k] = rb[idx[k]];
                }
                if (!solve_small(dim, M, r, y))
                    continue;
                for (k = 0; k < n && ok; ++k) {
                    double s = 0;
                    for (i = 0; i < dim; ++i)
                        s += ra[k * dim + i] * y[i];
                    if (s < rb[k] - 1e-9)
                        ok = 0;
                }
                if (ok)
                    return 1;
            }
    return 0;
}

static int satisfies(int dim, int m, const double *a, const double *b,
                     const double *x, double tol)
{
    int k, i;
    double S = 1.0; /* the scale of the documented tolerance */
    for (k = 0; k < m; ++k) {
        double nn = 0;
        for (i = 0; i < dim; ++i)
            nn += a[k * dim + i] * a[k * dim + i];
        if (nn > 0 && fabs(b[k]) / sqrt(nn) > S)
            S = fabs(b[k]) / sqrt(nn);
    }
    for (k = 0; k < m; ++k) {
        double s = 0, nn = 0;
        for (i = 0; i < dim; ++i) {
            s += a[k * dim + i] * x[i];
            nn += a[k * dim + i] * a[k * dim + i];
        }
        if (s < b[k] - tol * S * sqrt(nn))
            return 0;
    }
    return 1;
}

static void known(void)
{
    double x[3];
    /* 1-D-like: x >= 1 and -x >= 0 */
    {
        double a[] = {1, 0, -1, 0}, b[] = {1, 0};
        check_status(native(2, 2, a, b, x), MCG_EINFEASIBLE,
                     "2d empty: x >= 1, x <= 0");
    }
    {
        double a[] = {1, 0}, b[] = {1};
        check_status(native(2, 1, a, b, x), MCG_OK, "2d unbounded: x >= 1");
        check(x[0] >= 1 - 1e-8, "2d unbounded: x satisfies", x[0], 0);
    }
    {
        double a[] = {1, 0, 0}, b[] = {1};
        check_status(native(3, 1, a, b, x), MCG_OK, "3d unbounded: x >= 1");
    }
    check_status(native(2, 0, NULL, NULL, x), MCG_OK, "2d m = 0");
    check_status(native(3, 0, NULL, NULL, x), MCG_OK, "3d m = 0");
    {
        double a[] = {0, 0}, b[] = {1};
        check_status(native(2, 1, a, b, x), MCG_EINFEASIBLE, "zero row 0 >= 1");
        b[0] = -1;
        check_status(native(2, 1, a, b, x), MCG_OK, "zero row 0 >= -1");
    }
    {
        /* redundant copies of a triangle, scaled rows */
        double a[60], b[30];
        int k;
        for (k = 0; k < 30; ++k) {
            double s = 1.0 + k, tri[3][3] = {{1, 0, 0}, {0, 1, 0}, {-1, -1, -1}};
            a[2 * k] = s * tri[k % 3][0];
            a[2 * k + 1] = s * tri[k % 3][1];
            b[k] = s * tri[k % 3][2];
        }
        check_status(native(2, 30, a, b, x), MCG_OK, "redundant triangle");
        check(satisfies(2, 30, a, b, x, 2.001e-9), "redundant triangle: x inside",
              0, 0);
        for (k = 0; k < 30; ++k)
            if (k % 3 == 2)
                b[k] = (1.0 + k) * 0.001; /* x + y <= -0.001 */
        check_status(native(2, 30, a, b, x), MCG_EINFEASIBLE,
                     "redundant triangle made empty");
    }
    {
        /* nearly parallel: y >= x * 1e-7 + 1, y <= x * 2e-7 + 1 - 1e-3:
         * feasible only for x >= 1e4 (inside the box) */
        double a[] = {-1e-7, 1, 2e-7, -1}, b[] = {1, -1 + 1e-3};
        check_status(native(2, 2, a, b, x), MCG_OK,
                     "nearly parallel strip, apex at x = 1e4");
        check(satisfies(2, 2, a, b, x, 2.001e-9), "nearly parallel: x satisfies",
              x[0], 0);
        a[2] = 1e-7 * (1 - 1e-12); /* both slopes equal: empty strip... */
        a[0] = -1e-7;
        check_status(native(2, 2, a, b, x), MCG_EINFEASIBLE,
                     "parallel empty strip");
    }
    {
        /* exactly parallel rows, overlapping slab */
        double a[] = {1, 1, -1, -1, 2, 2}, b[] = {1, -3, 2.5};
        check_status(native(2, 3, a, b, x), MCG_OK, "parallel slab");
        check(satisfies(2, 3, a, b, x, 2.001e-9), "parallel slab: x satisfies", 0,
              0);
        b[1] = -0.9;
        check_status(native(2, 3, a, b, x), MCG_EINFEASIBLE,
                     "parallel empty slab");
    }
    {
        double a[] = {1, 0, 0, 0, 1, 0, 0, 0, 1, -1, -1, -1}, b[] = {0, 0, 0, 1};
        check_status(native(3, 4, a, b, x), MCG_EINFEASIBLE,
                     "3d octant and x+y+z <= -1");
        b[3] = -1;
        check_status(native(3, 4, a, b, x), MCG_OK, "3d simplex");
        check(satisfies(3, 4, a, b, x, 2.001e-9), "3d simplex: x satisfies", 0, 0);
    }
    {
        /* a thin 3-D wedge of translation cones (two planes, nearly
         * antiparallel normals): feasible with margin 1e-6 */
        double a[] = {0, 1, 0, 0, -1, 1e-9, 1, 0, 0},
               b[] = {0, -1e-6, 0.5};
        check_status(native(3, 3, a, b, x), MCG_OK, "3d thin wedge");
        check(satisfies(3, 3, a, b, x, 2.001e-9), "3d thin wedge: x satisfies", 0,
              0);
    }
}

static void random_small(void)
{
    int trial, dim, agree = 0, tested = 0, n_feas = 0, bad_x = 0, sure = 0;
    int degen_fail = 0;
    double x[3];
    for (trial = 0; trial < scaled(6000); ++trial) {
        int m, k, i, st, bf_lo, bf_hi;
        double x0[3];
        dim = 2 + trial % 2;
        m = 1 + (int)(urand() * (dim == 2 ? 10 : 8));
        randn(x0, 3);
        for (k = 0; k < m; ++k) {
            double s = 0;
            randn(A + k * dim, dim);
            if (trial % 5 == 0 && k > 0) /* near-duplicate directions */
                for (i = 0; i < dim; ++i)
                    A[k * dim + i] = A[i] + 1e-6 * nrand();
            for (i = 0; i < dim; ++i)
                s += A[k * dim + i] * x0[i];
            B[k] = s + nrand() * 2.0;
            if (trial % 7 == 0)
                B[k] = s; /* all rows through x0: degenerate, feasible */
        }
        if (trial % 7 == 0 && native(dim, m, A, B, x) != MCG_OK)
            ++degen_fail;
        st = native(dim, m, A, B, x);
        bf_lo = brute(dim, m, A, B, 1e-7);  /* relaxed: feasible? */
        bf_hi = brute(dim, m, A, B, -1e-7); /* tightened: feasible? */
        ++tested;
        if (bf_lo == bf_hi) {
            ++sure;
            if ((st == MCG_OK) == bf_lo &&
                (st == MCG_OK || st == MCG_EINFEASIBLE))
                ++agree;
            else
                printf("  disagree: trial %d dim %d m %d native %d brute %d\n",
                       trial, dim, m, st, bf_lo);
        } else if (st == MCG_OK || st == MCG_EINFEASIBLE) {
            ++agree; /* within 1e-7 of the boundary: either answer */
        }
        if (st == MCG_OK) {
            ++n_feas;
            if (!satisfies(dim, m, A, B, x, 2.001e-9))
                ++bad_x;
        }
    }
    printf("random small: %d instances (%d clear-cut), %d feasible\n", tested,
           sure, n_feas);
    check(agree == tested, "random m <= 10: native agrees with brute force",
          (double)(tested - agree), 0);
    check(degen_fail == 0, "degenerate: all rows through one point feasible",
          (double)degen_fail, 0);
    check(bad_x == 0, "random: returned x satisfies all rows", (double)bad_x,
          0);
    check(n_feas > tested / 5 && n_feas < tested * 4 / 5,
          "random: both answers occur", (double)n_feas / tested, 0);
}

static void random_large(void)
{
    int dim, st, k, i, ok_f = 1, ok_i = 1, ok_det = 1;
    double x[3], x2[3];
    for (dim = 2; dim <= 3; ++dim) {
        int m = scaled(MMAX) < 1000 ? 1000 : scaled(MMAX);
        double x0[3];
        randn(x0, 3);
        /* feasible: tangent to a unit ball around x0 */
        for (k = 0; k < m; ++k) {
            double s = 0, nn = 0;
            randn(A + k * dim, dim);
            for (i = 0; i < dim; ++i) {
                s += A[k * dim + i] * x0[i];
                nn += A[k * dim + i] * A[k * dim + i];
            }
            B[k] = s - sqrt(nn);
        }
        st = native(dim, m, A, B, x);
        if (st != MCG_OK || !satisfies(dim, m, A, B, x, 2.001e-9))
            ok_f = 0;
        st = native(dim, m, A, B, x2);
        if (st != MCG_OK || memcmp(x, x2, sizeof(double) * (size_t)dim) != 0)
            ok_det = 0;
        /* infeasible: a_k . x >= 1 for directions all around */
        for (k = 0; k < m; ++k)
            B[k] = 1.0;
        st = native(dim, m, A, B, x);
        if (st != MCG_EINFEASIBLE)
            ok_i = 0;
        /* infeasible by a tiny margin: ball of radius -1e-5 */
        for (k = 0; k < m; ++k) {
            double s = 0, nn = 0;
            for (i = 0; i < dim; ++i) {
                s += A[k * dim + i] * x0[i];
                nn += A[k * dim + i] * A[k * dim + i];
            }
            B[k] = s + 1e-5 * sqrt(nn);
        }
        st = native(dim, m, A, B, x);
        if (st != MCG_EINFEASIBLE)
            ok_i = 0;
    }
    check(ok_f, "m = 2e5 feasible (tangent to a ball), 2d and 3d", 0, 0);
    check(ok_det, "deterministic: same x on a second call", 0, 0);
    check(ok_i, "m = 2e5 infeasible (all around; margin 1e-5)", 0, 0);
}

static void invalid(void)
{
    double a[] = {1, 0, 0}, b[] = {1}, x[3], w[64];
    mcg_lp_backend be;
    check_status(mcg_lp_native_feasible(4, 1, a, b, x, w, 64), MCG_EINVAL,
                 "dim 4");
    check_status(mcg_lp_native_feasible(1, 1, a, b, x, w, 64), MCG_EINVAL,
                 "dim 1");
    check_status(mcg_lp_native_feasible(3, -1, a, b, x, w, 64), MCG_EINVAL,
                 "m < 0");
    check_status(mcg_lp_native_feasible(3, 1, NULL, b, x, w, 64), MCG_EINVAL,
                 "NULL A");
    check_status(mcg_lp_native_feasible(3, 1, a, b, NULL, w, 64), MCG_EINVAL,
                 "NULL x");
    check_status(mcg_lp_native_feasible(3, 1, a, b, x, w, 3), MCG_ENOMEM,
                 "lwork too small");
    check_status(mcg_lp_native_feasible(3, 1, a, b, x, NULL, 64), MCG_EINVAL,
                 "NULL work");
    a[1] = NAN;
    check_status(mcg_lp_native_feasible(3, 1, a, b, x, w, 64), MCG_EINVAL,
                 "NaN in A");
    a[1] = 0;
    b[0] = INFINITY;
    check_status(mcg_lp_native_feasible(3, 1, a, b, x, w, 64), MCG_EINVAL,
                 "inf in b");
    b[0] = 1;
    check(mcg_lp_native_work_size(3, -1) == 0 &&
              mcg_lp_native_work_size(5, 3) == 0,
          "work size 0 for invalid sizes", 0, 0);
    check_status(mcg_lp_native_backend(&be), MCG_OK, "native backend table");
    check(strcmp(be.name, "native") == 0, "backend name", 0, 0);
    check_status(mcg_lp_feasible(&be, 3, 1, a, b, x, w,
                                 mcg_lp_work_size(&be, 3, 1)),
                 MCG_OK, "through the table");
    check_status(mcg_lp_feasible(NULL, 3, 1, a, b, x, w, 64), MCG_EINVAL,
                 "NULL backend");
}

/* GLPK backend (when built in): the same answers as the native backend and
 * brute force on clear-cut random instances (random, near-duplicate rows,
 * all rows through one point), and on large instances with a known answer */
static void cross_glpk(void)
{
    static double WG[3 * (1 + 4 * 5000)];
    double x[3], xg[3], x0[3];
    int trial, dim, k, i, disagree = 0, clear = 0, bad_x = 0, sg, sn;
    if (mcg_lp_glpk_load(NULL) != MCG_OK) {
        printf("GLPK backend not built or libglpk not found: cross-check skipped\n");
        check(!mcg_lp_glpk_available(), "glpk says not available", 0, 0);
        check_status(mcg_lp_glpk_backend(NULL), MCG_EINVAL, "glpk backend(NULL)");
        check_status(mcg_lp_glpk_feasible(2, 1, x, x, xg, WG, 3), MCG_EUNAVAILABLE,
                     "glpk unloaded: feasible says unavailable");
        return;
    }
    check_status(mcg_lp_glpk_load(NULL), MCG_OK, "glpk load is idempotent");
    for (trial = 0; trial < scaled(4000); ++trial) {
        int m, bf_lo, bf_hi;
        dim = 2 + trial % 2;
        m = 1 + (int)(urand() * 9);
        randn(x0, 3);
        for (k = 0; k < m; ++k) {
            double s = 0;
            randn(A + k * dim, dim);
            if (trial % 5 == 0 && k > 0)
                for (i = 0; i < dim; ++i)
                    A[k * dim + i] = A[i] + 1e-6 * nrand();
            for (i = 0; i < dim; ++i)
                s += A[k * dim + i] * x0[i];
            B[k] = s + nrand() * 2.0;
            if (trial % 7 == 0)
                B[k] = s;
        }
        sn = native(dim, m, A, B, x);
        sg = mcg_lp_glpk_feasible(dim, m, A, B, xg, WG, sizeof WG / sizeof WG[0]);
        if (sg == MCG_OK && !satisfies(dim, m, A, B, xg, 2.001e-8))
            ++bad_x;
        bf_lo = brute(dim, m, A, B, 1e-6);
        bf_hi = brute(dim, m, A, B, -1e-6);
        if (trial % 7 == 0) {
            if (sg != MCG_OK || sn != MCG_OK) {
                ++disagree;
                printf("  degenerate trial %d dim %d m %d: native %d glpk %d\n",
                       trial, dim, m, sn, sg);
            }
            continue;
        }
        if (bf_lo != bf_hi)
            continue;
        ++clear;
        if (sg != sn || (sg != MCG_OK && sg != MCG_EINFEASIBLE)) {
            ++disagree;
            printf("  trial %d dim %d m %d: native %d glpk %d brute %d\n",
                   trial, dim, m, sn, sg, bf_lo);
        }
    }
    /* large: feasible (tangent to a ball), infeasible (all around, and by
     * a margin of 1e-5) */
    for (dim = 2; dim <= 3; ++dim) {
        int m = scaled(5000) < 100 ? 100 : scaled(5000), c;
        randn(x0, 3);
        for (c = 0; c < 3; ++c) {
            for (k = 0; k < m; ++k) {
                double s = 0, nn = 0;
                if (c == 0)
                    randn(A + k * dim, dim);
                for (i = 0; i < dim; ++i) {
                    s += A[k * dim + i] * x0[i];
                    nn += A[k * dim + i] * A[k * dim + i];
                }
                B[k] = c == 0 ? s - sqrt(nn) : (c == 1 ? 1.0 : s + 1e-5 * sqrt(nn));
            }
            sn = native(dim, m, A, B, x);
            sg = mcg_lp_glpk_feasible(dim, m, A, B, xg, WG,
                                      sizeof WG / sizeof WG[0]);
            ++clear;
            if (sn != sg || sg != (c == 0 ? MCG_OK : MCG_EINFEASIBLE)) {
                ++disagree;
                printf("  large dim %d case %d: native %d glpk %d\n", dim, c,
                       sn, sg);
            }
        }
    }
    printf("glpk cross-check: %d clear-cut instances\n", clear);
    check(disagree == 0, "glpk and native agree (clear-cut instances)",
          (double)disagree, 0);
    check(bad_x == 0, "glpk: returned x satisfies all rows", (double)bad_x, 0);
}

int main(void)
{
    known();
    random_small();
    random_large();
    invalid();
    cross_glpk();
    printf("%d checks, %d failed\n", n_checks, n_failed);
    return n_failed != 0;
}
