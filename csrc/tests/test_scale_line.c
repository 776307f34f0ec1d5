/*
 * test_scale_line.c -- plain-C checks of csrc/scale_line.c (mcg_scale_ransac,
 * the 1-point scale search of the 5+1 method, thesis ch. 7.4): exact recovery
 * of the scale on noise-free pairs of a 4-camera rig with 30 % gross
 * outliers (intra- and cross-camera pairs), the returned MSAC score against
 * the residuals of mcg_gec_residuals at t0 + lam w, the stopping rule
 * (fewer proposals than allowed on clean data), the degenerate cases
 * (w = 0, no proposal) and the status codes of invalid arguments.
 * Exit status 0 iff every check passes.
 */
#include "mcgeom.h"

#define TEST_SEED 0x5ca1e11e0ULL
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define N 200
#define LW (5 * N) /* mcg_scale_ransac_work_size(N) */

static double o1[3 * N], d1[3 * N], o2[3 * N], d2[3 * N], work[5 * N];
static int order[N];

/* a 4-camera rig moving by R, t = t0 + lam w, t0 = c0 - R c0 (camera 0 the
 * 5-point camera); pairs of cameras 1..3, every 4th one cross-camera, the
 * first n_out of them with a random time-2 bearing (gross outliers) */
static void scene(double R[9], double t0[3], double w[3], double lam, int n_out)
{
    double c[4][3], aa[3], t[3];
    int k, i;
    for (i = 0; i < 3; i++)
        aa[i] = 0.2 * nrand();
    mcg_rot_from_angle_axis(aa, R);
    for (k = 0; k < 4; k++)
        for (i = 0; i < 3; i++)
            c[k][i] = 0.3 * nrand();
    for (i = 0; i < 3; i++)
        w[i] = nrand();
    {
        double nw = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
        for (i = 0; i < 3; i++)
            w[i] /= nw;
    }
    for (i = 0; i < 3; i++)
        t0[i] = c[0][i] - (R[3 * i] * c[0][0] + R[3 * i + 1] * c[0][1] + R[3 * i + 2] * c[0][2]);
    for (i = 0; i < 3; i++)
        t[i] = t0[i] + lam * w[i];
    for (k = 0; k < N; k++) {
        int g = 1 + k % 3, h = k % 4 == 3 ? 1 + (g % 3) : g;
        double X[3], X2[3];
        X[0] = 4.0 * (urand() - 0.5);
        X[1] = 4.0 * (urand() - 0.5);
        X[2] = 2.0 + 8.0 * urand();
        for (i = 0; i < 3; i++)
            X2[i] = R[3 * i] * X[0] + R[3 * i + 1] * X[1] + R[3 * i + 2] * X[2] + t[i];
        for (i = 0; i < 3; i++) {
            o1[3 * k + i] = c[g][i];
            o2[3 * k + i] = c[h][i];
            d1[3 * k + i] = X[i] - c[g][i];
            d2[3 * k + i] = k < n_out ? nrand() : X2[i] - c[h][i];
        }
        order[k] = (int)((k * 37 + 11) % N); /* a fixed permutation (37 coprime to N) */
    }
}

static double msac_direct(const double R[9], const double t0[3], const double w[3], double lam,
                          double thr)
{
    double t[3], r[N], s = 0.0;
    int k;
    for (k = 0; k < 3; k++)
        t[k] = t0[k] + lam * w[k];
    if (mcg_gec_residuals(N, o1, d1, o2, d2, R, t, r) != MCG_OK)
        return NAN;
    for (k = 0; k < N; k++)
        s += r[k] * r[k] < thr * thr ? r[k] * r[k] : thr * thr;
    return s;
}

static void test_recovery(void)
{
    int trial, worst_ok = 1, score_ok = 1, inl_ok = 1, n_exact = 0;
    double worst = 0.0, worst_score = 0.0;
    for (trial = 0; trial < scaled(50); trial++) {
        double R[9], t0[3], w[3], lam = -1.0, score = -1.0, lam_true = 0.2 + 2.0 * urand();
        double thr = 1e-3, direct, err;
        int m = -1, st;
        scene(R, t0, w, lam_true, 60);
        st = mcg_scale_ransac(N, o1, d1, o2, d2, R, t0, w, N, order, 64, thr, 0.999, &lam,
                              &score, &m, work, LW);
        if (st != MCG_OK) {
            check_status(st, MCG_OK, "scale_ransac on a 4-camera scene");
            continue;
        }
        /* an outlier may fall within the threshold by chance and pull the
         * least-squares step (which lowers the score): then lam is near, not
         * at, the truth, and scores no worse than it */
        err = fabs(lam - lam_true) / lam_true;
        worst = err > worst ? err : worst;
        direct = msac_direct(R, t0, w, lam, thr);
        worst_ok &= err < 1e-2 && direct <= msac_direct(R, t0, w, lam_true, thr) * (1 + 1e-12);
        n_exact += err < 1e-9;
        inl_ok &= m >= N - 60 && m <= N;
        worst_score = fmax(worst_score, fabs(direct - score) / (score + 1e-300));
        score_ok &= fabs(direct - score) <= 1e-9 * score + 1e-20;
    }
    check(worst_ok, "scale within 1 %, no worse than the truth (30 % outliers)", worst, 1e-2);
    check(n_exact >= scaled(50) * 8 / 10, "scale exact (1e-9) in >= 80 % of the scenes",
          (double)n_exact, scaled(50) * 0.8);
    check(inl_ok, "every exact pair counted as inlier", 0.0, 0.0);
    check(score_ok, "score = MSAC of mcg_gec_residuals at t0 + lam w", worst_score, 1e-9);
}

/* clean data: the first batch finds an all-inlier scale, the stop needs 1 */
static void test_early_stop(void)
{
    double R[9], t0[3], w[3], lam, score;
    int m, st;
    scene(R, t0, w, 1.0, 0);
    st = mcg_scale_ransac(N, o1, d1, o2, d2, R, t0, w, N, order, 64, 1e-3, 0.999, &lam, &score,
                          &m, work, LW);
    check_status(st, MCG_OK, "scale_ransac on clean data");
    check(m == N && fabs(lam - 1.0) < 1e-9, "clean data: all inliers, lam = 1", fabs(lam - 1.0),
          1e-9);
    /* one allowed proposal gives the same answer (any exact pair is right) */
    st = mcg_scale_ransac(N, o1, d1, o2, d2, R, t0, w, N, order, 1, 1e-3, 0.999, &lam, &score,
                          NULL, work, LW);
    check(st == MCG_OK && fabs(lam - 1.0) < 1e-9, "one proposal on clean data",
          fabs(lam - 1.0), 1e-9);
}

static void test_degenerate_and_invalid(void)
{
    double R[9], t0[3], w[3], z[3] = {0.0, 0.0, 0.0}, lam, score, keep;
    int m, bad[1] = {N};
    scene(R, t0, w, 1.0, 0);
    check_status(mcg_scale_ransac(N, o1, d1, o2, d2, R, t0, z, N, order, 64, 1e-3, 0.999, &lam,
                                  &score, &m, work, LW),
                 MCG_EDEGENERATE, "w = 0: no pair proposes a scale");
    check_status(mcg_scale_ransac(N, o1, d1, o2, d2, R, t0, w, 0, order, 64, 1e-3, 0.999, &lam,
                                  &score, &m, work, LW),
                 MCG_EDEGENERATE, "empty order");
    check_status(mcg_scale_ransac(N, NULL, d1, o2, d2, R, t0, w, N, order, 64, 1e-3, 0.999, &lam,
                                  &score, &m, work, LW),
                 MCG_EINVAL, "NULL o1");
    check_status(mcg_scale_ransac(N, o1, d1, o2, d2, R, t0, w, N, order, 64, 1e-3, 0.999, NULL,
                                  &score, &m, work, LW),
                 MCG_EINVAL, "NULL lam");
    check_status(mcg_scale_ransac(0, o1, d1, o2, d2, R, t0, w, 0, order, 64, 1e-3, 0.999, &lam,
                                  &score, &m, work, LW),
                 MCG_EINVAL, "n = 0");
    check_status(mcg_scale_ransac(N, o1, d1, o2, d2, R, t0, w, 1, bad, 64, 1e-3, 0.999, &lam,
                                  &score, &m, work, LW),
                 MCG_EINVAL, "order index n");
    check_status(mcg_scale_ransac(N, o1, d1, o2, d2, R, t0, w, N, order, 0, 1e-3, 0.999, &lam,
                                  &score, &m, work, LW),
                 MCG_EINVAL, "max_proposals 0");
    check_status(mcg_scale_ransac(N, o1, d1, o2, d2, R, t0, w, N, order, 64, 0.0, 0.999, &lam,
                                  &score, &m, work, LW),
                 MCG_EINVAL, "threshold 0");
    check_status(mcg_scale_ransac(N, o1, d1, o2, d2, R, t0, w, N, order, 64, NAN, 0.999, &lam,
                                  &score, &m, work, LW),
                 MCG_EINVAL, "threshold NaN");
    check_status(mcg_scale_ransac(N, o1, d1, o2, d2, R, t0, w, N, order, 64, 1e-3, 1.0, &lam,
                                  &score, &m, work, LW),
                 MCG_EINVAL, "prob 1");
    check_status(mcg_scale_ransac(N, o1, d1, o2, d2, R, t0, w, N, order, 64, 1e-3, 0.999, &lam,
                                  &score, &m, work, LW - 1),
                 MCG_ENOMEM, "workspace one double short");
    keep = d1[7];
    d1[7] = NAN;
    check_status(mcg_scale_ransac(N, o1, d1, o2, d2, R, t0, w, N, order, 64, 1e-3, 0.999, &lam,
                                  &score, &m, work, LW),
                 MCG_EINVAL, "NaN in d1");
    d1[7] = keep;
    d2[3] = d2[4] = d2[5] = 0.0;
    check_status(mcg_scale_ransac(N, o1, d1, o2, d2, R, t0, w, N, order, 64, 1e-3, 0.999, &lam,
                                  &score, &m, work, LW),
                 MCG_EINVAL, "zero-length d2");
    t0[1] = HUGE_VAL;
    check_status(mcg_scale_ransac(N, o1, d1, o2, d2, R, t0, w, N, order, 64, 1e-3, 0.999, &lam,
                                  &score, &m, work, LW),
                 MCG_EINVAL, "inf in t0");
    check(mcg_scale_ransac_work_size(0) == 0 && mcg_scale_ransac_work_size(N) == LW,
          "work size: 0 for n = 0, 5 n otherwise", 0.0, 0.0);
}

int main(void)
{
    test_recovery();
    test_early_stop();
    test_degenerate_and_invalid();
    printf("%d checks, %d failed\n", n_checks, n_failed);
    return n_failed ? 1 : 0;
}
