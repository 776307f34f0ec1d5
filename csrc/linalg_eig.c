/*
 * linalg_eig.c -- the symmetric eigen-solvers of libmcgeom (the linalg.c
 * section of mcgeom.h): cyclic Jacobi (mcg_sym_eig; the 9 x 9 and 18 x 18
 * normal matrices of the linear 17-point method, Algorithm 2) and
 * Householder tridiagonalisation followed by implicit QR with Wilkinson
 * shifts (mcg_sym_eig_tridiag; Golub & Van Loan 8.3). Row-major, no
 * allocation, every loop bounded.
 */
#include "mcgeom.h"
#include "internal.h"
#include "linalg_internal.h"

#include <float.h>
#include <math.h>
#include <string.h>

/* The Householder reduction and the QR rotations of mcg_sym_eig_tridiag
 * (linear17's two 9 x 9 decompositions per call) carry MCG_AVX2_CLONE
 * (internal.h: the same bits on every CPU). */

/* Rotations of one Jacobi round whose parameters are computed together. */
#define EIG_CHUNK 16

/* Overwrite the upper triangle (diagonal included) of the n x n matrix a
 * with its symmetric part 0.5 (a + a^T) scaled by 2^-e so that max |a_ij| is
 * in [0.5, 1); returns e. A power of two scales exactly: multiplying by it is
 * exact whenever the factor is a normal number, ldexp is used otherwise. */
static int scaled_symmetric_part(size_t n, double *a)
{
    int e = scale_exponent(max_abs(a, n * n));
    double f = 0.5 * ldexp(1.0, -e);
    int exact = f >= DBL_MIN && f <= 1e300;
    size_t i, j;
    for (i = 0; i < n; ++i)
        for (j = i; j < n; ++j)
            a[i * n + j] = exact ? f * a[i * n + j] + f * a[j * n + i]
                                 : 0.5 * ldexp(a[i * n + j], -e) +
                                       0.5 * ldexp(a[j * n + i], -e);
    return e;
}

/* One round of the tournament ordering (see jacobi_sweeps): the np / 2
 * disjoint pairs (p, q) of round `round`, each rotation annihilating a_pq
 * of the upper triangle of a (nn x nn) and accumulated into the rows of v
 * (V^T). The rotation parameters of a pair depend only on a_pp, a_qq,
 * a_pq, which the other rotations of the same round do not touch, so they
 * are computed in chunks of EIG_CHUNK before being applied: the square
 * roots and divisions of a chunk overlap instead of forming one long
 * dependency chain. Results equal applying the rotations one by one. */
static void jacobi_round(size_t nn, size_t np, size_t round, double thresh, double *a,
                         double *v)
{
    size_t rp_[EIG_CHUNK], rq_[EIG_CHUNK];
    double rc_[EIG_CHUNK], rs_[EIG_CHUNK], rt_[EIG_CHUNK];
    size_t pi = 0, half = np / 2, p, q, r;
    while (pi < half) {
        size_t cnt = 0, jj;
        /* gather: parameters of up to EIG_CHUNK rotations */
        for (; pi < half && cnt < EIG_CHUNK; ++pi) {
            size_t x0 = (pi == 0) ? 0 : 1 + (pi - 1 + round) % (np - 1);
            size_t y0 = 1 + (np - 2 - pi + round) % (np - 1);
            double apq, g, app, aqq, d, h, den, t, c;
            if (x0 >= nn || y0 >= nn)
                continue;
            p = x0 < y0 ? x0 : y0;
            q = x0 < y0 ? y0 : x0;
            apq = a[p * nn + q];
            g = fabs(apq);
            if (g == 0.0)
                continue;
            app = a[p * nn + p];
            aqq = a[q * nn + q];
            /* Relative criterion (Demmel & Veselic): zeroing a_pq
             * moves the eigenvalues by at most eps sqrt|a_pp a_qq|,
             * which keeps the small eigenvalues of graded PSD
             * matrices (A^T A near a null space) accurate, and
             * guarantees termination. Squared to save a square
             * root; g^2 underflows only for g < 1e-154 max|a|. */
            if (g * g <= DBL_EPSILON * DBL_EPSILON * fabs(app * aqq)) {
                a[p * nn + q] = 0.0;
                continue;
            }
            if (g <= thresh)
                continue;
            /* t = tan of the smaller angle that annihilates a_pq
             * (Rutishauser), as 2 a_pq sgn(d) / (|d| + h) with
             * d = a_qq - a_pp, h = sqrt(d^2 + 4 a_pq^2); no overflow
             * since |a_ij| <= n after scaling */
            d = aqq - app;
            h = sqrt(d * d + 4.0 * apq * apq);
            den = d + copysign(h, d);
            t = (den != 0.0) ? 2.0 * apq / den : copysign(1.0, apq);
            c = 1.0 / sqrt(1.0 + t * t);
            rp_[cnt] = p;
            rq_[cnt] = q;
            rc_[cnt] = c;
            rs_[cnt] = t * c;
            rt_[cnt] = t * apq;
            ++cnt;
        }
        /* apply */
        for (jj = 0; jj < cnt; ++jj) {
            double c = rc_[jj], s = rs_[jj];
            p = rp_[jj];
            q = rq_[jj];
            a[p * nn + p] -= rt_[jj];
            a[q * nn + q] += rt_[jj];
            a[p * nn + q] = 0.0;
#define MCG_JROT(x, y)                                                        \
    do {                                                                      \
        double xx_ = (x), yy_ = (y);                                          \
        (x) = c * xx_ - s * yy_;                                              \
        (y) = s * xx_ + c * yy_;                                              \
    } while (0)
            for (r = 0; r < p; ++r)
                MCG_JROT(a[r * nn + p], a[r * nn + q]);
            for (r = p + 1; r < q; ++r)
                MCG_JROT(a[p * nn + r], a[r * nn + q]);
            for (r = q + 1; r < nn; ++r)
                MCG_JROT(a[p * nn + r], a[q * nn + r]);
            for (r = 0; r < nn; ++r)
                MCG_JROT(v[p * nn + r], v[q * nn + r]);
#undef MCG_JROT
        }
    }
}

/* Cyclic Jacobi on the upper triangle of a (nn x nn), rotations accumulated
 * into v (V^T, rows = eigenvectors, so that they touch contiguous memory),
 * in the round-robin ("tournament") ordering: each sweep is np - 1 rounds
 * of np / 2 disjoint pairs (np = n rounded up to even, pairs with the dummy
 * index n skipped); chunking the rounds removed the dependency chain that
 * dominated the run time of the row-cyclic order at n = 9 and 18. Returns
 * 1 once the off-diagonal part is exactly 0, 0 after MAX_SWEEPS. */
static int jacobi_sweeps(size_t nn, double *a, double *v)
{
    size_t np = nn + (nn & 1), p, q, round;
    int sweep;
    for (sweep = 0; sweep <= MAX_SWEEPS; ++sweep) {
        double thresh, off = 0.0;
        for (p = 0; p + 1 < nn; ++p)
            for (q = p + 1; q < nn; ++q)
                off += fabs(a[p * nn + q]);
        if (off == 0.0)
            return 1;
        if (sweep == MAX_SWEEPS)
            break;
        /* threshold Jacobi (Rutishauser): during the first sweeps skip the
         * rotations that would gain little; saves work on dense matrices
         * without changing the (quadratic) final convergence */
        thresh = (sweep < 3) ? 0.2 * off / (double)(nn * nn) : 0.0;
        for (round = 0; round + 1 < np; ++round)
            jacobi_round(nn, np, round, thresh, a, v);
    }
    return 0;
}

/* The argument checks of both eigen-solvers: 1 <= n <= max_n, no NULL, a
 * and v distinct, a finite. */
static int eig_args_ok(int n, size_t max_n, const double *a, const double *w, const double *v)
{
    return n >= 1 && (size_t)n <= max_n && a != NULL && w != NULL && v != NULL && a != v &&
           all_finite(a, (size_t)n * (size_t)n);
}

int mcg_sym_eig(int n, double *a, double *w, double *v)
{
    size_t nn, i, j;
    int e;
    double f2;

    if (!eig_args_ok(n, MAX_COLS, a, w, v))
        return MCG_EINVAL;
    nn = (size_t)n;

    /* Symmetric part, scaled so that max |a_ij| is in [0.5, 1): no overflow
     * in (a_qq - a_pp) below, exact (power of two) and undone at the end.
     * Only the upper triangle is used from here on: each rotation then
     * updates n - 2 pairs of entries instead of mirroring 2 (n - 2). */
    e = scaled_symmetric_part(nn, a);
    /* v holds V^T during the iteration; transposed at the end. */
    memset(v, 0, nn * nn * sizeof(double));
    for (i = 0; i < nn; ++i)
        v[i * nn + i] = 1.0;
    if (!jacobi_sweeps(nn, a, v))
        return MCG_ENUMERIC;

    for (i = 0; i < nn; ++i)
        w[i] = a[i * nn + i];
    sort_with_rows(nn, w, 0, v, NULL); /* (v's rows are the eigenvectors here) */
    f2 = pow2_or_zero(e);
    for (i = 0; i < nn; ++i) {
        w[i] = mul_pow2(w[i], e, f2);
        for (j = i + 1; j < nn; ++j) {
            double t = v[i * nn + j];
            v[i * nn + j] = v[j * nn + i];
            v[j * nn + i] = t;
        }
    }
    if (!all_finite(w, nn))
        return MCG_ENUMERIC;
    return MCG_OK;
}

/* ------------------------------------- symmetric eigen, tridiagonal QR */

/* Householder reduction of the symmetric n x n matrix a (upper triangle
 * holding the symmetric part, overwritten) to tridiagonal form
 * Q^T A Q = T: diagonal d[0..n-1], sub-diagonal e[0..n-2]; q (n x n,
 * row-major) accumulates Q. Each reflector H = I - v v^T 2 / (v^T v)
 * annihilates column k below the sub-diagonal and is applied to the
 * trailing block as A - v w^T - w v^T with w = p - (v^T p / v^T v) v,
 * p = 2 A v / (v^T v) (Golub & Van Loan, ch. 8.3.1). */
MCG_AVX2_CLONE
static void tridiagonalize(size_t n, double *a, double *d, double *e, double *q)
{
    double v[SPD_MAX], p[SPD_MAX];
    size_t i, j, k;
    for (i = 0; i < n; ++i) /* full symmetric storage from the upper triangle */
        for (j = 0; j < i; ++j)
            a[i * n + j] = a[j * n + i];
    memset(q, 0, n * n * sizeof(double));
    for (i = 0; i < n; ++i)
        q[i * n + i] = 1.0;
    for (k = 0; k + 2 < n; ++k) {
        size_t m = n - k - 1; /* length of the column part below the diagonal */
        double norm2 = 0.0, alpha, beta, vp = 0.0, kk;
        for (i = 0; i < m; ++i) {
            v[i] = a[(k + 1 + i) * n + k];
            norm2 += v[i] * v[i];
        }
        if (norm2 == 0.0) {
            e[k] = 0.0;
            continue;
        }
        /* alpha has the sign opposite to v0: no cancellation in v0 - alpha */
        alpha = -copysign(sqrt(norm2), v[0]);
        v[0] -= alpha;
        beta = 2.0 * (norm2 - alpha * (v[0] + alpha)); /* v^T v */
        e[k] = alpha;
        for (i = 0; i < m; ++i) { /* p = 2 A22 v / beta */
            double acc = 0.0;
            const double *row = a + (k + 1 + i) * n + (k + 1);
            for (j = 0; j < m; ++j)
                acc += row[j] * v[j];
            p[i] = 2.0 * acc / beta;
            vp += v[i] * p[i];
        }
        kk = vp / beta;
        for (i = 0; i < m; ++i) /* w = p - K v, stored in p */
            p[i] -= kk * v[i];
        for (i = 0; i < m; ++i) {
            double *row = a + (k + 1 + i) * n + (k + 1);
            for (j = 0; j < m; ++j)
                row[j] -= v[i] * p[j] + p[i] * v[j];
        }
        for (i = 0; i < n; ++i) { /* Q <- Q H on columns k+1.. */
            double *row = q + i * n + (k + 1), acc = 0.0;
            for (j = 0; j < m; ++j)
                acc += row[j] * v[j];
            acc *= 2.0 / beta;
            for (j = 0; j < m; ++j)
                row[j] -= acc * v[j];
        }
    }
    for (i = 0; i < n; ++i)
        d[i] = a[i * n + i];
    if (n >= 2)
        e[n - 2] = a[(n - 1) * n + (n - 2)];
}

/* Implicit symmetric QR with Wilkinson shift on the tridiagonal (d, e),
 * rotations accumulated into the rows of qt = Q^T (Golub & Van Loan,
 * Algorithm 8.3.3). Why the transpose: a rotation of columns k, k+1 of Q
 * touches two strided columns, one of Q^T two contiguous rows, which the
 * compiler vectorises; the products per entry are the same, so the result
 * is the same to the bit (issue 22: this loop was a third of the 9 x 9
 * decomposition). Returns 0 if the iteration budget ran out. */
MCG_AVX2_CLONE
static int tridiagonal_qr(size_t n, double *d, double *e, double *qt)
{
    size_t hi = n - 1, budget = 40 * n, i;
    while (hi > 0) {
        size_t lo, k;
        double delta, b, mu, x, z;
        /* deflate negligible couplings at the bottom */
        if (fabs(e[hi - 1]) <= DBL_EPSILON * (fabs(d[hi - 1]) + fabs(d[hi]))) {
            e[hi - 1] = 0.0;
            --hi;
            continue;
        }
        if (budget-- == 0)
            return 0;
        lo = hi - 1;
        while (lo > 0 && fabs(e[lo - 1]) > DBL_EPSILON * (fabs(d[lo - 1]) + fabs(d[lo])))
            --lo;
        if (lo > 0)
            e[lo - 1] = 0.0;
        /* Wilkinson shift: the eigenvalue of the trailing 2 x 2 nearer d[hi] */
        delta = 0.5 * (d[hi - 1] - d[hi]);
        b = e[hi - 1];
        mu = d[hi] - b * b / (delta + copysign(sqrt(delta * delta + b * b), delta));
        x = d[lo] - mu;
        z = e[lo];
        for (k = lo; k < hi; ++k) {
            /* rotation G = [c s; -s c] on (k, k+1) with s x + c z = 0 */
            /* sqrt of squares unless they could underflow (hypot is slow) */
            double r = sqrt(x * x + z * z), c, s, a0, b0, c0;
            if (r < 1e-150)
                r = hypot(x, z);
            if (r == 0.0) {
                c = 1.0;
                s = 0.0;
            } else {
                double inv = 1.0 / r;
                c = x * inv;
                s = -z * inv;
            }
            if (k > lo)
                e[k - 1] = c * x - s * z; /* the bulge is annihilated */
            a0 = d[k];
            b0 = e[k];
            c0 = d[k + 1];
            /* the 2 x 2 block of G^T T G */
            d[k] = c * c * a0 - 2.0 * c * s * b0 + s * s * c0;
            d[k + 1] = s * s * a0 + 2.0 * c * s * b0 + c * c * c0;
            e[k] = c * s * (a0 - c0) + (c * c - s * s) * b0;
            if (k + 1 < hi) {
                z = -s * e[k + 1]; /* new bulge at (k, k+2) */
                e[k + 1] *= c;
                x = e[k];
            }
            {
                double *rk = qt + k * n, *rl = rk + n;
                for (i = 0; i < n; ++i) {
                    double qk = rk[i], ql = rl[i];
                    rk[i] = c * qk - s * ql;
                    rl[i] = s * qk + c * ql;
                }
            }
        }
    }
    return 1;
}

int mcg_sym_eig_tridiag(int n, double *a, double *w, double *v)
{
    double e[SPD_MAX];
    size_t nn, i, j;
    int ex;
    if (!eig_args_ok(n, SPD_MAX, a, w, v))
        return MCG_EINVAL;
    nn = (size_t)n;
    /* no overflow or harmful underflow in the rotations */
    ex = scaled_symmetric_part(nn, a);
    tridiagonalize(nn, a, w, e, v);
    /* Q^T into a (free after the reduction) for the QR, then back into v */
    for (i = 0; i < nn; ++i)
        for (j = 0; j < nn; ++j)
            a[j * nn + i] = v[i * nn + j];
    if (!tridiagonal_qr(nn, w, e, a))
        return MCG_ENUMERIC;
    sort_with_rows(nn, w, 0, a, NULL); /* (a's rows are the eigenvectors) */
    for (i = 0; i < nn; ++i)
        for (j = 0; j < nn; ++j)
            v[j * nn + i] = a[i * nn + j];
    {
        double f2 = pow2_or_zero(ex);
        for (i = 0; i < nn; ++i)
            w[i] = mul_pow2(w[i], ex, f2);
    }
    if (!all_finite(w, nn) || !all_finite(v, nn * nn))
        return MCG_ENUMERIC;
    return MCG_OK;
}
