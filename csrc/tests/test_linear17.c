/* test_linear17.c -- plain-C checks of mcg_linear17 (thesis ch. 8) on
 * synthetic rigs with a known motion: exact recovery for each generalized
 * camera kind, the critical (no rotation) verdict, and argument validation. */
#include "mcgeom.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static int failures = 0;

#define CHECK(cond, ...)                                                      \
    do {                                                                      \
        if (cond) {                                                           \
            printf("ok   ");                                                  \
        } else {                                                              \
            printf("FAIL ");                                                  \
            failures++;                                                       \
        }                                                                     \
        printf(__VA_ARGS__);                                                  \
        printf("\n");                                                         \
    } while (0)

static unsigned long long rng_state = 0x9E3779B97F4A7C15ULL;

static double urand(void) /* xorshift64*, uniform in [0, 1) */
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return (double)((rng_state * 2685821657736338717ULL) >> 11) / 9007199254740992.0;
}

static double srand1(void) { return 2.0 * urand() - 1.0; }

static void matvec3(const double *r, const double *x, double *y)
{
    int i;
    for (i = 0; i < 3; i++)
        y[i] = r[3 * i] * x[0] + r[3 * i + 1] * x[1] + r[3 * i + 2] * x[2];
}

/* n correspondences of points seen from centres[cam1[k]] at time 1 and
 * centres[cam2[k]] at time 2 under X2 = R X1 + t. */
static void make_rays(int n, int ncam, const double *centres, int cross,
                      const double r[9], const double t[3], double *o1,
                      double *d1, double *o2, double *d2)
{
    int k, i;
    for (k = 0; k < n; k++) {
        int c1 = k % ncam, c2 = cross ? (k + 1) % ncam : c1;
        double x[3], x2[3];
        for (i = 0; i < 3; i++)
            x[i] = centres[3 * c1 + i] + 5.0 * srand1();
        x[0] += 6.0; /* keep points away from the rig */
        matvec3(r, x, x2);
        for (i = 0; i < 3; i++) {
            x2[i] += t[i];
            o1[3 * k + i] = centres[3 * c1 + i];
            o2[3 * k + i] = centres[3 * c2 + i];
            d1[3 * k + i] = x[i] - centres[3 * c1 + i];
            d2[3 * k + i] = x2[i] - centres[3 * c2 + i];
        }
    }
}

/* angle between two rotations from |A - B|_F = 2 sqrt(2) sin(angle / 2),
 * accurate near zero (acos of the trace is not: ~1e-8 rad of noise) */
static double rot_err(const double *a, const double *b)
{
    double f = 0.0, s;
    int i;
    for (i = 0; i < 9; i++)
        f += (a[i] - b[i]) * (a[i] - b[i]);
    s = sqrt(f) / (2.0 * sqrt(2.0));
    if (s > 1.0)
        s = 1.0;
    return 2.0 * asin(s);
}

static double vdiff(const double *a, const double *b)
{
    double s = 0.0;
    int i;
    for (i = 0; i < 3; i++)
        s += (a[i] - b[i]) * (a[i] - b[i]);
    return sqrt(s);
}

#define N 60

static void run_case(const char *name, int ncam, const double *centres, int cross,
                     int expect_case)
{
    double o1[3 * N], d1[3 * N], o2[3 * N], d2[3 * N], r[9];
    double w[3] = {0.1, -0.2, 0.15}, t[3] = {0.3, -0.1, 0.2};
    mcg_linear17_result res;
    int st;
    mcg_rot_from_angle_axis(w, r);
    make_rays(N, ncam, centres, cross, r, t, o1, d1, o2, d2);
    st = mcg_linear17(N, o1, d1, o2, d2, NULL, &res);
    CHECK(st == MCG_OK, "%s: status %d", name, st);
    CHECK(res.gc_case == expect_case, "%s: detected kind %d (expected %d), rank(A_R) %d",
          name, res.gc_case, expect_case, res.rank_ar);
    CHECK(rot_err(res.R, r) < 1e-9, "%s: rotation error %.3g rad", name, rot_err(res.R, r));
    CHECK(vdiff(res.t, t) < 1e-9 * sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]),
          "%s: translation error %.3g m", name, vdiff(res.t, t));
    CHECK(res.scale_observable == 1, "%s: scale observable", name);
    CHECK(res.n_in_front == N, "%s: %d of %d in front", name, res.n_in_front, N);
}

int main(void)
{
    /* non-axial 4-camera rig, collinear 3-camera rig */
    double general[12] = {0.0, 0.0, 0.0, 0.5, 0.1, 0.0, 0.0, 0.6, 0.2, -0.3, 0.2, 0.7};
    double axial[9] = {-0.4, 0.1, 0.2, 0.1, 0.1, 0.2, 0.6, 0.1, 0.2};
    double o1[3 * N], d1[3 * N], o2[3 * N], d2[3 * N];
    double eye[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, t[3] = {0.5, 0.1, 0.0};
    mcg_linear17_result res;
    mcg_linear17_options opt;
    int st;

    run_case("non-axial, intra-camera", 4, general, 0, MCG_GC_LOCALLY_CENTRAL);
    run_case("non-axial, cross-camera", 4, general, 1, MCG_GC_MOST_GENERAL);
    run_case("axial, cross-camera", 3, axial, 1, MCG_GC_AXIAL);
    run_case("axial, intra-camera", 3, axial, 0, MCG_GC_LOCALLY_CENTRAL_AXIAL);

    /* critical motion: no rotation, intra-camera only -> scale unobservable,
     * direction still right (ch. 7.3.2) */
    make_rays(N, 4, general, 0, eye, t, o1, d1, o2, d2);
    st = mcg_linear17(N, o1, d1, o2, d2, NULL, &res);
    CHECK(st == MCG_OK, "pure translation: status %d", st);
    CHECK(res.scale_observable == 0, "pure translation: scale reported unobservable "
          "(conditioning %.3g)", res.scale_conditioning);
    {
        double u[3] = {t[0] / sqrt(0.26), t[1] / sqrt(0.26), 0.0};
        CHECK(vdiff(res.t, u) < 1e-8, "pure translation: unit direction error %.3g",
              vdiff(res.t, u));
        CHECK(rot_err(res.R, eye) < 1e-9, "pure translation: rotation error %.3g",
              rot_err(res.R, eye));
    }
    /* ... whereas cross-camera rays fix the scale without rotation */
    make_rays(N, 4, general, 1, eye, t, o1, d1, o2, d2);
    st = mcg_linear17(N, o1, d1, o2, d2, NULL, &res);
    CHECK(st == MCG_OK && res.scale_observable == 1 && vdiff(res.t, t) < 1e-9,
          "pure translation, cross-camera: metric t error %.3g", vdiff(res.t, t));

    /* invalid input */
    make_rays(N, 4, general, 0, eye, t, o1, d1, o2, d2);
    CHECK(mcg_linear17(13, o1, d1, o2, d2, NULL, &res) == MCG_EINVAL, "n = 13 rejected");
    CHECK(mcg_linear17(N, NULL, d1, o2, d2, NULL, &res) == MCG_EINVAL, "NULL rejected");
    CHECK(mcg_linear17(N, o1, d1, o2, d2, NULL, NULL) == MCG_EINVAL, "NULL result rejected");
    d1[7] = NAN;
    CHECK(mcg_linear17(N, o1, d1, o2, d2, NULL, &res) == MCG_EINVAL, "NaN rejected");
    d1[7] = 1.0;
    d2[3] = d2[4] = d2[5] = 0.0;
    CHECK(mcg_linear17(N, o1, d1, o2, d2, NULL, &res) == MCG_EINVAL, "zero direction rejected");
    mcg_linear17_default_options(&opt);
    opt.max_iterations = -1;
    make_rays(N, 4, general, 0, eye, t, o1, d1, o2, d2);
    CHECK(mcg_linear17(N, o1, d1, o2, d2, &opt, &res) == MCG_EINVAL, "bad options rejected");
    /* every option is checked */
    {
        struct { const char *what; int field; double value; } bad[] = {
            {"refine = 2", 0, 2}, {"max_iterations = 10001", 1, 10001},
            {"tolerance NaN", 2, NAN}, {"tolerance < 0", 2, -1e-3},
            {"rank_rtol = 0", 3, 0.0}, {"rank_rtol = 1", 3, 1.0},
            {"min_scale_conditioning < 0", 4, -1.0}, {"max_scale_rel_std = 0", 5, 0.0},
            {"max_scale_rel_std NaN", 5, NAN}};
        size_t b;
        for (b = 0; b < sizeof bad / sizeof bad[0]; b++) {
            mcg_linear17_default_options(&opt);
            switch (bad[b].field) {
            case 0: opt.refine = (int)bad[b].value; break;
            case 1: opt.max_iterations = (int)bad[b].value; break;
            case 2: opt.tolerance = bad[b].value; break;
            case 3: opt.rank_rtol = bad[b].value; break;
            case 4: opt.min_scale_conditioning = bad[b].value; break;
            default: opt.max_scale_rel_std = bad[b].value; break;
            }
            CHECK(mcg_linear17(N, o1, d1, o2, d2, &opt, &res) == MCG_EINVAL,
                  "option %s rejected", bad[b].what);
        }
    }
    /* the alternation budget: noisy rays, tolerance 0, at most 2 iterations */
    {
        double rr[9], w[3] = {0.1, -0.2, 0.05};
        int k;
        mcg_rot_from_angle_axis(w, rr);
        make_rays(N, 4, general, 1, rr, t, o1, d1, o2, d2);
        for (k = 0; k < 3 * N; k++)
            d2[k] += 1e-3 * srand1();
        mcg_linear17_default_options(&opt);
        opt.tolerance = 0.0;
        opt.max_iterations = 2;
        st = mcg_linear17(N, o1, d1, o2, d2, &opt, &res);
        CHECK(st == MCG_OK && res.iterations <= 2 && !res.converged,
              "alternation budget 2: status %d, %d iterations, converged %d", st,
              res.iterations, res.converged);
        opt.max_iterations = 0;
        st = mcg_linear17(N, o1, d1, o2, d2, &opt, &res);
        CHECK(st == MCG_OK && res.iterations == 0,
              "alternation budget 0: status %d, %d iterations", st, res.iterations);
    }
    /* zero motion: E = 0, the linear method cannot work -> degenerate, no crash */
    {
        double zero[3] = {0.0, 0.0, 0.0};
        make_rays(N, 4, general, 0, eye, zero, o1, d1, o2, d2);
        st = mcg_linear17(N, o1, d1, o2, d2, NULL, &res);
        CHECK(st == MCG_EDEGENERATE, "zero motion reported degenerate (status %d)", st);
    }
    /* repeated correspondences: 16 distinct pairs among 60 are not enough */
    {
        double rr[9], w[3] = {0.1, -0.2, 0.05};
        int k;
        mcg_rot_from_angle_axis(w, rr);
        make_rays(N, 4, general, 1, rr, t, o1, d1, o2, d2);
        for (k = 16; k < N; k++) {
            memcpy(o1 + 3 * k, o1 + 3 * (k % 16), 3 * sizeof(double));
            memcpy(d1 + 3 * k, d1 + 3 * (k % 16), 3 * sizeof(double));
            memcpy(o2 + 3 * k, o2 + 3 * (k % 16), 3 * sizeof(double));
            memcpy(d2 + 3 * k, d2 + 3 * (k % 16), 3 * sizeof(double));
        }
        st = mcg_linear17(N, o1, d1, o2, d2, NULL, &res);
        CHECK(st == MCG_EDEGENERATE && res.n_distinct == 16,
              "16 distinct of 60: status %d, n_distinct %d", st, res.n_distinct);
        make_rays(N, 4, general, 1, rr, t, o1, d1, o2, d2);
        st = mcg_linear17(N, o1, d1, o2, d2, NULL, &res);
        CHECK(st == MCG_OK && res.n_distinct == 17, "60 distinct: status %d, n_distinct %d "
              "(counted up to 17)", st, res.n_distinct);
    }
    /* the refinement stops at a stationary point of the Sampson error, checked
     * on the independent residuals of mcg_gec_residuals (refine.c) by central
     * differences over R <- exp([w]x) R, t <- t + dt, against the gradient at
     * the linear estimate */
    {
        double rr[9], w[3] = {0.1, -0.2, 0.05}, grad[2], rs[N];
        int k, pass;
        mcg_rot_from_angle_axis(w, rr);
        make_rays(N, 4, general, 0, rr, t, o1, d1, o2, d2);
        for (k = 0; k < 3 * N; k++)
            d2[k] += 2e-3 * srand1();
        for (pass = 0; pass < 2; pass++) {
            double g2 = 0.0;
            int j;
            mcg_linear17_default_options(&opt);
            opt.refine = pass;
            st = mcg_linear17(N, o1, d1, o2, d2, &opt, &res);
            CHECK(st == MCG_OK, "stationarity: status %d", st);
            for (j = 0; j < 6; j++) {
                double f[2];
                int sg;
                for (sg = 0; sg < 2; sg++) {
                    double dw[3] = {0.0, 0.0, 0.0}, dr[9], rn[9], tn[3], h = 1e-6;
                    double step = sg ? -h : h, cost = 0.0;
                    int i;
                    memcpy(tn, res.t_metric, sizeof tn);
                    if (j < 3)
                        dw[j] = step;
                    else
                        tn[j - 3] += step;
                    mcg_rot_from_angle_axis(dw, dr);
                    for (i = 0; i < 9; i++) {
                        int a = i / 3, c = i % 3;
                        rn[i] = dr[3 * a] * res.R[c] + dr[3 * a + 1] * res.R[3 + c] +
                                dr[3 * a + 2] * res.R[6 + c];
                    }
                    mcg_gec_residuals(N, o1, d1, o2, d2, rn, tn, rs);
                    for (i = 0; i < N; i++)
                        cost += rs[i] * rs[i];
                    f[sg] = cost;
                }
                g2 += ((f[0] - f[1]) / 2e-6) * ((f[0] - f[1]) / 2e-6);
            }
            grad[pass] = sqrt(g2);
        }
        CHECK(grad[1] < 1e-4 * grad[0], "stationarity: |gradient| %.3g after the refinement, "
              "%.3g at the linear estimate", grad[1], grad[0]);
    }
    printf("%s: %d failure(s)\n", failures ? "FAILED" : "PASSED", failures);
    return failures ? 1 : 0;
}
