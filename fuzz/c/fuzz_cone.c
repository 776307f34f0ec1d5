/*
 * fuzz_cone.c -- libFuzzer harness of mcg_cone_linf, the L-infinity cone
 * problem of thesis eq. 9.3 (min over X of max_i angle(X - C_i, v_i)) by
 * bisection with an SOCP feasibility test, with decoded options.
 *
 * Inputs: mode 0 rays through a common point (plus noise and replaced
 * entries: the E+SOCP translation problem), mode 1 arbitrary apexes and axes.
 * Invariants: bad n, NaN/inf/huge values, zero axes, bad options give
 * MCG_EINVAL; on MCG_OK X is finite, 0 <= gamma_lower <= gamma <= pi/2,
 * gamma equals max_i angle(X - C_i, v_i) recomputed here (the apex counts
 * as angle 0), the active set is ascending, within [0, n) and not larger
 * than n, iterations and Newton steps within the budgets; when converged,
 * gamma - gamma_lower meets the tolerance (or the flag says why not).
 */
#include "fuzz_input.h"
#include "mcgeom.h"

/* routines selected by the first input byte (fuzz/make_corpus.py writes
 * seeds for each) */
#define FUZZ_MODES 2

#define MAXN 40
#define HALF_PI 1.5707963267948966

static double angle(const double *u0, const double *v0)
{
    /* atan2(|u x v|, u . v): accurate for every angle; 0 when u = 0. Both
     * vectors are first divided by their largest component (the angle does
     * not change): for apexes near 1e-160 the squares of the cross product
     * would be denormals of a few significant bits (a false finding) */
    double u[3], v[3], mu = fmax(fabs(u0[0]), fmax(fabs(u0[1]), fabs(u0[2])));
    double mv = fmax(fabs(v0[0]), fmax(fabs(v0[1]), fabs(v0[2]))), c[3], s, d;
    int i;
    if (mu == 0.0)
        return 0.0;
    for (i = 0; i < 3; ++i) {
        u[i] = u0[i] / mu;
        v[i] = v0[i] / mv;
    }
    c[0] = u[1] * v[2] - u[2] * v[1];
    c[1] = u[2] * v[0] - u[0] * v[2];
    c[2] = u[0] * v[1] - u[1] * v[0];
    s = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    d = u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
    return atan2(s, d);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in = fz_make(data, size);
    int mode = fz_u8(&in) % FUZZ_MODES, valid, st, i, k, use_opt = fz_u8(&in) % 4;
    int n = fz_size(&in, 1, MAXN, &valid);
    double apex[3 * MAXN], axis[3 * MAXN], worst = 0.0, dmin = HUGE_VAL;
    mcg_cone_options opt;
    mcg_cone_result res;
    mcg_cone_default_options(&opt);
    if (use_opt == 1) {
        opt.tolerance = fz_double(&in);
        opt.abs_tolerance = fz_double(&in);
        opt.max_iterations = fz_int(&in, -1, 300);
        opt.max_newton = fz_int(&in, -1, 1000);
        opt.max_radius = fz_double(&in);
        opt.active_tolerance = fz_double(&in);
    } else if (use_opt >= 2) { /* small valid budgets */
        opt.max_iterations = fz_int(&in, 1, 60);
        opt.max_newton = fz_int(&in, 1, 200);
        opt.tolerance = fz_range(&in, 1e-12, 1e-2);
    }
    if (!valid) {
        double dummy[3] = {1, 0, 0};
        st = mcg_cone_linf(n, dummy, dummy, &opt, &res);
        FZ_CHECK(st == MCG_EINVAL, "cone_linf(n = %d) returned %d", n, st);
        return 0;
    }
    if (mode == 0) {
        double X[3], noise = fz_range(&in, 0.0, 0.1);
        for (i = 0; i < 3; ++i)
            X[i] = fz_range(&in, -3.0, 3.0);
        for (k = 0; k < n; ++k)
            for (i = 0; i < 3; ++i) {
                apex[3 * k + i] = fz_range(&in, -1.0, 1.0);
                axis[3 * k + i] = X[i] - apex[3 * k + i] + noise * fz_range(&in, -1.0, 1.0);
            }
        for (k = fz_u8(&in) % 3; k > 0; --k) {
            double *arr = (fz_u8(&in) & 1) ? apex : axis;
            const int at = fz_int(&in, 0, 3 * n - 1); /* decoded before the value */
            arr[at] = fz_double(&in);
        }
    } else {
        fz_matrix(&in, apex, (size_t)n, 3);
        fz_matrix(&in, axis, (size_t)n, 3);
    }
    st = mcg_cone_linf(n, apex, axis, use_opt ? &opt : NULL, &res);
    FZ_CHECK(fz_status_known(st), "cone status %d", st);
    if (!fz_all_finite(apex, 3 * (size_t)n) || !fz_all_finite(axis, 3 * (size_t)n)) {
        FZ_CHECK(st == MCG_EINVAL, "cone_linf of non-finite input: %d", st);
        return 0;
    }
    if (st != MCG_OK)
        return 0;
    FZ_CHECK(fz_all_finite(res.X, 3), "cone: non-finite X");
    /* gamma is the angle at X: below pi/2 once converged (else
     * MCG_EINFEASIBLE), any angle up to pi when a small budget stopped the
     * bisection early */
    FZ_CHECK(res.gamma >= 0.0 && res.gamma <= 2.0 * HALF_PI &&
                 (res.gamma <= HALF_PI || !res.converged) && res.gamma_lower >= 0.0 &&
                 res.gamma_lower <= res.gamma * (1.0 + 1e-9) + 1e-12,
             "cone: gamma %.17g, gamma_lower %.17g", res.gamma, res.gamma_lower);
    for (k = 0; k < n; ++k) {
        double u[3], a;
        for (i = 0; i < 3; ++i)
            u[i] = res.X[i] - apex[3 * k + i];
        a = angle(u, axis + 3 * k);
        if (a > worst)
            worst = a;
        dmin = fmin(dmin, sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]));
    }
    /* with AT_INFINITY X is only a far point and only gamma is meaningful
     * (documented): no equality then */
    /* nor when the apexes are so far from the origin that X = apex + unit
     * offset cannot be represented (|apex| above 1e8: rounding of X beyond
     * the check's tolerance) */
    /* gamma is the angle at the optimum before X is rounded (header): the
     * angle at the returned X may differ by the rounding of X over its
     * distance to the nearest apex (an optimum 1e-9 from an apex at 6.9:
     * 6e-12 against 2.8e-7 at X) */
    if (!(res.flags & MCG_CONE_AT_INFINITY) && fz_maxabs(apex, 3 * (size_t)n) <= 1e8 &&
        dmin > 0.0)
        FZ_CHECK(fabs(worst - res.gamma) <=
                     1e-7 + 1e-7 * res.gamma + 4.0 * DBL_EPSILON * fz_maxabs(res.X, 3) / dmin,
             "cone: gamma %.17g but max angle at X %.17g (flags %d)", res.gamma, worst, res.flags);
    FZ_CHECK(res.n_active >= 0 && res.n_active <= n, "cone: n_active %d of %d", res.n_active, n);
    for (k = 0; k < res.n_active && k < 8; ++k) {
        FZ_CHECK(res.active[k] >= 0 && res.active[k] < n, "cone: active[%d] = %d", k,
                 res.active[k]);
        if (k > 0)
            FZ_CHECK(res.active[k] > res.active[k - 1], "cone: active set not ascending");
    }
    FZ_CHECK(res.iterations >= 0 && res.iterations <= (use_opt ? opt.max_iterations : 200),
             "cone: %d iterations", res.iterations);
    FZ_CHECK(res.converged == 0 || res.converged == 1, "cone: converged %d", res.converged);
    FZ_CHECK(res.flags >= 0 && res.flags <= 15, "cone: flags %d", res.flags);
    if (!res.converged)
        FZ_CHECK(res.flags & MCG_CONE_NOT_CONVERGED, "cone: not converged without the flag");
    return 0;
}
