/*
 * scale_line.c -- the metric scale of the 5+1 method by 1-point RANSAC
 * (thesis ch. 7.4, eq. 7.4), the hot loop of mcgeom.estimators.five_plus_one.
 *
 * The 5-point camera fixes R and the line of translations t(lam) = t0 + lam w.
 * For a correspondence (o1, d1) <-> (o2, d2) with unit bearings, a = R d1 and
 * s(lam) = t0 + lam w + R o1 - o2, the pair's essential matrix is [s]x R, so
 *
 *     e(lam)  = d2 . (s x a)                     = a_k + lam b_k,
 *     D(lam)  = |P(d2) (s x a)|^2 + |P(a) (d2 x s)|^2
 *             = A_k + 2 B_k lam + C_k lam^2      (P(v) = I - v v^T),
 *
 * both being affine in lam inside the norms, and the Sampson angular residual
 * is r_k(lam) = e / sqrt(D) (with the floors of mcg_gec_residuals: at most
 * pi/2 in size, 0 where e = D = 0). With g0, g1 the 6-vectors of the
 * tangent parts [P(d2) (s x a); P(a) (d2 x s)] at lam = 0 and per unit lam,
 * D = |g0 + lam g1|^2, and for lam >= 0 (every scale searched is positive)
 *
 *     D(lam)  = (|g0| - lam |g1|)^2 + 2 lam q,
 *     q       = |g0| |g1| + g0 . g1 = |g0| |g1| |g0 / |g0| + g1 / |g1||^2 / 2,
 *
 * a sum of two terms >= 0: where D is near 0 (e.g. where the pair's camera
 * centre stops moving) only q loses digits, in the sum of the unit vectors,
 * as the direct sum |g0 + lam g1|^2 loses them in g0 + lam g1, whereas the
 * expanded quadratic A + 2 B lam + C lam^2 cancels as a whole there. Three
 * numbers per pair instead of g0 and g1's twelve (issue 19: the scoring's
 * loads and arithmetic were most of the scale search, ~15 % of the C time
 * of a robust estimate on the Ladybug case).
 * Each correspondence proposes lam = -a_k / b_k (eq. 7.4); proposals are
 * scored by MSAC over all correspondences in batches of 16 with the adaptive
 * stop of a 1-point sample, and the best is re-estimated by weighted least
 * squares of eq. 7.4 on its inliers while that lowers the score.
 */
#include "mcgeom.h"
#include "internal.h"

#include <float.h>
#include <math.h>
#include <stddef.h>

#define MAX_PAIRS (1 << 26)
#define MAX_PROPOSALS (1 << 20)
#define BATCH 16        /* proposals scored between two stopping tests */
#define LS_ROUNDS 2     /* weighted least-squares re-estimations */
#define DIR2_MIN 1e-100 /* smallest squared length of a direction */
#define DEN_MIN 1e-300  /* floor of D(lam) in the least-squares weights */
#define INV_HALF_PI2 0.40528473456935109 /* (2 / pi)^2 */
/* terms per pair, each an array of n: a, b, |g0|, |g1| and q (see above) */
#define NT 5

size_t mcg_scale_ransac_work_size(int n)
{
    if (n < 1 || n > MAX_PAIRS)
        return 0;
    return NT * (size_t)n;
}

/* D(lam) of pair k, lam >= 0 (terms in structure-of-arrays order) */
static double den_at(const double *t, size_t n, size_t k, double lam)
{
    double u = t[2 * n + k] - lam * t[3 * n + k];
    return u * u + 2.0 * lam * t[4 * n + k];
}

/* squared residual of pair k at lam (terms in structure-of-arrays order):
 * e^2 / max(D, (2/pi)^2 e^2, DBL_MIN), the floors of mcg_gec_residuals (its
 * pi/2 cap where D -> 0 with e != 0; 0 where e = D = 0) */
static double r2_at(const double *t, size_t n, size_t k, double lam)
{
    double e = t[k] + lam * t[n + k], ee = e * e, cap = ee * INV_HALF_PI2;
    double d = den_at(t, n, k, lam);
    d = d > cap ? d : cap;
    return ee / (d > DBL_MIN ? d : DBL_MIN);
}

/* MSAC score sum_k min(r_k^2, thr2) at lam, and the number of inliers */
MCG_AVX2_CLONE
static double msac(const double *t, size_t n, double lam, double thr2, int *inliers)
{
    double s = 0.0;
    size_t k;
    int m = 0;
    for (k = 0; k < n; k++) {
        double r2 = r2_at(t, n, k, lam);
        m += r2 < thr2;
        s += r2 < thr2 ? r2 : thr2;
    }
    if (inliers)
        *inliers = m;
    return s;
}

/* msac without the count, abandoned (HUGE_VAL) once the partial sum reaches
 * `bound`: the terms are >= 0, so such a proposal cannot score below the
 * bound (the bail-out of Chum & Matas' randomised RANSAC, here with an
 * exact bound: the decisions are those of the full score). Blocks of
 * MSAC_BLOCK pairs between two tests keep the inner loop vectorisable.
 * terms, msac and msac_bounded carry MCG_AVX2_CLONE (internal.h; issue 19):
 * the same bits, about half the instructions of the scale search on an
 * AVX2 CPU. */
#define MSAC_BLOCK 64
MCG_AVX2_CLONE
static double msac_bounded(const double *t, size_t n, double lam, double thr2, double bound)
{
    double s = 0.0;
    size_t k0, k;
    for (k0 = 0; k0 < n; k0 += MSAC_BLOCK) {
        size_t k1 = n - k0 < MSAC_BLOCK ? n : k0 + MSAC_BLOCK;
        for (k = k0; k < k1; k++) {
            double r2 = r2_at(t, n, k, lam);
            s += r2 < thr2 ? r2 : thr2;
        }
        if (s >= bound)
            return HUGE_VAL;
    }
    return s;
}

/* the terms a, b, |g0|, |g1|, q of every pair (see the file comment); 0 on a
 * NaN, inf, zero direction or overflow */
MCG_AVX2_CLONE
static int terms(size_t n, const int *idx, const double *o1, const double *d1,
                 const double *o2, const double *d2, const double R[9], const double t0[3],
                 const double w[3], double *t)
{
    size_t k;
    int i;
    for (k = 0; k < n; k++) {
        const size_t q = idx ? 3 * (size_t)idx[k] : 3 * k;
        const double *p1 = o1 + q, *u1 = d1 + q, *p2 = o2 + q, *u2 = d2 + q;
        double n1 = dot3(u1, u1);
        double n2 = dot3(u2, u2);
        double a[3], b[3], s[3], g0[3], g1[3], k0[3], k1[3], x, v0[6], v1[6];
        double s0 = 0.0, s1 = 0.0, c = 0.0, p01;
        if (!(n1 >= DIR2_MIN && n2 >= DIR2_MIN) || !isfinite(n1) || !isfinite(n2))
            return 0;
        n1 = 1.0 / sqrt(n1);
        n2 = 1.0 / sqrt(n2);
        for (i = 0; i < 3; i++) {
            a[i] = (R[3 * i] * u1[0] + R[3 * i + 1] * u1[1] + R[3 * i + 2] * u1[2]) * n1;
            b[i] = u2[i] * n2;
            s[i] = t0[i] + R[3 * i] * p1[0] + R[3 * i + 1] * p1[1] + R[3 * i + 2] * p1[2] -
                   p2[i];
        }
        /* g = s x a, w x a (its lam part); k = d2 x s, d2 x w */
        cross3(s, a, g0);
        cross3(w, a, g1);
        cross3(b, s, k0);
        cross3(b, w, k1);
        {
            double e0 = dot3(b, g0);
            double e1 = dot3(b, g1);
            double q0 = dot3(a, k0);
            double q1 = dot3(a, k1);
            t[k] = e0;
            t[n + k] = e1;
            /* the tangent parts P(d2) g and P(a) k: lam-free (v0) and lam
             * (v1) 6-vectors */
            for (i = 0; i < 3; i++) {
                v0[i] = g0[i] - e0 * b[i];
                v0[3 + i] = k0[i] - q0 * a[i];
                v1[i] = g1[i] - e1 * b[i];
                v1[3 + i] = k1[i] - q1 * a[i];
            }
        }
        for (i = 0; i < 6; i++) {
            s0 += v0[i] * v0[i];
            s1 += v1[i] * v1[i];
        }
        s0 = sqrt(s0);
        s1 = sqrt(s1);
        /* q = |v0| |v1| |v0 / |v0| + v1 / |v1||^2 / 2
         *   = ||v1| v0 + |v0| v1|^2 / (2 |v0| |v1|), 0 when either is 0 */
        for (i = 0; i < 6; i++) {
            double h = s1 * v0[i] + s0 * v1[i];
            c += h * h;
        }
        p01 = s0 * s1;
        c = p01 > 0.0 ? 0.5 * c / p01 : 0.0;
        t[2 * n + k] = s0;
        t[3 * n + k] = s1;
        t[4 * n + k] = c;
        x = t[k] + t[n + k] + s0 + s1 + c;
        if (!isfinite(x))
            return 0;
    }
    return 1;
}

/* 1 if pair k proposes a positive scale lam = -a / b */
static int proposes(const double *t, size_t n, size_t k)
{
    double a = t[k], b = t[n + k];
    return fabs(b) > 1e-9 * (1.0 + fabs(a)) && a * b < 0.0;
}

int mcg_scale_ransac(int n, const double *o1, const double *d1, const double *o2,
                     const double *d2, const double R[9], const double t0[3],
                     const double w[3], int n_order, const int *order, int max_proposals,
                     double threshold, double prob, double *lam, double *score,
                     int *n_inliers, double *work, size_t lwork)
{
    int k;

    if (!o1 || !d1 || !o2 || !d2 || !R || !t0 || !w || !order || !lam || !score || !work)
        return MCG_EINVAL;
    if (n < 1 || n > MAX_PAIRS || n_order < 0 || n_order > MAX_PAIRS || max_proposals < 1 ||
        max_proposals > MAX_PROPOSALS)
        return MCG_EINVAL;
    if (!(isfinite(threshold) && threshold > 0.0) || !(prob > 0.0 && prob < 1.0))
        return MCG_EINVAL;
    if (!all_finite(R, 9) || !all_finite(t0, 3) || !all_finite(w, 3))
        return MCG_EINVAL;
    for (k = 0; k < n_order; k++)
        if (order[k] < 0 || order[k] >= n)
            return MCG_EINVAL;
    if (!all_finite(o1, 3 * (size_t)n) || !all_finite(d1, 3 * (size_t)n) ||
        !all_finite(o2, 3 * (size_t)n) || !all_finite(d2, 3 * (size_t)n))
        return MCG_EINVAL;
    if (lwork < mcg_scale_ransac_work_size(n))
        return MCG_ENOMEM;
    return mcg_scale_ransac_indexed(n, NULL, o1, d1, o2, d2, R, t0, w, n_order, order,
                                    max_proposals, threshold, prob, lam, score, n_inliers,
                                    work);
}

/* mcg_scale_ransac on the pairs idx[0..n) of the arrays (internal.h): the
 * caller has checked the arguments (robust.c validates its whole input
 * once), so only the terms' finiteness is tested here. Indices instead of
 * a gathered copy of the pairs: robust.c's workspace then needs no 12 n
 * doubles for them (issue 19: peak memory at 1e3 pairs). */
int mcg_scale_ransac_indexed(int n, const int *idx, const double *o1, const double *d1,
                             const double *o2, const double *d2, const double R[9],
                             const double t0[3], const double w[3], int n_order,
                             const int *order, int max_proposals, double threshold,
                             double prob, double *lam, double *score, int *n_inliers,
                             double *work)
{
    size_t nn = (size_t)n, used = 0, pos = 0;
    double thr2, best = HUGE_VAL, lam_best = 0.0, needed = HUGE_VAL;
    int k, m_best = 0, round;

    if (!terms(nn, idx, o1, d1, o2, d2, R, t0, w, work))
        return MCG_EINVAL;
    thr2 = threshold * threshold;

    /* batches of up to BATCH proposals, the first max_proposals pairs of
     * `order` that propose a positive scale (each batch advances pos by at
     * least one: at most n_order batches) */
    while (used < (size_t)max_proposals && pos < (size_t)n_order) {
        double bs = HUGE_VAL, bl = 0.0;
        int taken = 0;
        while (taken < BATCH && used + (size_t)taken < (size_t)max_proposals &&
               pos < (size_t)n_order) {
            size_t j = (size_t)order[pos++];
            double lj, sj;
            if (!proposes(work, nn, j))
                continue;
            lj = -work[j] / work[nn + j];
            taken++;
            /* a ratio that underflowed to 0 (tiny a_k) or a score that
             * overflowed (huge inputs) is no proposal: lam = 0 came out with
             * MCG_OK (found by fuzz_scale_line in its 10-minute run) */
            if (!(lj > 0.0))
                continue;
            /* (a score >= the batch's best or the overall best changes
             * nothing below: neither is replaced) */
            sj = msac_bounded(work, nn, lj, thr2, bs < best ? bs : best);
            if (!isfinite(sj))
                continue;
            if (sj < bs) { /* the first of equal scores */
                bs = sj;
                bl = lj;
            }
        }
        if (taken == 0)
            break;
        used += (size_t)taken;
        if (bs < best) {
            double ratio;
            best = msac(work, nn, bl, thr2, &m_best);
            lam_best = bl;
            ratio = (double)m_best / (double)n;
            /* samples after which a 1-point all-inlier sample was drawn
             * with probability prob */
            needed = ratio >= 1.0 ? 1.0 : ratio > 0.0 ? log1p(-prob) / log1p(-ratio) : HUGE_VAL;
        }
        if ((double)used >= needed)
            break;
    }
    if (used == 0 || !(best < HUGE_VAL))
        return MCG_EDEGENERATE;

    /* weighted least squares of eq. 7.4 on the inliers (weights 1 / D),
     * kept only if the MSAC score improves: near the critical motion the
     * linear equation is biased towards lam = 0, the robust score is not */
    for (round = 0; round < LS_ROUNDS; round++) {
        double sab = 0.0, sbb = 0.0, cand, sc;
        int m;
        for (k = 0; k < n; k++) {
            size_t q = (size_t)k;
            double den, wt;
            if (!(r2_at(work, nn, q, lam_best) < thr2))
                continue;
            den = den_at(work, nn, q, lam_best);
            wt = 1.0 / (den > DEN_MIN ? den : DEN_MIN);
            sab += wt * work[q] * work[nn + q];
            sbb += wt * work[nn + q] * work[nn + q];
        }
        if (!(sbb > 0.0))
            break;
        cand = -sab / sbb;
        if (!(cand > 0.0) || !isfinite(cand))
            break;
        sc = msac(work, nn, cand, thr2, &m);
        if (!(sc < best))
            break;
        lam_best = cand;
        best = sc;
        m_best = m;
    }
    *lam = lam_best;
    *score = best;
    if (n_inliers)
        *n_inliers = m_best;
    return MCG_OK;
}
