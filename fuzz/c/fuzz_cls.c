/*
 * fuzz_cls.c -- libFuzzer harness of the constrained least squares of
 * cls.c (thesis Algorithms 3 and 4, ch. 6.3): mcg_cls_general
 * (min |A x| s.t. |C x| = 1), mcg_cls_partial (s.t. |x[0:p]| = 1) and
 * mcg_cls_range (s.t. |x| = 1, x in range(G)), with their work sizes.
 *
 * Invariants (on MCG_OK): x and resid finite, resid = |A x|, the constraint
 * holds (|C x| = 1, |x[0:p]| = 1, |x| = 1), and x is a minimiser: for decoded
 * feasible directions y, |A y| / |C y| (resp. / |y[0:p]|, or y = G z /
 * |G z|) is not below resid beyond the rounding and the documented rank
 * truncation. Bad sizes: work size 0 and MCG_EINVAL; short work MCG_ENOMEM.
 */
#include "fuzz_input.h"
#include "mcgeom.h"

/* routines selected by the first input byte (fuzz/make_corpus.py writes
 * seeds for each) */
#define FUZZ_MODES 3

#define MAXD 12

static double norm(const double *x, int n)
{
    double mx = fz_maxabs(x, (size_t)n), s = 0.0;
    int i;
    if (!(mx > 0.0))
        return 0.0;
    for (i = 0; i < n; ++i)
        s += (x[i] / mx) * (x[i] / mx);
    return mx * sqrt(s);
}

/* y = M x, M rows x cols */
static void mul(const double *M, int rows, int cols, const double *x, double *y)
{
    int i, j;
    for (i = 0; i < rows; ++i) {
        double s = 0.0;
        for (j = 0; j < cols; ++j)
            s += M[i * cols + j] * x[j];
        y[i] = s;
    }
}

/* the decoded A and C are scaled to max |entry| = 1 so that the optimality
 * checks below cannot overflow; the problems are homogeneous in A and C */
static void normalise(double *a, size_t n)
{
    double mx = fz_maxabs(a, n);
    size_t i;
    if (mx > 0.0 && isfinite(mx))
        for (i = 0; i < n; ++i)
            a[i] /= mx;
}

static int call(int which, int m, int n, int k, const double *a, const double *c, double rcond,
                double *x, double *resid, int *rank2, size_t *ws_out, int short_work)
{
    size_t ws = which == 0 ? mcg_cls_general_work_size(m, n, k)
                : which == 1 ? mcg_cls_partial_work_size(m, n, k)
                             : mcg_cls_range_work_size(m, n, k);
    size_t lw = (short_work && ws > 0) ? ws - 1 : ws;
    double *work = fz_alloc(lw);
    int st;
    *ws_out = ws;
    if (which == 0)
        st = mcg_cls_general(m, n, k, a, c, x, resid, work, lw);
    else if (which == 1)
        st = mcg_cls_partial(m, n, k, a, rcond, x, resid, rank2, work, lw);
    else
        st = mcg_cls_range(m, n, k, a, c, rcond, x, resid, work, lw);
    free(work);
    return st;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in = fz_make(data, size);
    int which = fz_u8(&in) % FUZZ_MODES, vm, vn, vk, valid, st, rank2 = -1, i, trial;
    int m = fz_size(&in, 1, MAXD, &vm), n = fz_size(&in, 1, MAXD, &vn);
    int k = fz_size(&in, 1, MAXD, &vk), short_work = (fz_u8(&in) % 16) == 0;
    double a[MAXD * MAXD], c[MAXD * MAXD], x[MAXD], ax[MAXD], resid = NAN, rcond = 0.0;
    size_t ws;
    int scaled = fz_u8(&in) & 1;
    /* the documented size rules: partial needs 1 <= p <= n (p = k), range
     * and general any k, r >= 1 */
    valid = vm && vn && vk && (which != 1 || k <= n);
    memset(a, 0, sizeof a);
    memset(c, 0, sizeof c);
    if (valid) {
        fz_matrix(&in, a, (size_t)m, (size_t)n);
        /* C is k x n (general), G is n x r (range, r = k) */
        if (which == 0)
            fz_matrix(&in, c, (size_t)k, (size_t)n);
        else if (which == 2)
            fz_matrix(&in, c, (size_t)n, (size_t)k);
        if (which != 0 && (fz_u8(&in) & 3) == 0)
            rcond = fz_double(&in);
        if (scaled) {
            normalise(a, (size_t)(m * n));
            normalise(c, (size_t)(MAXD * MAXD));
        }
    }
    st = call(which, m, n, k, a, c, rcond, x, &resid, &rank2, &ws,
              short_work && valid && fz_all_finite(a, (size_t)(m * n)));
    FZ_CHECK(fz_status_known(st), "cls status %d", st);
    if (!vm || !vn || !vk) {
        FZ_CHECK(ws == 0, "cls %d work size %zu for sizes %d %d %d", which, ws, m, n, k);
        FZ_CHECK(st == MCG_EINVAL, "cls %d accepted sizes %d %d %d: %d", which, m, n, k, st);
        return 0;
    }
    if (!valid) {
        FZ_CHECK(st == MCG_EINVAL, "cls_partial accepted p %d > n %d: %d", k, n, st);
        return 0;
    }
    if (short_work && fz_all_finite(a, (size_t)(m * n))) {
        FZ_CHECK(st == MCG_ENOMEM || st == MCG_EINVAL, "cls %d with short work: %d", which, st);
        return 0;
    }
    if (!fz_all_finite(a, (size_t)(m * n)) || !fz_all_finite(c, sizeof c / sizeof c[0])) {
        FZ_CHECK(st != MCG_OK, "cls %d of non-finite input returned MCG_OK", which);
        return 0;
    }
    if (st != MCG_OK || !scaled)
        return 0;
    FZ_CHECK(fz_all_finite(x, (size_t)n) && isfinite(resid), "cls %d: non-finite x or resid",
             which);
    mul(a, m, n, x, ax);
    FZ_CHECK(fabs(norm(ax, m) - resid) <= 1e-9 * (1.0 + norm(x, n)),
             "cls %d: resid %g != |A x| %g", which, resid, norm(ax, m));
    {
        double cx[MAXD], con;
        if (which == 0) {
            mul(c, k, n, x, cx);
            con = norm(cx, k);
        } else if (which == 1) {
            con = norm(x, k);
        } else {
            con = norm(x, n);
        }
        /* rounding of C x grows with |x|, which can be huge: the free part
         * of x follows the smallest singular values of A_2 */
        FZ_CHECK(fabs(con - 1.0) <= 1e-9 * (1.0 + norm(x, n)), "cls %d: constraint norm %.17g "
                 "(|x| %g)", which, con, norm(x, n));
    }
    if (which == 1)
        FZ_CHECK(rank2 >= 0 && rank2 <= n - k, "cls_partial: rank2 %d (n - p = %d)", rank2,
                 n - k);
    /* optimality against decoded feasible directions */
    for (trial = 0; trial < 3; ++trial) {
        double y[MAXD], z[MAXD], ay[MAXD], cy[MAXD], den, ratio, tol, trunc;
        for (i = 0; i < MAXD; ++i)
            z[i] = fz_range(&in, -1.0, 1.0);
        trunc = 0.0;
        if (which == 2) {
            /* singular directions of G below rcond s_max(G) are dropped
             * (documented), so y = G z is feasible only up to its part along
             * them: |y_dropped| <= rcond s_max(G) |z| <= rcond |G|_F |z|.
             * With e = that bound / |y|, |A y| / |y| >= resid (1 - e) - |A| e,
             * a rigorous allowance (the old rcond-proportional one was not:
             * a y almost wholly along a dropped direction broke it) */
            double rc = rcond > 0.0 ? rcond : 1e-12, e;
            mul(c, n, k, z, y); /* y = G z */
            den = norm(y, n);
            if (!(den > 1e-3 * norm(z, k)))
                continue;
            e = rc * norm(c, n * k) * norm(z, k) / den;
            if (!(e < 0.5))
                continue; /* y mostly outside the range searched */
            trunc = e * (resid + norm(a, m * n));
        } else {
            memcpy(y, z, sizeof y);
            if (which == 0) {
                mul(c, k, n, y, cy);
                den = norm(cy, k);
            } else {
                den = norm(y, k);
            }
        }
        if (!(den > 1e-3 * norm(y, n)))
            continue; /* nearly outside the constraint set: ill-posed ratio */
        mul(a, m, n, y, ay);
        ratio = norm(ay, m) / den;
        /* rank truncations (rcond; partial: the default 1e-10 of A_2) and
         * rounding: relative to |A| |x| */
        tol = trunc + 1e-7 * (double)(m + n) * (1.0 + norm(x, n)) * (1.0 + norm(y, n) / den);
        if (which == 1 && rcond > 1e-7)
            tol += (rcond > 1.0 ? 1.0 : rcond) * (double)(m + n) * (1.0 + norm(x, n)) *
                   (1.0 + norm(y, n) / den);
        FZ_CHECK(ratio >= resid - tol, "cls %d: a feasible y has |A y|/|C y| %.17g < resid %.17g",
                 which, ratio, resid);
    }
    return 0;
}
