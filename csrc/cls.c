/*
 * cls.c -- constrained homogeneous least squares.
 *
 * Implements the "cls.c" section of mcgeom.h:
 *   - mcg_cls_general: min |A x| s.t. |C x| = 1, thesis Algorithm 3
 *     (Hartley & Zisserman, Multiple View Geometry, A5.4.2), with its last
 *     step taken as a generalized SVD of the pair (A'_1 projected, D1)
 *     rather than an SVD of A'_1 D1^{-1} (see step 5);
 *   - mcg_cls_partial: the special case C = [I_p | 0] of thesis Algorithm 4,
 *     i.e. min |A_1 x_1 + A_2 x_2| s.t. |x_1| = 1 with the free part
 *     x_2 = -A_2^+ A_1 x_1 and x_1 the solution of (A_2 A_2^+ - I) A_1 x_1 = 0
 *     in the least-squares sense (eq. 8.36; for the generalized epipolar
 *     system of eqs. 8.15-8.16, x = (vec E, vec R) and p = 9);
 *   - mcg_cls_range: min |A x| s.t. |x| = 1 and x in range(G), thesis
 *     ch. 6.3 (eqs. 6.18-6.19; Hartley & Zisserman A5.5).
 *
 * The projector A_2 A_2^+ is applied as U_r U_r^T from the SVD of A_2 (the
 * same thresholded decomposition that defines A_2^+) rather than as the
 * product of A_2 with an explicit pseudo-inverse: the product would amplify
 * rounding errors by cond(A_2), which may be up to 1 / rcond.
 *
 * Scratch space comes only from the caller's workspace; SVDs from linalg.c.
 */
#include "mcgeom.h"
#include "internal.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

#define PARTIAL_RCOND_DEFAULT 1e-10
#define RANGE_RCOND_DEFAULT 1e-12

/* svd work size for an m x n matrix, 0 columns allowed (no SVD needed) */
static size_t svd_ws0(size_t m, size_t n)
{
    if (n == 0)
        return 0;
    return mcg_svd_work_size((int)m, (int)n);
}

/* y (m) = a (m x n, row stride lda) x */
static void matvec(size_t m, size_t n, const double *a, size_t lda,
                   const double *x, double *y)
{
    size_t i, j;
    for (i = 0; i < m; ++i) {
        double acc = 0.0;
        for (j = 0; j < n; ++j)
            acc += a[i * lda + j] * x[j];
        y[i] = acc;
    }
}

/* Numerical rank: number of s[k] > tol (s descending). */
static size_t count_above(const double *s, size_t n, double tol)
{
    size_t r = 0;
    while (r < n && s[r] > tol)
        ++r;
    return r;
}

/* b (m x nb) <- U_r (U_r^T b) - b = -(I - A_2 A_2^+) b, where U_r are the
 * first r columns of u (m x ldu). t: r x nb scratch. The sign does not
 * matter for the homogeneous problem that follows. */
static void project_out(size_t m, size_t nb, double *b, const double *u,
                        size_t ldu, size_t r, double *t)
{
    size_t i, j, k;
    if (r == 0) {
        for (i = 0; i < m * nb; ++i)
            b[i] = -b[i];
        return;
    }
    memset(t, 0, r * nb * sizeof(double));
    for (i = 0; i < m; ++i)
        for (k = 0; k < r; ++k) {
            double uik = u[i * ldu + k];
            for (j = 0; j < nb; ++j)
                t[k * nb + j] += uik * b[i * nb + j];
        }
    for (i = 0; i < m; ++i)
        for (j = 0; j < nb; ++j) {
            double acc = -b[i * nb + j];
            for (k = 0; k < r; ++k)
                acc += u[i * ldu + k] * t[k * nb + j];
            b[i * nb + j] = acc;
        }
}

/* out (n2) = -A_2^+ y = -V_r S_r^{-1} U_r^T y (minimum-norm least-squares
 * solution of A_2 out = -y). tmp: r doubles. */
static void apply_neg_pinv(size_t m, size_t n2, const double *u, size_t ldu,
                           const double *s, const double *v, size_t r,
                           const double *y, double *out, double *tmp)
{
    size_t i, k;
    /* row-wise accumulation: r independent sums, contiguous rows of u */
    for (k = 0; k < r; ++k)
        tmp[k] = 0.0;
    for (i = 0; i < m; ++i)
        for (k = 0; k < r; ++k)
            tmp[k] += u[i * ldu + k] * y[i];
    for (k = 0; k < r; ++k)
        tmp[k] /= s[k];
    for (i = 0; i < n2; ++i) {
        double acc = 0.0;
        for (k = 0; k < r; ++k)
            acc += v[i * n2 + k] * tmp[k];
        out[i] = -acc;
    }
}

/* Unit vector minimising |b x| (b: m x nb): the right singular vector of
 * the smallest singular value (column nb - 1 of V, s descending; for m < nb
 * it spans part of the exact null space). */
static int smallest_right_sv(size_t m, size_t nb, const double *b,
                             double *s, double *v, double *x, double *sw,
                             size_t lsw)
{
    size_t i;
    int st = mcg_svd((int)m, (int)nb, b, NULL, s, v, sw, lsw);
    if (st != MCG_OK)
        return st;
    for (i = 0; i < nb; ++i)
        x[i] = v[i * nb + (nb - 1)];
    return MCG_OK;
}

/* ------------------------------------------------ Algorithm 3 (general) */

size_t mcg_cls_general_work_size(int m, int n, int k)
{
    int ok = 1;
    size_t mm, nn, kk, mn, ws, sw;
    if (m < 1 || n < 1 || k < 1 || (size_t)m > MAX_ROWS ||
        (size_t)n > MAX_COLS || (size_t)k > MAX_ROWS)
        return 0;
    mm = (size_t)m;
    nn = (size_t)n;
    kk = (size_t)k;
    mn = min_sz(mm, nn);
    /* The rank r of C is only known at run time: every block is sized for
     * the worst case over r (all sizes are monotone in the column count;
     * K has at most 2 r rows) */
    sw = max_sz(max_sz(svd_ws0(kk, nn), svd_ws0(mm, nn)),
                svd_ws0(2 * nn, nn));
    if (sw == 0)
        return 0;
    ws = mul_sz(nn, nn, &ok);                               /* V of C */
    ws = add_sz(ws, nn, &ok);                               /* D */
    ws = add_sz(ws, mul_sz(mm, nn, &ok), &ok);              /* A' */
    ws = add_sz(ws, mul_sz(mm, nn, &ok), &ok);              /* A'_2 */
    ws = add_sz(ws, mul_sz(mm, mn, &ok), &ok);              /* U_2 */
    ws = add_sz(ws, nn, &ok);                               /* s_2 */
    ws = add_sz(ws, mul_sz(nn, nn, &ok), &ok);              /* V_2 */
    ws = add_sz(ws, mul_sz(mm, nn, &ok), &ok);              /* M */
    ws = add_sz(ws, nn, &ok);                               /* s_M */
    ws = add_sz(ws, mul_sz(nn, nn, &ok), &ok);              /* V_M */
    ws = add_sz(ws, mul_sz(2 * nn, nn, &ok), &ok);          /* K */
    ws = add_sz(ws, mul_sz(2 * nn, nn, &ok), &ok);          /* U_K */
    ws = add_sz(ws, nn, &ok);                               /* s_K */
    ws = add_sz(ws, mul_sz(nn, nn, &ok), &ok);              /* V_K */
    ws = add_sz(ws, mul_sz(mn, nn, &ok), &ok);              /* U^T M */
    ws = add_sz(ws, mul_sz(nn, nn, &ok), &ok);              /* V of U_K1 */
    ws = add_sz(ws, nn, &ok);                               /* its s */
    ws = add_sz(ws, mm, &ok);                               /* A'_1 x'_1 */
    ws = add_sz(ws, mul_sz(3, nn, &ok), &ok);               /* x', y, tmp */
    ws = add_sz(ws, sw, &ok);
    return ok ? ws : 0;
}

int mcg_cls_general(int m, int n, int k, const double *a, const double *c,
                    double *x, double *resid, double *work, size_t lwork)
{
    size_t mm, nn, kk, mn, ws, sw_len, r, n2, mn2, r2, q, i, j, l;
    double *vc, *d, *ap, *a2, *u2, *s2, *v2, *mt, *sm, *vm, *km, *uk, *sk;
    double *vk, *t, *vy, *sy, *z, *xp, *y, *tmp, *sw, dnorm;
    int st;

    ws = mcg_cls_general_work_size(m, n, k);
    if (ws == 0)
        return MCG_EINVAL;
    if (a == NULL || c == NULL || x == NULL || work == NULL)
        return MCG_EINVAL;
    if (lwork < ws)
        return MCG_ENOMEM;
    mm = (size_t)m;
    nn = (size_t)n;
    kk = (size_t)k;
    mn = min_sz(mm, nn);
    if (!all_finite(a, mm * nn) || !all_finite(c, kk * nn))
        return MCG_EINVAL;

    vc = work;
    d = vc + nn * nn;
    ap = d + nn;
    a2 = ap + mm * nn;
    u2 = a2 + mm * nn;
    s2 = u2 + mm * mn;
    v2 = s2 + nn;
    mt = v2 + nn * nn;
    sm = mt + mm * nn;
    vm = sm + nn;
    km = vm + nn * nn;
    uk = km + 2 * nn * nn;
    sk = uk + 2 * nn * nn;
    vk = sk + nn;
    t = vk + nn * nn;
    vy = t + mn * nn;
    sy = vy + nn * nn;
    z = sy + nn;
    xp = z + mm;
    y = xp + nn;
    tmp = y + nn;
    sw = tmp + nn;
    sw_len = lwork - (size_t)(sw - work);

    /* 1. C = U D V^T (full n x n V even when k < n) */
    st = mcg_svd(k, n, c, NULL, d, vc, sw, sw_len);
    if (st != MCG_OK)
        return st;
    if (!(d[0] > 0.0))
        return MCG_EDEGENERATE; /* C = 0: |C x| = 1 is infeasible */
    /* 2. r = rank(D), same default tolerance as mcg_pinv */
    r = count_above(d, min_sz(kk, nn),
                    (double)max_sz(kk, nn) * DBL_EPSILON * d[0]);
    n2 = nn - r;
    mn2 = min_sz(mm, n2);

    /* A' = A V */
    for (i = 0; i < mm; ++i)
        for (j = 0; j < nn; ++j) {
            double acc = 0.0;
            for (l = 0; l < nn; ++l)
                acc += a[i * nn + l] * vc[l * nn + j];
            ap[i * nn + j] = acc;
        }
    /* M = A'_1 (m x r), A'_2 copied contiguous for their SVDs */
    for (i = 0; i < mm; ++i) {
        for (j = 0; j < r; ++j)
            mt[i * r + j] = ap[i * nn + j];
        for (j = 0; j < n2; ++j)
            a2[i * n2 + j] = ap[i * nn + r + j];
    }
    r2 = 0;
    if (n2 > 0) {
        st = mcg_svd(m, (int)n2, a2, u2, s2, v2, sw, sw_len);
        if (st != MCG_OK)
            return st;
        r2 = count_above(s2, mn2,
                         (double)max_sz(mm, n2) * DBL_EPSILON * s2[0]);
    }
    /* 4. M = (A'_2 A'_2^+ - I) A'_1 */
    project_out(mm, r, mt, u2, mn2, r2, t);
    /* 5. min |M x'_1| s.t. |D1 x'_1| = 1. Algorithm 3 substitutes
     * x'' = D1 x'_1 and takes the smallest singular vector of M D1^{-1};
     * a small d_j (a nearly singular C) makes that column huge, and an SVD
     * accurate to eps s_max then misses the minimum (fuzz_cls: 45 % off
     * with d_j = 4e-15, a direction the minimiser does not even use). The
     * pair (M, D1) is taken instead through the SVD of the stacked
     * K = [S_M V_M^T / s_M0; D1 / d_0] = U_K S_K V_K^T, which has no small
     * divisor (the generalized SVD route, Van Loan 1976; Golub & Van Loan
     * 8.7.4); S_M V_M^T (q = min(m, r) rows) has the norms |M x| of M.
     * With w = S_K V_K^T x'_1, M's part is U_K1 w and D1's U_K2 w, and
     * |U_K1 w|^2 + |U_K2 w|^2 = |w|^2, so the ratio is least for w the
     * smallest right singular vector of U_K1 (the first q rows of U_K). */
    st = mcg_svd(m, (int)r, mt, NULL, sm, vm, sw, sw_len);
    if (st != MCG_OK)
        return st;
    q = min_sz(mm, r);
    for (i = 0; i < q; ++i) {
        const double si = sm[0] > 0.0 ? sm[i] / sm[0] : 0.0; /* M = 0: any x */
        for (j = 0; j < r; ++j)
            km[i * r + j] = vm[j * r + i] * si;
    }
    memset(km + q * r, 0, r * r * sizeof(double));
    for (j = 0; j < r; ++j)
        km[(q + j) * r + j] = d[j] / d[0];
    st = mcg_svd((int)(q + r), (int)r, km, uk, sk, vk, sw, sw_len);
    if (st != MCG_OK)
        return st;
    /* S_K is singular only if M and D1 nearly share a null direction (the
     * ratio there is 0 / 0 at the working precision) */
    if (!(sk[r - 1] > 0.0))
        return MCG_EDEGENERATE;
    st = smallest_right_sv(q, r, uk, sy, vy, y, sw, sw_len);
    if (st != MCG_OK)
        return st;
    /* 6. x'_1 = V_K S_K^{-1} w scaled to |D1 x'_1| = 1,
     * x'_2 = -A'_2^+ A'_1 x'_1 */
    for (j = 0; j < r; ++j)
        tmp[j] = y[j] / sk[j];
    matvec(r, r, vk, r, tmp, xp);
    for (j = 0; j < r; ++j)
        tmp[j] = d[j] * xp[j];
    dnorm = norm_scaled(tmp, r);
    if (!(dnorm > 0.0) || !isfinite(dnorm))
        return MCG_ENUMERIC;
    for (j = 0; j < r; ++j)
        xp[j] /= dnorm;
    if (n2 > 0) {
        matvec(mm, r, ap, nn, xp, z);
        apply_neg_pinv(mm, n2, u2, mn2, s2, v2, r2, z, xp + r, tmp);
    }
    /* 8. x = V x' */
    matvec(nn, nn, vc, nn, xp, x);
    if (!all_finite(x, nn))
        return MCG_ENUMERIC;
    if (resid != NULL) {
        matvec(mm, nn, a, nn, x, z);
        *resid = norm_scaled(z, mm);
    }
    return MCG_OK;
}

/* ----------------------------------------- Algorithm 4 (C = [I_p | 0]) */

size_t mcg_cls_partial_work_size(int m, int n, int p)
{
    int ok = 1;
    size_t mm, nn, pp, n2, mn2, ws, sw;
    if (m < 1 || n < 1 || p < 1 || p > n || (size_t)m > MAX_ROWS ||
        (size_t)n > MAX_COLS)
        return 0;
    mm = (size_t)m;
    nn = (size_t)n;
    pp = (size_t)p;
    n2 = nn - pp;
    mn2 = min_sz(mm, n2);
    sw = max_sz(svd_ws0(mm, n2), svd_ws0(mm, pp));
    if (sw == 0)
        return 0;
    ws = mul_sz(mm, n2, &ok);                               /* A_2 */
    ws = add_sz(ws, mul_sz(mm, mn2, &ok), &ok);             /* U_2 */
    ws = add_sz(ws, n2, &ok);                               /* s_2 */
    ws = add_sz(ws, mul_sz(n2, n2, &ok), &ok);              /* V_2 */
    ws = add_sz(ws, mul_sz(mm, pp, &ok), &ok);              /* A'' */
    ws = add_sz(ws, mul_sz(mn2, pp, &ok), &ok);             /* U^T A'' */
    ws = add_sz(ws, mul_sz(pp, pp, &ok), &ok);              /* V'' */
    ws = add_sz(ws, pp, &ok);                               /* s'' */
    ws = add_sz(ws, mm, &ok);                               /* A_1 x_1 */
    ws = add_sz(ws, nn, &ok);                               /* tmp */
    ws = add_sz(ws, sw, &ok);
    return ok ? ws : 0;
}

int mcg_cls_partial(int m, int n, int p, const double *a, double rcond,
                    double *x, double *resid, int *rank2,
                    double *work, size_t lwork)
{
    size_t mm, nn, pp, n2, mn2, ws, sw_len, r2, i, j;
    double *a2, *u2, *s2, *v2, *app, *t, *vpp, *spp, *z, *tmp, *sw;
    int st;

    ws = mcg_cls_partial_work_size(m, n, p);
    if (ws == 0)
        return MCG_EINVAL;
    if (a == NULL || x == NULL || work == NULL || !isfinite(rcond))
        return MCG_EINVAL;
    if (lwork < ws)
        return MCG_ENOMEM;
    mm = (size_t)m;
    nn = (size_t)n;
    pp = (size_t)p;
    if (!all_finite(a, mm * nn))
        return MCG_EINVAL;
    if (rcond <= 0.0)
        rcond = PARTIAL_RCOND_DEFAULT;
    n2 = nn - pp;
    mn2 = min_sz(mm, n2);

    a2 = work;
    u2 = a2 + mm * n2;
    s2 = u2 + mm * mn2;
    v2 = s2 + n2;
    app = v2 + n2 * n2;
    t = app + mm * pp;
    vpp = t + mn2 * pp;
    spp = vpp + pp * pp;
    z = spp + pp;
    tmp = z + mm;
    sw = tmp + nn;
    sw_len = lwork - (size_t)(sw - work);

    /* split A = [A_1 | A_2]; with C = [I | 0] the SVD of C is trivial
     * (U = V = I, D1 = I), so A' = A and A'' starts as A_1 */
    for (i = 0; i < mm; ++i) {
        for (j = 0; j < pp; ++j)
            app[i * pp + j] = a[i * nn + j];
        for (j = 0; j < n2; ++j)
            a2[i * n2 + j] = a[i * nn + pp + j];
    }
    r2 = 0;
    if (n2 > 0) {
        st = mcg_svd(m, (int)n2, a2, u2, s2, v2, sw, sw_len);
        if (st != MCG_OK)
            return st;
        r2 = count_above(s2, mn2, rcond * s2[0]);
    }
    /* eq. 8.36: (A_2 A_2^+ - I) A_1 x_1 = 0 in the least-squares sense */
    project_out(mm, pp, app, u2, mn2, r2, t);
    st = smallest_right_sv(mm, pp, app, spp, vpp, x, sw, sw_len);
    if (st != MCG_OK)
        return st;
    if (n2 > 0) {
        matvec(mm, pp, a, nn, x, z);
        apply_neg_pinv(mm, n2, u2, mn2, s2, v2, r2, z, x + pp, tmp);
    }
    if (!all_finite(x, nn))
        return MCG_ENUMERIC;
    if (rank2 != NULL)
        *rank2 = (int)r2;
    if (resid != NULL) {
        matvec(mm, nn, a, nn, x, z);
        *resid = norm_scaled(z, mm);
    }
    return MCG_OK;
}

/* ------------------------------------ range constraint (thesis ch. 6.3) */

size_t mcg_cls_range_work_size(int m, int n, int r)
{
    int ok = 1;
    size_t mm, nn, rr, q, ws, sw;
    if (m < 1 || n < 1 || r < 1 || (size_t)m > MAX_ROWS ||
        (size_t)n > MAX_COLS || (size_t)r > MAX_COLS)
        return 0;
    mm = (size_t)m;
    nn = (size_t)n;
    rr = (size_t)r;
    q = min_sz(nn, rr); /* at most rank(G) columns survive */
    sw = max_sz(svd_ws0(nn, rr), svd_ws0(mm, q));
    if (sw == 0)
        return 0;
    ws = mul_sz(nn, q, &ok);                                /* U of G */
    ws = add_sz(ws, rr, &ok);                               /* s of G */
    ws = add_sz(ws, mul_sz(rr, rr, &ok), &ok);              /* V of G */
    ws = add_sz(ws, mul_sz(mm, q, &ok), &ok);               /* A U' */
    ws = add_sz(ws, q, &ok);                                /* its s */
    ws = add_sz(ws, mul_sz(q, q, &ok), &ok);                /* its V */
    ws = add_sz(ws, q, &ok);                                /* y */
    ws = add_sz(ws, mm, &ok);                               /* A x */
    ws = add_sz(ws, sw, &ok);
    return ok ? ws : 0;
}

int mcg_cls_range(int m, int n, int r, const double *a, const double *g,
                  double rcond, double *x, double *resid,
                  double *work, size_t lwork)
{
    size_t mm, nn, rr, qmax, q, ws, sw_len, i, j, l;
    double *ug, *sg, *vg, *b, *sb, *vb, *y, *z, *sw;
    int st;

    ws = mcg_cls_range_work_size(m, n, r);
    if (ws == 0)
        return MCG_EINVAL;
    if (a == NULL || g == NULL || x == NULL || work == NULL ||
        !isfinite(rcond))
        return MCG_EINVAL;
    if (lwork < ws)
        return MCG_ENOMEM;
    mm = (size_t)m;
    nn = (size_t)n;
    rr = (size_t)r;
    if (!all_finite(a, mm * nn) || !all_finite(g, nn * rr))
        return MCG_EINVAL;
    if (rcond <= 0.0)
        rcond = RANGE_RCOND_DEFAULT;
    qmax = min_sz(nn, rr);

    ug = work;
    sg = ug + nn * qmax;
    vg = sg + rr;
    b = vg + rr * rr;
    sb = b + mm * qmax;
    vb = sb + qmax;
    y = vb + qmax * qmax;
    z = y + qmax;
    sw = z + mm;
    sw_len = lwork - (size_t)(sw - work);

    /* orthonormal basis U' of range(G): x = U' y, |x| = |y| */
    st = mcg_svd(n, r, g, ug, sg, vg, sw, sw_len);
    if (st != MCG_OK)
        return st;
    if (!(sg[0] > 0.0))
        return MCG_EDEGENERATE; /* G = 0: no unit vector in its range */
    q = count_above(sg, qmax, rcond * sg[0]);
    /* min |A U' y| s.t. |y| = 1 */
    for (i = 0; i < mm; ++i)
        for (j = 0; j < q; ++j) {
            double acc = 0.0;
            for (l = 0; l < nn; ++l)
                acc += a[i * nn + l] * ug[l * qmax + j];
            b[i * q + j] = acc;
        }
    st = smallest_right_sv(mm, q, b, sb, vb, y, sw, sw_len);
    if (st != MCG_OK)
        return st;
    matvec(nn, q, ug, qmax, y, x);
    if (!all_finite(x, nn))
        return MCG_ENUMERIC;
    if (resid != NULL) {
        matvec(mm, nn, a, nn, x, z);
        *resid = norm_scaled(z, mm);
    }
    return MCG_OK;
}
