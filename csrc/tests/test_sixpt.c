/*
 * test_sixpt.c -- plain-C checks of csrc/sixpt.c (mcg_sixpt), the generic
 * minimal 6-point generalized relative pose.
 *
 * Independent references: (1) the generator's truth: the true motion of
 * random noise-free configurations (generic 6-camera rigs with intra- and
 * cross-camera rays, 2-camera heads, large rotations) must be among the
 * solutions to 1e-8 in at least 98 % of them (a homotopy path may fail in an
 * ill-conditioned configuration; none missed in 600 of the bench runs), and in every
 * one of a set of mild motions; (2) every returned solution is a rotation and
 * satisfies the six generalized epipolar constraints, evaluated here from the
 * raw rays as the triple-product form (R d1 x d2) . (t + R o1 - o2) = 0 (no
 * Cayley vector, no normalisation), to 1e-9 relative to the rig's size;
 * (3) degenerate data: all six rays from one centre (a central camera: no
 * metric scale) gives no solution, and the problem is invariant to a change
 * of the rig frame; (4) status codes of invalid input; (5) mcg_sixpt_local
 * (csrc/sixpt_local.c) against mcg_sixpt: each motion it returns is one of
 * mcg_sixpt's and valid as in (2), the truth is found from itself as the
 * start and, from the fixed starts, in most mild motions. Exit status 0 iff
 * every check passes.
 */
#include "mcgeom.h"

#define TEST_SEED 0x6b5f1d2c3a4e9877ULL
#include "testutil.h"
#include "../so3.h" /* dot3, cross3, mat_vec, mul33 */

#include <math.h>
#include <stdio.h>
#include <string.h>

/* A rotation by an angle uniform in (-max_angle, max_angle) about a random
 * axis, from its unit quaternion (w, x, y, z) */
static void random_rotation(double R[9], double max_angle)
{
    double q[4], half = 0.5 * max_angle * (2.0 * urand() - 1.0), n;
    randn(q + 1, 3);
    n = sqrt(dot3(q + 1, q + 1));
    q[0] = cos(half);
    q[1] *= sin(half) / n;
    q[2] *= sin(half) / n;
    q[3] *= sin(half) / n;
    mcg_rot_from_quat(q, R);
}

/* v scaled to length len */
static void normalize_scale(double v[3], double len)
{
    double n = sqrt(dot3(v, v));
    v[0] *= len / n;
    v[1] *= len / n;
    v[2] *= len / n;
}

/* A noise-free problem: 6 correspondences of a rig with 6 cameras (centres
 * random within 0.5 m) or a 2-camera head (baseline 0.3 m); pair k is
 * cross-camera when cross != 0 and k is odd; points 2..10 m away. central:
 * every camera at the origin (one centre). */
static void make_problem(int kind, int cross, const double R[9], const double t[3],
                         double o1[18], double d1[18], double o2[18], double d2[18])
{
    double cen[6][3] = {{0.0}};
    int k, i;
    for (k = 0; k < 6 && kind != 2; k++) {
        if (kind == 1) /* a head: two centres 0.3 m apart on the x axis */
            cen[k][0] = (k & 1) ? 0.15 : -0.15;
        else
            randn(cen[k], 3), cen[k][0] *= 0.5, cen[k][1] *= 0.5, cen[k][2] *= 0.5;
    }
    for (k = 0; k < 6; k++) {
        int c1 = k, c2 = (cross && (k & 1)) ? (k + 1) % 6 : k;
        double depth = 2.0 + 8.0 * urand(), X2[3];
        if (kind == 1) {
            c1 = k & 1;
            c2 = (cross && (k & 2)) ? 1 - c1 : c1;
        }
        /* the time-1 ray: a random unit direction; the point at depth on it */
        randn(d1 + 3 * k, 3);
        normalize_scale(d1 + 3 * k, depth);
        memcpy(o1 + 3 * k, cen[c1], sizeof cen[c1]);
        memcpy(o2 + 3 * k, cen[c2], sizeof cen[c2]);
        /* the time-2 ray: from camera c2 to R X + t, X = o1 + d1 */
        {
            double X[3] = {o1[3 * k] + d1[3 * k], o1[3 * k + 1] + d1[3 * k + 1],
                           o1[3 * k + 2] + d1[3 * k + 2]};
            mat_vec(R, X, X2);
        }
        for (i = 0; i < 3; i++)
            d2[3 * k + i] = X2[i] + t[i] - o2[3 * k + i];
    }
}

/* largest |(R d1 x d2) . (t + R o1 - o2)| / (|d1| |d2|) over the 6 pairs: the
 * coplanarity of the two rays with the baseline between their centres */
static double triple_residual(const double *o1, const double *d1, const double *o2,
                              const double *d2, const double R[9], const double t[3])
{
    double worst = 0.0;
    int k, i;
    for (k = 0; k < 6; k++) {
        double Rd[3], Ro[3], b[3], c[3];
        mat_vec(R, d1 + 3 * k, Rd);
        mat_vec(R, o1 + 3 * k, Ro);
        for (i = 0; i < 3; i++)
            b[i] = t[i] + Ro[i] - o2[3 * k + i];
        cross3(Rd, d2 + 3 * k, c);
        worst = fmax(worst, fabs(dot3(c, b)) / sqrt(dot3(d1 + 3 * k, d1 + 3 * k) *
                                                     dot3(d2 + 3 * k, d2 + 3 * k)));
    }
    return worst;
}

/* max |R R^T - I| and |det R - 1| */
static double rot_error(const double R[9])
{
    double Rt[9], P[9], e = fabs(det33(R) - 1.0);
    int i;
    for (i = 0; i < 9; i++)
        Rt[i] = R[3 * (i % 3) + i / 3];
    mul33(R, Rt, P);
    for (i = 0; i < 9; i++)
        e = fmax(e, fabs(P[i] - (i % 4 == 0 ? 1.0 : 0.0)));
    return e;
}

/* 1 if (Rq, tq) is one of the n solutions (R, t): max |R - Rq| < tol and
 * |t - tq| < tol * t_scale */
static int near_one(const double *R, const double *t, int n, const double Rq[9],
                    const double tq[3], double tol, double t_scale)
{
    int s, i;
    for (s = 0; s < n; s++) {
        double e = 0.0, et = 0.0;
        for (i = 0; i < 9; i++)
            e = fmax(e, fabs(R[9 * s + i] - Rq[i]));
        for (i = 0; i < 3; i++)
            et += (t[3 * s + i] - tq[i]) * (t[3 * s + i] - tq[i]);
        if (e < tol && sqrt(et) < tol * t_scale)
            return 1;
    }
    return 0;
}

/* 1 if (Rt, tt) is among the n solutions to 1e-8 (max |R - Rt|, |t - tt| / |tt|) */
static int has_truth(const double *R, const double *t, int n, const double Rt[9],
                     const double tt[3])
{
    return near_one(R, t, n, Rt, tt, 1e-8, sqrt(dot3(tt, tt)));
}

/* 1 if (Rq, tq) is one of the n solutions to 1e-6 (|t - tq| relative to
 * 1 + |tq|): the same solution polished by another solver (seen 2e-8 apart
 * where |t| = 0.02 m) */
static int among(const double *R, const double *t, int n, const double Rq[9],
                 const double tq[3])
{
    return near_one(R, t, n, Rq, tq, 1e-6, 1.0 + sqrt(dot3(tq, tq)));
}

int main(void)
{
    double o1[18], d1[18], o2[18], d2[18], R[576], t[192], Rt[9], tt[3], Rq0[9];
    int n, st, k, i, trial;
    char what[96];

    /* (1) + (2): truth among the solutions, every solution valid */
    for (k = 0; k < 4; k++) {
        int kind = k >> 1, cross = k & 1, trials = scaled(12), hits = 0, all_valid = 1;
        double worst_res = 0.0, worst_rot = 0.0;
        for (trial = 0; trial < trials; trial++) {
            random_rotation(Rt, 3.0); /* angles up to ~170 degrees */
            randn(tt, 3);
            make_problem(kind, cross, Rt, tt, o1, d1, o2, d2);
            st = mcg_sixpt(o1, d1, o2, d2, R, t, &n);
            if (st != MCG_OK || n < 0 || n > MCG_SIXPT_MAX_SOLUTIONS) {
                all_valid = 0;
                continue;
            }
            hits += has_truth(R, t, n, Rt, tt);
            for (i = 0; i < n; i++) {
                double scale = 1.0 + sqrt(dot3(t + 3 * i, t + 3 * i));
                worst_res = fmax(worst_res, triple_residual(o1, d1, o2, d2, R + 9 * i, t + 3 * i) /
                                                scale);
                worst_rot = fmax(worst_rot, rot_error(R + 9 * i));
            }
        }
        snprintf(what, sizeof what, "%s%s: status OK, 0..64 solutions",
                 kind ? "2-camera head" : "6-camera rig", cross ? " + cross" : "");
        check(all_valid, what, all_valid, 0);
        snprintf(what, sizeof what, "%s%s: truth among the solutions (>= 98 %%)",
                 kind ? "2-camera head" : "6-camera rig", cross ? " + cross" : "");
        check(hits >= 0.98 * trials, what, (double)hits / trials, 0.98);
        snprintf(what, sizeof what, "%s%s: every solution's GEC residual",
                 kind ? "2-camera head" : "6-camera rig", cross ? " + cross" : "");
        check(worst_res <= 1e-9, what, worst_res, 1e-9);
        snprintf(what, sizeof what, "%s%s: every solution a rotation",
                 kind ? "2-camera head" : "6-camera rig", cross ? " + cross" : "");
        check(worst_rot <= 1e-12, what, worst_rot, 1e-12);
    }

    /* mild motions (a vehicle's): the truth every time */
    {
        int trials = scaled(8), hits = 0;
        for (trial = 0; trial < trials; trial++) {
            random_rotation(Rt, 0.2);
            randn(tt, 3);
            make_problem(0, trial & 1, Rt, tt, o1, d1, o2, d2);
            if (mcg_sixpt(o1, d1, o2, d2, R, t, &n) == MCG_OK)
                hits += has_truth(R, t, n, Rt, tt);
        }
        check(hits == trials, "mild motions: truth every time", hits, trials);
    }

    /* (3) a change of the rig frame (X -> Q X + a at both times) moves the
     * truth accordingly: R' = Q R Q^T, t' = Q t + a - R' a */
    {
        double Q[9], a[3], p1[18], e1[18], p2[18], e2[18], Rq[9], tq[3], tmp[9], QT[9];
        random_rotation(Rt, 1.0);
        randn(tt, 3);
        make_problem(0, 1, Rt, tt, o1, d1, o2, d2);
        random_rotation(Q, 3.0);
        randn(a, 3);
        for (k = 0; k < 6; k++) {
            mat_vec(Q, o1 + 3 * k, p1 + 3 * k);
            mat_vec(Q, o2 + 3 * k, p2 + 3 * k);
            mat_vec(Q, d1 + 3 * k, e1 + 3 * k);
            mat_vec(Q, d2 + 3 * k, e2 + 3 * k);
            for (i = 0; i < 3; i++) {
                p1[3 * k + i] = 100.0 * (p1[3 * k + i] + a[i]); /* and metres -> cm */
                p2[3 * k + i] = 100.0 * (p2[3 * k + i] + a[i]);
            }
        }
        for (i = 0; i < 3; i++)
            for (k = 0; k < 3; k++)
                QT[3 * i + k] = Q[3 * k + i];
        mul33(Q, Rt, tmp);
        mul33(tmp, QT, Rq);
        mat_vec(Q, tt, tq);
        mat_vec(Rq, a, tmp);
        for (i = 0; i < 3; i++)
            tq[i] = 100.0 * (tq[i] + a[i] - tmp[i]);
        st = mcg_sixpt(p1, e1, p2, e2, R, t, &n);
        check(st == MCG_OK && has_truth(R, t, n, Rq, tq),
              "moved, rotated and rescaled rig frame: moved truth", n, 0);
    }

    /* one centre: a central camera (no metric scale): no solution */
    random_rotation(Rt, 1.0);
    randn(tt, 3);
    make_problem(2, 0, Rt, tt, o1, d1, o2, d2);
    st = mcg_sixpt(o1, d1, o2, d2, R, t, &n);
    check(st == MCG_OK && n == 0, "central camera (one centre): no solution", n, 0);

    /* (4) invalid input */
    make_problem(0, 1, Rt, tt, o1, d1, o2, d2);
    check_status(mcg_sixpt(NULL, d1, o2, d2, R, t, &n), MCG_EINVAL, "NULL o1");
    check_status(mcg_sixpt(o1, d1, o2, d2, R, t, NULL), MCG_EINVAL, "NULL n_solutions");
    d1[4] = NAN;
    check_status(mcg_sixpt(o1, d1, o2, d2, R, t, &n), MCG_EINVAL, "NaN direction");
    make_problem(0, 1, Rt, tt, o1, d1, o2, d2);
    o2[0] = INFINITY;
    check_status(mcg_sixpt(o1, d1, o2, d2, R, t, &n), MCG_EINVAL, "inf origin");
    make_problem(0, 1, Rt, tt, o1, d1, o2, d2);
    d2[6] = d2[7] = d2[8] = 0.0;
    check_status(mcg_sixpt(o1, d1, o2, d2, R, t, &n), MCG_EINVAL, "zero direction");

    /* (5) mcg_sixpt_local, with mcg_sixpt as its reference: every motion it
     * returns is a valid solution and one of mcg_sixpt's; from the truth as
     * its extra start it finds the truth; on mild motions (up to 0.3 rad)
     * its fixed starts find it in at least 30 % of 16 fixed problems (11 of
     * them; 0.63 of 150 ring-rig samples in the robust search's case) */
    {
        double Rl[9 * MCG_SIXPT_LOCAL_MAX_SOLUTIONS], tl[3 * MCG_SIXPT_LOCAL_MAX_SOLUTIONS];
        int trials = scaled(12), nl, all_among = 1, from_truth = 0, mild = 0, total = 0;
        /* (the rate on mild motions: a fixed count, the local search alone,
         * so that a reduced run -- valgrind's -- still measures a rate) */
        const int mild_trials = 16;
        double worst_res = 0.0, worst_rot = 0.0;
        for (trial = 0; trial < trials; trial++) {
            random_rotation(Rt, trial % 2 ? 3.0 : 0.6);
            randn(tt, 3);
            make_problem(trial & 1, (trial >> 1) & 1, Rt, tt, o1, d1, o2, d2);
            if (mcg_sixpt(o1, d1, o2, d2, R, t, &n) != MCG_OK ||
                mcg_sixpt_local(o1, d1, o2, d2, NULL, Rl, tl, &nl) != MCG_OK) {
                all_among = 0;
                continue;
            }
            total += nl;
            for (i = 0; i < nl; i++) {
                double scale = 1.0 + sqrt(dot3(tl + 3 * i, tl + 3 * i));
                all_among &= among(R, t, n, Rl + 9 * i, tl + 3 * i);
                worst_res = fmax(worst_res,
                                 triple_residual(o1, d1, o2, d2, Rl + 9 * i, tl + 3 * i) / scale);
                worst_rot = fmax(worst_rot, rot_error(Rl + 9 * i));
            }
            if (mcg_sixpt_local(o1, d1, o2, d2, Rt, Rl, tl, &nl) == MCG_OK)
                from_truth += has_truth(Rl, tl, nl, Rt, tt);
        }
        rng_state = TEST_SEED ^ 0x5d; /* (the same problems at every scale) */
        for (trial = 0; trial < mild_trials; trial++) {
            random_rotation(Rt, 0.6);
            randn(tt, 3);
            make_problem(trial & 1, (trial >> 1) & 1, Rt, tt, o1, d1, o2, d2);
            if (mcg_sixpt_local(o1, d1, o2, d2, NULL, Rl, tl, &nl) == MCG_OK)
                mild += has_truth(Rl, tl, nl, Rt, tt);
        }
        check(all_among && total > 0, "local: every motion one of mcg_sixpt's", total, 0);
        check(worst_res <= 1e-9, "local: every motion's GEC residual", worst_res, 1e-9);
        check(worst_rot <= 1e-12, "local: every motion a rotation", worst_rot, 1e-12);
        check(from_truth == trials, "local: the truth from the truth as a start", from_truth,
              trials);
        check(mild >= 0.3 * mild_trials, "local: mild motions, truth in >= 30 %", mild,
              0.3 * mild_trials);
        make_problem(2, 0, Rt, tt, o1, d1, o2, d2);
        st = mcg_sixpt_local(o1, d1, o2, d2, NULL, Rl, tl, &nl);
        check(st == MCG_OK && nl == 0, "local: central camera (one centre): no solution", nl, 0);
        make_problem(0, 1, Rt, tt, o1, d1, o2, d2);
        check_status(mcg_sixpt_local(o1, d1, o2, NULL, NULL, Rl, tl, &nl), MCG_EINVAL,
                     "local: NULL d2");
        memcpy(Rq0, Rt, sizeof Rq0);
        Rq0[0] *= 1.01;
        check_status(mcg_sixpt_local(o1, d1, o2, d2, Rq0, Rl, tl, &nl), MCG_EINVAL,
                     "local: a start that is no rotation");
        d1[2] = NAN;
        check_status(mcg_sixpt_local(o1, d1, o2, d2, NULL, Rl, tl, &nl), MCG_EINVAL,
                     "local: NaN direction");
    }

    printf("%d checks, %d failed\n", n_checks, n_failed);
    return n_failed ? 1 : 0;
}
