/*
 * robust_internal.h -- what the parts of the robust estimate share
 * (csrc/robust.c, the entry point mcg_robust_rig_motion, and the
 * robust_*.c files of its phases): the state of one call (ctx), the
 * constants more than one part reads, small helpers, and the functions one
 * part calls in another. Not installed; not part of the public API.
 */
#ifndef MCGEOM_ROBUST_INTERNAL_H
#define MCGEOM_ROBUST_INTERNAL_H

#include "mcgeom.h"
#include "internal.h"
#include "sampson.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#define MIN_CROSS 20       /* cross-camera correspondences that take the 6th draw */
#define SCORE_BLOCK 64     /* residuals per block of the early-exit scoring */
#define MIN_REFIT 6        /* fewest correspondences a refinement can fit */
#define WIDE 2.0           /* the final refinement uses r < WIDE * threshold */
#define PARALLEL_EPS 1e-12 /* 1 - cos^2 below: rays parallel, no depth */
/* The final refinement and the scale profile on more pairs than FINAL_SUB
 * first converge on a random subset of FINAL_SUB of them, then take at most
 * FINAL_POLISH Gauss-Newton/LM steps on all of them: from the subset's
 * optimum (within ~sigma / sqrt(FINAL_SUB) of the full one) a step or two
 * reaches the full optimum, and the cost per pair stays constant in N
 * (issue 19: 1e6 pairs in under 2 s; the full refinement took 10 steps of
 * all pairs, twice, and the profile two more such fits). */
#define FINAL_SUB 4096 /* (FINAL_POLISH: robust_lo.c) */
/* mcgeom.observability's UNDETERMINED_REL_STD: above it the data define no
 * metric scale at all (tests/test_robust_c.py checks that the copies agree) */
#define UNDETERMINED_REL_STD 1.0
/* mcgeom.observability's ZERO_FACTOR (|t| shrunk to 1 %: a static rig?);
 * tests/test_robust_c.py checks that the two copies agree; robust.c and
 * robust_verdict.c compute it */
#define ZERO_FACTOR 0.01

/* observability.scale_determined's bound on the zero profile (a vanishing
 * translation not excluded at 3 sigma): the zero profile is only compared
 * with it, so its fit stops once below (the value is then an upper bound),
 * or once evidently above (mcg_refine_motion_until: more than 100 times
 * its last step's decrease above; issue 19, the fits crept down for up to
 * 50 steps 10-20x above the bound: C instructions per estimate, 20
 * problems of `mcgeom bench robust`, ladybug6 8.98 -> 8.22 M, car8
 * 5.17 -> 4.55 M) */
#define ZERO_PROFILE_BOUND 9.0

/* pairs of the upright sampler's challenge subset (robust_offer.c) */
#define RIVAL_SUB 64
/* preemptive scoring from this many pairs on (robust_score.c) */
#define PREEMPT_MIN 4096
/* Two-stage 5+1 (thesis ch. 7.4 solves camera a's motion -- R and the
 * direction of its translation -- from its 5 pairs, then the scale): a
 * 5-point motion that its sixth pair does not make the best one (an
 * outlier sixth, or one that gives no scale) still has its scale searched
 * on the other cameras' pairs (REC_PROPOSALS 1-point proposals; the
 * pairs that fix the scale must be in front, as candidate() asks of the
 * sixth) when more of camera a's own pairs -- a fixed subset of at most
 * REC_PAIRS of them, scale-free -- lie within WIDE thresholds of it than
 * of any motion whose scale was searched so far, the best one included
 * (a record: a few per camera). An all-inlier 5-sample then yields a
 * scaled hypothesis whatever its sixth pair, so the adaptive stop counts
 * 5-samples (w^5, not w^6). Issue 19, measured:
 *  - Ladybug head, 30 % outliers, 60 problems of `mcgeom bench robust`:
 *    mean samples 81.7 -> 43.8; C instructions per estimate (callgrind,
 *    20 problems) 8.22 -> 6.65 M (ring4 2.88 -> 3.05, car8 4.55 -> 4.43);
 *    car rig driving forward: median scale error 0.241 -> 0.187;
 *  - `mcgeom experiment ch7 --trials 1200 --seed 10 --cross 0 0.1 0.3`:
 *    estimates more than 30 % off 753 / 10 / 14 -> 726 / 3 / 6, of them
 *    called observable 1 / 3 / 0 -> 0 / 2 / 0;
 *  - tests/test_robust.c two_stage_case (80 % of the sixth draws outliers,
 *    20 samples): the motion in 44 of 60 runs, against 25 for one stage.
 * Counted within WIDE thresholds (the adaptive stop's true inliers):
 * counted within one threshold, Ladybug took 7.03 M instructions per
 * estimate against 6.65 M (ring4 and car8 within 1 %); scored by MSAC
 * instead of counted, ring4 took 3.32 M against 3.05 M. */
#define REC_PAIRS 64
/* pairs of a linear17 or eigensolver sample: the fewest mcg_linear17 solves */
#define PAIRS17 17

typedef struct {
    /* inputs */
    int n, ncam;
    const double *o1, *d1, *o2, *d2, *focal;
    const int *cam1, *cam2;
    const double *cam_axes, *cam_focal;
    double min_var_ratio;
    mcg_robust_options opt;
    /* workspace */
    double *rbest, *rcur, *fsc, *sub, *wsub;
    int *perm, *off; /* indices grouped: intra of camera 0, 1, ..., cross */
    int *usable;     /* per camera: 1 if it can be the central sample's camera */
    int central_m;   /* pairs of a central sample: 5 (5+1), 3 (upright 3+1), 0 */
    int *xidx;       /* the scale search's pairs (indices of the input) */
    double *xwork;   /* its mcg_scale_ransac workspace */
    int *xorder;     /* its proposal order (line_scale draws it afresh) */
    double *msol;    /* the solutions of an upright / 6-point sample */
    double *vwork;   /* mcg_verdict_stats's workspace */
    double *cwork;   /* mcg_calibration_scale_std's (the verdict's) */
    /* the two-stage 5+1 (REC_PAIRS): on when records is 1 */
    int records;
    double *rec;     /* per camera: the record inlier count on its subset */
    int *rec_off;    /* camera a's subset: rec_idx[rec_off[a] .. rec_off[a + 1]) */
    int *rec_idx;
    int sample_size; /* pairs per sample (adaptive stop) */
    double found;    /* chance that a sample of inliers yields the motion
                      * (MCG_SAMPLER_6PT_LOCAL: found_rate; else 1) */
    int found_at;    /* n_wide when found was measured (-1: never) */
    int local_samples; /* MCG_SAMPLER_6PT_LOCAL: its samples so far */
    int nx;          /* its pairs (0: no scale search) */
    int nx_others;   /* 1: they are another camera's (gather_others) */
    /* derived */
    double thr2, med_focal, loss_scale;
    double size;     /* RMS spread of the origins + |their centroid| (metres) */
    int const_focal;
    uint64_t rng;
    /* state */
    double R[9], t[3], score;
    int have, n_inl, n_wide, n_hyp, n_lo, lo_rounds;
    /* preemptive scoring: the subset's pairs (o1 d1 o2 d2 blocks of stride
     * 3 n, from row n - nsub of the gather buffers) and the best's score on them */
    int nsub;
    double best_sub;
    /* the upright sampler's challenges (RIVAL_SUB): the subset's pairs and
     * the best's count within RIVAL_WIDE thresholds on it (nrival 0: off;
     * rival_best -1: not counted since the best changed, see rival) */
    int rival_idx[RIVAL_SUB], nrival, rival_best;
    /* the refinements also stop once their cost is at most this (-inf: no) */
    double refine_target;
    int final_stage; /* 1: the final refinement (mcg_refine_motion's tolerance) */
} ctx;

/* splitmix64 (Steele, Lea & Flood 2014): a seeded, stateless-to-copy stream */
static inline uint64_t rng_next(uint64_t *s)
{
    uint64_t z = (*s += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

/* uniform integer in [0, m), m >= 1 (the modulo bias is below 2^-40 for the
 * sizes accepted here) */
static inline int rng_below(uint64_t *s, int m)
{
    return (int)(rng_next(s) % (uint64_t)m);
}

/* doubles for n ints (rounded up) */
static inline size_t ints_as_doubles(size_t n)
{
    return (n * sizeof(int) + sizeof(double) - 1) / sizeof(double);
}

/* Unit copy of a 3-vector; 0 if it has no length. */
static inline int unit3(const double *v, double u[3])
{
    double s = sqrt(dot3(v, v));
    if (!(s > 0.0) || !isfinite(s))
        return 0;
    u[0] = v[0] / s;
    u[1] = v[1] / s;
    u[2] = v[2] / s;
    return 1;
}

/* Depths (s1, s2) of the closest points of the rays s1 a + p and s2 b
 * (unit a, b): min |s1 a + p - s2 b|; 0 if the rays are parallel. */
static inline int depths(const double a[3], const double b[3], const double p[3], double *s1,
                  double *s2)
{
    double cab = dot3(a, b), den = 1.0 - cab * cab, ap = dot3(a, p), bp = dot3(b, p);
    if (!(den > PARALLEL_EPS))
        return 0;
    *s1 = (-ap + cab * bp) / den;
    *s2 = (bp - cab * ap) / den;
    return 1;
}

/* |residual| of pair k at (R, t), in the threshold's unit (pixels with
 * focal); NaN for a pair without one (never below a threshold) */
static inline double pair_residual(const ctx *c, const double R[9], const double t[3], size_t k)
{
    return fabs(sampson_residual(R, t, c->o1 + 3 * k, c->d1 + 3 * k, c->o2 + 3 * k,
                                 c->d2 + 3 * k)) *
           (c->focal ? c->focal[k] : 1.0);
}

/* Copy pair k's rays (o1, d1, o2, d2) to row m of the gather buffers
 * (sub: four blocks of stride 3 n). */
static inline void robust_copy_pair(ctx *c, size_t k, int m)
{
    const size_t n = (size_t)c->n, r = 3 * (size_t)m;
    int i;
    for (i = 0; i < 3; i++) {
        c->sub[r + i] = c->o1[3 * k + i];
        c->sub[3 * n + r + i] = c->d1[3 * k + i];
        c->sub[6 * n + r + i] = c->o2[3 * k + i];
        c->sub[9 * n + r + i] = c->d2[3 * k + i];
    }
}

/* median of x[0..n) as numpy's (mean of the two middle values for even n),
 * computed on the scratch copy y (internal.h's median_inplace) */
static inline double median(const double *x, double *y, int n)
{
    memcpy(y, x, (size_t)n * sizeof *y);
    return median_inplace(y, n);
}

/* robust.c: the workspace */
size_t robust_sample_work_size(void);
int robust_scale_cap(int n);
/* CLOCK_MONOTONIC, seconds (the result's timings and max_seconds) */
double robust_now_seconds(void);

/* robust_score.c: MSAC scoring, the best, the records, preemptive scoring */
double robust_msac2(ctx *c, const double R[9], const double t[3], double bound, int *n_inl,
                    int *n_wide);
double robust_msac(ctx *c, const double R[9], const double t[3], double bound, int *n_inl);
void robust_preempt_setup(ctx *c);
int robust_preempted(ctx *c, const double R[9], const double t[3]);
void robust_setup_records(ctx *c);
void robust_take_best(ctx *c, const double R[9], const double t[3], double score, int n_inl,
                      int n_wide);
void robust_set_best(ctx *c, const double R[9], const double t[3]);

/* robust_lo.c: refinements on a gathered subset, local optimisation */
int robust_gather(ctx *c, const double *res, double limit, const double *w, double cen[3],
                  double keep);
int robust_refine_subset(ctx *c, int m, const double cen[3], int weighted, int loss,
                         double scale, int fix_scale, double R[9], double t[3],
                         mcg_refine_result *out);
void robust_shuffle_head(ctx *c, int m, int k);
int robust_refine_capped(ctx *c, int m, const double cen[3], int weighted, int loss,
                         double scale, int fix_scale, double R[9], double t[3],
                         mcg_refine_result *out);
const double *robust_fixed_weights(ctx *c);
void robust_local_optimise_held(ctx *c, const double *w, int hold);
void robust_local_optimise(ctx *c, const double *w);

/* robust_scale.c: the 1-point scale searches */
void robust_gather_cross(ctx *c);
int robust_pair_in_front(const double R[9], const double t[3], const double *o1,
                         const double *d1, const double *o2, const double *d2);
int robust_scale_search(ctx *c, const double R[9], const double t0[3], const double u[3],
                        double lam, int a, int from_record);
int robust_final_scale_search(ctx *c, const double cen[3], const double *w);

/* robust_offer.c: one hypothesis scored, kept, challenged */
void robust_rival_setup(ctx *c);
void robust_record(ctx *c, const double R[9], const double t0[3], const double u[3],
                   const double *w, int a);
int robust_offer(ctx *c, const double R[9], const double t0[3], const double u[3],
                 double lam, const double *w, int a);
int robust_offer_motion(ctx *c, const double R[9], const double t[3], const double *w);

/* robust_sample_5p1.c: the central (5+1, upright 3+1) samples */
int robust_orthonormalise(double r[9]);
int robust_sample(ctx *c, const double *w);

/* robust_samplers.c: the other samplers, one sample of the options' sampler */
int robust_check_sampler(const mcg_robust_options *o);
double robust_found_rate(ctx *c);
int robust_draw(ctx *c, const double *w);

/* robust_final.c: the final refinement, scale profile, covariance */
void robust_finish(ctx *c, mcg_robust_result *res, unsigned char *mask, double *weights_out);
void robust_rescale_refined(ctx *c, mcg_robust_result *res, unsigned char *mask,
                            double *weights, const double cen[3], const double *w);
double robust_scale_profile(ctx *c, const mcg_robust_result *res, const unsigned char *mask,
                            const double *weights, const double *f, int nf, double stop_below);
void robust_fill_covariance(mcg_robust_result *res);

/* robust_verdict.c: the scale verdict of the result (res->scale) */
void robust_scale_verdict(ctx *c, mcg_robust_result *res, const unsigned char *mask,
                          const double *w);
/* robust_verdict.c: the checks of the consensus of an observable scale
 * (res->consensus; work: the call's workspace, free after the verdict) */
void robust_consensus(ctx *c, mcg_robust_result *res, const unsigned char *mask,
                      const double *weights, const double *wp, double *work);

#endif /* MCGEOM_ROBUST_INTERNAL_H */
