/*
 * test_linalg.c -- plain-C checks of csrc/linalg.c and csrc/rotations.c
 * against independent facts:
 * reconstruction and orthogonality (QR, SVD), singular values of matrices
 * built with known spectra (U diag(s) V^T with U, V products of Householder
 * reflections generated here, s down to 1e-12), the four Moore-Penrose
 * conditions, A v = v w for sym_eig, Cholesky residuals, closed-form
 * rotations, and the status codes of invalid inputs.
 * Exit status 0 iff every check passes.
 */
#include "mcgeom.h"

#define TEST_SEED 0x9e3779b97f4a7c15ULL
#include "testutil.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define MAXM 200
#define MAXN 64
#define BIG (MAXM * MAXM)

/* ---- small helpers */
static double work[4 * BIG + 64 * MAXM];

static void transpose(int m, int n, const double *a, double *at)
{
    int i, j;
    for (i = 0; i < m; ++i)
        for (j = 0; j < n; ++j)
            at[j * m + i] = a[i * n + j];
}

static double max_abs(const double *a, int n)
{
    double mx = 0.0;
    int i;
    for (i = 0; i < n; ++i)
        if (fabs(a[i]) > mx)
            mx = fabs(a[i]);
    return mx;
}

static double max_abs_diff(const double *a, const double *b, int n)
{
    double mx = 0.0;
    int i;
    for (i = 0; i < n; ++i)
        if (fabs(a[i] - b[i]) > mx)
            mx = fabs(a[i] - b[i]);
    return mx;
}

/* Random m x m orthogonal matrix as a product of m Householder reflections
 * (independent of the library's QR). */
static void rand_orth(int m, double *q)
{
    double v[MAXM], row[MAXM];
    int i, j, k;
    memset(q, 0, (size_t)m * (size_t)m * sizeof(double));
    for (i = 0; i < m; ++i)
        q[i * m + i] = 1.0;
    for (k = 0; k < m; ++k) {
        double vv = 0.0;
        for (i = 0; i < m; ++i) {
            v[i] = nrand();
            vv += v[i] * v[i];
        }
        /* q <- q (I - 2 v v^T / v^T v) */
        for (i = 0; i < m; ++i) {
            double d = 0.0;
            for (j = 0; j < m; ++j)
                d += q[i * m + j] * v[j];
            row[i] = 2.0 * d / vv;
        }
        for (i = 0; i < m; ++i)
            for (j = 0; j < m; ++j)
                q[i * m + j] -= row[i] * v[j];
    }
}

/* a (m x n) = U diag(s) V^T with random orthogonal U, V; s has min(m,n) */
static void with_spectrum(int m, int n, const double *s, double *a)
{
    static double u[MAXM * MAXM], v[MAXM * MAXM];
    int i, j, k, mn = m < n ? m : n;
    rand_orth(m, u);
    rand_orth(n, v);
    for (i = 0; i < m; ++i)
        for (j = 0; j < n; ++j) {
            double acc = 0.0;
            for (k = 0; k < mn; ++k)
                acc += u[i * m + k] * s[k] * v[j * n + k];
            a[i * n + j] = acc;
        }
}

/* ------------------------------------------------------------------ QR */

static void test_qr_case(int m, int n, int rank_def)
{
    static double a[BIG], q[BIG], r[MAXN * MAXN], qr[BIG];
    char what[128];
    double na, e1, e2, e3;
    int i, j, st;
    size_t ws = mcg_qr_work_size(m, n);
    randn(a, m * n);
    if (rank_def && n >= 3) /* repeat a column: rank n - 1 */
        for (i = 0; i < m; ++i)
            a[i * n + n - 1] = a[i * n + 0] - 2.0 * a[i * n + 1];
    st = mcg_qr(m, n, a, q, r, work, ws);
    snprintf(what, sizeof what, "qr %dx%d%s status", m, n,
             rank_def ? " rank-def" : "");
    check_status(st, MCG_OK, what);
    matmul(m, n, n, q, r, qr);
    na = max_abs(a, m * n);
    e1 = max_abs_diff(a, qr, m * n) / na;
    e2 = orthonormality_error(q, m, n);
    e3 = 0.0;
    for (i = 0; i < n; ++i)
        for (j = 0; j < i; ++j)
            e3 += fabs(r[i * n + j]);
    snprintf(what, sizeof what, "qr %dx%d  |a - q r| / |a|", m, n);
    check(e1 < 1e-14 * sqrt((double)m), what, e1, 1e-14 * sqrt((double)m));
    snprintf(what, sizeof what, "qr %dx%d  |q^T q - I|", m, n);
    check(e2 < 1e-14 * sqrt((double)m), what, e2, 1e-14 * sqrt((double)m));
    snprintf(what, sizeof what, "qr %dx%d  r strictly upper-triangular", m, n);
    check(e3 == 0.0, what, e3, 0.0);
    /* q may be NULL: same r */
    memcpy(qr, r, (size_t)(n * n) * sizeof(double));
    st = mcg_qr(m, n, a, NULL, r, work, ws);
    snprintf(what, sizeof what, "qr %dx%d  q = NULL gives the same r", m, n);
    check(st == MCG_OK && max_abs_diff(qr, r, n * n) == 0.0, what,
          max_abs_diff(qr, r, n * n), 0.0);
}

static void test_qr(void)
{
    test_qr_case(1, 1, 0);
    test_qr_case(5, 3, 0);
    test_qr_case(10, 10, 0);
    test_qr_case(50, 7, 0);
    test_qr_case(200, 18, 0);
    test_qr_case(40, 9, 1);
}

/* ----------------------------------------------------------------- SVD */

/* Checks a = u s v^T, orthogonality, ordering. Returns reconstruction err. */
static void svd_checks(int m, int n, const double *a, const char *label,
                       const double *s_true, double stol)
{
    static double u[BIG], v[MAXM * MAXM], us[BIG], rec[BIG];
    static double vt[MAXM * MAXM];
    double s[MAXM];
    char what[160];
    int i, k, st, mn = m < n ? m : n, desc = 1;
    double na = max_abs(a, m * n), e, smax;
    size_t ws = mcg_svd_work_size(m, n);
    size_t p = (size_t)(m > n ? m : n);

    snprintf(what, sizeof what, "svd %s %dx%d work size <= p n + 3 n^2 + 4 p",
             label, m, n);
    check(ws <= p * (size_t)n + 3 * (size_t)n * (size_t)n + 4 * p, what,
          (double)ws, (double)(p * (size_t)n + 3 * (size_t)n * (size_t)n +
                               4 * p));
    st = mcg_svd(m, n, a, u, s, v, work, ws);
    snprintf(what, sizeof what, "svd %s %dx%d status", label, m, n);
    check_status(st, MCG_OK, what);
    if (st != MCG_OK)
        return;
    smax = s[0] > 0 ? s[0] : 1.0;
    for (i = 0; i < m; ++i)
        for (k = 0; k < mn; ++k)
            us[i * mn + k] = u[i * mn + k] * s[k];
    transpose(n, n, v, vt);
    /* rec = (u s) v[:, :mn]^T */
    for (i = 0; i < m; ++i) {
        int j;
        for (j = 0; j < n; ++j) {
            double acc = 0.0;
            for (k = 0; k < mn; ++k)
                acc += us[i * mn + k] * vt[k * n + j];
            rec[i * n + j] = acc;
        }
    }
    e = max_abs_diff(a, rec, m * n) / (na > 0 ? na : 1.0);
    snprintf(what, sizeof what, "svd %s %dx%d  |a - u s v^T| / |a|", label,
             m, n);
    check(e < 2e-14 * sqrt((double)(m + n)), what, e,
          2e-14 * sqrt((double)(m + n)));
    e = orthonormality_error(u, m, mn);
    snprintf(what, sizeof what, "svd %s %dx%d  |u^T u - I|", label, m, n);
    check(e < 2e-14 * sqrt((double)m), what, e, 2e-14 * sqrt((double)m));
    e = orthonormality_error(v, n, n);
    snprintf(what, sizeof what, "svd %s %dx%d  |v^T v - I| (full n x n)",
             label, m, n);
    check(e < 2e-14 * sqrt((double)n), what, e, 2e-14 * sqrt((double)n));
    for (k = 0; k + 1 < n; ++k)
        if (s[k] < s[k + 1])
            desc = 0;
    for (k = 0; k < n; ++k)
        if (s[k] < 0.0)
            desc = 0;
    for (k = mn; k < n; ++k)
        if (s[k] != 0.0)
            desc = 0;
    snprintf(what, sizeof what,
             "svd %s %dx%d  s >= 0, descending, s[min(m,n):] == 0", label, m,
             n);
    check(desc, what, s[n - 1], 0.0);
    /* null space: |a v_k| for the columns k >= m (wide) must vanish */
    if (m < n) {
        double mx = 0.0;
        for (k = m; k < n; ++k)
            for (i = 0; i < m; ++i) {
                double acc = 0.0;
                int j;
                for (j = 0; j < n; ++j)
                    acc += a[i * n + j] * v[j * n + k];
                if (fabs(acc) > mx)
                    mx = fabs(acc);
            }
        mx /= smax;
        snprintf(what, sizeof what, "svd %s %dx%d  |a v[:, m:]| / s_max",
                 label, m, n);
        check(mx < 1e-14 * sqrt((double)n), what, mx,
              1e-14 * sqrt((double)n));
    }
    if (s_true != NULL) {
        double mx = 0.0;
        for (k = 0; k < mn; ++k)
            if (fabs(s[k] - s_true[k]) > mx)
                mx = fabs(s[k] - s_true[k]);
        mx /= s_true[0];
        snprintf(what, sizeof what, "svd %s %dx%d  max|s - s_true| / s_max",
                 label, m, n);
        check(mx < stol, what, mx, stol);
    }
}

static void test_svd(void)
{
    static const int shapes[][2] = {{1, 1}, {1, 5}, {5, 1}, {2, 2},
                                    {3, 3}, {6, 4}, {4, 6}, {30, 9},
                                    {9, 30}, {100, 18}, {17, 18}, {18, 17},
                                    {18, 18}, {64, 64}, {200, 40}};
    static double a[BIG], b[BIG], c[BIG];
    double s_true[MAXM];
    size_t t;
    int k;
    for (t = 0; t < sizeof shapes / sizeof shapes[0]; ++t) {
        int m = shapes[t][0], n = shapes[t][1], mn = m < n ? m : n;
        randn(a, m * n);
        svd_checks(m, n, a, "gauss", NULL, 0.0);
        /* ill-conditioned: s from 1 down to 1e-12, geometric */
        for (k = 0; k < mn; ++k)
            s_true[k] = mn > 1 ? pow(1e-12, (double)k / (double)(mn - 1))
                               : 1.0;
        with_spectrum(m, n, s_true, a);
        svd_checks(m, n, a, "cond1e12", s_true, 4e-15 * sqrt((double)mn));
        /* rank-deficient: product of m x r and r x n */
        if (mn >= 3) {
            int r = mn / 2;
            double mx = 0.0;
            static double u[BIG], v[MAXM * MAXM];
            double s[MAXM];
            randn(b, m * r);
            randn(c, r * n);
            matmul(m, r, n, b, c, a);
            svd_checks(m, n, a, "rank-def", NULL, 0.0);
            mcg_svd(m, n, a, u, s, v, work, mcg_svd_work_size(m, n));
            for (k = r; k < n; ++k)
                if (s[k] > mx)
                    mx = s[k];
            mx /= s[0];
            check(mx < 1e-14 * sqrt((double)(m + n)),
                  "svd rank-def: s[r:] / s_max (zero singular values)", mx,
                  1e-14 * sqrt((double)(m + n)));
        }
    }
    /* graded: columns scaled by 1 .. 1e-10 (Jacobi's strength) */
    {
        int m = 30, n = 8, i, j;
        randn(a, m * n);
        for (i = 0; i < m; ++i)
            for (j = 0; j < n; ++j)
                a[i * n + j] *= pow(1e-10, (double)j / (n - 1));
        svd_checks(m, n, a, "graded", NULL, 0.0);
    }
    /* all zero: s = 0, u and v still orthonormal */
    memset(a, 0, sizeof(double) * 12);
    svd_checks(4, 3, a, "zero", NULL, 0.0);
    svd_checks(3, 4, a, "zero", NULL, 0.0);
    /* exactly repeated singular values */
    for (k = 0; k < 6; ++k)
        s_true[k] = (k < 3) ? 2.0 : 1.0;
    with_spectrum(9, 6, s_true, a);
    svd_checks(9, 6, a, "repeated", s_true, 1e-14);
    /* extreme scales: result scales exactly */
    {
        static double u[BIG], v[MAXM * MAXM];
        double s1[8], s2[8], s3[8];
        int i;
        randn(a, 40);
        mcg_svd(8, 5, a, u, s1, v, work, mcg_svd_work_size(8, 5));
        for (i = 0; i < 40; ++i)
            b[i] = a[i] * 0x1p+1000;
        k = mcg_svd(8, 5, b, u, s2, v, work, mcg_svd_work_size(8, 5));
        for (i = 0; i < 40; ++i)
            c[i] = a[i] * 0x1p-1000;
        k |= mcg_svd(8, 5, c, u, s3, v, work, mcg_svd_work_size(8, 5));
        {
            double e = 0.0;
            for (i = 0; i < 5; ++i) {
                double e2 = fabs(s2[i] * 0x1p-1000 - s1[i]) / s1[0];
                double e3 = fabs(s3[i] * 0x1p+1000 - s1[i]) / s1[0];
                if (e2 > e)
                    e = e2;
                if (e3 > e)
                    e = e3;
            }
            check(k == 0 && e == 0.0, "svd scale 2^+-1000: s scales exactly",
                  e, 0.0);
        }
    }
    /* a huge matrix whose s_max exceeds DBL_MAX cannot be represented */
    {
        static double u[BIG], v[MAXM * MAXM];
        double s[4];
        int i;
        for (i = 0; i < 16; ++i)
            a[i] = DBL_MAX;
        check_status(mcg_svd(4, 4, a, u, s, v, work, mcg_svd_work_size(4, 4)),
                     MCG_ENUMERIC, "svd s_max > DBL_MAX -> ENUMERIC");
    }
    /* work size bound over a sweep of shapes */
    {
        int m, n, ok = 1;
        for (m = 1; m <= 70; ++m)
            for (n = 1; n <= 70; ++n) {
                size_t p = (size_t)(m > n ? m : n);
                if (mcg_svd_work_size(m, n) >
                    p * (size_t)n + 3 * (size_t)n * (size_t)n + 4 * p)
                    ok = 0;
            }
        check(ok, "svd work size bound for all m, n <= 70", 0.0, 0.0);
    }
}

/* ---------------------------------------------------------------- pinv */

static void pinv_case(int m, int n, int r, const char *label)
{
    static double a[BIG], b[BIG], c[BIG], x[BIG], ax[BIG], xa[BIG], t1[BIG];
    char what[160];
    int rank = -1, st, want;
    double e, na, nx;
    size_t ws = mcg_pinv_work_size(m, n);
    if (r > 0) {
        randn(b, m * r);
        randn(c, r * n);
        matmul(m, r, n, b, c, a);
        want = r;
    } else {
        randn(a, m * n);
        want = m < n ? m : n;
    }
    st = mcg_pinv(m, n, a, 0.0, x, &rank, work, ws);
    snprintf(what, sizeof what, "pinv %s %dx%d status, rank %d", label, m, n,
             want);
    check(st == MCG_OK && rank == want, what, (double)rank, (double)want);
    na = max_abs(a, m * n);
    nx = max_abs(x, n * m);
    matmul(m, n, m, a, x, ax);
    matmul(n, m, n, x, a, xa);
    matmul(m, m, n, ax, a, t1);
    e = max_abs_diff(t1, a, m * n) / na;
    snprintf(what, sizeof what, "pinv %s %dx%d  A X A = A", label, m, n);
    check(e < 1e-12, what, e, 1e-12);
    matmul(n, m, m, x, ax, t1);
    e = max_abs_diff(t1, x, n * m) / nx;
    snprintf(what, sizeof what, "pinv %s %dx%d  X A X = X", label, m, n);
    check(e < 1e-12, what, e, 1e-12);
    transpose(m, m, ax, t1);
    e = max_abs_diff(t1, ax, m * m);
    snprintf(what, sizeof what, "pinv %s %dx%d  (A X)^T = A X", label, m, n);
    check(e < 1e-12, what, e, 1e-12);
    transpose(n, n, xa, t1);
    e = max_abs_diff(t1, xa, n * n);
    snprintf(what, sizeof what, "pinv %s %dx%d  (X A)^T = X A", label, m, n);
    check(e < 1e-12, what, e, 1e-12);
}

static void test_pinv(void)
{
    double a[6] = {1, 2, 3, 4, 5, 6}, x[6];
    int rank;
    pinv_case(10, 4, 0, "full");
    pinv_case(4, 10, 0, "full");
    pinv_case(7, 7, 0, "full");
    pinv_case(30, 18, 9, "rank9");
    pinv_case(12, 20, 5, "rank5");
    /* rcond >= 1 drops everything: zero pseudo-inverse, rank 0 */
    rank = -1;
    check(mcg_pinv(2, 3, a, 2.0, x, &rank, work, mcg_pinv_work_size(2, 3)) ==
                  MCG_OK &&
              rank == 0 && max_abs(x, 6) == 0.0,
          "pinv rcond = 2: rank 0, A^+ = 0", (double)rank, 0.0);
}

/* ------------------------------------------------------------ sym_eig */

typedef int (*eig_fn)(int, double *, double *, double *);

static void eig_case(eig_fn eig, int n, const double *a0, const double *w_true,
                     const char *label)
{
    static double a[MAXN * MAXN], v[MAXN * MAXN], av[MAXN * MAXN];
    double w[MAXN], e, na;
    char what[160];
    int i, k, st, asc = 1;
    memcpy(a, a0, (size_t)(n * n) * sizeof(double));
    st = eig(n, a, w, v);
    snprintf(what, sizeof what, "sym_eig %s n=%d status", label, n);
    check_status(st, MCG_OK, what);
    na = max_abs(a0, n * n);
    matmul(n, n, n, a0, v, av);
    e = 0.0;
    for (i = 0; i < n; ++i)
        for (k = 0; k < n; ++k) {
            double d = fabs(av[i * n + k] - v[i * n + k] * w[k]);
            if (d > e)
                e = d;
        }
    e /= (na > 0 ? na : 1.0);
    snprintf(what, sizeof what, "sym_eig %s n=%d  |A v - v w| / |A|", label,
             n);
    check(e < 1e-14 * n, what, e, 1e-14 * n);
    e = orthonormality_error(v, n, n);
    snprintf(what, sizeof what, "sym_eig %s n=%d  |v^T v - I|", label, n);
    check(e < 1e-14 * n, what, e, 1e-14 * n);
    for (k = 0; k + 1 < n; ++k)
        if (w[k] > w[k + 1])
            asc = 0;
    snprintf(what, sizeof what, "sym_eig %s n=%d  ascending", label, n);
    check(asc, what, 0.0, 0.0);
    if (w_true != NULL) {
        e = 0.0;
        for (k = 0; k < n; ++k)
            if (fabs(w[k] - w_true[k]) > e)
                e = fabs(w[k] - w_true[k]);
        e /= (na > 0 ? na : 1.0);
        snprintf(what, sizeof what, "sym_eig %s n=%d  |w - w_true| / |A|",
                 label, n);
        check(e < 1e-14 * n, what, e, 1e-14 * n);
    }
}

/* Both symmetric eigen-solvers (cyclic Jacobi and tridiagonal QR) pass the
 * same checks; label carries the solver's name. */
static void test_sym_eig_with(eig_fn eig, const char *name)
{
    char label[64];
    static double a[MAXN * MAXN], q[MAXN * MAXN], b[MAXN * MAXN];
    double w_true[MAXN];
    static const int sizes[] = {1, 2, 3, 9, 18, 40, 64};
    size_t t;
    int i, j, k;
    for (t = 0; t < sizeof sizes / sizeof sizes[0]; ++t) {
        int n = sizes[t];
        randn(a, n * n); /* not symmetric: only the symmetric part counts */
        for (i = 0; i < n; ++i)
            for (j = 0; j < i; ++j) {
                double s = 0.5 * (a[i * n + j] + a[j * n + i]);
                a[i * n + j] = a[j * n + i] = s;
            }
        snprintf(label, sizeof label, "%s gauss", name);
        eig_case(eig, n, a, NULL, label);
        /* known spectrum with repeats and a wide range, in random basis */
        for (k = 0; k < n; ++k)
            w_true[k] = (k < n / 3) ? -1.0 : (k < n / 2 ? 1e-9 : (double)k);
        rand_orth(n, q);
        for (i = 0; i < n; ++i)
            for (j = 0; j < n; ++j) {
                double acc = 0.0;
                for (k = 0; k < n; ++k)
                    acc += q[i * n + k] * w_true[k] * q[j * n + k];
                a[i * n + j] = acc;
            }
        for (i = 0; i < n; ++i) /* exact symmetry */
            for (j = 0; j < i; ++j)
                a[i * n + j] = a[j * n + i];
        snprintf(label, sizeof label, "%s known", name);
        eig_case(eig, n, a, w_true, label);
    }
    /* PSD rank 5: B^T B with B 5 x 18 -> 13 eigenvalues ~ 0 */
    randn(b, 5 * 18);
    for (i = 0; i < 18; ++i)
        for (j = 0; j < 18; ++j) {
            double acc = 0.0;
            for (k = 0; k < 5; ++k)
                acc += b[k * 18 + i] * b[k * 18 + j];
            a[i * 18 + j] = acc;
        }
    snprintf(label, sizeof label, "%s psd-rank5", name);
    eig_case(eig, 18, a, NULL, label);
    {
        double w[18], e = 0.0;
        memcpy(q, a, sizeof(double) * 18 * 18);
        eig(18, q, w, b);
        for (k = 0; k < 13; ++k)
            if (fabs(w[k]) > e)
                e = fabs(w[k]);
        e /= w[17];
        snprintf(label, sizeof label, "%s psd-rank5: 13 null eigenvalues / w_max", name);
        check(e < 1e-14, label, e, 1e-14);
    }
    /* diagonal input: immediate exit, exact */
    memset(a, 0, sizeof(double) * 81);
    for (i = 0; i < 9; ++i)
        a[i * 9 + i] = (double)(9 - i);
    for (i = 0; i < 9; ++i)
        w_true[i] = (double)(i + 1);
    snprintf(label, sizeof label, "%s diagonal", name);
    eig_case(eig, 9, a, w_true, label);
    /* timing (information only): n = 9 and 18 */
    {
        double w[18];
        int rep, reps = scaled(20000), nn;
        for (nn = 9; nn <= 18; nn += 9) {
            clock_t c0;
            double us;
            randn(b, nn * nn);
            for (i = 0; i < nn; ++i)
                for (j = 0; j < nn; ++j) {
                    double acc = 0.0;
                    for (k = 0; k < nn; ++k)
                        acc += b[k * nn + i] * b[k * nn + j];
                    a[i * nn + j] = acc;
                }
            c0 = clock();
            for (rep = 0; rep < reps; ++rep) {
                memcpy(q, a, sizeof(double) * (size_t)(nn * nn));
                eig(nn, q, w, b);
            }
            us = 1e6 * (double)(clock() - c0) / CLOCKS_PER_SEC / reps;
            printf("info  %s n=%d: %.2f us per call\n", name, nn, us);
        }
    }
}

static void test_sym_eig(void)
{
    test_sym_eig_with(mcg_sym_eig, "sym_eig");
    test_sym_eig_with(mcg_sym_eig_tridiag, "sym_eig_tridiag");
}

/* ---------------------------------------------------------- spd_solve */

static void test_spd(void)
{
    static double b[MAXN * MAXN], a[MAXN * MAXN];
    double rhs[MAXN], x[MAXN], r[MAXN];
    static const int sizes[] = {1, 2, 9, 18, 64};
    size_t t;
    int i, j, k;
    char what[128];
    for (t = 0; t < sizeof sizes / sizeof sizes[0]; ++t) {
        int n = sizes[t];
        double e = 0.0, nb;
        randn(b, n * n);
        for (i = 0; i < n; ++i)
            for (j = 0; j < n; ++j) {
                double acc = (i == j) ? 0.1 : 0.0;
                for (k = 0; k < n; ++k)
                    acc += b[k * n + i] * b[k * n + j];
                a[i * n + j] = acc;
            }
        randn(rhs, n);
        i = mcg_spd_solve(n, a, rhs, x);
        matmul(n, n, 1, a, x, r);
        nb = max_abs(rhs, n);
        for (k = 0; k < n; ++k)
            if (fabs(r[k] - rhs[k]) > e)
                e = fabs(r[k] - rhs[k]);
        e /= nb;
        snprintf(what, sizeof what, "spd_solve n=%d  |a x - b| / |b|", n);
        check(i == MCG_OK && e < 1e-10, what, e, 1e-10);
    }
    /* indefinite and singular */
    {
        double ind[4] = {1, 2, 2, 1}, sing[4] = {1, 1, 1, 1}, bb[2] = {1, 1};
        check_status(mcg_spd_solve(2, ind, bb, x), MCG_ENUMERIC,
                     "spd_solve indefinite -> ENUMERIC");
        check_status(mcg_spd_solve(2, sing, bb, x), MCG_ENUMERIC,
                     "spd_solve singular -> ENUMERIC");
        check_status(mcg_spd_solve(65, a, rhs, x), MCG_EINVAL,
                     "spd_solve n = 65 -> EINVAL");
    }
}

/* ---------------------------------------------------------- rotations */

/* independent closed form: rotation by angle t about unit axis k */
static void rodrigues_ref(const double k[3], double t, double r[9])
{
    double c = cos(t), s = sin(t), C = 1.0 - c;
    r[0] = c + k[0] * k[0] * C;
    r[1] = k[0] * k[1] * C - k[2] * s;
    r[2] = k[0] * k[2] * C + k[1] * s;
    r[3] = k[1] * k[0] * C + k[2] * s;
    r[4] = c + k[1] * k[1] * C;
    r[5] = k[1] * k[2] * C - k[0] * s;
    r[6] = k[2] * k[0] * C - k[1] * s;
    r[7] = k[2] * k[1] * C + k[0] * s;
    r[8] = c + k[2] * k[2] * C;
}

static double det3(const double a[9])
{
    return a[0] * (a[4] * a[8] - a[5] * a[7]) -
           a[1] * (a[3] * a[8] - a[5] * a[6]) +
           a[2] * (a[3] * a[7] - a[4] * a[6]);
}

static void test_rotations(void)
{
    static const double angles[] = {0.0,        1e-300,     1e-12, 1e-8,
                                    1e-4,       0.3,        1.0,   2.0,
                                    3.0,        3.14159,    3.141592653589793 - 1e-9,
                                    3.141592653589793};
    double e_rod = 0, e_aa = 0, e_q = 0, e_qr = 0, e_orth = 0, e_hz = 0;
    size_t t;
    int trial, i, bad = 0;
    for (t = 0; t < sizeof angles / sizeof angles[0]; ++t) {
        for (trial = 0; trial < 20; ++trial) {
            double k[3], nk, w[3], w2[3], r[9], rr[9], q[4], q2[4], r2[9];
            double th = angles[t], e;
            int flip;
            k[0] = nrand();
            k[1] = nrand();
            k[2] = nrand();
            if (trial == 0) { /* axis along a coordinate axis */
                k[0] = 0;
                k[1] = 0;
                k[2] = 1;
            }
            nk = sqrt(k[0] * k[0] + k[1] * k[1] + k[2] * k[2]);
            for (i = 0; i < 3; ++i) {
                k[i] /= nk;
                w[i] = th * k[i];
            }
            bad |= mcg_rot_from_angle_axis(w, r);
            rodrigues_ref(k, th, rr);
            e = max_abs_diff(r, rr, 9);
            if (e > e_rod)
                e_rod = e;
            {
                double o = 0.0;
                int a1, a2, l;
                for (a1 = 0; a1 < 3; ++a1)
                    for (a2 = 0; a2 < 3; ++a2) {
                        double acc = 0.0;
                        for (l = 0; l < 3; ++l)
                            acc += r[a1 * 3 + l] * r[a2 * 3 + l];
                        o = fmax(o, fabs(acc - (a1 == a2)));
                    }
                o = fmax(o, fabs(det3(r) - 1.0));
                if (o > e_orth)
                    e_orth = o;
            }
            /* angle-axis round trip; at pi, w and -w are the same rotation */
            bad |= mcg_angle_axis_from_rot(r, w2);
            e = fmax(fmax(fabs(w2[0] - w[0]), fabs(w2[1] - w[1])),
                     fabs(w2[2] - w[2]));
            if (th > 3.14159) {
                double e2 = fmax(fmax(fabs(w2[0] + w[0]), fabs(w2[1] + w[1])),
                                 fabs(w2[2] + w[2]));
                e = fmin(e, e2);
            }
            if (e > e_aa)
                e_aa = e;
            /* quaternion: q = (cos t/2, sin t/2 k); R(q) = Rodrigues */
            q[0] = cos(0.5 * th);
            for (i = 0; i < 3; ++i)
                q[i + 1] = sin(0.5 * th) * k[i];
            q2[0] = 3.0 * q[0]; /* unnormalised input is normalised */
            for (i = 1; i < 4; ++i)
                q2[i] = 3.0 * q[i];
            bad |= mcg_rot_from_quat(q2, r2);
            e = max_abs_diff(r2, rr, 9);
            if (e > e_q)
                e_q = e;
            bad |= mcg_quat_from_rot(r, q2);
            flip = (q2[0] < 0.0);
            bad |= flip;
            e = 0.0;
            for (i = 0; i < 4; ++i)
                e = fmax(e, fabs(q2[i] - q[i]));
            if (th > 3.14159) {
                double e2 = 0.0;
                for (i = 0; i < 4; ++i)
                    e2 = fmax(e2, fabs(q2[i] + q[i]));
                e = fmin(e, e2);
            }
            if (e > e_qr)
                e_qr = e;
        }
    }
    check(!bad, "rotations: all calls OK, quat_from_rot q[0] >= 0", bad, 0);
    check(e_rod < 1e-15 * 4, "rot_from_angle_axis vs Rodrigues closed form",
          e_rod, 4e-15);
    check(e_orth < 4e-16 * 8, "rot_from_angle_axis orthonormal, det 1",
          e_orth, 3.2e-15);
    check(e_aa < 1e-13, "angle_axis round trip (angles 0..pi, 1e-300..)",
          e_aa, 1e-13);
    check(e_q < 4e-15, "rot_from_quat (unnormalised) vs Rodrigues", e_q,
          4e-15);
    check(e_qr < 1e-13, "quat_from_rot round trip (sign: q0 >= 0)", e_qr,
          1e-13);
    /* the round trips above are limited by cond(angle <- R) ~ 1/sin near pi
     * and by |dR| ~ eps for tiny angles; check the accurate regimes tighter */
    {
        double w[3] = {0.3, -0.2, 0.5}, r[9], w2[3], e;
        mcg_rot_from_angle_axis(w, r);
        mcg_angle_axis_from_rot(r, w2);
        e = max_abs_diff(w, w2, 3);
        check(e < 1e-15, "angle_axis round trip at angle 0.62", e, 1e-15);
        w[0] = 3e-9;
        w[1] = -1e-9;
        w[2] = 2e-9;
        mcg_rot_from_angle_axis(w, r);
        mcg_angle_axis_from_rot(r, w2);
        e = max_abs_diff(w, w2, 3);
        check(e < 1e-16 * 4, "angle_axis round trip at angle 4e-9 (abs)", e,
              4e-16);
    }
    /* Hamilton convention: q = (cos t/2, 0, 0, sin t/2) is R_z(t) */
    {
        double q[4] = {cos(0.35), 0, 0, sin(0.35)}, r[9], rz[9];
        double c = cos(0.7), s = sin(0.7);
        rz[0] = c;
        rz[1] = -s;
        rz[2] = 0;
        rz[3] = s;
        rz[4] = c;
        rz[5] = 0;
        rz[6] = 0;
        rz[7] = 0;
        rz[8] = 1;
        mcg_rot_from_quat(q, r);
        e_hz = max_abs_diff(r, rz, 9);
        check(e_hz < 1e-15, "rot_from_quat Hamilton: (c, 0, 0, s) = R_z",
              e_hz, 1e-15);
    }
    /* project_so3 */
    {
        double w[3] = {0.4, 1.1, -0.7}, r[9], m[9], p[9], e;
        double s3[9] = {3, 0.5, 0.1, 0.5, 2, 0.2, 0.1, 0.2, 1};
        mcg_rot_from_angle_axis(w, r);
        matmul(3, 3, 3, r, s3, m); /* R S, S SPD: polar factor is R */
        i = mcg_project_so3(m, p);
        e = max_abs_diff(p, r, 9);
        check(i == MCG_OK && e < 1e-14, "project_so3(R S), S SPD -> R", e,
              1e-14);
        for (i = 0; i < 9; ++i)
            m[i] = r[i] + 1e-3 * nrand();
        i = mcg_project_so3(m, p);
        e = fabs(det3(p) - 1.0);
        check(i == MCG_OK && e < 1e-14 && max_abs_diff(p, r, 9) < 1e-2,
              "project_so3(R + noise): det 1, near R", e, 1e-14);
        /* det < 0 input: reflection; result is still a proper rotation */
        for (i = 0; i < 9; ++i)
            m[i] = -r[i];
        i = mcg_project_so3(m, p);
        e = fabs(det3(p) - 1.0);
        check(i == MCG_OK && e < 1e-14, "project_so3(-R): det +1", e, 1e-14);
        /* rank 2: still unique */
        {
            double m2[9] = {1, 0, 0, 0, 2, 0, 0, 0, 0};
            i = mcg_project_so3(m2, p);
            e = fabs(p[0] - 1) + fabs(p[4] - 1) + fabs(p[8] - 1);
            check(i == MCG_OK && e < 1e-15, "project_so3(diag(1,2,0)) = I", e,
                  1e-15);
        }
        {
            double m1[9] = {1, 2, 3, 2, 4, 6, -1, -2, -3};
            check_status(mcg_project_so3(m1, p), MCG_EDEGENERATE,
                         "project_so3(rank 1) -> EDEGENERATE");
        }
        {
            double nr[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1.1}, ww[4];
            check_status(mcg_angle_axis_from_rot(nr, ww), MCG_EINVAL,
                         "angle_axis_from_rot(non-rotation) -> EINVAL");
            nr[8] = -1.0;
            check_status(mcg_quat_from_rot(nr, ww), MCG_EINVAL,
                         "quat_from_rot(det -1) -> EINVAL");
        }
    }
}

/* ------------------------------------------------------ invalid input */

static void test_invalid(void)
{
    double a[64], b[64], c[64], s[8], v[64], w[8], x[8];
    int rank, i;
    for (i = 0; i < 64; ++i)
        a[i] = (double)(i % 7) - 3.0;
    /* work sizes of invalid shapes are 0 */
    check(mcg_qr_work_size(0, 1) == 0 && mcg_qr_work_size(2, 3) == 0 &&
              mcg_svd_work_size(0, 3) == 0 && mcg_svd_work_size(3, -1) == 0 &&
              mcg_svd_work_size(1 << 21, 3) == 0 &&
              mcg_svd_work_size(3, 5000) == 0 &&
              mcg_pinv_work_size(0, 0) == 0,
          "work sizes of invalid shapes are 0", 0, 0);
    check_status(mcg_qr(0, 0, a, b, c, work, 100), MCG_EINVAL, "qr m = 0");
    check_status(mcg_qr(2, 3, a, b, c, work, 100), MCG_EINVAL, "qr m < n");
    check_status(mcg_qr(3, 2, NULL, b, c, work, 100), MCG_EINVAL,
                 "qr a = NULL");
    check_status(mcg_qr(3, 2, a, b, NULL, work, 100), MCG_EINVAL,
                 "qr r = NULL");
    check_status(mcg_qr(3, 2, a, b, c, work, mcg_qr_work_size(3, 2) - 1),
                 MCG_ENOMEM, "qr lwork too small");
    check_status(mcg_svd(3, 0, a, b, s, v, work, 100), MCG_EINVAL, "svd n = 0");
    check_status(mcg_svd(1 << 21, 2, a, b, s, v, work, 100), MCG_EINVAL,
                 "svd m = 2^21");
    check_status(mcg_svd(3, 2, a, b, NULL, v, work, 100), MCG_EINVAL,
                 "svd s = NULL");
    check_status(mcg_svd(3, 2, a, b, s, NULL, work, 100), MCG_EINVAL,
                 "svd v = NULL");
    check_status(mcg_svd(3, 2, a, b, s, v, NULL, 100), MCG_EINVAL,
                 "svd work = NULL");
    check_status(mcg_svd(3, 2, a, b, s, v, work, mcg_svd_work_size(3, 2) - 1),
                 MCG_ENOMEM, "svd lwork too small");
    check_status(mcg_svd(2, 3, a, NULL, s, v, work, mcg_svd_work_size(2, 3)),
                 MCG_OK, "svd u = NULL allowed");
    a[4] = NAN;
    check_status(mcg_qr(3, 2, a, b, c, work, 100), MCG_EINVAL, "qr NaN");
    check_status(mcg_svd(3, 2, a, b, s, v, work, 100), MCG_EINVAL, "svd NaN");
    check_status(mcg_pinv(3, 2, a, 0.0, b, &rank, work, 1000), MCG_EINVAL,
                 "pinv NaN");
    a[4] = INFINITY;
    check_status(mcg_svd(3, 2, a, b, s, v, work, 100), MCG_EINVAL, "svd inf");
    a[4] = 1.0;
    check_status(mcg_pinv(3, 2, a, NAN, b, &rank, work, 1000), MCG_EINVAL,
                 "pinv rcond NaN");
    check_status(mcg_pinv(3, 2, a, 0.0, b, &rank, work,
                          mcg_pinv_work_size(3, 2) - 1),
                 MCG_ENOMEM, "pinv lwork too small");
    check_status(mcg_pinv(3, 2, a, 0.0, b, NULL, work, 1000), MCG_OK,
                 "pinv rank = NULL allowed");
    check_status(mcg_sym_eig(0, a, w, v), MCG_EINVAL, "sym_eig n = 0");
    check_status(mcg_sym_eig(2, NULL, w, v), MCG_EINVAL, "sym_eig a = NULL");
    check_status(mcg_sym_eig(2, a, w, a), MCG_EINVAL, "sym_eig v aliases a");
    b[0] = 1;
    b[1] = NAN;
    b[2] = 0;
    b[3] = 1;
    check_status(mcg_sym_eig(2, b, w, v), MCG_EINVAL, "sym_eig NaN");
    check_status(mcg_sym_eig_tridiag(2, b, w, v), MCG_EINVAL, "sym_eig_tridiag NaN");
    check_status(mcg_sym_eig_tridiag(0, a, w, v), MCG_EINVAL, "sym_eig_tridiag n = 0");
    check_status(mcg_sym_eig_tridiag(65, a, w, v), MCG_EINVAL, "sym_eig_tridiag n = 65");
    check_status(mcg_sym_eig_tridiag(2, NULL, w, v), MCG_EINVAL, "sym_eig_tridiag a = NULL");
    check_status(mcg_sym_eig_tridiag(2, a, w, a), MCG_EINVAL, "sym_eig_tridiag v aliases a");
    b[1] = 0;
    check_status(mcg_spd_solve(2, b, NULL, x), MCG_EINVAL, "spd_solve b NULL");
    c[0] = NAN;
    check_status(mcg_spd_solve(2, b, c, x), MCG_EINVAL, "spd_solve NaN b");
    check_status(mcg_spd_solve(0, b, c, x), MCG_EINVAL, "spd_solve n = 0");
    c[0] = NAN;
    c[1] = c[2] = 0;
    check_status(mcg_rot_from_angle_axis(c, v), MCG_EINVAL,
                 "rot_from_angle_axis NaN");
    check_status(mcg_rot_from_angle_axis(NULL, v), MCG_EINVAL,
                 "rot_from_angle_axis NULL");
    c[0] = c[1] = c[2] = c[3] = 0.0;
    check_status(mcg_rot_from_quat(c, v), MCG_EINVAL, "rot_from_quat q = 0");
    c[0] = INFINITY;
    check_status(mcg_rot_from_quat(c, v), MCG_EINVAL, "rot_from_quat inf");
    for (i = 0; i < 9; ++i)
        b[i] = (i % 4 == 0) ? 1.0 : 0.0;
    b[5] = NAN;
    check_status(mcg_quat_from_rot(b, c), MCG_EINVAL, "quat_from_rot NaN");
    check_status(mcg_angle_axis_from_rot(b, c), MCG_EINVAL,
                 "angle_axis_from_rot NaN");
    check_status(mcg_project_so3(b, c), MCG_EINVAL, "project_so3 NaN");
    check_status(mcg_project_so3(NULL, c), MCG_EINVAL, "project_so3 NULL");
}

/* ---------------------------------------------- exact-size workspaces */

/* Every buffer is allocated with exactly the documented size plus a canary
 * tail: a write past the end changes the canary (and, under
 * -fsanitize=address, any access past the documented size lands in the
 * redzone of a second, exact-size allocation). Also a sweep of all small
 * shapes for the basic SVD identities. */
#define CANARY 8
static double *alloc_canary(size_t n)
{
    double *p = malloc((n + CANARY) * sizeof(double));
    size_t i;
    if (p == NULL)
        return NULL;
    for (i = 0; i < n + CANARY; ++i)
        p[i] = (i < n) ? nrand() : 12345.0;
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
    int m, n, ok_canary = 1, ok_status = 1, ok_id = 1;
    double worst = 0.0;
    for (m = 1; m <= 13; ++m)
        for (n = 1; n <= 13; ++n) {
            size_t mn = (size_t)(m < n ? m : n);
            size_t sz = (size_t)m * (size_t)n;
            size_t wsv = mcg_svd_work_size(m, n);
            size_t wsp = mcg_pinv_work_size(m, n);
            double *a = alloc_canary(sz), *u = alloc_canary((size_t)m * mn);
            double *s = alloc_canary((size_t)n);
            double *v = alloc_canary((size_t)n * (size_t)n);
            double *w = alloc_canary(wsv), *x = alloc_canary(sz);
            double *wp = alloc_canary(wsp);
            double *wexact = malloc(wsv * sizeof(double));
            double *q = NULL, *r = NULL, *wq = NULL;
            int rank;
            if (!a || !u || !s || !v || !w || !x || !wp || !wexact) {
                ok_status = 0;
                goto next;
            }
            if (mcg_svd(m, n, a, u, s, v, w, wsv) != MCG_OK ||
                mcg_svd(m, n, a, u, s, v, wexact, wsv) != MCG_OK)
                ok_status = 0;
            else {
                /* |a - u s v^T| and orthogonality */
                int i, j, k;
                double e = 0.0;
                for (i = 0; i < m; ++i)
                    for (j = 0; j < n; ++j) {
                        double acc = 0.0;
                        for (k = 0; k < (int)mn; ++k)
                            acc += u[i * (int)mn + k] * s[k] * v[j * n + k];
                        e = fmax(e, fabs(acc - a[i * n + j]));
                    }
                e = fmax(e, orthonormality_error(u, m, (int)mn));
                e = fmax(e, orthonormality_error(v, n, n));
                if (e > worst)
                    worst = e;
                if (e > 1e-13)
                    ok_id = 0;
            }
            ok_canary &= canary_ok(a, sz) && canary_ok(u, (size_t)m * mn) &&
                         canary_ok(s, (size_t)n) &&
                         canary_ok(v, (size_t)n * (size_t)n) &&
                         canary_ok(w, wsv);
            if (mcg_pinv(m, n, a, 0.0, x, &rank, wp, wsp) != MCG_OK)
                ok_status = 0;
            ok_canary &= canary_ok(x, sz) && canary_ok(wp, wsp);
            if (m >= n) {
                size_t wsq = mcg_qr_work_size(m, n);
                q = alloc_canary(sz);
                r = alloc_canary((size_t)n * (size_t)n);
                wq = alloc_canary(wsq);
                if (!q || !r || !wq ||
                    mcg_qr(m, n, a, q, r, wq, wsq) != MCG_OK)
                    ok_status = 0;
                else
                    ok_canary &= canary_ok(q, sz) &&
                                 canary_ok(r, (size_t)n * (size_t)n) &&
                                 canary_ok(wq, wsq);
            }
        next:
            free(a);
            free(u);
            free(s);
            free(v);
            free(w);
            free(x);
            free(wp);
            free(wexact);
            free(q);
            free(r);
            free(wq);
        }
    check(ok_status, "qr/svd/pinv all shapes <= 13x13 with exact lwork: OK",
          0, 0);
    check(ok_canary, "qr/svd/pinv write nothing past documented sizes", 0, 0);
    check(ok_id, "svd all shapes <= 13x13: a = u s v^T, orthogonality", worst,
          1e-13);
}

int main(void)
{
    test_qr();
    test_svd();
    test_pinv();
    test_sym_eig();
    test_spd();
    test_rotations();
    test_exact_workspaces();
    test_invalid();
    printf("%s: %d checks, %d failed\n", n_failed ? "FAILED" : "PASSED",
           n_checks, n_failed);
    return n_failed ? 1 : 0;
}
