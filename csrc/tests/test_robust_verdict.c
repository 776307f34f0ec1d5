/*
 * test_robust_verdict.c -- plain-C checks of the robust estimate's scale
 * verdict (csrc/robust_verdict.c, res->scale of mcg_robust_rig_motion) and
 * of its pixel entry point (csrc/robust_pinhole.c):
 *  - mcg_scale_reason against the rule spelled out here, at each boundary
 *    (6 / 7 inliers, rel_std at max_rel_std, a profile of 9, the critical
 *    angle 0.05 deg, half of the inliers in front, the -1 of an uncounted
 *    cheirality);
 *  - a ring of 4 pinholes with cross-camera pairs and 20 % outliers: the
 *    scale observable, t reported metric and equal to res->t, the
 *    calibration part of rel_std and of the covariance equal to an
 *    independent mcg_calibration_scale_std on the pairs the result says it
 *    used, rel_std their quadrature, the same with the weights' output NULL;
 *  - the same rig driving straight without cross-camera pairs (the critical
 *    motion, thesis ch. 7.3.2): not observable, a unit t along the travel;
 *  - a static rig: the static verdict (t = 0) or no motion found;
 *  - a search its cap ended early: unconfirmed exactly when the confidence
 *    is below 0.5;
 *  - no verdict without evidence (verdict_still_factor 0), and EINVAL for a
 *    negative or NaN calibration std;
 *  - mcg_robust_rig_motion_pinhole: the same result as mcg_pinhole_ray_pairs
 *    followed by mcg_robust_rig_motion (bit for bit), the rays in its
 *    workspace, the stages' times (seconds_*) summing to seconds,
 *    EDEGENERATE for fewer than 6 distinct correspondences, EINVAL for an
 *    id out of range, ENOMEM for a short workspace.
 * Exit status 0 iff every check passes.
 */
#include "mcgeom.h"

#define TEST_SEED 0x5ca1ec0dedULL
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NCAM 4
#define N 300
#define F 700.0 /* pixels */

static double intr[5 * NCAM], rot[9 * NCAM], centres[3 * NCAM], fmean[NCAM];
static double px1[2 * N], px2[2 * N];
static long long ids1[N], ids2[N];
static double o1[3 * N], d1[3 * N], o2[3 * N], d2[3 * N], ppr[N];
static int c1[N], c2[N];
static unsigned char mask[N], mask_b[N];
static double wts[N], wts_b[N];

/* A ring of NCAM pinholes (radius 0.5 m, looking outward, f = F, 640 x 480) */
static void make_rig(void)
{
    int k, i;
    for (k = 0; k < NCAM; k++) {
        const double a = 6.283185307179586 * k / NCAM;
        /* cam_from_rig: rows x = (-sin a, cos a, 0), y = (0, 0, -1), z = (cos a, sin a, 0) */
        const double r[9] = {-sin(a), cos(a), 0.0, 0.0, 0.0, -1.0, cos(a), sin(a), 0.0};
        for (i = 0; i < 9; i++)
            rot[9 * k + i] = r[i];
        centres[3 * k] = 0.5 * cos(a);
        centres[3 * k + 1] = 0.5 * sin(a);
        centres[3 * k + 2] = 0.0;
        intr[5 * k] = intr[5 * k + 1] = F;
        intr[5 * k + 2] = 320.0;
        intr[5 * k + 3] = 240.0;
        intr[5 * k + 4] = 0.0;
        fmean[k] = F;
    }
}

/* pixel of the rig-frame point X in camera k (0 if behind it) */
static int project(int k, const double X[3], double px[2])
{
    double y[3], x[3];
    int i;
    for (i = 0; i < 3; i++)
        y[i] = X[i] - centres[3 * k + i];
    for (i = 0; i < 3; i++)
        x[i] = rot[9 * k + 3 * i] * y[0] + rot[9 * k + 3 * i + 1] * y[1] +
               rot[9 * k + 3 * i + 2] * y[2];
    if (!(x[2] > 0.1))
        return 0;
    px[0] = F * x[0] / x[2] + 320.0 + 0.5 * nrand();
    px[1] = F * x[1] / x[2] + 240.0 + 0.5 * nrand();
    return 1;
}

/* n pairs of the motion (R, t): camera k % NCAM at time 1, at time 2 the
 * same one or (every 4th, when cross) the next; the first n_out pairs get
 * random time-2 pixels */
static void pixels(int n, int n_out, int cross, const double R[9], const double t[3])
{
    int k = 0, i;
    while (k < n) {
        int g = k % NCAM, h = cross && k % 4 == 3 ? (g + 1) % NCAM : g;
        const double a = 6.283185307179586 * g / NCAM + 0.5 * (urand() - 0.5);
        const double depth = 3.0 + 15.0 * urand(), z = 2.0 * (urand() - 0.5);
        double X[3] = {0.5 * cos(a) + depth * cos(a), 0.5 * sin(a) + depth * sin(a), z}, X2[3];
        if (h != g) { /* a point the next camera sees too */
            const double b = 6.283185307179586 * (g + 0.5) / NCAM;
            X[0] = 8.0 * cos(b);
            X[1] = 8.0 * sin(b);
        }
        for (i = 0; i < 3; i++)
            X2[i] = R[3 * i] * X[0] + R[3 * i + 1] * X[1] + R[3 * i + 2] * X[2] + t[i];
        if (!project(g, X, px1 + 2 * k) || !project(h, X2, px2 + 2 * k))
            continue;
        if (k < n_out) {
            px2[2 * k] = 640.0 * urand();
            px2[2 * k + 1] = 480.0 * urand();
        }
        ids1[k] = g;
        ids2[k] = h;
        k++;
    }
}

static void options(mcg_robust_options *opt, const double *ext)
{
    mcg_robust_default_options(opt);
    opt->threshold = 1.0; /* pixels */
    opt->max_scale_rel_std = 0.1;
    opt->verdict_still_factor = 1.5;
    opt->seed = 3;
    opt->extrinsic_std = ext;
}

/* the pinhole entry, and the same on the rays by the two calls it makes */
static int run(int n, const mcg_robust_options *opt, mcg_robust_result *res, double *work,
               size_t lwork)
{
    return mcg_robust_rig_motion_pinhole(n, NCAM, intr, rot, centres, fmean, ids1, ids2, px1,
                                         px2, opt, res, mask, wts, work, lwork);
}

static void reason_case(void)
{
    const double inf = HUGE_VAL, crit = 1.0 * 3.14159265358979 / 180.0;
    /* (n_in, n_cross, n_cams, critical angle, rel_std, profile, n_front) -> want */
    struct {
        int n_in, n_cross, n_cams;
        double crit, rel, profile;
        int front, want;
    } t[] = {
        {6, 10, 4, crit, 0.01, 100.0, 6, MCG_SCALE_NO_REDUNDANCY},
        {7, 0, 4, crit, 0.01, 100.0, 7, MCG_SCALE_OBSERVABLE},
        {7, 0, 4, crit, 0.1, 9.0, 4, MCG_SCALE_OBSERVABLE},   /* at the bounds */
        {7, 0, 4, crit, 0.1, 9.0, 3, MCG_SCALE_CHEIRALITY},   /* 3 / 7 < 0.5 */
        {100, 0, 4, crit, 0.1000001, 100.0, 100, MCG_SCALE_UNCERTAIN},
        {100, 0, 4, crit, 0.01, 8.999, 100, MCG_SCALE_UNCERTAIN},
        {100, 0, 4, crit, inf, NAN, 100, MCG_SCALE_UNCERTAIN},
        {100, 0, 1, crit, 0.5, NAN, 100, MCG_SCALE_ONE_CAMERA},
        {100, 0, 4, 0.0499 * 3.14159265358979 / 180.0, 0.5, NAN, 100, MCG_SCALE_CRITICAL},
        {100, 1, 4, 0.0, 0.5, NAN, 100, MCG_SCALE_UNCERTAIN}, /* a cross pair: not critical */
        {100, 5, 4, crit, 0.01, NAN, 100, MCG_SCALE_OBSERVABLE}, /* no profile computed */
        {100, 5, 4, crit, 0.01, NAN, -1, -1},                 /* cheirality not counted */
        {100, 5, 4, crit, 0.5, NAN, -1, MCG_SCALE_UNCERTAIN}, /* ... and not needed */
    };
    int k, bad = 0;
    for (k = 0; k < (int)(sizeof t / sizeof t[0]); k++) {
        int got = mcg_scale_reason(t[k].n_in, t[k].n_cross, t[k].n_cams, t[k].crit, t[k].rel,
                                   0.1, t[k].profile, t[k].front);
        if (got != t[k].want) {
            printf("  row %d: reason %d, want %d\n", k, got, t[k].want);
            bad++;
        }
    }
    check(bad == 0, "mcg_scale_reason: the rule at its boundaries (rows wrong)", bad, 0);
    check(strcmp(mcg_scale_reason_string(MCG_SCALE_CRITICAL),
                 "critical motion: camera displacements parallel") == 0 &&
              strcmp(mcg_scale_reason_string(99), "unknown") == 0,
          "mcg_scale_reason_string", 0, 0);
}

static double norm3(const double v[3]) { return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

static void observable_case(double *work, size_t lwork)
{
    const double aa[3] = {0.02, 0.15, -0.03}, t[3] = {0.3, -0.6, 0.05};
    double R[9], ext[2 * NCAM], so1[3 * N], sd1[3 * N], so2[3 * N], sd2[3 * N], sw[N];
    double rel_cal = -1.0, cov[36], dcov = 0.0, *cw;
    int sc1[N], sc2[N], m = 0, k, i, st, equal = 1;
    mcg_robust_options opt;
    mcg_robust_result res;
    for (k = 0; k < NCAM; k++) {
        ext[2 * k] = 2e-3;
        ext[2 * k + 1] = 2e-4;
    }
    mcg_rot_from_angle_axis(aa, R);
    pixels(N, N / 5, 1, R, t);
    options(&opt, ext);
    st = run(N, &opt, &res, work, lwork);
    check_status(st, MCG_OK, "ring with cross pairs: status");
    check(res.have_scale && res.scale.reason == MCG_SCALE_OBSERVABLE && res.scale.observable &&
              res.scale.determined && res.scale.translation_detected,
          "ring with cross pairs: scale observable", res.scale.reason, 0);
    check(memcmp(res.scale.t, res.t, sizeof res.t) == 0 &&
              memcmp(res.scale.t_metric, res.t, sizeof res.t) == 0,
          "  t reported metric: res.scale.t == res.t", 0, 0);
    check(fabs(norm3(res.scale.t) / norm3(t) - 1.0) < 0.05, "  |t| against the truth",
          fabs(norm3(res.scale.t) / norm3(t) - 1.0), 0.05);
    /* the calibration part, independently: the pairs of mask bit 1 */
    for (k = 0; k < N; k++) {
        if (!(mask[k] & 2))
            continue;
        for (i = 0; i < 3; i++) {
            so1[3 * m + i] = work[3 * k + i];
            sd1[3 * m + i] = work[3 * N + 3 * k + i];
            so2[3 * m + i] = work[6 * N + 3 * k + i];
            sd2[3 * m + i] = work[9 * N + 3 * k + i];
        }
        sc1[m] = (int)ids1[k];
        sc2[m] = (int)ids2[k];
        sw[m] = wts[k];
        equal &= sw[m] == sw[0];
        m++;
    }
    cw = malloc(mcg_calibration_std_work_size(NCAM) * sizeof *cw);
    if (!cw)
        exit(2);
    st = mcg_calibration_scale_std(m, so1, sd1, so2, sd2, sc1, sc2, NCAM, ext, res.R, res.t,
                                   equal ? NULL : sw, opt.loss, res.loss_scale, &rel_cal, cov, cw,
                                   mcg_calibration_std_work_size(NCAM));
    free(cw);
    for (i = 0; i < 36; i++)
        dcov = fmax(dcov, fabs(res.scale.covariance[i] - (res.covariance[i] + cov[i])) /
                              (fabs(res.covariance[i] + cov[i]) + 1e-300));
    check(st == MCG_OK && fabs(res.scale.rel_std_calibration - rel_cal) <= 1e-12 * rel_cal &&
              rel_cal > 0.0,
          "  calibration part == mcg_calibration_scale_std on the used pairs",
          res.scale.rel_std_calibration - rel_cal, 1e-12 * rel_cal);
    check(dcov <= 1e-12, "  covariance == the refinement's + the calibration's", dcov, 1e-12);
    check(fabs(res.scale.rel_std - hypot(res.scale.rel_std_noise, rel_cal)) <= 1e-15 *
              res.scale.rel_std && res.scale.rel_std_noise == res.refinement.scale_rel_std,
          "  rel_std: noise and calibration in quadrature", res.scale.rel_std, 0);
    check(res.scale.profile >= 9.0 && res.scale.front_fraction >= 0.5,
          "  its profile (>= 9) and cheirality (>= 0.5)", res.scale.profile, 9.0);

    /* without the weights' output buffer the verdict weighs as the final
     * refinement did (its own pixel scaling), the same as with it */
    {
        mcg_robust_result r2;
        st = mcg_robust_rig_motion_pinhole(N, NCAM, intr, rot, centres, fmean, ids1, ids2, px1,
                                           px2, &opt, &r2, mask, NULL, work, lwork);
        check(st == MCG_OK && r2.scale.rel_std_calibration == res.scale.rel_std_calibration &&
                  r2.scale.rel_std == res.scale.rel_std && r2.scale.reason == res.scale.reason,
              "  the same verdict without the weights' output (NULL)",
              r2.scale.rel_std_calibration - res.scale.rel_std_calibration, 0);
    }
    /* no verdict without its evidence */
    opt.verdict_still_factor = 0.0;
    st = run(N, &opt, &res, work, lwork);
    check(st == MCG_OK && !res.have_scale && res.seconds_verdict == 0.0,
          "verdict_still_factor 0: no verdict (and no time for it)", res.have_scale, 0);
    /* calibration stds: >= 0 and finite */
    opt.verdict_still_factor = 1.5;
    ext[3] = -1e-3;
    check_status(run(N, &opt, &res, work, lwork), MCG_EINVAL, "negative extrinsic_std: EINVAL");
    ext[3] = NAN;
    check_status(run(N, &opt, &res, work, lwork), MCG_EINVAL, "NaN extrinsic_std: EINVAL");
}

static void critical_case(double *work, size_t lwork)
{
    const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, t[3] = {0.0, 0.9, 0.0};
    mcg_robust_options opt;
    mcg_robust_result res;
    int st;
    pixels(N, N / 10, 0, I, t);
    options(&opt, NULL);
    st = run(N, &opt, &res, work, lwork);
    check_status(st, MCG_OK, "straight, intra-camera pairs only: status");
    check(res.have_scale && !res.scale.observable && !res.scale.determined &&
              (res.scale.reason == MCG_SCALE_CRITICAL || res.scale.reason == MCG_SCALE_UNCERTAIN),
          "  not observable (critical or too uncertain)", res.scale.reason, 0);
    check(fabs(norm3(res.scale.t) - 1.0) < 1e-12 && res.scale.t[1] > 0.99,
          "  t a unit direction along the travel (t_y)", res.scale.t[1], 0.99);
}

static void static_case(double *work, size_t lwork)
{
    /* (a rig turning about its origin moves its off-centre cameras: the
     * static rig keeps R = I) */
    const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, t0[3] = {0.0, 0.0, 0.0};
    mcg_robust_options opt;
    mcg_robust_result res;
    int st;
    pixels(N, 0, 0, I, t0);
    options(&opt, NULL);
    st = run(N, &opt, &res, work, lwork);
    check(st == MCG_EDEGENERATE ||
              (st == MCG_OK && res.scale.reason == MCG_SCALE_STATIC &&
               norm3(res.scale.t) == 0.0 && !res.scale.translation_detected),
          "static rig: static verdict with t = 0, or no motion found", st, 0);
}

static void unconfirmed_case(double *work, size_t lwork)
{
    const double aa[3] = {0.05, -0.1, 0.02}, t[3] = {0.5, 0.2, -0.1};
    double R[9];
    mcg_robust_options opt;
    mcg_robust_result res;
    int st, seed, agree = 1, seen = 0;
    mcg_rot_from_angle_axis(aa, R);
    pixels(N, N / 2, 1, R, t);
    options(&opt, NULL);
    opt.max_iterations = 2;
    for (seed = 0; seed < 20; seed++) {
        opt.seed = (unsigned long long)seed;
        st = run(N, &opt, &res, work, lwork);
        if (st != MCG_OK || !res.have_scale)
            continue;
        seen += res.scale.reason == MCG_SCALE_UNCONFIRMED;
        agree &= (res.scale.reason == MCG_SCALE_UNCONFIRMED) ==
                 (res.stop != MCG_ROBUST_STOP_CONFIDENCE && res.confidence < 0.5);
        agree &= res.scale.reason != MCG_SCALE_UNCONFIRMED || !res.scale.observable;
    }
    check(agree && seen > 0, "2 samples, 50 % outliers: unconfirmed iff confidence < 0.5 "
          "(count)", seen, 1);
}

static void pinhole_case(double *work, size_t lwork)
{
    const double aa[3] = {-0.04, 0.12, 0.01}, t[3] = {-0.2, 0.7, 0.1};
    double R[9], *work_b;
    mcg_robust_options opt;
    mcg_robust_result a, b;
    int st, sb, bad, k;
    size_t lb = mcg_robust_work_size(N, NCAM);
    mcg_rot_from_angle_axis(aa, R);
    pixels(N, N / 5, 1, R, t);
    options(&opt, NULL);
    st = run(N, &opt, &a, work, lwork);
    /* the two calls it makes */
    work_b = malloc(lb * sizeof *work_b);
    if (!work_b)
        exit(2);
    sb = mcg_pinhole_ray_pairs(N, NCAM, intr, rot, centres, fmean, ids1, ids2, px1, px2, o1, d1,
                               o2, d2, ppr, &bad);
    for (k = 0; k < N; k++) {
        c1[k] = (int)ids1[k];
        c2[k] = (int)ids2[k];
    }
    {
        double axes[3 * NCAM];
        int i;
        for (k = 0; k < NCAM; k++)
            for (i = 0; i < 3; i++)
                axes[3 * k + i] = rot[9 * k + 6 + i];
        if (sb == MCG_OK)
            sb = mcg_robust_rig_motion(N, o1, d1, o2, d2, c1, c2, NCAM, ppr, axes, fmean, &opt, &b,
                                       mask_b, wts_b, work_b, lb);
    }
    free(work_b);
    check(st == MCG_OK && sb == MCG_OK && memcmp(a.R, b.R, sizeof a.R) == 0 &&
              memcmp(a.t, b.t, sizeof a.t) == 0 && memcmp(mask, mask_b, N) == 0 &&
              memcmp(wts, wts_b, sizeof wts) == 0 && a.scale.reason == b.scale.reason &&
              memcmp(a.scale.t, b.scale.t, sizeof a.scale.t) == 0,
          "pinhole entry == mcg_pinhole_ray_pairs + mcg_robust_rig_motion", st, 0);
    /* the stages' times: each >= 0, summing to the call's; the rays' only
     * on the pixel entry point, the verdict's only when asked for */
    check(a.seconds_rays > 0.0 && b.seconds_rays == 0.0 && a.seconds_search > 0.0 &&
              a.seconds_final > 0.0 && a.seconds_verdict > 0.0 &&
              fabs(a.seconds_rays + a.seconds_search + a.seconds_final + a.seconds_verdict -
                   a.seconds) <= 1e-12 &&
              fabs(b.seconds_search + b.seconds_final + b.seconds_verdict - b.seconds) <= 1e-12,
          "  the stages' times sum to seconds (the rays' on the pixel entry point only)", 0, 0);
    check(memcmp(work, o1, sizeof o1) == 0 && memcmp(work + 3 * N, d1, sizeof d1) == 0 &&
              memcmp(work + 9 * N, d2, sizeof d2) == 0 && memcmp(work + 12 * N, ppr, sizeof ppr) == 0,
          "  its rays and pixels per radian in the workspace", 0, 0);
    /* fewer than 6 distinct correspondences: 5 repeated over and over */
    for (k = 5; k < N; k++) {
        px1[2 * k] = px1[2 * (k % 5)];
        px1[2 * k + 1] = px1[2 * (k % 5) + 1];
        px2[2 * k] = px2[2 * (k % 5)];
        px2[2 * k + 1] = px2[2 * (k % 5) + 1];
        ids1[k] = ids1[k % 5];
        ids2[k] = ids2[k % 5];
    }
    check_status(run(N, &opt, &a, work, lwork), MCG_EDEGENERATE,
                 "5 distinct correspondences repeated: EDEGENERATE");
    ids2[7] = NCAM;
    check_status(run(N, &opt, &a, work, lwork), MCG_EINVAL, "a camera id out of range: EINVAL");
    check_status(run(N, &opt, &a, work, mcg_robust_pinhole_work_size(N, NCAM) - 1), MCG_ENOMEM,
                 "a short workspace: ENOMEM");
}

int main(void)
{
    const size_t lwork = mcg_robust_pinhole_work_size(N, NCAM);
    double *work = malloc(lwork * sizeof *work);
    if (!work)
        return 2;
    make_rig();
    reason_case();
    observable_case(work, lwork);
    critical_case(work, lwork);
    static_case(work, lwork);
    unconfirmed_case(work, lwork);
    pinhole_case(work, lwork);
    free(work);
    printf("%d checks, %d failed\n", n_checks, n_failed);
    return n_failed != 0;
}
