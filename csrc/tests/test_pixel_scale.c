/*
 * test_pixel_scale.c -- plain-C checks of csrc/pixel_scale.c
 * (mcg_sampson_pixel_scale): the angular Sampson residual of
 * mcg_gec_residuals times the returned scale equals the image-plane Sampson
 * error |e| / |de/dpixels| computed independently, by central differences
 * of the epipolar constraint with respect to the four pixel coordinates of
 * pinhole cameras (intra- and cross-camera pairs of a 3-camera rig); the
 * "no constraint" value 0 where the camera centre does not move; the status
 * codes of invalid arguments. Exit status 0 iff every check passes.
 */
#include "mcgeom.h"

#define TEST_SEED 0x91e15ca1eULL
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define N 60
#define NC 3

static double Rc[NC][9], cc[NC][3], fc[NC]; /* camera-from-rig rotation, centre, focal */

/* unit bearing (rig frame) of pixel (u, v) of camera k (principal point 0) */
static void bearing(int k, double u, double v, double out[3])
{
    double x[3] = {u / fc[k], v / fc[k], 1.0}, nx = sqrt(x[0] * x[0] + x[1] * x[1] + 1.0);
    int i;
    for (i = 0; i < 3; i++)
        out[i] = (Rc[k][i] * x[0] + Rc[k][3 + i] * x[1] + Rc[k][6 + i] * x[2]) / nx;
}

/* e = d2 . (c x R d1), c = t + R o1 - o2, from pixels */
static double epi(const double R[9], const double t[3], int k1, int k2, const double p[4])
{
    double b1[3], b2[3], a[3], c[3], q[3];
    int i;
    bearing(k1, p[0], p[1], b1);
    bearing(k2, p[2], p[3], b2);
    for (i = 0; i < 3; i++) {
        a[i] = R[3 * i] * b1[0] + R[3 * i + 1] * b1[1] + R[3 * i + 2] * b1[2];
        c[i] = t[i] + R[3 * i] * cc[k1][0] + R[3 * i + 1] * cc[k1][1] + R[3 * i + 2] * cc[k1][2] -
               cc[k2][i];
    }
    q[0] = c[1] * a[2] - c[2] * a[1];
    q[1] = c[2] * a[0] - c[0] * a[2];
    q[2] = c[0] * a[1] - c[1] * a[0];
    return b2[0] * q[0] + b2[1] * q[1] + b2[2] * q[2];
}

static void test_against_image_plane_sampson(void)
{
    static double o1[3 * N], d1[3 * N], o2[3 * N], d2[3 * N], z1[3 * N], z2[3 * N], f1[N], f2[N],
        sc[N], r[N];
    double R[9], t[3], aa[3], worst = 0.0;
    int cam1[N], cam2[N], k, i, st;
    static double px[N][4];
    for (k = 0; k < NC; k++) {
        for (i = 0; i < 3; i++) {
            aa[i] = 0.6 * nrand();
            cc[k][i] = 0.5 * nrand();
        }
        mcg_rot_from_angle_axis(aa, Rc[k]);
        fc[k] = 300.0 + 500.0 * urand();
    }
    for (i = 0; i < 3; i++) {
        aa[i] = 0.1 * nrand();
        t[i] = nrand();
    }
    mcg_rot_from_angle_axis(aa, R);
    for (k = 0; k < N; k++) {
        int g = k % NC, h = k % 4 == 3 ? (g + 1) % NC : g;
        double p[4], b1[3], b2[3];
        for (i = 0; i < 4; i++)
            p[i] = 400.0 * (urand() - 0.5); /* noisy pairs: e != 0 */
        memcpy(px[k], p, sizeof p);
        bearing(g, p[0], p[1], b1);
        bearing(h, p[2], p[3], b2);
        for (i = 0; i < 3; i++) {
            o1[3 * k + i] = cc[g][i];
            o2[3 * k + i] = cc[h][i];
            d1[3 * k + i] = b1[i];
            d2[3 * k + i] = b2[i];
            z1[3 * k + i] = Rc[g][6 + i]; /* optical axis: the camera's z in the rig frame */
            z2[3 * k + i] = Rc[h][6 + i];
        }
        f1[k] = fc[g];
        f2[k] = fc[h];
        cam1[k] = g;
        cam2[k] = h;
    }
    st = mcg_sampson_pixel_scale(N, o1, d1, o2, d2, R, t, z1, z2, f1, f2, 1e-18, sc);
    check_status(st, MCG_OK, "pixel scale of a 3-camera rig");
    st = mcg_gec_residuals(N, o1, d1, o2, d2, R, t, r);
    check_status(st, MCG_OK, "residuals of the same pairs");
    for (k = 0; k < N; k++) {
        double g2 = 0.0, h = 1e-4, e0 = epi(R, t, cam1[k], cam2[k], px[k]), want, got;
        for (i = 0; i < 4; i++) {
            double q[4], ep, em;
            memcpy(q, px[k], sizeof q);
            q[i] += h;
            ep = epi(R, t, cam1[k], cam2[k], q);
            q[i] -= 2.0 * h;
            em = epi(R, t, cam1[k], cam2[k], q);
            g2 += ((ep - em) / (2.0 * h)) * ((ep - em) / (2.0 * h));
        }
        want = fabs(e0) / sqrt(g2);
        got = fabs(r[k]) * sc[k];
        if (fabs(r[k]) < 1.5) /* below the pi/2 cap of the angular residual */
            worst = fmax(worst, fabs(got - want) / want);
    }
    check(worst < 1e-6, "|r| x scale = image-plane Sampson error (rel.)", worst, 1e-6);
}

static void test_edge_and_invalid(void)
{
    double o[3] = {0.1, 0.2, 0.3}, d[3] = {0.0, 0.0, 2.0}, z[3] = {0.0, 0.0, 1.0}, f = 500.0;
    double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, t0[3] = {0, 0, 0}, s = -1.0, bad;
    /* R = I, t = 0, o1 = o2: the centre does not move, no constraint */
    check_status(mcg_sampson_pixel_scale(1, o, d, o, d, I, t0, z, z, &f, &f, 1e-18, &s), MCG_OK,
                 "static camera");
    check(s == 0.0, "static camera: scale 0 (no first-order constraint)", s, 0.0);
    check_status(mcg_sampson_pixel_scale(0, o, d, o, d, I, t0, z, z, &f, &f, 1e-18, &s), MCG_OK,
                 "n = 0");
    check_status(mcg_sampson_pixel_scale(-1, o, d, o, d, I, t0, z, z, &f, &f, 1e-18, &s),
                 MCG_EINVAL, "n = -1");
    check_status(mcg_sampson_pixel_scale(1, o, d, o, NULL, I, t0, z, z, &f, &f, 1e-18, &s),
                 MCG_EINVAL, "NULL d2");
    check_status(mcg_sampson_pixel_scale(1, o, d, o, d, I, t0, z, z, &f, &f, -1.0, &s),
                 MCG_EINVAL, "min_var_ratio < 0");
    bad = 0.0;
    check_status(mcg_sampson_pixel_scale(1, o, d, o, d, I, t0, z, z, &bad, &f, 1e-18, &s),
                 MCG_EINVAL, "focal 0");
    bad = NAN;
    check_status(mcg_sampson_pixel_scale(1, o, d, o, d, I, t0, z, z, &f, &bad, 1e-18, &s),
                 MCG_EINVAL, "focal NaN");
    t0[2] = HUGE_VAL;
    check_status(mcg_sampson_pixel_scale(1, o, d, o, d, I, t0, z, z, &f, &f, 1e-18, &s),
                 MCG_EINVAL, "inf in t");
    t0[2] = 0.0;
    d[2] = 0.0;
    check_status(mcg_sampson_pixel_scale(1, o, d, o, d, I, t0, z, z, &f, &f, 1e-18, &s),
                 MCG_EINVAL, "zero-length direction");
}

int main(void)
{
    test_against_image_plane_sampson();
    test_edge_and_invalid();
    printf("%d checks, %d failed\n", n_checks, n_failed);
    return n_failed ? 1 : 0;
}
