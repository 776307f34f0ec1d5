/*
 * refine_eval.c -- the residual and one evaluation of the refinement
 * (csrc/refine.c): the Sampson angular error of the generalized epipolar
 * constraint for every pair (mcg_gec_residuals, thesis eq. 8.15), and for a
 * motion the robust cost, its gradient and Gauss-Newton information summed
 * over blocks of pairs (residuals and Jacobian rows in closed form, the
 * losses of mcg_refine_options with a fast exact logarithm for Cauchy).
 */
#include "refine_internal.h"
#include "sampson.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

/* The pass itself, cloned for AVX2 (MCG_AVX2_CLONE). It is static behind a
 * plain mcg_gec_residuals: a cloned public function would export its ifunc
 * resolver too (mcg_gec_residuals.resolver), and libmcgeom.so exports the
 * functions of mcgeom.h and nothing else (.ci/c_checks). */
MCG_AVX2_CLONE
static int gec_residuals(int n, const double *o1, const double *d1, const double *o2,
                         const double *d2, const double R[9], const double t[3],
                         double *res)
{
    int k, bad = 0;

    /* One branch-free pass: one square root and one division per pair. */
    for (k = 0; k < n; k++) {
        sampson_terms s;
        sampson_pair(R, t, o1 + 3 * k, d1 + 3 * k, o2 + 3 * k, d2 + 3 * k, &s);
        res[k] = s.e / sqrt(s.m) + s.marker;
    }
    for (k = 0; k < n; k++) /* the markers (a short contiguous scan) */
        bad |= res[k] != res[k];
    if (bad)
        return MCG_EINVAL;
    return MCG_OK;
}

int mcg_gec_residuals(int n, const double *o1, const double *d1,
                      const double *o2, const double *d2, const double R[9],
                      const double t[3], double *res)
{
    if (!o1 || !d1 || !o2 || !d2 || !R || !t || !res)
        return MCG_EINVAL;
    if (n < 0 || n > MAX_RAYS)
        return MCG_EINVAL;
    if (!all_finite(R, 9) || !all_finite(t, 3))
        return MCG_EINVAL;
    return gec_residuals(n, o1, d1, o2, d2, R, t, res);
}

/* Pairs per block of an evaluation: residuals and Jacobian rows of a block
 * go to small stack arrays (structure of arrays) so that the per-pair loop
 * is branch-free and vectorises; the normal equations are then summed from
 * them. 32 pairs = 2.3 KB of stack, no caller workspace. */
#define BLK 32

/* independent partial sums of the normal equations (SIMD lanes) */
#define LANES 4

/* Residuals and Jacobian rows [dr/dw, dr/dt] of nb <= BLK pairs, in the raw
 * form of mcg_gec_residuals (A = R d1, B = d2 unnormalised, p = R o1,
 * c = t + p - o2, Q = c x A, H = B x c, E = B.Q,
 * den = |B|^2 |Q|^2 + |A|^2 |H|^2 - 2 E^2, r = E den^-1/2 = E s; r is
 * homogeneous of degree 0 in A and B, and |A|, |B| do not change with
 * (R, t)). With K = A x B and V = 2 |A|^2 |B|^2 c - |B|^2 (A.c) A
 * - |A|^2 (B.c) B:
 *     dE/dt = K,                dE/dw = p x K + A x H,
 *     dden/dt = 2 V - 4 E K,    dden/dw = 2 p x V + 2 |B|^2 (A.c) Q - 4 E dE/dw,
 *     dr/dt = s (1 + 2 r^2) K - r s^2 V,
 *     dr/dw = p x dr/dt + s (1 + 2 r^2) A x H - r s^2 |B|^2 (A.c) Q.
 * On the cap (or e = den = 0) the row is 0 and ok[k] = 0 (else 1). An invalid pair
 * (zero direction, NaN/inf, overflow) gets r = NaN. */
MCG_AVX2_CLONE
static void block_rows(int nb, const double *restrict o1, const double *restrict d1,
                       const double *restrict o2, const double *restrict d2,
                       const double *restrict rm, const double *restrict tv,
                       double *restrict rb, double (*restrict jb)[BLK], double *restrict ok)
{
    int k;
    for (k = 0; k < nb; k++) {
        sampson_terms p;
        sampson_row w;
        int i;
        sampson_pair(rm, tv, o1 + 3 * k, d1 + 3 * k, o2 + 3 * k, d2 + 3 * k, &p);
        sampson_jacobian(&p, &w);
        rb[k] = w.r + p.marker;
        ok[k] = w.on;
        for (i = 0; i < 6; i++)
            jb[i][k] = w.j[i];
    }
}

/* rho(z) and rho'(z) of the squared residual z */
static void loss_eval(const lossfn *l, double z, double *rho, double *drho)
{
    switch (l->loss) {
    case MCG_LOSS_HUBER:
        if (z <= l->s2) {
            *rho = z;
            *drho = 1.0;
        } else {
            double sq = sqrt(z);
            *rho = 2.0 * l->s * sq - l->s2;
            *drho = l->s / sq;
        }
        break;
    case MCG_LOSS_CAUCHY: {
        double u = z * l->inv_s2;
        *rho = l->s2 * log1p(u);
        *drho = 1.0 / (1.0 + u);
        break;
    }
    case MCG_LOSS_SOFT_L1: {
        double sq = sqrt(1.0 + z * l->inv_s2);
        *rho = 2.0 * l->s2 * (sq - 1.0);
        *drho = 1.0 / sq;
        break;
    }
    default:
        *rho = z;
        *drho = 1.0;
        break;
    }
}

/* Below this u = r^2 / s^2 a term's log1p(u) is its series to u^4 (error
 * < u^5 / 5 < 1e-17 u), above it a factor of the block's product. */
#define CAUCHY_SERIES 5e-4

/* log1p(u) for 0 <= u < CAUCHY_SERIES by its series to u^4. The callers
 * pass small * u (0 above the cut): the series of a large u overflows
 * (u^4 > DBL_MAX from u ~ 1e77, and 0 * inf is NaN). */
static inline double cauchy_series(double u)
{
    return u * (1.0 - u * (0.5 - u * (1.0 / 3.0 - 0.25 * u)));
}

/* 1 + u above this is left to log1p per pair (log_ge1 needs a finite normal
 * argument; a residual this large is an outlier whose cost is anyway flat) */
#define LOG_GE1_MAX 1e300

/* The bits of a double and back. For doubles >= 0 (and +inf, NaN above all)
 * the order of the bits as unsigned integers is that of the values: the
 * comparisons of log_ge1 and cauchy_block are made on the bits, as integer
 * selects (a floating-point compare-and-select kept GCC from vectorising
 * the loop under its default -ftrapping-math). */
static inline uint64_t bits_of(double x)
{
    uint64_t b;
    memcpy(&b, &x, sizeof b);
    return b;
}

static inline double of_bits(uint64_t b)
{
    double x;
    memcpy(&x, &b, sizeof x);
    return x;
}

/* 1.0 where the integer condition c holds, else 0.0, without a branch */
static inline double one_if(int c)
{
    return of_bits(-(uint64_t)(c != 0) & bits_of(1.0));
}

/* log(x) for finite x >= 1 in a form the vectoriser takes (log1p is a call
 * per pair): x = m 2^e with m in [sqrt(1/2), sqrt(2)), log m = 2 atanh(s),
 * s = (m - 1) / (m + 1), |s| <= 0.1716, by its series to s^21 (the next
 * term is below 3e-17 of the sum), plus e log 2. The exponent goes to a
 * double by the 2^52 bias trick (integer ops only: AVX2 has no int64 ->
 * double conversion). Relative error a few 1e-16 (tested against log by
 * csrc/tests/test_refine.c through the Cauchy cost), far below the 2.2e-13
 * of a term that the cost's other shortcut already accepts (cauchy_block). */
static inline double log_ge1(double x)
{
    const uint64_t b = bits_of(x);
    double m = of_bits((b & 0x000FFFFFFFFFFFFFull) | bits_of(1.0)); /* [1, 2) */
    double e = of_bits((b >> 52) | bits_of(4503599627370496.0));   /* 2^52 + biased e */
    const double big = one_if(bits_of(m) > bits_of(1.4142135623730951)); /* m > sqrt 2 */
    double z, s, p;
    m *= 1.0 - 0.5 * big;
    e = e - (4503599627370496.0 + 1023.0) + big;
    s = (m - 1.0) / (m + 1.0);
    z = s * s;
    p = 1.0 / 21.0;
    p = p * z + 1.0 / 19.0;
    p = p * z + 1.0 / 17.0;
    p = p * z + 1.0 / 15.0;
    p = p * z + 1.0 / 13.0;
    p = p * z + 1.0 / 11.0;
    p = p * z + 1.0 / 9.0;
    p = p * z + 1.0 / 7.0;
    p = p * z + 1.0 / 5.0;
    p = p * z + 1.0 / 3.0;
    p = p * z + 1.0;
    return e * 0.69314718055994530942 + 2.0 * s * p;
}

/* The Cauchy loss of nb <= BLK residuals rb (weights wts, NULL = 1): the
 * IRLS weights ob = w / (1 + u), u = r^2 / s^2 (thesis ch. 8.5's robust
 * refinement; rho(z) = s^2 log(1 + z / s^2)), the sums of the accumulator,
 * and the block's cost sum w s^2 log1p(u). The cost is computed without a
 * log1p per pair (issue 19: log1p was 1/5 of the refinements' time at 1e3
 * pairs, and its call kept the loop from vectorising):
 * sum log1p(u) = log(prod (1 + u)) over the terms with u >= CAUCHY_SERIES
 * (one log per block; the relative rounding of each factor, 1e-16 / u
 * <= 2.2e-13 of its term, is far below the cost differences LM decides
 * on), plus the series u - u^2/2 + u^3/3 - u^4/4 of the smaller ones
 * (where 1 + u would lose u's digits); a block of equal weights (all 1
 * when none are given, the common case) is that times its weight;
 * unequal weights take the series or log_ge1 per pair. A residual beyond
 * LOG_GE1_MAX, an overflowing product or a NaN take log1p per pair. */
MCG_AVX2_CLONE
static double cauchy_block(int nb, const double *restrict rb, const double *restrict wts,
                           const double *restrict okb, const lossfn *restrict l,
                           double *restrict ob, double *sw, double *swr2, double *som,
                           double *somr2, int *used_n)
{
    double prod = 1.0, series = 0.0, a = 0.0, b = 0.0, c = 0.0, d = 0.0;
    const double w0 = wts ? wts[0] : 1.0;
    int k, used = 0, same = 1;
    for (k = 0; k < nb; k++) {
        double w = wts ? wts[k] : 1.0, z = rb[k] * rb[k], u = z * l->inv_s2;
        same &= w == w0;
        double om = w / (1.0 + u), small = u < CAUCHY_SERIES ? 1.0 : 0.0;
        ob[k] = om;
        a += w;
        b += w * z;
        c += om;
        d += om * z;
        used += okb[k] != 0.0 && w > 0.0;
        series += cauchy_series(small * u);
        prod *= small != 0.0 ? 1.0 : 1.0 + u;
    }
    *sw += a;
    *swr2 += b;
    *som += c;
    *somr2 += d;
    *used_n += used;
    if (same && prod < DBL_MAX && series == series) /* (prod >= 1 or NaN) */
        return w0 * l->s2 * (series + log(prod));
    if (wts) {
        /* unequal weights (the pixel scaling of the final refinement: every
         * pair its own): the same split per pair, log(1 + u) by log_ge1
         * (log1p per pair was ~9 % of a façade call's instructions) */
        double term[BLK], acc = 0.0;
        int fine = 1;
        /* the terms elementwise (this loop vectorises; a sum in it would not,
         * as floating-point addition is not associative), then their sum */
        for (k = 0; k < nb; k++) {
            /* (u >= 0 or NaN: the comparisons on the bits, see bits_of) */
            const double u = rb[k] * rb[k] * l->inv_s2;
            const double small = one_if(bits_of(u) < bits_of(CAUCHY_SERIES));
            const double x = 1.0 + (1.0 - small) * u; /* log_ge1(1) = 0 exactly */
            fine &= bits_of(u) < bits_of(LOG_GE1_MAX); /* (NaN, inf: 0) */
            term[k] = wts[k] * (cauchy_series(small * u) + log_ge1(x));
        }
        for (k = 0; k < nb; k++)
            acc += term[k];
        if (fine)
            return l->s2 * acc;
    }
    series = 0.0;
    for (k = 0; k < nb; k++)
        series += (wts ? wts[k] : 1.0) * log1p(rb[k] * rb[k] * l->inv_s2);
    return l->s2 * series;
}

/* One pass over the rays at (R, t): robust cost and normal equations. */
MCG_AVX2_CLONE
static void evaluate(int n, const double *o1, const double *d1, const double *o2,
                     const double *d2, const double *wts, const lossfn *l,
                     const double r[9], const double t[3], accum *acc)
{
    /* hs[p][lane]: LANES independent partial sums of the upper triangle of
     * [J r]^T W [J r] without its corner, row by row: the 21 entries of
     * J^T W J and, last in each row, the 6 of J^T W r */
    double hs[27][LANES], cost = 0.0, sw = 0.0, swr2 = 0.0, som = 0.0, somr2 = 0.0;
    double rb[BLK], jb[6][BLK], ob[BLK], okb[BLK], oj[6][BLK];
    int k0, k, i, m, p, used_n = 0;
    memset(hs, 0, sizeof hs);
    for (k0 = 0; k0 < n; k0 += BLK) {
        int nb = n - k0 < BLK ? n - k0 : BLK;
        block_rows(nb, o1 + 3 * k0, d1 + 3 * k0, o2 + 3 * k0, d2 + 3 * k0, r, t,
                   rb, jb, okb);
        /* weights: ob = omega = w rho'(r^2) */
        if (l->loss == MCG_LOSS_CAUCHY)
            cost += cauchy_block(nb, rb, wts ? wts + k0 : NULL, okb, l, ob, &sw, &swr2, &som,
                                 &somr2, &used_n);
        else
            for (k = 0; k < nb; k++) {
                double w = wts ? wts[k0 + k] : 1.0, z = rb[k] * rb[k], rho, drho;
                if (l->loss == MCG_LOSS_NONE) {
                    rho = z;
                    drho = 1.0;
                } else {
                    loss_eval(l, z, &rho, &drho);
                }
                ob[k] = w * drho;
                cost += w * rho;
                sw += w;
                swr2 += w * z;
                som += ob[k];
                somr2 += ob[k] * z;
                used_n += okb[k] != 0.0 && w > 0.0;
            }
        /* zero-pad the block to a multiple of LANES (BLK is one) */
        for (k = nb; k < BLK && k % LANES != 0; k++) {
            ob[k] = 0.0;
            rb[k] = 0.0;
            for (i = 0; i < 6; i++)
                jb[i][k] = 0.0;
        }
        /* normal equations: for each entry, LANES partial sums over the
         * block (vectorisable; the sums stay in registers) */
        nb = (nb + LANES - 1) / LANES * LANES;
        for (i = 0; i < 6; i++)
            for (k = 0; k < nb; k++)
                oj[i][k] = ob[k] * jb[i][k];
        p = 0;
        for (i = 0; i < 6; i++)
            for (m = i; m < 7; m++, p++) {
                const double *x = oj[i], *y = m < 6 ? jb[m] : rb;
                double sl[LANES];
                int ln;
                for (ln = 0; ln < LANES; ln++)
                    sl[ln] = 0.0;
                for (k = 0; k < nb; k += LANES)
                    for (ln = 0; ln < LANES; ln++)
                        sl[ln] += x[k + ln] * y[k + ln];
                for (ln = 0; ln < LANES; ln++)
                    hs[p][ln] += sl[ln];
            }
    }
    memset(acc, 0, sizeof *acc);
    p = 0;
    for (i = 0; i < 6; i++)
        for (m = i; m < 7; m++, p++) {
            double v = 0.0;
            int ln;
            for (ln = 0; ln < LANES; ln++)
                v += hs[p][ln];
            if (m < 6)
                acc->h[6 * i + m] = acc->h[6 * m + i] = v;
            else
                acc->g[i] = v;
        }
    acc->cost = cost;
    acc->sw = sw;
    acc->swr2 = swr2;
    acc->som = som;
    acc->somr2 = somr2;
    acc->n_used = used_n;
    /* a NaN marker (or an overflow) reaches the sums */
    acc->bad = !isfinite(cost) || !isfinite(swr2);
}

/* the plain entry of the static clone above (internal.h, MCG_AVX2_CLONE) */
void refine_evaluate(int n, const double *o1, const double *d1, const double *o2,
                     const double *d2, const double *wts, const lossfn *l,
                     const double r[9], const double t[3], accum *acc)
{
    evaluate(n, o1, d1, o2, d2, wts, l, r, t, acc);
}
