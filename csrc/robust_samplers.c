/*
 * robust_samplers.c -- the other samples of the robust estimate
 * (csrc/robust.c, issue 21): the upright 4-point with the vertical known
 * (mcg_upright4), the generic 6-point (mcg_sixpt, or the local search of
 * mcg_sixpt_local and the measured rate at which it finds a sample's
 * motion), 17 pairs for Kneip & Li's eigensolver or for linear17; and the
 * dispatch of one sample of the options' sampler (draw).
 */
#include "robust_internal.h"

#include <math.h>
#include <string.h>

/* draws of a 6-point sample before one with two cameras is given up */
#define SAMPLE_TRIES 16

/* The local 6-point sampler (sample_local) and the check of its solver
 * (found_rate) */
#define HOMOTOPY_EVERY 256  /* of its samples, this one solved by mcg_sixpt */
#define FOUND_CHECKS 16     /* samples of the consensus solved */
#define FOUND_PAIRS 64      /* pairs of the consensus they are drawn from */
#define FOUND_AGREE 0.5     /* a hit: a motion with this fraction of the others */
#define FOUND_MIN_OTHERS 10 /* pool pairs besides a sample, at least */

/* The eigensolver sampler (issue 21; PAIRS17 pairs, robust_internal.h)
 * takes at most EIGEN_ITERATIONS LM steps from linear17's rotation, with
 * the no-motion trap below EIGEN_TRAP of the start's travel -- the values
 * of mcgeom.estimators.eigensolver's own RANSAC sample
 * (minimal_solutions). */
#define EIGEN_ITERATIONS 100
#define EIGEN_TRAP 1e-2

/* The options of the samplers: a known sampler, and for the upright one a
 * finite vertical of non-zero length at both times. */
int robust_check_sampler(const mcg_robust_options *o)
{
    if (o->sampler == MCG_SAMPLER_5P1 || o->sampler == MCG_SAMPLER_6PT ||
        o->sampler == MCG_SAMPLER_AUTO || o->sampler == MCG_SAMPLER_EIGEN ||
        o->sampler == MCG_SAMPLER_LINEAR17 || o->sampler == MCG_SAMPLER_6PT_LOCAL)
        return 1;
    if (o->sampler != MCG_SAMPLER_UPRIGHT4)
        return 0;
    return all_finite(o->g1, 3) && all_finite(o->g2, 3) && dot3(o->g1, o->g1) >= 1e-100 &&
           dot3(o->g2, o->g2) >= 1e-100;
}

/* m distinct pairs drawn uniformly into idx (m <= PAIRS17) from the np
 * distinct pairs of pool (NULL: all n, np = n; np >= m).
 * `central`: 1 when all of them are intra-camera pairs of one camera (rays
 * from one centre: no metric scale, the solvers are degenerate there). */
static void draw_distinct(ctx *c, int m, const int *pool, int np, int *idx, int *central)
{
    int j, i;
    for (j = 0; j < m; j++) {
        int k, dup;
        do { /* rejection of repeats: m <= 17 of np >= m */
            k = rng_below(&c->rng, np);
            k = pool ? pool[k] : k;
            dup = 0;
            for (i = 0; i < j; i++)
                dup |= idx[i] == k;
        } while (dup);
        idx[j] = k;
    }
    *central = 1;
    for (j = 0; j < m; j++)
        *central &= c->cam1[idx[j]] == c->cam2[idx[j]] && c->cam1[idx[j]] == c->cam1[idx[0]];
}

/* Copy the pairs idx[0..m) into the m x 3 arrays a1, b1, a2, b2. */
static void copy_pairs(const ctx *c, const int *idx, int m, double *a1, double *b1,
                       double *a2, double *b2)
{
    int j, i;
    for (j = 0; j < m; j++)
        for (i = 0; i < 3; i++) {
            a1[3 * j + i] = c->o1[3 * (size_t)idx[j] + i];
            b1[3 * j + i] = c->d1[3 * (size_t)idx[j] + i];
            a2[3 * j + i] = c->o2[3 * (size_t)idx[j] + i];
            b2[3 * j + i] = c->d2[3 * (size_t)idx[j] + i];
        }
}

/* A sample of m distinct pairs of pool (as draw_distinct's) drawn
 * uniformly into idx and copied into the m x 3 arrays a1, b1, a2, b2: 1; 0
 * when every one of SAMPLE_TRIES draws was central (all pairs intra-camera
 * pairs of one camera: its rotation may be determined but not |t|, the
 * solvers find it degenerate); -1 when there are fewer than m pairs. */
static int draw_sample_of(ctx *c, int m, const int *pool, int np, int *idx, double *a1,
                          double *b1, double *a2, double *b2)
{
    int tries, central = 1;
    if (np < m)
        return -1;
    for (tries = 0; tries < SAMPLE_TRIES && central; tries++)
        draw_distinct(c, m, pool, np, idx, &central);
    if (central)
        return 0;
    copy_pairs(c, idx, m, a1, b1, a2, b2);
    return 1;
}

/* draw_sample_of all pairs */
static int draw_sample(ctx *c, int m, int *idx, double *a1, double *b1, double *a2,
                       double *b2)
{
    return draw_sample_of(c, m, NULL, c->n, idx, a1, b1, a2, b2);
}

/* 1 when (R, t) satisfies the constraint of one of the m sample pairs
 * (origins a1 -> a2) trivially: the constraint reads d2 . (g x R d1) = 0
 * with g = R a1 + t - a2 (thesis eq. 8.16 with m = o x d), which holds for
 * any rays when g = 0 -- that pair's camera only rotated about its centre.
 * Such a solution used fewer constraints than the sample has: e.g. the
 * static rig (R = I, t = 0) solves every upright sample of intra-camera
 * pairs when the vertical did not tilt (a car on flat ground) and explains
 * every intra-camera pair, outliers too (seen on the car rig: 320 of 320
 * "inliers" at t = 0). */
static int trivial(const ctx *c, const double R[9], const double t[3], const double *a1,
                   const double *a2, int m)
{
    const double tol = 1e-7 * (c->size + sqrt(dot3(t, t)));
    int k, i;
    for (k = 0; k < m; k++) {
        double g[3];
        mat_vec(R, a1 + 3 * k, g);
        for (i = 0; i < 3; i++)
            g[i] += t[i] - a2[3 * k + i];
        if (dot3(g, g) <= tol * tol)
            return 1;
    }
    return 0;
}

/* 1 when every sample pair (a1, b1) -> (a2, b2) whose rays are not
 * parallel triangulates in front of both cameras under (R, t):
 * s1 R b1 + (R a1 + t - a2) = s2 b2 with s1, s2 > 0 at the closest points
 * (the cheirality that picks 5+1's candidates, issue 18). A minimal solver
 * returns every real root; those with a point behind a camera are no
 * motion of the rig (seen with the upright solver on the car rig turning
 * with a vertical 0.2 deg off: t backwards and 0.04 of the truth won). */
static int in_front(const double R[9], const double t[3], const double *a1, const double *b1,
                    const double *a2, const double *b2, int m)
{
    int k;
    for (k = 0; k < m; k++) {
        int f = robust_pair_in_front(R, t, a1 + 3 * k, b1 + 3 * k, a2 + 3 * k, b2 + 3 * k);
        if (f == 0 || f == -2) /* (parallel rays pass) */
            return 0;
    }
    return 1;
}

/* Offer the ns solutions (R: ns x 9, t: ns x 3) of a minimal solver on the
 * m sample pairs idx (origins a1 -> a2): each re-orthonormalised
 * (mcg_refine_motion rejects a rotation off by 1e-6), skipped when not
 * finite, trivial for a pair or with a pair behind a camera (in_front).
 * When the sample has an intra-camera pair
 * (camera a, centre c_a) the solution is offered as a 5+1 one on camera
 * a's line t(lam) = t0 + lam u, t0 = c_a - R c_a, u = (t - t0) / |t - t0|,
 * lam = |t - t0| (the same motion), so that a new best gets the 1-point
 * scale search of offer: where intra-camera pairs hardly fix |t| (a car
 * driving forward or turning a little) the sample's own |t| is as weakly
 * determined as a 5+1 sample's, and the yaw of an upright sample with a
 * vertical off by 0.2 deg came with a wrong |t| that the local
 * optimisation, which holds |t|, kept (measured on the car rig turning:
 * 75-84 % inliers and scale errors of 0.26-0.96 where 5+1 had 96 %, 0.02).
 * Returns the count offered. */
static int offer_solutions(ctx *c, const double *Rs, const double *ts, int ns, const int *idx,
                           const double *a1, const double *b1, const double *a2,
                           const double *b2, int m, const double *w)
{
    int j, k, a = -1, offered = 0;
    for (k = 0; k < m && a < 0; k++)
        if (c->cam1[idx[k]] == c->cam2[idx[k]])
            a = k;
    for (j = 0; j < ns; j++) {
        double R[9], t0[3], u[3], lam;
        const double *t = ts + 3 * j;
        memcpy(R, Rs + 9 * j, sizeof R);
        if (!all_finite(R, 9) || !all_finite(t, 3) || !robust_orthonormalise(R) ||
            trivial(c, R, t, a1, a2, m) || !in_front(R, t, a1, b1, a2, b2, m))
            continue;
        offered++;
        if (a >= 0) {
            mat_vec(R, a1 + 3 * a, t0);
            for (k = 0; k < 3; k++) {
                t0[k] = a1[3 * a + k] - t0[k];
                u[k] = t[k] - t0[k];
            }
            lam = sqrt(dot3(u, u));
            if (lam > 0.0 && unit3(u, u)) {
                robust_offer(c, R, t0, u, lam, w, c->cam1[idx[a]]);
                continue;
            }
        }
        robust_offer_motion(c, R, t, w);
    }
    return offered;
}

/* One upright or 6-point sample: m distinct pairs (4 with the vertical
 * known -> mcg_upright4 with opt.g1, opt.g2, Sweeney et al. 2014, Lee et al.
 * 2014; else 6 -> mcg_sixpt, the generic minimal solver, Stewenius et al.
 * 2005), drawn uniformly: with outliers spread evenly an all-inlier sample
 * is as likely as anywhere, and a rig with few pairs per camera (where 5+1
 * has no 5-point camera) is covered as evenly as its pairs are. A central
 * sample is redrawn (draw_sample). */
static int sample_minimal(ctx *c, const double *w)
{
    const int upright = c->opt.sampler == MCG_SAMPLER_UPRIGHT4, m = upright ? 4 : 6;
    const int max_sol = upright ? MCG_UPRIGHT4_MAX_SOLUTIONS : MCG_SIXPT_MAX_SOLUTIONS;
    int idx[6], ns = 0, st;
    double a1[18], b1[18], a2[18], b2[18];
    if (draw_sample(c, m, idx, a1, b1, a2, b2) <= 0)
        return 0;
    st = upright ? mcg_upright4(a1, b1, a2, b2, c->opt.g1, c->opt.g2, c->msol,
                                c->msol + 9 * max_sol, &ns)
                 : mcg_sixpt(a1, b1, a2, b2, c->msol, c->msol + 9 * max_sol, &ns);
    if (st != MCG_OK)
        return 0;
    return offer_solutions(c, c->msol, c->msol + 9 * max_sol, ns, idx, a1, b1, a2, b2, m, w);
}

/* |t + R g - g|: how far the motion (R, t) carries g (metres) */
static double travel(const double R[9], const double t[3], const double g[3])
{
    double v[3];
    int i;
    mat_vec(R, g, v);
    for (i = 0; i < 3; i++)
        v[i] += t[i] - g[i];
    return sqrt(dot3(v, v));
}

/* One eigensolver sample (MCG_SAMPLER_EIGEN): PAIRS17 distinct pairs drawn
 * uniformly (a central sample redrawn as in sample_minimal) -> the rotation
 * of mcg_linear17 without its refinement -> mcg_eigensolver from it (Kneip
 * and Li, "Efficient computation of relative pose for multi-camera
 * systems", CVPR 2014: the rotation minimising the smallest eigenvalue of
 * the generalized-epipolar matrix, t its eigenvector). Near pure forward
 * motion with intra-camera rays that eigenvalue also vanishes at R = I,
 * t = 0 (every such ray fits the resting rig), and the minimiser can slide
 * there: a result whose centroid of origins travels less than EIGEN_TRAP
 * of the start's is that trap, and the start (0 steps) is offered instead.
 * A motion without a metric t (no rotation with intra-camera rays only) is
 * no hypothesis. As mcgeom.estimators.eigensolver.minimal_solutions, which
 * drives mcgeom.robust's Python search. The workspace of mcg_eigensolver
 * is c->msol (sample_work_size). */
static int sample_eigen(ctx *c, const double *w)
{
    int idx[PAIRS17], has_scale, has0, its, k, i, got;
    double a1[3 * PAIRS17], b1[3 * PAIRS17], a2[3 * PAIRS17], b2[3 * PAIRS17];
    double R[9], t[3], R0[9], t0[3], g[3] = {0.0, 0.0, 0.0}, lmin;
    mcg_linear17_options lo;
    mcg_linear17_result lr;
    if ((got = draw_sample(c, PAIRS17, idx, a1, b1, a2, b2)) <= 0)
        return got;
    mcg_linear17_default_options(&lo);
    lo.refine = 0;
    if (mcg_linear17(PAIRS17, a1, b1, a2, b2, &lo, &lr) != MCG_OK ||
        mcg_eigensolver(PAIRS17, a1, b1, a2, b2, lr.R, EIGEN_ITERATIONS, R, t, &lmin,
                        &has_scale, &its, c->msol, robust_sample_work_size()) != MCG_OK ||
        !has_scale)
        return 0;
    for (k = 0; k < PAIRS17; k++)
        for (i = 0; i < 3; i++)
            g[i] += (a1[3 * k + i] + a2[3 * k + i]) / (2.0 * PAIRS17);
    if (mcg_eigensolver(PAIRS17, a1, b1, a2, b2, lr.R, 0, R0, t0, &lmin, &has0, &its, c->msol,
                        robust_sample_work_size()) == MCG_OK &&
        has0 && travel(R, t, g) < EIGEN_TRAP * travel(R0, t0, g)) {
        memcpy(R, R0, sizeof R);
        memcpy(t, t0, sizeof t);
    }
    return offer_solutions(c, R, t, 1, idx, a1, b1, a2, b2, PAIRS17, w);
}

/* One linear 17-point sample (MCG_SAMPLER_LINEAR17): PAIRS17 distinct pairs
 * drawn as sample_eigen's -> the motion of mcg_linear17 with its default
 * refinement (thesis ch. 8: the generalized essential matrix from the 17 x
 * 18 linear system, R by its constrained decomposition, t by the least
 * squares of eq. 8.15, then the Sampson optimum of the 17 pairs, ch.
 * 8.4.3). The refinement is kept because eq. 8.15's |t| on 17 noisy pairs
 * is biased towards 0 (errors in variables) and the local optimisation
 * holds |t|: without it, on 20 pairs with 2 outliers (test_robust.c's
 * few-pairs scene) the search ended 1.3 deg and 88 % off in |t| with both
 * outliers flagged; on the Ladybug head with 30 % outliers (40 problems,
 * 1000 samples) the median scale error was 0.26 against 0.17 with it (5+1:
 * 0.17), for 23 against 64 us a sample. Its metric t is offered whether
 * or not the sample alone makes it trustworthy (17 pairs rarely do: the
 * consensus judges it); a sample whose t is not determined at all
 * (t_metric 0) gives no hypothesis. */
static int sample_linear17(ctx *c, const double *w)
{
    int idx[PAIRS17], got;
    double a1[3 * PAIRS17], b1[3 * PAIRS17], a2[3 * PAIRS17], b2[3 * PAIRS17];
    const double *t;
    mcg_linear17_options lo;
    mcg_linear17_result lr;
    if ((got = draw_sample(c, PAIRS17, idx, a1, b1, a2, b2)) <= 0)
        return got;
    mcg_linear17_default_options(&lo);
    if (mcg_linear17(PAIRS17, a1, b1, a2, b2, &lo, &lr) != MCG_OK)
        return 0;
    t = lr.scale_observable ? lr.t : lr.t_metric;
    if (!(dot3(t, t) > 0.0))
        return 0;
    return offer_solutions(c, lr.R, t, 1, idx, a1, b1, a2, b2, PAIRS17, w);
}

/* One local 6-point sample (MCG_SAMPLER_6PT_LOCAL): 6 pairs drawn as
 * sample_minimal's -> mcg_sixpt_local from its fixed starts and, once the
 * search has a best motion, from it too (an all-inlier sample's motion then
 * lies next to it) -> its motions offered as sample_minimal's. Every
 * HOMOTOPY_EVERY-th sample is solved by the complete mcg_sixpt instead: a
 * motion no start reaches is still found (a planar ring turned by 180 deg
 * with cross-camera pairs only: the local search found it in none of 10
 * samples, from 1e-3 rad away only from the truth itself), at ~0.1 ms a
 * sample on average (1 in 64 cost the 12-camera case of `mcgeom experiment
 * peer_solvers` about a third of its time). */
static int sample_local(ctx *c, const double *w)
{
    int idx[6], ns = 0, got;
    double a1[18], b1[18], a2[18], b2[18];
    if (++c->local_samples % HOMOTOPY_EVERY == 0)
        return sample_minimal(c, w); /* (c->opt.sampler read there: the homotopy) */
    if ((got = draw_sample(c, 6, idx, a1, b1, a2, b2)) <= 0)
        return got;
    if (mcg_sixpt_local(a1, b1, a2, b2, c->have ? c->R : NULL, c->msol,
                        c->msol + 9 * MCG_SIXPT_LOCAL_MAX_SOLUTIONS, &ns) != MCG_OK)
        return 0;
    return offer_solutions(c, c->msol, c->msol + 9 * MCG_SIXPT_LOCAL_MAX_SOLUTIONS, ns, idx,
                           a1, b1, a2, b2, 6, w);
}

/* How often mcg_sixpt_local finds the motion of a sample of inliers, measured
 * on this data (MCG_SAMPLER_6PT_LOCAL; the adaptive stop and the confidence
 * count an all-inlier sample as found with this chance, so an incomplete
 * solver draws more samples instead of stopping early): FOUND_CHECKS
 * samples of 6 distinct pairs (not all of one camera) drawn from FOUND_PAIRS
 * pairs of the best's consensus (a uniform reservoir sample of the pairs
 * within the threshold), each solved from the fixed starts only -- as a
 * sample drawn before any consensus was -- and a hit when one of its
 * motions puts FOUND_AGREE of the other pool pairs within WIDE thresholds.
 * Returns (hits + 1/2) / (checks + 1) (a Jeffreys-like estimate, never 0 or
 * 1), or 1/2 when the consensus is too small to draw checks from. */
double robust_found_rate(ctx *c)
{
    int pool[FOUND_PAIRS], np = 0, seen = 0, k, s, hits = 0, checks = 0;
    for (k = 0; k < c->n; k++)
        if (c->rbest[k] < c->opt.threshold) {
            seen++;
            if (np < FOUND_PAIRS)
                pool[np++] = k;
            else {
                int j = rng_below(&c->rng, seen);
                if (j < FOUND_PAIRS)
                    pool[j] = k;
            }
        }
    if (np < 6 + FOUND_MIN_OTHERS)
        return 0.5;
    for (s = 0; s < FOUND_CHECKS; s++) {
        int idx[6], ns = 0, j, i;
        double a1[18], b1[18], a2[18], b2[18];
        if (draw_sample_of(c, 6, pool, np, idx, a1, b1, a2, b2) <= 0)
            continue; /* a consensus of one camera's pairs: no 6-point sample */
        checks++;
        if (mcg_sixpt_local(a1, b1, a2, b2, NULL, c->msol,
                            c->msol + 9 * MCG_SIXPT_LOCAL_MAX_SOLUTIONS, &ns) != MCG_OK)
            continue;
        for (j = 0; j < ns; j++) {
            const double *R = c->msol + 9 * j, *t = c->msol + 9 * MCG_SIXPT_LOCAL_MAX_SOLUTIONS +
                                                     3 * j;
            int agree = 0;
            for (i = 0; i < np; i++) {
                int in_sample = 0, q;
                for (q = 0; q < 6; q++)
                    in_sample |= idx[q] == pool[i];
                agree += !in_sample &&
                         pair_residual(c, R, t, (size_t)pool[i]) < WIDE * c->opt.threshold;
            }
            if (agree >= FOUND_AGREE * (np - 6)) {
                hits++;
                break;
            }
        }
    }
    return checks > 0 ? (hits + 0.5) / (checks + 1.0) : 0.5;
}

/* One sample of the options' sampler: the hypotheses offered, or -1 when
 * the data can never give one (5+1: no camera with 5 intra-camera pairs;
 * the eigensolver and linear17: fewer than 17 pairs). */
int robust_draw(ctx *c, const double *w)
{
    if (c->central_m > 0)
        return robust_sample(c, w);
    switch (c->opt.sampler) {
    case MCG_SAMPLER_EIGEN:
        return sample_eigen(c, w);
    case MCG_SAMPLER_LINEAR17:
        return sample_linear17(c, w);
    case MCG_SAMPLER_6PT_LOCAL:
        return sample_local(c, w);
    default:
        return sample_minimal(c, w);
    }
}
