/*
 * test_linf_local.c -- plain-C checks of csrc/linf_local.c, the local
 * L-infinity minimisation over (R, t) that polishes the branch and bound's
 * optimum (bnb.c):
 * - the closed-form per-correspondence error equals the smallest half-angle
 *   at which both wedge planes of mcg_wedge_normals (eqs. 10.9-10.12) admit
 *   the baseline, found independently by bisection on the wedge test;
 * - the result is a local minimum: no random perturbation of (R, t), at
 *   1e-5 or 1e-7, lowers the maximum error, and it is never above the start;
 * - the status codes of invalid arguments.
 * Exit status 0 iff every check passes.
 */
#include "mcgeom.h"
#include "../internal.h"

#define TEST_SEED 0x11f10ca1ULL
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define MAXN 64

static double U1[3 * MAXN], A1[3 * MAXN], U2[3 * MAXN], A2[3 * MAXN];
static double W[9 * MAXN];

static void unit(double *x)
{
    double n = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    x[0] /= n;
    x[1] /= n;
    x[2] /= n;
}

/* n correspondences of a random 3-camera rig (centres within 0.5 m) seeing
 * points 2-10 m away, motion (R, t), bearing noise of about `noise` rad */
static void make_problem(int n, const double R[9], const double t[3], double noise)
{
    double centres[9];
    int i, k;
    randn(centres, 9);
    for (k = 0; k < 9; ++k)
        centres[k] *= 0.3;
    for (i = 0; i < n; ++i) {
        const double *c = centres + 3 * (i % 3);
        double X[3], X2[3], e[6];
        randn(X, 3);
        unit(X);
        for (k = 0; k < 3; ++k)
            X[k] = c[k] + (2.0 + 8.0 * urand()) * X[k];
        matmul(3, 3, 1, R, X, X2);
        randn(e, 6);
        for (k = 0; k < 3; ++k) {
            X2[k] += t[k];
            A1[3 * i + k] = c[k];
            A2[3 * i + k] = c[k];
        }
        for (k = 0; k < 3; ++k) {
            U1[3 * i + k] = X[k] - c[k];
            U2[3 * i + k] = X2[k] - c[k];
        }
        unit(U1 + 3 * i);
        unit(U2 + 3 * i);
        for (k = 0; k < 3; ++k) {
            U1[3 * i + k] += noise * e[k];
            U2[3 * i + k] += noise * e[3 + k];
        }
        unit(U1 + 3 * i);
        unit(U2 + 3 * i);
    }
}

/* max error (sine) at (R, t): no steps */
static double max_error(int n, const double R[9], const double t[3])
{
    double Rc[9], tc[3], f = -1.0;
    int steps;
    memcpy(Rc, R, sizeof Rc);
    memcpy(tc, t, sizeof tc);
    mcg_linf_local(n, U1, A1, U2, A2, Rc, tc, 1.0, 1.0, 0, W, &f, &steps);
    return f;
}

/* the smallest eps at which b = t - (a2 - R a1) satisfies both wedge rows
 * of correspondence i, by bisection on mcg_wedge_normals */
static double wedge_error(int i, const double R[9], const double t[3])
{
    double v[3], ra[3], b[3], lo = 0.0, hi = 1.5;
    int k, it;
    matmul(3, 3, 1, R, U1 + 3 * i, v);
    matmul(3, 3, 1, R, A1 + 3 * i, ra);
    for (k = 0; k < 3; ++k)
        b[k] = t[k] - (A2[3 * i + k] - ra[k]);
    for (it = 0; it < 200; ++it) {
        double mid = 0.5 * (lo + hi), n1[3], n2[3];
        int st = mcg_wedge_normals(v, U2 + 3 * i, mid, mid, n1, n2), ok;
        ok = st == MCG_EDEGENERATE ||
             (st == MCG_OK && n1[0] * b[0] + n1[1] * b[1] + n1[2] * b[2] >= 0.0 &&
              n2[0] * b[0] + n2[1] * b[1] + n2[2] * b[2] >= 0.0);
        if (ok)
            hi = mid;
        else
            lo = mid;
    }
    return hi;
}

static void closed_form_matches_wedges(void)
{
    double worst = 0.0;
    int trial, i;
    for (trial = 0; trial < 20; ++trial) {
        double w[3], R[9], t[3];
        randn(w, 3);
        for (i = 0; i < 3; ++i)
            w[i] *= 0.2;
        mcg_rot_from_angle_axis(w, R);
        randn(t, 3);
        make_problem(12, R, t, 2e-3);
        /* errors at a perturbed motion (a few mrad to a few degrees) */
        for (i = 0; i < 3; ++i) {
            w[i] += 0.02 * nrand();
            t[i] += 0.05 * nrand();
        }
        mcg_rot_from_angle_axis(w, R);
        for (i = 0; i < 12; ++i) {
            double f, ref, d;
            memcpy(U1, U1 + 3 * i, 3 * sizeof(double));
            memcpy(A1, A1 + 3 * i, 3 * sizeof(double));
            memcpy(U2, U2 + 3 * i, 3 * sizeof(double));
            memcpy(A2, A2 + 3 * i, 3 * sizeof(double));
            f = asin(max_error(1, R, t));
            ref = wedge_error(0, R, t);
            d = fabs(f - ref);
            if (d > worst)
                worst = d;
        }
    }
    check(worst < 1e-10, "closed-form error = wedge bisection (max |difference|, rad)", worst,
          1e-10);
}

static void local_minimum(void)
{
    int trial, lowered = 0, above_start = 0, k, j;
    double worst = 0.0;
    for (trial = 0; trial < 10; ++trial) {
        double w[3], R[9], t[3], Rs[9], ts[3], f0, f, fmin;
        int n = 20 + 10 * (trial % 3), steps, st;
        randn(w, 3);
        for (k = 0; k < 3; ++k)
            w[k] *= 0.3;
        mcg_rot_from_angle_axis(w, R);
        randn(t, 3);
        make_problem(n, R, t, 1e-3);
        /* start a little off the true motion */
        for (k = 0; k < 3; ++k)
            w[k] += 1e-3 * nrand();
        mcg_rot_from_angle_axis(w, Rs);
        memcpy(ts, t, sizeof ts);
        f0 = max_error(n, Rs, ts);
        st = mcg_linf_local(n, U1, A1, U2, A2, Rs, ts, 1e-3, 1e-13, 500, W, &f, &steps);
        check_status(st, MCG_OK, "local minimisation runs");
        if (f > f0)
            ++above_start;
        fmin = f;
        for (j = 0; j < 400; ++j) {
            double dw[3], Rp[9], Rn[9], tn[3], scale = j % 2 ? 1e-5 : 1e-7, fp;
            randn(dw, 3);
            for (k = 0; k < 3; ++k) {
                dw[k] *= scale;
                tn[k] = ts[k] + scale * nrand();
            }
            mcg_rot_from_angle_axis(dw, Rp);
            matmul(3, 3, 3, Rp, Rs, Rn);
            fp = max_error(n, Rn, tn);
            if (fp < fmin)
                fmin = fp;
        }
        if (f - fmin > 1e-13)
            ++lowered;
        if (f - fmin > worst)
            worst = f - fmin;
    }
    check(above_start == 0, "never above the start", 0, 0);
    check(lowered == 0, "no perturbation of the result lowers the max error (worst gain)",
          worst, 1e-13);
}

static void invalid(void)
{
    double R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, t[3] = {0.1, 0.2, 0.3}, f;
    int steps;
    make_problem(6, R, t, 0.0);
    check_status(mcg_linf_local(0, U1, A1, U2, A2, R, t, 1e-3, 1e-9, 10, W, &f, &steps),
                 MCG_EINVAL, "n = 0");
    check_status(mcg_linf_local(6, NULL, A1, U2, A2, R, t, 1e-3, 1e-9, 10, W, &f, &steps),
                 MCG_EINVAL, "NULL bearings");
    check_status(mcg_linf_local(6, U1, A1, U2, A2, R, t, 1e-3, 1e-9, 10, NULL, &f, &steps),
                 MCG_EINVAL, "NULL workspace");
    check_status(mcg_linf_local(6, U1, A1, U2, A2, R, t, 1e-3, 1e-2, 10, W, &f, &steps),
                 MCG_EINVAL, "delta_min above delta0");
    check_status(mcg_linf_local(6, U1, A1, U2, A2, R, t, NAN, 1e-9, 10, W, &f, &steps),
                 MCG_EINVAL, "NaN trust radius");
    check_status(mcg_linf_local(6, U1, A1, U2, A2, R, t, 1e-3, 1e-9, -1, W, &f, &steps),
                 MCG_EINVAL, "negative step budget");
}

int main(void)
{
    closed_form_matches_wedges();
    local_minimum();
    invalid();
    printf("%d checks, %d failed\n", n_checks, n_failed);
    return n_failed != 0;
}
