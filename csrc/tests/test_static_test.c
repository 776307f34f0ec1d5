/*
 * test_static_test.c -- plain-C checks of csrc/static_test.c
 * (mcg_static_noise), against independent references: on exact data of a
 * moving 3-camera rig the residuals are those of each camera's true
 * translation (R c + t - c, through mcg_gec_residuals), also with planted
 * outliers in one camera; on noisy data the median is no worse than the true
 * directions' and equals the median of the sorted residuals (qsort); cameras
 * below min_rows and pairs of group -1 are left out; the explained fraction
 * of mcg_static_check against an atan2 recount, also with its bound at each
 * angle; the status codes of invalid arguments. Exit status 0 iff every check passes.
 */
#include "mcgeom.h"

#define TEST_SEED 0x57a71c0de5ULL
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NC 3
#define PER 24
#define N (NC * PER)

static double o1[3 * N], d1[3 * N], o2[3 * N], d2[3 * N], R[9], t[3];
static int grp[N];

static double gauss(void)
{
    return sqrt(-2.0 * log(urand())) * cos(6.283185307179586 * urand());
}

/* a moving rig: camera k at c_k sees points 2..12 m ahead; bearings with
 * angular noise sigma (radians) */
static void scene(double sigma)
{
    double w[3], c[NC][3];
    int k, i, j;
    for (i = 0; i < 3; i++)
        w[i] = 0.2 * (urand() - 0.5);
    mcg_rot_from_angle_axis(w, R);
    for (i = 0; i < 3; i++)
        t[i] = urand() - 0.5;
    for (k = 0; k < NC; k++)
        for (i = 0; i < 3; i++)
            c[k][i] = 0.5 * (urand() - 0.5);
    for (j = 0; j < N; j++) {
        double X[3], X2[3];
        k = j % NC;
        grp[j] = k;
        X[0] = 6.0 * (urand() - 0.5);
        X[1] = 6.0 * (urand() - 0.5);
        X[2] = 2.0 + 10.0 * urand();
        for (i = 0; i < 3; i++)
            X2[i] = R[3 * i] * X[0] + R[3 * i + 1] * X[1] + R[3 * i + 2] * X[2] + t[i];
        for (i = 0; i < 3; i++) {
            o1[3 * j + i] = o2[3 * j + i] = c[k][i];
            d1[3 * j + i] = X[i] - c[k][i] + sigma * gauss();
            d2[3 * j + i] = X2[i] - c[k][i] + sigma * gauss();
        }
    }
}

/* |residual| of pair j at the camera's true translation t + R c - c, i.e.
 * the motion (R, t) itself */
static double true_residual(int j)
{
    double e;
    mcg_gec_residuals(1, o1 + 3 * j, d1 + 3 * j, o2 + 3 * j, d2 + 3 * j, R, t, &e);
    return fabs(e);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double sorted_median(const double *x, int n)
{
    double *s = malloc(sizeof(double) * (size_t)n), m;
    memcpy(s, x, sizeof(double) * (size_t)n);
    qsort(s, (size_t)n, sizeof(double), cmp_double);
    m = n % 2 ? s[n / 2] : 0.5 * (s[n / 2 - 1] + s[n / 2]);
    free(s);
    return m;
}

static double *workspace(int n, size_t *lw)
{
    *lw = mcg_static_noise_work_size(n);
    return malloc(sizeof(double) * (*lw ? *lw : 1));
}

static void test_exact_and_outliers(void)
{
    double res[N], med, worst = 0.0, worst_out = 0.0;
    size_t lw;
    double *work = workspace(N, &lw);
    int trial, used, st, j;
    for (trial = 0; trial < scaled(20); trial++) {
        scene(0.0);
        /* 4 of camera 0's 24 pairs are outliers */
        for (j = 0; j < 4; j++) {
            d2[3 * (3 * j)] += 0.3;
            d2[3 * (3 * j) + 1] -= 0.2;
        }
        st = mcg_static_noise(N, o1, d1, o2, d2, grp, R, 5, 32, res, &med, &used, work, lw);
        if (st != MCG_OK || used != N) {
            check(0, "static_noise on exact data: status / used", (double)st, 0.0);
            break;
        }
        for (j = 0; j < N; j++) {
            double d = fabs(res[j] - true_residual(j));
            if (j % 3 == 0 && j < 12)
                worst_out = fmax(worst_out, d / fmax(true_residual(j), 1e-300));
            else
                worst = fmax(worst, d);
        }
    }
    check(worst < 1e-10, "exact pairs: residuals of the true directions (rad)", worst, 1e-10);
    check(worst_out < 1e-6, "planted outliers: residual as at the true direction (rel)",
          worst_out, 1e-6);
    free(work);
}

static void test_noisy_median(void)
{
    double res[N], tr[N], used_res[N], med, worst_sel = 0.0, worst_ratio = 0.0;
    size_t lw;
    double *work = workspace(N, &lw);
    int trial, used, j, m;
    for (trial = 0; trial < scaled(20); trial++) {
        scene(1e-3);
        if (mcg_static_noise(N, o1, d1, o2, d2, grp, R, 5, 32, res, &med, &used, work, lw) !=
            MCG_OK)
            continue;
        for (j = m = 0; j < N; j++) {
            tr[j] = true_residual(j);
            used_res[m++] = res[j];
        }
        /* even count (72): numpy's mean of the two middle values */
        worst_sel = fmax(worst_sel, fabs(med - sorted_median(used_res, m)));
        /* the fitted directions leave about what the true ones leave (the
         * least-squares step minimises the algebraic rows of each camera, not
         * the median Sampson residual: up to 1.19 x seen) */
        worst_ratio = fmax(worst_ratio, med / sorted_median(tr, N));
    }
    check(worst_sel == 0.0, "median equals the sorted middle of the residuals", worst_sel, 0.0);
    check(worst_ratio < 1.5, "median of the fit / median at the true directions", worst_ratio,
          1.5);
    free(work);
}

static void test_selection(void)
{
    double res[N], med;
    size_t lw;
    double *work = workspace(N, &lw);
    int used, j, ok = 1, st;
    scene(1e-3);
    for (j = 0; j < N; j++) {
        if (j % 3 == 2)
            grp[j] = j < 30 ? 2 : -1; /* camera 2 keeps 10 pairs */
        if (j % 3 == 1 && j % 2 == 0)
            grp[j] = -1; /* half of camera 1 are cross-camera */
    }
    st = mcg_static_noise(N, o1, d1, o2, d2, grp, R, 12, 8, res, &med, &used, work, lw);
    check_status(st, MCG_OK, "static_noise with cameras below min_rows");
    for (j = 0; j < N; j++) {
        /* camera 0: 24 pairs, camera 1: 12 left, camera 2: 10 (< min_rows) */
        int expect = grp[j] == 0 || grp[j] == 1;
        ok &= expect ? res[j] >= 0.0 : res[j] == -1.0;
    }
    check(ok, "pairs left out are -1, the others >= 0", (double)!ok, 0.0);
    check(used == 36, "used = 24 + 12 pairs", (double)used, 0.0);
    for (j = 0; j < N; j++)
        grp[j] = -1;
    st = mcg_static_noise(N, o1, d1, o2, d2, grp, R, 1, 8, res, &med, &used, work, lw);
    check(st == MCG_OK && used == 0 && med == 0.0, "no pair used: median 0", med, 0.0);
    st = mcg_static_noise(0, o1, d1, o2, d2, grp, R, 1, 8, res, &med, &used, work, lw);
    check(st == MCG_OK && used == 0, "n = 0", (double)st, 0.0);
    free(work);
}

static void test_status(void)
{
    double res[N], med, nan = NAN;
    size_t lw;
    double *work = workspace(N, &lw);
    int used;
    scene(1e-3);
    check_status(mcg_static_noise(N, NULL, d1, o2, d2, grp, R, 5, 32, res, &med, &used, work,
                                  lw), MCG_EINVAL, "NULL origins1");
    check_status(mcg_static_noise(N, o1, d1, o2, d2, grp, R, 0, 32, res, &med, &used, work, lw),
                 MCG_EINVAL, "min_rows = 0");
    check_status(mcg_static_noise(N, o1, d1, o2, d2, grp, R, 5, -1, res, &med, &used, work, lw),
                 MCG_EINVAL, "samples = -1");
    check_status(mcg_static_noise(N, o1, d1, o2, d2, grp, R, 5, 65537, res, &med, &used, work,
                                  lw), MCG_EINVAL, "samples = 65537");
    check_status(mcg_static_noise(-1, o1, d1, o2, d2, grp, R, 5, 32, res, &med, &used, work,
                                  lw), MCG_EINVAL, "n = -1");
    check_status(mcg_static_noise(N, o1, d1, o2, d2, grp, R, 5, 32, res, &med, &used, work,
                                  lw - 1), MCG_ENOMEM, "workspace one short");
    check(mcg_static_noise_work_size(-1) == 0, "work_size(-1) = 0", 0.0, 0.0);
    grp[5] = -2;
    check_status(mcg_static_noise(N, o1, d1, o2, d2, grp, R, 5, 32, res, &med, &used, work, lw),
                 MCG_EINVAL, "group -2");
    grp[5] = 2;
    d2[7] = nan;
    check_status(mcg_static_noise(N, o1, d1, o2, d2, grp, R, 5, 32, res, &med, &used, work, lw),
                 MCG_EINVAL, "NaN direction");
    d2[6] = d2[7] = d2[8] = 0.0;
    check_status(mcg_static_noise(N, o1, d1, o2, d2, grp, R, 5, 32, res, &med, &used, work, lw),
                 MCG_EINVAL, "zero direction");
    R[0] = nan;
    d2[6] = 1.0;
    check_status(mcg_static_noise(N, o1, d1, o2, d2, grp, R, 5, 32, res, &med, &used, work, lw),
                 MCG_EINVAL, "NaN in R");
    free(work);
}

/* mcg_static_check: a static rig (R = I, t = 0, ~1e-4 rad noise) is static
 * with its rotation recovered; a moving rig (rotation up to 0.1 rad, |t| up
 * to 0.87 m) is not, with the estimate's rotation given; a given noise
 * level is used as is */
static void test_check(void)
{
    mcg_static_options opt;
    mcg_static_result res;
    size_t lw = mcg_static_check_work_size(N);
    double *work = malloc(sizeof(double) * lw), err = 0.0;
    int i, st, ok_static = 1, ok_moving = 1, trial;
    mcg_static_default_options(&opt);
    for (trial = 0; trial < scaled(10); trial++) {
        scene(0.0);
        /* static (R = I, t = 0: a rig that rotates moves its off-centre
         * cameras): time 2 sees each point along the same bearing, with noise */
        for (i = 0; i < 9; i++)
            R[i] = (i % 4 == 0) ? 1.0 : 0.0;
        for (i = 0; i < 3 * N; i++)
            d2[i] = d1[i] + 5e-4 * gauss();
        st = mcg_static_check(N, o1, d1, o2, d2, grp, NULL, NULL, 0.0, &opt, &res, work, lw);
        ok_static &= st == MCG_OK && res.is_static && res.decided_at == 0;
        for (i = 0; i < 9; i++)
            err = fmax(err, fabs(res.R_fit[i] - R[i]));
        scene(1e-4);
        st = mcg_static_check(N, o1, d1, o2, d2, grp, R, NULL, 0.0, &opt, &res, work, lw);
        ok_moving &= st == MCG_OK && !res.is_static;
    }
    check(ok_static, "static rig: static at the pure rotation", (double)!ok_static, 0.0);
    check(err < 1e-3, "static rig: R_fit = R (max entry error)", err, 1e-3);
    check(ok_moving, "moving rig (estimate's R given): not static", (double)!ok_moving, 0.0);
    st = mcg_static_check(N, o1, d1, o2, d2, grp, R, NULL, 10.0, &opt, &res, work, lw);
    check(st == MCG_OK && res.is_static && res.noise_level == 10.0,
          "a given noise level of 10 rad explains every angle", res.noise_level, 0.0);
    check_status(mcg_static_check(N, o1, d1, o2, d2, grp, NULL, NULL, -1.0, &opt, &res, work,
                                  lw), MCG_EINVAL, "static_check: noise_level -1");
    opt.fraction = 1.5;
    check_status(mcg_static_check(N, o1, d1, o2, d2, grp, NULL, NULL, 0.0, &opt, &res, work,
                                  lw), MCG_EINVAL, "static_check: fraction 1.5");
    mcg_static_default_options(&opt);
    check_status(mcg_static_check(N, o1, d1, o2, d2, grp, NULL, NULL, 0.0, &opt, &res, work,
                                  lw - 1), MCG_ENOMEM, "static_check: workspace one short");
    free(work);
}

/* issue 22's faster paths against plain references: camera ids >= n (the
 * merge sort instead of the counting sort, ids in decreasing order) give
 * the same residuals bit for bit; the explained fraction of a given level
 * is the count of atan2 angles below parallax_factor x level, for levels
 * at several quantiles of the angles (the tan prefilter near its bound) */
static void test_fast_paths(void)
{
    mcg_static_options opt;
    mcg_static_result res;
    double r1[N], r2[N], m1, m2, ang[N], *work;
    size_t lw = mcg_static_check_work_size(N);
    int big[N], u1, u2, j, q, same = 1, st;
    work = malloc(sizeof(double) * lw);
    scene(1e-3);
    for (j = 0; j < N; j++)
        big[j] = 100000 - 7 * grp[j];
    st = mcg_static_noise(N, o1, d1, o2, d2, grp, R, 12, 32, r1, &m1, &u1, work, lw);
    st |= mcg_static_noise(N, o1, d1, o2, d2, big, R, 12, 32, r2, &m2, &u2, work, lw);
    for (j = 0; j < N; j++)
        same &= r1[j] == r2[j];
    check(st == MCG_OK && same && m1 == m2 && u1 == u2,
          "ids >= n: the same residuals as compact ids", m1 - m2, 0.0);
    for (j = 0; j < N; j++) {
        double a[3], b[3], x[3], na = 0.0, nb = 0.0;
        int c;
        for (c = 0; c < 3; c++) {
            na += d1[3 * j + c] * d1[3 * j + c];
            nb += d2[3 * j + c] * d2[3 * j + c];
        }
        for (c = 0; c < 3; c++) {
            a[c] = (R[3 * c] * d1[3 * j] + R[3 * c + 1] * d1[3 * j + 1] +
                    R[3 * c + 2] * d1[3 * j + 2]) / sqrt(na);
            b[c] = d2[3 * j + c] / sqrt(nb);
        }
        x[0] = a[1] * b[2] - a[2] * b[1];
        x[1] = a[2] * b[0] - a[0] * b[2];
        x[2] = a[0] * b[1] - a[1] * b[0];
        ang[j] = atan2(sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]),
                       a[0] * b[0] + a[1] * b[1] + a[2] * b[2]);
    }
    mcg_static_default_options(&opt);
    for (q = 1; q < 10; q++) {
        double lim = sorted_median(ang, N) * 0.25 * q, level = lim / opt.parallax_factor;
        int inside = 0;
        for (j = 0; j < N; j++)
            inside += ang[j] < lim;
        st = mcg_static_check(N, o1, d1, o2, d2, grp, NULL, R, level, &opt, &res, work, lw);
        check(st == MCG_OK && fabs(res.explained - (double)inside / N) < 1e-12,
              "explained = atan2 count below the bound", res.explained - (double)inside / N,
              1e-12);
    }
    /* bounds at the angles themselves, where the tan prefilter cannot
     * decide (its second pass with atan2): the angles as the kernel rounds
     * them (unit bearings d / |d| as v (1 / |v|), then R u1) */
    {
        int bad = 0, k, c;
        for (j = 0; j < N; j++) {
            double u[3], w[3], a[3], x[3], s1 = 0.0, s2 = 0.0;
            for (c = 0; c < 3; c++) {
                s1 += d1[3 * j + c] * d1[3 * j + c];
                s2 += d2[3 * j + c] * d2[3 * j + c];
            }
            s1 = 1.0 / sqrt(s1);
            s2 = 1.0 / sqrt(s2);
            for (c = 0; c < 3; c++) {
                u[c] = d1[3 * j + c] * s1;
                w[c] = d2[3 * j + c] * s2;
            }
            for (c = 0; c < 3; c++)
                a[c] = R[3 * c] * u[0] + R[3 * c + 1] * u[1] + R[3 * c + 2] * u[2];
            x[0] = a[1] * w[2] - a[2] * w[1];
            x[1] = a[2] * w[0] - a[0] * w[2];
            x[2] = a[0] * w[1] - a[1] * w[0];
            ang[j] = atan2(sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]),
                           a[0] * w[0] + a[1] * w[1] + a[2] * w[2]);
        }
        for (j = 0; j < N; j++) {
            double level = ang[j] / opt.parallax_factor, lim = opt.parallax_factor * level;
            int inside = 0;
            for (k = 0; k < N; k++)
                inside += ang[k] < lim;
            st = mcg_static_check(N, o1, d1, o2, d2, grp, NULL, R, level, &opt, &res, work, lw);
            bad += st != MCG_OK || fabs(res.explained - (double)inside / N) > 1e-12;
        }
        check(bad == 0, "explained = atan2 count with the bound at each angle", (double)bad, 0);
    }
    free(work);
}

int main(void)
{
    test_check();
    test_fast_paths();
    test_exact_and_outliers();
    test_noisy_median();
    test_selection();
    test_status();
    printf("%d checks, %d failed\n", n_checks, n_failed);
    return n_failed ? 1 : 0;
}
