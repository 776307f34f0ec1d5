/*
 * leverage.c -- the leverage of every ray pair in the least-squares fit of a
 * rig motion (mcg_sampson_leverage): how much of one parameter direction
 * the pair determines alone.
 *
 * Linearised at the fit (R, t), the Sampson angular residuals r
 * (mcg_gec_residuals, thesis eq. 8.15 applied to the generalized epipolar
 * constraint, eq. 8.16) have the Jacobian J (one row J_k per pair, the
 * parameters [dw, dt] of mcg_refine_motion, or dt alone with R held). The
 * hat matrix J (J^T J)^-1 J^T maps the measurements to the fitted values;
 * its diagonal h_k = J_k (J^T J)^-1 J_k^T in [0, 1] (summing to the number
 * of parameters) is pair k's leverage (Hoaglin & Welsch 1978), and
 * 1 - h_k its redundancy number (Baarda 1968; Foerstner 1987): the share of
 * an error in pair k that shows in its own residual. A pair with h_k near 1
 * fixes a direction of the motion by itself: a gross error there is
 * absorbed by the fit, every residual stays small, and no statistic of the
 * residuals can see it (observations with a redundancy number below ~0.1
 * count as uncontrolled in geodetic reliability analysis). The direct
 * estimators' verdicts (mcgeom/estimators/_outliers.py) do not call a
 * scale metric that rests on such a pair. h_k does not depend on how the
 * parameters are scaled or combined, so neither on the rotation's
 * parametrisation nor on the units.
 *
 * The result also gives the largest move of the cameras' travel
 * |t + R c - c| when one pair is deleted (Cook 1977's case deletion,
 * linearised at the fit) in metres' share of the travel and in stds of it:
 * a pair of moderate leverage with a large residual moves the fit as much.
 * The root sum of squares of those moves is the travel's std that the
 * pairs' own residuals tell (HC3, MacKinnon & White 1985; Long & Ervin
 * 2000 for small samples), where travel_std assumes one noise level for
 * all pairs: a wrong match within a robust fit's threshold, whose residual
 * is uniform over the threshold band rather than noise, at a pair that
 * fixes much of |t|, moves the estimate by more than travel_std says.
 * With weights (a weighted fit's: the robust search's final refinement,
 * 0 for the pairs it did not use; mcgeom/robust/_verdict.py) every sum is
 * weighted.
 */
#include "refine_internal.h" /* refine_evaluate: J^T J in one vectorised pass */
#include "sampson.h"

#include <float.h>
#include <math.h>
#include <string.h>

#define MAX_PAIRS (1 << 26)
/* smallest pivot of the Cholesky factor of the unit-diagonal J^T J: its
 * reciprocal condition number at least ~1e-12 */
#define PIVOT_MIN 1e-12
/* The leverages sum to the number of parameters (the trace of the hat
 * matrix) in exact arithmetic; computed (and clipped to [0, 1]), they miss
 * it by ~eps cond(J^T J).
 * A larger miss is a direction that rounding alone determines (two nearly
 * parallel Jacobian columns can keep every pivot above PIVOT_MIN: fuzz
 * input, 58 copies of two pairs, pivots 1, 3.8e-4, 4.9e-12, sum 2), and the
 * leverages then mean nothing: MCG_EDEGENERATE. */
#define TRACE_TOL 1e-6
/* largest weight accepted (a frequency or pixel scaling is far below; the
 * products of the pass stay far from overflow) */
#define MAX_WEIGHT 1e100
/* pairs per block of the second pass (structure of arrays on the stack, so
 * that the per-pair loops vectorise, as refine_eval.c's) */
#define BLK 32

/* The second pass over one block of nb pairs: each pair's residual r,
 * u = L^-1 S J_k (forward substitution with the inverse diagonal il; the
 * parameters p0..5, np of them), its leverage h = |u|^2 and the change of
 * the travel on deleting it, |w . u| |r| / (1 - h). Branch-free loops over
 * the block. */
MCG_AVX2_CLONE
static void block_pass(int nb, const double *o1, const double *d1, const double *o2,
                       const double *d2, const double *wts, const double R[9],
                       const double t[3], int p0, const double *l, const double *il,
                       const double *sc, const double *w, double *hb, double *mb)
{
    double rb[BLK], jb[6][BLK], ub[6][BLK];
    const int np = 6 - p0;
    int k, a, b;
    for (k = 0; k < nb; k++) {
        sampson_terms p;
        sampson_row q;
        sampson_pair(R, t, o1 + 3 * k, d1 + 3 * k, o2 + 3 * k, d2 + 3 * k, &p);
        sampson_jacobian(&p, &q);
        rb[k] = q.r;
        for (a = 0; a < 6; a++)
            jb[a][k] = q.j[a];
    }
    for (a = 0; a < np; a++)
        for (k = 0; k < nb; k++) {
            double v = jb[p0 + a][k] * sc[a];
            for (b = 0; b < a; b++)
                v -= l[6 * a + b] * ub[b][k];
            ub[a][k] = v * il[a];
        }
    for (k = 0; k < nb; k++) {
        double h = 0.0, g = 0.0, wk = wts ? wts[k] : 1.0;
        for (a = 0; a < np; a++) {
            h += ub[a][k] * ub[a][k];
            g += w[a] * ub[a][k];
        }
        h *= wk;
        g *= wk;
        /* (rounding can leave [0, 1] by ~eps cond(J^T J)) */
        h = h < 0.0 ? 0.0 : h > 1.0 ? 1.0 : h;
        hb[k] = h;
        /* (a leverage of 1 to rounding: a bounded stand-in for the unbounded
         * move; the leverage says it) */
        mb[k] = fabs(g * rb[k]) / fmax(1.0 - h, 1e-12);
        /* (extreme weights: an overflowed or undefined move counts as
         * unbounded) */
        mb[k] = mb[k] <= DBL_MAX ? mb[k] : DBL_MAX;
    }
}

int mcg_sampson_leverage(int n, const double *o1, const double *d1, const double *o2,
                         const double *d2, const double *weights, const double R[9],
                         const double t[3], int hold_rotation, double *lev,
                         mcg_leverage_result *out)
{
    double l[36], il[6], sc[6], g[6], w[6], cen[3] = {0.0, 0.0, 0.0}, rc[3], v[3];
    double trace = 0.0, travel, ww, sd, best = -1.0, top = -1.0, hc_scale = 0.0, hc_ssq = 1.0;
    const int p0 = hold_rotation ? 3 : 0, np = 6 - p0;
    int k, k0, a, b, c;
    accum acc;
    lossfn lf;
    mcg_leverage_result res;
    if (!o1 || !d1 || !o2 || !d2 || !R || !t)
        return MCG_EINVAL;
    if (n < 0 || n > MAX_PAIRS || (hold_rotation != 0 && hold_rotation != 1))
        return MCG_EINVAL;
    if (!all_finite(R, 9) || !all_finite(t, 3))
        return MCG_EINVAL;
    for (k = 0; weights && k < n; k++)
        if (!(weights[k] >= 0.0 && weights[k] <= MAX_WEIGHT))
            return MCG_EINVAL;
    memset(&res, 0, sizeof res);
    res.leverage_pair = res.influence_pair = -1;
    /* J^T W J and the weighted sum of squared residuals (least squares: no
     * loss), as the refinement's evaluation computes them */
    lf.loss = MCG_LOSS_NONE;
    lf.s = lf.s2 = lf.inv_s2 = 1.0;
    refine_evaluate(n, o1, d1, o2, d2, weights, &lf, R, t, &acc);
    if (acc.bad || !all_finite(acc.h, 36))
        return MCG_EINVAL;
    for (k = 0; k < n; k++)
        for (a = 0; a < 3; a++)
            cen[a] += (weights && !(weights[k] > 0.0)) ? 0.0 : o1[3 * k + a] + o2[3 * k + a];
    if (!all_finite(cen, 3))
        return MCG_EINVAL;
    /* Cholesky L L^T of the Jacobi-scaled J^T J (the rotation's radians and
     * the translation's metres differ by orders of magnitude; h_k is the
     * same for J S, S diagonal): then h_k = |L^-1 S J_k|^2. A pivot below
     * PIVOT_MIN of the unit diagonal is a direction that no pair determines
     * (a rank-deficient J up to rounding: fewer pairs than parameters, |t|
     * of a single centre) */
    for (a = 0; a < np; a++) {
        if (!(acc.h[7 * (p0 + a)] > 0.0))
            return MCG_EDEGENERATE; /* a parameter no pair moves */
        sc[a] = 1.0 / sqrt(acc.h[7 * (p0 + a)]);
    }
    for (a = 0; a < np; a++)
        for (b = 0; b <= a; b++) {
            double x = acc.h[6 * (p0 + b) + p0 + a] * sc[a] * sc[b];
            for (c = 0; c < b; c++)
                x -= l[6 * a + c] * l[6 * b + c];
            if (a == b) {
                if (!(x > PIVOT_MIN))
                    return MCG_EDEGENERATE;
                l[6 * a + a] = sqrt(x);
                il[a] = 1.0 / l[6 * a + a];
            } else {
                l[6 * a + b] = x * il[b];
            }
        }
    /* The centroid's travel tau = t + R c - c and its gradient g in the
     * parameters (the rotation perturbed on the left, R <- exp([dw]x) R, as
     * the rows of sampson_jacobian): d tau = -[R c]x dw + dt, so
     * d|tau| = ((R c) x u) . dw + u . dt, u = tau / |tau|. Deleting pair k
     * moves the least-squares parameters by -H^-1 J_k^T r_k / (1 - h_k)
     * (exact for a linear model; Cook 1977, Belsley, Kuh & Welsch 1980's
     * DFBETA), so |tau| by -(g^T H^-1 J_k^T) r_k / (1 - h_k), with
     * g^T H^-1 J_k^T = (L^-1 S g) . (L^-1 S J_k); its std is
     * sigma sqrt(g^T H^-1 g), sigma^2 = sum r^2 / (n - np). With weights
     * w_k (the pairs a weighted fit used, w_k > 0) H = J^T W J, h_k =
     * w_k J_k H^-1 J_k^T, the move w_k g^T H^-1 J_k^T r_k / (1 - h_k),
     * sigma^2 = sum w r^2 / (m - np), m the pairs used; c their centroid. */
    for (k = 0, c = 0; k < n; k++)
        c += !(weights && !(weights[k] > 0.0));
    for (a = 0; a < 3; a++)
        cen[a] /= 2.0 * (c > 0 ? c : 1);
    mat_vec(R, cen, rc);
    for (a = 0; a < 3; a++)
        v[a] = t[a] + rc[a] - cen[a];
    { /* (scaled: a travel near DBL_MAX does not overflow its square) */
        double big = fmax(fabs(v[0]), fmax(fabs(v[1]), fabs(v[2])));
        travel = big > 0.0 ? big * sqrt((v[0] / big) * (v[0] / big) + (v[1] / big) * (v[1] / big)
                                        + (v[2] / big) * (v[2] / big))
                           : 0.0;
        if (!(travel <= DBL_MAX))
            return MCG_EINVAL; /* (a travel beyond the doubles: magnitudes far off) */
    }
    for (a = 0; a < 6; a++)
        g[a] = 0.0;
    if (travel > 0.0) {
        double u[3], cu[3];
        for (a = 0; a < 3; a++)
            u[a] = v[a] / travel;
        cross3(rc, u, cu);
        for (a = 0; a < 3; a++) {
            g[a] = cu[a];
            g[3 + a] = u[a];
        }
    }
    ww = 0.0;
    for (a = 0; a < np; a++) {
        double x = g[p0 + a] * sc[a];
        for (b = 0; b < a; b++)
            x -= l[6 * a + b] * w[b];
        w[a] = x * il[a];
        ww += w[a] * w[a];
    }
    sd = acc.n_used > np ? sqrt(acc.swr2 / (acc.n_used - np) * ww) : HUGE_VAL;
    /* (an exact fit, sum w r^2 = 0, with a gradient beyond the doubles,
     * ww = inf: 0 x inf, a std nothing determines; fuzz_leverage, a travel
     * of 1e77 m) */
    if (isnan(sd))
        sd = HUGE_VAL;
    for (k0 = 0; k0 < n; k0 += BLK) {
        int nb = n - k0 < BLK ? n - k0 : BLK;
        double hb[BLK], mb[BLK];
        block_pass(nb, o1 + 3 * k0, d1 + 3 * k0, o2 + 3 * k0, d2 + 3 * k0,
                   weights ? weights + k0 : NULL, R, t, p0, l, il, sc, w, hb, mb);
        for (k = 0; k < nb; k++) {
            trace += hb[k];
            if (hb[k] > top) {
                top = hb[k];
                res.leverage_pair = k0 + k;
            }
            if (mb[k] > best) {
                best = mb[k];
                res.influence_pair = k0 + k;
            }
            /* sum of mb^2, scaled by the largest so far (as BLAS dnrm2):
             * no overflow of the squares short of the result's own */
            if (mb[k] > hc_scale) {
                hc_ssq = 1.0 + hc_ssq * (hc_scale / mb[k]) * (hc_scale / mb[k]);
                hc_scale = mb[k];
            } else if (mb[k] > 0.0) {
                hc_ssq += (mb[k] / hc_scale) * (mb[k] / hc_scale);
            }
        }
        if (lev)
            memcpy(lev + k0, hb, (size_t)nb * sizeof(double));
    }
    if (!(fabs(trace - np) <= TRACE_TOL * np))
        return MCG_EDEGENERATE;
    res.max_leverage = top;
    res.travel = travel;
    res.travel_std = sd;
    res.travel_std_hc = hc_scale * sqrt(hc_ssq);
    if (!(res.travel_std_hc <= DBL_MAX))
        res.travel_std_hc = HUGE_VAL;
    if (n > 0 && travel > 0.0) {
        res.max_influence = fmin(best / travel, DBL_MAX);
        res.max_influence_stds = sd > 0.0 && sd < HUGE_VAL ? fmin(best / sd, DBL_MAX) : 0.0;
    }
    if (out)
        *out = res;
    return MCG_OK;
}
