/*
 * test_upright4.c -- plain-C checks of csrc/upright4.c (mcg_upright4), the
 * minimal generalized relative pose with a known vertical.
 *
 * Independent references: (1) the true motion of random noise-free
 * configurations (generic rigs with cross-camera rays, 2-camera heads) must
 * be among the solutions to 1e-8; (2) every returned solution satisfies the
 * four generalized epipolar constraints and R g1 = g2; (3) the number of
 * solutions equals the number of sign changes of det M(theta), computed by
 * direct LU of the 4 x 4 matrix of rows [ (R d1 x d2)^T, d2.R m1 + m2.R d1 ]
 * on a fine grid of yaws (no polynomial, no upright frames: the rotations
 * with R g1 = g2 are built by Rodrigues' formula, yaw_rotation()); (4) status codes of
 * invalid and degenerate input. The central 3-point solver of the same file
 * (mcg_upright3_central, internal.h) is checked likewise: the truth among
 * its solutions, every solution on the constraints, and its count against
 * the sign changes of det [R(theta) d1_k x d2_k]_k on a grid of yaws.
 * Exit status 0 iff every check passes.
 */
#include "mcgeom.h"

#define TEST_SEED 0x0b417f4a11ULL
#include "testutil.h"
#include "../so3.h" /* dot3, cross3, mat_vec, mul33 */
#include "../internal.h" /* mcg_upright3_central */

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

static void random_rotation(double R[9], double max_angle)
{
    double w[3], n;
    int i;
    randn(w, 3);
    n = sqrt(dot3(w, w));
    for (i = 0; i < 3; i++)
        w[i] *= max_angle * (2.0 * urand() - 1.0) / n;
    mcg_rot_from_angle_axis(w, R);
}

/* A noise-free problem: 4 correspondences of a rig with ncam cameras
 * (centres random within 0.5 m, or a 2-camera head with baseline 0.3 m),
 * cross-camera pairs when cross != 0, points 2..10 m away. */
static void make_problem(int head, int cross, const double R[9], const double t[3],
                         double o1[12], double d1[12], double o2[12], double d2[12])
{
    double cen[4][3];
    int k, i;
    for (k = 0; k < 4; k++)
        for (i = 0; i < 3; i++)
            cen[k][i] = head ? (i == 0 ? (k & 1 ? 0.15 : -0.15) : 0.0) : 0.5 * nrand();
    for (k = 0; k < 4; k++) {
        int c1 = head ? k & 1 : k, c2 = cross ? (head ? (k + 1) & 1 : (k + 1) % 4) : c1;
        scene_correspondence(cen[c1], cen[c2], R, t, 0.0, o1 + 3 * k, d1 + 3 * k, o2 + 3 * k,
                             d2 + 3 * k);
    }
}

/* generalized epipolar residual of correspondence k (unit directions) */
static double gec(const double R[9], const double t[3], const double *o1, const double *d1,
                  const double *o2, const double *d2)
{
    double a[3], b[3], m1[3], m2[3], Rd[3], Rm[3], x[3], n1 = sqrt(dot3(d1, d1)),
        n2 = sqrt(dot3(d2, d2));
    int i;
    for (i = 0; i < 3; i++) {
        a[i] = d1[i] / n1;
        b[i] = d2[i] / n2;
    }
    cross3(o1, a, m1);
    cross3(o2, b, m2);
    mat_vec(R, a, Rd);
    mat_vec(R, m1, Rm);
    cross3(Rd, b, x);
    return dot3(t, x) + dot3(b, Rm) + dot3(m2, Rd);
}

/* The rotation with R g1 = g2 and yaw theta: Rodrigues' rotation taking g1
 * to g2 (about g1 x g2), preceded by theta about g1. */
static void yaw_rotation(const double g1[3], const double g2[3], double th, double R[9])
{
    double w[3], A[9], B[9], s, c;
    int i, j, k;
    cross3(g1, g2, w);
    s = sqrt(dot3(w, w));
    c = dot3(g1, g2);
    for (i = 0; i < 3; i++)
        w[i] = s > 0 ? w[i] / s * atan2(s, c) : 0.0;
    mcg_rot_from_angle_axis(w, A);
    for (i = 0; i < 3; i++)
        w[i] = th * g1[i];
    mcg_rot_from_angle_axis(w, B);
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) {
            R[3 * i + j] = 0.0;
            for (k = 0; k < 3; k++)
                R[3 * i + j] += A[3 * i + k] * B[3 * k + j];
        }
}

static double det4(double M[16])
{
    double d = 1.0;
    int i, j, k;
    for (k = 0; k < 4; k++) {
        int p = k;
        for (i = k + 1; i < 4; i++)
            if (fabs(M[4 * i + k]) > fabs(M[4 * p + k]))
                p = i;
        if (M[4 * p + k] == 0.0)
            return 0.0;
        if (p != k) {
            for (j = 0; j < 4; j++) {
                double s = M[4 * k + j];
                M[4 * k + j] = M[4 * p + j];
                M[4 * p + j] = s;
            }
            d = -d;
        }
        d *= M[4 * k + k];
        for (i = k + 1; i < 4; i++) {
            double f = M[4 * i + k] / M[4 * k + k];
            for (j = k; j < 4; j++)
                M[4 * i + j] -= f * M[4 * k + j];
        }
    }
    return d;
}

static double det_at(const double g1[3], const double g2[3], double th, const double *o1,
                     const double *d1, const double *o2, const double *d2)
{
    double R[9], M[16], z[3] = {0, 0, 0};
    int k;
    yaw_rotation(g1, g2, th, R);
    for (k = 0; k < 4; k++) {
        double a[3], Ra[3], x[3], n = sqrt(dot3(d1 + 3 * k, d1 + 3 * k)),
                                  nb = sqrt(dot3(d2 + 3 * k, d2 + 3 * k)), b[3];
        int i;
        for (i = 0; i < 3; i++) {
            a[i] = d1[3 * k + i] / n;
            b[i] = d2[3 * k + i] / nb;
        }
        mat_vec(R, a, Ra);
        cross3(Ra, b, x);
        memcpy(M + 4 * k, x, sizeof x);
        M[4 * k + 3] = gec(R, z, o1 + 3 * k, d1 + 3 * k, o2 + 3 * k, d2 + 3 * k);
    }
    return det4(M);
}

static void test_random(int head, int cross, int trials, const char *label)
{
    int trial, found = 0, count_ok = 0, counted = 0;
    double worst_gec = 0.0, worst_g = 0.0;
    char what[128];
    for (trial = 0; trial < trials; trial++) {
        double R[9], t[3], o1[12], d1[12], o2[12], d2[12], g1[3], g2[3], Rs[72], ts[24];
        int n = -1, st, s, k, i, hit = 0;
        random_rotation(R, 3.14159);
        randn(t, 3);
        randn(g1, 3);
        mat_vec(R, g1, g2);
        make_problem(head, cross, R, t, o1, d1, o2, d2);
        st = mcg_upright4(o1, d1, o2, d2, g1, g2, Rs, ts, &n);
        if (st != MCG_OK) {
            check_status(st, MCG_OK, label);
            continue;
        }
        for (s = 0; s < n; s++) {
            double e = 0.0, Rg[3], gn = sqrt(dot3(g1, g1)), g2n = sqrt(dot3(g2, g2));
            for (i = 0; i < 9; i++)
                e = fmax(e, fabs(Rs[9 * s + i] - R[i]));
            for (i = 0; i < 3; i++)
                e = fmax(e, fabs(ts[3 * s + i] - t[i]) / sqrt(dot3(t, t)));
            hit |= e < 1e-8;
            for (k = 0; k < 4; k++)
                worst_gec = fmax(worst_gec, fabs(gec(Rs + 9 * s, ts + 3 * s, o1 + 3 * k,
                                                     d1 + 3 * k, o2 + 3 * k, d2 + 3 * k)) /
                                                (1.0 + sqrt(dot3(ts + 3 * s, ts + 3 * s))));
            mat_vec(Rs + 9 * s, g1, Rg);
            for (i = 0; i < 3; i++)
                worst_g = fmax(worst_g, fabs(Rg[i] / gn - g2[i] / g2n));
        }
        found += hit;
        if (trial < trials / 20) { /* the sign changes of det M(theta) on a grid */
            double g1u[3], g2u[3], prev, th;
            int changes = 0, j;
            for (i = 0; i < 3; i++) {
                g1u[i] = g1[i] / sqrt(dot3(g1, g1));
                g2u[i] = g2[i] / sqrt(dot3(g2, g2));
            }
            prev = det_at(g1u, g2u, -3.14159265358979, o1, d1, o2, d2);
            for (j = 1; j <= 4000; j++) {
                double cur;
                th = -3.14159265358979 + 6.28318530717958 * j / 4000.0;
                cur = det_at(g1u, g2u, th, o1, d1, o2, d2);
                changes += (cur < 0.0) != (prev < 0.0);
                prev = cur;
            }
            count_ok += changes == n;
            counted++;
        }
    }
    snprintf(what, sizeof what, "%s: true motion among the solutions (fraction)", label);
    check(found >= 0.995 * trials, what, (double)found / trials, 0.995);
    snprintf(what, sizeof what, "%s: every solution satisfies the 4 constraints", label);
    check(worst_gec < 1e-9, what, worst_gec, 1e-9);
    snprintf(what, sizeof what, "%s: every solution maps g1 to g2", label);
    check(worst_g < 1e-12, what, worst_g, 1e-12);
    snprintf(what, sizeof what, "%s: solution count = sign changes of det M(yaw)", label);
    /* the grid reference misses a pair of roots closer than its step: at
     * most 2 % of the configurations, and at least one is allowed (the
     * reduced MCG_TEST_SCALE runs check ~45: one miss is 2.2 %) */
    {
        int allowed = counted / 50 > 1 ? counted / 50 : 1;
        check(counted - count_ok <= allowed, what, (double)(counted - count_ok),
              (double)allowed);
    }
}

static void test_status(void)
{
    double o[12] = {0}, d[12], g[3] = {0, 0, 1}, R[72], t[24], zero[3] = {0, 0, 0};
    int n, i, st;
    for (i = 0; i < 12; i++)
        d[i] = (i % 3 == 2) ? 1.0 : 0.1 * (i % 5);
    check_status(mcg_upright4(NULL, d, o, d, g, g, R, t, &n), MCG_EINVAL, "NULL o1");
    check_status(mcg_upright4(o, d, o, d, g, g, R, t, NULL), MCG_EINVAL, "NULL n_solutions");
    check_status(mcg_upright4(o, d, o, d, zero, g, R, t, &n), MCG_EINVAL, "zero gravity g1");
    {
        double dn[12];
        memcpy(dn, d, sizeof d);
        dn[4] = NAN;
        check_status(mcg_upright4(o, dn, o, d, g, g, R, t, &n), MCG_EINVAL, "NaN in d1");
        dn[4] = 0.0;
        dn[3] = dn[5] = 0.0;
        check_status(mcg_upright4(o, dn, o, d, g, g, R, t, &n), MCG_EINVAL,
                     "zero-length direction");
    }
    /* every ray from one centre: no metric scale, det M = 0 for every yaw */
    st = mcg_upright4(o, d, o, d, g, g, R, t, &n);
    check_status(st, MCG_EDEGENERATE, "central rays (one centre)");
}

/* A yaw within 1e-4 rad of pi: the tangent half-angle q ~ 2e4 is a root far
 * out on the line, which the root search must still bracket (its interval
 * grows until the Sturm counts at its ends are those of the infinities). */
static void test_near_pi(int trials)
{
    int trial, found = 0;
    for (trial = 0; trial < trials; trial++) {
        double g1[3], w[3], R[9], t[3], g2[3], o1[12], d1[12], o2[12], d2[12], Rs[72], ts[24];
        double n, th = 3.14159265358979323846 - 1e-4 * (trial & 1 ? 1.0 : -1.0);
        int ns = 0, s, i, hit = 0;
        randn(g1, 3);
        n = sqrt(dot3(g1, g1));
        for (i = 0; i < 3; i++)
            w[i] = th * g1[i] / n;
        mcg_rot_from_angle_axis(w, R);
        randn(t, 3);
        mat_vec(R, g1, g2);
        make_problem(0, 1, R, t, o1, d1, o2, d2);
        if (mcg_upright4(o1, d1, o2, d2, g1, g2, Rs, ts, &ns) != MCG_OK)
            continue;
        for (s = 0; s < ns; s++) {
            double e = 0.0;
            for (i = 0; i < 9; i++)
                e = fmax(e, fabs(Rs[9 * s + i] - R[i]));
            for (i = 0; i < 3; i++)
                e = fmax(e, fabs(ts[3 * s + i] - t[i]) / sqrt(dot3(t, t)));
            hit |= e < 1e-8;
        }
        found += hit;
    }
    check(found >= 0.995 * trials, "yaw pi -+ 1e-4: true motion among the solutions (fraction)",
          (double)found / trials, 0.995);
}

/* Regression (peer_solvers' "yaw pi - 1e-4" family, configuration 909 of
 * seed 0): det M(q) vanishes exactly at q = 0, where the Sturm bisection
 * first splits [-b, b]; the interval right of 0 then had a(lo) = 0 and its
 * root q ~ 2e4 (the true yaw) was dropped. Rays o1, d1, o2, d2 (4 x 3 each),
 * g1, g2, then the true R (row-major) and t. */
static void test_root_at_split(void)
{
    static const double in[54] = {
        -0.5110880441117254, 0.5327115479123791, 0.3542436482673757,
        -0.5110880441117254, 0.5327115479123791, 0.3542436482673757,
        -0.0986656164275362, -0.7895651974496248, 0.28267733313964577,
        0.22034900969536955, 0.5008207053836949, -0.1176003236888507,
        -0.5087165733345616, 1.4701719586684314, -2.254218443518719,
        -0.7470234640637683, -2.3478553765726877, -2.4775896764081087,
        -1.0870644722768357, -1.301579532122271, -1.3966322694460256,
        -0.5600818741669044, 2.774133198674577, -4.205628710389344,
        -0.5110880441117254, 0.5327115479123791, 0.3542436482673757,
        -0.5110880441117254, 0.5327115479123791, 0.3542436482673757,
        -0.0986656164275362, -0.7895651974496248, 0.28267733313964577,
        0.22034900969536955, 0.5008207053836949, -0.1176003236888507,
        -0.8444592683170427, -0.007999849100603584, -0.84718064906168,
        1.2601209627780492, 0.6779189929911161, 2.2808019288065595,
        1.450505744419153, 1.1427762560542791, 2.3940964504983175,
        -3.931149545445875, 1.563880923856845, -0.5598226102697386,
        0.40030227696886406, -0.6719046465969774, 0.6231390157380085,
        0.40030227696886406, -0.6719046465969774, 0.6231390157380085,
    };
    static const double truth[12] = {
        -0.6795161699082954, -0.5379922324341052, 0.4988207420243554,
        -0.5378676046311649, -0.0970882890200615, -0.8374200284346501,
        0.4989551229534513, -0.8373399679793895, -0.22339553107164356,
        -0.023238433924956822, -1.420428582269927, 1.2685482703510171,
    };
    double Rs[72], ts[24], e_best = INFINITY;
    int n = 0, s, i, st;
    st = mcg_upright4(in, in + 12, in + 24, in + 36, in + 48, in + 51, Rs, ts, &n);
    check_status(st, MCG_OK, "root at the first split: status");
    for (s = 0; s < n; s++) {
        double e = 0.0;
        for (i = 0; i < 9; i++)
            e = fmax(e, fabs(Rs[9 * s + i] - truth[i]));
        for (i = 0; i < 3; i++)
            e = fmax(e, fabs(ts[3 * s + i] - truth[9 + i]) / sqrt(dot3(truth + 9, truth + 9)));
        e_best = fmin(e_best, e);
    }
    check(e_best < 1e-8, "root at the first split: true motion among the solutions", e_best,
          1e-8);
}

/* Time per call on generic 4-camera problems with cross-camera rays
 * (printed, not asserted: the machine may be shared; issue 21 targets
 * <= 3 us, PoseLib's gen_relpose_upright_4pt 1.2 us). CPU time of the whole
 * batch, as test_essential5.c. */
static void timing(void)
{
    enum { NP = 200 };
    static double o1[NP][12], d1[NP][12], o2[NP][12], d2[NP][12], g1[NP][3], g2[NP][3];
    double R[9], t[3], Rs[72], ts[24], t0, el;
    int reps = scaled(50), r, p, n, total = 0;
    for (p = 0; p < NP; p++) {
        random_rotation(R, 3.14159);
        randn(t, 3);
        randn(g1[p], 3);
        mat_vec(R, g1[p], g2[p]);
        make_problem(0, 1, R, t, o1[p], d1[p], o2[p], d2[p]);
    }
    t0 = (double)clock();
    for (r = 0; r < reps; r++)
        for (p = 0; p < NP; p++) {
            mcg_upright4(o1[p], d1[p], o2[p], d2[p], g1[p], g2[p], Rs, ts, &n);
            total += n;
        }
    el = ((double)clock() - t0) / CLOCKS_PER_SEC;
    printf("info  mcg_upright4: %.2f us per call (%d calls, %.2f real solutions per call)\n",
           1e6 * el / (reps * NP), reps * NP, (double)total / (reps * NP));
}

/* det [R(theta) a_k x b_k]_k of the central problem (unit bearings) */
static double det3_at(const double g1[3], const double g2[3], double th, const double *a,
                      const double *b)
{
    double R[9], M[9], Ra[3];
    int k;
    yaw_rotation(g1, g2, th, R);
    for (k = 0; k < 3; k++) {
        mat_vec(R, a + 3 * k, Ra);
        cross3(Ra, b + 3 * k, M + 3 * k);
    }
    return M[0] * (M[4] * M[8] - M[5] * M[7]) - M[1] * (M[3] * M[8] - M[5] * M[6]) +
           M[2] * (M[3] * M[7] - M[4] * M[6]);
}

/* The central upright 3-point solver on random noise-free cameras: centre
 * c, rig motion (R, t) with R g1 = g2, bearings d1 = X - c, d2 = R X + t - c
 * (both times the camera's own centre c), so d2^T [u]x R d1 = 0 with
 * u = R c + t - c. */
static void test_central3(int trials)
{
    int trial, found = 0, count_ok = 0, counted = 0, sat = 1, st_ok = 1;
    double worst_gec = 0.0, worst_g = 0.0;
    for (trial = 0; trial < trials; trial++) {
        double R[9], t[3], c[3], g1[3], g2[3], d1[9], d2[9], a[9], b[9], u[3], Rs[54], us[18];
        int k, i, ns = 0, st, hit = 0;
        random_rotation(R, 1.0);
        randn(g1, 3);
        randn(t, 3);
        randn(c, 3);
        {
            double n = sqrt(dot3(g1, g1));
            for (i = 0; i < 3; i++)
                g1[i] /= n;
        }
        mat_vec(R, g1, g2);
        for (i = 0; i < 3; i++)
            c[i] *= 0.5;
        for (k = 0; k < 3; k++) {
            double X[3], X2[3], na, nb;
            randn(X, 3);
            for (i = 0; i < 3; i++)
                X[i] = c[i] + 6.0 * X[i];
            mat_vec(R, X, X2);
            for (i = 0; i < 3; i++) {
                d1[3 * k + i] = X[i] - c[i];
                d2[3 * k + i] = X2[i] + t[i] - c[i];
            }
            na = sqrt(dot3(d1 + 3 * k, d1 + 3 * k));
            nb = sqrt(dot3(d2 + 3 * k, d2 + 3 * k));
            for (i = 0; i < 3; i++) {
                a[3 * k + i] = d1[3 * k + i] / na;
                b[3 * k + i] = d2[3 * k + i] / nb;
            }
        }
        mat_vec(R, c, u);
        for (i = 0; i < 3; i++)
            u[i] += t[i] - c[i];
        {
            double n = sqrt(dot3(u, u));
            for (i = 0; i < 3; i++)
                u[i] /= n;
        }
        st = mcg_upright3_central(d1, d2, g1, g2, Rs, us, &ns);
        st_ok &= st == MCG_OK;
        for (k = 0; k < ns; k++) {
            double e = 0.0, x[3], Rg[3], dg, cu[3], du;
            for (i = 0; i < 9; i++)
                e = fmax(e, fabs(Rs[9 * k + i] - R[i]));
            cross3(us + 3 * k, u, cu);
            du = sqrt(dot3(cu, cu));
            hit |= e < 1e-8 && du < 1e-8;
            for (i = 0; i < 3; i++) { /* the constraints, unit bearings */
                double Ra[3];
                mat_vec(Rs + 9 * k, a + 3 * i, Ra);
                cross3(us + 3 * k, Ra, x);
                worst_gec = fmax(worst_gec, fabs(dot3(b + 3 * i, x)));
            }
            mat_vec(Rs + 9 * k, g1, Rg);
            dg = 0.0;
            for (i = 0; i < 3; i++)
                dg = fmax(dg, fabs(Rg[i] - g2[i]));
            worst_g = fmax(worst_g, dg);
            sat &= fabs(sqrt(dot3(us + 3 * k, us + 3 * k)) - 1.0) < 1e-12;
        }
        found += hit;
        /* the count against det's sign changes on 20000 yaws (trials whose
         * smallest |det| on the grid is not near a tangency) */
        if (trial < trials / 4) {
            int changes = 0, g;
            double prev = det3_at(g1, g2, -3.14159265358979, a, b), tiny = fabs(prev);
            for (g = 1; g <= 20000; g++) {
                double th = -3.14159265358979 + 6.28318530717958 * g / 20000.0;
                double v = det3_at(g1, g2, th, a, b);
                changes += (v < 0.0) != (prev < 0.0);
                tiny = fmin(tiny, fabs(v));
                prev = v;
            }
            if (tiny > 1e-9) {
                counted++;
                count_ok += changes == ns;
            }
        }
    }
    check(st_ok, "central 3-point: MCG_OK on generic data", 0.0, 0.0);
    check(found == trials, "central 3-point: the truth among the solutions (of trials)", found,
          trials);
    check(worst_gec < 1e-9, "central 3-point: every solution on the 3 constraints", worst_gec,
          1e-9);
    check(worst_g < 1e-12, "central 3-point: every solution maps g1 to g2", worst_g, 1e-12);
    check(sat, "central 3-point: unit directions", 0.0, 0.0);
    check(counted > trials / 5 && count_ok == counted,
          "central 3-point: solutions = sign changes of det on the yaw grid (of counted)",
          count_ok, counted);
    {
        double d1[9] = {0, 0, 1, 0.1, 0, 1, 0, 0.1, 1}, d2[9], g[3] = {0, 0, 1}, Rs[54],
               us[18];
        int ns = -1;
        memcpy(d2, d1, sizeof d2);
        d2[5] = 0.0; /* a zero bearing */
        d2[3] = d2[4] = 0.0;
        check(mcg_upright3_central(d1, d2, g, g, Rs, us, &ns) == MCG_EINVAL,
              "central 3-point: zero bearing -> MCG_EINVAL", 0.0, 0.0);
        memcpy(d2, d1, sizeof d2);
        memcpy(d1 + 6, d1, 3 * sizeof *d1); /* a repeated pair */
        memcpy(d2 + 6, d2, 3 * sizeof *d2);
        st_ok = mcg_upright3_central(d1, d2, g, g, Rs, us, &ns);
        check(st_ok == MCG_EDEGENERATE, "central 3-point: repeated pair -> MCG_EDEGENERATE",
              st_ok, MCG_EDEGENERATE);
    }
}

int main(void)
{
    test_random(0, 1, scaled(3000), "generic 4-camera rig, cross-camera");
    test_random(0, 0, scaled(3000), "generic 4-camera rig, intra-camera");
    test_random(1, 0, scaled(3000), "2-camera head, intra-camera");
    test_random(1, 1, scaled(3000), "2-camera head, cross-camera");
    test_near_pi(scaled(2000));
    test_root_at_split();
    test_central3(scaled(4000));
    test_status();
    timing();
    printf("%d checks, %d failed\n", n_checks, n_failed);
    return n_failed != 0;
}
