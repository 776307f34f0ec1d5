/*
 * test_refine.c -- plain-C checks of csrc/refine.c: the Sampson residual
 * against an independent evaluation with the explicit per-pair essential
 * matrix F = [t + R o1 - o2]x R and tangent projectors, the identity
 * e(Pluecker form of eq. 8.15) = d2^T F d1, the edge cases of the residual,
 * the analytic Jacobian against finite differences (through the information
 * matrix and the Gauss-Newton step), exact recovery from perturbed starts on
 * noise-free data of a 4-camera rig, robust losses with 30 % gross outliers,
 * the weighted Cauchy cost against log1p, fix_scale, the critical-motion
 * evidence, and the status codes of invalid
 * arguments. Timings are printed, not asserted.
 * Exit status 0 iff every check passes.
 */
#include "mcgeom.h"

#define TEST_SEED 0x5eed0f4e11e0ULL
#include "testutil.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#define NMAX 400

/* ---- small helpers */

static void cross(const double a[3], const double b[3], double c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

static double dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static double norm(const double a[3]) { return sqrt(dot(a, a)); }

static void mv(const double r[9], const double x[3], double y[3])
{
    matmul(3, 3, 1, r, x, y);
}

static void skew(const double v[3], double s[9])
{
    s[0] = 0.0;   s[1] = -v[2]; s[2] = v[1];
    s[3] = v[2];  s[4] = 0.0;   s[5] = -v[0];
    s[6] = -v[1]; s[7] = v[0];  s[8] = 0.0;
}

/* angle between rotations from |A - B|_F = 2 sqrt(2) sin(angle / 2) */
static double rot_err(const double *a, const double *b)
{
    double f = 0.0, s;
    int i;
    for (i = 0; i < 9; i++)
        f += (a[i] - b[i]) * (a[i] - b[i]);
    s = sqrt(f) / (2.0 * sqrt(2.0));
    return 2.0 * asin(s > 1.0 ? 1.0 : s);
}

static double vdist(const double *a, const double *b)
{
    double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return norm(d);
}

static void random_rotation(double angle, double r[9])
{
    double w[3];
    randn(w, 3);
    {
        double s = angle / norm(w);
        w[0] *= s; w[1] *= s; w[2] *= s;
    }
    mcg_rot_from_angle_axis(w, r);
}

/* a 4-camera non-axial rig: centres (rig frame, metres) */
static const double CENTRES[12] = {0.0, 0.0, 0.0, 0.5, 0.1, 0.0,
                                   0.0, 0.6, 0.2, -0.3, 0.2, 0.7};

/* n noise-free correspondences of random points seen from camera k % 4 at
 * time 1 and from the same camera (cross = 0) or the next one (cross = 1)
 * at time 2; directions get random lengths (not unit). */
static void make_rays(int n, int cross_cam, const double r[9], const double t[3],
                      double *po1, double *pd1, double *po2, double *pd2)
{
    int k, i;
    for (k = 0; k < n; k++) {
        int c1 = k % 4, c2 = cross_cam ? (k + 1) % 4 : c1;
        double x[3], x2[3], l1 = 0.5 + urand(), l2 = 0.5 + 2.0 * urand();
        randn(x, 3);
        for (i = 0; i < 3; i++)
            x[i] = 4.0 * x[i];
        x[0] += 8.0; /* a cloud 8 m ahead, 4 m spread */
        mv(r, x, x2);
        for (i = 0; i < 3; i++) {
            x2[i] += t[i];
            po1[3 * k + i] = CENTRES[3 * c1 + i];
            po2[3 * k + i] = CENTRES[3 * c2 + i];
            pd1[3 * k + i] = l1 * (x[i] - CENTRES[3 * c1 + i]);
            pd2[3 * k + i] = l2 * (x2[i] - CENTRES[3 * c2 + i]);
        }
    }
}

/* the independent reference: e = d2^T F d1, F = [t + R o1 - o2]x R, and the
 * Sampson error with explicit projectors P(d) = I - d d^T */
static double ref_residual(const double *o1, const double *d1, const double *o2,
                           const double *d2, const double r[9], const double t[3],
                           double *e_out)
{
    double u1[3], u2[3], ro[3], c[3], cx[9], f[9], ft[9], fd1[3], ftd2[3];
    double p1[9], p2[9], g1[3], g2[3], e, den;
    int i, j;
    for (i = 0; i < 3; i++) {
        u1[i] = d1[i] / norm(d1);
        u2[i] = d2[i] / norm(d2);
    }
    mv(r, o1, ro);
    for (i = 0; i < 3; i++)
        c[i] = t[i] + ro[i] - o2[i];
    skew(c, cx);
    matmul(3, 3, 3, cx, r, f);
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) {
            ft[3 * i + j] = f[3 * j + i];
            p1[3 * i + j] = (i == j) - u1[i] * u1[j];
            p2[3 * i + j] = (i == j) - u2[i] * u2[j];
        }
    mv(f, u1, fd1);
    mv(ft, u2, ftd2);
    e = dot(u2, fd1);
    mv(p1, ftd2, g1);
    mv(p2, fd1, g2);
    den = dot(g1, g1) + dot(g2, g2);
    if (e_out)
        *e_out = e;
    return e / sqrt(den);
}

/* e of the Pluecker form of eq. 8.15 with unit directions */
static double pluecker_e(const double *o1, const double *d1, const double *o2,
                         const double *d2, const double r[9], const double t[3])
{
    double u1[3], u2[3], m1[3], m2[3], tx[9], ru1[3], a[3], rm1[3];
    int i;
    for (i = 0; i < 3; i++) {
        u1[i] = d1[i] / norm(d1);
        u2[i] = d2[i] / norm(d2);
    }
    cross(o1, u1, m1);
    cross(o2, u2, m2);
    skew(t, tx);
    mv(r, u1, ru1);
    mv(tx, ru1, a);
    mv(r, m1, rm1);
    return dot(u2, a) + dot(u2, rm1) + dot(m2, ru1);
}

#define HALF_PI_TEST 1.5707963267948966

static double now(void) { return (double)clock() / CLOCKS_PER_SEC; }

static double o1[3 * NMAX], d1[3 * NMAX], o2[3 * NMAX], d2[3 * NMAX];
static double res[NMAX], res2[NMAX];

/* left-perturbed motion: R' = exp([w]x) R, t' = t + dt */
static void perturb(const double r[9], const double t[3], const double w[3],
                    const double dt[3], double rp[9], double tp[3])
{
    double dr[9];
    int i;
    mcg_rot_from_angle_axis(w, dr);
    matmul(3, 3, 3, dr, r, rp);
    for (i = 0; i < 3; i++)
        tp[i] = t[i] + dt[i];
}

/* ---- residuals */

static void test_residuals(void)
{
    double r[9], t[3] = {0.3, -0.2, 0.25}, rp[9], tp[3];
    double w[3] = {0.02, -0.01, 0.03}, dt[3] = {0.05, 0.02, -0.04};
    double maxz = 0.0, maxref = 0.0, maxe = 0.0, maxsw = 0.0, maxlen = 0.0;
    double l1[3 * NMAX], l2[3 * NMAX];
    int k, i, st, n = 200;
    random_rotation(0.3, r);
    make_rays(n, 1, r, t, o1, d1, o2, d2);
    /* noise-free truth: zero residuals */
    st = mcg_gec_residuals(n, o1, d1, o2, d2, r, t, res);
    check_status(st, MCG_OK, "gec_residuals status");
    for (k = 0; k < n; k++)
        maxz = fmax(maxz, fabs(res[k]));
    check(maxz < 1e-14, "residuals vanish at the true motion", maxz, 1e-14);

    /* a wrong motion: the explicit-F reference, and e = d2^T F d1 equals the
     * Pluecker form of eq. 8.15 */
    perturb(r, t, w, dt, rp, tp);
    mcg_gec_residuals(n, o1, d1, o2, d2, rp, tp, res);
    for (k = 0; k < n; k++) {
        double e, ref = ref_residual(o1 + 3 * k, d1 + 3 * k, o2 + 3 * k, d2 + 3 * k,
                                     rp, tp, &e);
        double ep = pluecker_e(o1 + 3 * k, d1 + 3 * k, o2 + 3 * k, d2 + 3 * k, rp, tp);
        maxref = fmax(maxref, fabs(res[k] - ref) / (1e-3 + fabs(ref)));
        maxe = fmax(maxe, fabs(e - ep));
    }
    check(maxref < 1e-12, "residual = explicit F / projector reference (rel)", maxref, 1e-12);
    check(maxe < 1e-14, "d2^T [t + R o1 - o2]x R d1 = Pluecker form (8.15)", maxe, 1e-14);

    /* swapping the frames with the inverse motion gives the same residual:
     * R' = R^T, t' = -R^T t */
    {
        double rt[9], ti[3];
        for (i = 0; i < 3; i++) {
            int j;
            for (j = 0; j < 3; j++)
                rt[3 * i + j] = rp[3 * j + i];
        }
        mv(rt, tp, ti);
        for (i = 0; i < 3; i++)
            ti[i] = -ti[i];
        mcg_gec_residuals(n, o2, d2, o1, d1, rt, ti, res2);
        for (k = 0; k < n; k++)
            maxsw = fmax(maxsw, fabs(res[k] - res2[k]));
        check(maxsw < 1e-14, "swapped frames + inverse motion: same residual", maxsw, 1e-14);
    }
    /* independent of the lengths of the directions */
    for (k = 0; k < 3 * n; k++) {
        l1[k] = d1[k] * 7.5;
        l2[k] = d2[k] * 0.01;
    }
    mcg_gec_residuals(n, o1, l1, o2, l2, rp, tp, res2);
    for (k = 0; k < n; k++)
        maxlen = fmax(maxlen, fabs(res[k] - res2[k]));
    check(maxlen < 1e-14, "residual independent of direction lengths", maxlen, 1e-14);

    /* first order: turning d2 by a small angle a within the tangent plane
     * along the unit gradient direction g of e changes r by a |g| / sqrt(D) */
    {
        double a = 1e-7, worst = 0.0;
        for (k = 0; k < 20; k++) {
            double u1[3], u2[3], fd1[3], c[3], ro[3], g[3], ng, nd, e, e2, rr, rn;
            double u2n[3], ref;
            for (i = 0; i < 3; i++) {
                u1[i] = d1[3 * k + i] / norm(d1 + 3 * k);
                u2[i] = d2[3 * k + i] / norm(d2 + 3 * k);
            }
            /* at the true motion r = 0: the perturbed r is the angular error */
            mv(r, u1, ro);
            {
                double oo[3];
                mv(r, o1 + 3 * k, oo);
                for (i = 0; i < 3; i++)
                    c[i] = t[i] + oo[i] - o2[3 * k + i];
            }
            cross(c, ro, fd1);
            e = dot(u2, fd1);
            for (i = 0; i < 3; i++)
                g[i] = fd1[i] - e * u2[i];
            ng = norm(g);
            for (i = 0; i < 3; i++)
                u2n[i] = cos(a) * u2[i] + sin(a) * g[i] / ng;
            mcg_gec_residuals(1, o1 + 3 * k, u1, o2 + 3 * k, u2n, r, t, &rn);
            /* reference: first-order error a * |P g2| / sqrt(D) with both
             * gradients of the unperturbed pair */
            {
                double ftd2[3], h[3];
                cross(u2, c, h); /* R F^T d2 */
                e2 = dot(ro, h);
                for (i = 0; i < 3; i++)
                    ftd2[i] = h[i] - e2 * ro[i];
                nd = sqrt(ng * ng + dot(ftd2, ftd2));
            }
            rr = a * ng / nd;
            ref = fabs(rn - rr) / rr;
            worst = fmax(worst, ref);
        }
        check(worst < 1e-5, "small bearing rotation: r = first-order angle", worst, 1e-5);
    }

    /* edge cases: a camera that does not move (c = 0: F = 0) has r = 0; e at
     * its stationary maximum (D = 0, e != 0) gives the cap pi/2 */
    {
        double eye[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, z[3] = {0, 0, 0};
        double po[3] = {0.2, 0.1, -0.3}, da[3] = {0.3, -0.5, 0.8}, db[3] = {0.5, 0.4, 0.1};
        double tt[3] = {1.0, 0.0, 0.0}, ua[3] = {0.0, 1.0, 0.0}, ub[3] = {0.0, 0.0, 1.0};
        double r1 = -1.0, r2 = -1.0;
        st = mcg_gec_residuals(1, po, da, po, db, eye, z, &r1);
        check(st == MCG_OK && r1 == 0.0, "F = 0 (centre does not move): r = 0", r1, 0.0);
        /* c = t = x, a = y, d2 = z: e = z.(x cross y) = 1, both gradients 0 */
        st = mcg_gec_residuals(1, z, ua, z, ub, eye, tt, &r2);
        check(st == MCG_OK && r2 == HALF_PI_TEST, "stationary e (D = 0): r = pi/2",
              r2 - HALF_PI_TEST, 0.0);
        tt[0] = -1.0;
        st = mcg_gec_residuals(1, z, ua, z, ub, eye, tt, &r2);
        check(st == MCG_OK && r2 == -HALF_PI_TEST, "... and -pi/2 for e < 0",
              r2 + HALF_PI_TEST, 0.0);
        st = mcg_gec_residuals(0, o1, d1, o2, d2, eye, tt, res);
        check_status(st, MCG_OK, "n = 0 is valid");
    }
}

/* ---- Jacobian against finite differences */

/* central differences of the residual of pair k w.r.t. [dw, dt] */
static void fd_jacobian(int k, const double r[9], const double t[3], double j[6])
{
    int p, i;
    for (p = 0; p < 6; p++) {
        double h = 1e-6, w[3] = {0, 0, 0}, dt[3] = {0, 0, 0}, rp[9], tp[3], fp, fm;
        if (p < 3)
            w[p] = h;
        else
            dt[p - 3] = h;
        perturb(r, t, w, dt, rp, tp);
        mcg_gec_residuals(1, o1 + 3 * k, d1 + 3 * k, o2 + 3 * k, d2 + 3 * k, rp, tp, &fp);
        for (i = 0; i < 3; i++) {
            w[i] = -w[i];
            dt[i] = -dt[i];
        }
        perturb(r, t, w, dt, rp, tp);
        mcg_gec_residuals(1, o1 + 3 * k, d1 + 3 * k, o2 + 3 * k, d2 + 3 * k, rp, tp, &fm);
        j[p] = (fp - fm) / (2.0 * h);
    }
}

static void test_jacobian(void)
{
    double r[9], t[3] = {0.4, 0.1, -0.3}, rp[9], tp[3], wts[NMAX];
    double w[3] = {0.05, 0.03, -0.04}, dt[3] = {0.1, -0.05, 0.08};
    double worst = 0.0;
    mcg_refine_options opt;
    mcg_refine_result rr;
    int k, i, j, n = 40, st;
    random_rotation(0.4, r);
    make_rays(n, 1, r, t, o1, d1, o2, d2);
    perturb(r, t, w, dt, rp, tp); /* evaluate away from the solution */
    mcg_refine_default_options(&opt);
    opt.max_iterations = 0;
    /* the information matrix of a single pair (weights select it) is the
     * outer product J_k^T J_k: compare with the finite-difference one */
    for (k = 0; k < n; k++) {
        double jf[6], rk, scale = 0.0, err = 0.0, rt[9], tt[3];
        for (i = 0; i < n; i++)
            wts[i] = (i == k) ? 1.0 : 0.0;
        memcpy(rt, rp, sizeof rt);
        memcpy(tt, tp, sizeof tt);
        st = mcg_refine_motion(n, o1, d1, o2, d2, wts, &opt, rt, tt, &rr);
        if (st != MCG_OK) {
            check_status(st, MCG_OK, "single-pair information matrix");
            return;
        }
        mcg_gec_residuals(1, o1 + 3 * k, d1 + 3 * k, o2 + 3 * k, d2 + 3 * k, rp, tp, &rk);
        fd_jacobian(k, rp, tp, jf);
        for (i = 0; i < 6; i++)
            for (j = 0; j < 6; j++) {
                scale = fmax(scale, fabs(jf[i] * jf[j]));
                err = fmax(err, fabs(rr.info[6 * i + j] - jf[i] * jf[j]));
            }
        worst = fmax(worst, err / scale);
    }
    check(worst < 1e-7, "J_k^T J_k = finite-difference outer product (rel)", worst, 1e-7);

    /* the sign: one undamped Gauss-Newton step dx = -H^-1 J^T r from a start
     * near the solution gives the gradient 2 J^T r = -2 H dx of sum r^2;
     * compare with finite differences of the cost */
    {
        double w2[3] = {2e-3, -1e-3, 1.5e-3}, dt2[3] = {4e-3, 2e-3, -3e-3};
        double r0[9], t0[3], r1[9], t1[3], h[36], dx[6], dr[9], rt0[9], gfd[6];
        perturb(r, t, w2, dt2, r0, t0);
        memcpy(r1, r0, sizeof r1);
        memcpy(t1, t0, sizeof t1);
        st = mcg_refine_motion(n, o1, d1, o2, d2, NULL, &opt, r1, t1, &rr);
        memcpy(h, rr.info, sizeof h);
        opt.max_iterations = 1;
        opt.initial_lambda = 0.0;
        st |= mcg_refine_motion(n, o1, d1, o2, d2, NULL, &opt, r1, t1, &rr);
        check(st == MCG_OK && rr.final_cost < rr.initial_cost,
              "one Gauss-Newton step lowers the cost", rr.final_cost, rr.initial_cost);
        for (i = 0; i < 3; i++)
            for (j = 0; j < 3; j++)
                rt0[3 * i + j] = r0[3 * j + i];
        matmul(3, 3, 3, r1, rt0, dr);
        mcg_angle_axis_from_rot(dr, dx);
        for (i = 0; i < 3; i++)
            dx[3 + i] = t1[i] - t0[i];
        for (i = 0; i < 6; i++) {
            double hh = 1e-7, wp[3] = {0, 0, 0}, dp[3] = {0, 0, 0}, rp2[9], tp2[3];
            double cp = 0.0, cm = 0.0;
            if (i < 3)
                wp[i] = hh;
            else
                dp[i - 3] = hh;
            perturb(r0, t0, wp, dp, rp2, tp2);
            mcg_gec_residuals(n, o1, d1, o2, d2, rp2, tp2, res);
            for (k = 0; k < n; k++)
                cp += res[k] * res[k];
            for (k = 0; k < 3; k++) {
                wp[k] = -wp[k];
                dp[k] = -dp[k];
            }
            perturb(r0, t0, wp, dp, rp2, tp2);
            mcg_gec_residuals(n, o1, d1, o2, d2, rp2, tp2, res);
            for (k = 0; k < n; k++)
                cm += res[k] * res[k];
            gfd[i] = (cp - cm) / (2.0 * hh);
        }
        {
            double gmax = 0.0, err = 0.0;
            for (i = 0; i < 6; i++) {
                double ga = 0.0;
                for (j = 0; j < 6; j++)
                    ga -= 2.0 * h[6 * i + j] * dx[j];
                gmax = fmax(gmax, fabs(gfd[i]));
                err = fmax(err, fabs(ga - gfd[i]));
            }
            check(err < 1e-5 * gmax, "gradient -2 H dx = finite differences (rel)",
                  err / gmax, 1e-5);
        }
    }
}

/* ---- exact recovery, robust losses, fix_scale */

static void run_recovery(const char *name, int cross_cam, double angle, double tscale)
{
    double r[9], t[3], rs[9], ts[3], w[3], dt[3];
    mcg_refine_result rr;
    char what[128];
    int st, n = 120, i;
    random_rotation(0.3, r);
    randn(t, 3);
    for (i = 0; i < 3; i++)
        t[i] *= 0.5 / norm(t) * 1.0;
    make_rays(n, cross_cam, r, t, o1, d1, o2, d2);
    randn(w, 3);
    randn(dt, 3);
    for (i = 0; i < 3; i++) {
        w[i] *= angle / sqrt(3.0);
        dt[i] *= tscale * norm(t) / sqrt(3.0);
    }
    perturb(r, t, w, dt, rs, ts);
    st = mcg_refine_motion(n, o1, d1, o2, d2, NULL, NULL, rs, ts, &rr);
    snprintf(what, sizeof what, "%s: status", name);
    check_status(st, MCG_OK, what);
    snprintf(what, sizeof what, "%s: rotation error (rad), %d iterations", name, rr.iterations);
    check(rot_err(rs, r) < 1e-10, what, rot_err(rs, r), 1e-10);
    snprintf(what, sizeof what, "%s: translation error (m)", name);
    check(vdist(ts, t) < 1e-10 * norm(t), what, vdist(ts, t), 1e-10 * norm(t));
    snprintf(what, sizeof what, "%s: converged (reason %d), final cost", name, rr.reason);
    check(rr.converged && rr.final_cost < 1e-24, what, rr.final_cost, 1e-24);
    snprintf(what, sizeof what, "%s: scale_rel_std ~ 0 on noise-free data", name);
    check(rr.scale_rel_std < 1e-6, what, rr.scale_rel_std, 1e-6);
    check(rr.n_used == n, "all pairs used", rr.n_used, n);
}

static void add_outliers(int n, double frac, double *dirs)
{
    int k;
    for (k = 0; k < n; k++)
        if (urand() < frac)
            randn(dirs + 3 * k, 3); /* a random direction: a gross outlier */
}

static void test_robust(void)
{
    double r[9], t[3] = {0.3, -0.35, 0.2}, rs[9], ts[3], w[3] = {0.02, -0.015, 0.01};
    double dt[3] = {0.05, -0.03, 0.04};
    static const int losses[3] = {MCG_LOSS_CAUCHY, MCG_LOSS_HUBER, MCG_LOSS_SOFT_L1};
    static const char *names[3] = {"cauchy", "huber", "soft_l1"};
    mcg_refine_options opt;
    mcg_refine_result rr;
    char what[128];
    double err_none, terr_none;
    int n = 300, st, l;
    random_rotation(0.25, r);
    make_rays(n, 1, r, t, o1, d1, o2, d2);
    add_outliers(n, 0.3, d2);
    mcg_refine_default_options(&opt);
    perturb(r, t, w, dt, rs, ts);
    st = mcg_refine_motion(n, o1, d1, o2, d2, NULL, &opt, rs, ts, &rr);
    err_none = rot_err(rs, r);
    terr_none = vdist(ts, t);
    check(st == MCG_OK, "least squares with 30% outliers runs", err_none, 0.0);
    /* Cauchy's influence vanishes for gross outliers: close to the truth;
     * Huber and soft-L1 bound it (each outlier still pulls with ~s): only
     * much better than least squares */
    for (l = 0; l < 3; l++) {
        double tol = losses[l] == MCG_LOSS_CAUCHY ? 2e-4 : 0.3 * err_none;
        opt.loss = losses[l];
        opt.loss_scale = 1e-3;
        opt.max_iterations = 200;
        perturb(r, t, w, dt, rs, ts);
        st = mcg_refine_motion(n, o1, d1, o2, d2, NULL, &opt, rs, ts, &rr);
        snprintf(what, sizeof what, "%s, 30%% outliers: rotation error (rad), %d it",
                 names[l], rr.iterations);
        check(st == MCG_OK && rot_err(rs, r) < tol && rot_err(rs, r) < err_none, what,
              rot_err(rs, r), tol);
        snprintf(what, sizeof what, "%s, 30%% outliers: translation error (m)", names[l]);
        tol = losses[l] == MCG_LOSS_CAUCHY ? 5e-3 * norm(t) : 0.8 * terr_none;
        check(vdist(ts, t) < tol, what, vdist(ts, t), tol);
    }
    printf("      (least squares on the same data: rotation error %.3g rad, "
           "translation error %.3g m)\n", err_none, terr_none);
}

/* The Cauchy cost with unequal weights (refine.c's cauchy_block takes its
 * logarithms from its own vectorisable log there, not from log1p): the
 * initial cost of mcg_refine_motion (max_iterations = 0) against
 * sum w s^2 log1p(r^2 / s^2) from mcg_gec_residuals and libm here, for loss
 * scales that put the residuals of 30 % outliers and of a perturbed motion
 * on both sides of the series cut, and across many octaves of 1 + u (up to
 * u ~ 1e120 at s = 1e-60, where the series of u itself would overflow). */
static void test_cauchy_cost(void)
{
    static const double scales[5] = {1e-60, 1e-6, 1e-3, 3e-2, 1.0};
    double r[9], t[3] = {0.3, -0.35, 0.2}, rs[9], ts[3], w[3] = {0.01, -0.02, 0.015};
    double dt[3] = {0.04, 0.02, -0.03}, res[NMAX], wt[NMAX];
    mcg_refine_options opt;
    mcg_refine_result rr;
    char what[128];
    int n = 300, k, j, st;
    random_rotation(0.25, r);
    make_rays(n, 1, r, t, o1, d1, o2, d2);
    add_outliers(n, 0.3, d2);
    perturb(r, t, w, dt, rs, ts);
    for (k = 0; k < n; k++)
        wt[k] = 0.25 + 2.0 * urand();
    st = mcg_gec_residuals(n, o1, d1, o2, d2, rs, ts, res);
    check(st == MCG_OK, "residuals for the Cauchy cost", 0.0, 0.0);
    for (j = 0; j < 5; j++) {
        double s = scales[j], ref = 0.0, rel;
        double R0[9], t0[3];
        memcpy(R0, rs, sizeof R0);
        memcpy(t0, ts, sizeof t0);
        for (k = 0; k < n; k++)
            ref += wt[k] * s * s * log1p(res[k] * res[k] / (s * s));
        mcg_refine_default_options(&opt);
        opt.loss = MCG_LOSS_CAUCHY;
        opt.loss_scale = s;
        opt.max_iterations = 0;
        st = mcg_refine_motion(n, o1, d1, o2, d2, wt, &opt, R0, t0, &rr);
        rel = fabs(rr.initial_cost - ref) / ref;
        snprintf(what, sizeof what, "weighted Cauchy cost, s = %g: relative error vs log1p", s);
        check(st == MCG_OK && rel < 1e-13, what, rel, 1e-13);
    }
}

static void test_fix_scale(void)
{
    double r[9], t[3] = {0.3, 0.1, -0.2}, rs[9], ts[3], w[3] = {0.01, 0.02, -0.01};
    double dt[3] = {0.04, -0.06, 0.05}, eye[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, n0;
    mcg_refine_options opt;
    mcg_refine_result rr;
    int n = 100, st, i;
    /* a general motion, start with the true |t| but a wrong direction */
    random_rotation(0.3, r);
    make_rays(n, 0, r, t, o1, d1, o2, d2);
    mcg_refine_default_options(&opt);
    opt.fix_scale = 1;
    perturb(r, t, w, dt, rs, ts);
    n0 = norm(ts);
    for (i = 0; i < 3; i++)
        ts[i] *= norm(t) / n0;
    n0 = norm(ts);
    st = mcg_refine_motion(n, o1, d1, o2, d2, NULL, &opt, rs, ts, &rr);
    check(st == MCG_OK && fabs(norm(ts) - n0) < 1e-14 * n0, "fix_scale keeps |t|",
          fabs(norm(ts) - n0), 1e-14 * n0);
    check(rot_err(rs, r) < 1e-10 && vdist(ts, t) < 1e-10, "fix_scale with the true |t|: exact",
          fmax(rot_err(rs, r), vdist(ts, t)), 1e-10);
    /* the wrong |t|: kept, the direction still found */
    perturb(r, t, w, dt, rs, ts);
    n0 = norm(ts);
    for (i = 0; i < 3; i++)
        ts[i] *= 2.0 / n0;
    st = mcg_refine_motion(n, o1, d1, o2, d2, NULL, &opt, rs, ts, &rr);
    check(st == MCG_OK && fabs(norm(ts) - 2.0) < 1e-14, "fix_scale keeps a wrong |t| = 2",
          fabs(norm(ts) - 2.0), 1e-14);

    /* critical motion (thesis ch. 7.3.2): no rotation, intra-camera rays. The
     * residual does not depend on |t|: H is singular along t. */
    make_rays(n, 0, eye, t, o1, d1, o2, d2);
    perturb(eye, t, w, dt, rs, ts);
    st = mcg_refine_motion(n, o1, d1, o2, d2, NULL, &opt, rs, ts, &rr);
    {
        double u[3], ut[3], dirr;
        for (i = 0; i < 3; i++) {
            u[i] = ts[i] / norm(ts);
            ut[i] = t[i] / norm(t);
        }
        dirr = vdist(u, ut);
        check(st == MCG_OK && rot_err(rs, eye) < 1e-10 && dirr < 1e-10,
              "critical motion, fix_scale: R and the direction of t exact",
              fmax(rot_err(rs, eye), dirr), 1e-10);
    }
    check(rr.scale_rel_std == HUGE_VAL, "critical motion: scale_rel_std = HUGE_VAL",
          rr.scale_rel_std, HUGE_VAL);
    check(rr.info_cond < 1e-10, "critical motion: info_cond ~ 0", rr.info_cond, 1e-10);
    /* the same data with cross-camera rays fix the scale */
    make_rays(n, 1, eye, t, o1, d1, o2, d2);
    perturb(eye, t, w, dt, rs, ts);
    st = mcg_refine_motion(n, o1, d1, o2, d2, NULL, NULL, rs, ts, &rr);
    check(st == MCG_OK && vdist(ts, t) < 1e-10 && rr.info_cond > 1e-6,
          "no rotation but cross-camera rays: metric t exact, info_cond > 0",
          vdist(ts, t), 1e-10);
}

/* ---- the translation with R held (mcg_refine_translation) */

/* sum of squared reference residuals at (r, t) */
static double ref_cost(int n, const double r[9], const double t[3])
{
    double c = 0.0, e;
    int k;
    for (k = 0; k < n; k++) {
        double x = ref_residual(o1 + 3 * k, d1 + 3 * k, o2 + 3 * k, d2 + 3 * k, r, t, &e);
        c += x * x;
    }
    return c;
}

/* 3 x 3 inverse by cofactors (0 if singular) */
static int inv3(const double a[9], double b[9])
{
    double det = a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) +
                 a[2] * (a[3] * a[7] - a[4] * a[6]);
    if (!(fabs(det) > 0.0))
        return 0;
    b[0] = (a[4] * a[8] - a[5] * a[7]) / det;
    b[1] = (a[2] * a[7] - a[1] * a[8]) / det;
    b[2] = (a[1] * a[5] - a[2] * a[4]) / det;
    b[3] = (a[5] * a[6] - a[3] * a[8]) / det;
    b[4] = (a[0] * a[8] - a[2] * a[6]) / det;
    b[5] = (a[2] * a[3] - a[0] * a[5]) / det;
    b[6] = (a[3] * a[7] - a[4] * a[6]) / det;
    b[7] = (a[1] * a[6] - a[0] * a[7]) / det;
    b[8] = (a[0] * a[4] - a[1] * a[3]) / det;
    return 1;
}

static void test_translation(void)
{
    double r[9], rk[9], t[3] = {0.4, -0.2, 0.3}, ts[3], tf[3], rf[9], e;
    double jt[3 * NMAX], h[9], hi[9], g[3] = {0, 0, 0}, u[3], var = 0.0, s2 = 0.0, gn = 0.0;
    double jn = 0.0, rn2 = 0.0;
    mcg_refine_options opt;
    mcg_refine_result rr, rfull;
    int n = 200, st, i, j, k;
    /* noise-free, intra-camera rays of a rig that turned: t exact from a
     * start 40 % short (the bias of the linear solution), R not written */
    random_rotation(0.2, r);
    make_rays(n, 0, r, t, o1, d1, o2, d2);
    memcpy(rk, r, sizeof rk);
    for (i = 0; i < 3; i++)
        ts[i] = 0.6 * t[i] + 0.01 * (i + 1);
    st = mcg_refine_translation(n, o1, d1, o2, d2, NULL, NULL, rk, ts, &rr);
    check(st == MCG_OK && vdist(ts, t) < 1e-10 * norm(t),
          "refine_translation: noise-free t exact from a start 40 % short", vdist(ts, t),
          1e-10 * norm(t));
    check(memcmp(rk, r, sizeof rk) == 0, "refine_translation: R not written", 0.0, 0.0);

    /* noisy bearings (1e-3 rad): the result is a stationary point of the
     * cost of the independent reference residual (central differences), and
     * its scale_rel_std is sqrt(sigma2 u^T H_tt^-1 u) / |t| of that
     * reference's finite-difference Jacobian (R known: no Schur complement) */
    for (k = 0; k < n; k++) {
        double nz[3], l = norm(d2 + 3 * k);
        randn(nz, 3);
        for (i = 0; i < 3; i++)
            d2[3 * k + i] += 1e-3 * l * nz[i];
    }
    memcpy(ts, t, sizeof ts);
    st = mcg_refine_translation(n, o1, d1, o2, d2, NULL, NULL, rk, ts, &rr);
    check(st == MCG_OK && rr.converged, "refine_translation: noisy data, converged", st, 0);
    for (k = 0; k < n; k++) {
        double x = ref_residual(o1 + 3 * k, d1 + 3 * k, o2 + 3 * k, d2 + 3 * k, r, ts, &e);
        rn2 += x * x;
        for (i = 0; i < 3; i++) {
            double tp[3], tm[3], hstep = 1e-7;
            memcpy(tp, ts, sizeof tp);
            memcpy(tm, ts, sizeof tm);
            tp[i] += hstep;
            tm[i] -= hstep;
            jt[3 * k + i] = (ref_residual(o1 + 3 * k, d1 + 3 * k, o2 + 3 * k, d2 + 3 * k, r, tp,
                                          &e) -
                             ref_residual(o1 + 3 * k, d1 + 3 * k, o2 + 3 * k, d2 + 3 * k, r, tm,
                                          &e)) / (2.0 * hstep);
            g[i] += jt[3 * k + i] * x;
            jn += jt[3 * k + i] * jt[3 * k + i];
        }
    }
    gn = norm(g);
    check(gn <= 1e-6 * sqrt(jn) * sqrt(rn2),
          "refine_translation: gradient of the reference cost ~ 0", gn,
          1e-6 * sqrt(jn) * sqrt(rn2));
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) {
            h[3 * i + j] = 0.0;
            for (k = 0; k < n; k++)
                h[3 * i + j] += jt[3 * k + i] * jt[3 * k + j];
        }
    s2 = rn2 / (n - 3);
    for (i = 0; i < 3; i++)
        u[i] = ts[i] / norm(ts);
    if (inv3(h, hi))
        for (i = 0; i < 3; i++)
            for (j = 0; j < 3; j++)
                var += u[i] * hi[3 * i + j] * u[j];
    {
        double want = sqrt(s2 * var) / norm(ts);
        check(fabs(rr.scale_rel_std - want) <= 1e-4 * want,
              "refine_translation: scale_rel_std from the reference H_tt (relative difference)",
              fabs(rr.scale_rel_std - want) / want, 1e-4);
        check(fabs(rr.sigma2 - s2) <= 1e-9 * s2,
              "refine_translation: sigma2 with 3 dof (relative difference)",
              fabs(rr.sigma2 - s2) / s2, 1e-9);
    }
    /* a lower cost than any nearby t, and than the start */
    {
        double c0 = ref_cost(n, r, ts), worst = HUGE_VAL;
        for (i = 0; i < 3; i++)
            for (j = -1; j <= 1; j += 2) {
                double tp[3];
                memcpy(tp, ts, sizeof tp);
                tp[i] += j * 1e-4;
                worst = fmin(worst, ref_cost(n, r, tp) - c0);
            }
        check(worst >= 0.0 && c0 <= ref_cost(n, r, t), "refine_translation: a local minimum",
              worst, 0.0);
    }
    /* with R free too, |t| can only be less certain (S <= H_tt) */
    memcpy(rf, r, sizeof rf);
    memcpy(tf, ts, sizeof tf);
    st = mcg_refine_motion(n, o1, d1, o2, d2, NULL, NULL, rf, tf, &rfull);
    check(st == MCG_OK && rfull.scale_rel_std >= rr.scale_rel_std,
          "refine_translation: R known gives a smaller std of |t| than R estimated",
          rr.scale_rel_std, rfull.scale_rel_std);
    /* the arguments */
    memcpy(tf, ts, sizeof tf);
    mcg_refine_default_options(&opt);
    opt.fix_scale = 1;
    check_status(mcg_refine_translation(n, o1, d1, o2, d2, NULL, &opt, rk, tf, &rr),
                 MCG_EINVAL, "refine_translation: fix_scale refused");
    check_status(mcg_refine_translation(n, o1, d1, o2, d2, NULL, NULL, NULL, tf, &rr),
                 MCG_EINVAL, "refine_translation: R NULL");
    rk[0] += 1e-3;
    check_status(mcg_refine_translation(n, o1, d1, o2, d2, NULL, NULL, rk, tf, &rr),
                 MCG_EINVAL, "refine_translation: R not a rotation");
    check(memcmp(tf, ts, sizeof tf) == 0, "refine_translation: t untouched on error", 0.0, 0.0);
    check_status(mcg_refine_translation(5, o1, d1, o2, d2, NULL, NULL, r, tf, &rr), MCG_EINVAL,
                 "refine_translation: n < 6");
}

/* ---- invalid arguments */

static void test_invalid(void)
{
    double r[9], t[3] = {0.3, 0.1, -0.2}, rs[9], ts[3], wts[NMAX], bad[9];
    double eye[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, z[3] = {0, 0, 0};
    mcg_refine_options opt;
    mcg_refine_result rr;
    int n = 30, k;
#define RESET() (memcpy(rs, r, sizeof rs), memcpy(ts, t, sizeof ts))
    random_rotation(0.2, r);
    make_rays(n, 0, r, t, o1, d1, o2, d2);
    RESET();
    check_status(mcg_refine_motion(n, o1, d1, o2, d2, NULL, NULL, rs, ts, NULL), MCG_EINVAL,
                 "refine: NULL result");
    check_status(mcg_refine_motion(n, NULL, d1, o2, d2, NULL, NULL, rs, ts, &rr), MCG_EINVAL,
                 "refine: NULL origins");
    check_status(mcg_refine_motion(5, o1, d1, o2, d2, NULL, NULL, rs, ts, &rr), MCG_EINVAL,
                 "refine: n = 5 < 6");
    check_status(mcg_refine_motion(n, o1, d1, o2, d2, NULL, NULL, NULL, ts, &rr), MCG_EINVAL,
                 "refine: NULL R");
    d1[7] = NAN;
    check_status(mcg_refine_motion(n, o1, d1, o2, d2, NULL, NULL, rs, ts, &rr), MCG_EINVAL,
                 "refine: NaN direction");
    check_status(mcg_gec_residuals(n, o1, d1, o2, d2, r, t, res), MCG_EINVAL,
                 "residuals: NaN direction");
    d1[7] = 1.0;
    o2[4] = INFINITY;
    check_status(mcg_refine_motion(n, o1, d1, o2, d2, NULL, NULL, rs, ts, &rr), MCG_EINVAL,
                 "refine: inf origin");
    check_status(mcg_gec_residuals(n, o1, d1, o2, d2, r, t, res), MCG_EINVAL,
                 "residuals: inf origin");
    o2[4] = 0.1;
    o1[5] = 1e200;
    check_status(mcg_gec_residuals(n, o1, d1, o2, d2, r, t, res), MCG_EINVAL,
                 "residuals: overflowing magnitude");
    make_rays(n, 0, r, t, o1, d1, o2, d2);
    d2[3] = d2[4] = d2[5] = 0.0;
    check_status(mcg_refine_motion(n, o1, d1, o2, d2, NULL, NULL, rs, ts, &rr), MCG_EINVAL,
                 "refine: zero direction");
    check_status(mcg_gec_residuals(n, o1, d1, o2, d2, r, t, res), MCG_EINVAL,
                 "residuals: zero direction");
    make_rays(n, 0, r, t, o1, d1, o2, d2);
    check_status(mcg_gec_residuals(-1, o1, d1, o2, d2, r, t, res), MCG_EINVAL,
                 "residuals: n < 0");
    check_status(mcg_gec_residuals(n, o1, d1, o2, d2, r, t, NULL), MCG_EINVAL,
                 "residuals: NULL output");
    memcpy(bad, r, sizeof bad);
    bad[0] += 0.01;
    check_status(mcg_refine_motion(n, o1, d1, o2, d2, NULL, NULL, bad, ts, &rr), MCG_EINVAL,
                 "refine: R not a rotation");
    for (k = 0; k < 9; k++)
        bad[k] = -r[k];
    check_status(mcg_refine_motion(n, o1, d1, o2, d2, NULL, NULL, bad, ts, &rr), MCG_EINVAL,
                 "refine: det R = -1");
    ts[1] = NAN;
    check_status(mcg_refine_motion(n, o1, d1, o2, d2, NULL, NULL, rs, ts, &rr), MCG_EINVAL,
                 "refine: NaN in t");
    RESET();
    for (k = 0; k < n; k++)
        wts[k] = 1.0;
    wts[3] = -1.0;
    check_status(mcg_refine_motion(n, o1, d1, o2, d2, wts, NULL, rs, ts, &rr), MCG_EINVAL,
                 "refine: negative weight");
    wts[3] = NAN;
    check_status(mcg_refine_motion(n, o1, d1, o2, d2, wts, NULL, rs, ts, &rr), MCG_EINVAL,
                 "refine: NaN weight");
    for (k = 0; k < n; k++)
        wts[k] = 0.0;
    check_status(mcg_refine_motion(n, o1, d1, o2, d2, wts, NULL, rs, ts, &rr), MCG_EDEGENERATE,
                 "refine: all weights zero");
    mcg_refine_default_options(&opt);
    opt.loss = 9;
    check_status(mcg_refine_motion(n, o1, d1, o2, d2, NULL, &opt, rs, ts, &rr), MCG_EINVAL,
                 "refine: unknown loss");
    mcg_refine_default_options(&opt);
    opt.loss_scale = 0.0;
    check_status(mcg_refine_motion(n, o1, d1, o2, d2, NULL, &opt, rs, ts, &rr), MCG_EINVAL,
                 "refine: loss_scale 0");
    mcg_refine_default_options(&opt);
    opt.max_iterations = -1;
    check_status(mcg_refine_motion(n, o1, d1, o2, d2, NULL, &opt, rs, ts, &rr), MCG_EINVAL,
                 "refine: max_iterations -1");
    mcg_refine_default_options(&opt);
    opt.cost_tolerance = NAN;
    check_status(mcg_refine_motion(n, o1, d1, o2, d2, NULL, &opt, rs, ts, &rr), MCG_EINVAL,
                 "refine: NaN tolerance");
    mcg_refine_default_options(&opt);
    opt.fix_scale = 1;
    check_status(mcg_refine_motion(n, o1, d1, o2, d2, NULL, &opt, rs, z, &rr), MCG_EINVAL,
                 "refine: fix_scale with t = 0");
    /* R = I, t = 0 with intra-camera rays: every F = 0, nothing to refine */
    memcpy(rs, eye, sizeof rs);
    memcpy(ts, z, sizeof ts);
    check_status(mcg_refine_motion(n, o1, d1, o2, d2, NULL, NULL, rs, ts, &rr),
                 MCG_EDEGENERATE, "refine: R = I, t = 0, intra-camera: degenerate");
    check(memcmp(rs, eye, sizeof rs) == 0 && memcmp(ts, z, sizeof ts) == 0,
          "refine: R, t untouched on error", 0.0, 0.0);
#undef RESET
}

/* ---- the iteration budget: with zero tolerances the refinement stops at
 * exactly max_iterations trial steps and says so */

static void test_budget(void)
{
    double r[9], t[3] = {0.3, -0.2, 0.25}, rs[9], ts[3], w[3] = {0.05, -0.04, 0.03};
    double dt[3] = {0.05, 0.04, -0.03};
    mcg_refine_options opt;
    mcg_refine_result rr;
    int n = 60, st;
    random_rotation(0.3, r);
    make_rays(n, 1, r, t, o1, d1, o2, d2);
    perturb(r, t, w, dt, rs, ts);
    mcg_refine_default_options(&opt);
    opt.cost_tolerance = opt.step_tolerance = 0.0;
    opt.max_iterations = 2;
    st = mcg_refine_motion(n, o1, d1, o2, d2, NULL, &opt, rs, ts, &rr);
    check_status(st, MCG_OK, "refine budget: status");
    check(rr.iterations == 2 && rr.reason == MCG_REFINE_STOP_MAX_ITERATIONS && !rr.converged,
          "refine budget: stops after max_iterations = 2, reason MAX_ITERATIONS",
          (double)rr.iterations, 2.0);
    check(rr.final_cost < rr.initial_cost, "refine budget: the 2 steps lowered the cost",
          rr.final_cost, rr.initial_cost);
    mcg_refine_default_options(&opt);
    opt.max_iterations = 10001;
    check_status(mcg_refine_motion(n, o1, d1, o2, d2, NULL, &opt, rs, ts, &rr), MCG_EINVAL,
                 "refine: max_iterations 10001 (above the cap)");
}

/* ---- timings (printed, not asserted; best of 5 rounds of CPU time) */

static void timings(void)
{
    double r[9], t[3] = {0.3, -0.2, 0.25}, rs[9], ts[3], w[3] = {0.01, -0.02, 0.015};
    double dt[3] = {0.03, 0.02, -0.02}, best = HUGE_VAL, best10 = HUGE_VAL, sink = 0.0;
    mcg_refine_options opt;
    mcg_refine_result rr;
    int n = 300, reps, k, round, iters = 0;
    random_rotation(0.3, r);
    make_rays(n, 1, r, t, o1, d1, o2, d2);
    for (round = 0; round < 5; round++) {
        double t0 = now();
        reps = scaled(1000);
        for (k = 0; k < reps; k++) {
            mcg_gec_residuals(n, o1, d1, o2, d2, r, t, res);
            sink += res[k % n];
        }
        best = fmin(best, (now() - t0) / ((double)reps * n));
    }
    printf("time  gec_residuals: %.2f ns per correspondence (%d pairs)\n", 1e9 * best, n);
    best = HUGE_VAL;
    mcg_refine_default_options(&opt);
    for (round = 0; round < 5; round++) {
        double t0 = now();
        reps = scaled(100);
        iters = 0;
        for (k = 0; k < reps; k++) {
            perturb(r, t, w, dt, rs, ts);
            mcg_refine_motion(n, o1, d1, o2, d2, NULL, &opt, rs, ts, &rr);
            iters += rr.iterations;
        }
        best = fmin(best, (now() - t0) / reps);
    }
    /* exactly 10 iterations (tolerances 0) */
    opt.cost_tolerance = opt.step_tolerance = 0.0;
    opt.max_iterations = 10;
    for (round = 0; round < 5; round++) {
        double t0 = now();
        reps = scaled(100);
        for (k = 0; k < reps; k++) {
            perturb(r, t, w, dt, rs, ts);
            mcg_refine_motion(n, o1, d1, o2, d2, NULL, &opt, rs, ts, &rr);
        }
        best10 = fmin(best10, (now() - t0) / reps);
    }
    printf("time  refine_motion, %d pairs: %.1f us to convergence (%.1f iterations); "
           "%.1f us for exactly %d iterations\n", n, 1e6 * best, (double)iters / reps,
           1e6 * best10, rr.iterations);
    if (sink != sink)
        printf("(unreachable)\n");
}

int main(void)
{
    test_residuals();
    test_jacobian();
    run_recovery("4-camera rig, intra-camera rays", 0, 0.05, 0.1);
    run_recovery("4-camera rig, cross-camera rays", 1, 0.05, 0.1);
    run_recovery("4-camera rig, far start (0.3 rad, 50% t)", 1, 0.3, 0.5);
    test_robust();
    test_cauchy_cost();
    test_fix_scale();
    test_translation();
    test_invalid();
    test_budget();
    timings();
    printf("%d checks, %d failed\n", n_checks, n_failed);
    return n_failed ? 1 : 0;
}
