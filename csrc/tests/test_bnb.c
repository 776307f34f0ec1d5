/*
 * test_bnb.c -- plain-C checks of csrc/bnb.c (branch and bound over rotations
 * with LP feasibility, thesis ch. 10) as an embedding user calls it:
 * noise-free rigs of 2-4 cameras (the error at the optimum is 0, the true
 * rotation is found from a start 0.05 rad away, the translation with its
 * metric scale), noisy ones (the returned error is at most the error at the
 * true rotation and at least the certified lower bound), R_init = identity,
 * max_blocks = 0 (the error at the given rotation only), determinism, and the
 * status codes of invalid arguments. Exit status 0 iff every check passes.
 */
#include "mcgeom.h"

#define TEST_SEED 0xb4bb4bULL
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define MAXN 200
#define WORK (40 * MAXN + 16 * 1024 + 5 * 20000)

static double D1[3 * MAXN], A1[3 * MAXN], D2[3 * MAXN], A2[3 * MAXN];
static int G[MAXN];
static double W[WORK];

/* the defaults with a heap of 20000 blocks (the test's workspace) */
static void options(mcg_bnb_options *o)
{
    mcg_bnb_default_options(o);
    o->max_queue = 20000;
}

static void mat_vec(const double R[9], const double x[3], double y[3])
{
    int i;
    for (i = 0; i < 3; ++i)
        y[i] = R[3 * i] * x[0] + R[3 * i + 1] * x[1] + R[3 * i + 2] * x[2];
}

/* a small random rotation of angle <= a */
static void small_rotation(double a, double R[9])
{
    double w[3], n;
    randn(w, 3);
    n = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    w[0] *= a * urand() / n;
    w[1] *= a * urand() / n;
    w[2] *= a * urand() / n;
    mcg_rot_from_angle_axis(w, R);
}

static double rot_angle(const double A[9], const double B[9])
{
    double tr = 0.0;
    int i, k;
    for (i = 0; i < 3; ++i)
        for (k = 0; k < 3; ++k)
            tr += A[3 * i + k] * B[3 * i + k];
    tr = 0.5 * (tr - 1.0);
    return acos(tr > 1.0 ? 1.0 : tr < -1.0 ? -1.0 : tr);
}

/* m cameras on a ring of radius 0.5 m looking outward, pts points each at
 * 3-20 m in front, motion (R, t); bearing noise of sd `noise` rad. Returns n. */
static int make_problem(int m, int pts, const double R[9], const double t[3], double noise)
{
    int c, k, n = 0, i;
    for (c = 0; c < m; ++c) {
        double yaw = 2.0 * 3.14159265358979 * c / m;
        double h[3] = {cos(yaw), sin(yaw), 0.0}, ctr[3], ctr2[3];
        for (i = 0; i < 3; ++i)
            ctr[i] = 0.5 * h[i];
        memcpy(ctr2, ctr, sizeof ctr);
        for (k = 0; k < pts; ++k, ++n) {
            double X[3], X2[3], d[3], depth = 3.0 + 17.0 * urand();
            randn(d, 3);
            for (i = 0; i < 3; ++i)
                X[i] = ctr[i] + depth * (h[i] + 0.4 * d[i]);
            mat_vec(R, X, X2);
            for (i = 0; i < 3; ++i) {
                X2[i] += t[i];
                A1[3 * n + i] = ctr[i];
                A2[3 * n + i] = ctr2[i];
                D1[3 * n + i] = X[i] - ctr[i] + noise * depth * nrand();
                D2[3 * n + i] = X2[i] - ctr2[i] + noise * depth * nrand();
            }
            G[n] = c;
        }
    }
    return n;
}

static void noise_free(void)
{
    int trial, fails_r = 0, fails_t = 0, fails_f = 0;
    double worst_r = 0.0, worst_t = 0.0, worst_f = 0.0;
    for (trial = 0; trial < scaled(6); ++trial) {
        double R[9], Rs[9], R0[9], t[3], dt = 0.0;
        int m = 2 + trial % 3, n, i, st;
        mcg_bnb_options o;
        mcg_bnb_result res;
        small_rotation(0.3, R);
        randn(t, 3);
        n = make_problem(m, 12, R, t, 0.0);
        small_rotation(0.05, Rs);
        matmul(3, 3, 3, Rs, R, R0);
        options(&o);
        o.resolution = 1e-3;
        st = mcg_bnb_linf(n, D1, A1, D2, A2, G, m, R0, &o, &res, W, WORK);
        if (st != MCG_OK) {
            check_status(st, MCG_OK, "noise-free problem solved");
            continue;
        }
        for (i = 0; i < 3; ++i)
            dt += (res.t[i] - t[i]) * (res.t[i] - t[i]);
        dt = sqrt(dt / (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]));
        if (rot_angle(res.R, R) > 1e-6)
            ++fails_r;
        if (dt > 1e-5)
            ++fails_t;
        if (res.linf > 1e-8 || res.lower_bound > res.linf)
            ++fails_f;
        if (rot_angle(res.R, R) > worst_r)
            worst_r = rot_angle(res.R, R);
        if (dt > worst_t)
            worst_t = dt;
        if (res.linf > worst_f)
            worst_f = res.linf;
    }
    check(fails_r == 0, "noise-free: rotation within 1e-6 rad (worst)", worst_r, 1e-6);
    check(fails_t == 0, "noise-free: metric translation within 1e-5 (worst rel.)", worst_t, 1e-5);
    check(fails_f == 0, "noise-free: L-inf error 0 (worst, rad)", worst_f, 1e-8);
}

static void noisy(void)
{
    int trial, above = 0, lb_above = 0;
    double worst = -1.0;
    for (trial = 0; trial < scaled(8); ++trial) {
        double R[9], t[3], I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
        int m = 2 + trial % 3, n, st;
        mcg_bnb_options o;
        mcg_bnb_result res, at_true;
        small_rotation(0.3, R);
        randn(t, 3);
        n = make_problem(m, 10, R, t, 1e-3);
        options(&o);
        o.resolution = 1e-3;
        /* the error at the true rotation: max_blocks = 0 */
        o.max_blocks = 0;
        st = mcg_bnb_linf(n, D1, A1, D2, A2, G, m, R, &o, &at_true, W, WORK);
        check_status(st, MCG_OK, "max_blocks = 0: the error at a rotation");
        o.max_blocks = 2000000;
        /* the search from the identity (a poor start) */
        st = mcg_bnb_linf(n, D1, A1, D2, A2, G, m, I, &o, &res, W, WORK);
        check_status(st, MCG_OK, "noisy problem from R_init = I");
        if (res.linf > at_true.initial_linf + 1e-9)
            ++above;
        if (res.lower_bound > at_true.initial_linf + 1e-12 || res.lower_bound > res.linf)
            ++lb_above;
        if (res.linf - at_true.initial_linf > worst)
            worst = res.linf - at_true.initial_linf;
    }
    check(above == 0, "noisy: f(returned) <= f(true rotation) (worst difference)", worst, 1e-9);
    check(lb_above == 0, "noisy: lower bound <= f(true rotation) and <= f(returned)", 0, 0);
}

static void determinism(void)
{
    double R[9], t[3] = {0.3, -0.2, 0.5};
    mcg_bnb_options o;
    mcg_bnb_result a, b;
    int n;
    small_rotation(0.2, R);
    n = make_problem(3, 8, R, t, 5e-4);
    options(&o);
    o.resolution = 1e-3;
    mcg_bnb_linf(n, D1, A1, D2, A2, G, 3, R, &o, &a, W, WORK);
    mcg_bnb_linf(n, D1, A1, D2, A2, G, 3, R, &o, &b, W, WORK);
    check(a.linf == b.linf && a.blocks == b.blocks && memcmp(a.R, b.R, sizeof a.R) == 0,
          "two identical calls give identical results", fabs(a.linf - b.linf), 0);
}

static void invalid(void)
{
    double R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, t[3] = {0.1, 0.2, 0.3}, keep;
    mcg_bnb_options o;
    mcg_bnb_result res;
    int n = make_problem(2, 6, R, t, 0.0);
    options(&o);
    check_status(mcg_bnb_linf(0, D1, A1, D2, A2, G, 2, R, &o, &res, W, WORK), MCG_EINVAL,
                 "n = 0");
    check_status(mcg_bnb_linf(n, NULL, A1, D2, A2, G, 2, R, &o, &res, W, WORK), MCG_EINVAL,
                 "NULL bearings");
    check_status(mcg_bnb_linf(n, D1, A1, D2, A2, G, 2, R, &o, NULL, W, WORK), MCG_EINVAL,
                 "NULL result");
    check_status(mcg_bnb_linf(n, D1, A1, D2, A2, G, 2, R, &o, &res, W, 10), MCG_ENOMEM,
                 "workspace too small");
    check_status(mcg_bnb_linf(n, D1, A1, D2, A2, G, n + 1, R, &o, &res, W, WORK), MCG_EINVAL,
                 "more groups than correspondences");
    G[0] = 5;
    check_status(mcg_bnb_linf(n, D1, A1, D2, A2, G, 2, R, &o, &res, W, WORK), MCG_EINVAL,
                 "group index out of range");
    G[0] = 0;
    keep = D1[4];
    D1[4] = NAN;
    check_status(mcg_bnb_linf(n, D1, A1, D2, A2, G, 2, R, &o, &res, W, WORK), MCG_EINVAL,
                 "NaN bearing");
    D1[4] = keep;
    D1[3] = D1[4] = D1[5] = 0.0;
    check_status(mcg_bnb_linf(n, D1, A1, D2, A2, G, 2, R, &o, &res, W, WORK), MCG_EINVAL,
                 "zero bearing");
    D1[3] = 1e200; /* |d| overflows when squared */
    check_status(mcg_bnb_linf(n, D1, A1, D2, A2, G, 2, R, &o, &res, W, WORK), MCG_EINVAL,
                 "bearing component 1e200");
    D1[3] = 1.0;
    A2[7] = -1e151;
    check_status(mcg_bnb_linf(n, D1, A1, D2, A2, G, 2, R, &o, &res, W, WORK), MCG_EINVAL,
                 "origin component -1e151");
    A2[7] = A1[7];
    o.max_seconds = -1.0;
    check_status(mcg_bnb_linf(n, D1, A1, D2, A2, G, 2, R, &o, &res, W, WORK), MCG_EINVAL,
                 "max_seconds < 0");
    o.max_seconds = NAN;
    check_status(mcg_bnb_linf(n, D1, A1, D2, A2, G, 2, R, &o, &res, W, WORK), MCG_EINVAL,
                 "max_seconds NaN");
    o.max_seconds = 0.0;
    o.resolution = 0.0;
    check_status(mcg_bnb_linf(n, D1, A1, D2, A2, G, 2, R, &o, &res, W, WORK), MCG_EINVAL,
                 "resolution 0");
    check(mcg_bnb_work_size(n, 2, &o) == 0, "work size 0 for invalid options", 0, 0);
    options(&o);
    o.grid = 0;
    check(mcg_bnb_work_size(n, 2, &o) == 0, "work size 0 for grid 0", 0, 0);
    check(mcg_bnb_work_size(0, 1, NULL) == 0, "work size 0 for n = 0", 0, 0);
}

/* The time budget: a search that would take long (a tiny resolution) stops
 * at max_seconds with TIME_LIMIT, a certified bound below its error, and
 * fewer blocks than the block budget. */
static void time_budget(void)
{
    double R[9], t[3] = {0.3, -0.2, 0.1};
    mcg_bnb_options o;
    mcg_bnb_result res;
    int n, st;
    small_rotation(0.2, R);
    n = make_problem(3, 20, R, t, 2e-3);
    options(&o);
    o.resolution = 1e-7;
    o.max_seconds = 0.02;
    st = mcg_bnb_linf(n, D1, A1, D2, A2, G, 3, R, &o, &res, W, WORK);
    check_status(st, MCG_OK, "time-limited search returns");
    check(res.stop == MCG_BNB_TIME_LIMIT, "stop = MCG_BNB_TIME_LIMIT", (double)res.stop,
          MCG_BNB_TIME_LIMIT);
    check(res.lower_bound <= res.linf && res.linf <= res.initial_linf,
          "lower bound <= linf <= initial linf at the time limit", res.linf - res.lower_bound,
          0);
    check(res.blocks < o.max_blocks && res.queued > 0, "stopped before the block budget",
          (double)res.blocks, (double)o.max_blocks);
    /* the block budget: exactly max_blocks blocks, then MAX_BLOCKS */
    options(&o);
    o.resolution = 1e-7;
    o.max_blocks = 50;
    st = mcg_bnb_linf(n, D1, A1, D2, A2, G, 3, R, &o, &res, W, WORK);
    check_status(st, MCG_OK, "block-limited search returns");
    check(res.stop == MCG_BNB_MAX_BLOCKS && res.blocks == 50,
          "max_blocks = 50: 50 blocks, stop = MCG_BNB_MAX_BLOCKS", (double)res.blocks, 50);
    check(res.lower_bound <= res.linf, "lower bound <= linf at the block limit",
          res.linf - res.lower_bound, 0);
}

int main(void)
{
    mcg_bnb_options o;
    options(&o);
    check(mcg_bnb_work_size(MAXN, 8, &o) <= WORK && mcg_bnb_work_size(MAXN, 8, &o) > 0,
          "test workspace is large enough", (double)mcg_bnb_work_size(MAXN, 8, &o), WORK);
    noise_free();
    noisy();
    determinism();
    invalid();
    time_budget();
    printf("%d checks, %d failed\n", n_checks, n_failed);
    return n_failed != 0;
}
