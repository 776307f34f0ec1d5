/*
 * robust.c -- the whole robust estimate of a rig motion in one call:
 * camera-balanced 5+1 sampling (thesis ch. 7; or upright 4-point / generic
 * 6-point samples), MSAC scoring, adaptive
 * stopping, local optimisation and the final refinement (LO-RANSAC, Chum,
 * Matas & Kittler 2003; MSAC, Torr & Zisserman 2000).
 *
 * Phases of mcg_robust_rig_motion (static functions below):
 *   check inputs   sizes, pointers, finiteness, camera ids, options;
 *   carve          the caller's workspace into residual buffers, the
 *                  gathered subset of the refinements and the index groups;
 *   group          correspondences by camera: the intra-camera ones of each
 *                  camera (the 5-point camera's candidates) and the
 *                  cross-camera ones (cam1 != cam2);
 *   search         the sampling loop: 5 intra-camera correspondences of a
 *                  camera a drawn with probability proportional to its count
 *                  -> mcg_essential5 (unit bearings in rig axes: for camera
 *                  a, s2 d2 = s1 R d1 + u with u = t + R c_a - c_a, so
 *                  d2^T [u]x R d1 = 0 is an ordinary essential matrix) ->
 *                  both rotations of each E with the sign of u that puts the
 *                  five points in front (cheirality) -> the metric scale of
 *                  t(lam) = t0 + lam u, t0 = c_a - R c_a, from the sixth
 *                  correspondence by eq. 7.4 (lam = -a / b), kept only when
 *                  lam > 0 and the sixth point is in front of both its rays
 *                  (issue 18: the minimal problem must pick the candidate
 *                  that satisfies cheirality) -> MSAC score over all
 *                  correspondences (mcg_gec_residuals in blocks, abandoned
 *                  once the partial score exceeds the best) -> every new best
 *                  is locally optimised (re-estimated on its inliers by
 *                  mcg_refine_motion with |t| held, Cauchy loss, while the
 *                  score improves) -> the adaptive stop
 *                  k = log(1 - prob) / log(1 - w^5), w the inlier ratio
 *                  (5-samples: the two-stage 5+1 of REC_PAIRS);
 *   finish         the final refinement of all six degrees of freedom on the
 *                  correspondences within 2 thresholds (robust loss of the
 *                  threshold's scale), refitted once if that set moved, and
 *                  the inlier mask.
 *
 * Large inputs (issue 19: 1e6 pairs in under 2 s, the time per pair about
 * constant from 1e3 to 1e6): preemptive scoring on a fixed random subset
 * (PREEMPT_SUB), LO on at most ~LO_MAX inliers, and the final refinement
 * and scale profile converged on a random FINAL_SUB of the pairs and then
 * polished on all (FINAL_POLISH steps); the workspace stays ~16.5 n.
 *
 * Other samplers (opt.sampler, issue 21; "the upright and 6-point samples"
 * below): MCG_SAMPLER_UPRIGHT4 with the vertical known draws, when some
 * camera has 3 intra-camera pairs, 3+1 samples as the two-stage 5+1 does
 * (3 pairs of a camera -> mcg_upright3_central: its rotation and direction
 * of travel; the scale as for 5+1; w^3), else 4 pairs of any cameras solved
 * with the known vertical (mcg_upright4); MCG_SAMPLER_6PT draws 6 and
 * solves them with the generic minimal solver (mcg_sixpt);
 * MCG_SAMPLER_6PT_LOCAL (AUTO's choice without a 5-point camera) draws 6
 * and solves them by local search (mcg_sixpt_local, every HOMOTOPY_EVERY-th
 * by mcg_sixpt), measures how often that finds its consensus' motion
 * (found_rate) and uses found_rate w^6 in the stop;
 * MCG_SAMPLER_EIGEN draws 17 and solves them with Kneip and Li's
 * eigensolver from linear17's rotation (sample_eigen); MCG_SAMPLER_LINEAR17
 * draws 17 and takes the motion of linear17 (sample_linear17: ~55 us a
 * sample where the 6-point solver takes ~27 ms); each real
 * solution with its own metric t is scored, locally optimised and finished
 * as above, the adaptive stop uses w^4, w^6 or w^17. Solutions that satisfy a
 * sample pair trivially (its camera only rotated about its centre, e.g.
 * the static rig) are dropped.
 *
 * The sixth correspondence is drawn among the cross-camera ones when there
 * are at least MIN_CROSS of them (they fix the scale whatever the motion,
 * while near the critical motion of ch. 7.3.2 the intra-camera ones of the
 * other cameras hardly depend on it), else among all correspondences not of
 * camera a: what mcgeom.estimators.five_plus_one.propose did in Python.
 *
 * Units: the residual is the Sampson angular error (radians); with
 * per-correspondence pixels per radian `focal` it is r * focal pixels, and
 * the threshold is in pixels. The refinements weigh a residual by
 * (focal / median focal)^2 and use the loss scale threshold / median focal
 * (radians); with the optional camera table (optical axes and focal lengths)
 * the final refinement uses the exact first-order pixel scaling of every
 * residual at the motion (mcg_sampson_pixel_scale) instead.
 */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */

#include "mcgeom.h"
#include "internal.h"
#include "sampson.h"

#include <float.h>
#include <math.h>
#include <string.h>
#include <time.h>

#define MAX_PAIRS (1 << 26)
#define MAX_CAMERAS 4096
#define MIN_CROSS 20       /* cross-camera correspondences that take the 6th draw */
#define SCORE_BLOCK 64     /* residuals per block of the early-exit scoring */
#define CLOCK_EVERY 8      /* samples between two reads of the clock */
#define MIN_REFIT 6        /* fewest correspondences a refinement can fit */
#define WIDE 2.0           /* the final refinement uses r < WIDE * threshold */
#define PARALLEL_EPS 1e-12 /* 1 - cos^2 below: rays parallel, no depth */
/* Pairs of a scale search at most (a random subset beyond): the search
 * proposes one number, |t| along a line, which the MSAC over all pairs, LO
 * and the final refinement then judge and polish; 512 pairs of the 1-point
 * RANSAC of thesis ch. 7.4 fix it as well as thousands. 4096 before (issue
 * 19): at 1e4 pairs a fifth of the C instructions went to scale searches of
 * 4096 pairs each. Measured on the scaling bench's ring (30 problems per
 * size, rays in): C instructions per estimate at 1e3 10.35 -> 8.20 M
 * (callgrind, 11 estimates), at 1e4 64.6 -> 47.2 M; median rotation error
 * 0.0143 / 0.0042 / 0.0016 deg -> 0.0143 / 0.0039 / 0.0015 and scale error
 * 0.0159 / 0.0063 / 0.0029 -> 0.0157 / 0.0062 / 0.0021 at 1e3 / 1e4 / 1e5
 * (the bench cases, 150-320 pairs, are below the cap: unchanged). */
#define SCALE_PAIRS 512
#define SCALE_PROPOSALS 64 /* 1-point scale proposals per search */
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
/* The final refinement and the scale profile on more pairs than FINAL_SUB
 * first converge on a random subset of FINAL_SUB of them, then take at most
 * FINAL_POLISH Gauss-Newton/LM steps on all of them: from the subset's
 * optimum (within ~sigma / sqrt(FINAL_SUB) of the full one) a step or two
 * reaches the full optimum, and the cost per pair stays constant in N
 * (issue 19: 1e6 pairs in under 2 s; the full refinement took 10 steps of
 * all pairs, twice, and the profile two more such fits). */
#define FINAL_SUB 4096
/* mcgeom.observability's ZERO_FACTOR (|t| shrunk to 1 %: a static rig?) and
 * UNDETERMINED_REL_STD (above it the data define no metric scale at all);
 * tests/test_robust_c.py checks that the two copies agree */
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
#define UNDETERMINED_REL_STD 1.0
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
/* The same error lets a wrong motion win for good: once a hypothesis near
 * a pure rotation (|t| a few cm, fitting the distant points: 20-40 % of
 * the pairs) has been locally optimised, the later hypotheses near the
 * truth, each with its vertical's error, score worse than it at one
 * threshold and are dropped, though most pairs lie within a few
 * thresholds of them (car rig driving forward, 20 % outliers, vertical 0.2
 * deg off: 3 of 200 estimates with 0.2-0.3 of the pairs as inliers where
 * the truth has 0.78, rotation 0.2-0.3 deg and |t| 98 % off, all three
 * called observable). So an upright hypothesis that loses the MSAC but
 * has more pairs than the best within RIVAL_WIDE thresholds, counted on a
 * fixed subset of RIVAL_SUB pairs, challenges it (rival): it is made the
 * best tentatively, gets the scale search and the local optimisation of a
 * new best, and keeps the place only if it then scores better. Measured
 * (200 problems per case of `mcgeom experiment peer_solvers`' cases, 0.2
 * deg off): estimates with the rotation more than 0.1 deg off, car rig
 * forward 3 -> 0, turning 2 -> 0; ring4 and Ladybug none before or after;
 * mean samples 16.4 -> 11.9 (forward), 7.9 -> 5.7 (turning); median time
 * -1 % to +4 %. Within LO_WIDE (4) thresholds rather than 8, one of the
 * three stayed (the hypotheses near the truth had 20-26 of the 64 pairs
 * there against the wrong best's 26; 39 against 28 within 8). `mcgeom
 * experiment ch7 --trials 1200 --seed 10 --cross 0 0.1 0.3
 * --vertical-error-deg 0.2`: estimates more than 30 % off in |t| 713 / 15
 * / 19 -> 709 / 6 / 3, observable 1 / 1185 / 1181 -> 0 / 1194 / 1197,
 * none of the bad called observable before or after; with --seed 11
 * --vertical-error-deg 0.5, bad and called observable 8 / 0 / 0 -> 4 / 0 / 0
 * (the 4: the same trap, the hypotheses near the truth just short of the
 * best's count). Challenging also within 2 pairs of the best's count
 * halved those 4 but cost 3-8 % more time and raised the Ladybug head's
 * median scale error at 50-60 % outliers (40 problems): not taken. */
#define RIVAL_SUB 64
#define RIVAL_WIDE 8.0
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
/* doubles of the solutions of one upright or 6-point sample (R and t) */
#define MINIMAL_SOLUTIONS_SIZE (12 * MCG_SIXPT_MAX_SOLUTIONS)
/* draws of a 6-point sample before one with two cameras is given up */
#define SAMPLE_TRIES 16
/* Pairs of a linear17 or eigensolver sample (MCG_SAMPLER_LINEAR17,
 * MCG_SAMPLER_EIGEN): the fewest that mcg_linear17 solves. The eigensolver
 * sampler (issue 21) takes at most EIGEN_ITERATIONS LM steps from
 * linear17's rotation, with the no-motion trap below EIGEN_TRAP of the
 * start's travel -- the values of mcgeom.estimators.eigensolver's own
 * RANSAC sample (minimal_solutions). */
/* The local 6-point sampler (sample_local) and the check of its solver
 * (found_rate) */
#define HOMOTOPY_EVERY 256  /* of its samples, this one solved by mcg_sixpt */
#define FOUND_CHECKS 16     /* samples of the consensus solved */
#define FOUND_PAIRS 64      /* pairs of the consensus they are drawn from */
#define FOUND_AGREE 0.5     /* a hit: a motion with this fraction of the others */
#define FOUND_MIN_OTHERS 10 /* pool pairs besides a sample, at least */
#define PAIRS17 17
#define EIGEN_ITERATIONS 100
#define EIGEN_TRAP 1e-2

/* doubles of the region c->msol: the solutions of one upright or 6-point
 * sample, or an eigensolver sample's mcg_eigensolver workspace (405 for 17
 * pairs: the solutions' 768 hold it, so the workspace did not grow) */
static size_t sample_work_size(void)
{
    const size_t e = mcg_eigensolver_work_size(PAIRS17);
    return e > MINIMAL_SOLUTIONS_SIZE ? e : MINIMAL_SOLUTIONS_SIZE;
}

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* splitmix64 (Steele, Lea & Flood 2014): a seeded, stateless-to-copy stream */
static uint64_t rng_next(uint64_t *s)
{
    uint64_t z = (*s += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

/* uniform integer in [0, m), m >= 1 (the modulo bias is below 2^-40 for the
 * sizes accepted here) */
static int rng_below(uint64_t *s, int m)
{
    return (int)(rng_next(s) % (uint64_t)m);
}

void mcg_robust_default_options(mcg_robust_options *opt)
{
    if (!opt)
        return;
    opt->threshold = 1e-3;
    opt->prob = 0.999;
    opt->min_iterations = 0;
    opt->max_iterations = 1000;
    opt->max_seconds = 0.0;
    opt->seed = 0;
    opt->lo_rounds = 2;
    opt->refine = 1;
    opt->loss = MCG_LOSS_CAUCHY;
    opt->max_scale_rel_std = 0.0;
    opt->sampler = MCG_SAMPLER_5P1;
    opt->g1[0] = opt->g1[1] = opt->g1[2] = 0.0;
    opt->g2[0] = opt->g2[1] = opt->g2[2] = 0.0;
    opt->verdict_still_factor = 0.0;
}

static int check_sampler(const mcg_robust_options *o);

static int check_options(const mcg_robust_options *o)
{
    if (!(isfinite(o->threshold) && o->threshold > 0.0))
        return 0;
    if (!(o->prob > 0.0 && o->prob < 1.0))
        return 0;
    if (o->max_iterations < 1 || o->max_iterations > 10000000)
        return 0;
    if (o->min_iterations < 0 || o->min_iterations > o->max_iterations)
        return 0;
    if (!(isfinite(o->max_seconds) && o->max_seconds >= 0.0 && o->max_seconds <= 1e9))
        return 0;
    if (o->lo_rounds < 0 || o->lo_rounds > 100)
        return 0;
    if (o->refine != 0 && o->refine != 1)
        return 0;
    if (o->loss < MCG_LOSS_NONE || o->loss > MCG_LOSS_SOFT_L1)
        return 0;
    if (!(isfinite(o->max_scale_rel_std) && o->max_scale_rel_std >= 0.0 &&
          o->max_scale_rel_std <= 10.0))
        return 0;
    if (!(isfinite(o->verdict_still_factor) && o->verdict_still_factor >= 0.0 &&
          o->verdict_still_factor <= 1e6))
        return 0;
    return check_sampler(o);
}

/* ------------------------------------------------------------ workspace */

/* doubles for n ints (rounded up) */
static size_t ints_as_doubles(size_t n) { return (n * sizeof(int) + sizeof(double) - 1) / sizeof(double); }

/* Below PREEMPT_MIN pairs the scale search's workspace lies over the
 * gathered subset (sub, wsub: 13 n doubles), which is dead while
 * mcg_scale_ransac runs (LO and the final stage gather it afresh; the
 * preemptive subset that lives in its tail exists only from PREEMPT_MIN),
 * and the search takes at most as many pairs as fit there (all of them
 * since its workspace is 5 doubles per pair, 13 n / 14 when it was 14);
 * its pairs are indices into the input, not a copy (issue 19: the peak
 * memory of a call on 1e3 pairs was 3.1x, then 2.26x its input, mostly
 * these buffers). */
static int scale_work_aliased(int n) { return n < PREEMPT_MIN; }

/* pairs of the scale search at most */
static int scale_cap(int n)
{
    int cap = n < SCALE_PAIRS ? n : SCALE_PAIRS;
    const int fit = (int)(13 * (size_t)n / mcg_scale_ransac_work_size(1));
    if (scale_work_aliased(n) && cap > fit)
        cap = fit;
    return cap;
}

static size_t scale_work_own(int n)
{
    return scale_work_aliased(n) ? 0 : mcg_scale_ransac_work_size(scale_cap(n));
}

/* pairs of the records' subsets at most (REC_PAIRS per camera) */
static size_t rec_pairs(int n, int n_cameras)
{
    size_t m = (size_t)n_cameras * REC_PAIRS;
    return m < (size_t)n ? m : (size_t)n;
}

static size_t rec_size(int n, int n_cameras)
{
    return (size_t)n_cameras + ints_as_doubles((size_t)n_cameras + 1) +
           ints_as_doubles(rec_pairs(n, n_cameras));
}

size_t mcg_robust_work_size(int n, int n_cameras)
{
    int ok = 1;
    size_t s, nn;
    if (n < 6 || n > MAX_PAIRS || n_cameras < 1 || n_cameras > MAX_CAMERAS)
        return 0;
    nn = (size_t)n;
    /* best and current residuals, pixel scaling, gathered subset (12 n) and
     * its weights, the grouped indices and the group offsets */
    s = mul_sz(nn, 16, &ok);
    s = add_sz(s, ints_as_doubles(nn), &ok);
    s = add_sz(s, ints_as_doubles(2 * (size_t)n_cameras + 2), &ok);
    /* the scale search: its pairs' indices and order, its workspace */
    nn = (size_t)scale_cap(n);
    s = add_sz(s, 2 * ints_as_doubles(nn) + scale_work_own(n), &ok);
    /* the solutions of one minimal sample (the 6-point solver's are the most) */
    s = add_sz(s, sample_work_size(), &ok);
    /* the verdict's evidence (opt.verdict_still_factor) */
    s = add_sz(s, mcg_verdict_stats_work_size(n_cameras), &ok);
    /* the two-stage 5+1: each camera's record score, its subset's offsets
     * and indices */
    s = add_sz(s, rec_size(n, n_cameras), &ok);
    return ok ? s : 0;
}

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

static double msac_sub(ctx *c, const double R[9], const double t[3], double bound);

/* ------------------------------------------------------------ scoring */

/* MSAC score of (R, t) over all pairs (rcur receives |r| in the threshold's
 * unit); stops early and returns +inf once the partial sum reaches `bound`.
 * *n_inl: residuals below the threshold, *n_wide below WIDE thresholds (when
 * completed). */
static double msac2(ctx *c, const double R[9], const double t[3], double bound, int *n_inl,
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

static double msac(ctx *c, const double R[9], const double t[3], double bound, int *n_inl)
{
    int mw;
    return msac2(c, R, t, bound, n_inl, &mw);
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
static void setup_records(ctx *c)
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
static void take_best(ctx *c, const double R[9], const double t[3], double score, int n_inl,
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
static void set_best(ctx *c, const double R[9], const double t[3])
{
    int n_inl, n_wide;
    double sc = msac2(c, R, t, INFINITY, &n_inl, &n_wide);
    take_best(c, R, t, sc, n_inl, n_wide);
}

/* ------------------------------------------------------ preemptive scoring */

/* Copy a stratified random subset of PREEMPT_SUB pairs (one from each of
 * PREEMPT_SUB equal runs of the input order: distinct, each pair equally
 * likely) to the tail of the gather buffers, with their focal lengths. */
static void preempt_setup(ctx *c)
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
static int preempted(ctx *c, const double R[9], const double t[3])
{
    return c->nsub > 0 && c->have && !(msac_sub(c, R, t, c->best_sub) < c->best_sub);
}

/* --------------------------------------------------- refinement on a subset */

/* Gather the pairs with sel(k) into the subset buffers, shifted to their
 * centroid cen (the frame of mcgeom.geometry.refine_centred: |t| held by
 * fix_scale is then the centroid's travel, independent of the rig origin),
 * with weights w(k) (NULL: all 1). Returns the count. */
static int gather(ctx *c, const double *res, double limit, const double *w, double cen[3],
                  double keep)
{
    int k, m = 0, i;
    /* keep < 1: each selected pair is taken with that probability */
    const uint64_t cut = keep < 1.0 ? (uint64_t)(keep * 18446744073709551615.0) : UINT64_MAX;
    double *so1 = c->sub, *sd1 = c->sub + 3 * (size_t)c->n, *so2 = c->sub + 6 * (size_t)c->n,
           *sd2 = c->sub + 9 * (size_t)c->n;
    /* rows from n - nsub on hold the preemptive subset during the search
     * (LO gathers ~LO_MAX of the inliers, but the upright sampler's first
     * round takes every pair within LO_WIDE thresholds of a poor hypothesis,
     * which can be many more) */
    const int rows = c->n - c->nsub;
    cen[0] = cen[1] = cen[2] = 0.0;
    for (k = 0; k < c->n && m < rows; k++) {
        if (!(res[k] < limit) || (cut != UINT64_MAX && rng_next(&c->rng) > cut))
            continue;
        for (i = 0; i < 3; i++) {
            so1[3 * m + i] = c->o1[3 * k + i];
            sd1[3 * m + i] = c->d1[3 * k + i];
            so2[3 * m + i] = c->o2[3 * k + i];
            sd2[3 * m + i] = c->d2[3 * k + i];
            cen[i] += c->o1[3 * k + i] + c->o2[3 * k + i];
        }
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

static int refine_steps(ctx *c, int m, const double cen[3], int weighted, int loss,
                        double scale, int fix_scale, int max_iterations, double R[9],
                        double t[3], mcg_refine_result *out);

/* mcg_refine_motion on the gathered m pairs, (R, t) in the rig frame
 * (converted to and from the centroid frame: t' = t + R c - c). */
static int refine_subset(ctx *c, int m, const double cen[3], int weighted, int loss,
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
static void shuffle_head(ctx *c, int m, int k)
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
static int refine_capped(ctx *c, int m, const double cen[3], int weighted, int loss,
                         double scale, int fix_scale, double R[9], double t[3],
                         mcg_refine_result *out)
{
    mcg_refine_result first;
    int st;
    if (m <= FINAL_SUB)
        return refine_subset(c, m, cen, weighted, loss, scale, fix_scale, R, t, out);
    shuffle_head(c, m, FINAL_SUB);
    st = refine_subset(c, FINAL_SUB, cen, weighted, loss, scale, fix_scale, R, t, &first);
    if (st != MCG_OK)
        return st;
    st = refine_steps(c, m, cen, weighted, loss, scale, fix_scale, FINAL_POLISH, R, t, out);
    if (st == MCG_OK)
        out->iterations += first.iterations;
    return st;
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

/* Weights (focal_k / median)^2 of the fixed pixel scaling, or NULL when
 * every focal is the same (or there is none). */
static const double *fixed_weights(ctx *c)
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
static void local_optimise_held(ctx *c, const double *w, int hold)
{
    const double wide = c->opt.sampler == MCG_SAMPLER_UPRIGHT4 ? LO_WIDE : 1.0;
    int round;
    for (round = 0; round < c->lo_rounds; round++) {
        double R[9], t[3], cen[3], sc;
        int m, n_inl, n_wide, same, k;
        mcg_refine_result rr;
        if (c->n_inl < MIN_REFIT)
            return;
        m = gather(c, c->rbest, c->opt.threshold * (round == 0 ? wide : 1.0), w, cen,
                   c->n_inl > LO_MAX ? (double)LO_MAX / c->n_inl : 1.0);
        if (m < MIN_REFIT)
            return;
        memcpy(R, c->R, sizeof R);
        memcpy(t, c->t, sizeof t);
        c->n_lo++;
        if (refine_steps(c, m, cen, w != NULL, MCG_LOSS_CAUCHY, c->loss_scale, hold,
                         LO_ITERATIONS, R, t, &rr) != MCG_OK)
            return;
        sc = msac2(c, R, t, c->score * (1.0 - 1e-9), &n_inl, &n_wide);
        if (!(sc < c->score * (1.0 - 1e-9)))
            return;
        same = 1;
        for (k = 0; k < c->n && same; k++)
            same = (c->rcur[k] < c->opt.threshold) == (c->rbest[k] < c->opt.threshold);
        take_best(c, R, t, sc, n_inl, n_wide);
        if (same) /* the same inliers would give the same fit again */
            return;
    }
}

static void local_optimise(ctx *c, const double *w) { local_optimise_held(c, w, 1); }

static int gather_others(ctx *c, int a, int cap);
static int unit3(const double *v, double u[3]);
static int depths(const double a[3], const double b[3], const double p[3], double *s1,
                  double *s2);

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

/* |residual| of pair k at (R, t), in the threshold's unit (pixels with
 * focal); NaN for a pair without one (never below a threshold) */
static double pair_residual(const ctx *c, const double R[9], const double t[3], size_t k)
{
    return fabs(sampson_residual(R, t, c->o1 + 3 * k, c->d1 + 3 * k, c->o2 + 3 * k,
                                 c->d2 + 3 * k)) *
           (c->focal ? c->focal[k] : 1.0);
}

/* The upright sampler's subset for its challenges (RIVAL_SUB): one pair
 * from the middle of each of RIVAL_SUB equal runs of the input order (all
 * pairs when there are fewer; no random draw, so the samples are those of
 * a search without it). Off for the other samplers and without LO. */
static void rival_setup(ctx *c)
{
    int j, k = c->n < RIVAL_SUB ? c->n : RIVAL_SUB;
    c->nrival = 0;
    if (c->opt.sampler != MCG_SAMPLER_UPRIGHT4 || c->lo_rounds <= 0)
        return;
    for (j = 0; j < k; j++)
        c->rival_idx[j] = (int)(((double)j + 0.5) * c->n / k);
    c->nrival = k;
}

/* pairs of the challenge subset within RIVAL_WIDE thresholds of (R, t) */
static int rival_count(const ctx *c, const double R[9], const double t[3])
{
    const double lim = RIVAL_WIDE * c->opt.threshold;
    int j, m = 0;
    for (j = 0; j < c->nrival; j++)
        m += pair_residual(c, R, t, (size_t)c->rival_idx[j]) < lim;
    return m;
}

/* The pair (o1, d1) -> (o2, d2) triangulated under (R, t): s1 R d1 +
 * (R o1 + t - o2) = s2 d2 at the closest points. 1 when both depths are
 * positive, 0 when not, -1 for parallel rays (a point at infinity: no
 * depth), -2 for a zero direction. */
static int pair_in_front(const double R[9], const double t[3], const double *o1,
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
        f = pair_in_front(R, t, c->o1 + 3 * k, c->d1 + 3 * k, c->o2 + 3 * k, c->d2 + 3 * k);
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
static int scale_search(ctx *c, const double R[9], const double t0[3], const double u[3],
                        double lam, int a, int from_record)
{
    double sc, t[3], lam2, bound = c->have ? c->score : INFINITY;
    int n_inl = 0, n_wide = 0, i, took = 0, m, cap = scale_cap(c->n);
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
            if (!from_record || (scale_in_front(c, m, R, t) && !preempted(c, R, t))) {
                c->n_hyp++;
                sc = msac2(c, R, t, bound, &n_inl, &n_wide);
                if (sc < bound) {
                    take_best(c, R, t, sc, n_inl, n_wide);
                    took = 1;
                }
            }
        }
        if (c->nx_others)
            c->nx = c->nx_others = 0; /* that set belonged to camera a */
    }
    return took;
}

/* The second stage of the two-stage 5+1 (REC_PAIRS) for the 5-point motion
 * (R, t0 + lam u) of camera a that its sixth pair did not make the best:
 * a record on camera a's subset has its scale searched, and is locally
 * optimised if that makes it the best. */
static void record(ctx *c, const double R[9], const double t0[3], const double u[3],
                   const double *w, int a)
{
    double t[3];
    int i, j, m = 0, end = c->rec_off[a + 1];
    for (i = 0; i < 3; i++)
        t[i] = t0[i] + u[i]; /* (camera a's residuals do not depend on lam > 0) */
    /* (stops once the rest cannot make a record) */
    for (j = c->rec_off[a]; j < end && m + (end - j) > c->rec[a]; j++) {
        m += pair_residual(c, R, t, (size_t)c->rec_idx[j]) < WIDE * c->opt.threshold;
    }
    if (!(m > c->rec[a]))
        return;
    c->rec[a] = m;
    if (scale_search(c, R, t0, u, 0.0, a, 1) && c->lo_rounds > 0)
        local_optimise(c, w);
}

/* An upright hypothesis (R, t0 + lam u; u NULL: t = t0, a motion with its
 * own metric t) that lost the MSAC to the best: when more of the subset's
 * pairs lie within RIVAL_WIDE thresholds of it than of the best, it is
 * made the best tentatively, with the scale search (on a line) and the
 * local optimisation of a new best, and kept if it then scores better than
 * the best did; else the best is restored. 1 when it took the place (see
 * RIVAL_SUB). */
static int rival(ctx *c, const double R[9], const double t0[3], const double u[3],
                 double lam, const double *w, int a)
{
    double Rb[9], tb[3], t[3], score0 = c->score;
    int i;
    if (c->nrival <= 0 || !c->have)
        return 0;
    for (i = 0; i < 3; i++)
        t[i] = u ? t0[i] + lam * u[i] : t0[i];
    /* (the best's count on demand: most new bests, LO's rounds among
     * them, are never challenged) */
    if (c->rival_best < 0)
        c->rival_best = rival_count(c, c->R, c->t);
    if (!(rival_count(c, R, t) > c->rival_best))
        return 0;
    memcpy(Rb, c->R, sizeof Rb);
    memcpy(tb, c->t, sizeof tb);
    set_best(c, R, t);
    if (u)
        scale_search(c, R, t0, u, lam, a, 0);
    local_optimise(c, w);
    if (c->score < score0)
        return 1;
    set_best(c, Rb, tb);
    return 0;
}

/* Score a hypothesis on the line t(lam) = t0 + lam u of its 5-point camera
 * (t = t0 + lam u); keep and locally optimise it if it is the best. A new
 * best first has its scale searched again on the cross-camera pairs (or,
 * with fewer than MIN_CROSS of them, on the pairs not of its 5-point camera
 * a, as the Python proposer did: one noisy sixth pair is a poor start where
 * |t| is weakly observable; measured on the car rig driving forward, 40
 * problems, median scale error of the metric estimate 0.35 -> 0.26)
 * (thesis ch. 7.4: the 1-point scale RANSAC of mcg_scale_ransac, scored on
 * those pairs only): they fix the scale whatever the motion, while the
 * intra-camera pairs, usually most of the data, hardly depend on it near
 * the critical motion and let a wrong scale win the MSAC over all pairs
 * (seen on the DGP surround rig: 4109 vs 4227 inliers, |t| 22 % short). */
static int offer(ctx *c, const double R[9], const double t0[3], const double u[3],
                 double lam, const double *w, int a)
{
    double sc, t[3];
    int n_inl = 0, n_wide = 0, i;
    for (i = 0; i < 3; i++)
        t[i] = t0[i] + lam * u[i];
    c->n_hyp++;
    if (preempted(c, R, t))
        return 0;
    sc = msac2(c, R, t, c->have ? c->score : INFINITY, &n_inl, &n_wide);
    if (!(sc < (c->have ? c->score : INFINITY)))
        return rival(c, R, t0, u, lam, w, a);
    take_best(c, R, t, sc, n_inl, n_wide);
    scale_search(c, R, t0, u, lam, a, 0);
    if (c->lo_rounds > 0)
        local_optimise(c, w);
    return 1;
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
static int final_scale_search(ctx *c, const double cen[3], const double *w)
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
        if (c->opt.sampler != MCG_SAMPLER_UPRIGHT4 || gather_others(c, -1, scale_cap(c->n)) <= 0)
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
    local_optimise_held(c, w, 0);
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
    set_best(c, R0, t); /* (tentatively, to be optimised) */
    local_optimise_held(c, w, 0);
    if (!(c->score < score0)) {
        set_best(c, Rb, Tb);
        return 2;
    }
    return 1;
}

/* The pairs of the scale search: up to scale_cap cross-camera pairs
 * (a random subset when there are more: the scale is one number), when
 * there are at least MIN_CROSS of them. */
static void gather_cross(ctx *c)
{
    int g0 = c->off[c->ncam], m = c->off[c->ncam + 1] - g0, j, cap = scale_cap(c->n);
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

/* ------------------------------------------------------- the 5+1 sample */

/* Unit copy of a 3-vector; 0 if it has no length. */
static int unit3(const double *v, double u[3])
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
static int depths(const double a[3], const double b[3], const double p[3], double *s1,
                  double *s2)
{
    double cab = dot3(a, b), den = 1.0 - cab * cab, ap = dot3(a, p), bp = dot3(b, p);
    if (!(den > PARALLEL_EPS))
        return 0;
    *s1 = (-ap + cab * bp) / den;
    *s2 = (bp - cab * ap) / den;
    return 1;
}

/* Unit null vector of the 3 x 3 matrix's rows (transpose: 1) from the
 * largest cross product of two of them (E has rank 2). */
static int null_vector(const double *e, int transpose, double v[3])
{
    double r[3][3], x[3][3], best = 0.0;
    int i, j, k = -1;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++)
            r[i][j] = transpose ? e[3 * j + i] : e[3 * i + j];
    cross3(r[0], r[1], x[0]);
    cross3(r[1], r[2], x[1]);
    cross3(r[2], r[0], x[2]);
    for (i = 0; i < 3; i++) {
        double s = dot3(x[i], x[i]);
        if (s > best) {
            best = s;
            k = i;
        }
    }
    return k >= 0 && unit3(x[k], v);
}

/* Re-orthonormalise a near-rotation (Gram-Schmidt on its rows): the
 * closed-form decomposition leaves rounding of the 5-point solution that
 * mcg_refine_motion's rotation check (1e-6) could reject. */
static int orthonormalise(double r[9])
{
    double a[3], b[3], c3[3], x;
    if (!unit3(r, a))
        return 0;
    x = dot3(a, r + 3);
    b[0] = r[3] - x * a[0];
    b[1] = r[4] - x * a[1];
    b[2] = r[5] - x * a[2];
    if (!unit3(b, b))
        return 0;
    cross3(a, b, c3);
    memcpy(r, a, sizeof a);
    memcpy(r + 3, b, sizeof b);
    memcpy(r + 6, c3, sizeof c3);
    return 1;
}

/* The two rotations of an essential matrix E = [u]x R (|u| = 1 after
 * scaling |E|_F = sqrt 2): [u]x E = (u u^T - I) R and R^T u = v, the right
 * null vector, give R = u v^T - [u]x E for the sign of v with det R = +1
 * (the other sign gives det -1); the twisted pair is (2 u u^T - I) R
 * (Hartley & Zisserman 9.6.2). u is returned unit, of arbitrary sign. */
static int decompose(const double E[9], double R1[9], double R2[9], double u[3])
{
    double e[9], v[3], ue[9], s = 0.0;
    int i, j;
    for (i = 0; i < 9; i++)
        s += E[i] * E[i];
    if (!(s > 0.0) || !isfinite(s))
        return 0;
    s = sqrt(2.0 / s);
    for (i = 0; i < 9; i++)
        e[i] = E[i] * s;
    if (!null_vector(e, 1, u) || !null_vector(e, 0, v))
        return 0;
    skew_times(u, e, ue); /* [u]x E */
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++)
            R1[3 * i + j] = u[i] * v[j] - ue[3 * i + j];
    if (det33(R1) < 0.0)
        for (i = 0; i < 3; i++)
            for (j = 0; j < 3; j++)
                R1[3 * i + j] -= 2.0 * u[i] * v[j];
    if (!orthonormalise(R1))
        return 0;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) {
            double h[3] = {2.0 * u[i] * u[0] - (i == 0), 2.0 * u[i] * u[1] - (i == 1),
                           2.0 * u[i] * u[2] - (i == 2)};
            R2[3 * i + j] = h[0] * R1[j] + h[1] * R1[3 + j] + h[2] * R1[6 + j];
        }
    return orthonormalise(R2);
}

/* The motion of one rotation candidate of a 5+1 (or upright 3+1) sample:
 * the sign of the camera's translation direction u from the cheirality of
 * its m = 5 (3) points (all in front), the scale lam > 0 from the sixth
 * correspondence (eq. 7.4: a + lam b = 0 with a = d2.((t0 + R o1 - o2) x R d1), b = d2.((u) x R d1),
 * unit bearings), then the sixth point in front of both its rays.
 * `six` < 0: a rig with one camera, lam = 1 (direction only). Returns 1
 * with (t0, u, lam), 2 with (t0, u) and lam = 1 when the sixth pair gives
 * no scale (no offer: the two-stage's record() may still search it), 0
 * when the m are not in front. */
static int candidate(const ctx *c, const double R[9], const double u_in[3],
                     const double b1[15], const double b2[15], int m, const double ca[3],
                     int six, double t0[3], double u[3], double *lam_out)
{
    double rca[3], A[3], t_out[3];
    int k, plus = 0, minus = 0, usable = 0, i;
    for (k = 0; k < m; k++) {
        double s1, s2;
        mat_vec(R, b1 + 3 * k, A);
        if (!depths(A, b2 + 3 * k, u_in, &s1, &s2))
            continue;
        usable++;
        plus += s1 > 0.0 && s2 > 0.0;
        minus += s1 < 0.0 && s2 < 0.0;
    }
    if (usable < 3 || (plus < usable && minus < usable))
        return 0;
    for (i = 0; i < 3; i++)
        u[i] = plus == usable ? u_in[i] : -u_in[i];
    mat_vec(R, ca, rca);
    for (i = 0; i < 3; i++)
        t0[i] = ca[i] - rca[i];
    *lam_out = 1.0;
    if (six < 0)
        return 1;
    {
        const double *o1 = c->o1 + 3 * (size_t)six, *o2 = c->o2 + 3 * (size_t)six;
        double e1[3], e2[3], ro1[3], s0[3], x[3], a, b, lam, g[3], s1, s2;
        if (!unit3(c->d1 + 3 * (size_t)six, e1) || !unit3(c->d2 + 3 * (size_t)six, e2))
            return 2;
        mat_vec(R, e1, A);
        mat_vec(R, o1, ro1);
        for (i = 0; i < 3; i++)
            s0[i] = t0[i] + ro1[i] - o2[i];
        if (dot3(s0, s0) <= 1e-24 * (1.0 + dot3(o1, o1) + dot3(ca, ca))) {
            /* the sixth pair's cameras sit at camera a's centre (a central
             * rig): a = 0 for every lam, no scale; direction only */
            return 1;
        }
        cross3(s0, A, x);
        a = dot3(e2, x);
        cross3(u, A, x);
        b = dot3(e2, x);
        if (!(fabs(b) > 1e-12 * (1.0 + fabs(a))))
            return 2; /* critical for this pair: no scale */
        lam = -a / b;
        if (!(lam > 0.0) || !isfinite(lam))
            return 2;
        for (i = 0; i < 3; i++) {
            t_out[i] = t0[i] + lam * u[i];
            g[i] = ro1[i] + t_out[i] - o2[i];
        }
        /* s1 R d1 + (R o1 + t - o2) = s2 d2: both depths positive */
        if (depths(A, e2, g, &s1, &s2) && !(s1 > 0.0 && s2 > 0.0))
            return 2;
        *lam_out = lam;
    }
    return 1;
}

/* One central sample: m = c->central_m intra-camera pairs of one camera a
 * and a sixth pair. 5+1 (thesis ch. 7): 5 pairs -> mcg_essential5 -> both
 * rotations of each E; upright 3+1 (the vertical known, opt.g1/g2): 3
 * pairs -> mcg_upright3_central (Fraundorfer et al. 2010), the rotation
 * and the direction of camera a's travel -- the two-stage search of
 * REC_PAIRS then as for 5+1 (the sixth pair's scale, the 1-point scale
 * search of a new best, the records), with 3-samples in the adaptive stop
 * (w^3: half the samples of w^5 at 30 % outliers). Returns the number of
 * hypotheses offered, -1 when no camera has m usable pairs. */
#define CENTRAL_CANDIDATES 20 /* 10 essential matrices x 2 rotations */
static int sample(ctx *c, const double *w)
{
    const int mm = c->central_m;
    int total = 0, a, k, m, cnt, start, six = -1, n_e = 0, j, offered = 0, nc = 0;
    double b1[15], b2[15], E[90], ca[3], Rc[9 * CENTRAL_CANDIDATES], uc[3 * CENTRAL_CANDIDATES];
    const int *off = c->off;
    for (k = 0; k < c->ncam; k++) {
        cnt = off[k + 1] - off[k];
        total += cnt >= mm && c->usable[k] ? cnt : 0;
    }
    if (total == 0)
        return -1;
    /* camera a with probability proportional to its intra-camera count */
    m = rng_below(&c->rng, total);
    for (a = 0; a < c->ncam; a++) {
        cnt = off[a + 1] - off[a];
        if (cnt < mm || !c->usable[a])
            continue;
        if (m < cnt)
            break;
        m -= cnt;
    }
    start = off[a];
    cnt = off[a + 1] - start;
    /* mm distinct ones: a partial Fisher-Yates shuffle of camera a's group */
    for (j = 0; j < mm; j++) {
        int r = j + rng_below(&c->rng, cnt - j), tmp = c->perm[start + j], idx;
        c->perm[start + j] = c->perm[start + r];
        c->perm[start + r] = tmp;
        idx = c->perm[start + j];
        if (!unit3(c->d1 + 3 * (size_t)idx, b1 + 3 * j) ||
            !unit3(c->d2 + 3 * (size_t)idx, b2 + 3 * j))
            return 0;
    }
    memcpy(ca, c->o1 + 3 * (size_t)c->perm[start], sizeof ca);
    /* the sixth: a cross-camera one when there are enough, else any one not
     * of camera a (the grouped order skips a's group) */
    {
        int ncross = off[c->ncam + 1] - off[c->ncam], nother = c->n - cnt;
        if (ncross >= MIN_CROSS) {
            six = c->perm[off[c->ncam] + rng_below(&c->rng, ncross)];
        } else if (nother > 0) {
            int r = rng_below(&c->rng, nother);
            six = c->perm[r < start ? r : r + cnt];
        }
    }
    /* the candidates (R, u) of camera a's motion */
    if (mm == 5) {
        if (mcg_essential5(b1, b2, E, &n_e) != MCG_OK)
            return 0;
        for (j = 0; j < n_e; j++) {
            double R1[9], R2[9], u[3];
            if (!decompose(E + 9 * j, R1, R2, u))
                continue;
            memcpy(Rc + 9 * nc, R1, sizeof R1);
            memcpy(uc + 3 * nc++, u, sizeof u);
            memcpy(Rc + 9 * nc, R2, sizeof R2);
            memcpy(uc + 3 * nc++, u, sizeof u);
        }
    } else if (mcg_upright3_central(b1, b2, c->opt.g1, c->opt.g2, Rc, uc, &nc) != MCG_OK) {
        return 0;
    }
    for (j = 0; j < nc; j++) {
        double t0[3], us[3], lam;
        int got = candidate(c, Rc + 9 * j, uc + 3 * j, b1, b2, mm, ca, six, t0, us, &lam);
        int best = 0;
        if (got == 0)
            continue; /* not in front of camera a */
        if (got == 1) {
            best = offer(c, Rc + 9 * j, t0, us, lam, w, six >= 0 ? a : -1);
            offered++;
        }
        if (!best && c->records)
            record(c, Rc + 9 * j, t0, us, w, a);
    }
    return offered;
}

/* ---------------------------------------- the upright and 6-point samples */

/* Score a motion with a metric t of its own (an upright or 6-point
 * solution); keep and locally optimise it if it is the best. */
static int offer_motion(ctx *c, const double R[9], const double t[3], const double *w)
{
    double sc;
    int n_inl = 0, n_wide = 0;
    c->n_hyp++;
    sc = msac2(c, R, t, c->have ? c->score : INFINITY, &n_inl, &n_wide);
    if (!(sc < (c->have ? c->score : INFINITY)))
        return rival(c, R, t, NULL, 0.0, w, -1);
    take_best(c, R, t, sc, n_inl, n_wide);
    if (c->lo_rounds > 0)
        local_optimise(c, w);
    return 1;
}

/* The options of the samplers: a known sampler, and for the upright one a
 * finite vertical of non-zero length at both times. */
static int check_sampler(const mcg_robust_options *o)
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
        int f = pair_in_front(R, t, a1 + 3 * k, b1 + 3 * k, a2 + 3 * k, b2 + 3 * k);
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
        if (!all_finite(R, 9) || !all_finite(t, 3) || !orthonormalise(R) ||
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
                offer(c, R, t0, u, lam, w, c->cam1[idx[a]]);
                continue;
            }
        }
        offer_motion(c, R, t, w);
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
                        &has_scale, &its, c->msol, sample_work_size()) != MCG_OK ||
        !has_scale)
        return 0;
    for (k = 0; k < PAIRS17; k++)
        for (i = 0; i < 3; i++)
            g[i] += (a1[3 * k + i] + a2[3 * k + i]) / (2.0 * PAIRS17);
    if (mcg_eigensolver(PAIRS17, a1, b1, a2, b2, lr.R, 0, R0, t0, &lmin, &has0, &its, c->msol,
                        sample_work_size()) == MCG_OK &&
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
static double found_rate(ctx *c)
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

/* The adaptive stop's sample count: log(1 - prob) / log(1 - found w^m), w the
 * best's fraction within WIDE thresholds (at 1 threshold the tail of the
 * noise, ~16 % of the inliers at 0.5 px noise and 1 px, would count as
 * outliers and more than double the samples drawn for an all-inlier
 * sample), m the sample size, capped at max_iterations */
static int adaptive_count(const ctx *c)
{
    double nw = c->found * pow((double)c->n_wide / c->n, (double)c->sample_size), kk;
    if (nw >= 1.0)
        return 1;
    if (!(nw > 0.0))
        return c->opt.max_iterations;
    kk = log1p(-c->opt.prob) / log1p(-nw);
    return kk < c->opt.max_iterations ? (int)ceil(kk) : c->opt.max_iterations;
}

/* One sample of the options' sampler: the hypotheses offered, or -1 when
 * the data can never give one (5+1: no camera with 5 intra-camera pairs;
 * the eigensolver and linear17: fewer than 17 pairs). */
static int draw(ctx *c, const double *w)
{
    if (c->central_m > 0)
        return sample(c, w);
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

/* ------------------------------------------------------------ phases */

static int check_inputs(int n, const double *o1, const double *d1, const double *o2,
                        const double *d2, const int *cam1, const int *cam2, int n_cameras,
                        const double *focal, const double *cam_axes, const double *cam_focal)
{
    int k;
    if (n < 6 || n > MAX_PAIRS || n_cameras < 1 || n_cameras > MAX_CAMERAS)
        return MCG_EINVAL;
    if (!all_finite(o1, 3 * (size_t)n) || !all_finite(d1, 3 * (size_t)n) ||
        !all_finite(o2, 3 * (size_t)n) || !all_finite(d2, 3 * (size_t)n))
        return MCG_EINVAL;
    for (k = 0; k < n; k++) {
        if (cam1[k] < 0 || cam1[k] >= n_cameras || cam2[k] < 0 || cam2[k] >= n_cameras)
            return MCG_EINVAL;
        if (!(dot3(d1 + 3 * k, d1 + 3 * k) >= 1e-100) ||
            !(dot3(d2 + 3 * k, d2 + 3 * k) >= 1e-100))
            return MCG_EINVAL;
        if (focal && !(isfinite(focal[k]) && focal[k] > 0.0))
            return MCG_EINVAL;
    }
    if ((cam_axes == NULL) != (cam_focal == NULL))
        return MCG_EINVAL;
    if (cam_axes) {
        if (!focal || !all_finite(cam_axes, 3 * (size_t)n_cameras))
            return MCG_EINVAL;
        for (k = 0; k < n_cameras; k++)
            if (!(isfinite(cam_focal[k]) && cam_focal[k] > 0.0))
                return MCG_EINVAL;
    }
    return MCG_OK;
}

static void carve(ctx *c, double *work)
{
    size_t n = (size_t)c->n;
    c->rbest = work;
    c->rcur = work + n;
    c->fsc = work + 2 * n;
    c->sub = work + 3 * n;
    c->wsub = work + 15 * n;
    {
        /* (below PREEMPT_MIN the scale search's workspace lies over sub and
         * wsub: scale_work_own) */
        const size_t m = (size_t)scale_cap(c->n);
        double *after = work + 16 * n, *x;
        c->perm = (int *)after;
        c->off = (int *)(after + ints_as_doubles(n));
        c->usable = c->off + c->ncam + 2;
        x = after + ints_as_doubles(n) + ints_as_doubles(2 * (size_t)c->ncam + 2);
        c->xidx = (int *)x;
        c->xorder = (int *)(x + ints_as_doubles(m));
        x += 2 * ints_as_doubles(m);
        c->xwork = scale_work_aliased(c->n) ? c->sub : x;
        c->msol = x + scale_work_own(c->n);
        c->vwork = c->msol + sample_work_size();
        c->rec = c->vwork + mcg_verdict_stats_work_size(c->ncam);
        c->rec_off = (int *)(c->rec + c->ncam);
        c->rec_idx = (int *)(c->rec + c->ncam + ints_as_doubles((size_t)c->ncam + 1));
    }
}

/* Do the rays of every camera share one origin at both times (within
 * 1e-9 of 1 + the largest |coordinate|)? A central sample (5+1, the upright
 * 3+1) solves its camera's motion about one centre: rays of one camera id
 * from several origins (a generalized camera labelled as one) break that
 * model, and mcgeom.robust refused them for 5+1 in an O(N) numpy pass of
 * scatters and gathers (issue 19: 86 ms of a 0.98 s estimate on 1e6 pairs;
 * this pass ~3 ns a pair). first: n_cameras doubles of scratch (the index
 * 2 k + time of each camera's first ray, exact in a double). */
static int one_centre_per_camera(const ctx *c, double *first)
{
    const size_t n = (size_t)c->n;
    double big = 0.0, tol;
    size_t k;
    int g, i, at2;
    for (k = 0; k < 3 * n; k++) {
        big = fabs(c->o1[k]) > big ? fabs(c->o1[k]) : big;
        big = fabs(c->o2[k]) > big ? fabs(c->o2[k]) : big;
    }
    tol = 1e-9 * (1.0 + big);
    for (g = 0; g < c->ncam; g++)
        first[g] = -1.0;
    for (k = 0; k < n; k++)
        for (at2 = 0; at2 < 2; at2++) {
            const double *o = (at2 ? c->o2 : c->o1) + 3 * k, *ref;
            size_t j;
            g = at2 ? c->cam2[k] : c->cam1[k];
            if (first[g] < 0.0) {
                first[g] = (double)(2 * k + (size_t)at2);
                continue;
            }
            j = (size_t)first[g];
            ref = (j & 1 ? c->o2 : c->o1) + 3 * (j >> 1);
            for (i = 0; i < 3; i++)
                if (!(fabs(o[i] - ref[i]) <= tol))
                    return 0;
        }
    return 1;
}

/* Counting sort of the pairs by group: camera k's intra-camera pairs, then
 * the cross-camera ones (group ncam). */
static void group(ctx *c)
{
    int k, g;
    int *off = c->off;
    for (g = 0; g <= c->ncam + 1; g++)
        off[g] = 0;
    for (k = 0; k < c->n; k++)
        off[(c->cam1[k] == c->cam2[k] ? c->cam1[k] : c->ncam) + 1]++;
    for (g = 0; g <= c->ncam; g++)
        off[g + 1] += off[g];
    /* place with running positions (off[g] advanced, then restored) */
    for (k = 0; k < c->n; k++) {
        g = c->cam1[k] == c->cam2[k] ? c->cam1[k] : c->ncam;
        c->perm[off[g]++] = k;
    }
    for (g = c->ncam; g > 0; g--)
        off[g] = off[g - 1];
    off[0] = 0;
}

/* RMS distance (radians, small angles) of the unit bearings of camera g's
 * intra-camera pairs (time 1: d = d1, else d2) from their best plane through
 * the centre: sqrt of the smallest eigenvalue of mean(u u^T). */
static double plane_rms(const ctx *c, int g, int time2)
{
    double m[9] = {0.0}, ev[3], vec[9];
    int j, i, k, cnt = c->off[g + 1] - c->off[g];
    for (j = c->off[g]; j < c->off[g + 1]; j++) {
        const double *d = (time2 ? c->d2 : c->d1) + 3 * (size_t)c->perm[j];
        double u[3];
        if (!unit3(d, u))
            continue;
        for (i = 0; i < 3; i++)
            for (k = 0; k < 3; k++)
                m[3 * i + k] += u[i] * u[k] / cnt;
    }
    if (mcg_sym_eig(3, m, ev, vec) != MCG_OK)
        return 0.0;
    return ev[0] > 0.0 ? sqrt(ev[0]) : 0.0;
}

/* A camera whose bearings (all of them, outliers too) lie within the
 * threshold of one plane through its centre at either time has no
 * determined essential matrix (points on a line, or a plane through the
 * camera): it is never the 5-point camera (as bearings_planar in
 * mcgeom.estimators.essential). */
static void mark_usable(ctx *c)
{
    int g;
    for (g = 0; g < c->ncam; g++)
        c->usable[g] = c->off[g + 1] - c->off[g] >= c->central_m &&
                       plane_rms(c, g, 0) > c->loss_scale && plane_rms(c, g, 1) > c->loss_scale;
}

/* median of x[0..n) as numpy's (mean of the two middle values for even n),
 * computed on the scratch copy y (internal.h's median_inplace) */
static double median(const double *x, double *y, int n)
{
    memcpy(y, x, (size_t)n * sizeof *y);
    return median_inplace(y, n);
}

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
        return fixed_weights(c);
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
static void finish(ctx *c, mcg_robust_result *res, unsigned char *mask, double *weights_out)
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
        m = gather(c, c->rcur, 0.5, w, cen, 1.0);
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
        st = refine_capped(c, m, cen, w != NULL, c->opt.loss, scale, 0, R, t, &rr);
        if (round == 0 && st == MCG_OK && !(rr.scale_rel_std <= UNDETERMINED_REL_STD)) {
            memcpy(R, R0, sizeof R0);
            memcpy(t, t0, sizeof t0);
            c->final_stage = 1;
            st = refine_capped(c, m, cen, w != NULL, c->opt.loss, scale, 0, R, t, &rr);
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
        (void)msac(c, R, t, INFINITY, &n_inl);
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
static void rescale_refined(ctx *c, mcg_robust_result *res, unsigned char *mask,
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
    set_best(c, Rf, tf);
    jump = final_scale_search(c, cen, w);
    res->hypotheses = c->n_hyp;
    res->local_optimizations = c->n_lo;
    if (jump == 1) { /* the final stage starts again from the jump */
        memcpy(res->t_hypothesis, c->t, sizeof c->t);
        res->score = c->score;
        c->final_stage = 1;
        finish(c, res, mask, weights);
    } else if (jump == 2) {
        /* the jump lost to the refined motion's free local optimisation,
         * which replaced it as the best: the refined motion and its
         * residuals (the inlier mask) back */
        set_best(c, Rf, tf);
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
    if (!orthonormalise(rn))
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
static double scale_profile(ctx *c, const mcg_robust_result *res, const unsigned char *mask,
                            const double *weights, const double *f, int nf, double stop_below)
{
    double cen[3], worst = INFINITY, rc[3], shift[3], base, gain = 1.0;
    int j, i, m, st = MCG_OK;
    const mcg_refine_result *fr = &res->refinement;
    if (!(isfinite(fr->sigma2) && fr->sigma2 > 0.0))
        return 0.0;
    for (j = 0; j < c->n; j++)
        c->rcur[j] = (mask[j] & 2) ? 0.0 : 1.0;
    m = gather(c, c->rcur, 0.5, weights, cen, 1.0);
    if (m < MIN_REFIT)
        return 0.0;
    base = fr->final_cost;
    if (m > FINAL_SUB) {
        double R[9], t[3];
        mcg_refine_result rr;
        shuffle_head(c, m, FINAL_SUB);
        gain = (double)m / FINAL_SUB;
        m = FINAL_SUB;
        memcpy(R, res->R, sizeof R);
        memcpy(t, res->t, sizeof t);
        if (refine_subset(c, m, cen, weights != NULL, c->opt.loss, res->loss_scale, 0, R, t,
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
        st = refine_subset(c, m, cen, weights != NULL, c->opt.loss, res->loss_scale, 1, R, t,
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
static void fill_covariance(mcg_robust_result *res)
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

/* How likely a search of k samples of m pairs drew one of inliers of the
 * final motion's consensus and solved it, w its fraction of the pairs
 * within WIDE thresholds (as the adaptive stop counts them), found the
 * chance that the solver finds a sample's motion (found_rate; 1 for the
 * complete solvers): 1 - (1 - found w^m)^k. The
 * adaptive stop ends the search once the search's best reaches opt.prob;
 * a search that its cap ended below it may return a partial fit: 17-point
 * RANSAC at its 1000-sample cap on the Ladybug head with 30 % outliers
 * returned motions 1-2.4 deg off with 10-16 % of the pairs as inliers in 3
 * of 30 problems (the truth has ~70 %), at a confidence below 1e-7, where
 * the right ones had 0.90-0.92. */
static double search_confidence(int k, int m, double w, double found)
{
    const double p = found * pow(w, (double)m);
    if (k <= 0 || !(p > 0.0))
        return 0.0;
    if (!(p < 1.0))
        return 1.0;
    return -expm1((double)k * log1p(-p));
}

int mcg_robust_rig_motion(int n, const double *o1, const double *d1, const double *o2,
                          const double *d2, const int *cam1, const int *cam2, int n_cameras,
                          const double *focal, const double *cam_axes,
                          const double *cam_focal, const mcg_robust_options *opt,
                          mcg_robust_result *res, unsigned char *mask, double *weights,
                          double *work, size_t lwork)
{
    ctx c;
    double t_start, deadline;
    int st, k, iters = 0, k_needed;
    double cen[3];
    const double *wlo;

    if (!o1 || !d1 || !o2 || !d2 || !cam1 || !cam2 || !res || !mask || !work)
        return MCG_EINVAL;
    memset(res, 0, sizeof *res);
    memset(&c, 0, sizeof c);
    /* the clock covers the input checks too (O(N): part of the call's cost,
     * and of the time budget) */
    t_start = now_seconds();
    if (opt)
        c.opt = *opt;
    else
        mcg_robust_default_options(&c.opt);
    if (!check_options(&c.opt))
        return MCG_EINVAL;
    st = check_inputs(n, o1, d1, o2, d2, cam1, cam2, n_cameras, focal, cam_axes, cam_focal);
    if (st != MCG_OK)
        return st;
    if (lwork < mcg_robust_work_size(n, n_cameras))
        return MCG_ENOMEM;
    deadline = c.opt.max_seconds > 0.0 ? t_start + c.opt.max_seconds : INFINITY;
    c.n = n;
    c.ncam = n_cameras;
    c.o1 = o1;
    c.d1 = d1;
    c.o2 = o2;
    c.d2 = d2;
    c.cam1 = cam1;
    c.cam2 = cam2;
    c.focal = focal;
    c.cam_axes = cam_axes;
    c.cam_focal = cam_focal;
    c.thr2 = c.opt.threshold * c.opt.threshold;
    c.rng = (uint64_t)c.opt.seed;
    c.refine_target = -HUGE_VAL;
    c.lo_rounds = c.opt.lo_rounds;
    carve(&c, work);
    group(&c);
    if (c.opt.sampler == MCG_SAMPLER_AUTO) {
        /* mcgeom.cv.choose_sampler's rule, from the group counts (issue
         * 19: its numpy passes cost ~60 us of a cold call's Python) */
        int has5 = 0;
        for (k = 0; k < n_cameras; k++)
            has5 |= c.off[k + 1] - c.off[k] >= 5;
        c.opt.sampler = has5 ? MCG_SAMPLER_5P1 : MCG_SAMPLER_6PT_LOCAL;
    }
    res->sampler = c.opt.sampler;
    /* central samples: 5+1; the upright sampler's 3+1 when a camera has 3
     * intra-camera pairs (else, and when none of those cameras is usable
     * below, the 4-point samples of any cameras) */
    c.central_m = c.opt.sampler == MCG_SAMPLER_5P1 ? 5 : 0;
    if (c.opt.sampler == MCG_SAMPLER_UPRIGHT4)
        for (k = 0; k < n_cameras; k++)
            if (c.off[k + 1] - c.off[k] >= 3)
                c.central_m = 3;
    c.med_focal = 1.0;
    c.const_focal = 1;
    if (focal) {
        double fmax = focal[0];
        c.med_focal = median(focal, c.rcur, n);
        for (k = 0; k < n; k++) {
            c.const_focal &= focal[k] == focal[0];
            fmax = focal[k] > fmax ? focal[k] : fmax;
        }
        if (cam_axes) {
            double cf = 0.0;
            for (k = 0; k < n_cameras; k++)
                cf = cam_focal[k] > cf ? cam_focal[k] : cf;
            c.min_var_ratio = 1e-12 / (cf * cf);
        }
    }
    c.loss_scale = c.opt.threshold / c.med_focal;
    c.size = origin_spread(n, o1, o2, cen);
    c.size += sqrt(dot3(cen, cen));
    /* (only central samples read usable: their camera, and the records) */
    if (c.central_m > 0)
        mark_usable(&c);
    if (c.central_m == 3) {
        int any = 0;
        for (k = 0; k < n_cameras; k++)
            any |= c.usable[k];
        c.central_m = any ? 3 : 0;
    }
    /* (c.rec is scratch until setup_records) */
    if (c.central_m > 0 && !one_centre_per_camera(&c, c.rec))
        return MCG_EINVAL;
    /* (the two-stage search counts central samples: REC_PAIRS) */
    c.records = c.central_m > 0;
    c.sample_size = c.records                                   ? c.central_m
                    : c.opt.sampler == MCG_SAMPLER_UPRIGHT4    ? 4
                    : c.opt.sampler == MCG_SAMPLER_EIGEN ||
                      c.opt.sampler == MCG_SAMPLER_LINEAR17 ? PAIRS17
                                                               : 6;
    res->sample_size = c.sample_size;
    if (c.records)
        setup_records(&c);
    gather_cross(&c);
    preempt_setup(&c);
    rival_setup(&c);
    /* the LO weights live in fsc until the final stage reuses it */
    wlo = c.lo_rounds > 0 ? fixed_weights(&c) : NULL;

    /* search */
    k_needed = c.opt.max_iterations;
    c.found = 1.0;
    c.found_at = -1;
    c.local_samples = 0;
    for (;;) {
        int exhausted = 0;
        while (iters < c.opt.max_iterations &&
               (iters < k_needed || iters < c.opt.min_iterations)) {
            int before = c.have ? c.n_wide : -1, got;
            iters++;
            got = draw(&c, wlo);
            if (got < 0) {
                exhausted = 1; /* no camera with 5 intra-camera pairs (5+1), n < 17 */
                break;
            }
            if (c.have && c.n_wide != before)
                k_needed = adaptive_count(&c);
            /* (a 6-point sample takes ~0.03 s: the clock after each one) */
            if ((iters % CLOCK_EVERY == 0 || c.opt.sampler == MCG_SAMPLER_6PT) &&
                now_seconds() > deadline) {
                res->stop = MCG_ROBUST_STOP_TIME;
                break;
            }
        }
        /* the local 6-point solver may have missed all-inlier samples: once
         * the stop is reached, measure how often it finds this consensus'
         * motion and draw on while the stop, so corrected, asks for more
         * (again when the consensus has grown since) */
        if (exhausted || res->stop == MCG_ROBUST_STOP_TIME ||
            c.opt.sampler != MCG_SAMPLER_6PT_LOCAL || !c.have || c.found_at == c.n_wide ||
            iters >= c.opt.max_iterations)
            break;
        c.found = found_rate(&c);
        c.found_at = c.n_wide;
        k_needed = adaptive_count(&c);
        if (iters >= k_needed && iters >= c.opt.min_iterations)
            break;
    }
    /* (a search its cap or clock ended: the rate for its confidence) */
    if (c.opt.sampler == MCG_SAMPLER_6PT_LOCAL && c.have && c.found_at != c.n_wide) {
        c.found = found_rate(&c);
        c.found_at = c.n_wide;
    }
    res->found_rate = c.found;
    if (res->stop != MCG_ROBUST_STOP_TIME)
        res->stop = iters >= c.opt.max_iterations ? MCG_ROBUST_STOP_MAX_ITERATIONS
                                                   : MCG_ROBUST_STOP_CONFIDENCE;
    c.records = 0; /* (the search's bookkeeping) */
    (void)final_scale_search(&c, cen, wlo);
    res->iterations = iters;
    res->hypotheses = c.n_hyp;
    res->local_optimizations = c.n_lo;
    if (!c.have || c.n_inl < MIN_REFIT) {
        res->n_inliers = c.have ? c.n_inl : 0;
        fill_covariance(res);
        res->seconds = now_seconds() - t_start;
        return MCG_EDEGENERATE;
    }
    memcpy(res->t_hypothesis, c.t, sizeof c.t);
    res->score = c.score;
    c.nsub = 0; /* the final stage gathers over the preemptive subset */

    /* finish */
    for (k = 0; k < n; k++)
        mask[k] = 0;
    if (weights)
        for (k = 0; k < n; k++)
            weights[k] = 0.0;
    res->loss_scale = focal ? c.loss_scale : c.opt.threshold;
    res->scale_profile = NAN;
    c.final_stage = 1;
    if (c.opt.refine) {
        finish(&c, res, mask, weights);
        rescale_refined(&c, res, mask, weights, cen, wlo);
    }
    c.final_stage = 0;
    memcpy(res->R, c.R, sizeof c.R);
    memcpy(res->t, c.t, sizeof c.t);
    res->zero_profile = NAN;
    if (res->refined && c.opt.max_scale_rel_std > 0.0) {
        const double *wp =
            weights ? weights : (focal && (cam_axes || !c.const_focal) ? c.fsc : NULL);
        const double srs = res->refinement.scale_rel_std,
                     k1 = 1.0 + 3.0 * c.opt.max_scale_rel_std;
        const double f[2] = {1.0 / k1, k1}, f0[1] = {ZERO_FACTOR};
        if (srs <= c.opt.max_scale_rel_std)
            res->scale_profile = scale_profile(&c, res, mask, wp, f, 2, -HUGE_VAL);
        /* "could the cameras not have moved at all?" where the verdict will
         * not call the scale observable but it may still be determined
         * (mcgeom.observability.scale_determined: the profile at
         * ZERO_FACTOR decides; Python computed it in numpy before) */
        if (srs <= UNDETERMINED_REL_STD &&
            (srs > c.opt.max_scale_rel_std || !(res->scale_profile >= 9.0)))
            res->zero_profile = scale_profile(&c, res, mask, wp, f0, 1, ZERO_PROFILE_BOUND);
    }
    res->n_inliers = 0;
    res->inlier_rms = NAN;
    {
        double ss = 0.0, wide = WIDE * c.opt.threshold;
        int n_wide = 0;
        for (k = 0; k < n; k++) {
            int in = c.rbest[k] < c.opt.threshold;
            mask[k] = (unsigned char)((mask[k] & 2) | in);
            res->n_inliers += in;
            n_wide += c.rbest[k] < wide;
            if (in)
                ss += c.rbest[k] * c.rbest[k];
        }
        if (res->n_inliers > 0)
            res->inlier_rms = sqrt(ss / res->n_inliers);
        res->confidence = search_confidence(res->iterations, c.sample_size, (double)n_wide / n,
                                            c.found);
    }
    fill_covariance(res);
    if (c.opt.verdict_still_factor > 0.0) {
        /* the evidence in the same call (issue 19: the verdict's own
         * cffi call and its Python wrapper were ~1/8 of a cold call's
         * Python); the still angle as mcgeom.observability.scale_verdict_stats */
        double still = isfinite(res->loss_scale)
                           ? c.opt.verdict_still_factor * res->loss_scale : 0.0;
        still = still >= 4.0 ? 3.5 : (still >= 0.0 ? still : 0.0);
        res->have_verdict = mcg_verdict_stats(n, o1, d1, o2, d2, cam1, cam2, n_cameras, mask,
                                              res->R, res->t, still, &res->verdict, c.vwork,
                                              mcg_verdict_stats_work_size(n_cameras)) == MCG_OK;
    }
    res->seconds = now_seconds() - t_start;
    return MCG_OK;
}
