/*
 * fuzz_lp.c -- libFuzzer harness of the LP feasibility backends of the
 * branch and bound (thesis ch. 10.3): {x in R^dim : A_k . x >= b_k}, dim 2
 * or 3, by the native solver (mcg_lp_native_*), GLPK through dlopen
 * (mcg_lp_glpk_*, when libglpk loads: $MCG_GLPK_LIBRARY, set by fuzz/run)
 * and the backend table (mcg_lp_*_backend, mcg_lp_work_size,
 * mcg_lp_feasible).
 *
 * Invariants: invalid dim or m, NaN/inf or |value| > 1e150 give
 * MCG_EINVAL and work size 0 for bad sizes; a short workspace MCG_ENOMEM;
 * MCG_OK comes with a finite point satisfying every row to the backend's
 * documented tolerance (2e-9 S |A_k| native, 2e-8 S |A_k| GLPK). Clear-cut
 * answers must agree: a decoded point inside every row by a margin of
 * 1e-6 S |A_k| (or a feasible point returned by the other backend with that
 * margin) forbids MCG_EINFEASIBLE; a pair of opposite rows a.x >= 1,
 * -a.x >= 0 forbids MCG_OK. The table calls give the same answers as the
 * direct calls.
 */
#include "fuzz_input.h"
#include "mcgeom.h"

/* routines selected by the first input byte (fuzz/make_corpus.py writes
 * seeds for each) */
#define FUZZ_MODES 3

#define MAXM 48

static int glpk_ok = 0;

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    glpk_ok = mcg_lp_glpk_load(NULL) == MCG_OK;
    fprintf(stderr, "fuzz_lp: GLPK backend %s\n", glpk_ok ? "loaded" : "NOT available");
    return 0;
}

static double row_norm(int dim, const double *A, int k)
{
    double s = 0.0;
    int i;
    for (i = 0; i < dim; ++i)
        s += A[k * dim + i] * A[k * dim + i];
    return sqrt(s);
}

/* the scale S of the header: max(1, max_k |b_k| / |A_k|) over non-zero rows */
static double lp_scale(int dim, int m, const double *A, const double *b)
{
    double S = 1.0;
    int k;
    for (k = 0; k < m; ++k) {
        double nk = row_norm(dim, A, k);
        if (nk > 1e-100 && fabs(b[k]) / nk > S)
            S = fabs(b[k]) / nk;
    }
    return S;
}

/* min_k (A_k . x - b_k) / |A_k| over non-zero rows, in units of S */
static double margin(int dim, int m, const double *A, const double *b, const double *x, double S)
{
    double mg = INFINITY;
    int k, i;
    for (k = 0; k < m; ++k) {
        double nk = row_norm(dim, A, k), v = -b[k];
        if (!(nk > 1e-100)) {
            if (b[k] > 0.0)
                return -INFINITY;
            continue;
        }
        for (i = 0; i < dim; ++i)
            v += A[k * dim + i] * x[i];
        if (v / (nk * S) < mg)
            mg = v / (nk * S);
    }
    return mg;
}

static int values_ok(int dim, int m, const double *A, const double *b)
{
    int k;
    for (k = 0; k < m * dim; ++k)
        if (!isfinite(A[k]) || fabs(A[k]) > 1e150)
            return 0;
    for (k = 0; k < m; ++k)
        if (!isfinite(b[k]) || fabs(b[k]) > 1e150)
            return 0;
    return 1;
}

/* one backend, directly and through its table; returns the status and x */
static int solve(int glpk, int dim, int m, const double *A, const double *b, double *x,
                 int short_work)
{
    mcg_lp_backend be;
    size_t ws = glpk ? mcg_lp_glpk_work_size(dim, m) : mcg_lp_native_work_size(dim, m);
    size_t lw = (short_work && ws > 0) ? ws - 1 : ws;
    double *work = fz_alloc(lw), x2[3] = {NAN, NAN, NAN};
    int st, st2;
    FZ_CHECK((glpk ? mcg_lp_glpk_backend(&be) : mcg_lp_native_backend(&be)) == MCG_OK,
             "lp backend %d not filled", glpk);
    FZ_CHECK(mcg_lp_work_size(&be, dim, m) == ws, "lp table work size differs");
    st = glpk ? mcg_lp_glpk_feasible(dim, m, A, b, x, work, lw)
              : mcg_lp_native_feasible(dim, m, A, b, x, work, lw);
    st2 = mcg_lp_feasible(&be, dim, m, A, b, x2, work, lw);
    FZ_CHECK(st == st2, "lp %s: direct %d, table %d", be.name, st, st2);
    if (st == MCG_OK)
        FZ_CHECK(memcmp(x, x2, (size_t)dim * sizeof(double)) == 0 || glpk,
                 "lp native: table point differs");
    free(work);
    return st;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in = fz_make(data, size);
    int mode = fz_u8(&in) % FUZZ_MODES, dim, m, vm, k, i, st[2], planted = 0, contradiction = -1;
    int short_work = (fz_u8(&in) % 32) == 0;
    double A[MAXM * 3], b[MAXM], x[2][3], p[3], S, mp = -INFINITY;
    uint8_t dsel = fz_u8(&in);
    dim = (dsel % 16 == 15) ? (int)(dsel >> 4) - 4 : 2 + (dsel & 1); /* sometimes invalid */
    m = fz_size(&in, 0, MAXM, &vm);
    if (!vm || (dim != 2 && dim != 3)) {
        double dummy[8] = {0};
        FZ_CHECK(mcg_lp_native_work_size(dim, m) == 0, "native work size for dim %d m %d",
                 dim, m);
        FZ_CHECK(mcg_lp_native_feasible(dim, m, dummy, dummy, dummy, dummy, 8) == MCG_EINVAL,
                 "native accepted dim %d m %d", dim, m);
        if (glpk_ok)
            FZ_CHECK(mcg_lp_glpk_feasible(dim, m, dummy, dummy, dummy, dummy, 8) == MCG_EINVAL,
                     "glpk accepted dim %d m %d", dim, m);
        return 0;
    }
    if (mode == 0) { /* arbitrary rows */
        fz_matrix(&in, A, (size_t)m, (size_t)dim);
        fz_doubles(&in, b, (size_t)m);
    } else { /* rows around a planted point p: feasible iff every slack >= 0 */
        double scale = mode == 2 ? pow(10.0, fz_range(&in, -6.0, 6.0)) : 1.0;
        for (i = 0; i < dim; ++i)
            p[i] = fz_range(&in, -5.0, 5.0) * scale;
        for (k = 0; k < m; ++k) {
            double v = 0.0, slack = fz_range(&in, -0.5, 2.0);
            for (i = 0; i < dim; ++i) {
                const double a = fz_range(&in, -1.0, 1.0); /* decoded before the scale */
                A[k * dim + i] = a * (mode == 2 ? fz_range(&in, 0.0, 1e3) : 1.0);
                v += A[k * dim + i] * p[i];
            }
            b[k] = v - slack * row_norm(dim, A, k) * scale;
        }
        planted = 1;
        /* sometimes two opposite rows a.x >= 1 and -a.x >= 0: infeasible */
        if (m >= 2 && (fz_u8(&in) & 3) == 0) {
            contradiction = fz_int(&in, 0, m - 2);
            for (i = 0; i < dim; ++i)
                A[(contradiction + 1) * dim + i] = -A[contradiction * dim + i];
            if (row_norm(dim, A, contradiction) > 1e-3) {
                b[contradiction] = row_norm(dim, A, contradiction) * scale;
                b[contradiction + 1] = 0.0;
            } else {
                contradiction = -1;
            }
        }
    }
    for (k = 0; k < 2; ++k) {
        x[k][0] = x[k][1] = x[k][2] = NAN;
        st[k] = (k == 1 && !glpk_ok) ? -1 : solve(k, dim, m, A, b, x[k], short_work);
        if (st[k] < 0)
            continue;
        FZ_CHECK(fz_status_known(st[k]), "lp %d status %d", k, st[k]);
        if (short_work && values_ok(dim, m, A, b) && m > 0) {
            FZ_CHECK(st[k] == MCG_ENOMEM || st[k] == MCG_EINFEASIBLE,
                     "lp %d with short work: %d", k, st[k]);
            continue;
        }
        if (!values_ok(dim, m, A, b) && !short_work)
            FZ_CHECK(st[k] == MCG_EINVAL, "lp %d accepted NaN/inf/huge values: %d", k, st[k]);
    }
    if (short_work || !values_ok(dim, m, A, b))
        return 0;
    S = lp_scale(dim, m, A, b);
    if (planted && contradiction < 0)
        mp = margin(dim, m, A, b, p, S);
    for (k = 0; k < 2; ++k) {
        if (st[k] < 0)
            continue;
        FZ_CHECK(st[k] == MCG_OK || st[k] == MCG_EINFEASIBLE || st[k] == MCG_ENUMERIC,
                 "lp %d: status %d on valid input", k, st[k]);
        if (st[k] == MCG_OK) {
            double tol = k == 0 ? 2e-9 : 2e-8;
            FZ_CHECK(fz_all_finite(x[k], (size_t)dim), "lp %d: non-finite point", k);
            for (i = 0; i < dim; ++i)
                FZ_CHECK(fabs(x[k][i]) <= 1e6 * S * (1.0 + 1e-9), "lp %d: x outside the box", k);
            FZ_CHECK(margin(dim, m, A, b, x[k], S) >= -tol * (1.0 + 1e-6),
                     "lp %d: returned point violates a row by %g S |A_k|", k,
                     -margin(dim, m, A, b, x[k], S));
            FZ_CHECK(contradiction < 0, "lp %d: feasible with contradicting rows", k);
        }
        if (mp >= 1e-6)
            FZ_CHECK(st[k] != MCG_EINFEASIBLE,
                     "lp %d: infeasible, but the planted point has margin %g S", k, mp);
    }
    /* cross-check: a point of one backend well inside every row */
    if (st[0] >= 0 && st[1] >= 0) {
        for (k = 0; k < 2; ++k)
            if (st[k] == MCG_OK && margin(dim, m, A, b, x[k], S) >= 1e-6)
                FZ_CHECK(st[1 - k] != MCG_EINFEASIBLE,
                         "lp: backend %d infeasible, backend %d has a point with margin %g S",
                         1 - k, k, margin(dim, m, A, b, x[k], S));
    }
    return 0;
}
