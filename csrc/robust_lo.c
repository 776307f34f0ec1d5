/*
 * robust_lo.c -- the refinements inside the robust estimate (csrc/robust.c):
 * gathering a subset of the pairs into the workspace (shifted to their
 * centroid), mcg_refine_motion on it, and the local optimisation of a new
 * best (LO-RANSAC, Chum, Matas & Kittler 2003; Lebeda, Matas & Chum 2012):
 * the best motion re-estimated on its inliers while its MSAC score improves.
 */
#include "robust_internal.h"

#include <math.h>
#include <string.h>

/* inliers the local optimisation fits at most (a random subset beyond):
 * LO improves a hypothesis, whose consensus is then scored on all pairs;
 * a few thousand inliers fix six parameters to far below the noise, and
 * the cap keeps its cost independent of N (Lebeda, Matas & Chum 2012 cap
 * the inner sample of LO-RANSAC likewise). The final refinement uses all.
 * 1024 rather than 4096 (issue 19; measured on the scaling bench: C time at
 * 1e4 pairs 35 -> 19 ms, at 1e6 0.67 -> 0.45 s, rotation errors unchanged),
 * then 256: LO's LM steps were a fifth of the pair evaluations at 1e3 pairs
 * (~800 inliers); 256 inliers still pin the six parameters to ~1.8x the
 * final std, which is all LO needs to find the consensus (30 problems of
 * the scaling bench at 1e3: median rotation error 0.0139 -> 0.0134 deg,
 * scale error 0.0175 -> 0.0176). */
#define LO_MAX 256
/* steps on all pairs after converging on FINAL_SUB of them (robust_internal.h) */
#define FINAL_POLISH 3

/* Steps of the local optimisation's refinement: LO only has to improve the
 * inlier set (the final stage converges on all of them); the LM runs of LO
 * stopped after 6-12 steps at the 1e-10 tolerance, for changes far below
 * the noise after the first few. */
#define LO_ITERATIONS 8

/* The upright sampler's hypotheses carry the error of the given vertical (an
 * IMU's 0.1-0.5 deg: pixels at the threshold): their inliers at one
 * threshold are a biased few, and a local optimisation on them stopped
 * short of the consensus (car rig turning, vertical 0.2 deg off: MSAC
 * scores at twice the optimum's, 130-160 samples drawn before the adaptive
 * stop instead of ~5). So the first round of their local optimisation
 * gathers the pairs within LO_WIDE thresholds (the Cauchy loss bounds the
 * outliers' pull: the widened first step of Lebeda, Matas and Chum's LO+,
 * BMVC 2012); |t| stays held. Measured, the vertical 0.2 deg off: mean
 * samples (40 problems) Ladybug 30 % outliers 49.1 -> 46.8, car rig
 * forward 20 % outliers 158.8 -> 67.0, turning 31.7 -> 19.6; on the car rig
 * driving forward (`mcgeom experiment ch7 --trials 1200 --seed 10 --cross
 * 0 0.1 0.3 --vertical-error-deg 0.2`: yaw < 2 deg, 1 px, 10 % outliers),
 * estimates more than 30 % off in |t| yet reported observable 2 / 57 / 29
 * -> 7 / 1 / 0 (with final_scale_search; those without cross-camera pairs
 * were a search failure at |t| 1-3 % of the truth with ~50 % of the pairs
 * as inliers where the true motion has ~90 %: -> 1 / 1 / 0 with the scale
 * search on all pairs, see final_scale_search). Freeing |t| as well
 * drew fewer samples (Ladybug 29.4) but slid to such wrong scales more
 * often. For 5+1 the widened round changed the real-data results (KITTI
 * raw, intra-camera pairs: 1.1 deg rotation error) and is not used. */
#define LO_WIDE 4.0

/* Convergence of the refinements (LO, scale profile): a step that
 * lowers the cost by less than REFINE_TOL sigma^2 (sigma^2 ~ the cost per
 * pair) ends the LM run. Near the optimum the cost excess is
 * dx^T H dx / 2, so the motion is then within ~sqrt(2 REFINE_TOL q / (1 - q))
 * of its standard deviation of the optimum (q ~ 0.1-0.2, the linear rate of
 * the IRLS steps of a Cauchy loss), and a profile's cost increase, which
 * the verdict compares with 9 sigma^2, within ~1e-3 sigma^2. The default
 * relative 1e-10 of mcg_refine_motion took 9-16 steps per fit where 4-8
 * reach this (issue 19: refinements were ~2/3 of the C time at 1e3 pairs).
 * Not the final refinement's first fit: where |t| is unobservable its cost
 * is flat along |t| and where it stops decides how far it slides, which the
 * verdict in Python judges (an exactly critical motion converged at
 * another |t| than 50 steps of the tight tolerance reached); it keeps the
 * default, and so does its refit unless the first fit found |t| determined. */
#define REFINE_TOL 1e-3

/* Gather the pairs with sel(k) into the subset buffers, shifted to their
 * centroid cen (the frame of mcgeom.geometry.refine_centred: |t| held by
 * fix_scale is then the centroid's travel, independent of the rig origin),
 * with weights w(k) (NULL: all 1). Returns the count. */
int robust_gather(ctx *c, const double *res, double limit, const double *w, double cen[3],
                  double keep)
{
    int k, m = 0, i;
    /* keep < 1: each selected pair is taken with that probability */
    const uint64_t cut = keep < 1.0 ? (uint64_t)(keep * 18446744073709551615.0) : UINT64_MAX;
    double *so1 = c->sub, *so2 = c->sub + 6 * (size_t)c->n;
    /* rows from n - nsub on hold the preemptive subset during the search
     * (LO gathers ~LO_MAX of the inliers, but the upright sampler's first
     * round takes every pair within LO_WIDE thresholds of a poor hypothesis,
     * which can be many more) */
    const int rows = c->n - c->nsub;
    cen[0] = cen[1] = cen[2] = 0.0;
    for (k = 0; k < c->n && m < rows; k++) {
        if (!(res[k] < limit) || (cut != UINT64_MAX && rng_next(&c->rng) > cut))
            continue;
        robust_copy_pair(c, (size_t)k, m);
        for (i = 0; i < 3; i++)
            cen[i] += c->o1[3 * k + i] + c->o2[3 * k + i];
        c->wsub[m] = w ? w[k] : 1.0;
        m++;
    }
    if (m == 0)
        return 0;
    for (i = 0; i < 3; i++)
        cen[i] /= 2.0 * m;
    for (k = 0; k < m; k++)
        for (i = 0; i < 3; i++) {
            so1[3 * k + i] -= cen[i];
            so2[3 * k + i] -= cen[i];
        }
    return m;
}

/* refine_subset with at most max_iterations steps. */
static int refine_steps(ctx *c, int m, const double cen[3], int weighted, int loss,
                        double scale, int fix_scale, int max_iterations, double R[9],
                        double t[3], mcg_refine_result *out)
{
    mcg_refine_options ro;
    double tc[3], rc[3];
    int st, i;
    mcg_refine_default_options(&ro);
    ro.max_iterations = max_iterations;
    /* converged once a step lowers the cost by less than REFINE_TOL of its
     * mean per pair (~ the residual variance in the cost's unit) */
    if (!c->final_stage)
        ro.cost_tolerance = REFINE_TOL / m;
    ro.loss = loss;
    ro.loss_scale = scale;
    ro.fix_scale = fix_scale;
    mat_vec(R, cen, rc);
    for (i = 0; i < 3; i++)
        tc[i] = t[i] + rc[i] - cen[i];
    if (fix_scale && !(dot3(tc, tc) > 0.0))
        return MCG_EDEGENERATE;
    st = mcg_refine_motion_until(m, c->sub, c->sub + 3 * (size_t)c->n,
                                 c->sub + 6 * (size_t)c->n, c->sub + 9 * (size_t)c->n,
                                 weighted ? c->wsub : NULL, &ro, c->refine_target, R, tc, out);
    if (st != MCG_OK)
        return st;
    mat_vec(R, cen, rc);
    for (i = 0; i < 3; i++)
        t[i] = tc[i] - rc[i] + cen[i];
    return MCG_OK;
}

/* mcg_refine_motion on the gathered m pairs, (R, t) in the rig frame
 * (converted to and from the centroid frame: t' = t + R c - c). */
int robust_refine_subset(ctx *c, int m, const double cen[3], int weighted, int loss,
                         double scale, int fix_scale, double R[9], double t[3],
                         mcg_refine_result *out)
{
    mcg_refine_options ro;
    mcg_refine_default_options(&ro);
    return refine_steps(c, m, cen, weighted, loss, scale, fix_scale, ro.max_iterations, R, t,
                        out);
}

/* Move a uniform random choice of k of the m gathered pairs (and their
 * weights) to the front of the subset buffers (partial Fisher-Yates). */
void robust_shuffle_head(ctx *c, int m, int k)
{
    const size_t n = (size_t)c->n;
    int j, i;
    for (j = 0; j < k; j++) {
        int r = j + rng_below(&c->rng, m - j);
        double tmp;
        if (r == j)
            continue;
        for (i = 0; i < 12; i++) { /* o1 d1 o2 d2: 4 blocks of 3 n */
            double *a = c->sub + (size_t)(i / 3) * 3 * n + 3 * (size_t)j + (size_t)(i % 3);
            double *b = c->sub + (size_t)(i / 3) * 3 * n + 3 * (size_t)r + (size_t)(i % 3);
            tmp = *a;
            *a = *b;
            *b = tmp;
        }
        tmp = c->wsub[j];
        c->wsub[j] = c->wsub[r];
        c->wsub[r] = tmp;
    }
}

/* refine_subset with the cost per pair bounded in m (FINAL_SUB): beyond
 * FINAL_SUB pairs, converge on a random FINAL_SUB of them, then polish on
 * all m with FINAL_POLISH steps (the statistics in *out are those of all m;
 * its iterations count both runs). Reorders the gathered pairs. */
int robust_refine_capped(ctx *c, int m, const double cen[3], int weighted, int loss,
                         double scale, int fix_scale, double R[9], double t[3],
                         mcg_refine_result *out)
{
    mcg_refine_result first;
    int st;
    if (m <= FINAL_SUB)
        return robust_refine_subset(c, m, cen, weighted, loss, scale, fix_scale, R, t, out);
    robust_shuffle_head(c, m, FINAL_SUB);
    st = robust_refine_subset(c, FINAL_SUB, cen, weighted, loss, scale, fix_scale, R, t, &first);
    if (st != MCG_OK)
        return st;
    st = refine_steps(c, m, cen, weighted, loss, scale, fix_scale, FINAL_POLISH, R, t, out);
    if (st == MCG_OK)
        out->iterations += first.iterations;
    return st;
}

/* Weights (focal_k / median)^2 of the fixed pixel scaling, or NULL when
 * every focal is the same (or there is none). */
const double *robust_fixed_weights(ctx *c)
{
    int k;
    if (!c->focal || c->const_focal)
        return NULL;
    for (k = 0; k < c->n; k++) {
        double f = c->focal[k] / c->med_focal;
        c->fsc[k] = f * f;
    }
    return c->fsc;
}

/* Local optimisation of the best motion (thesis ch. 8.5's refinement used as
 * LO): re-estimated on its inliers (the upright sampler's first round:
 * within LO_WIDE thresholds) with the length of the centroid's translation
 * held (near the critical motion a free fit slides |t|; the final stage
 * frees it), Cauchy loss, kept while the MSAC score improves. */
void robust_local_optimise_held(ctx *c, const double *w, int hold)
{
    const double wide = c->opt.sampler == MCG_SAMPLER_UPRIGHT4 ? LO_WIDE : 1.0;
    int round;
    for (round = 0; round < c->lo_rounds; round++) {
        double R[9], t[3], cen[3], sc;
        int m, n_inl, n_wide, same, k;
        mcg_refine_result rr;
        if (c->n_inl < MIN_REFIT)
            return;
        m = robust_gather(c, c->rbest, c->opt.threshold * (round == 0 ? wide : 1.0), w, cen,
                          c->n_inl > LO_MAX ? (double)LO_MAX / c->n_inl : 1.0);
        if (m < MIN_REFIT)
            return;
        memcpy(R, c->R, sizeof R);
        memcpy(t, c->t, sizeof t);
        c->n_lo++;
        if (refine_steps(c, m, cen, w != NULL, MCG_LOSS_CAUCHY, c->loss_scale, hold,
                         LO_ITERATIONS, R, t, &rr) != MCG_OK)
            return;
        sc = robust_msac2(c, R, t, c->score * (1.0 - 1e-9), &n_inl, &n_wide);
        if (!(sc < c->score * (1.0 - 1e-9)))
            return;
        same = 1;
        for (k = 0; k < c->n && same; k++)
            same = (c->rcur[k] < c->opt.threshold) == (c->rbest[k] < c->opt.threshold);
        robust_take_best(c, R, t, sc, n_inl, n_wide);
        if (same) /* the same inliers would give the same fit again */
            return;
    }
}

void robust_local_optimise(ctx *c, const double *w) { robust_local_optimise_held(c, w, 1); }
