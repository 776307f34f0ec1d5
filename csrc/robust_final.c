/*
 * robust_final.c -- the final stage of the robust estimate (csrc/robust.c):
 * the refinement of all six degrees of freedom on the pairs within WIDE
 * thresholds of the best motion (refitted once if that set moved), the
 * scale searched once more at the refined motion, the profile of the cost
 * along |t| that the scale verdict reads (thesis ch. 7.3's observability),
 * and the covariance of the refinement.
 */
#include "robust_internal.h"

#include <math.h>
#include <string.h>

/* Pixel scaling of the final refinement at (R, t): with the camera table,
 * the exact first-order scaling of every residual (mcg_sampson_pixel_scale,
 * 0 -> the fixed focal), else the fixed focal. Writes the weights
 * (f / median f)^2 into fsc (or returns NULL when they are all equal) and the
 * loss scale (radians). */
static const double *final_weights(ctx *c, const double R[9], const double t[3],
                                   double *scale)
{
    int k0, k, i;
    if (!c->focal) {
        *scale = c->opt.threshold;
        return NULL;
    }
    if (!c->cam_axes) {
        *scale = c->loss_scale;
        return robust_fixed_weights(c);
    }
    for (k0 = 0; k0 < c->n; k0 += SCORE_BLOCK) {
        int nb = c->n - k0 < SCORE_BLOCK ? c->n - k0 : SCORE_BLOCK;
        double z1[3 * SCORE_BLOCK], z2[3 * SCORE_BLOCK], f1[SCORE_BLOCK], f2[SCORE_BLOCK];
        for (k = 0; k < nb; k++) {
            int a = c->cam1[k0 + k], b = c->cam2[k0 + k];
            for (i = 0; i < 3; i++) {
                z1[3 * k + i] = c->cam_axes[3 * a + i];
                z2[3 * k + i] = c->cam_axes[3 * b + i];
            }
            f1[k] = c->cam_focal[a];
            f2[k] = c->cam_focal[b];
        }
        if (mcg_sampson_pixel_scale(nb, c->o1 + 3 * k0, c->d1 + 3 * k0, c->o2 + 3 * k0,
                                    c->d2 + 3 * k0, R, t, z1, z2, f1, f2, c->min_var_ratio,
                                    c->fsc + k0) != MCG_OK)
            for (k = 0; k < nb; k++)
                c->fsc[k0 + k] = 0.0;
        for (k = 0; k < nb; k++)
            if (!(c->fsc[k0 + k] > 0.0))
                c->fsc[k0 + k] = c->focal[k0 + k];
    }
    {
        double med = median(c->fsc, c->rcur, c->n);
        *scale = c->opt.threshold / med;
        for (k = 0; k < c->n; k++) {
            double f = c->fsc[k] / med;
            c->fsc[k] = f * f;
        }
    }
    return c->fsc;
}

/* The final refinement (all six degrees of freedom) on the pairs within
 * WIDE thresholds of the best motion, once more if that set moved; the
 * residuals of the result end in rbest. mask bit 1: the pairs of the last
 * refinement that succeeded (bit 2, the set to fit next, is scratch). */
void robust_finish(ctx *c, mcg_robust_result *res, unsigned char *mask, double *weights_out)
{
    double R[9], t[3], cen[3], scale, R0[9], t0[3];
    const double wide = WIDE * c->opt.threshold;
    int round, k, m, n_inl, moved = 1, st;
    const double *w;
    mcg_refine_result rr;
    memcpy(R, c->R, sizeof R);
    memcpy(t, c->t, sizeof t);
    res->refined = 0;
    for (k = 0; k < c->n; k++)
        mask[k] = c->rbest[k] < wide ? 4 : 0;
    for (round = 0; round < 2 && moved; round++) {
        w = final_weights(c, R, t, &scale);
        for (k = 0; k < c->n; k++)
            c->rcur[k] = (mask[k] & 4) ? 0.0 : 1.0; /* gather the set to fit */
        m = robust_gather(c, c->rcur, 0.5, w, cen, 1.0);
        if (m < MIN_REFIT)
            break;
        /* REFINE_TOL where |t| is determined (no flat valley to slide
         * along: the argument of REFINE_TOL holds): the refit of a moved set
         * when the first fit found it so, and the first fit when its own
         * result says so; a first fit that ends undetermined is run again
         * from its start at mcg_refine_motion's tolerance, where it stops
         * as before (issue 19: the tight first fit took 7-11 of the ~20 LM
         * evaluations of an estimate on ring4 / Ladybug, 45 % of the C
         * instructions on ring4) */
        memcpy(R0, R, sizeof R0);
        memcpy(t0, t, sizeof t0);
        c->final_stage = round > 0 && !(res->refinement.scale_rel_std <= UNDETERMINED_REL_STD);
        st = robust_refine_capped(c, m, cen, w != NULL, c->opt.loss, scale, 0, R, t, &rr);
        if (round == 0 && st == MCG_OK && !(rr.scale_rel_std <= UNDETERMINED_REL_STD)) {
            memcpy(R, R0, sizeof R0);
            memcpy(t, t0, sizeof t0);
            c->final_stage = 1;
            st = robust_refine_capped(c, m, cen, w != NULL, c->opt.loss, scale, 0, R, t, &rr);
        }
        if (st != MCG_OK)
            break;
        res->refined = 1;
        res->refinement = rr;
        res->loss_scale = scale;
        res->n_used = m;
        for (k = 0; k < c->n; k++) {
            mask[k] = (mask[k] & 4) ? 2 : 0;
            if (weights_out)
                weights_out[k] = (mask[k] & 2) ? (w ? w[k] : 1.0) : 0.0;
        }
        (void)robust_msac(c, R, t, INFINITY, &n_inl);
        memcpy(c->R, R, sizeof R);
        memcpy(c->t, t, sizeof t);
        {
            double *tmp = c->rbest;
            c->rbest = c->rcur;
            c->rcur = tmp;
        }
        /* refit once more if the set moved (and is large enough); beyond
         * FINAL_SUB pairs only if more than 1 in 1000 of them changed sides:
         * at 1e6 pairs a few always cross the 2-threshold line, and their
         * refit moves the motion far below its noise (issue 19) */
        moved = 0;
        m = 0;
        for (k = 0; k < c->n; k++) {
            int in = c->rbest[k] < wide;
            moved += in != ((mask[k] >> 1) & 1);
            m += in;
            mask[k] = (unsigned char)(mask[k] | (in ? 4 : 0));
        }
        moved = moved > (m > FINAL_SUB ? m / 1000 : 0) && m >= MIN_REFIT;
    }
    for (k = 0; k < c->n; k++)
        mask[k] &= 2;
}

/* The scale searched once more at the refined motion, where the
 * refinement found |t| determined (the verdict may call it metric): the
 * search's best carried a rotation error that compensated its scale error,
 * and at that rotation the cross-camera pairs pointed nowhere else; at the
 * refined rotation they may point to another scale (trial 1023 of `mcgeom
 * experiment ch7 --trials 1200 --seed 10 --cross 0.1`: refined at |t|
 * 0.209 m with 22 cross-camera inliers, the line through it has 35 at
 * 1.04 m, the truth 1.05 m). A jump that wins (see final_scale_search) is
 * refined again; otherwise the refined motion stays as it was. Where |t| is
 * not determined no scale is reported, and the search cost the upright
 * sampler without cross-camera pairs, whose scale search runs on all
 * pairs, 5.24 M C instructions per estimate against 4.77 M gated (40
 * problems of `mcgeom experiment peer_solvers`' four upright cases; the
 * same honesty). */
void robust_rescale_refined(ctx *c, mcg_robust_result *res, unsigned char *mask,
                            double *weights, const double cen[3], const double *w)
{
    double Rf[9], tf[3];
    int jump;
    if (!res->refined ||
        !(res->refinement.scale_rel_std <= (c->opt.max_scale_rel_std > 0.0
                                                ? c->opt.max_scale_rel_std
                                                : UNDETERMINED_REL_STD)))
        return;
    memcpy(Rf, c->R, sizeof Rf);
    memcpy(tf, c->t, sizeof tf);
    c->final_stage = 0;
    robust_set_best(c, Rf, tf);
    jump = robust_final_scale_search(c, cen, w);
    res->hypotheses = c->n_hyp;
    res->local_optimizations = c->n_lo;
    if (jump == 1) { /* the final stage starts again from the jump */
        memcpy(res->t_hypothesis, c->t, sizeof c->t);
        res->score = c->score;
        c->final_stage = 1;
        robust_finish(c, res, mask, weights);
    } else if (jump == 2) {
        /* the jump lost to the refined motion's free local optimisation,
         * which replaced it as the best: the refined motion and its
         * residuals (the inlier mask) back */
        robust_set_best(c, Rf, tf);
    }
}

/* The start of a profile fit: the free optimum (R, t) (rig frame; the
 * centroid's translation tc = t + shift, shift = R cen - cen) with tc
 * scaled to f |tc|, and the other five parameters (rotation, direction of
 * tc) moved to their conditional optimum under the quadratic model of the
 * cost at the optimum, information h (6 x 6 in [dw, dt], the centred
 * frame): for the step s u along u = tc / |tc|, s = (f - 1) |tc|, the rest
 * y (dw and tc's two tangent directions b1, b2) solves
 * (P^T h P) y = -P^T h u s (the Schur complement step of a profile
 * likelihood). The fit then starts near its optimum instead of at R
 * (measured: the profile's pair evaluations at 1e3 pairs -17 %, ring4
 * -15 %; none gained for the zero profile, whose 1 % of |tc| lies far
 * beyond the quadratic model: not used there). On a
 * singular block or a step of more than MAX_START_TURN the plain start is
 * kept. R, t: in, the plain start (R the optimum's); out, the start. */
#define MAX_START_TURN 0.1

static void profile_start(const double h[36], const double t_opt[3], const double shift[3],
                          double f, const double cen[3], double R[9], double t[3])
{
    double tc[3], u[3], b1[3], b2[3], p[6][5], hp[6][5], a[25], rhs[5], y[5], hu[6];
    double ntc, sstep, dw[3], dr[9], rn[9], tn[3], rc[3];
    int i, j, k;
    for (i = 0; i < 3; i++)
        tc[i] = t_opt[i] + shift[i];
    ntc = sqrt(dot3(tc, tc));
    if (!(ntc > 0.0) || !all_finite(h, 36))
        return;
    for (i = 0; i < 3; i++)
        u[i] = tc[i] / ntc;
    /* b1, b2: an orthonormal basis of u's normal plane */
    k = fabs(u[0]) <= fabs(u[1]) && fabs(u[0]) <= fabs(u[2]) ? 0 : fabs(u[1]) <= fabs(u[2]) ? 1 : 2;
    {
        double ax[3] = {0.0, 0.0, 0.0};
        ax[k] = 1.0;
        cross3(u, ax, b1);
        if (!unit3(b1, b1))
            return;
        cross3(u, b1, b2);
    }
    memset(p, 0, sizeof p);
    for (i = 0; i < 3; i++) {
        p[i][i] = 1.0;
        p[3 + i][3] = b1[i];
        p[3 + i][4] = b2[i];
    }
    for (i = 0; i < 6; i++) {
        hu[i] = h[6 * i + 3] * u[0] + h[6 * i + 4] * u[1] + h[6 * i + 5] * u[2];
        for (j = 0; j < 5; j++) {
            hp[i][j] = 0.0;
            for (k = 0; k < 6; k++)
                hp[i][j] += h[6 * i + k] * p[k][j];
        }
    }
    sstep = (f - 1.0) * ntc;
    for (i = 0; i < 5; i++) {
        rhs[i] = 0.0;
        for (k = 0; k < 6; k++)
            rhs[i] -= p[k][i] * hu[k] * sstep;
        for (j = 0; j < 5; j++) {
            a[5 * i + j] = 0.0;
            for (k = 0; k < 6; k++)
                a[5 * i + j] += p[k][i] * hp[k][j];
        }
    }
    if (mcg_spd_solve(5, a, rhs, y) != MCG_OK || !all_finite(y, 5))
        return;
    for (i = 0; i < 3; i++)
        dw[i] = y[i];
    if (!(sqrt(dot3(dw, dw)) <= MAX_START_TURN) ||
        mcg_rot_from_angle_axis(dw, dr) != MCG_OK)
        return;
    mul33(dr, R, rn);
    if (!robust_orthonormalise(rn))
        return;
    /* tc + s u + y3 b1 + y4 b2 on the sphere of radius f |tc| */
    for (i = 0; i < 3; i++)
        tn[i] = tc[i] + sstep * u[i] + y[3] * b1[i] + y[4] * b2[i];
    if (!unit3(tn, tn))
        return;
    mat_vec(rn, cen, rc);
    for (i = 0; i < 3; i++)
        t[i] = f * ntc * tn[i] - rc[i] + cen[i];
    memcpy(R, rn, sizeof rn);
}

/* The scale profile of the final refinement (the statistic of
 * mcgeom.observability.scale_profile): the motion re-optimised on the same
 * pairs with the centroid's translation held at 1/k and k times its length
 * (k = 1 + 3 max_scale_rel_std; rotation and direction free), the smaller
 * cost increase over the free optimum in units of sigma2: a likelihood
 * ratio, ~chi^2 with 1 dof, that sees the non-linearity of near-critical
 * motions where the first-order std does not. 0 when a refit fails.
 * Beyond FINAL_SUB pairs the fits run on a random FINAL_SUB of them, the
 * free one included, and the increase is scaled by m / FINAL_SUB: the cost
 * is a sum over the pairs, so a uniform subset's increase is that fraction
 * of the full one in expectation (its noise, relative ~ 1 / sqrt(FINAL_SUB),
 * matters only near the 9 of the verdict, where the scale of m > 4096 pairs
 * is seldom). Keeps the profile's cost independent of N (issue 19).
 * stop_below (-inf: none): a statistic only compared with that bound; the
 * fits stop once their increase is below it (then an upper bound below
 * it, the decision unchanged; issue 19: the zero profile's fit from 1 % of
 * |t| took up to 50 LM steps, a third of the C time on the Ladybug case). */
double robust_scale_profile(ctx *c, const mcg_robust_result *res, const unsigned char *mask,
                            const double *weights, const double *f, int nf, double stop_below)
{
    double cen[3], worst = INFINITY, rc[3], shift[3], base, gain = 1.0;
    int j, i, m, st = MCG_OK;
    const mcg_refine_result *fr = &res->refinement;
    if (!(isfinite(fr->sigma2) && fr->sigma2 > 0.0))
        return 0.0;
    for (j = 0; j < c->n; j++)
        c->rcur[j] = (mask[j] & 2) ? 0.0 : 1.0;
    m = robust_gather(c, c->rcur, 0.5, weights, cen, 1.0);
    if (m < MIN_REFIT)
        return 0.0;
    base = fr->final_cost;
    if (m > FINAL_SUB) {
        double R[9], t[3];
        mcg_refine_result rr;
        robust_shuffle_head(c, m, FINAL_SUB);
        gain = (double)m / FINAL_SUB;
        m = FINAL_SUB;
        memcpy(R, res->R, sizeof R);
        memcpy(t, res->t, sizeof t);
        if (robust_refine_subset(c, m, cen, weights != NULL, c->opt.loss, res->loss_scale, 0, R, t,
                                 &rr) != MCG_OK)
            return 0.0;
        base = rr.final_cost;
    }
    mat_vec(res->R, cen, rc);
    for (i = 0; i < 3; i++)
        shift[i] = rc[i] - cen[i];
    /* (the fits' costs fall monotonically: below the target the statistic
     * is below stop_below whatever the further steps) */
    c->refine_target = base + stop_below * fr->sigma2 / gain;
    for (j = 0; j < nf; j++) {
        double R[9], t[3];
        mcg_refine_result rr;
        memcpy(R, res->R, sizeof R);
        for (i = 0; i < 3; i++)
            t[i] = (res->t[i] + shift[i]) * f[j] - shift[i];
        if (f[j] >= 0.5 && f[j] <= 2.0) /* (the zero profile's 1 % is beyond the model) */
            profile_start(fr->info, res->t, shift, f[j], cen, R, t);
        st = robust_refine_subset(c, m, cen, weights != NULL, c->opt.loss, res->loss_scale, 1, R, t,
                                  &rr);
        if (st != MCG_OK)
            break;
        worst = fmin(worst, gain * (rr.final_cost - base) / fr->sigma2);
    }
    c->refine_target = -HUGE_VAL;
    if (st != MCG_OK)
        return 0.0;
    return worst > 0.0 ? worst : 0.0;
}

/* res->covariance: sigma2 info^-1 of the final refinement (one Cholesky
 * solve per column), HUGE_VAL everywhere without one or when info is not
 * positive definite; mcgeom.observability.total_scale_std's noise part (the
 * 6 x 6 inverse in numpy cost ~25 us of a cold call's Python: issue 19). */
void robust_fill_covariance(mcg_robust_result *res)
{
    int i, j;
    double e[6], col[6];
    const double s2 = res->refinement.sigma2;
    for (j = 0; j < 6 && res->refined && isfinite(s2); j++) {
        for (i = 0; i < 6; i++)
            e[i] = i == j;
        if (mcg_spd_solve(6, res->refinement.info, e, col) != MCG_OK)
            break;
        for (i = 0; i < 6; i++)
            res->covariance[6 * i + j] = s2 * col[i];
    }
    if (j < 6)
        for (i = 0; i < 36; i++)
            res->covariance[i] = HUGE_VAL;
}
