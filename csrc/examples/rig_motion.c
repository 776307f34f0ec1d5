/*
 * rig_motion.c -- estimate the motion of a multi-camera rig with the C API
 * of libmcgeom alone (no Python): a worked example for embedding users.
 *
 *   1. synthesize a rig of 4 cameras on a ring of radius 0.5 m looking
 *      outward, a motion rig2_from_rig1 (R, t) with rotation, and points
 *      3-20 m in front of each camera, seen at both times by the same
 *      camera, with Gaussian noise of 1e-3 on each component of the unit bearings
 *      (about 1.5 pixels at f = 1000);
 *   2. the linear 17-point estimate (mcg_linear17, thesis ch. 8), which
 *      needs no initial guess and recovers the metric scale;
 *   3. its Levenberg-Marquardt refinement on the Sampson angular error
 *      (mcg_refine_motion);
 *   4. the globally optimal L-infinity motion by branch and bound with a
 *      block and time budget (mcg_bnb_linf, thesis ch. 10), started at
 *      the refined rotation.
 * Each step prints its rotation error (degrees) and relative translation
 * error against the truth and is checked against a tolerance; the exit
 * status is 0 iff all checks pass.
 *
 * Usage: rig_motion [points_per_camera]   (default 40, at least 5)
 *
 * Build against an installed libmcgeom:
 *   cc rig_motion.c $(pkg-config --cflags --libs mcgeom) -lm -o rig_motion
 */
#include <mcgeom.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define N_CAMERAS 4
#define RING_RADIUS 0.5      /* metres */
#define BEARING_NOISE 1e-3   /* radians (standard deviation) */
#define PI 3.14159265358979323846

/* A deterministic generator (xorshift64*), so every run prints the same. */
static unsigned long long rng = 0x2545F4914F6CDD1DULL;

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

static void mat_vec(const double R[9], const double x[3], double y[3])
{
    int i;
    for (i = 0; i < 3; ++i)
        y[i] = R[3 * i] * x[0] + R[3 * i + 1] * x[1] + R[3 * i + 2] * x[2];
}

/* angle of R_a R_b^T, degrees */
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

/* |t_a - t_b| / |t_b| */
static double translation_error(const double ta[3], const double tb[3])
{
    double d = 0.0, nb = 0.0;
    int i;
    for (i = 0; i < 3; ++i) {
        d += (ta[i] - tb[i]) * (ta[i] - tb[i]);
        nb += tb[i] * tb[i];
    }
    return sqrt(d / nb);
}

/* Correspondences of camera c: origin = its centre (rig frame) at both
 * times, directions towards the point at time 1 and at time 2, noisy.
 * Returns the number written. */
static int synthesize(int per_camera, const double R[9], const double t[3], double *o1,
                      double *d1, double *o2, double *d2, int *camera)
{
    int c, k, i, n = 0;
    for (c = 0; c < N_CAMERAS; ++c) {
        double yaw = 2.0 * PI * c / N_CAMERAS;
        double axis[3] = {cos(yaw), sin(yaw), 0.0}, centre[3];
        for (i = 0; i < 3; ++i)
            centre[i] = RING_RADIUS * axis[i];
        for (k = 0; k < per_camera; ++k, ++n) {
            double X[3], X2[3], depth = 3.0 + 17.0 * uniform();
            for (i = 0; i < 3; ++i) /* within ~40 degrees of the optical axis */
                X[i] = centre[i] + depth * (axis[i] + 0.4 * gaussian());
            mat_vec(R, X, X2);
            for (i = 0; i < 3; ++i) {
                X2[i] += t[i];
                o1[3 * n + i] = centre[i];
                o2[3 * n + i] = centre[i];
            }
            for (i = 0; i < 3; ++i) {
                double r1 = sqrt((X[0] - centre[0]) * (X[0] - centre[0]) +
                                 (X[1] - centre[1]) * (X[1] - centre[1]) +
                                 (X[2] - centre[2]) * (X[2] - centre[2]));
                double r2 = sqrt((X2[0] - centre[0]) * (X2[0] - centre[0]) +
                                 (X2[1] - centre[1]) * (X2[1] - centre[1]) +
                                 (X2[2] - centre[2]) * (X2[2] - centre[2]));
                d1[3 * n + i] = (X[i] - centre[i]) / r1 + BEARING_NOISE * gaussian();
                d2[3 * n + i] = (X2[i] - centre[i]) / r2 + BEARING_NOISE * gaussian();
            }
            camera[n] = c;
        }
    }
    return n;
}

static int failures = 0;

static void report(const char *step, const double R[9], const double t[3],
                   const double R_true[9], const double t_true[3], double max_rot_deg,
                   double max_rel_t)
{
    double er = rotation_error_deg(R, R_true), et = translation_error(t, t_true);
    int ok = er <= max_rot_deg && et <= max_rel_t;
    printf("%-4s %-10s rotation error %.4f deg (max %.2f), |t - t_true| / |t_true| "
           "%.4f (max %.2f), t = (%.4f, %.4f, %.4f) m\n",
           ok ? "ok" : "FAIL", step, er, max_rot_deg, et, max_rel_t, t[0], t[1], t[2]);
    failures += !ok;
}

static int fail(const char *what, int status)
{
    printf("FAIL %s: %s\n", what, mcg_status_message(status));
    return 1;
}

int main(int argc, char **argv)
{
    const double w_true[3] = {0.10, -0.20, 0.15}; /* angle-axis, radians */
    const double t_true[3] = {0.30, -0.10, 0.20}; /* metres */
    double R_true[9], R[9], t[3];
    double *o1, *d1, *o2, *d2, *work;
    int *camera, per_camera = 40, n, st;
    mcg_linear17_result lin;
    mcg_refine_options ropt;
    mcg_refine_result ref;
    mcg_bnb_options bopt;
    mcg_bnb_result bnb;
    size_t lwork;

    if (argc > 1) {
        char *end;
        long v = strtol(argv[1], &end, 10);
        if (*end != '\0' || v < 5 || v > 100000) {
            fprintf(stderr, "usage: %s [points_per_camera, 5..100000]\n", argv[0]);
            return 2;
        }
        per_camera = (int)v;
    }
    n = N_CAMERAS * per_camera;
    o1 = malloc(3 * (size_t)n * sizeof *o1);
    d1 = malloc(3 * (size_t)n * sizeof *d1);
    o2 = malloc(3 * (size_t)n * sizeof *o2);
    d2 = malloc(3 * (size_t)n * sizeof *d2);
    camera = malloc((size_t)n * sizeof *camera);
    if (!o1 || !d1 || !o2 || !d2 || !camera)
        return fail("allocation", MCG_ENOMEM);

    st = mcg_rot_from_angle_axis(w_true, R_true);
    if (st != MCG_OK)
        return fail("mcg_rot_from_angle_axis", st);
    n = synthesize(per_camera, R_true, t_true, o1, d1, o2, d2, camera);
    printf("%d cameras x %d points, bearing noise %.1e rad; true t = (%.2f, %.2f, %.2f) m\n",
           N_CAMERAS, per_camera, BEARING_NOISE, t_true[0], t_true[1], t_true[2]);

    /* 2. linear 17-point (default options: NULL) */
    st = mcg_linear17(n, o1, d1, o2, d2, NULL, &lin);
    if (st != MCG_OK)
        return fail("mcg_linear17", st);
    if (!lin.scale_observable) {
        printf("FAIL linear17 reports the scale unobservable on a rotating rig\n");
        ++failures;
    }
    report("linear17", lin.R, lin.t, R_true, t_true, 0.5, 0.2);

    /* 3. refinement from the linear estimate */
    memcpy(R, lin.R, sizeof R);
    memcpy(t, lin.t, sizeof t);
    mcg_refine_default_options(&ropt);
    ropt.loss = MCG_LOSS_HUBER;
    ropt.loss_scale = 3.0 * BEARING_NOISE;
    st = mcg_refine_motion(n, o1, d1, o2, d2, NULL, &ropt, R, t, &ref);
    if (st != MCG_OK)
        return fail("mcg_refine_motion", st);
    report("refine", R, t, R_true, t_true, 0.1, 0.06);
    printf("     refine: %d iterations, RMS residual %.2e rad, relative std of |t| %.3f\n",
           ref.iterations, ref.rms, ref.scale_rel_std);

    /* 4. branch and bound, budgets set by the caller */
    mcg_bnb_default_options(&bopt);
    bopt.resolution = 1e-3;
    bopt.max_queue = 20000;
    bopt.max_blocks = 200000;
    bopt.max_seconds = 60.0;
    lwork = mcg_bnb_work_size(n, N_CAMERAS, &bopt);
    if (lwork == 0)
        return fail("mcg_bnb_work_size", MCG_EINVAL);
    work = malloc(lwork * sizeof *work);
    if (!work)
        return fail("workspace allocation", MCG_ENOMEM);
    st = mcg_bnb_linf(n, d1, o1, d2, o2, camera, N_CAMERAS, R, &bopt, &bnb, work, lwork);
    if (st != MCG_OK)
        return fail("mcg_bnb_linf", st);
    report("bnb_linf", bnb.R, bnb.t, R_true, t_true, 0.3, 0.15);
    printf("     bnb_linf: L-infinity error %.3e rad, certified lower bound %.3e rad, "
           "%ld blocks, stop %d, %.2f s\n",
           bnb.linf, bnb.lower_bound, bnb.blocks, bnb.stop, bnb.seconds);
    if (!(bnb.lower_bound <= bnb.linf && bnb.linf <= bnb.initial_linf)) {
        printf("FAIL bnb_linf bounds out of order\n");
        ++failures;
    }

    free(work);
    free(camera);
    free(d2);
    free(o2);
    free(d1);
    free(o1);
    printf("%s\n", failures ? "FAILED" : "all checks passed");
    return failures != 0;
}
