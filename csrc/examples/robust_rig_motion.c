/*
 * robust_rig_motion.c -- the robust motion of a multi-camera rig from
 * correspondences with outliers, with the C API of libmcgeom alone (no
 * Python): a worked example for embedding users.
 *
 *   1. synthesize a rig of 4 cameras on a ring of radius 0.5 m looking
 *      outward, a motion rig2_from_rig1 (R, t), points 3-20 m in front of
 *      the cameras seen by the same camera at both times (every 5th one by
 *      the next camera at time 2: cross-camera pairs, which fix the metric
 *      scale whatever the motion), bearing noise of 1e-3 (about 1 pixel at
 *      f = 1000), and 30 % gross outliers (a random time-2 bearing);
 *   2. one call of mcg_robust_rig_motion (thesis ch. 7: 5+1 samples, MSAC,
 *      local optimisation, adaptive stop, final refinement) with a
 *      caller-allocated workspace of mcg_robust_work_size doubles;
 *   3. checks: rotation and metric translation against the truth, the
 *      returned mask against the outliers planted, R orthonormal, and the
 *      call's scale verdict (res.scale: the metric scale is observable),
 *      which includes the checks of its consensus (res.consensus,
 *      mcg_consensus_check: no wrong match carries the fit, and the std
 *      that the inliers' own residuals tell is within the limit);
 *   4. the same rig driving straight ahead without rotation and without
 *      cross-camera pairs: the critical motion of thesis ch. 7.3.2, whose
 *      data fix no metric scale. The verdict must say so and report a unit
 *      direction of travel, never a metric-looking t.
 * The exit status is 0 iff all checks pass.
 *
 * Usage: robust_rig_motion [correspondences]   (default 400, at least 40)
 *
 * Build against an installed libmcgeom:
 *   cc robust_rig_motion.c $(pkg-config --cflags --libs mcgeom) -lm -o robust_rig_motion
 */
#include <mcgeom.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define N_CAMERAS 4
#define RING_RADIUS 0.5    /* metres */
#define BEARING_NOISE 1e-3 /* radians (standard deviation per component) */
#define OUTLIERS 0.3       /* fraction with a random time-2 bearing */
#define PI 3.14159265358979323846

/* A deterministic generator (xorshift64*), so every run prints the same. */
static unsigned long long rng = 0x9E3779B97F4A7C15ULL;

static double uniform(void) /* in (0, 1) */
{
    rng ^= rng >> 12;
    rng ^= rng << 25;
    rng ^= rng >> 27;
    return ((double)((rng * 2685821657736338717ULL) >> 11) + 0.5) / 9007199254740992.0;
}

static double gaussian(void) /* Box-Muller */
{
    return sqrt(-2.0 * log(uniform())) * cos(2.0 * PI * uniform());
}

static void unit(double v[3])
{
    double s = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    v[0] /= s;
    v[1] /= s;
    v[2] /= s;
}

/* Pair k: camera k % N_CAMERAS at time 1, the same or (every 5th pair, when
 * cross) the next camera at time 2; the first n_out pairs are outliers. */
static void synthesize(int n, int n_out, int cross, const double R[9], const double t[3],
                       double *o1, double *d1, double *o2, double *d2, int *cam1, int *cam2)
{
    int k, i;
    for (k = 0; k < n; ++k) {
        int a = k % N_CAMERAS, b = cross && k % 5 == 4 ? (a + 1) % N_CAMERAS : a;
        double ya = 2.0 * PI * a / N_CAMERAS, yb = 2.0 * PI * b / N_CAMERAS;
        double ca[3] = {RING_RADIUS * cos(ya), RING_RADIUS * sin(ya), 0.0};
        double cb[3] = {RING_RADIUS * cos(yb), RING_RADIUS * sin(yb), 0.0};
        double X[3], X2[3], u1[3], u2[3], depth = 3.0 + 17.0 * uniform();
        for (i = 0; i < 3; ++i) /* within ~40 degrees of camera a's axis */
            X[i] = ca[i] + depth * (ca[i] / RING_RADIUS + 0.4 * gaussian());
        for (i = 0; i < 3; ++i)
            X2[i] = R[3 * i] * X[0] + R[3 * i + 1] * X[1] + R[3 * i + 2] * X[2] + t[i];
        for (i = 0; i < 3; ++i) {
            u1[i] = X[i] - ca[i];
            u2[i] = k < n_out ? gaussian() : X2[i] - cb[i];
        }
        unit(u1);
        unit(u2);
        for (i = 0; i < 3; ++i) {
            o1[3 * k + i] = ca[i];
            o2[3 * k + i] = cb[i];
            d1[3 * k + i] = u1[i] + BEARING_NOISE * gaussian();
            d2[3 * k + i] = u2[i] + BEARING_NOISE * gaussian();
        }
        cam1[k] = a;
        cam2[k] = b;
    }
}

static double rotation_error_deg(const double Ra[9], const double Rb[9])
{
    double tr = 0.0, c;
    int k;
    for (k = 0; k < 9; ++k)
        tr += Ra[k] * Rb[k];
    c = 0.5 * (tr - 1.0);
    c = c > 1.0 ? 1.0 : (c < -1.0 ? -1.0 : c);
    return acos(c) * 180.0 / PI;
}

static int failures = 0;

static void expect(int ok, const char *what, double value, double limit)
{
    printf("%-4s %-52s %10.4g (limit %g)\n", ok ? "ok" : "FAIL", what, value, limit);
    failures += !ok;
}

int main(int argc, char **argv)
{
    const double w_true[3] = {0.08, -0.15, 0.12}; /* angle-axis, radians */
    const double t_true[3] = {0.40, -0.25, 0.10}; /* metres */
    /* the rig's calibration error per camera: 2 mm (per axis) for its centre,
     * 0.1 mrad for its orientation; it enters the verdict's std of |t| */
    const double extrinsic_std[2 * N_CAMERAS] = {2e-3, 1e-4, 2e-3, 1e-4, 2e-3, 1e-4, 2e-3, 1e-4};
    const double I3[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, t_straight[3] = {0.0, 0.8, 0.0};
    double R_true[9], *o1, *d1, *o2, *d2, *work, dt = 0.0, nt = 0.0, orth = 0.0, nu;
    int *cam1, *cam2, n = 400, n_out, st, k, i, j, caught = 0, lost = 0;
    unsigned char *mask;
    size_t lwork;
    mcg_robust_options opt;
    mcg_robust_result res;
    mcg_consensus_result cons;

    if (argc > 1) {
        char *end;
        long v = strtol(argv[1], &end, 10);
        if (*end != '\0' || v < 40 || v > 1000000) {
            fprintf(stderr, "usage: %s [correspondences, 40..1000000]\n", argv[0]);
            return 2;
        }
        n = (int)v;
    }
    n_out = (int)(OUTLIERS * n);
    o1 = malloc(3 * (size_t)n * sizeof *o1);
    d1 = malloc(3 * (size_t)n * sizeof *d1);
    o2 = malloc(3 * (size_t)n * sizeof *o2);
    d2 = malloc(3 * (size_t)n * sizeof *d2);
    cam1 = malloc((size_t)n * sizeof *cam1);
    cam2 = malloc((size_t)n * sizeof *cam2);
    mask = malloc((size_t)n);
    lwork = mcg_robust_work_size(n, N_CAMERAS);
    work = malloc(lwork * sizeof *work);
    if (!o1 || !d1 || !o2 || !d2 || !cam1 || !cam2 || !mask || !work) {
        printf("FAIL allocation\n");
        return 1;
    }
    if ((st = mcg_rot_from_angle_axis(w_true, R_true)) != MCG_OK) {
        printf("FAIL mcg_rot_from_angle_axis: %s\n", mcg_status_message(st));
        return 1;
    }
    synthesize(n, n_out, 1, R_true, t_true, o1, d1, o2, d2, cam1, cam2);
    printf("%d cameras, %d correspondences (%d outliers), bearing noise %.0e rad; "
           "true t = (%.2f, %.2f, %.2f) m\n", N_CAMERAS, n, n_out, BEARING_NOISE, t_true[0],
           t_true[1], t_true[2]);

    mcg_robust_default_options(&opt);
    opt.threshold = 4.0 * BEARING_NOISE; /* radians: no focal lengths given */
    opt.seed = 1;
    /* the scale verdict in the same call (res.scale): metric only when the
     * relative std of |t| is at most 10 % and |t| x/ 1.3 is excluded at 3
     * sigma; 1.5 noise levels for the rotation-only (static rig) test */
    opt.max_scale_rel_std = 0.1;
    opt.verdict_still_factor = 1.5;
    opt.extrinsic_std = extrinsic_std;
    st = mcg_robust_rig_motion(n, o1, d1, o2, d2, cam1, cam2, N_CAMERAS, NULL, NULL, NULL, &opt,
                               &res, mask, NULL, work, lwork);
    if (st != MCG_OK) {
        printf("FAIL mcg_robust_rig_motion: %s\n", mcg_status_message(st));
        return 1;
    }
    printf("%d samples, %d hypotheses, %d local optimisations, %d inliers, %.2f ms (search "
           "%.2f, final refinement %.2f, verdict %.2f); t = (%.4f, %.4f, %.4f) m, relative std "
           "of |t| %.3g (noise %.3g, calibration %.3g): %s\n", res.iterations, res.hypotheses,
           res.local_optimizations, res.n_inliers, 1e3 * res.seconds, 1e3 * res.seconds_search,
           1e3 * res.seconds_final, 1e3 * res.seconds_verdict, res.scale.t[0], res.scale.t[1],
           res.scale.t[2], res.scale.rel_std, res.scale.rel_std_noise,
           res.scale.rel_std_calibration, mcg_scale_reason_string(res.scale.reason));

    for (i = 0; i < 3; ++i) {
        dt += (res.t[i] - t_true[i]) * (res.t[i] - t_true[i]);
        nt += t_true[i] * t_true[i];
        for (j = 0; j < 3; ++j) {
            double s = 0.0;
            for (k = 0; k < 3; ++k)
                s += res.R[3 * i + k] * res.R[3 * j + k];
            orth = fmax(orth, fabs(s - (i == j)));
        }
    }
    for (k = 0; k < n; ++k) {
        caught += k < n_out && !(mask[k] & 1);
        lost += k >= n_out && !(mask[k] & 1);
    }
    expect(rotation_error_deg(res.R, R_true) < 0.2, "rotation error (deg)",
           rotation_error_deg(res.R, R_true), 0.2);
    expect(sqrt(dt / nt) < 0.05, "metric translation: |t - t_true| / |t_true|", sqrt(dt / nt),
           0.05);
    expect(res.have_scale && res.scale.observable && res.scale.reason == MCG_SCALE_OBSERVABLE,
           "scale verdict: observable (1 = yes)", res.scale.observable, 1);
    expect(res.scale.rel_std <= 0.1, "relative std of |t| (noise and calibration)",
           res.scale.rel_std, 0.1);
    expect(caught >= 0.95 * n_out, "outliers rejected (count)", caught, 0.95 * n_out);
    expect(lost <= 0.1 * (n - n_out), "inliers rejected (count)", lost, 0.1 * (n - n_out));
    expect(orth < 1e-9, "max |R R^T - I|", orth, 1e-9);

    /* the checks of the consensus the call ran on that verdict */
    cons = res.consensus;
    printf("consensus: largest leverage %.3g, largest one-pair move %.3g stds, %d pairs "
           "refitted without, the residuals' relative std of |t| %.3g; reported %.3g\n",
           cons.stats.max_leverage, cons.stats.max_influence_stds, cons.n_dropped,
           cons.residuals_rel_std, cons.rel_std);
    expect(res.have_consensus && cons.reason == MCG_CONSENSUS_METRIC,
           "consensus checks ran, metric (0 = yes)", cons.reason, 0);

    /* 4. driving straight, intra-camera pairs only: no metric scale */
    synthesize(n, n_out, 0, I3, t_straight, o1, d1, o2, d2, cam1, cam2);
    st = mcg_robust_rig_motion(n, o1, d1, o2, d2, cam1, cam2, N_CAMERAS, NULL, NULL, NULL, &opt,
                               &res, mask, NULL, work, lwork);
    if (st != MCG_OK) {
        printf("FAIL mcg_robust_rig_motion (straight): %s\n", mcg_status_message(st));
        return 1;
    }
    nu = sqrt(res.scale.t[0] * res.scale.t[0] + res.scale.t[1] * res.scale.t[1] +
              res.scale.t[2] * res.scale.t[2]);
    printf("driving straight, no cross-camera pairs: t = (%.4f, %.4f, %.4f), relative std "
           "of |t| %.3g: %s\n", res.scale.t[0], res.scale.t[1], res.scale.t[2],
           res.scale.rel_std, mcg_scale_reason_string(res.scale.reason));
    expect(res.have_scale && !res.scale.observable, "critical motion: scale not observable "
           "(0 = right)", res.scale.observable, 0);
    expect(!res.scale.determined && fabs(nu - 1.0) < 1e-12, "  and t a unit direction: "
           "| |t| - 1 |", fabs(nu - 1.0), 1e-12);
    expect(res.scale.t[1] > 0.99, "  along the travel: t_y of the unit t", res.scale.t[1], 0.99);

    free(o1);
    free(d1);
    free(o2);
    free(d2);
    free(cam1);
    free(cam2);
    free(mask);
    free(work);
    return failures != 0;
}
