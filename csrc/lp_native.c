/*
 * lp_native.c -- LP feasibility of {x : a_k . x >= b_k, k < m} in 2 and 3
 * variables (the translation tests of thesis ch. 10.3: 3 variables for the
 * rig, 2 for the single-camera preemptive test), by Seidel's randomized
 * incremental algorithm, and the backend table shared with other LP backends
 * (lp_glpk.c when GLPK is available).
 *
 * Algorithm. A fixed generic objective c.x is minimised over the constraints
 * intersected with a box |x_i| <= big (so that every intermediate optimum is
 * bounded and unique in general position). The constraints are visited in an
 * order shuffled by a deterministic generator (a fixed seed: the same input
 * gives the same answer); while the current optimum satisfies the next
 * constraint it stays optimal, otherwise the new optimum lies on that
 * constraint's boundary and is found by the same algorithm one dimension
 * lower (3 -> 2 -> 1), over the constraints visited so far projected onto
 * the boundary. If the lower problem is empty, so is the whole set. Expected
 * O(m) time for d = 2, 3 over the shuffles (O(d! m)); adversarial orders cost
 * at most O(m^d). Ties (zero components of the projected objective) are
 * harmless for a feasibility answer: any optimum of the previous constraints
 * will do.
 *
 * Scaling and tolerances. Each row is normalised (|a_k| = 1); a row with
 * |a_k| <= 1e-100 is the constraint 0 >= b_k (infeasible iff b_k > 0).
 * With S = max(1, max_k |b_k| / |a_k|), the box is big = 1e6 S and every
 * constraint is relaxed by tol = 1e-9 S (in distance units): the answer is
 * "feasible" with a point x satisfying a_k . x >= b_k - 2 tol |a_k| and
 * |x_i| <= big, or "infeasible". Sets whose feasibility or infeasibility
 * margin (the distance by which all constraints can be tightened or must be
 * loosened) exceeds ~tol get the exact answer; thinner ones may go either
 * way. The returned x is a vertex of the relaxed set (or of the box), not a
 * central point. A feasible answer is verified against the original rows
 * before it is returned (MCG_ENUMERIC if that check fails).
 *
 * No allocation: the caller passes mcg_lp_native_work_size(dim, m) doubles.
 */
#include "lp_internal.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

/* A projected row norm below PARALLEL: the row is parallel to the line (plane)
 * of the lower-dimensional step. It then excludes that line (plane) only if
 * it is violated everywhere on it within the box (by more than tol plus its
 * change g * extent there), else it is dropped there. The threshold sits
 * above the rounding of exactly parallel rows (~1e-16: duplicated rows) and
 * below rows that still cross the line inside the box (1e-12 was too large:
 * fuzz_lp finding 9, a feasible cone declared empty). */
#define PARALLEL 3e-14
#define BOX_FACTOR 1e6
#define TOL_FACTOR 1e-9

/* generic objective directions (powers of the plastic number's inverse) */
static const double OBJ3[3] = {1.0, 0.7548776662466927, 0.5698402909980532};
static const double OBJ2[2] = {1.0, 0.7548776662466927};

static uint64_t split_next(uint64_t *s)
{
    uint64_t z = (*s += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

/* shuffle n rows of w doubles in place (Fisher-Yates, fixed seed) */
static void shuffle_rows(double *rows, int n, int w, uint64_t seed)
{
    int i, j, k;
    for (i = n - 1; i > 0; --i) {
        j = (int)(split_next(&seed) % (uint64_t)(i + 1));
        if (j != i)
            for (k = 0; k < w; ++k) {
                double t = rows[i * w + k];
                rows[i * w + k] = rows[j * w + k];
                rows[j * w + k] = t;
            }
    }
}

/*
 * 1-D step of the 2-D solver: minimise c . (q0 + s e) over the line
 * r . y = h (r unit) subject to rows[0..n) (unit rows r_j . y >= h_j) and
 * the box |y_i| <= B. Returns 1 and the point y, or 0 if empty.
 */
static int solve_line(const double *rows, int n, const double r[2], double h,
                      double B, const double c[2], double tol, double y[2])
{
    double q0[2] = {h * r[0], h * r[1]}, e[2] = {-r[1], r[0]};
    double lo = -HUGE_VAL, hi = HUGE_VAL, s, ce;
    int j, i;

    for (i = 0; i < 2; ++i) { /* the box */
        if (fabs(e[i]) < PARALLEL) { /* as for the rows below */
            if (fabs(q0[i]) > B + tol)
                return 0;
            continue;
        }
        {
            double s1 = (-B - q0[i]) / e[i], s2 = (B - q0[i]) / e[i];
            if (s1 > s2) {
                double t = s1;
                s1 = s2;
                s2 = t;
            }
            if (s1 > lo)
                lo = s1;
            if (s2 < hi)
                hi = s2;
        }
    }
    for (j = 0; j < n; ++j) {
        const double *rj = rows + 3 * j;
        double g = rj[0] * e[0] + rj[1] * e[1];
        double rhs = rj[2] - (rj[0] * q0[0] + rj[1] * q0[1]);
        /* parallel only if the row changes by less than tol over the whole
         * line within the box (|s| < 2 B): a nearly parallel row (g ~ 1e-13)
         * can still cross the line inside the box, far from q0, and then
         * bounds s like any other (found by fuzz_lp: a feasible cone with
         * margin 1 S declared empty) */
        if (fabs(g) < PARALLEL) {
            if (rhs > tol + fabs(g) * 3.0 * B)
                return 0;
            continue;
        }
        if (g > 0) {
            double v = rhs / g;
            if (v > lo)
                lo = v;
        } else {
            double v = rhs / g;
            if (v < hi)
                hi = v;
        }
    }
    ce = c[0] * e[0] + c[1] * e[1];
    if (lo > hi) {
        /* empty up to rounding? verify the midpoint within the tolerance
         * (the box too: the line may miss it) */
        s = 0.5 * (lo + hi);
        for (i = 0; i < 2; ++i)
            if (fabs(q0[i] + s * e[i]) > B + tol)
                return 0;
        for (j = 0; j < n; ++j) {
            const double *rj = rows + 3 * j;
            double yy0 = q0[0] + s * e[0], yy1 = q0[1] + s * e[1];
            if (rj[0] * yy0 + rj[1] * yy1 < rj[2] - tol)
                return 0;
        }
    } else {
        s = ce > 0 ? lo : (ce < 0 ? hi : lo);
    }
    y[0] = q0[0] + s * e[0];
    y[1] = q0[1] + s * e[1];
    return 1;
}

/*
 * Seidel in 2-D: minimise c . y over unit rows[0..n) (r . y >= h) and the
 * box |y_i| <= B. Returns 1 and y, or 0 if empty.
 */
static int solve_2d(const double *rows, int n, double B, const double c[2],
                    double tol, double y[2])
{
    int k;
    y[0] = c[0] > 0 ? -B : (c[0] < 0 ? B : -B);
    y[1] = c[1] > 0 ? -B : (c[1] < 0 ? B : -B);
    for (k = 0; k < n; ++k) {
        const double *r = rows + 3 * k;
        if (r[0] * y[0] + r[1] * y[1] >= r[2] - tol)
            continue;
        if (!solve_line(rows, k, r, r[2], B, c, tol, y))
            return 0;
    }
    return 1;
}

/* orthonormal basis e1, e2 of the plane orthogonal to the unit a */
static void plane_basis(const double a[3], double e1[3], double e2[3])
{
    double t[3] = {0, 0, 0}, n;
    int i = 0;
    if (fabs(a[1]) < fabs(a[i]))
        i = 1;
    if (fabs(a[2]) < fabs(a[i]))
        i = 2;
    t[i] = 1.0;
    /* e1 = unit(t - (t.a) a) */
    e1[0] = t[0] - a[i] * a[0];
    e1[1] = t[1] - a[i] * a[1];
    e1[2] = t[2] - a[i] * a[2];
    n = sqrt(dot3(e1, e1));
    e1[0] /= n;
    e1[1] /= n;
    e1[2] /= n;
    cross3(a, e1, e2);
}

/*
 * Seidel in 3-D over unit rows[0..n) (4 doubles: a, b); rows[0..6) are the
 * box, satisfied by the start corner. proj: scratch of 3 n doubles.
 */
static int solve_3d(const double *rows, int n, double big, double tol,
                    double *proj, double x[3])
{
    int k, j, i;
    for (i = 0; i < 3; ++i)
        x[i] = OBJ3[i] > 0 ? -big : big;
    for (k = 6; k < n; ++k) {
        const double *a = rows + 4 * k;
        double e1[3], e2[3], p0[3], c2[2], y[2];
        int np = 0;
        if (dot3(a, x) >= a[3] - tol)
            continue;
        plane_basis(a, e1, e2);
        for (i = 0; i < 3; ++i)
            p0[i] = a[3] * a[i];
        for (j = 0; j < k; ++j) {
            const double *r = rows + 4 * j;
            double ru = dot3(r, e1);
            double rv = dot3(r, e2);
            double rh = r[3] - dot3(r, p0);
            double g = sqrt(ru * ru + rv * rv);
            /* parallel only if the row changes by less than tol over the
             * plane within the box (|y_i| < 2 big, as solve_2d's box): see
             * solve_line */
            if (g < PARALLEL) {
                if (rh > tol + g * 6.0 * big)
                    return 0; /* a parallel constraint excludes the plane */
                continue;
            }
            proj[3 * np] = ru / g;
            proj[3 * np + 1] = rv / g;
            proj[3 * np + 2] = rh / g;
            ++np;
        }
        c2[0] = dot3(OBJ3, e1);
        c2[1] = dot3(OBJ3, e2);
        /* the box |x_i| <= big maps into |y_i| <= sqrt(3) big < 2 big */
        if (!solve_2d(proj, np, 2.0 * big, c2, tol, y))
            return 0;
        for (i = 0; i < 3; ++i)
            x[i] = p0[i] + y[0] * e1[i] + y[1] * e2[i];
    }
    return 1;
}

size_t mcg_lp_native_work_size(int dim, int m)
{
    if ((dim != 2 && dim != 3) || m < 0 || m > LP_MAX_ROWS)
        return 0;
    if (dim == 2)
        return 3 * (size_t)m + 1;
    return 7 * ((size_t)m + 6);
}

int mcg_lp_native_feasible(int dim, int m, const double *A, const double *b,
                           double *x, double *work, size_t lwork)
{
    size_t need;
    double S, big, tol;
    int k, i, st, nr = 0, w = dim + 1;

    if ((dim != 2 && dim != 3) || m < 0 || m > LP_MAX_ROWS || !x)
        return MCG_EINVAL;
    if (m > 0 && (!A || !b))
        return MCG_EINVAL;
    need = mcg_lp_native_work_size(dim, m);
    if (!work || lwork < need)
        return work ? MCG_ENOMEM : MCG_EINVAL;
    st = lp_check_rows(dim, m, A, b, &S); /* zero rows are decided here */
    if (st != MCG_OK)
        return st;
    big = BOX_FACTOR * S;
    tol = TOL_FACTOR * S;
    {
        double *rows = work + (dim == 3 ? 6 * w : 0);
        for (k = 0; k < m; ++k) {
            double n = lp_row_norm(dim, A, k);
            if (!(n > ZERO_ROW))
                continue;
            for (i = 0; i < dim; ++i)
                rows[nr * w + i] = A[k * dim + i] / n;
            /* relaxed by tol (see the file comment) */
            rows[nr * w + dim] = b[k] / n - tol;
            ++nr;
        }
        shuffle_rows(rows, nr, w, 0x5e1de15eedULL ^ (uint64_t)nr);
        if (dim == 2) {
            if (!solve_2d(rows, nr, big, OBJ2, 0.1 * tol, x))
                return MCG_EINFEASIBLE;
        } else {
            /* the box as the first six rows: x_i >= -big, -x_i >= -big */
            memset(work, 0, 6 * 4 * sizeof(double));
            for (i = 0; i < 3; ++i) {
                work[(2 * i) * 4 + i] = 1.0;
                work[(2 * i) * 4 + 3] = -big;
                work[(2 * i + 1) * 4 + i] = -1.0;
                work[(2 * i + 1) * 4 + 3] = -big;
            }
            if (!solve_3d(work, nr + 6, big, 0.1 * tol, work + 4 * (nr + 6),
                          x))
                return MCG_EINFEASIBLE;
        }
    }
    return lp_verify_point(dim, m, A, b, x, tol);
}

/* ------------------------------------------------------ backend table */

static size_t native_work_size(void *ctx, int dim, int m)
{
    (void)ctx;
    return mcg_lp_native_work_size(dim, m);
}

static int native_feasible(void *ctx, int dim, int m, const double *A,
                           const double *b, double *x, double *work,
                           size_t lwork)
{
    (void)ctx;
    return mcg_lp_native_feasible(dim, m, A, b, x, work, lwork);
}

int mcg_lp_native_backend(mcg_lp_backend *be)
{
    if (!be)
        return MCG_EINVAL;
    be->name = "native";
    be->ctx = NULL;
    be->work_size = native_work_size;
    be->feasible = native_feasible;
    return MCG_OK;
}

size_t mcg_lp_work_size(const mcg_lp_backend *be, int dim, int m)
{
    if (!be || !be->work_size)
        return 0;
    return be->work_size(be->ctx, dim, m);
}

int mcg_lp_feasible(const mcg_lp_backend *be, int dim, int m, const double *A,
                    const double *b, double *x, double *work, size_t lwork)
{
    if (!be || !be->feasible)
        return MCG_EINVAL;
    return be->feasible(be->ctx, dim, m, A, b, x, work, lwork);
}

#ifndef MCG_HAVE_GLPK
/* Built without GLPK: the GLPK backend's entry points exist and say so
 * (lp_glpk.c, GPL-3.0, replaces them when GLPK is found). */
int mcg_lp_glpk_available(void) { return 0; }

int mcg_lp_glpk_load(const char *path)
{
    (void)path;
    return MCG_EUNAVAILABLE;
}

size_t mcg_lp_glpk_work_size(int dim, int m)
{
    (void)dim;
    (void)m;
    return 0;
}

int mcg_lp_glpk_feasible(int dim, int m, const double *A, const double *b,
                         double *x, double *work, size_t lwork)
{
    (void)dim;
    (void)m;
    (void)A;
    (void)b;
    (void)x;
    (void)work;
    (void)lwork;
    return MCG_EUNAVAILABLE;
}

int mcg_lp_glpk_backend(mcg_lp_backend *be)
{
    return be ? MCG_EUNAVAILABLE : MCG_EINVAL;
}
#endif
