/*
 * test_cls.c -- plain-C checks of csrc/cls.c (thesis Algorithms 3-4,
 * eq. 8.36, ch. 6.3) against independent facts:
 *   - the constraint holds (|C x| = 1, |x[:p]| = 1, |x| = 1 and x in
 *     range(G)) and resid = |A x|;
 *   - first-order optimality (Lagrange): A^T A x = lambda C^T C x with
 *     lambda = resid^2 (general), A_2^T A x = 0 and A_1^T A x = lambda x_1
 *     (partial), P A^T A x = lambda x with P the projector on range(G);
 *   - the minimum is no worse than thousands of random feasible points;
 *   - an independent route where one exists (C invertible: y = C x and the
 *     smallest singular value of A C^{-1}; partial with p = n: s_min(A);
 *     general with C = [I | 0] equals partial);
 *   - the generalized epipolar system of a synthetic rig motion is solved
 *     exactly (x = +-(vec E, vec R) / |E|);
 *   - rank2 of A_2 with the rcond tolerance; minimum-norm x[p:];
 *   - status codes of invalid inputs.
 * Exit status 0 iff every check passes.
 */
#include "mcgeom.h"

#define TEST_SEED 0x13198a2e03707344ULL
#include "testutil.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAXM 64
#define MAXN 20
#define NRAND 3000

static double work[200000];
static const size_t LWORK = sizeof work / sizeof work[0];

/* y = a^T x, a m x n */
static void matvec_t(int m, int n, const double *a, const double *x,
                     double *y)
{
    int i, j;
    for (j = 0; j < n; ++j)
        y[j] = 0.0;
    for (i = 0; i < m; ++i)
        for (j = 0; j < n; ++j)
            y[j] += a[i * n + j] * x[i];
}

static double nrm(const double *x, int n)
{
    double acc = 0.0;
    int i;
    for (i = 0; i < n; ++i)
        acc += x[i] * x[i];
    return sqrt(acc);
}

/* |A x| */
static double resid_of(int m, int n, const double *a, const double *x)
{
    double y[MAXM];
    matmul(m, n, 1, a, x, y);
    return nrm(y, m);
}

/* ------------------------------------------------------------ general */

static void general_case(int m, int n, int k, const double *a,
                         const double *c, const char *label)
{
    double x[MAXN], y[MAXM], g1[MAXN], g2[MAXN], cx[MAXM], z[MAXN];
    double resid = -1, lam, e, best = INFINITY, na2;
    char what[160];
    int st, i, t;
    size_t ws = mcg_cls_general_work_size(m, n, k);
    st = mcg_cls_general(m, n, k, a, c, x, &resid, work, ws);
    snprintf(what, sizeof what, "general %s (m=%d n=%d k=%d) status", label,
             m, n, k);
    check_status(st, MCG_OK, what);
    if (st != MCG_OK)
        return;
    matmul(k, n, 1, c, x, cx);
    e = fabs(nrm(cx, k) - 1.0);
    snprintf(what, sizeof what, "general %s  |C x| = 1", label);
    check(e < 1e-12, what, e, 1e-12);
    e = fabs(resid - resid_of(m, n, a, x)) / (1.0 + resid);
    snprintf(what, sizeof what, "general %s  resid = |A x|", label);
    check(e < 1e-13, what, e, 1e-13);
    /* Lagrange: A^T A x = lambda C^T C x, lambda = resid^2 */
    lam = resid * resid;
    matmul(m, n, 1, a, x, y);
    matvec_t(m, n, a, y, g1);
    matvec_t(k, n, c, cx, g2);
    na2 = 0.0;
    for (i = 0; i < m * n; ++i)
        na2 += a[i] * a[i];
    e = 0.0;
    for (i = 0; i < n; ++i)
        e = fmax(e, fabs(g1[i] - lam * g2[i]));
    e /= na2 * nrm(x, n);
    snprintf(what, sizeof what, "general %s  A^T A x = resid^2 C^T C x", label);
    check(e < 1e-13, what, e, 1e-13);
    /* random feasible points z / |C z| */
    for (t = 0; t < NRAND; ++t) {
        double nc, r;
        randn(z, n);
        matmul(k, n, 1, c, z, cx);
        nc = nrm(cx, k);
        if (nc < 1e-3)
            continue;
        for (i = 0; i < n; ++i)
            z[i] /= nc;
        r = resid_of(m, n, a, z);
        if (r < best)
            best = r;
    }
    snprintf(what, sizeof what,
             "general %s  resid <= min over %d random feasible", label, NRAND);
    check(resid <= best * (1.0 + 1e-12), what, resid - best, 0.0);
}

static void test_general(void)
{
    static double a[MAXM * MAXN], c[MAXM * MAXN], b1[MAXM * MAXN],
        b2[MAXM * MAXN];
    int i;
    randn(a, 20 * 6);
    randn(c, 6 * 6);
    general_case(20, 6, 6, a, c, "C square");
    /* independent route: y = C x, min |A C^{-1} y| s.t. |y| = 1 */
    {
        double cinv[36], ac[120], x[6], s[6], v[36], resid;
        int rank;
        mcg_pinv(6, 6, c, 0.0, cinv, &rank, work, LWORK);
        matmul(20, 6, 6, a, cinv, ac);
        mcg_svd(20, 6, ac, NULL, s, v, work, LWORK);
        mcg_cls_general(20, 6, 6, a, c, x, &resid, work, LWORK);
        check(fabs(resid - s[5]) < 1e-12 * s[0],
              "general C square: resid = s_min(A C^-1)", fabs(resid - s[5]),
              1e-12 * s[0]);
    }
    randn(c, 3 * 6);
    general_case(20, 6, 3, a, c, "C wide 3x6");
    /* C 8x8 of rank 5 */
    randn(b1, 8 * 5);
    randn(b2, 5 * 8);
    matmul(8, 5, 8, b1, b2, c);
    randn(a, 20 * 8);
    general_case(20, 8, 8, a, c, "C rank 5");
    /* A wide (m < n): zero residual reachable */
    randn(a, 5 * 8);
    randn(c, 4 * 8);
    general_case(5, 8, 4, a, c, "A wide 5x8");
    {
        double x[8], resid;
        mcg_cls_general(5, 8, 4, a, c, x, &resid, work, LWORK);
        check(resid < 1e-13, "general A wide: resid ~ 0 (null space hit)",
              resid, 1e-13);
    }
    /* C = [I_9 | 0] vs partial */
    {
        double x1[18], x2[18], r1, r2, e = 0.0, sgn;
        int rank2;
        randn(a, 30 * 18);
        memset(c, 0, sizeof(double) * 9 * 18);
        for (i = 0; i < 9; ++i)
            c[i * 18 + i] = 1.0;
        general_case(30, 18, 9, a, c, "C = [I9 | 0]");
        mcg_cls_general(30, 18, 9, a, c, x1, &r1, work, LWORK);
        mcg_cls_partial(30, 18, 9, a, 0.0, x2, &r2, &rank2, work, LWORK);
        sgn = (x1[0] * x2[0] + x1[1] * x2[1] + x1[2] * x2[2] >= 0) ? 1 : -1;
        for (i = 0; i < 18; ++i)
            e = fmax(e, fabs(x1[i] - sgn * x2[i]));
        check(fabs(r1 - r2) < 1e-12 * (1 + r1) && e < 1e-12,
              "general with C = [I|0] equals partial (x up to sign)", e,
              1e-12);
    }
    /* C diagonal, C_ll = 0.5 + l / 16, except C_pp = d << 1 above the rank
     * cut (fuzz_cls found a 1.3e-3 error; 45 % in tests): the minimiser
     * needs no component ~ 1 / d along e_p, so the minimum equals, to
     * O(d^2), the one with x[p] free: partial (p = 7 constrained columns
     * A_l / C_ll, then the free column A_p) */
    {
        static const double dd[3] = {1e-9, 1e-13, 4e-15};
        double x1[8], x2[8], r1, r2, worst = 0.0;
        int rank2, trial, l;
        for (trial = 0; trial < 30; ++trial) {
            const int p = trial % 8; /* the small direction, any axis */
            randn(a, 12 * 8);
            memset(c, 0, sizeof(double) * 8 * 8);
            for (l = 0; l < 8; ++l)
                c[l * 8 + l] = l == p ? dd[trial % 3] : 0.5 + 0.5 * (double)l / 8.0;
            mcg_cls_general(12, 8, 8, a, c, x1, &r1, work, LWORK);
            for (i = 0; i < 12; ++i) {
                int col = 0;
                for (l = 0; l < 8; ++l)
                    if (l != p)
                        b1[i * 8 + col++] = a[i * 8 + l] / c[l * 8 + l];
                b1[i * 8 + 7] = a[i * 8 + p];
            }
            mcg_cls_partial(12, 8, 7, b1, 0.0, x2, &r2, &rank2, work, LWORK);
            worst = fmax(worst, fabs(r1 - r2) / r2);
        }
        check(worst < 1e-12, "general: C with a singular value 4e-15..1e-9 equals "
              "partial with that direction free", worst, 1e-12);
    }
    /* scaled C: the solution scales inversely */
    {
        double x1[6], x2[6], r1, r2, e = 0.0, sgn;
        randn(a, 20 * 6);
        randn(c, 6 * 6);
        mcg_cls_general(20, 6, 6, a, c, x1, &r1, work, LWORK);
        for (i = 0; i < 36; ++i)
            b1[i] = 1e6 * c[i];
        mcg_cls_general(20, 6, 6, a, b1, x2, &r2, work, LWORK);
        sgn = (x1[0] * x2[0] >= 0) ? 1 : -1;
        for (i = 0; i < 6; ++i)
            e = fmax(e, fabs(1e6 * sgn * x2[i] - x1[i]) / nrm(x1, 6));
        check(e < 1e-12 && fabs(1e6 * r2 - r1) < 1e-12 * r1,
              "general: C -> 1e6 C scales x and resid by 1e-6", e, 1e-12);
    }
}

/* ------------------------------------------------------------ partial */

static void partial_case(int m, int n, int p, const double *a, double rcond,
                         int want_rank2, const char *label)
{
    static double a1[MAXM * MAXN], a2[MAXM * MAXN], a2p[MAXM * MAXN];
    double x[MAXN], z[MAXN], y[MAXM], g[MAXN], resid = -1, e, lam, na2,
        best = INFINITY, x1n;
    char what[160];
    int st, i, j, t, rank2 = -1, rk;
    size_t ws = mcg_cls_partial_work_size(m, n, p);
    st = mcg_cls_partial(m, n, p, a, rcond, x, &resid, &rank2, work, ws);
    snprintf(what, sizeof what, "partial %s (m=%d n=%d p=%d) status", label,
             m, n, p);
    check_status(st, MCG_OK, what);
    if (st != MCG_OK)
        return;
    snprintf(what, sizeof what, "partial %s  rank2 = %d", label, want_rank2);
    check(rank2 == want_rank2, what, (double)rank2, (double)want_rank2);
    x1n = nrm(x, p);
    e = fabs(x1n - 1.0);
    snprintf(what, sizeof what, "partial %s  |x[:p]| = 1", label);
    check(e < 1e-14, what, e, 1e-14);
    e = fabs(resid - resid_of(m, n, a, x)) / (1.0 + resid);
    snprintf(what, sizeof what, "partial %s  resid = |A x|", label);
    check(e < 1e-13, what, e, 1e-13);
    /* optimality: A^T A x = (lambda x_1, 0) */
    matmul(m, n, 1, a, x, y);
    matvec_t(m, n, a, y, g);
    lam = resid * resid;
    na2 = 0.0;
    for (i = 0; i < m * n; ++i)
        na2 += a[i] * a[i];
    e = 0.0;
    for (i = 0; i < n; ++i)
        e = fmax(e, fabs(g[i] - (i < p ? lam * x[i] : 0.0)));
    e /= na2 * nrm(x, n);
    snprintf(what, sizeof what, "partial %s  A^T A x = (resid^2 x1, 0)", label);
    check(e < 1e-13, what, e, 1e-13);
    /* x[p:] = -A_2^+ A_1 x[:p] (eq. 8.36) with an explicit pseudo-inverse */
    if (p < n) {
        int n2 = n - p;
        double r1[MAXM], x2[MAXN];
        for (i = 0; i < m; ++i)
            for (j = 0; j < n; ++j) {
                if (j < p)
                    a1[i * p + j] = a[i * n + j];
                else
                    a2[i * n2 + j - p] = a[i * n + j];
            }
        mcg_pinv(m, n2, a2, rcond > 0 ? rcond : 1e-10, a2p, &rk, work, LWORK);
        matmul(m, p, 1, a1, x, r1);
        matmul(n2, m, 1, a2p, r1, x2);
        e = 0.0;
        for (i = 0; i < n2; ++i)
            e = fmax(e, fabs(x[p + i] + x2[i]));
        e /= nrm(x, n);
        snprintf(what, sizeof what, "partial %s  x[p:] = -A2^+ A1 x[:p]",
                 label);
        check(e < 1e-12 && rk == rank2, what, e, 1e-12);
    }
    /* random feasible points: random unit x1, random or optimal x2 */
    for (t = 0; t < NRAND; ++t) {
        double nz, r;
        randn(z, n);
        nz = nrm(z, p);
        for (i = 0; i < p; ++i)
            z[i] /= nz;
        r = resid_of(m, n, a, z);
        if (r < best)
            best = r;
        if (p < n && t % 2 == 0) { /* optimal x2 for this x1 */
            int n2 = n - p;
            double r1[MAXM], x2[MAXN];
            matmul(m, p, 1, a1, z, r1);
            matmul(n2, m, 1, a2p, r1, x2);
            for (i = 0; i < n2; ++i)
                z[p + i] = -x2[i];
            r = resid_of(m, n, a, z);
            if (r < best)
                best = r;
        }
    }
    snprintf(what, sizeof what,
             "partial %s  resid <= min over %d random feasible", label, NRAND);
    /* absolute slack: both may be at rounding level when A_2 is wide */
    check(resid <= best * (1.0 + 1e-12) + 1e-14 * sqrt(na2), what,
          resid - best, 1e-14 * sqrt(na2));
}

/* synthetic generalized epipolar system (see test_plucker.c) */
static void gec_system(int n, double *rows, double *xtrue)
{
    double r[9], t[3] = {0.2, 0.05, -0.15}, q[4], nq = 0.0, tx[9];
    double o1[3 * MAXM], d1[3 * MAXM], o2[3 * MAXM], d2[3 * MAXM];
    double L1[6 * MAXM], L2[6 * MAXM];
    int i, j, k;
    for (i = 0; i < 4; ++i) {
        q[i] = nrand();
        nq += q[i] * q[i];
    }
    for (i = 0; i < 4; ++i)
        q[i] /= sqrt(nq);
    mcg_rot_from_quat(q, r);
    tx[0] = 0;
    tx[1] = -t[2];
    tx[2] = t[1];
    tx[3] = t[2];
    tx[4] = 0;
    tx[5] = -t[0];
    tx[6] = -t[1];
    tx[7] = t[0];
    tx[8] = 0;
    matmul(3, 3, 3, tx, r, xtrue);
    for (i = 0; i < 9; ++i)
        xtrue[9 + i] = r[i];
    for (k = 0; k < n; ++k) {
        double x[3], x2[3];
        for (i = 0; i < 3; ++i) {
            x[i] = 3.0 * nrand();
            o1[3 * k + i] = 0.4 * nrand();
            o2[3 * k + i] = 0.4 * nrand();
        }
        x[2] += 8.0;
        for (i = 0; i < 3; ++i) {
            x2[i] = t[i];
            for (j = 0; j < 3; ++j)
                x2[i] += r[3 * i + j] * x[j];
            d1[3 * k + i] = x[i] - o1[3 * k + i];
            d2[3 * k + i] = x2[i] - o2[3 * k + i];
        }
    }
    mcg_plucker_from_points(n, o1, d1, L1);
    mcg_plucker_from_points(n, o2, d2, L2);
    mcg_gec_rows(n, L1, L2, rows);
}

static void test_partial(void)
{
    static double a[MAXM * MAXN], b1[MAXM * MAXN], b2[MAXM * MAXN];
    int i, j;
    randn(a, 30 * 18);
    partial_case(30, 18, 9, a, 0.0, 9, "random");
    randn(a, 12 * 7);
    partial_case(12, 7, 3, a, 0.0, 4, "random 12x7 p=3");
    /* m < n - p: A_2 wide, rank m */
    randn(a, 6 * 18);
    partial_case(6, 18, 9, a, 0.0, 6, "wide A2");
    /* A_2 of rank 5 */
    randn(a, 30 * 18);
    randn(b1, 30 * 5);
    randn(b2, 5 * 9);
    matmul(30, 5, 9, b1, b2, b1 + 30 * 5);
    for (i = 0; i < 30; ++i)
        for (j = 0; j < 9; ++j)
            a[i * 18 + 9 + j] = b1[30 * 5 + i * 9 + j];
    partial_case(30, 18, 9, a, 0.0, 5, "A2 rank 5");
    /* minimum norm: x[p:] lies in the row space of A_2 (pinv(A2) A2 x2 = x2) */
    {
        double x[18], a2[270], a2p[270], y[30], z[9], e = 0.0;
        int rk;
        mcg_cls_partial(30, 18, 9, a, 0.0, x, NULL, NULL, work, LWORK);
        for (i = 0; i < 30; ++i)
            for (j = 0; j < 9; ++j)
                a2[i * 9 + j] = a[i * 18 + 9 + j];
        mcg_pinv(30, 9, a2, 1e-10, a2p, &rk, work, LWORK);
        matmul(30, 9, 1, a2, x + 9, y);
        matmul(9, 30, 1, a2p, y, z);
        for (i = 0; i < 9; ++i)
            e = fmax(e, fabs(z[i] - x[9 + i]));
        check(e < 1e-12, "partial A2 rank 5: x[p:] is the minimum-norm part",
              e, 1e-12);
    }
    /* rcond decides the rank of A_2: singular values 1 .. 1e-8 */
    {
        double s2[9];
        for (i = 0; i < 9; ++i)
            s2[i] = (i < 8) ? pow(10.0, -(double)i / 2.0) : 1e-8;
        randn(a, 30 * 18);
        randn(b1, 30 * 9);
        for (i = 0; i < 30; ++i) /* A_2 = B1 (orthonormalised) diag(s2) */
            for (j = 0; j < 9; ++j)
                b2[i * 9 + j] = b1[i * 9 + j];
        {
            double q[270], r[81];
            mcg_qr(30, 9, b2, q, r, work, LWORK);
            for (i = 0; i < 30; ++i)
                for (j = 0; j < 9; ++j)
                    a[i * 18 + 9 + j] = q[i * 9 + j] * s2[j];
        }
        partial_case(30, 18, 9, a, 0.0, 9, "s(A2) to 1e-8, rcond 1e-10");
        partial_case(30, 18, 9, a, 1e-6, 8, "s(A2) to 1e-8, rcond 1e-6");
    }
    /* p = n: plain min |A x|, |x| = 1 -> s_min(A) */
    {
        double x[9], resid, s[9], v[81];
        int rank2 = -1;
        randn(a, 20 * 9);
        partial_case(20, 9, 9, a, 0.0, 0, "p = n");
        mcg_cls_partial(20, 9, 9, a, 0.0, x, &resid, &rank2, work, LWORK);
        mcg_svd(20, 9, a, NULL, s, v, work, LWORK);
        check(fabs(resid - s[8]) < 1e-13 * s[0], "partial p = n: resid = s_min",
              fabs(resid - s[8]), 1e-13 * s[0]);
    }
    /* generalized epipolar system: exact (E, R) up to scale and sign */
    {
        static double rows[40 * 18];
        double xt[18], x[18], resid, ne, e = 0.0, sgn;
        int rank2;
        gec_system(40, rows, xt);
        mcg_cls_partial(40, 18, 9, rows, 0.0, x, &resid, &rank2, work, LWORK);
        ne = nrm(xt, 9);
        sgn = (x[0] * xt[0] + x[1] * xt[1] + x[2] * xt[2] >= 0) ? 1 : -1;
        for (i = 0; i < 18; ++i)
            e = fmax(e, fabs(sgn * x[i] - xt[i] / ne));
        check(e < 1e-12 && resid < 1e-12 && rank2 == 9,
              "partial on 40 generalized epipolar rows: +-(E, R) / |E|", e,
              1e-12);
    }
}

/* -------------------------------------------------------------- range */

static void range_case(int m, int n, int r, const double *a, const double *g,
                       const char *label)
{
    static double gp[MAXN * MAXN], pg[MAXN * MAXN];
    double x[MAXN], px[MAXN], y[MAXM], h[MAXN], ph[MAXN], c[MAXN], z[MAXN];
    double resid = -1, e, lam, na2, best = INFINITY;
    char what[160];
    int st, i, t, rk;
    size_t ws = mcg_cls_range_work_size(m, n, r);
    st = mcg_cls_range(m, n, r, a, g, 0.0, x, &resid, work, ws);
    snprintf(what, sizeof what, "range %s (m=%d n=%d r=%d) status", label, m,
             n, r);
    check_status(st, MCG_OK, what);
    if (st != MCG_OK)
        return;
    e = fabs(nrm(x, n) - 1.0);
    snprintf(what, sizeof what, "range %s  |x| = 1", label);
    check(e < 1e-14, what, e, 1e-14);
    /* projector on range(G): P = G G^+ */
    mcg_pinv(n, r, g, 1e-12, gp, &rk, work, LWORK);
    matmul(n, r, n, g, gp, pg);
    matmul(n, n, 1, pg, x, px);
    e = 0.0;
    for (i = 0; i < n; ++i)
        e = fmax(e, fabs(px[i] - x[i]));
    snprintf(what, sizeof what, "range %s  x in range(G): |G G^+ x - x|", label);
    check(e < 1e-12, what, e, 1e-12);
    e = fabs(resid - resid_of(m, n, a, x)) / (1.0 + resid);
    snprintf(what, sizeof what, "range %s  resid = |A x|", label);
    check(e < 1e-13, what, e, 1e-13);
    /* optimality: P A^T A x = lambda x */
    matmul(m, n, 1, a, x, y);
    matvec_t(m, n, a, y, h);
    matmul(n, n, 1, pg, h, ph);
    lam = resid * resid;
    na2 = 0.0;
    for (i = 0; i < m * n; ++i)
        na2 += a[i] * a[i];
    e = 0.0;
    for (i = 0; i < n; ++i)
        e = fmax(e, fabs(ph[i] - lam * x[i]));
    e /= na2;
    snprintf(what, sizeof what, "range %s  P A^T A x = resid^2 x", label);
    check(e < 1e-12, what, e, 1e-12);
    for (t = 0; t < NRAND; ++t) {
        double nz, rr;
        randn(c, r);
        matmul(n, r, 1, g, c, z);
        nz = nrm(z, n);
        if (nz < 1e-6)
            continue;
        for (i = 0; i < n; ++i)
            z[i] /= nz;
        rr = resid_of(m, n, a, z);
        if (rr < best)
            best = rr;
    }
    snprintf(what, sizeof what,
             "range %s  resid <= min over %d random feasible", label, NRAND);
    check(resid <= best * (1.0 + 1e-12), what, resid - best, 0.0);
}

static void test_range(void)
{
    static double a[MAXM * MAXN], g[MAXN * MAXN], b1[MAXN * MAXN],
        b2[MAXN * MAXN];
    randn(a, 25 * 10);
    randn(g, 10 * 4);
    range_case(25, 10, 4, a, g, "random G 10x4");
    /* G 10 x 6 of rank 3 */
    randn(b1, 10 * 3);
    randn(b2, 3 * 6);
    matmul(10, 3, 6, b1, b2, g);
    range_case(25, 10, 6, a, g, "G rank 3");
    /* G 5 x 8 spans R^5: plain min |A x| on |x| = 1 */
    {
        double x[5], resid, s[5], v[25];
        randn(a, 12 * 5);
        randn(g, 5 * 8);
        range_case(12, 5, 8, a, g, "G 5x8 (full space)");
        mcg_cls_range(12, 5, 8, a, g, 0.0, x, &resid, work, LWORK);
        mcg_svd(12, 5, a, NULL, s, v, work, LWORK);
        check(fabs(resid - s[4]) < 1e-13 * s[0],
              "range with range(G) = R^n: resid = s_min(A)",
              fabs(resid - s[4]), 1e-13 * s[0]);
    }
    /* m < q: zero residual reachable */
    randn(a, 3 * 10);
    randn(g, 10 * 6);
    range_case(3, 10, 6, a, g, "A 3x10, G 10x6");
}

/* ------------------------------------------------------ invalid input */

static void test_invalid(void)
{
    static double a[400], c[400], x[20];
    double resid;
    int rank2;
    randn(a, 400);
    randn(c, 400);
    check(mcg_cls_general_work_size(0, 3, 3) == 0 &&
              mcg_cls_general_work_size(3, 0, 3) == 0 &&
              mcg_cls_general_work_size(3, 3, 0) == 0 &&
              mcg_cls_general_work_size(3, 5000, 3) == 0 &&
              mcg_cls_partial_work_size(3, 5, 0) == 0 &&
              mcg_cls_partial_work_size(3, 5, 6) == 0 &&
              mcg_cls_range_work_size(3, 5, 0) == 0 &&
              mcg_cls_range_work_size(1 << 21, 5, 2) == 0,
          "cls work sizes of invalid shapes are 0", 0, 0);
    check_status(mcg_cls_general(0, 3, 3, a, c, x, &resid, work, LWORK),
                 MCG_EINVAL, "general m = 0");
    check_status(mcg_cls_general(5, 3, 0, a, c, x, &resid, work, LWORK),
                 MCG_EINVAL, "general k = 0");
    check_status(mcg_cls_general(5, 3, 3, NULL, c, x, &resid, work, LWORK),
                 MCG_EINVAL, "general A = NULL");
    check_status(mcg_cls_general(5, 3, 3, a, NULL, x, &resid, work, LWORK),
                 MCG_EINVAL, "general C = NULL");
    check_status(mcg_cls_general(5, 3, 3, a, c, NULL, &resid, work, LWORK),
                 MCG_EINVAL, "general x = NULL");
    check_status(mcg_cls_general(5, 3, 3, a, c, x, NULL, work, LWORK), MCG_OK,
                 "general resid = NULL allowed");
    check_status(mcg_cls_general(5, 3, 3, a, c, x, &resid, work,
                                 mcg_cls_general_work_size(5, 3, 3) - 1),
                 MCG_ENOMEM, "general lwork too small");
    c[4] = NAN;
    check_status(mcg_cls_general(5, 3, 3, a, c, x, &resid, work, LWORK),
                 MCG_EINVAL, "general NaN in C");
    c[4] = 0.5;
    a[14] = INFINITY;
    check_status(mcg_cls_general(5, 3, 3, a, c, x, &resid, work, LWORK),
                 MCG_EINVAL, "general inf in A");
    a[14] = 0.5;
    memset(c, 0, sizeof(double) * 9);
    check_status(mcg_cls_general(5, 3, 3, a, c, x, &resid, work, LWORK),
                 MCG_EDEGENERATE, "general C = 0 -> EDEGENERATE");
    check_status(mcg_cls_partial(5, 3, 0, a, 0.0, x, &resid, &rank2, work,
                                 LWORK),
                 MCG_EINVAL, "partial p = 0");
    check_status(mcg_cls_partial(5, 3, 4, a, 0.0, x, &resid, &rank2, work,
                                 LWORK),
                 MCG_EINVAL, "partial p > n");
    check_status(mcg_cls_partial(5, 3, 2, a, NAN, x, &resid, &rank2, work,
                                 LWORK),
                 MCG_EINVAL, "partial rcond NaN");
    check_status(mcg_cls_partial(5, 3, 2, a, 0.0, x, &resid, &rank2, work,
                                 mcg_cls_partial_work_size(5, 3, 2) - 1),
                 MCG_ENOMEM, "partial lwork too small");
    check_status(mcg_cls_partial(5, 3, 2, a, 0.0, x, &resid, &rank2, NULL,
                                 LWORK),
                 MCG_EINVAL, "partial work = NULL");
    check_status(mcg_cls_partial(5, 3, 2, a, 0.0, x, NULL, NULL, work, LWORK),
                 MCG_OK, "partial resid, rank2 = NULL allowed");
    a[3] = NAN;
    check_status(mcg_cls_partial(5, 3, 2, a, 0.0, x, &resid, &rank2, work,
                                 LWORK),
                 MCG_EINVAL, "partial NaN in A");
    check_status(mcg_cls_range(5, 3, 2, a, c, 0.0, x, &resid, work, LWORK),
                 MCG_EINVAL, "range NaN in A");
    a[3] = 0.1;
    randn(c, 6);
    check_status(mcg_cls_range(5, 3, 0, a, c, 0.0, x, &resid, work, LWORK),
                 MCG_EINVAL, "range r = 0");
    check_status(mcg_cls_range(5, 3, 2, a, NULL, 0.0, x, &resid, work, LWORK),
                 MCG_EINVAL, "range G = NULL");
    check_status(mcg_cls_range(5, 3, 2, a, c, 0.0, x, &resid, work,
                               mcg_cls_range_work_size(5, 3, 2) - 1),
                 MCG_ENOMEM, "range lwork too small");
    c[1] = -INFINITY;
    check_status(mcg_cls_range(5, 3, 2, a, c, 0.0, x, &resid, work, LWORK),
                 MCG_EINVAL, "range inf in G");
    memset(c, 0, sizeof(double) * 6);
    check_status(mcg_cls_range(5, 3, 2, a, c, 0.0, x, &resid, work, LWORK),
                 MCG_EDEGENERATE, "range G = 0 -> EDEGENERATE");
}

/* ---------------------------------------------- exact-size workspaces */

/* All small shapes with a workspace of exactly the documented size plus a
 * canary tail (writes past the end change it; under -fsanitize=address the
 * second, exact allocation catches reads too). */
#define CANARY 8
static double *alloc_canary(size_t n)
{
    double *p = malloc((n + CANARY) * sizeof(double));
    size_t i;
    if (p == NULL)
        return NULL;
    for (i = 0; i < n + CANARY; ++i)
        p[i] = (i < n) ? 0.0 : 12345.0;
    return p;
}
static int canary_ok(const double *p, size_t n)
{
    size_t i;
    for (i = n; i < n + CANARY; ++i)
        if (p[i] != 12345.0)
            return 0;
    return 1;
}

static void test_exact_workspaces(void)
{
    static double a[MAXM * MAXN], c[MAXM * MAXN];
    double x[MAXN + CANARY];
    int m, n, k, ok_status = 1, ok_canary = 1, i;
    for (m = 1; m <= 8; ++m)
        for (n = 1; n <= 8; ++n)
            for (k = 1; k <= 9; ++k) {
                size_t ws;
                double *w, *we, resid;
                int rank2, st;
                randn(a, m * n);
                randn(c, k * n);
                for (i = 0; i < CANARY; ++i)
                    x[n + i] = 12345.0;
                /* general: C is k x n */
                ws = mcg_cls_general_work_size(m, n, k);
                w = alloc_canary(ws);
                we = malloc(ws * sizeof(double));
                if (!w || !we)
                    ok_status = 0;
                else {
                    st = mcg_cls_general(m, n, k, a, c, x, &resid, w, ws);
                    st |= mcg_cls_general(m, n, k, a, c, x, &resid, we, ws);
                    if (st != MCG_OK)
                        ok_status = 0;
                    ok_canary &= canary_ok(w, ws) && canary_ok(x, (size_t)n);
                }
                free(w);
                free(we);
                /* range: G is n x k */
                ws = mcg_cls_range_work_size(m, n, k);
                w = alloc_canary(ws);
                we = malloc(ws * sizeof(double));
                if (!w || !we)
                    ok_status = 0;
                else {
                    st = mcg_cls_range(m, n, k, a, c, 0.0, x, &resid, w, ws);
                    st |= mcg_cls_range(m, n, k, a, c, 0.0, x, &resid, we, ws);
                    if (st != MCG_OK)
                        ok_status = 0;
                    ok_canary &= canary_ok(w, ws) && canary_ok(x, (size_t)n);
                }
                free(w);
                free(we);
                /* partial: p = k when k <= n */
                if (k <= n) {
                    ws = mcg_cls_partial_work_size(m, n, k);
                    w = alloc_canary(ws);
                    we = malloc(ws * sizeof(double));
                    if (!w || !we)
                        ok_status = 0;
                    else {
                        st = mcg_cls_partial(m, n, k, a, 0.0, x, &resid,
                                             &rank2, w, ws);
                        st |= mcg_cls_partial(m, n, k, a, 0.0, x, &resid,
                                              &rank2, we, ws);
                        if (st != MCG_OK)
                            ok_status = 0;
                        ok_canary &= canary_ok(w, ws) && canary_ok(x, (size_t)n);
                    }
                    free(w);
                    free(we);
                }
            }
    check(ok_status, "cls all shapes m,n <= 8, k <= 9 with exact lwork: OK",
          0, 0);
    check(ok_canary, "cls writes nothing past the workspace and x", 0, 0);
}

int main(void)
{
    test_general();
    test_partial();
    test_range();
    test_exact_workspaces();
    test_invalid();
    printf("%s: %d checks, %d failed\n", n_failed ? "FAILED" : "PASSED",
           n_checks, n_failed);
    return n_failed ? 1 : 0;
}
