/*
 * robust_score.c -- the scoring of the robust estimate (csrc/robust.c):
 * the MSAC score of a motion over all pairs (Torr & Zisserman 2000: each
 * squared residual capped at the squared threshold), the best motion so far
 * and the per-camera records of the two-stage 5+1 (REC_PAIRS), and the
 * preemptive scoring of large inputs on a fixed random subset (Nister 2003;
 * Chum & Matas 2002).
 */
#include "robust_internal.h"

#include <math.h>
#include <string.h>

/* Preemptive scoring (issue 19; cf. the preemptive and randomised RANSAC of
 * Nister 2003 and Chum & Matas 2002): with at least PREEMPT_MIN pairs, a
 * hypothesis is first scored on a fixed random subset of PREEMPT_SUB pairs
 * and scored on all of them only when it beats the best one there too. A
 * bad hypothesis then costs PREEMPT_SUB residuals whatever N; the best one
 * (and so LO, the adaptive stop and the final stage) is still decided on
 * all pairs. The subset lives in the tail of the refinements' gather
 * buffers, which LO (at most ~LO_MAX pairs) does not reach during the search
 * (gather stops short of it). From 4096 pairs rather than 16384 (issue 19:
 * at 1e4 pairs every hypothesis was scored on all of them; the scaling
 * bench's ring at 1e4, with SCALE_PAIRS 512, C instructions per estimate
 * 47.2 -> 39.5 M, median scale error over 30 problems 0.0062 -> 0.0044,
 * rotation 0.0039 -> 0.0039 deg). */
#define PREEMPT_SUB 2048

/* MSAC score of (R, t) over all pairs (rcur receives |r| in the threshold's
 * unit); stops early and returns +inf once the partial sum reaches `bound`.
 * *n_inl: residuals below the threshold, *n_wide below WIDE thresholds (when
 * completed). */
double robust_msac2(ctx *c, const double R[9], const double t[3], double bound, int *n_inl,
                    int *n_wide)
{
    double s = 0.0, w2 = WIDE * WIDE * c->thr2;
    int k0, k, m = 0, mw = 0;
    for (k0 = 0; k0 < c->n; k0 += SCORE_BLOCK) {
        int nb = c->n - k0 < SCORE_BLOCK ? c->n - k0 : SCORE_BLOCK;
        double *r = c->rcur + k0;
        if (mcg_gec_residuals(nb, c->o1 + 3 * k0, c->d1 + 3 * k0, c->o2 + 3 * k0,
                              c->d2 + 3 * k0, R, t, r) != MCG_OK)
            return INFINITY;
        for (k = 0; k < nb; k++) {
            double a = fabs(r[k]) * (c->focal ? c->focal[k0 + k] : 1.0), z = a * a;
            r[k] = a;
            m += z < c->thr2;
            mw += z < w2;
            s += z < c->thr2 ? z : c->thr2;
        }
        if (s >= bound)
            return INFINITY;
    }
    *n_inl = m;
    *n_wide = mw;
    return s;
}

double robust_msac(ctx *c, const double R[9], const double t[3], double bound, int *n_inl)
{
    int mw;
    return robust_msac2(c, R, t, bound, n_inl, &mw);
}

/* Copy a stratified random subset of PREEMPT_SUB pairs (one from each of
 * PREEMPT_SUB equal runs of the input order: distinct, each pair equally
 * likely) to the tail of the gather buffers, with their focal lengths. */
void robust_preempt_setup(ctx *c)
{
    const size_t n = (size_t)c->n, s = PREEMPT_SUB, row = n - s;
    int j, i;
    c->nsub = 0;
    if (c->n < PREEMPT_MIN)
        return;
    for (j = 0; j < PREEMPT_SUB; j++) {
        size_t lo = (size_t)j * n / s, hi = (size_t)(j + 1) * n / s;
        size_t k = lo + (size_t)rng_below(&c->rng, (int)(hi - lo));
        for (i = 0; i < 3; i++) {
            c->sub[3 * (row + j) + i] = c->o1[3 * k + i];
            c->sub[3 * n + 3 * (row + j) + i] = c->d1[3 * k + i];
            c->sub[6 * n + 3 * (row + j) + i] = c->o2[3 * k + i];
            c->sub[9 * n + 3 * (row + j) + i] = c->d2[3 * k + i];
        }
        c->wsub[row + j] = c->focal ? c->focal[k] : 1.0;
    }
    c->nsub = PREEMPT_SUB;
    c->best_sub = INFINITY;
}

/* MSAC score of (R, t) on the preemptive subset (residuals into rcur, as
 * scratch); +inf once the partial sum reaches `bound`. */
static double msac_sub(ctx *c, const double R[9], const double t[3], double bound)
{
    const size_t n = (size_t)c->n, row = n - (size_t)c->nsub;
    double s = 0.0;
    int k0, k;
    for (k0 = 0; k0 < c->nsub; k0 += SCORE_BLOCK) {
        int nb = c->nsub - k0 < SCORE_BLOCK ? c->nsub - k0 : SCORE_BLOCK;
        size_t at = 3 * (row + (size_t)k0);
        double *r = c->rcur + k0;
        if (mcg_gec_residuals(nb, c->sub + at, c->sub + 3 * n + at, c->sub + 6 * n + at,
                              c->sub + 9 * n + at, R, t, r) != MCG_OK)
            return INFINITY;
        for (k = 0; k < nb; k++) {
            double a = fabs(r[k]) * c->wsub[row + (size_t)(k0 + k)], z = a * a;
            s += z < c->thr2 ? z : c->thr2;
        }
        if (s >= bound)
            return INFINITY;
    }
    return s;
}

/* Preemptive rejection (from PREEMPT_MIN pairs, once there is a best): is
 * (R, t) no better than the best on the subset? */
int robust_preempted(ctx *c, const double R[9], const double t[3])
{
    return c->nsub > 0 && c->have && !(msac_sub(c, R, t, c->best_sub) < c->best_sub);
}

/* A new best raises each camera's record to its own inlier count on that
 * camera's subset: a later 5-point motion has its scale searched only if
 * more of that camera's pairs agree with it than with the best. */
static void records_of_best(ctx *c)
{
    int a, j;
    for (a = 0; a < c->ncam; a++) {
        int m = 0;
        for (j = c->rec_off[a]; j < c->rec_off[a + 1]; j++)
            m += c->rbest[c->rec_idx[j]] < WIDE * c->opt.threshold;
        if (m > c->rec[a])
            c->rec[a] = m;
    }
}

/* Each camera's subset for the records: REC_PAIRS of its intra-camera
 * pairs (all when it has fewer), one from the middle of each of that many
 * equal runs of the input order; no records yet. */
void robust_setup_records(ctx *c)
{
    int a, j, m = 0;
    for (a = 0; a < c->ncam; a++) {
        int start = c->off[a], cnt = c->off[a + 1] - start;
        int k = cnt < REC_PAIRS ? cnt : REC_PAIRS;
        c->rec_off[a] = m;
        c->rec[a] = -1.0;
        if (!c->usable[a])
            continue;
        for (j = 0; j < k; j++)
            c->rec_idx[m++] = c->perm[start + (int)(((double)j + 0.5) * cnt / k)];
    }
    c->rec_off[c->ncam] = m;
}

/* Make (R, t) with residuals in rcur the best; the buffers swap. */
void robust_take_best(ctx *c, const double R[9], const double t[3], double score, int n_inl,
                      int n_wide)
{
    double *tmp = c->rbest;
    c->n_wide = n_wide;
    memcpy(c->R, R, sizeof c->R);
    memcpy(c->t, t, sizeof c->t);
    c->score = score;
    c->n_inl = n_inl;
    c->have = 1;
    c->rbest = c->rcur;
    c->rcur = tmp;
    if (c->nsub > 0) /* (rcur is scratch now) */
        c->best_sub = msac_sub(c, R, t, INFINITY);
    c->rival_best = -1;
    if (c->records)
        records_of_best(c);
}

/* (R, t) made the best whatever its score, scored on all pairs (R, t must
 * not be c->R, c->t) */
void robust_set_best(ctx *c, const double R[9], const double t[3])
{
    int n_inl, n_wide;
    double sc = robust_msac2(c, R, t, INFINITY, &n_inl, &n_wide);
    robust_take_best(c, R, t, sc, n_inl, n_wide);
}
