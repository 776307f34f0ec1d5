/*
 * consensus.c -- the checks of a robust estimate's consensus before its
 * scale is called metric (mcg_consensus_check; mcgeom/robust/_verdict.py
 * words the reasons).
 *
 * A robust search's final refinement is a least-squares fit on its inliers.
 * A wrong match that the consensus took in can carry that fit:
 *   - with the leverage to pull the fit onto itself (h_k near 1, thesis
 *     eq. 8.15's Sampson residuals linearised; csrc/leverage.c), its error
 *     shows in no residual. Deleting one pair (Cook 1977) shows a single
 *     such pair; several can mask each other, each below the rules, so the
 *     fit is redone without the pair of highest leverage while that is
 *     above SCREEN_LEVERAGE, up to LEVER_ROUNDS pairs, and judged by how
 *     far the travel moves and how uncertain it is without them (session
 *     36: 12 of 1,687 metric estimates 10-73 % off -> none of 1,671 on the
 *     property suite's rigs with 10-50 % outliers);
 *   - within the threshold by chance, its residual is spread over the
 *     threshold band rather than the noise: the std of one noise level for
 *     all pairs is then too small where it helps fix |t|. The std the
 *     pairs' own residuals tell (HC3, MacKinnon & White 1985:
 *     mcg_leverage_result.travel_std_hc) replaces it where it is more than
 *     RESIDUALS_WIDEN times larger (session 38: rms of error / std 1.18 /
 *     1.20 / 1.31 -> 1.02 / 1.03 / 1.09 at 10 / 30 / 50 % outliers).
 *
 * The travel judged is that of the pairs' centroid c, |t + R c - c| (the
 * frame in which the refinement's relative std is computed); the refits
 * run on the used pairs shifted to c.
 */
#include "mcgeom.h"
#include "internal.h"

#include <float.h>
#include <math.h>
#include <string.h>

#define MAX_PAIRS (1 << 26)
#define MAX_LEVERAGE 0.9      /* estimators/_outliers.py MAX_LEVERAGE */
#define DELETION_STDS 4.0     /* estimators/_outliers.py DELETION_STDS */
#define SCREEN_LEVERAGE 0.5   /* estimators/_outliers.py SCREEN_LEVERAGE */
#define OUTLIER_MOVE_STDS 3.0 /* estimators/_outliers.py OUTLIER_MOVE_STDS */
#define LEVER_ROUNDS 3        /* robust/_verdict.py LEVER_ROUNDS */
#define RESIDUALS_WIDEN 1.25  /* robust/_verdict.py RESIDUALS_WIDEN */
/* the refits' cost tolerance: |t| to ~1e-3 of its std (REFINE_TOL of
 * csrc/robust_lo.c), over the pairs used */
#define REFIT_TOL 1e-3

size_t mcg_consensus_check_work_size(int n)
{
    int ok = 1;
    size_t w;
    if (n < 0 || n > MAX_PAIRS)
        return 0;
    /* every pair's leverage (n), the used pairs' rays shifted to their
     * centroid (12 n), their weights (n) and leverages (n) */
    w = mul_sz(15, (size_t)n, &ok);
    w = add_sz(w, 1, &ok);
    return ok ? w : 0;
}

static double norm3(const double v[3]) { return sqrt(dot3(v, v)); }

/* The refits without the pairs of highest leverage (see the file comment):
 * lev_all holds every pair's leverage in the fit; out gets the decision
 * (reason, rel_std) and the figures. */
static void without_lever_pairs(int n, const double *o1, const double *d1, const double *o2,
                                const double *d2, const double *weights, const double R0[9],
                                const double t0[3], double rel_std, double max_rel_std,
                                const double *lev_all, double *work, mcg_consensus_result *out)
{
    double c[3] = {0.0, 0.0, 0.0}, R[9], tc[3], rc[3], before, rel = NAN;
    double *uo1, *ud1, *uo2, *ud2, *w, *lev;
    int m = 0, k, a, i, round, have_st = 1, strong = 0;
    mcg_leverage_result st;
    mcg_refine_options opt;
    for (k = 0; k < n; k++)
        m += weights[k] > 0.0;
    uo1 = work;
    ud1 = uo1 + 3 * (size_t)m;
    uo2 = ud1 + 3 * (size_t)m;
    ud2 = uo2 + 3 * (size_t)m;
    w = ud2 + 3 * (size_t)m;
    lev = w + m;
    for (k = 0, i = 0; k < n; k++) {
        if (!(weights[k] > 0.0))
            continue;
        for (a = 0; a < 3; a++) {
            uo1[3 * i + a] = o1[3 * k + a];
            ud1[3 * i + a] = d1[3 * k + a];
            uo2[3 * i + a] = o2[3 * k + a];
            ud2[3 * i + a] = d2[3 * k + a];
            c[a] += o1[3 * k + a] + o2[3 * k + a];
        }
        w[i] = weights[k];
        lev[i] = lev_all[k];
        i++;
    }
    for (a = 0; a < 3; a++)
        c[a] *= 0.5 / m;
    for (i = 0; i < m; i++)
        for (a = 0; a < 3; a++) {
            uo1[3 * i + a] -= c[a];
            uo2[3 * i + a] -= c[a];
        }
    memcpy(R, R0, sizeof R);
    mat_vec(R, c, rc);
    for (a = 0; a < 3; a++)
        tc[a] = t0[a] + rc[a] - c[a];
    before = norm3(tc);
    mcg_refine_default_options(&opt);
    opt.cost_tolerance = REFIT_TOL / m;
    for (round = 0; round < LEVER_ROUNDS && have_st; round++) {
        mcg_refine_result rr;
        double Rn[9], tn[3];
        int top = 0;
        for (i = 1; i < m; i++)
            if (lev[i] > lev[top])
                top = i;
        if (!(lev[top] > SCREEN_LEVERAGE))
            break;
        strong = strong || lev[top] > MAX_LEVERAGE;
        /* (its index among all n pairs: the top-th used one) */
        for (k = 0, i = -1; k < n; k++)
            if (weights[k] > 0.0 && ++i == top)
                break;
        out->dropped[out->n_dropped++] = k;
        w[top] = 0.0;
        memcpy(Rn, R, sizeof Rn);
        memcpy(tn, tc, sizeof tn);
        if (mcg_refine_motion(m, uo1, ud1, uo2, ud2, w, &opt, Rn, tn, &rr) != MCG_OK) {
            have_st = 0;
            break;
        }
        memcpy(R, Rn, sizeof R);
        memcpy(tc, tn, sizeof tc);
        rel = rr.scale_rel_std;
        have_st = mcg_sampson_leverage(m, uo1, ud1, uo2, ud2, w, R, tc, 0, lev, &st) == MCG_OK;
    }
    out->lever_strong = strong;
    out->lever_rel_std = rel;
    out->rel_std = rel_std;
    if (out->n_dropped == 0)
        return;
    if (strong && (!have_st || st.max_leverage > MAX_LEVERAGE)) {
        out->reason = MCG_CONSENSUS_UNDETERMINED;
        return;
    }
    if (!have_st)
        return;
    {
        double after = norm3(tc), move = before > 0.0 ? fabs(after / before - 1.0) : HUGE_VAL;
        out->have_move = 1;
        out->lever_move = move;
        if (strong && !(rel <= max_rel_std)) {
            out->reason = MCG_CONSENSUS_LEVER_STD;
            return;
        }
        if (move > OUTLIER_MOVE_STDS * rel_std) {
            if (move > max_rel_std) {
                out->reason = MCG_CONSENSUS_LEVER_MOVE;
                return;
            }
            rel_std = hypot(rel_std, move);
        }
    }
    /* (an error in the dropped pairs would show little in their residuals:
     * the scale is no more precise than the rest of the consensus fixes it) */
    if (rel > rel_std)
        rel_std = rel;
    out->rel_std = rel_std;
    if (!(rel_std <= max_rel_std))
        out->reason = MCG_CONSENSUS_WIDENED_STD;
}

int mcg_consensus_check(int n, const double *o1, const double *d1, const double *o2,
                        const double *d2, const double *weights, const double R[9],
                        const double t[3], double rel_std, double cal_rel_std,
                        double max_rel_std, mcg_consensus_result *out, double *work,
                        size_t lwork)
{
    mcg_consensus_result res;
    mcg_leverage_result *st = &res.stats;
    double hc, rel;
    int s;
    if (!o1 || !d1 || !o2 || !d2 || !weights || !R || !t || !out || (!work && lwork))
        return MCG_EINVAL;
    if (n < 0 || n > MAX_PAIRS || !(isfinite(rel_std) && rel_std >= 0.0) ||
        !(isfinite(cal_rel_std) && cal_rel_std >= 0.0) ||
        !(isfinite(max_rel_std) && max_rel_std > 0.0))
        return MCG_EINVAL;
    if (lwork < mcg_consensus_check_work_size(n))
        return MCG_ENOMEM;
    memset(&res, 0, sizeof res);
    res.reason = MCG_CONSENSUS_METRIC;
    res.rel_std = rel_std;
    res.residuals_rel_std = NAN;
    res.lever_move = NAN;
    res.lever_rel_std = NAN;
    s = mcg_sampson_leverage(n, o1, d1, o2, d2, weights, R, t, 0, work, st);
    if (s == MCG_EDEGENERATE) { /* singular: nothing decided */
        *out = res;
        return MCG_OK;
    }
    if (s != MCG_OK)
        return s;
    res.have_stats = 1;
    rel = rel_std;
    /* the one-pair rule (estimators/_outliers.py one_pair_rule): a leverage
     * above MAX_LEVERAGE is judged by the refits below instead */
    if (!(st->max_leverage > MAX_LEVERAGE) && st->max_influence_stds > DELETION_STDS &&
        st->max_influence > max_rel_std)
        res.reason = MCG_CONSENSUS_ONE_PAIR;
    if (st->travel > 0.0)
        res.residuals_rel_std = st->travel_std_hc / st->travel;
    if (st->max_leverage > SCREEN_LEVERAGE &&
        (res.reason == MCG_CONSENSUS_METRIC || st->max_leverage > MAX_LEVERAGE)) {
        without_lever_pairs(n, o1, d1, o2, d2, weights, R, t, rel_std, max_rel_std, work,
                            work + n, &res);
        rel = res.rel_std;
        res.widened_by_lever = res.reason == MCG_CONSENSUS_METRIC && rel != rel_std;
    }
    res.rel_std_lever = rel;
    hc = combine_rel_std(res.residuals_rel_std, cal_rel_std);
    if (res.reason == MCG_CONSENSUS_METRIC && !isnan(res.residuals_rel_std) &&
        hc > RESIDUALS_WIDEN * rel) {
        rel = hc;
        res.widened_by_residuals = 1;
        if (!(hc <= max_rel_std))
            res.reason = MCG_CONSENSUS_RESIDUALS_STD;
    }
    res.rel_std = rel;
    *out = res;
    return MCG_OK;
}
