/*
 * test_cone.c -- plain-C checks of csrc/cone.c (L-infinity cone bisection,
 * thesis eq. 9.3): rays through a common point (gamma* = 0 at that point),
 * two skew rays with a closed-form minimax point, three axes with a common
 * apex (smallest enclosing cap), n = 1, parallel axes (infimum at infinity),
 * overlapping collinear rays, an infeasible pair, random instances checked by
 * the certified bracket and by random perturbations of X, and the status
 * codes of invalid arguments. Exit status 0 iff every check passes.
 */
#include "mcgeom.h"

#define TEST_SEED 0xc0ce5eedULL
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#define NMAX 200

static double dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static double vdist(const double *a, const double *b)
{
    double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return sqrt(dot(d, d));
}

/* independent evaluation: max angle at X (acos form, clamped) */
static double max_angle(int n, const double *c, const double *v,
                        const double X[3])
{
    double best = 0.0;
    int i;
    for (i = 0; i < n; ++i) {
        double w[3] = {X[0] - c[3 * i], X[1] - c[3 * i + 1],
                       X[2] - c[3 * i + 2]};
        double nw = sqrt(dot(w, w)), nv = sqrt(dot(v + 3 * i, v + 3 * i));
        double cs, a;
        if (nw == 0.0)
            continue;
        cs = dot(w, v + 3 * i) / (nw * nv);
        cs = cs > 1.0 ? 1.0 : (cs < -1.0 ? -1.0 : cs);
        a = acos(cs);
        if (a > best)
            best = a;
    }
    return best;
}

static void common_point(void)
{
    double c[3 * NMAX], v[3 * NMAX], P[3];
    mcg_cone_result r;
    int trial, i, st, ok_g = 1, ok_x = 1;
    double worst_g = 0.0, worst_x = 0.0;
    for (trial = 0; trial < 50; ++trial) {
        int n = 2 + (int)(urand() * 30);
        randn(P, 3);
        for (i = 0; i < n; ++i) {
            double u[3], d = 0.5 + 3.0 * urand();
            randn(u, 3);
            c[3 * i] = P[0] - d * u[0];
            c[3 * i + 1] = P[1] - d * u[1];
            c[3 * i + 2] = P[2] - d * u[2];
            v[3 * i] = 2.0 * u[0]; /* any length */
            v[3 * i + 1] = 2.0 * u[1];
            v[3 * i + 2] = 2.0 * u[2];
        }
        st = mcg_cone_linf(n, c, v, NULL, &r);
        if (st != MCG_OK)
            ok_g = 0;
        if (r.gamma > worst_g)
            worst_g = r.gamma;
        if (vdist(r.X, P) > worst_x)
            worst_x = vdist(r.X, P);
    }
    ok_g = ok_g && worst_g <= 1e-9;
    ok_x = worst_x <= 1e-7;
    check(ok_g, "rays through one point: gamma* = 0", worst_g, 1e-9);
    check(ok_x, "rays through one point: X = the point", worst_x, 1e-7);
}

static void skew_pair(void)
{
    /* line 1: apex (-1, 0, -e), axis +x; line 2: apex (0, -1, e), axis +y.
     * Symmetric under (x, y, z) -> (y, x, -z): X* = (e^2, e^2, 0),
     * tan gamma* = e / sqrt(1 + e^2). */
    const double es[3] = {0.1, 0.5, 2.0};
    int k;
    for (k = 0; k < 3; ++k) {
        double e = es[k];
        double c[6] = {-1, 0, -e, 0, -1, e}, v[6] = {1, 0, 0, 0, 3, 0};
        double Xs[3] = {e * e, e * e, 0.0}, g = atan(e / sqrt(1 + e * e));
        mcg_cone_result r;
        char what[80];
        int st = mcg_cone_linf(2, c, v, NULL, &r);
        snprintf(what, sizeof what, "skew pair e=%.1f: status", e);
        check_status(st, MCG_OK, what);
        snprintf(what, sizeof what, "skew pair e=%.1f: gamma* closed form", e);
        check(fabs(r.gamma - g) <= 1e-10, what, fabs(r.gamma - g), 1e-10);
        snprintf(what, sizeof what, "skew pair e=%.1f: X closed form", e);
        check(vdist(r.X, Xs) <= 1e-6, what, vdist(r.X, Xs), 1e-6);
        snprintf(what, sizeof what, "skew pair e=%.1f: both active, bracket", e);
        check(r.n_active == 2 && r.converged && r.gamma_lower <= g + 1e-15 &&
                  r.flags == 0,
              what, r.gamma - r.gamma_lower, 1e-10);
    }
}

static void coincident_apexes(void)
{
    /* three axes at angle a from +z, 120 degrees apart, common apex P:
     * the optimum is the ray P + s z, gamma* = a */
    double a = 0.3, P[3] = {1.0, -2.0, 0.5}, c[9], v[9], Xs[3];
    mcg_cone_result r;
    int i, st;
    for (i = 0; i < 3; ++i) {
        double phi = 2.0943951023931953 * i;
        memcpy(c + 3 * i, P, sizeof P);
        v[3 * i] = sin(a) * cos(phi);
        v[3 * i + 1] = sin(a) * sin(phi);
        v[3 * i + 2] = cos(a);
    }
    Xs[0] = P[0]; Xs[1] = P[1]; Xs[2] = P[2] + 1.0;
    st = mcg_cone_linf(3, c, v, NULL, &r);
    check_status(st, MCG_OK, "coincident apexes: status");
    check(fabs(r.gamma - a) <= 1e-9, "coincident apexes: gamma* = cap radius",
          fabs(r.gamma - a), 1e-9);
    check(vdist(r.X, Xs) <= 1e-6, "coincident apexes: X = apex + unit dir",
          vdist(r.X, Xs), 1e-6);
    check((r.flags & MCG_CONE_COINCIDENT_APEXES) &&
              (r.flags & MCG_CONE_NONUNIQUE) && r.n_active == 3,
          "coincident apexes: flags, 3 active", (double)r.flags, 0);
}

static void small_cases(void)
{
    mcg_cone_result r;
    int st;
    {
        double c[3] = {1, 2, 3}, v[3] = {0, 0, 5}, Xs[3] = {1, 2, 4};
        st = mcg_cone_linf(1, c, v, NULL, &r);
        check_status(st, MCG_OK, "n = 1: status");
        check(r.gamma == 0.0 && vdist(r.X, Xs) == 0.0 &&
                  (r.flags & MCG_CONE_NONUNIQUE) && r.n_active == 1,
              "n = 1: X = apex + unit axis, gamma 0, non-unique",
              vdist(r.X, Xs), 0);
    }
    {
        /* two rays meeting at (1, 1, 0) */
        double c[6] = {0, 1, 0, 1, -2, 0}, v[6] = {1, 0, 0, 0, 1, 0};
        double Xs[3] = {1, 1, 0};
        st = mcg_cone_linf(2, c, v, NULL, &r);
        check_status(st, MCG_OK, "n = 2 intersecting: status");
        check(r.gamma <= 1e-10 && vdist(r.X, Xs) <= 1e-7,
              "n = 2 intersecting: gamma 0 at the intersection",
              vdist(r.X, Xs), 1e-7);
    }
    {
        /* parallel axes: the angles tend to 0 far along them */
        double c[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0}, v[9] = {0, 0, 1, 0, 0, 2,
                                                          0, 0, 1};
        st = mcg_cone_linf(3, c, v, NULL, &r);
        check_status(st, MCG_OK, "parallel axes: status");
        check(r.gamma < 1e-5 && (r.flags & MCG_CONE_AT_INFINITY) &&
                  (r.flags & MCG_CONE_NONUNIQUE),
              "parallel axes: gamma ~ 0, flagged at infinity", r.gamma, 1e-5);
    }
    {
        /* overlapping collinear rays: any X on the axis beyond z = 1 */
        double c[6] = {0, 0, 0, 0, 0, 1}, v[6] = {0, 0, 1, 0, 0, 1};
        st = mcg_cone_linf(2, c, v, NULL, &r);
        check_status(st, MCG_OK, "collinear rays: status");
        check(r.gamma <= 1e-10 && r.X[2] >= 1.0 - 1e-9 &&
                  (r.flags & MCG_CONE_NONUNIQUE),
              "collinear rays: gamma 0, non-unique", r.gamma, 1e-10);
    }
    {
        /* rays facing away from each other: no point within pi/2 of both */
        double c[6] = {0, 0, 0, -10, 0, 0}, v[6] = {1, 0, 0, -1, 0, 0};
        st = mcg_cone_linf(2, c, v, NULL, &r);
        check_status(st, MCG_EINFEASIBLE, "rays facing away: infeasible");
        check(r.gamma_lower == 1.5707963267948966, "infeasible: lower = pi/2",
              r.gamma_lower, 0);
    }
    {
        /* the start point is behind a ray, the optimum is not */
        double c[6] = {0, 0, 0, 10, 0.5, 0}, v[6] = {1, 0, 0, 1, 0, 0};
        st = mcg_cone_linf(2, c, v, NULL, &r);
        check_status(st, MCG_OK, "start behind a ray: status");
        check(r.gamma < 1e-4, "start behind a ray: gamma ~ 0 far away",
              r.gamma, 1e-4);
    }
}

static void random_instances(void)
{
    double c[3 * NMAX], v[3 * NMAX];
    mcg_cone_result r;
    int trial, i, k, bad_status = 0;
    double worst_bracket = 0.0, worst_perturb = 0.0, worst_eval = 0.0;
    long steps = 0, iters = 0;
    clock_t t0 = clock();
    for (trial = 0; trial < scaled(300); ++trial) {
        int n = 2 + (int)(urand() * (trial % 3 == 0 ? 150 : 10));
        double P[3], noise = (trial % 2 || n > 20) ? 0.05 : 0.5;
        randn(P, 3);
        for (i = 0; i < n; ++i) {
            double u[3], d = 1.0 + 5.0 * urand();
            randn(u, 3);
            for (k = 0; k < 3; ++k) {
                c[3 * i + k] = P[k] - d * u[k];
                v[3 * i + k] = u[k] + noise * nrand();
            }
        }
        if ((k = mcg_cone_linf(n, c, v, NULL, &r)) != MCG_OK) {
            ++bad_status;
            continue;
        }
        steps += r.newton_steps;
        iters += r.iterations;
        if ((r.gamma - r.gamma_lower) / fmax(r.gamma, 0.01) > worst_bracket)
            worst_bracket = (r.gamma - r.gamma_lower) / fmax(r.gamma, 0.01);
        if (fabs(max_angle(n, c, v, r.X) - r.gamma) > worst_eval)
            worst_eval = fabs(max_angle(n, c, v, r.X) - r.gamma);
        for (k = 0; k < 20; ++k) {
            double Y[3], d[3], f, s = pow(10.0, -1.0 - 5.0 * urand());
            randn(d, 3);
            Y[0] = r.X[0] + s * d[0];
            Y[1] = r.X[1] + s * d[1];
            Y[2] = r.X[2] + s * d[2];
            f = max_angle(n, c, v, Y);
            if (r.gamma - f > worst_perturb)
                worst_perturb = r.gamma - f;
        }
    }
    check_status(bad_status, 0, "random instances: all MCG_OK");
    check(worst_bracket <= 2e-10,
          "random: (gamma - certified lower bound) / gamma", worst_bracket,
          2e-10);
    check(worst_eval <= 1e-12, "random: gamma = max angle at X",
          worst_eval, 1e-12);
    check(worst_perturb <= 1e-10, "random: no perturbation of X is better",
          worst_perturb, 1e-10);
    printf("      random: %.1f bisection steps, %.1f Newton steps per call, "
           "%.1f us per call\n",
           iters / (double)scaled(300), steps / (double)scaled(300),
           1e6 * (double)(clock() - t0) / CLOCKS_PER_SEC / (double)scaled(300));
}

static void bad_arguments(void)
{
    double c[6] = {0, 0, 0, 1, 0, 0}, v[6] = {0, 0, 1, 0, 1, 1};
    double nanv = NAN;
    mcg_cone_result r;
    mcg_cone_options o;
    check_status(mcg_cone_linf(0, c, v, NULL, &r), MCG_EINVAL, "n = 0");
    check_status(mcg_cone_linf((1 << 20) + 1, c, v, NULL, &r), MCG_EINVAL,
                 "n = 2^20 + 1");
    check_status(mcg_cone_linf(2, NULL, v, NULL, &r), MCG_EINVAL, "apex NULL");
    check_status(mcg_cone_linf(2, c, NULL, NULL, &r), MCG_EINVAL, "axis NULL");
    check_status(mcg_cone_linf(2, c, v, NULL, NULL), MCG_EINVAL, "res NULL");
    c[4] = nanv;
    check_status(mcg_cone_linf(2, c, v, NULL, &r), MCG_EINVAL, "NaN apex");
    c[4] = 0.0;
    v[1] = INFINITY;
    check_status(mcg_cone_linf(2, c, v, NULL, &r), MCG_EINVAL, "inf axis");
    v[1] = 0.0;
    v[3] = v[4] = v[5] = 0.0;
    check_status(mcg_cone_linf(2, c, v, NULL, &r), MCG_EINVAL, "zero axis");
    v[4] = 1.0;
    mcg_cone_default_options(&o);
    o.tolerance = 0.0;
    check_status(mcg_cone_linf(2, c, v, &o, &r), MCG_EINVAL, "tolerance 0");
    mcg_cone_default_options(&o);
    o.max_iterations = 0;
    check_status(mcg_cone_linf(2, c, v, &o, &r), MCG_EINVAL, "0 iterations");
    mcg_cone_default_options(&o);
    o.max_radius = NAN;
    check_status(mcg_cone_linf(2, c, v, &o, &r), MCG_EINVAL, "radius NaN");
    mcg_cone_default_options(&o);
    o.max_iterations = 3;
    check_status(mcg_cone_linf(2, c, v, &o, &r), MCG_OK, "3 iterations: OK");
    check(r.iterations <= 3 && !r.converged &&
              (r.flags & MCG_CONE_NOT_CONVERGED),
          "3 iterations: bounded, reported not converged", r.iterations, 3);
}

int main(void)
{
    common_point();
    skew_pair();
    coincident_apexes();
    small_cases();
    random_instances();
    bad_arguments();
    printf("%d checks, %d failed\n", n_checks, n_failed);
    return n_failed ? 1 : 0;
}
