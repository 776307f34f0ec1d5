/*
 * cone.c -- L-infinity cone bisection (thesis ch. 9, eqs. 9.2-9.3, the
 * algorithm of ch. 9.4): the point X minimising the largest angle between
 * X - C_i and the axis v_i over n cones (apex C_i, axis v_i),
 *     gamma* = min_X max_i angle(X - C_i, v_i),
 * found by bisection on the bound gamma with an exact second-order-cone
 * feasibility test of K(gamma) = intersection_i {X : angle(X - C_i, v_i) <=
 * gamma} at each step.
 *
 * Feasibility test. With w = X - C_i, unit v, P = I - v v^T, c = cos gamma,
 * s = sin gamma, the cone is the second-order cone |c P w| <= s v.w (it
 * contains its apex; for gamma < pi/2 it is convex, at gamma = pi/2 it is the
 * half-space v.w >= 0). Its margin g_i(X) = c |P w| - s v.w = |w| sin(theta_i
 * - gamma) (theta_i the angle) is convex in X. The test solves the 4-variable
 * SOCP  tau*(gamma) = min tau  s.t. |c P_i w_i| <= s v_i.w_i + tau (all i),
 * |X - m| <= R (a search ball, see below)  by a primal log-barrier
 * path-following method: Newton steps on
 *     F_t(X, tau) = t tau - sum_i log((s v.w + tau)^2 - c^2 |P w|^2)
 *                   - log(R^2 - |X - m|^2),
 * a self-concordant barrier of parameter nu = 2 n + 2, damped steps
 * 1 / (1 + lambda) (lambda the Newton decrement, which keeps every iterate
 * strictly inside), t multiplied by 8 whenever lambda <= 0.3. Decisions are
 * certified, not approximated:
 *   - feasible: an iterate with tau < 0 is strictly inside every cone (its
 *     angles are evaluated directly, and they bound gamma* from above);
 *   - infeasible: at a centred iterate (lambda <= 0.3) the barrier theory
 *     bounds tau - tau* <= (nu + 2 (sqrt(nu) + 1) lambda / (1 - lambda)) / t;
 *     when tau minus that bound is > 0, K(gamma) misses the search ball and
 *     gamma is a certified lower bound of gamma* (in the ball).
 * A feasible test is continued until the gap bound is below |tau| / 2, so that
 * the returned point is deep inside K(gamma); its largest angle (usually well
 * below gamma) becomes the new upper bound (a Dinkelbach-type step on top of
 * the bisection). No polyhedral approximation is involved.
 *
 * Coordinates are normalised (X' = (X - m) / L, m the centroid of the apexes,
 * L their RMS distance from it); the search ball has radius
 * opt->max_radius * L about m. Without it the infimum can lie at infinity
 * (parallel axes: the angles tend to 0 far along them); a solution farther
 * than half the radius is flagged MCG_CONE_AT_INFINITY (out there the angles
 * change by ~L/|X|^2 per unit of distance: X is not determined).
 *
 * Active set. For n > 8 the bisection first runs on a subset of the cones
 * (the 4 with the largest angles at the start point): a relaxation, so its
 * certified lower bounds hold for the full problem. If its solution is
 * within the tolerance for every cone, it is the optimum (upper bound =
 * lower bound); else up to 4 most violated cones join and the bisection
 * resumes from the same lower bound. Past 64 cones the full set is used.
 * At the end the point is polished: the tau-minimiser at gamma = the final
 * upper bound, solved to a 1e-9 relative gap, is within O(gamma - gamma*)
 * of the optimum even where the minimum is flat (two active cones touching,
 * where any point of the final sublevel set would only be within
 * O(sqrt(tolerance))).
 *
 * No allocation, no globals: the per-cone quantities are recomputed from the
 * inputs in every pass (O(n) per Newton step; a subset of up to 64 cones is
 * cached on the stack, 3 KB), every loop is bounded by n, the options' caps
 * or a constant.
 */
#include "mcgeom.h"
#include "internal.h"

#include <float.h>
#include <math.h>
#include <string.h>

#define HALF_PI 1.5707963267948966
#define MAX_CONES ((int)1 << 20)
#define AXIS2_MIN 1e-200   /* |v|^2 below: a zero axis */
#define COORD_MAX 1e150    /* |coordinate| above: rejected (overflow) */
#define MU 3.0
#define LAMBDA_CENTRED 0.3 /* Newton decrement of a centred iterate */
#define MAX_BACKTRACK 60
/* Barrier-weight increases per Newton step while the iterate stays centred:
 * the duality-gap bound shrinks by MU each time, so 700 increases take it
 * from any finite start below every decision threshold (3^700 > 1e300); the
 * cap only guarantees termination in floating point. */
#define MAX_CENTRED_UPDATES 700

typedef struct {
    int n;            /* cones of this (sub)problem */
    const int *idx;   /* NULL: cones 0..n-1; else the indices of a subset */
    const double *cache; /* NULL, or n x 6: normalised apex, unit axis */
    const double *apex, *axis;
    double m[3];   /* centroid of the apexes */
    double L;      /* scene size (RMS distance of the apexes from m) */
    double invL;
    double R;      /* search-ball radius, normalised coordinates */
} cone_ctx;

/* normalised apex c and unit axis v of cone i */
static void cone_get(const cone_ctx *k, int q, double c[3], double v[3])
{
    int i = k->idx ? k->idx[q] : q;
    const double *a = k->apex + 3 * i, *d = k->axis + 3 * i;
    double s;
    int j;
    if (k->cache) {
        const double *e = k->cache + 6 * q;
        c[0] = e[0]; c[1] = e[1]; c[2] = e[2];
        v[0] = e[3]; v[1] = e[4]; v[2] = e[5];
        return;
    }
    s = 1.0 / sqrt(dot3(d, d));
    for (j = 0; j < 3; ++j) {
        c[j] = (a[j] - k->m[j]) * k->invL;
        v[j] = d[j] * s;
    }
}

/* angle in [0, pi] between w and the unit axis v (0 for w = 0: a cone
 * contains its apex) */
static double angle_of(const double w[3], const double v[3])
{
    double vw = dot3(v, w);
    double p[3] = {w[0] - vw * v[0], w[1] - vw * v[1], w[2] - vw * v[2]};
    return atan2(sqrt(dot3(p, p)), vw);
}

/* largest angle at the normalised point x; *imax its cone */
static double max_angle(const cone_ctx *k, const double x[3], int *imax)
{
    double best = -1.0, c[3], v[3], w[3];
    int i, ib = 0;
    for (i = 0; i < k->n; ++i) {
        double a;
        cone_get(k, i, c, v);
        w[0] = x[0] - c[0]; w[1] = x[1] - c[1]; w[2] = x[2] - c[2];
        a = angle_of(w, v);
        if (a > best) {
            best = a;
            ib = i;
        }
    }
    if (imax)
        *imax = ib;
    return best;
}

/* largest margin g_i = cg |P w| - sg v.w at x */
static double max_margin(const cone_ctx *k, const double x[3], double cg,
                         double sg)
{
    double best = -HUGE_VAL, c[3], v[3], w[3], p[3];
    int i;
    for (i = 0; i < k->n; ++i) {
        double vw, g;
        cone_get(k, i, c, v);
        w[0] = x[0] - c[0]; w[1] = x[1] - c[1]; w[2] = x[2] - c[2];
        vw = dot3(v, w);
        p[0] = w[0] - vw * v[0]; p[1] = w[1] - vw * v[1];
        p[2] = w[2] - vw * v[2];
        g = cg * sqrt(dot3(p, p)) - sg * vw;
        if (g > best)
            best = g;
    }
    return best;
}

/* Gradient g[4] and Hessian h[16] of the barrier part of F_t at z = (x, tau)
 * (without the t tau term). Returns 0 if z is not strictly inside.
 * Per cone, with a = s v.w + tau, q = a^2 - c^2 |P w|^2 and
 * hv = (a s v - c^2 P w, a): gradient -(2/q) hv, Hessian
 * (4/q^2) hv hv^T - (2/q) [[v v^T - c^2 I, s v], [s v^T, 1]]. */
static int barrier_derivs(const cone_ctx *k, const double z[4], double cg,
                          double sg, double g[4], double h[16])
{
    double c2 = cg * cg, b, r2, buf[6];
    double g0 = 0, g1 = 0, g2 = 0, g3 = 0;
    double h00 = 0, h10 = 0, h11 = 0, h20 = 0, h21 = 0, h22 = 0;
    double h30 = 0, h31 = 0, h32 = 0, h33 = 0, dsum = 0;
    int i;
    for (i = 0; i < k->n; ++i) {
        const double *e;
        double w0, w1, w2, vw, p0, p1, p2, av, q, iq, iq2, a0, a1, a2, a3;
        double v0, v1, v2;
        if (k->cache) {
            e = k->cache + 6 * i;
        } else {
            cone_get(k, i, buf, buf + 3);
            e = buf;
        }
        v0 = e[3]; v1 = e[4]; v2 = e[5];
        w0 = z[0] - e[0]; w1 = z[1] - e[1]; w2 = z[2] - e[2];
        vw = v0 * w0 + v1 * w1 + v2 * w2;
        p0 = w0 - vw * v0; p1 = w1 - vw * v1; p2 = w2 - vw * v2;
        av = sg * vw + z[3];
        q = av * av - c2 * (p0 * p0 + p1 * p1 + p2 * p2);
        if (!(av > 0.0) || !(q > 0.0))
            return 0;
        iq = 2.0 / q;
        iq2 = iq * iq;
        a0 = av * sg * v0 - c2 * p0;
        a1 = av * sg * v1 - c2 * p1;
        a2 = av * sg * v2 - c2 * p2;
        a3 = av;
        g0 -= iq * a0; g1 -= iq * a1; g2 -= iq * a2; g3 -= iq * a3;
        h00 += iq2 * a0 * a0 - iq * v0 * v0;
        h10 += iq2 * a1 * a0 - iq * v1 * v0;
        h11 += iq2 * a1 * a1 - iq * v1 * v1;
        h20 += iq2 * a2 * a0 - iq * v2 * v0;
        h21 += iq2 * a2 * a1 - iq * v2 * v1;
        h22 += iq2 * a2 * a2 - iq * v2 * v2;
        h30 += iq2 * a3 * a0 - iq * sg * v0;
        h31 += iq2 * a3 * a1 - iq * sg * v1;
        h32 += iq2 * a3 * a2 - iq * sg * v2;
        h33 += iq2 * a3 * a3 - iq;
        dsum += iq * c2;
    }
    r2 = dot3(z, z);
    b = k->R * k->R - r2;
    if (!(b > 0.0))
        return 0;
    {
        double ib = 2.0 / b, ib2 = ib * ib;
        g0 += ib * z[0]; g1 += ib * z[1]; g2 += ib * z[2];
        h00 += ib2 * z[0] * z[0] + ib + dsum;
        h10 += ib2 * z[1] * z[0];
        h11 += ib2 * z[1] * z[1] + ib + dsum;
        h20 += ib2 * z[2] * z[0];
        h21 += ib2 * z[2] * z[1];
        h22 += ib2 * z[2] * z[2] + ib + dsum;
    }
    g[0] = g0; g[1] = g1; g[2] = g2; g[3] = g3;
    h[0] = h00; h[1] = h10; h[2] = h20; h[3] = h30;
    h[4] = h10; h[5] = h11; h[6] = h21; h[7] = h31;
    h[8] = h20; h[9] = h21; h[10] = h22; h[11] = h32;
    h[12] = h30; h[13] = h31; h[14] = h32; h[15] = h33;
    return 1;
}

/* Solve h d = rhs (4 x 4, SPD) by LDL^T. Returns 0 on a tiny pivot. */
static int chol4_plain(const double h[16], const double rhs[4], double d[4])
{
    /* LDL^T without square roots; pivots must stay above 1e-13 of the
     * diagonal they come from (else the caller scales and shifts) */
    double l[16], dg[4], y[4];
    int i, j, kk;
    for (j = 0; j < 4; ++j) {
        double s = h[5 * j];
        for (kk = 0; kk < j; ++kk)
            s -= l[4 * j + kk] * l[4 * j + kk] * dg[kk];
        if (!(s > 1e-13 * h[5 * j]) || !isfinite(s))
            return 0;
        dg[j] = s;
        for (i = j + 1; i < 4; ++i) {
            double t = h[4 * i + j];
            for (kk = 0; kk < j; ++kk)
                t -= l[4 * i + kk] * l[4 * j + kk] * dg[kk];
            l[4 * i + j] = t / s;
        }
    }
    for (i = 0; i < 4; ++i) {
        double s = rhs[i];
        for (kk = 0; kk < i; ++kk)
            s -= l[4 * i + kk] * y[kk];
        y[i] = s;
    }
    for (i = 3; i >= 0; --i) {
        double s = y[i] / dg[i];
        for (kk = i + 1; kk < 4; ++kk)
            s -= l[4 * kk + i] * d[kk];
        d[i] = s;
    }
    return 1;
}

/* h d = rhs for a symmetric positive (semi)definite h: Jacobi scaling, then
 * Cholesky with a diagonal shift of 1e-14, 1e-12, ... relative when rounding
 * makes the scaled matrix lose definiteness (ill-conditioned barrier Hessians
 * near the optimum). Returns 0 on failure. */
static int chol4_solve(const double h[16], const double rhs[4], double d[4])
{
    double hs[16], sc[4], rs[4], shift = 0.0;
    int i, j, attempt;
    if (chol4_plain(h, rhs, d)) /* the usual case */
        return 1;
    for (i = 0; i < 4; ++i) {
        if (!(h[5 * i] > 0.0) || !isfinite(h[5 * i]))
            return 0;
        sc[i] = 1.0 / sqrt(h[5 * i]);
        rs[i] = rhs[i] * sc[i];
    }
    for (attempt = 0; attempt < 8; ++attempt) {
        for (i = 0; i < 4; ++i)
            for (j = 0; j < 4; ++j)
                hs[4 * i + j] = h[4 * i + j] * sc[i] * sc[j] +
                                (i == j ? shift : 0.0);
        if (chol4_plain(hs, rs, d)) {
            for (i = 0; i < 4; ++i)
                d[i] *= sc[i];
            return 1;
        }
        shift = shift == 0.0 ? 1e-14 : shift * 100.0;
    }
    return 0;
}

enum { FEAS_NUMERIC = -2, FEAS_NO = -1, FEAS_UNDECIDED = 0, FEAS_YES = 1 };

/* Feasibility test of K(gamma) in the ball. x: start on input (strictly
 * inside the ball), on FEAS_YES a strictly feasible deep point. *steps is
 * incremented by the Newton steps used (at most max_steps). */
static int feasibility(const cone_ctx *k, double gamma, double x[3],
                       double deep, double hint, int max_steps, int *steps)
{
    double cg = cos(gamma), sg = sin(gamma);
    double nu = 2.0 * k->n + 2.0, t, z[4], g[4], h[16], d[4], rhs[4];
    double g0;
    int it, have = 0, a, up;

    if (gamma >= HALF_PI) {
        cg = 0.0;
        sg = 1.0;
    }
    g0 = max_margin(k, x, cg, sg);
    z[0] = x[0]; z[1] = x[1]; z[2] = x[2];
    /* start on the scale of the current margin: near the optimum g0 is
     * small and so is the gap needed for a decision */
    {
        double sc = fmax(fabs(g0), hint * (1.0 + sqrt(dot3(x, x))));
        z[3] = g0 + sc;
        t = nu / sc;
    }
    for (it = 0; it < max_steps; ++it) {
        double lam2, lam, alpha, zn[4];
        int bt;
        if (!have) {
            if (!barrier_derivs(k, z, cg, sg, g, h))
                return FEAS_NUMERIC;
            have = 1;
        }
        for (up = 0;; ++up) { /* t grows by MU until a decision (see below) */
            if (up == MAX_CENTRED_UPDATES || !isfinite(t)) {
                x[0] = z[0]; x[1] = z[1]; x[2] = z[2];
                return z[3] < 0.0 ? FEAS_YES : FEAS_UNDECIDED;
            }
            for (a = 0; a < 4; ++a)
                rhs[a] = -g[a];
            rhs[3] -= t;
            if (!chol4_solve(h, rhs, d)) {
                x[0] = z[0]; x[1] = z[1]; x[2] = z[2];
                return z[3] < 0.0 ? FEAS_YES : FEAS_UNDECIDED;
            }
            lam2 = -(rhs[0] * d[0] + rhs[1] * d[1] + rhs[2] * d[2] +
                     rhs[3] * d[3]);
            lam = sqrt(fabs(lam2));
            if (lam > LAMBDA_CENTRED)
                break;
            {
                double gap = (nu + 2.0 * (sqrt(nu) + 1.0) * lam / (1.0 - lam)) / t;
                if (z[3] - gap > 0.0)
                    return FEAS_NO;
                if (z[3] < 0.0 && gap <= deep * fabs(z[3])) {
                    x[0] = z[0]; x[1] = z[1]; x[2] = z[2];
                    return FEAS_YES;
                }
                if (gap < 1e-15 * (1.0 + fabs(z[3]) + sqrt(dot3(z, z)))) {
                    x[0] = z[0]; x[1] = z[1]; x[2] = z[2];
                    return z[3] < 0.0 ? FEAS_YES : FEAS_UNDECIDED;
                }
            }
            t *= MU; /* h unchanged, only the tau gradient moves */
        }
        ++*steps;
        alpha = lam > LAMBDA_CENTRED ? 1.0 / (1.0 + lam) : 1.0;
        for (bt = 0; bt < MAX_BACKTRACK; ++bt) {
            for (a = 0; a < 4; ++a)
                zn[a] = z[a] + alpha * d[a];
            if (barrier_derivs(k, zn, cg, sg, g, h))
                break;
            alpha *= 0.5;
        }
        if (bt == MAX_BACKTRACK) { /* rounding: keep the last valid point */
            x[0] = z[0]; x[1] = z[1]; x[2] = z[2];
            return z[3] < 0.0 ? FEAS_YES : FEAS_UNDECIDED;
        }
        memcpy(z, zn, sizeof(z));
        /* an iterate with tau < 0 is strictly feasible: keep going for a
         * deep point, but remember it in case the cap is reached */
        if (z[3] < 0.0 && it + 1 == max_steps) {
            x[0] = z[0]; x[1] = z[1]; x[2] = z[2];
            return FEAS_YES;
        }
    }
    return FEAS_UNDECIDED;
}

void mcg_cone_default_options(mcg_cone_options *o)
{
    if (!o)
        return;
    o->tolerance = 1e-10;
    o->abs_tolerance = 1e-12;
    o->max_iterations = 200;
    o->max_newton = 400;
    o->max_radius = 1e6;
    o->active_tolerance = 1e-8;
}

static int options_ok(const mcg_cone_options *o)
{
    return isfinite(o->tolerance) && o->tolerance >= 1e-15 &&
           o->tolerance <= 0.1 && isfinite(o->abs_tolerance) &&
           o->abs_tolerance >= 1e-15 && o->abs_tolerance <= 0.1 &&
           o->max_iterations >= 1 && o->max_iterations <= 10000 &&
           o->max_newton >= 1 && o->max_newton <= 100000 &&
           isfinite(o->max_radius) && o->max_radius >= 1.0 &&
           o->max_radius <= 1e12 && isfinite(o->active_tolerance) &&
           o->active_tolerance >= 0.0 && o->active_tolerance <= 1.0;
}

/* least-squares point closest to all lines (normalised), regularised
 * towards the origin; returns 0 if the system is singular */
static int nearest_point(const cone_ctx *k, double x[3])
{
    double a[16], b[4] = {0, 0, 0, 0}, c[3], v[3], d[4];
    int i, r, s;
    memset(a, 0, sizeof(a));
    for (i = 0; i < k->n; ++i) {
        double vc;
        cone_get(k, i, c, v);
        vc = dot3(v, c);
        for (r = 0; r < 3; ++r) {
            for (s = 0; s < 3; ++s)
                a[4 * r + s] += (r == s ? 1.0 : 0.0) - v[r] * v[s];
            b[r] += c[r] - vc * v[r];
        }
    }
    for (r = 0; r < 3; ++r)
        a[4 * r + r] += 1e-9 * k->n;
    a[15] = 1.0;
    if (!chol4_solve(a, b, d))
        return 0;
    x[0] = d[0]; x[1] = d[1]; x[2] = d[2];
    return 1;
}

/* pull x strictly inside the ball (radius frac * R) */
static void clamp_ball(const cone_ctx *k, double x[3], double frac)
{
    double r = sqrt(dot3(x, x)), lim = frac * k->R;
    if (r > lim) {
        double s = lim / r;
        x[0] *= s; x[1] *= s; x[2] *= s;
    }
}

#define MAX_SUB 64 /* largest working subset before the full set is used */
#define ADD_PER_ROUND 4
#define POLISH_HINT 1e-6

/* fill cache (k->n <= MAX_SUB rows) with the normalised cones of k */
static void fill_cache(cone_ctx *k, double *cache)
{
    int q;
    k->cache = NULL;
    for (q = 0; q < k->n; ++q)
        cone_get(k, q, cache + 6 * q, cache + 6 * q + 3);
    k->cache = cache;
}

/* widest bracket, relative to its upper end, that an undecided feasibility
 * test may close as "at the floating-point limit" */
#define UNDECIDED_BRACKET 1e-6

/* Bisection on gamma for the (sub)problem k, from the bracket [*lo, f_k(x)].
 * x: start on input, the best point of k on output (*fx = f_k(x)).
 * Returns MCG_OK, MCG_EINFEASIBLE (*lo = pi/2) or MCG_ENUMERIC; *conv = 1
 * if the bracket met the tolerance. */
static int solve_sub(const cone_ctx *k, const mcg_cone_options *o, double *lo,
                     double x[3], double *fx, int *iters, int *newton,
                     int *conv)
{
    double ub, fbest, y[3];
    int r;
    fbest = max_angle(k, x, NULL);
    ub = fbest;
    *conv = 0;
    if (!(fbest < HALF_PI) && *iters >= o->max_iterations) {
        /* the budget is spent (by earlier active-set rounds): this test is
         * an iteration too; return unconverged with the bound in hand */
        *fx = fbest;
        return MCG_OK;
    }
    if (!(fbest < HALF_PI)) {
        /* is there any point within pi / 2 of every axis? */
        memcpy(y, x, sizeof(y));
        ++*iters;
        r = feasibility(k, HALF_PI, y, 0.5, 1e-14, o->max_newton, newton);
        if (r == FEAS_YES) {
            double f = max_angle(k, y, NULL);
            ub = fmin(f, HALF_PI);
            fbest = f;
            memcpy(x, y, sizeof(y));
        } else {
            *fx = fbest;
            if (r == FEAS_NUMERIC)
                return MCG_ENUMERIC;
            *lo = HALF_PI; /* certified (or at the precision limit) */
            return MCG_EINFEASIBLE;
        }
    }
    while (*iters < o->max_iterations &&
           ub - *lo > fmax(o->abs_tolerance, o->tolerance * ub)) {
        double mid = 0.5 * (*lo + ub);
        ++*iters;
        memcpy(y, x, sizeof(y));
        clamp_ball(k, y, 0.999);
        r = feasibility(k, mid, y, 0.5, 1e-14, o->max_newton, newton);
        if (r == FEAS_UNDECIDED || r == FEAS_NUMERIC) {
            /* the start on the scale of the margin can be too aggressive
             * (ill-conditioned from the first step): retry from afar */
            memcpy(y, x, sizeof(y));
            clamp_ball(k, y, 0.999);
            r = feasibility(k, mid, y, 0.5, 1.0, o->max_newton, newton);
        }
        if (r == FEAS_YES) {
            double f = max_angle(k, y, NULL);
            ub = fmin(mid, f);
            if (f < fbest) {
                fbest = f;
                memcpy(x, y, sizeof(y));
            }
        } else if (r == FEAS_NO) {
            *lo = mid;
        } else if (r == FEAS_NUMERIC) {
            *fx = fbest;
            return MCG_ENUMERIC;
        } else {
            /* the sign of tau* is below the rounding of the margins: the
             * bracket is at the floating-point limit, as good as it gets --
             * if it is narrow already. In a wide bracket (the first
             * bisection steps; 25 cones, 13 of them identical, undecided at
             * pi / 4 with [0, pi / 2] open: fuzz_cone) the test just could
             * not decide: stop, unconverged, with the best point in hand */
            *conv = ub - *lo <= UNDECIDED_BRACKET * ub + o->abs_tolerance;
            break;
        }
    }
    if (ub - *lo <= fmax(o->abs_tolerance, o->tolerance * ub))
        *conv = 1;
    *fx = fbest;
    return MCG_OK;
}

/* Polish x (f_k(x) = *fx): the tau-minimiser at gamma = f_k(x) is within
 * O(f_k(x) - gamma*) of the optimum also where the sublevel sets shrink
 * slowly (few active cones, a flat minimum: there any point of the final
 * bracket's sublevel set would only be within O(sqrt(tolerance))). The
 * polished point is kept if the full problem kf is no worse there. */
static void polish(const cone_ctx *k, const cone_ctx *kf,
                   const mcg_cone_options *o, double x[3], double *fx,
                   int *newton)
{
    double y[3], fb = *fx;
    int r;
    memcpy(y, x, sizeof(y));
    clamp_ball(k, y, 0.999);
    r = feasibility(k, fmin(max_angle(k, x, NULL), HALF_PI), y, 1e-9,
                    POLISH_HINT, o->max_newton, newton);
    if (r == FEAS_YES || r == FEAS_UNDECIDED) {
        double f = max_angle(kf, y, NULL);
        if (f <= fb + fmax(o->abs_tolerance, o->tolerance * fb)) {
            *fx = f;
            memcpy(x, y, sizeof(y));
        }
    }
}

/* Add to the subset sub (size *ns) up to ADD_PER_ROUND cones of the full
 * problem kf whose angle at x exceeds thr, the largest first. Returns the
 * number added. */
static int add_violators(const cone_ctx *kf, const double x[3], double thr,
                         int *sub, int *ns)
{
    double topa[ADD_PER_ROUND], c[3], v[3], w[3];
    int topi[ADD_PER_ROUND], nt = 0, i, j, q;
    for (i = 0; i < kf->n; ++i) {
        double a;
        int in = 0;
        cone_get(kf, i, c, v);
        w[0] = x[0] - c[0]; w[1] = x[1] - c[1]; w[2] = x[2] - c[2];
        a = angle_of(w, v);
        if (!(a > thr) || (nt == ADD_PER_ROUND && a <= topa[nt - 1]))
            continue;
        for (j = 0; j < *ns && !in; ++j)
            in = sub[j] == i;
        if (in)
            continue;
        if (nt < ADD_PER_ROUND)
            ++nt;
        for (q = nt - 1; q > 0 && topa[q - 1] < a; --q) {
            topa[q] = topa[q - 1];
            topi[q] = topi[q - 1];
        }
        topa[q] = a;
        topi[q] = i;
    }
    for (j = 0; j < nt; ++j)
        sub[(*ns)++] = topi[j];
    return nt;
}

/* The argument checks of mcg_cone_linf (its header comment lists them). */
static int check_inputs(int n, const double *apex, const double *axis,
                        const mcg_cone_options *o)
{
    int i;
    if (!options_ok(o))
        return MCG_EINVAL;
    for (i = 0; i < 3 * n; ++i)
        if (!isfinite(apex[i]) || !isfinite(axis[i]) ||
            fabs(apex[i]) > COORD_MAX || fabs(axis[i]) > COORD_MAX)
            return MCG_EINVAL;
    for (i = 0; i < n; ++i)
        if (!(dot3(axis + 3 * i, axis + 3 * i) > AXIS2_MIN))
            return MCG_EINVAL;
    return MCG_OK;
}

/* The normalised problem: apexes centred on their centroid m and scaled by
 * their RMS distance L from it (X = m + L x), the search ball of radius
 * max_radius. Returns 1 when all apexes coincide (to rounding): a
 * homogeneous problem whose optimum is a ray from the apex, solved in a
 * unit frame. */
static int normalise(cone_ctx *k, int n, const double *apex, const double *axis,
                     double max_radius)
{
    double L2 = 0.0;
    int i, j, coincident = 0;
    k->n = n;
    k->idx = NULL;
    k->cache = NULL;
    k->apex = apex;
    k->axis = axis;
    k->m[0] = k->m[1] = k->m[2] = 0.0;
    for (i = 0; i < n; ++i)
        for (j = 0; j < 3; ++j)
            k->m[j] += apex[3 * i + j];
    for (j = 0; j < 3; ++j)
        k->m[j] /= n;
    for (i = 0; i < n; ++i)
        for (j = 0; j < 3; ++j) {
            double dd = apex[3 * i + j] - k->m[j];
            L2 += dd * dd;
        }
    k->L = sqrt(L2 / n);
    if (!(k->L > 1e-13 * sqrt(dot3(k->m, k->m))) || !(k->L > 1e-300)) {
        coincident = 1;
        k->L = 1.0;
    }
    k->invL = 1.0 / k->L;
    k->R = max_radius;
    return coincident;
}

/* 1 if every axis is parallel (same sense) to the first: then gamma* = 0
 * with overlapping rays is not unique (flagged). */
static int axes_parallel(const cone_ctx *k)
{
    double c0[3], v0[3], c[3], v[3];
    int i;
    cone_get(k, 0, c0, v0);
    for (i = 1; i < k->n; ++i) {
        double cr[3];
        cone_get(k, i, c, v);
        cross3(v0, v, cr);
        if (dot3(cr, cr) > 1e-24 || dot3(v0, v) < 0.0)
            return 0;
    }
    return 1;
}

/* The start of the bisection: the better of the centroid and the
 * least-squares point nearest to the lines (for coincident apexes, the unit
 * mean axis: the common apex is trivially "inside" every cone). Returns its
 * largest angle. */
static double initial_point(const cone_ctx *k, int coincident, double xbest[3])
{
    double x[3], fbest;
    int i;
    x[0] = x[1] = x[2] = 0.0;
    xbest[0] = xbest[1] = xbest[2] = 0.0;
    fbest = max_angle(k, xbest, NULL);
    if (coincident) {
        double s[3] = {0, 0, 0}, c[3], v[3], r;
        for (i = 0; i < k->n; ++i) {
            cone_get(k, i, c, v);
            s[0] += v[0]; s[1] += v[1]; s[2] += v[2];
        }
        r = sqrt(dot3(s, s));
        if (r > 1e-12 * k->n) {
            xbest[0] = s[0] / r; xbest[1] = s[1] / r; xbest[2] = s[2] / r;
        } else {
            cone_get(k, 0, c, v);
            memcpy(xbest, v, 3 * sizeof(double));
        }
        fbest = max_angle(k, xbest, NULL);
    } else if (nearest_point(k, x)) {
        double f;
        clamp_ball(k, x, 0.5);
        f = max_angle(k, x, NULL);
        if (f < fbest) {
            fbest = f;
            memcpy(xbest, x, sizeof(x));
        }
    }
    return fbest;
}

/* The bisection of ch. 9.4 (eq. 9.3) in active-set rounds: solve a subset
 * (a relaxation: its optimum is a certified lower bound of gamma*), stop
 * when its solution satisfies every cone, else add the most violated cones;
 * past MAX_SUB cones the full set is solved. *ks: the last (sub)problem
 * (its subset in sub, its cache in cache); *lo the certified lower bound,
 * *conv whether the last bisection converged. Returns the status. */
static int active_set_rounds(const cone_ctx *k, const mcg_cone_options *o, cone_ctx *ks,
                             int *sub, double *cache, double xbest[3], double *fbest,
                             double *lo, int *conv, mcg_cone_result *res)
{
    double x[3];
    int ns = 0, round, status = MCG_OK;
    *lo = 0.0;
    *ks = *k;
    ks->idx = sub;
    ks->n = 0;
    if (k->n <= 2 * ADD_PER_ROUND)
        *ks = *k; /* small problems: the full set at once */
    else
        ns = 0, add_violators(k, xbest, -1.0, sub, &ns), ks->n = ns;
    for (round = 0; round <= MAX_SUB; ++round) {
        double fs, ff, tol;
        ks->cache = NULL;
        if (ks->n <= MAX_SUB)
            fill_cache(ks, cache);
        memcpy(x, xbest, sizeof(x));
        status = solve_sub(ks, o, lo, x, &fs, &res->iterations,
                           &res->newton_steps, conv);
        if (status != MCG_OK)
            break;
        ff = ks->idx ? max_angle(k, x, NULL) : fs;
        tol = fmax(o->abs_tolerance, o->tolerance * fs);
        if (ff < *fbest || ks->idx == NULL) {
            *fbest = ff;
            memcpy(xbest, x, sizeof(x));
        }
        if (ks->idx == NULL || ff <= fs + tol)
            break;
        if (!*conv)
            break; /* out of iterations */
        if (ns + ADD_PER_ROUND > MAX_SUB) {
            *ks = *k;
            continue;
        }
        add_violators(k, x, fs + tol, sub, &ns);
        ks->n = ns;
    }
    return status;
}

/* The result in world coordinates (X = m + L x), the active cones (angle
 * within the active tolerance of gamma) and the flags. */
static void report_result(const cone_ctx *k, const mcg_cone_options *o, int coincident,
                          int all_parallel, double xbest[3], double fbest, double lo,
                          mcg_cone_result *res)
{
    double thr, c[3], v[3], w[3];
    int i, j;
    if (coincident) {
        double r = sqrt(dot3(xbest, xbest));
        if (r > 0.0)
            for (j = 0; j < 3; ++j)
                xbest[j] /= r;
    }
    for (j = 0; j < 3; ++j)
        res->X[j] = k->m[j] + k->L * xbest[j];
    res->gamma = fbest;
    res->gamma_lower = fmin(lo, fbest);
    thr = fbest - fmax(o->active_tolerance,
                       10.0 * fmax(o->abs_tolerance, o->tolerance * fbest));
    for (i = 0; i < k->n; ++i) {
        cone_get(k, i, c, v);
        w[0] = xbest[0] - c[0]; w[1] = xbest[1] - c[1];
        w[2] = xbest[2] - c[2];
        if (angle_of(w, v) >= thr) {
            if (res->n_active < 8)
                res->active[res->n_active] = i;
            ++res->n_active;
        }
    }
    if (coincident)
        res->flags |= MCG_CONE_COINCIDENT_APEXES | MCG_CONE_NONUNIQUE;
    else if (sqrt(dot3(xbest, xbest)) > 0.5 * k->R)
        res->flags |= MCG_CONE_AT_INFINITY | MCG_CONE_NONUNIQUE;
    if (all_parallel && fbest <= 100.0 * fmax(o->abs_tolerance, 1e-12))
        res->flags |= MCG_CONE_NONUNIQUE;
    if (!res->converged)
        res->flags |= MCG_CONE_NOT_CONVERGED;
}

int mcg_cone_linf(int n, const double *apex, const double *axis,
                  const mcg_cone_options *opt, mcg_cone_result *res)
{
    mcg_cone_options o;
    cone_ctx k, ks;
    double lo, fbest, xbest[3];
    int j, status, coincident, all_parallel, conv = 0;
    int sub[MAX_SUB];
    double cache[6 * MAX_SUB];

    if (!res)
        return MCG_EINVAL;
    memset(res, 0, sizeof(*res));
    if (n < 1 || n > MAX_CONES || !apex || !axis)
        return MCG_EINVAL;
    if (opt)
        o = *opt;
    else
        mcg_cone_default_options(&o);
    status = check_inputs(n, apex, axis, &o);
    if (status != MCG_OK)
        return status;
    coincident = normalise(&k, n, apex, axis, o.max_radius);
    all_parallel = axes_parallel(&k);

    if (n == 1) {
        /* any point of the ray is optimal (gamma* = 0): apex + unit axis */
        double v[3], c[3];
        cone_get(&k, 0, c, v);
        for (j = 0; j < 3; ++j)
            res->X[j] = apex[j] + v[j];
        res->gamma = 0.0;
        res->gamma_lower = 0.0;
        res->n_active = 1;
        res->active[0] = 0;
        res->converged = 1;
        res->flags = MCG_CONE_NONUNIQUE;
        return MCG_OK;
    }

    fbest = initial_point(&k, coincident, xbest);
    status = active_set_rounds(&k, &o, &ks, sub, cache, xbest, &fbest, &lo, &conv, res);
    if (status == MCG_OK && fbest > 0.0)
        polish(&ks, &k, &o, xbest, &fbest, &res->newton_steps);
    res->converged = status == MCG_OK && conv;
    if (status == MCG_ENUMERIC)
        return status;
    report_result(&k, &o, coincident, all_parallel, xbest, fbest, lo, res);
    return status;
}
