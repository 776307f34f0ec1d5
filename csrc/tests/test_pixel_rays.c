/*
 * test_pixel_rays.c -- plain-C checks of csrc/pixel_rays.c
 * (mcg_pinhole_ray_pairs): rig-frame points projected into pinhole cameras
 * (skewed, off-centre, rotated, displaced) come back as their unit
 * directions from the camera centres; the pixels per radian equal the
 * pixel-noise model evaluated independently (the angle to each optical axis
 * by atan2, then cos^4 + cos^2); the status codes and the index of a pixel
 * without a finite bearing. Exit status 0 iff every check passes.
 */
#include "mcgeom.h"

#define TEST_SEED 0x5eed0f1a7e5ULL
#include "testutil.h"

#include <float.h>
#include <math.h>
#include <stdio.h>

#define N 200
#define NC 4

static double intr[NC * 5], rot[NC * 9], cen[NC * 3], foc[NC];

static void make_rig(void)
{
    int k, i;
    for (k = 0; k < NC; k++) {
        double aa[3] = {0.0, 1.5707963267948966 * k, 0.0};
        aa[0] = 0.2 * nrand();
        aa[2] = 0.2 * nrand();
        /* camera k looks out at yaw 90 k deg: cam_from_rig = rotation of -aa */
        {
            double th = sqrt(aa[0] * aa[0] + aa[1] * aa[1] + aa[2] * aa[2]), u[3], c, s;
            double *R = rot + 9 * k;
            for (i = 0; i < 3; i++)
                u[i] = th > 0 ? -aa[i] / th : 0.0;
            c = cos(th);
            s = sin(th);
            R[0] = c + u[0] * u[0] * (1 - c);
            R[1] = u[0] * u[1] * (1 - c) - u[2] * s;
            R[2] = u[0] * u[2] * (1 - c) + u[1] * s;
            R[3] = u[1] * u[0] * (1 - c) + u[2] * s;
            R[4] = c + u[1] * u[1] * (1 - c);
            R[5] = u[1] * u[2] * (1 - c) - u[0] * s;
            R[6] = u[2] * u[0] * (1 - c) - u[1] * s;
            R[7] = u[2] * u[1] * (1 - c) + u[0] * s;
            R[8] = c + u[2] * u[2] * (1 - c);
        }
        intr[5 * k] = 400.0 + 800.0 * urand();       /* fx */
        intr[5 * k + 1] = intr[5 * k] * (0.9 + 0.2 * urand()); /* fy */
        intr[5 * k + 2] = 300.0 + 100.0 * urand();   /* cx */
        intr[5 * k + 3] = 200.0 + 100.0 * urand();   /* cy */
        intr[5 * k + 4] = k == 1 ? 2.5 : 0.0;        /* skew on one camera */
        foc[k] = 0.5 * (intr[5 * k] + intr[5 * k + 1]);
        for (i = 0; i < 3; i++)
            cen[3 * k + i] = 0.3 * nrand();
    }
}

/* pixel of rig point X in camera k; the direction X - c (not normalised) */
static void project(int k, const double X[3], double px[2], double dir[3])
{
    const double *R = rot + 9 * k, *K = intr + 5 * k;
    double v[3], xc[3];
    int i;
    for (i = 0; i < 3; i++)
        v[i] = X[i] - cen[3 * k + i];
    for (i = 0; i < 3; i++)
        xc[i] = R[3 * i] * v[0] + R[3 * i + 1] * v[1] + R[3 * i + 2] * v[2];
    px[0] = K[0] * xc[0] / xc[2] + K[4] * xc[1] / xc[2] + K[2];
    px[1] = K[1] * xc[1] / xc[2] + K[3];
    for (i = 0; i < 3; i++)
        dir[i] = v[i];
}

/* the model of the header, by angles: theta = atan2(|b x z|, b . z) */
static double ppr_reference(const double *b1, int k1, const double *b2, int k2)
{
    const double *z[2] = {rot + 9 * k1 + 6, rot + 9 * k2 + 6};
    const double *b[2] = {b1, b2};
    double f[2] = {foc[k1], foc[k2]}, var = 0.0;
    int j;
    for (j = 0; j < 2; j++) {
        double cx = b[j][1] * z[j][2] - b[j][2] * z[j][1], cy = b[j][2] * z[j][0] - b[j][0] * z[j][2],
               cz = b[j][0] * z[j][1] - b[j][1] * z[j][0];
        double th = atan2(sqrt(cx * cx + cy * cy + cz * cz),
                          b[j][0] * z[j][0] + b[j][1] * z[j][1] + b[j][2] * z[j][2]);
        double c = cos(th);
        c = c < 1e-3 ? 1e-3 : (c > 1.0 ? 1.0 : c);
        var += (pow(c, 4.0) + c * c) / (2.0 * f[j] * f[j]);
    }
    return 1.0 / sqrt(var / 2.0);
}

static double px1[2 * N], px2[2 * N], o1[3 * N], d1[3 * N], o2[3 * N], d2[3 * N], ppr[N];
static double dir1[3 * N], dir2[3 * N];
static long long ids1[N], ids2[N];

static void make_pairs(void)
{
    int k, i;
    for (k = 0; k < N; k++) {
        double X[3], xc;
        ids1[k] = (long long)(rng_next() % NC);
        ids2[k] = k % 5 == 0 ? (ids1[k] + 1) % NC : ids1[k]; /* some cross-camera pairs */
        /* a point in front of camera ids1[k] (and ids2[k]: their axes) */
        for (;;) {
            const double *z1 = rot + 9 * ids1[k] + 6, *z2 = rot + 9 * ids2[k] + 6;
            double depth = 2.0 + 10.0 * urand();
            for (i = 0; i < 3; i++)
                X[i] = depth * (z1[i] + z2[i]) / 2.0 + 2.0 * nrand();
            xc = 1.0;
            for (i = 0; i < 2; i++) {
                const long long c = i ? ids2[k] : ids1[k];
                const double *R = rot + 9 * c;
                double v0 = X[0] - cen[3 * c], v1 = X[1] - cen[3 * c + 1], v2 = X[2] - cen[3 * c + 2];
                double zc = R[6] * v0 + R[7] * v1 + R[8] * v2;
                if (zc < 0.5)
                    xc = -1.0;
            }
            if (xc > 0)
                break;
        }
        project((int)ids1[k], X, px1 + 2 * k, dir1 + 3 * k);
        project((int)ids2[k], X, px2 + 2 * k, dir2 + 3 * k);
    }
}

static void test_rays_and_ppr(void)
{
    int k, i, bad = 7, st;
    double worst_d = 0.0, worst_o = 0.0, worst_f = 0.0;
    st = mcg_pinhole_ray_pairs(N, NC, intr, rot, cen, foc, ids1, ids2, px1, px2, o1, d1, o2, d2,
                               ppr, &bad);
    check_status(st, MCG_OK, "pinhole_ray_pairs on projected points");
    check(bad == -1, "bad index -1 on success", (double)bad, 0.0);
    for (k = 0; k < N; k++) {
        double n1 = sqrt(dir1[3 * k] * dir1[3 * k] + dir1[3 * k + 1] * dir1[3 * k + 1] +
                         dir1[3 * k + 2] * dir1[3 * k + 2]);
        double n2 = sqrt(dir2[3 * k] * dir2[3 * k] + dir2[3 * k + 1] * dir2[3 * k + 1] +
                         dir2[3 * k + 2] * dir2[3 * k + 2]);
        double f;
        for (i = 0; i < 3; i++) {
            worst_d = fmax(worst_d, fabs(d1[3 * k + i] - dir1[3 * k + i] / n1));
            worst_d = fmax(worst_d, fabs(d2[3 * k + i] - dir2[3 * k + i] / n2));
            worst_o = fmax(worst_o, fabs(o1[3 * k + i] - cen[3 * ids1[k] + i]));
            worst_o = fmax(worst_o, fabs(o2[3 * k + i] - cen[3 * ids2[k] + i]));
        }
        f = ppr_reference(d1 + 3 * k, (int)ids1[k], d2 + 3 * k, (int)ids2[k]);
        worst_f = fmax(worst_f, fabs(ppr[k] - f) / f);
    }
    check(worst_d < 1e-12, "bearings = unit directions to the points", worst_d, 1e-12);
    check(worst_o == 0.0, "origins = camera centres", worst_o, 0.0);
    check(worst_f < 1e-12, "pixels per radian = the model by angles (relative)", worst_f, 1e-12);
    /* without focal: the same rays, ppr untouched */
    {
        static double e1[3 * N], e2[3 * N], q1[3 * N], q2[3 * N];
        double diff = 0.0;
        st = mcg_pinhole_ray_pairs(N, NC, intr, rot, cen, NULL, ids1, ids2, px1, px2, q1, e1, q2,
                                   e2, NULL, &bad);
        check_status(st, MCG_OK, "pinhole_ray_pairs without pixels per radian");
        for (k = 0; k < 3 * N; k++)
            diff = fmax(diff, fmax(fabs(e1[k] - d1[k]), fabs(e2[k] - d2[k])));
        check(diff == 0.0, "the same bearings without ppr", diff, 0.0);
    }
}

static void test_status(void)
{
    int bad, st;
    double keep;
    long long id;
    st = mcg_pinhole_ray_pairs(0, NC, intr, rot, cen, foc, ids1, ids2, px1, px2, o1, d1, o2, d2,
                               ppr, &bad);
    check_status(st, MCG_OK, "n = 0");
    check_status(mcg_pinhole_ray_pairs(-1, NC, intr, rot, cen, foc, ids1, ids2, px1, px2, o1, d1,
                                       o2, d2, ppr, &bad), MCG_EINVAL, "n < 0");
    check_status(mcg_pinhole_ray_pairs(N, 0, intr, rot, cen, foc, ids1, ids2, px1, px2, o1, d1,
                                       o2, d2, ppr, &bad), MCG_EINVAL, "m = 0");
    check_status(mcg_pinhole_ray_pairs(N, NC, intr, rot, cen, foc, ids1, ids2, NULL, px2, o1, d1,
                                       o2, d2, ppr, &bad), MCG_EINVAL, "NULL pixels");
    check_status(mcg_pinhole_ray_pairs(N, NC, intr, rot, cen, NULL, ids1, ids2, px1, px2, o1, d1,
                                       o2, d2, ppr, &bad), MCG_EINVAL, "ppr without focal");
    id = ids2[9];
    ids2[9] = NC;
    check_status(mcg_pinhole_ray_pairs(N, NC, intr, rot, cen, foc, ids1, ids2, px1, px2, o1, d1,
                                       o2, d2, ppr, &bad), MCG_EINVAL, "an id = m");
    ids2[9] = -1;
    check_status(mcg_pinhole_ray_pairs(N, NC, intr, rot, cen, foc, ids1, ids2, px1, px2, o1, d1,
                                       o2, d2, ppr, &bad), MCG_EINVAL, "an id < 0");
    ids2[9] = id;
    keep = px1[2 * 11];
    px1[2 * 11] = NAN;
    check_status(mcg_pinhole_ray_pairs(N, NC, intr, rot, cen, foc, ids1, ids2, px1, px2, o1, d1,
                                       o2, d2, ppr, &bad), MCG_EINVAL, "a NaN pixel");
    px1[2 * 11] = keep;
    keep = px2[2 * 13 + 1];
    px2[2 * 13 + 1] = 1e300;
    st = mcg_pinhole_ray_pairs(N, NC, intr, rot, cen, foc, ids1, ids2, px1, px2, o1, d1, o2, d2,
                               ppr, &bad);
    check_status(st, MCG_EINVAL, "a pixel without a finite bearing (1e300)");
    check(bad == N + 13, "its index n + k (time 2)", (double)bad, 0.0);
    px2[2 * 13 + 1] = keep;
    /* fuzz_pixel_rays' finding: a rotation table of huge entries overflowed
     * R^T b to inf with MCG_OK */
    {
        static double saved[9 * NC];
        int j;
        for (j = 0; j < 9 * NC; j++) {
            saved[j] = rot[j];
            rot[j] = DBL_MAX; /* R^T b = DBL_MAX (b0 + b1 + b2): inf where that sum > 1 */
        }
        st = mcg_pinhole_ray_pairs(N, NC, intr, rot, cen, foc, ids1, ids2, px1, px2, o1, d1, o2,
                                   d2, ppr, &bad);
        check_status(st, MCG_EINVAL, "a rotation table whose R^T b overflows");
        check(bad >= 0 && bad < 2 * N, "the index of a pair it overflows", (double)bad, 0.0);
        for (j = 0; j < 9 * NC; j++)
            rot[j] = saved[j];
    }
    /* focal lengths whose squares overflow: no finite pixels per radian */
    keep = foc[(int)ids1[0]];
    foc[(int)ids1[0]] = 1e200;
    check_status(mcg_pinhole_ray_pairs(N, NC, intr, rot, cen, foc, ids1, ids2, px1, px2, o1, d1,
                                       o2, d2, ppr, &bad), MCG_EINVAL, "focal 1e200 (f^2 = inf)");
    foc[(int)ids1[0]] = keep;
    keep = intr[5 * 2];
    intr[5 * 2] = 0.0;
    check_status(mcg_pinhole_ray_pairs(N, NC, intr, rot, cen, foc, ids1, ids2, px1, px2, o1, d1,
                                       o2, d2, ppr, &bad), MCG_EINVAL, "fx = 0");
    intr[5 * 2] = keep;
    keep = foc[3];
    foc[3] = -1.0;
    check_status(mcg_pinhole_ray_pairs(N, NC, intr, rot, cen, foc, ids1, ids2, px1, px2, o1, d1,
                                       o2, d2, ppr, &bad), MCG_EINVAL, "focal <= 0");
    check_status(mcg_pinhole_ray_pairs(N, NC, intr, rot, cen, NULL, ids1, ids2, px1, px2, o1, d1,
                                       o2, d2, NULL, &bad), MCG_OK, "focal ignored without ppr");
    foc[3] = keep;
}

int main(void)
{
    make_rig();
    make_pairs();
    test_rays_and_ppr();
    test_status();
    printf("%d checks, %d failed\n", n_checks, n_failed);
    return n_failed != 0;
}
