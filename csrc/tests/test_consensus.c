/*
 * test_consensus.c -- plain-C checks of csrc/consensus.c
 * (mcg_consensus_check). The decisions against an independent numpy
 * reference are tests/test_consensus.py's; here, what a C user relies on:
 * a clean least-squares fit of a 4-camera rig is metric, drops no pair, and
 * its std is at most widened; the residuals' std with a calibration part
 * beyond max_rel_std is refused; a gross outlier among the few
 * cross-camera pairs that fix the scale, absorbed by the fit, is refused;
 * weights of 0 for pairs outside the consensus; the status codes (bad
 * arguments, a workspace too small, a singular fit decides nothing).
 * Exit status 0 iff every check passes.
 */
#include "mcgeom.h"

#define TEST_SEED 0xc025e125ULL
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NC 4
#define PER 15
#define NX 4                 /* cross-camera pairs */
#define N (NC * PER + NX + 6) /* and 6 pairs outside the consensus */

static double o1[3 * N], d1[3 * N], o2[3 * N], d2[3 * N], w[N];

/* 4 cameras on a ring (radius 0.5 m), PER pairs each, NX from camera g at
 * time 1 to camera g + 1 at time 2, then 6 random pairs of weight 0 */
static void scene(const double R[9], const double t[3], double noise)
{
    int g, k, m = 0;
    for (g = 0; g < NC + NX; ++g) {
        int a = g < NC ? g : g - NC, b = g < NC ? g : (a + 1) % NC, per = g < NC ? PER : 1;
        double ca[3] = {0.5 * cos(1.5707963267948966 * a), 0.5 * sin(1.5707963267948966 * a), 0};
        double cb[3] = {0.5 * cos(1.5707963267948966 * b), 0.5 * sin(1.5707963267948966 * b), 0};
        for (k = 0; k < per; ++k, ++m) {
            scene_correspondence(ca, cb, R, t, noise, o1 + 3 * m, d1 + 3 * m, o2 + 3 * m,
                                 d2 + 3 * m);
            w[m] = 1.0;
        }
    }
    for (; m < N; ++m) {
        double c[3] = {0.5, 0.0, 0.0};
        scene_correspondence(c, c, R, t, 0.0, o1 + 3 * m, d1 + 3 * m, o2 + 3 * m, d2 + 3 * m);
        randn(d2 + 3 * m, 3); /* a wrong match, outside the consensus */
        w[m] = 0.0;
    }
}

/* the least-squares fit on the pairs of weight 1, from (R, t) */
static int fit(const double R[9], const double t[3], double Rf[9], double tf[3], double *rel)
{
    mcg_refine_result rr;
    int st;
    memcpy(Rf, R, 9 * sizeof(double));
    memcpy(tf, t, 3 * sizeof(double));
    st = mcg_refine_motion(N, o1, d1, o2, d2, w, NULL, Rf, tf, &rr);
    *rel = rr.scale_rel_std;
    return st;
}

int main(void)
{
    double R[9], t[3] = {0.6, -0.3, 0.1}, axis[3] = {0.2, 0.3, 1.0}, Rf[9], tf[3], rel;
    size_t lw = mcg_consensus_check_work_size(N);
    double *work = malloc(lw * sizeof(double));
    mcg_consensus_result c;
    int st;
    if (!work)
        return 2;
    rot_about(axis, 0.3, R);
    scene(R, t, 2e-3);
    check_status(fit(R, t, Rf, tf, &rel), MCG_OK, "clean fit");
    st = mcg_consensus_check(N, o1, d1, o2, d2, w, Rf, tf, rel, 0.0, 0.1, &c, work, lw);
    check_status(st, MCG_OK, "clean: status");
    check(c.reason == MCG_CONSENSUS_METRIC && c.n_dropped == 0 && c.have_stats &&
              c.rel_std >= rel && !c.have_move,
          "clean: metric, no pair dropped, std at most widened", c.rel_std / rel, 1.0);
    check(c.rel_std <= 1.25 * c.residuals_rel_std + rel && c.residuals_rel_std > 0.0,
          "clean: the residuals' std is positive and bounds any widening",
          c.residuals_rel_std / rel, 1.0);
    st = mcg_consensus_check(N, o1, d1, o2, d2, w, Rf, tf, rel, 0.5, 0.1, &c, work, lw);
    check(st == MCG_OK && c.reason == MCG_CONSENSUS_RESIDUALS_STD && c.rel_std > 0.5,
          "a calibration part of 0.5: the residuals' std refused", c.rel_std, 0.5);

    /* a gross outlier among the cross-camera pairs, absorbed by the fit: a
     * small rotation, so that the intra-camera pairs hardly fix |t| (the
     * near-critical motion of thesis ch. 7.3.2) and the cross-camera ones
     * carry it */
    rot_about(axis, 0.02, R);
    scene(R, t, 2e-3);
    d2[3 * (NC * PER)] += 0.4;
    d2[3 * (NC * PER) + 2] -= 0.3;
    check_status(fit(R, t, Rf, tf, &rel), MCG_OK, "fit with the outlier");
    st = mcg_consensus_check(N, o1, d1, o2, d2, w, Rf, tf, rel, 0.0, 0.1, &c, work, lw);
    check(st == MCG_OK && c.reason != MCG_CONSENSUS_METRIC && c.stats.max_influence_stds > 4.0,
          "a cross-camera outlier carrying the fit: not metric", c.stats.max_influence_stds, 4.0);

    check_status(mcg_consensus_check(N, o1, d1, o2, d2, w, Rf, tf, rel, 0.0, 0.1, &c, work,
                                     lw - 1),
                 MCG_ENOMEM, "workspace one double short");
    check_status(mcg_consensus_check(N, o1, d1, o2, d2, NULL, Rf, tf, rel, 0.0, 0.1, &c, work,
                                     lw),
                 MCG_EINVAL, "NULL weights");
    check_status(mcg_consensus_check(N, o1, d1, o2, d2, w, Rf, tf, -1.0, 0.0, 0.1, &c, work,
                                     lw),
                 MCG_EINVAL, "a negative rel_std");
    check_status(mcg_consensus_check(N, o1, d1, o2, d2, w, Rf, tf, rel, NAN, 0.1, &c, work, lw),
                 MCG_EINVAL, "a NaN calibration part");
    check_status(mcg_consensus_check(N, o1, d1, o2, d2, w, Rf, tf, rel, 0.0, 0.0, &c, work, lw),
                 MCG_EINVAL, "max_rel_std 0");
    w[2] = -1.0;
    check_status(mcg_consensus_check(N, o1, d1, o2, d2, w, Rf, tf, rel, 0.0, 0.1, &c, work, lw),
                 MCG_EINVAL, "a negative weight");
    w[2] = 1.0;
    {
        /* one centre for every pair: |t| is fixed by none, nothing decided */
        static double z[3 * N];
        st = mcg_consensus_check(N, z, d1, z, d2, w, R, t, 0.01, 0.0, 0.1, &c, work, lw);
        check(st == MCG_OK && c.reason == MCG_CONSENSUS_METRIC && !c.have_stats &&
                  c.rel_std == 0.01,
              "a singular fit: nothing decided", c.rel_std, 0.01);
    }
    free(work);
    printf("%d checks, %d failed\n", n_checks, n_failed);
    return n_failed != 0;
}
