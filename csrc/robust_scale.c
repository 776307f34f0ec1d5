/*
 * robust_scale.c -- the metric scale inside the robust estimate
 * (csrc/robust.c): the 1-point scale search of thesis ch. 7.4
 * (mcg_scale_ransac) along the line t0 + lam u of a hypothesis, on the
 * cross-camera pairs or, without enough of them, on the pairs of the other
 * cameras; the cheirality of the pairs that fix a scale; and the final
 * search of the best motion's scale at its own locally optimised rotation
 * (near the critical motion of ch. 7.3.2).
 */
#include "robust_internal.h"

#include <math.h>
#include <string.h>

#define SCALE_PROPOSALS 64 /* 1-point scale proposals per search */

#define REC_PROPOSALS 16

/* Pairs of a record's scale search at most (a random subset beyond; the
 * cap of the others is scale_cap): a record is a candidate whose sixth pair
 * failed, and the scale found for it only has to make it win the MSAC over
 * all pairs, after which its local optimisation and the final refinement
 * on all inliers set the motion; a search of a new best keeps scale_cap.
 * Records make most of the searches (43 of 46 on 10 problems of the scaling
 * bench at 1e3 pairs), each on every pair of the other cameras up to
 * SCALE_PAIRS: 250 on the Ladybug head, 280 on the car rig. Issue 19,
 * measured with 128: C instructions per estimate (callgrind, 40 problems of
 * each `mcgeom bench robust` case) ring4 2.51 -> 2.42 M, Ladybug 5.46 ->
 * 4.95 M, car8 3.83 -> 3.64 M (64: 2.35 / 4.75 / 3.44 M); `mcgeom bench
 * robust` (300 problems a case): cold median ms 1.03 / 1.72 / 1.27 ->
 * 0.97 / 1.61 / 1.18, median rotation error 0.0164 / 0.0179 / 0.0094 ->
 * 0.0164 / 0.0176 / 0.0094 deg, scale error 0.0270 / 0.160 / 0.180 ->
 * 0.0273 / 0.157 / 0.179; 60 problems of the scaling bench's ring at 1e3
 * pairs: 9.13 -> 7.82 M (median rotation error 0.0118 -> 0.0117 deg, scale
 * error 0.0228 -> 0.0199); `mcgeom experiment ch7 --trials 1200 --seed 10
 * --cross 0 0.1 0.3`: no estimate more than 30 % off called observable
 * (0 / 0 / 0, as before); observable 0 / 1198 / 1198 -> 0 / 1198 / 1200,
 * more than 30 % off 728 / 2 / 2 -> 736 / 2 / 0, median scale error of the
 * observable 0.00468 / 0.00285 -> 0.00467 / 0.00284 (the searches now
 * shuffle the identity, not the last order: the same distribution). */
#define REC_SCALE_PAIRS 128

/* The pairs of the scale search: up to scale_cap cross-camera pairs
 * (a random subset when there are more: the scale is one number), when
 * there are at least MIN_CROSS of them. */
void robust_gather_cross(ctx *c)
{
    int g0 = c->off[c->ncam], m = c->off[c->ncam + 1] - g0, j, cap = robust_scale_cap(c->n);
    int take = m < cap ? m : cap;
    c->nx = 0;
    if (m < MIN_CROSS)
        return;
    for (j = 0; j < take; j++) {
        int r = j + rng_below(&c->rng, m - j), tmp = c->perm[g0 + j];
        c->perm[g0 + j] = c->perm[g0 + r];
        c->perm[g0 + r] = tmp;
        c->xidx[j] = c->perm[g0 + j];
    }
    c->nx = take;
}

/* The pairs of the scale search when there are few cross-camera pairs: up
 * to cap (at most scale_cap) of those not of camera a (each kept with
 * probability cap / their count), gathered for one search. */
static int gather_others(ctx *c, int a, int cap)
{
    int start = a >= 0 ? c->off[a] : 0, cnt = a >= 0 ? c->off[a + 1] - start : 0;
    int nother = c->n - cnt, j, m = 0;
    uint64_t cut = nother > cap ? (uint64_t)((double)cap / nother * 18446744073709551615.0)
                                : UINT64_MAX;
    if (nother < 1)
        return 0;
    for (j = 0; j < c->n && m < cap; j++) {
        if (j >= start && j < start + cnt)
            continue;
        if (cut != UINT64_MAX && rng_next(&c->rng) > cut)
            continue;
        c->xidx[m++] = c->perm[j];
    }
    if (m == 0)
        return 0;
    c->nx = m;
    c->nx_others = 1;
    return m;
}

/* The 1-point scale search (thesis ch. 7.4, mcg_scale_ransac on the first m
 * pairs gathered in xidx) for the motion (R, t0 + lam u) on the line t0 + lam' u:
 * 1 and *lam2 when it found a scale other than lam and not the trivial
 * root lam' = 0 of pairs whose cameras sit at the line's fixed point (a
 * central rig: every F vanishes there, a zero-residual false consensus),
 * found up to rounding. */
static int line_scale(ctx *c, int m, const double R[9], const double t0[3],
                      const double u[3], double lam, int proposals, double prob,
                      double *lam2)
{
    double sc2;
    int j;
    for (j = 0; j < m; j++)
        c->xorder[j] = j;
    for (j = 0; j < m; j++) { /* a fresh random order of the proposals */
        int r = j + rng_below(&c->rng, m - j), tmp = c->xorder[j];
        c->xorder[j] = c->xorder[r];
        c->xorder[r] = tmp;
    }
    return mcg_scale_ransac_indexed(m, c->xidx, c->o1, c->d1, c->o2, c->d2, R, t0, u, m,
                                    c->xorder, proposals, c->loss_scale,
                                    prob, lam2, &sc2, NULL, c->xwork) == MCG_OK &&
           *lam2 != lam && *lam2 > 1e-9 * (c->size + sqrt(dot3(t0, t0)));
}

/* The pair (o1, d1) -> (o2, d2) triangulated under (R, t): s1 R d1 +
 * (R o1 + t - o2) = s2 d2 at the closest points. 1 when both depths are
 * positive, 0 when not, -1 for parallel rays (a point at infinity: no
 * depth), -2 for a zero direction. */
int robust_pair_in_front(const double R[9], const double t[3], const double *o1,
                         const double *d1, const double *o2, const double *d2)
{
    double e1[3], e2[3], A[3], g[3], s1, s2;
    int i;
    if (!unit3(d1, e1) || !unit3(d2, e2))
        return -2;
    mat_vec(R, e1, A);
    mat_vec(R, o1, g);
    for (i = 0; i < 3; i++)
        g[i] += t[i] - o2[i];
    if (!depths(A, e2, g, &s1, &s2))
        return -1;
    return s1 > 0.0 && s2 > 0.0;
}

/* Are most of the scale search's m pairs that (R, t) explains (residual
 * within the threshold) in front of both their rays? The sixth pair of a
 * 5+1 sample is checked so (candidate); a scale searched for a motion the
 * sixth did not make the best (record) must pass the same test on the
 * pairs that gave it (a wrong 5-point root has a scale that puts them
 * behind: on 6 noise-free pairs it fits them exactly). */
static int scale_in_front(const ctx *c, int m, const double R[9], const double t[3])
{
    int j, front = 0, behind = 0;
    for (j = 0; j < m; j++) {
        const size_t k = (size_t)c->xidx[j];
        int f;
        if (!(pair_residual(c, R, t, k) < c->opt.threshold))
            continue;
        f = robust_pair_in_front(R, t, c->o1 + 3 * k, c->d1 + 3 * k, c->o2 + 3 * k, c->d2 + 3 * k);
        front += f == 1;
        behind += f == 0; /* (no depth: neither) */
    }
    return front > behind;
}

/* The scale search of a new best (R, t0 + lam u) on camera a's line (see
 * offer), or of a record (from_record: REC_PROPOSALS on at most
 * REC_SCALE_PAIRS pairs, its scale's pairs in front, scored on the
 * preemptive subset first): the motion it finds becomes the best if it
 * scores better; 1 when it did. */
int robust_scale_search(ctx *c, const double R[9], const double t0[3], const double u[3],
                        double lam, int a, int from_record)
{
    double sc, t[3], lam2, bound = c->have ? c->score : INFINITY;
    int n_inl = 0, n_wide = 0, i, took = 0, m, cap = robust_scale_cap(c->n);
    if (from_record && cap > REC_SCALE_PAIRS)
        cap = REC_SCALE_PAIRS;
    if (c->nx > 0 || (a >= 0 && gather_others(c, a, cap) > 0)) {
        /* (the cross-camera pairs are a random subset of all of them in a
         * random order: any prefix is one too) */
        m = c->nx < cap ? c->nx : cap;
        if (line_scale(c, m, R, t0, u, lam, from_record ? REC_PROPOSALS : SCALE_PROPOSALS,
                       c->opt.prob, &lam2)) {
            for (i = 0; i < 3; i++)
                t[i] = t0[i] + lam2 * u[i];
            /* (a record's motion is first scored on the preemptive subset,
             * as offer's are: at 1e6 pairs a full score costs ~6 ms) */
            if (!from_record || (scale_in_front(c, m, R, t) && !robust_preempted(c, R, t))) {
                c->n_hyp++;
                sc = robust_msac2(c, R, t, bound, &n_inl, &n_wide);
                if (sc < bound) {
                    robust_take_best(c, R, t, sc, n_inl, n_wide);
                    took = 1;
                }
            }
        }
        if (c->nx_others)
            c->nx = c->nx_others = 0; /* that set belonged to camera a */
    }
    return took;
}

/* The scale of the search's best motion searched once more, at its own
 * (locally optimised) rotation, on the cross-camera pairs: along the line
 * of the centroid cen of the origins (t = cen - R cen + lam u, u the
 * direction of the centroid's travel). A scale more than FINAL_SCALE_JUMP
 * away is locally optimised from there (the rotation refits to it) and
 * kept if that scores better than the best; else the best is restored.
 * Near the critical motion of thesis ch. 7.3.2 only the few cross-camera
 * pairs fix |t|: a hypothesis whose rotation fits the intra-camera majority
 * better can win the MSAC with a wrong scale that the later hypotheses'
 * searches, each at its own rough rotation, never correct, and the final
 * refinement on its consensus set then reports that scale as precise (car
 * rig driving forward with 10 % cross-camera pairs, 160 problems: 4 with
 * |t| 1.6-3.8x off reported observable at a relative std of 2-9 %; the true
 * motion scored better than the returned one in all four, with 33-38
 * cross-camera inliers against its 25-28). 5+1, `mcgeom experiment ch7
 * --trials 1200 --seed 10 --cross 0.1 0.3`: such estimates 14 / 9 -> 3 / 0,
 * estimates more than 30 % off 76 / 38 -> 10 / 14, observable 1129 / 1169
 * -> 1193 / 1186.
 * The best and the jump compete after a local optimisation of each with |t|
 * free (see the body), the scale search tries every proposal (its
 * adaptive stop assumes that an inlier proposes the right scale; near the
 * critical motion most pairs are inliers at any scale and propose none),
 * and the search runs once more at the refined motion (after finish, in
 * mcg_robust_rig_motion, where the refinement found |t| determined).
 * `mcgeom experiment ch7 --trials 1200 --seed 10 --cross 0 0.1 0.3`: 5+1,
 * estimates more than 30 % off 728 / 4 / 6 -> 728 / 2 / 2, observable
 * 0 / 1197 / 1194 -> 0 / 1198 / 1198, of the bad called observable
 * 0 / 1 / 0 -> 0 / 0 / 0; with --vertical-error-deg 0.2 (upright sampler)
 * 738 / 13 / 20 -> 713 / 15 / 19, called observable 2 / 0 / 1 -> 0 / 0 / 0.
 * C instructions per estimate: 20 of those problems (5+1, cross 0.1)
 * 3.62 -> 3.87 M; 40 problems of `mcgeom experiment peer_solvers`' four
 * upright cases 4.07 -> 4.77 M (their scale search runs on all pairs); the
 * bench cases of `mcgeom bench robust` (no cross-camera pairs) unchanged. */
#define FINAL_SCALE_JUMP 0.1

/* The scale search along the line of the best motion (c->R, c->t) through
 * the centroid cen of the origins: R0 = c->R, t0 = cen - R0 cen, u the unit
 * direction of c->t - t0, lam2 the scale found. 1 when it lies more than
 * FINAL_SCALE_JUMP from the best's own (a jump), else 0. */
static int best_line_jump(ctx *c, const double cen[3], double R0[9], double t0[3],
                          double u[3], double *lam2)
{
    double rc[3], lam;
    int i;
    mat_vec(c->R, cen, rc);
    for (i = 0; i < 3; i++) {
        t0[i] = cen[i] - rc[i];
        u[i] = c->t[i] - t0[i];
    }
    lam = sqrt(dot3(u, u));
    memcpy(R0, c->R, 9 * sizeof(double));
    return lam > 0.0 && unit3(u, u) &&
           line_scale(c, c->nx, R0, t0, u, lam, SCALE_PROPOSALS, 1.0, lam2) &&
           fabs(*lam2 - lam) > FINAL_SCALE_JUMP * lam;
}

/* Returns 0 when no scale jumped, 1 when the jump won (it is the best), 2
 * when it lost (the best is its own free optimisation). */
int robust_final_scale_search(ctx *c, const double cen[3], const double *w)
{
    double t0[3], u[3], lam2, R0[9], score0, t[3], Rb[9], Tb[3];
    int i, others = 0;
    if (!c->have || c->lo_rounds <= 0)
        return 0;
    if (c->nx <= 0) {
        /* The upright sampler without cross-camera pairs: its |t| comes
         * from a 4-pair solve with the vertical's error, and its local
         * optimisation holds |t|: near the critical motion a hypothesis of
         * a few cm (a near-pure rotation fitting the distant points) won
         * the MSAC with ~50 % of the pairs where the true motion has ~90 %
         * (car rig driving forward, intra-camera pairs, vertical 0.2 deg
         * off: 7 of 1200 such estimates called observable). Every pair
         * constrains the scale along the centroid's line through its
         * camera's rotation-induced offset (R - I)(c_k - cen): the search
         * runs on all of them (gather_others with no camera excluded).
         * `mcgeom experiment ch7 --trials 1200 --seed 10 --cross 0
         * --vertical-error-deg 0.2`: estimates more than 30 % off yet
         * called observable 7 -> 1, more than 30 % off 833 -> 784. (Only
         * for this sampler: 5+1's scale comes from its scale search on
         * the other cameras' pairs at every new best.) */
        if (c->opt.sampler != MCG_SAMPLER_UPRIGHT4 ||
            gather_others(c, -1, robust_scale_cap(c->n)) <= 0)
            return 0;
        others = 1;
    }
    i = best_line_jump(c, cen, R0, t0, u, &lam2);
    if (!i) {
        if (others)
            c->nx = c->nx_others = 0; /* (that set was for this search only) */
        return 0;
    }
    /* the two scales compete on equal terms: each locally optimised with
     * |t| free (the final stage's freedom). Held at its own |t|, the best
     * keeps the rotation error that compensated its scale error (at the
     * critical motion the two trade off), while the jump's optimisation
     * refits the rotation: a jump to a wrong scale then won against a best
     * that the final refinement would have taken to the true one (trial 381
     * of `mcgeom experiment ch7 --trials 1200 --seed 10 --cross 0.1`:
     * |t| 1.72 -> 0.11 m, the truth 1.84 m) */
    robust_local_optimise_held(c, w, 0);
    memcpy(Rb, c->R, sizeof Rb);
    memcpy(Tb, c->t, sizeof Tb);
    score0 = c->score;
    if (others) {
        /* The upright sampler's best without cross-camera pairs: its
         * held |t| came from a sample whose rotation carried the
         * vertical's error, and its free optimisation mostly reaches the
         * right scale by itself (car rig turning, vertical 0.2 deg off:
         * the search's |t| 0.1-33 m, the truth ~1 m, after the free
         * optimisation 0.8-1.5 m in 34 of 34 jumps; the jump's own
         * optimisation ended within 10 % of it in 33, its MSAC score
         * within 0.5 % in all). So the line is searched again at the free
         * optimum, and the jump is optimised only if its scale still lies
         * elsewhere: one line search instead of a local optimisation in
         * most jumps (there: 68 -> 37 local optimisations in 73 searches,
         * 4 jumps left). C instructions per estimate, 40 problems of each upright
         * case of `mcgeom experiment peer_solvers`: car rig turning 4.75
         * -> 4.40 M, ring4 3.20 -> 2.98 M, car rig forward 5.19 -> 5.01 M,
         * Ladybug 4.40 -> 4.28 M; median errors of 200 problems each
         * unchanged (paired: as many better as worse); `mcgeom experiment
         * ch7 --trials 1200 --seed 10 --cross 0 --vertical-error-deg 0.2`:
         * more than 30 % off 715 -> 708, none of them called observable
         * (as before). */
        i = best_line_jump(c, cen, R0, t0, u, &lam2);
        c->nx = c->nx_others = 0; /* (that set was for this search only) */
        if (!i)
            return 2;
    }
    c->n_hyp++;
    for (i = 0; i < 3; i++)
        t[i] = t0[i] + lam2 * u[i];
    robust_set_best(c, R0, t); /* (tentatively, to be optimised) */
    robust_local_optimise_held(c, w, 0);
    if (!(c->score < score0)) {
        robust_set_best(c, Rb, Tb);
        return 2;
    }
    return 1;
}
