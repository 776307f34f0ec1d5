/*
 * translation.c -- translation of views with known rotations (thesis ch. 6).
 *
 * Views carry known rotations; their bearings are de-rotated into the world
 * frame (thesis ch. 6.1, Remark after Def. 1: x = R^-1 x_view), so that only
 * the centres c_i (world frame) are unknown. A ray of view i may start at an
 * offset w from the view's centre (a camera of a rig, world-aligned, ch. 4.2
 * Fig. 4.2); w = 0 is the omnidirectional camera of ch. 6.
 *
 *   - bilinear relation (eq. 6.5) of x_i <-> x_j with origins p = c + w:
 *         (x_i x x_j)^T (p_j - p_i) = 0;
 *   - trilinear relation (eq. 6.11) of x_i <-> x_j <-> x_k with
 *     a = p_j - p_i, b = p_k - p_i, u = x_i x x_j, v = x_i x x_k:
 *         u (x_k x b)^T - (x_j x a) v^T = 0      (9 equations);
 *   - per view pair or triple (a "block" of ch. 6.2.3), the Gram matrix
 *     S^T S of its rows [coefficients of the centres | constant term]: the
 *     diagonal blocks of A^T A of eqs. 6.18-6.19, mapped through G;
 *   - a skyline (envelope) Cholesky factorisation and solver, and the few
 *     smallest eigenpairs of a symmetric-definite pencil (N, L) in skyline
 *     storage by subspace inverse iteration with Rayleigh-Ritz: the solver
 *     of min |A G c| s.t. |G c| = 1 (ch. 6.3, Algorithm 1 line 12) without
 *     forming A or G.
 *
 * Skyline storage of a symmetric n x n matrix: row r holds the columns
 * first[r] .. r (first[r] <= r) at env[ptr[r] .. ptr[r] + r - first[r]],
 * ptr[r + 1] = ptr[r] + r - first[r] + 1, ptr[0] = 0.
 */
#include "mcgeom.h"
#include "internal.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#define MAX_SKY_N 200000
#define MAX_SKY_ENV ((size_t)1 << 28)
#define MAX_BLOCKS 2000000

static int valid_pts(int n, const double *p, int need)
{
    if (p == NULL)
        return !need;
    return all_finite(p, 3 * (size_t)n);
}

/* one bilinear row: coefficients of (c_i, c_j) and the constant */
static void bilinear_row(const double *xi, const double *xj, const double *wi,
                         const double *wj, double row[7])
{
    double u[3];
    int q;
    cross3(xi, xj, u);
    row[6] = 0.0;
    for (q = 0; q < 3; ++q) {
        row[q] = -u[q];
        row[3 + q] = u[q];
        if (wi != NULL)
            row[6] += u[q] * (wj[q] - wi[q]);
    }
}

int mcg_bilinear_rows(int n, const double *x1, const double *x2, const double *w1,
                      const double *w2, double *rows)
{
    int k;
    if (n < 1 || (size_t)n > MAX_ROWS || x1 == NULL || x2 == NULL || rows == NULL)
        return MCG_EINVAL;
    if ((w1 == NULL) != (w2 == NULL))
        return MCG_EINVAL;
    if (!valid_pts(n, x1, 1) || !valid_pts(n, x2, 1) || !valid_pts(n, w1, 0) ||
        !valid_pts(n, w2, 0))
        return MCG_EINVAL;
    for (k = 0; k < n; ++k)
        bilinear_row(x1 + 3 * k, x2 + 3 * k, w1 ? w1 + 3 * k : NULL,
                     w2 ? w2 + 3 * k : NULL, rows + 7 * k);
    if (!all_finite(rows, 7 * (size_t)n))
        return MCG_EINVAL;
    return MCG_OK;
}

/* The 9 trilinear rows (eq. 6.11) of one correspondence with view i as the
 * reference: row 3 s + t holds the coefficients of (a, b) (6 values) and the
 * constant (M at a0 = wj - wi, b0 = wk - wi). With (x_k x b)_t =
 * ([x_k]x)_tq b_q and (x_j x a)_s = ([x_j]x)_sq a_q:
 *   coef(a_q) = -([x_j]x)_sq v_t,  coef(b_q) = u_s ([x_k]x)_tq. */
static void trilinear_rows9(const double *xi, const double *xj, const double *xk,
                            const double *wi, const double *wj, const double *wk,
                            double rows[63])
{
    double u[3], v[3], sj[9], sk[9], a0[3] = {0, 0, 0}, b0[3] = {0, 0, 0};
    int s, t, q;
    cross3(xi, xj, u);
    cross3(xi, xk, v);
    skew3(xj, sj);
    skew3(xk, sk);
    if (wi != NULL)
        for (q = 0; q < 3; ++q) {
            a0[q] = wj[q] - wi[q];
            b0[q] = wk[q] - wi[q];
        }
    for (s = 0; s < 3; ++s)
        for (t = 0; t < 3; ++t) {
            double *row = rows + 7 * (3 * s + t);
            row[6] = 0.0;
            for (q = 0; q < 3; ++q) {
                row[q] = -sj[3 * s + q] * v[t];
                row[3 + q] = u[s] * sk[3 * t + q];
                row[6] += row[q] * a0[q] + row[3 + q] * b0[q];
            }
        }
}

int mcg_trilinear_rows(int n, const double *x1, const double *x2, const double *x3,
                       const double *w1, const double *w2, const double *w3,
                       double *rows)
{
    int k;
    if (n < 1 || (size_t)n > MAX_ROWS || x1 == NULL || x2 == NULL || x3 == NULL ||
        rows == NULL)
        return MCG_EINVAL;
    if ((w1 == NULL) != (w2 == NULL) || (w1 == NULL) != (w3 == NULL))
        return MCG_EINVAL;
    if (!valid_pts(n, x1, 1) || !valid_pts(n, x2, 1) || !valid_pts(n, x3, 1) ||
        !valid_pts(n, w1, 0) || !valid_pts(n, w2, 0) || !valid_pts(n, w3, 0))
        return MCG_EINVAL;
    for (k = 0; k < n; ++k)
        trilinear_rows9(x1 + 3 * k, x2 + 3 * k, x3 + 3 * k, w1 ? w1 + 3 * k : NULL,
                        w2 ? w2 + 3 * k : NULL, w3 ? w3 + 3 * k : NULL,
                        rows + 63 * k);
    if (!all_finite(rows, 63 * (size_t)n))
        return MCG_EINVAL;
    return MCG_OK;
}

/* upper triangle of g += r r^T for a row r of length d (g: d x d,
 * row-major); the lower triangle is filled once per block at the end
 * (mirror_lower): half the work of the full outer product */
static void add_outer_upper(int d, const double *r, double *g)
{
    int a, b;
    for (a = 0; a < d; ++a) {
        double ra = r[a];
        if (ra == 0.0)
            continue;
        for (b = a; b < d; ++b)
            g[a * d + b] += ra * r[b];
    }
}

static void mirror_lower(int d, double *g)
{
    int a, b;
    for (a = 1; a < d; ++a)
        for (b = 0; b < a; ++b)
            g[a * d + b] = g[b * d + a];
}

/* Upper triangle of g (10 x 10 over (c_ref, c_o1, c_o2, 1)) += the sum of
 * r r^T over the 9 trilinear rows of trilinear_rows9(x_ref, x_o1, x_o2), in
 * closed form: with u = x_r x x_1, v = x_r x x_2, alpha_st = -v_t [x_1]x_s
 * and beta_st = u_s [x_2]x_t (the a- and b-parts of row 3 s + t),
 *   sum alpha alpha^T = |v|^2 ([x_1]x^T [x_1]x) = |v|^2 (|x_1|^2 I - x_1 x_1^T),
 *   sum beta beta^T   = |u|^2 (|x_2|^2 I - x_2 x_2^T),
 *   sum alpha beta^T  = -([x_1]x^T u)([x_2]x^T v)^T = -(u x x_1)(v x x_2)^T,
 * and the constant of each row is (alpha, beta) . z, z = (a0, b0) the
 * offsets. A row over the centres is (-(alpha + beta), alpha, beta, const).
 * Several times fewer operations than the 9 explicit outer products of
 * 10-rows (KITTI-00's 1.1M trilinear relations: 1.6 s -> 0.5 s); the same
 * sums up to rounding (csrc/tests/test_translation.c and
 * tests/test_multiview.py check them against the rows of
 * mcg_trilinear_rows). */
static void add_trilinear_gram(const double *xr, const double *x1, const double *x2,
                               const double *wr, const double *w1, const double *w2,
                               int ref, int o1, int o2, double *g)
{
    double u[3], v[3], p[3], q[3], z[6] = {0, 0, 0, 0, 0, 0};
    double G[6][6], Gz[6], zGz = 0.0, uu, vv, n1, n2;
    double blk[3][3][3][3]; /* blk[P][Q]: 3 x 3 block between positions P, Q */
    double col[3][3];       /* constant column of each position */
    const int pos[3] = {ref, o1, o2};
    int a, b, P, Q;
    cross3(xr, x1, u);
    cross3(xr, x2, v);
    cross3(u, x1, p);
    cross3(v, x2, q);
    uu = dot3(u, u);
    vv = dot3(v, v);
    n1 = dot3(x1, x1);
    n2 = dot3(x2, x2);
    if (wr != NULL)
        for (a = 0; a < 3; ++a) {
            z[a] = w1[a] - wr[a];
            z[3 + a] = w2[a] - wr[a];
        }
    for (a = 0; a < 3; ++a)
        for (b = 0; b < 3; ++b) {
            G[a][b] = vv * ((a == b ? n1 : 0.0) - x1[a] * x1[b]);
            G[3 + a][3 + b] = uu * ((a == b ? n2 : 0.0) - x2[a] * x2[b]);
            G[a][3 + b] = -p[a] * q[b];
            G[3 + b][a] = G[a][3 + b];
        }
    for (a = 0; a < 6; ++a) {
        Gz[a] = 0.0;
        for (b = 0; b < 6; ++b)
            Gz[a] += G[a][b] * z[b];
        zGz += z[a] * Gz[a];
    }
    /* positions 1 (alpha), 2 (beta), 0 (-(alpha + beta)) */
    for (a = 0; a < 3; ++a) {
        for (b = 0; b < 3; ++b) {
            const double A = G[a][b], B = G[a][3 + b], Bt = G[3 + a][b], C = G[3 + a][3 + b];
            blk[1][1][a][b] = A;
            blk[2][2][a][b] = C;
            blk[1][2][a][b] = B;
            blk[2][1][a][b] = Bt;
            blk[0][0][a][b] = A + B + Bt + C;
            blk[0][1][a][b] = -(A + Bt);
            blk[1][0][a][b] = -(A + B);
            blk[0][2][a][b] = -(B + C);
            blk[2][0][a][b] = -(Bt + C);
        }
        col[1][a] = Gz[a];
        col[2][a] = Gz[3 + a];
        col[0][a] = -(Gz[a] + Gz[3 + a]);
    }
    /* the diagonal entries and zGz are sums of squares: a closed form can
     * round them below 0 (A + B + B^T + C where alpha ~ -beta), so they are
     * clamped at 0, within rounding of the exact sums and keeping every
     * diagonal of the block Gram >= 0 as the explicit sum does */
    for (P = 0; P < 3; ++P)
        for (a = 0; a < 3; ++a)
            if (blk[P][P][a][a] < 0.0)
                blk[P][P][a][a] = 0.0;
    for (P = 0; P < 3; ++P)
        for (Q = 0; Q < 3; ++Q)
            for (a = 0; a < 3; ++a)
                for (b = 0; b < 3; ++b) {
                    const int r = 3 * pos[P] + a, c = 3 * pos[Q] + b;
                    if (r <= c)
                        g[10 * r + c] += blk[P][Q][a][b];
                }
    for (P = 0; P < 3; ++P)
        for (a = 0; a < 3; ++a)
            g[10 * (3 * pos[P] + a) + 9] += col[P][a];
    g[99] += zGz > 0.0 ? zGz : 0.0;
}

int mcg_relation_grams(int q, int n, const double *x, const double *w,
                       const int *block, int n_blocks, double *grams)
{
    const int d = 3 * q + 1;
    size_t k;
    int i;
    if ((q != 2 && q != 3) || n < 0 || (size_t)n > MAX_ROWS || n_blocks < 1 ||
        n_blocks > MAX_BLOCKS || x == NULL || block == NULL || grams == NULL)
        return MCG_EINVAL;
    if (!all_finite(x, 3 * (size_t)q * (size_t)n) ||
        (w != NULL && !all_finite(w, 3 * (size_t)q * (size_t)n)))
        return MCG_EINVAL;
    for (i = 0; i < n; ++i)
        if (block[i] < 0 || block[i] >= n_blocks)
            return MCG_EINVAL;
    memset(grams, 0, sizeof(double) * (size_t)n_blocks * (size_t)(d * d));
    for (k = 0; k < (size_t)n; ++k) {
        const double *xk = x + 3 * (size_t)q * k;
        const double *wk = w ? w + 3 * (size_t)q * k : NULL;
        double *g = grams + (size_t)block[k] * (size_t)(d * d);
        if (q == 2) {
            double row[7];
            bilinear_row(xk, xk + 3, wk, wk ? wk + 3 : NULL, row);
            add_outer_upper(7, row, g);
        } else {
            /* all three choices of the reference view: the block's rows, and
             * so the solution, do not depend on the order of its views */
            int ref;
            for (ref = 0; ref < 3; ++ref) {
                const int o1 = (ref + 1) % 3, o2 = (ref + 2) % 3;
                /* a = c_o1 - c_ref, b = c_o2 - c_ref */
                add_trilinear_gram(xk + 3 * ref, xk + 3 * o1, xk + 3 * o2,
                                   wk ? wk + 3 * ref : NULL, wk ? wk + 3 * o1 : NULL,
                                   wk ? wk + 3 * o2 : NULL, ref, o1, o2, g);
            }
        }
    }
    for (i = 0; i < n_blocks; ++i)
        mirror_lower(d, grams + (size_t)i * (size_t)(d * d));
    if (!all_finite(grams, (size_t)n_blocks * (size_t)(d * d)))
        return MCG_EINVAL;
    return MCG_OK;
}

/* ------------------------------------------------------------- skyline */

static int valid_profile(int n, const int *first, const int *ptr)
{
    int r;
    if (n < 1 || n > MAX_SKY_N || first == NULL || ptr == NULL || ptr[0] != 0)
        return 0;
    for (r = 0; r < n; ++r) {
        if (first[r] < 0 || first[r] > r)
            return 0;
        /* ptr[r] bounded first: the sum below cannot overflow an int */
        if (ptr[r] < 0 || (size_t)ptr[r] > MAX_SKY_ENV)
            return 0;
        if (ptr[r + 1] != ptr[r] + (r - first[r]) + 1)
            return 0;
    }
    return (size_t)ptr[n] <= MAX_SKY_ENV;
}

int mcg_skyline_cholesky(int n, const int *first, const int *ptr, double *env)
{
    int r, c, k;
    if (!valid_profile(n, first, ptr) || env == NULL)
        return MCG_EINVAL;
    if (!all_finite(env, (size_t)ptr[n]))
        return MCG_EINVAL;
    for (r = 0; r < n; ++r) {
        /* row pointers at the start of the stored part of the row (pointer
         * arithmetic stays inside the array): lr[c - fr] = L(r, c) */
        double *lr = env + ptr[r];
        const int fr = first[r];
        for (c = fr; c <= r; ++c) {
            const double *lc = env + ptr[c];
            const int fc = first[c];
            int k0 = fr > fc ? fr : fc;
            double s = lr[c - fr];
            for (k = k0; k < c; ++k)
                s -= lr[k - fr] * lc[k - fc];
            if (c < r) {
                lr[c - fr] = s / lc[c - fc];
            } else {
                if (!(s > 0.0) || !isfinite(s))
                    return MCG_ENUMERIC; /* not positive definite */
                lr[r - fr] = sqrt(s);
            }
        }
    }
    return MCG_OK;
}

/* solve L L^T x = b in place with the factor of mcg_skyline_cholesky */
static void sky_solve(int n, const int *first, const int *ptr, const double *l,
                      double *b)
{
    int r, k;
    for (r = 0; r < n; ++r) {
        const double *lr = l + ptr[r];
        const int fr = first[r];
        double s = b[r];
        for (k = fr; k < r; ++k)
            s -= lr[k - fr] * b[k];
        b[r] = s / lr[r - fr];
    }
    for (r = n - 1; r >= 0; --r) {
        const double *lr = l + ptr[r];
        const int fr = first[r];
        double xr = b[r] / lr[r - fr];
        b[r] = xr;
        for (k = fr; k < r; ++k)
            b[k] -= lr[k - fr] * xr;
    }
}

int mcg_skyline_solve(int n, const int *first, const int *ptr, const double *chol,
                      double *b)
{
    if (!valid_profile(n, first, ptr) || chol == NULL || b == NULL)
        return MCG_EINVAL;
    if (!all_finite(b, (size_t)n))
        return MCG_EINVAL;
    sky_solve(n, first, ptr, chol, b);
    return all_finite(b, (size_t)n) ? MCG_OK : MCG_ENUMERIC;
}

/* y = A x for a symmetric skyline matrix */
static void sky_matvec(int n, const int *first, const int *ptr, const double *a,
                       const double *x, double *y)
{
    int r, c;
    memset(y, 0, sizeof(double) * (size_t)n);
    for (r = 0; r < n; ++r) {
        const double *ar = a + ptr[r];
        const int fr = first[r];
        double s = ar[r - fr] * x[r];
        for (c = fr; c < r; ++c) {
            s += ar[c - fr] * x[c];
            y[c] += ar[c - fr] * x[r];
        }
        y[r] += s;
    }
}

static double dot(int n, const double *a, const double *b)
{
    double s = 0.0;
    int i;
    for (i = 0; i < n; ++i)
        s += a[i] * b[i];
    return s;
}

size_t mcg_skyline_eig_work_size(int n, int p, int env_size)
{
    int ok = 1;
    size_t w;
    if (n < 1 || p < 1 || p > 8 || p > n || env_size < n)
        return 0;
    w = (size_t)env_size;                                   /* factor */
    w = add_sz(w, mul_sz(5 * (size_t)p, (size_t)n, &ok), &ok); /* X Y NY LY tmp */
    w = add_sz(w, 3 * 64 + (size_t)n, &ok);                 /* small + r */
    return ok ? w : 0;
}

/* L-orthonormalise the p columns (each n values, stored consecutively) of y
 * by modified Gram-Schmidt, twice; ly receives L y. A column that loses
 * (numerically) everything is replaced by a unit vector and retried. */
static void l_orthonormalise(int n, int p, const int *first, const int *ptr,
                             const double *lmat, double *y, double *ly)
{
    int j, i, pass, k, e = 0;
    for (j = 0; j < p; ++j) {
        double *yj = y + (size_t)j * n;
        int tries;
        for (tries = 0; tries < n + 1; ++tries) {
            double norm0, nrm;
            sky_matvec(n, first, ptr, lmat, yj, ly + (size_t)j * n);
            norm0 = sqrt(fabs(dot(n, yj, ly + (size_t)j * n)));
            for (pass = 0; pass < 2; ++pass)
                for (i = 0; i < j; ++i) {
                    double h = dot(n, yj, ly + (size_t)i * n);
                    for (k = 0; k < n; ++k)
                        yj[k] -= h * y[(size_t)i * n + k];
                }
            sky_matvec(n, first, ptr, lmat, yj, ly + (size_t)j * n);
            nrm = sqrt(fabs(dot(n, yj, ly + (size_t)j * n)));
            if (nrm > 1e-10 * norm0 && nrm > 0.0 && isfinite(nrm)) {
                for (k = 0; k < n; ++k) {
                    yj[k] /= nrm;
                    ly[(size_t)j * n + k] /= nrm;
                }
                break;
            }
            memset(yj, 0, sizeof(double) * (size_t)n);
            yj[e % n] = 1.0;
            ++e;
        }
    }
}

int mcg_skyline_eig(int n, const int *first, const int *ptr, const double *a,
                    const double *b, double shift, int p, int max_iter, double tol,
                    double *vals, double *vecs, double *resid, int *iters,
                    double *work, size_t lwork)
{
    const size_t env = (size_t)(ptr ? ptr[n > 0 && n <= MAX_SKY_N ? n : 0] : 0);
    double *fac, *x, *y, *ny, *ly, *tmp, *sa, *sv, *sw, *rv;
    double anorm = 0.0;
    int it, i, j, k, r, st;
    if (!valid_profile(n, first, ptr) || a == NULL || b == NULL || vals == NULL ||
        vecs == NULL || resid == NULL || iters == NULL || work == NULL)
        return MCG_EINVAL;
    if (p < 1 || p > 8 || p > n || max_iter < 1 || max_iter > 1000000 ||
        !(tol > 0.0) || !isfinite(shift) || shift < 0.0)
        return MCG_EINVAL;
    if (lwork < mcg_skyline_eig_work_size(n, p, (int)env) || env > (size_t)1 << 30)
        return MCG_ENOMEM;
    if (!all_finite(a, env) || !all_finite(b, env))
        return MCG_EINVAL;
    fac = work;
    x = fac + env;
    y = x + (size_t)p * n;
    ny = y + (size_t)p * n;
    ly = ny + (size_t)p * n;
    tmp = ly + (size_t)p * n;
    sa = tmp + (size_t)p * n;
    sv = sa + 64;
    sw = sv + 64;
    rv = sw + 64;
    /* factor A + shift B (SPD when B is and shift > 0, or A is) */
    for (k = 0; k < (int)env; ++k)
        fac[k] = a[k] + shift * b[k];
    st = mcg_skyline_cholesky(n, first, ptr, fac);
    if (st != MCG_OK)
        return st;
    for (r = 0; r < n; ++r) {
        double d = fabs(a[ptr[r + 1] - 1]);
        if (d > anorm)
            anorm = d;
    }
    if (anorm == 0.0)
        anorm = 1.0;
    /* deterministic start: columns spread over the whole vector */
    for (j = 0; j < p; ++j)
        for (k = 0; k < n; ++k)
            x[(size_t)j * n + k] = 1.0 + 0.5 * cos(0.7 * (j + 1) * (k + 1) + j);
    l_orthonormalise(n, p, first, ptr, b, x, ly);
    *iters = 0;
    for (it = 1; it <= max_iter; ++it) {
        double worst = 0.0;
        /* Y = (A + shift B)^-1 B X */
        for (j = 0; j < p; ++j) {
            memcpy(y + (size_t)j * n, ly + (size_t)j * n, sizeof(double) * (size_t)n);
            sky_solve(n, first, ptr, fac, y + (size_t)j * n);
        }
        l_orthonormalise(n, p, first, ptr, b, y, ly);
        /* Rayleigh-Ritz: Y^T A Y (Y is B-orthonormal) */
        for (j = 0; j < p; ++j)
            sky_matvec(n, first, ptr, a, y + (size_t)j * n, ny + (size_t)j * n);
        for (i = 0; i < p; ++i)
            for (j = 0; j < p; ++j)
                sa[i * p + j] = 0.5 * (dot(n, y + (size_t)i * n, ny + (size_t)j * n) +
                                       dot(n, y + (size_t)j * n, ny + (size_t)i * n));
        st = mcg_sym_eig(p, sa, sw, sv);
        if (st != MCG_OK)
            return MCG_ENUMERIC;
        /* X = Y V, and A X, B X for the residuals */
        for (j = 0; j < p; ++j)
            for (k = 0; k < n; ++k) {
                double s = 0.0, sn = 0.0, sl = 0.0;
                for (i = 0; i < p; ++i) {
                    s += y[(size_t)i * n + k] * sv[i * p + j];
                    sn += ny[(size_t)i * n + k] * sv[i * p + j];
                    sl += ly[(size_t)i * n + k] * sv[i * p + j];
                }
                x[(size_t)j * n + k] = s;
                tmp[(size_t)j * n + k] = sn - sw[j] * sl;
            }
        for (j = 0; j < p; ++j) {
            /* L X for the next iteration */
            sky_matvec(n, first, ptr, b, x + (size_t)j * n, ly + (size_t)j * n);
            rv[j] = sqrt(dot(n, tmp + (size_t)j * n, tmp + (size_t)j * n)) /
                    (anorm * sqrt(dot(n, x + (size_t)j * n, x + (size_t)j * n)));
        }
        *iters = it;
        for (j = 0; j < (p < 2 ? p : 2); ++j)
            if (rv[j] > worst)
                worst = rv[j];
        if (worst <= tol)
            break;
    }
    for (j = 0; j < p; ++j) {
        vals[j] = sw[j];
        resid[j] = rv[j];
        memcpy(vecs + (size_t)j * n, x + (size_t)j * n, sizeof(double) * (size_t)n);
    }
    if (!all_finite(vecs, (size_t)p * n) || !all_finite(vals, (size_t)p))
        return MCG_ENUMERIC;
    return MCG_OK;
}
