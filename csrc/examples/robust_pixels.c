/*
 * robust_pixels.c -- the robust motion of a rig of pinhole cameras straight
 * from matched pixels, with the C API of libmcgeom alone: what a C pipeline
 * that runs its own feature matcher calls once per frame pair.
 *
 *   1. a car-like rig of 5 undistorted pinhole cameras (640 x 480 px,
 *      f = 500 px) looking out every 72 degrees from a ring of radius 1 m:
 *      no two views overlap, so every match is intra-camera;
 *   2. the car drives 1.2 m forward while turning by 10 degrees; points 4-30
 *      m away seen by the same camera at both times, 0.5 px of pixel noise,
 *      25 % of the matches wrong (a random pixel of the image at time 2);
 *   3. one call of mcg_robust_rig_motion_pinhole: the pixels' rays, the 5+1
 *      search with its threshold in pixels, the final refinement and the
 *      scale verdict, in a caller-allocated workspace of
 *      mcg_robust_pinhole_work_size doubles. The calibration error of the
 *      rig (2 mm and 0.1 degree per camera) enters the verdict's relative
 *      std of |t|;
 *   4. checks: the rotation against the truth, the verdict (from 500
 *      matches on, the turn makes the scale observable from intra-camera
 *      matches alone, thesis ch. 7.3.2), the metric translation within 3
 *      of the relative standard deviations of |t| that the verdict reports
 *      (with too few matches the verdict says the scale is not observable:
 *      res.scale.t is then a unit direction, or an estimate of |t| that must
 *      not be used as metric), the wrong matches rejected.
 * The exit status is 0 iff all checks pass. It prints where the call's time
 * went (the pixels' rays, the search, the final refinement, the verdict).
 *
 * Usage: robust_pixels [matches]   (default 500, at least 50)
 *
 * Build against an installed libmcgeom:
 *   cc robust_pixels.c $(pkg-config --cflags --libs mcgeom) -lm -o robust_pixels
 */
#include <mcgeom.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#define N_CAMERAS 5
#define WIDTH 640.0
#define HEIGHT 480.0
#define FOCAL 500.0      /* pixels */
#define RING_RADIUS 1.0  /* metres */
#define PIXEL_NOISE 0.5  /* pixels (standard deviation per coordinate) */
#define WRONG 0.25       /* fraction of wrong matches */
#define PI 3.14159265358979323846

/* xorshift64*: every run prints the same */
static unsigned long long state = 0x2545F4914F6CDD1DULL;

static double uniform(double lo, double hi)
{
    state ^= state >> 12;
    state ^= state << 25;
    state ^= state >> 27;
    return lo + (hi - lo) * (((double)((state * 2685821657736338717ULL) >> 11) + 0.5) /
                             9007199254740992.0);
}

static double gaussian(void) /* Box-Muller */
{
    return sqrt(-2.0 * log(uniform(0.0, 1.0))) * cos(2.0 * PI * uniform(0.0, 1.0));
}

/* The rig: camera i looks along yaw 72 i degrees (rig frame: x forward, y
 * left, z up). intr: fx, fy, cx, cy, skew; rot: cam_from_rig (rows: image
 * right, image down, optical axis); centres in the rig frame. */
static double intr[5 * N_CAMERAS], rot[9 * N_CAMERAS], centres[3 * N_CAMERAS],
    focal[N_CAMERAS];

static void make_rig(void)
{
    int i;
    for (i = 0; i < N_CAMERAS; ++i) {
        const double yaw = 2.0 * PI * i / N_CAMERAS, c = cos(yaw), s = sin(yaw);
        const double r[9] = {s, -c, 0.0, 0.0, 0.0, -1.0, c, s, 0.0};
        int k;
        for (k = 0; k < 9; ++k)
            rot[9 * i + k] = r[k];
        intr[5 * i] = intr[5 * i + 1] = FOCAL;
        intr[5 * i + 2] = WIDTH / 2.0;
        intr[5 * i + 3] = HEIGHT / 2.0;
        intr[5 * i + 4] = 0.0;
        focal[i] = FOCAL;
        centres[3 * i] = RING_RADIUS * c;
        centres[3 * i + 1] = RING_RADIUS * s;
        centres[3 * i + 2] = 0.0;
    }
}

/* pixel of rig-frame point X in camera i; 0 when it is behind the camera or
 * outside the image */
static int project(int i, const double X[3], double px[2])
{
    double d[3], z[3];
    int r, k;
    for (k = 0; k < 3; ++k)
        d[k] = X[k] - centres[3 * i + k];
    for (r = 0; r < 3; ++r)
        z[r] = rot[9 * i + 3 * r] * d[0] + rot[9 * i + 3 * r + 1] * d[1] +
               rot[9 * i + 3 * r + 2] * d[2];
    if (!(z[2] > 0.1))
        return 0;
    px[0] = FOCAL * z[0] / z[2] + WIDTH / 2.0;
    px[1] = FOCAL * z[1] / z[2] + HEIGHT / 2.0;
    return px[0] >= 0.0 && px[0] < WIDTH && px[1] >= 0.0 && px[1] < HEIGHT;
}

/* X2 = R X1 + t */
static void move(const double R[9], const double t[3], const double X[3], double Y[3])
{
    int r;
    for (r = 0; r < 3; ++r)
        Y[r] = R[3 * r] * X[0] + R[3 * r + 1] * X[1] + R[3 * r + 2] * X[2] + t[r];
}

static int failures;

static void expect(int ok, const char *what, double value, double limit)
{
    printf("%-4s %-52s %.4g (limit %.4g)\n", ok ? "ok" : "FAIL", what, value, limit);
    failures += !ok;
}

int main(int argc, char **argv)
{
    const int n = argc > 1 ? atoi(argv[1]) : 500;
    /* the car turns left by 10 degrees about z while driving 1.2 m forward:
     * rig2_from_rig1 maps a point fixed in the world from the rig's frame at
     * time 1 to its frame at time 2 */
    const double yaw = 10.0 * PI / 180.0;
    const double R_true[9] = {cos(yaw), sin(yaw), 0.0, -sin(yaw), cos(yaw), 0.0, 0.0, 0.0, 1.0};
    const double zero[3] = {0.0, 0.0, 0.0}, travel[3] = {-1.2, 0.0, 0.0};
    double t_true[3];
    const double ext_std[2 * N_CAMERAS] = {2e-3, 1.745e-3, 2e-3, 1.745e-3, 2e-3, 1.745e-3,
                                           2e-3, 1.745e-3, 2e-3, 1.745e-3};
    double *px1, *px2, *work, err_R = 0.0, dt = 0.0, nt = 0.0, tr;
    long long *ids1, *ids2;
    unsigned char *mask, *wrong;
    mcg_robust_options opt;
    mcg_robust_result res;
    size_t lwork;
    int k, i, st, caught = 0, lost = 0, n_wrong = 0;

    if (n < 50 || n > 1000000) {
        fprintf(stderr, "usage: robust_pixels [matches in 50 .. 1000000]\n");
        return 2;
    }
    make_rig();
    move(R_true, zero, travel, t_true); /* t = -R (1.2, 0, 0): the rig's travel, in frame 2 */
    px1 = malloc(2 * (size_t)n * sizeof *px1);
    px2 = malloc(2 * (size_t)n * sizeof *px2);
    ids1 = malloc((size_t)n * sizeof *ids1);
    ids2 = malloc((size_t)n * sizeof *ids2);
    mask = malloc((size_t)n);
    wrong = malloc((size_t)n);
    lwork = mcg_robust_pinhole_work_size(n, N_CAMERAS);
    work = malloc(lwork * sizeof *work);
    if (!px1 || !px2 || !ids1 || !ids2 || !mask || !wrong || !work || lwork == 0) {
        fprintf(stderr, "out of memory\n");
        return 2;
    }

    /* 2. matches: a pixel at time 1, its point 4-30 m along the ray, that
     * point's pixel in the same camera at time 2 (drawn again until it is in
     * the image), noise; a quarter replaced by a random pixel */
    for (k = 0; k < n; ++k) {
        double X[3], Y[3], p[2];
        i = k % N_CAMERAS;
        ids1[k] = ids2[k] = i;
        do {
            const double u = uniform(0.0, WIDTH), v = uniform(0.0, HEIGHT);
            const double depth = uniform(4.0, 30.0);
            const double ray_cam[3] = {(u - WIDTH / 2.0) / FOCAL, (v - HEIGHT / 2.0) / FOCAL,
                                       1.0};
            const double len = sqrt(ray_cam[0] * ray_cam[0] + ray_cam[1] * ray_cam[1] + 1.0);
            int r;
            for (r = 0; r < 3; ++r) /* rig frame: rot^T times the camera ray */
                X[r] = centres[3 * i + r] + depth / len *
                                               (rot[9 * i + r] * ray_cam[0] +
                                                rot[9 * i + 3 + r] * ray_cam[1] +
                                                rot[9 * i + 6 + r] * ray_cam[2]);
            px1[2 * k] = u;
            px1[2 * k + 1] = v;
            move(R_true, t_true, X, Y);
        } while (!project(i, Y, p));
        px1[2 * k] += PIXEL_NOISE * gaussian();
        px1[2 * k + 1] += PIXEL_NOISE * gaussian();
        px2[2 * k] = p[0] + PIXEL_NOISE * gaussian();
        px2[2 * k + 1] = p[1] + PIXEL_NOISE * gaussian();
        wrong[k] = uniform(0.0, 1.0) < WRONG;
        if (wrong[k]) {
            px2[2 * k] = uniform(0.0, WIDTH);
            px2[2 * k + 1] = uniform(0.0, HEIGHT);
            n_wrong++;
        }
    }
    printf("%d pinhole cameras, %d matches (%d wrong), %.1f px noise; the car turned %.0f deg "
           "and drove %.1f m\n", N_CAMERAS, n, n_wrong, PIXEL_NOISE, 10.0, 1.2);

    /* 3. one call: threshold in pixels; the verdict in the same call */
    mcg_robust_default_options(&opt);
    opt.threshold = 1.0;
    opt.seed = 7;
    opt.max_scale_rel_std = 0.1;
    opt.verdict_still_factor = 1.5;
    opt.extrinsic_std = ext_std;
    st = mcg_robust_rig_motion_pinhole(n, N_CAMERAS, intr, rot, centres, focal, ids1, ids2, px1,
                                       px2, &opt, &res, mask, NULL, work, lwork);
    if (st != MCG_OK) {
        printf("FAIL mcg_robust_rig_motion_pinhole: %s\n", mcg_status_message(st));
        return 1;
    }
    printf("%d samples, %d inliers, %.2f ms (rays %.3f, search %.3f, final refinement %.3f, "
           "verdict %.3f); t = (%.4f, %.4f, %.4f) %s, relative std of |t| %.3g: %s\n",
           res.iterations, res.n_inliers, 1e3 * res.seconds, 1e3 * res.seconds_rays,
           1e3 * res.seconds_search, 1e3 * res.seconds_final, 1e3 * res.seconds_verdict,
           res.scale.t[0], res.scale.t[1], res.scale.t[2],
           res.scale.observable ? "m" : "(not metric)", res.scale.rel_std,
           mcg_scale_reason_string(res.scale.reason));

    /* 4. checks: the angle of R_true^T R, |t - t_true| / |t_true|, the mask */
    tr = 0.0;
    for (i = 0; i < 3; ++i)
        for (k = 0; k < 3; ++k)
            tr += R_true[3 * k + i] * res.R[3 * k + i];
    err_R = acos(fmax(-1.0, fmin(1.0, 0.5 * (tr - 1.0)))) * 180.0 / PI;
    for (i = 0; i < 3; ++i) {
        dt += (res.scale.t[i] - t_true[i]) * (res.scale.t[i] - t_true[i]);
        nt += t_true[i] * t_true[i];
    }
    for (k = 0; k < n; ++k) {
        caught += wrong[k] && !(mask[k] & 1);
        lost += !wrong[k] && !(mask[k] & 1);
    }
    expect(err_R < 0.1, "rotation error (deg)", err_R, 0.1);
    expect(res.have_scale, "a scale verdict (1 = yes)", res.have_scale, 1);
    if (n >= 500) /* enough matches that the 10 degree turn fixes the scale */
        expect(res.scale.observable, "scale verdict: observable (1 = yes)", res.scale.observable,
               1);
    if (res.scale.observable) {
        /* the truth within 3 of the reported standard deviations of |t| */
        expect(sqrt(dt / nt) < 3.0 * res.scale.rel_std,
               "metric translation: |t - t_true| / |t_true|", sqrt(dt / nt),
               3.0 * res.scale.rel_std);
    } else if (res.scale.determined) {
        /* too few matches for a metric claim: |t| is an estimate whose
         * relative std (or profile along |t|) the verdict finds too wide; a
         * caller must not chain or plot it as metric */
        printf("     scale not observable with %d matches: |t| only an estimate (relative "
               "std %.3g), not metric\n", n, res.scale.rel_std);
    } else {
        /* the data do not fix |t| at all: t is the unit direction of travel */
        const double u = sqrt(res.scale.t[0] * res.scale.t[0] + res.scale.t[1] * res.scale.t[1] +
                              res.scale.t[2] * res.scale.t[2]);
        expect(fabs(u - 1.0) < 1e-12, "scale undetermined: t a unit direction, | |t| - 1 |",
               fabs(u - 1.0), 1e-12);
    }
    expect(caught >= 0.95 * n_wrong, "wrong matches rejected (count)", caught, 0.95 * n_wrong);
    expect(lost <= 0.1 * (n - n_wrong), "right matches rejected (count)", lost,
           0.1 * (n - n_wrong));

    free(px1);
    free(px2);
    free(ids1);
    free(ids2);
    free(mask);
    free(wrong);
    free(work);
    return failures != 0;
}
