/*
 * test_eigensolver.c -- plain-C checks of csrc/eigensolver.c (mcg_eigensolver,
 * Kneip and Li's eigensolver).
 *
 * References independent of the kernel: (1) the true motion of noise-free
 * generalized problems (4-camera rigs and 2-camera heads, a third of the
 * rays cross-camera: with intra-camera rays only, no motion is a trivial
 * minimum, see csrc/eigensolver.c) is recovered to 1e-9 from a start 5 degrees off; (2) on noisy
 * problems the result is a local minimum of lambda(R), the smallest
 * eigenvalue of M(R) = sum v v^T built here from its definition (centred,
 * RMS-scaled origins, unit directions): no rotation 1e-4 rad away in any of
 * six directions is lower, and it is not above lambda at the start; (3) with
 * max_iterations = 0 R is the start; (4) status codes. Exit status 0 iff
 * every check passes.
 */
#include "mcgeom.h"

#define TEST_SEED 0xe16e5017e3ULL
#include "testutil.h"
#include "../so3.h" /* dot3, cross3, mat_vec, mul33 */

#include <math.h>
#include <stdio.h>
#include <string.h>

#define N 40

static void make(int head, double noise, const double R[9], const double t[3], double *o1,
                 double *d1, double *o2, double *d2)
{
    double cen[4][3];
    int k, i;
    for (k = 0; k < 4; k++)
        for (i = 0; i < 3; i++)
            cen[k][i] = head ? (i == 0 ? (k & 1 ? 0.25 : -0.25) : 0.0) : 0.5 * nrand();
    for (k = 0; k < N; k++) {
        int c1 = head ? k % 2 : k % 4, c2 = k % 3 == 0 ? (head ? 1 - c1 : (c1 + 1) % 4) : c1;
        scene_correspondence(cen[c1], cen[c2], R, t, noise, o1 + 3 * k, d1 + 3 * k, o2 + 3 * k,
                             d2 + 3 * k);
    }
}

/* lambda(R) from its definition */
static double lambda_ref(const double R[9], const double *o1, const double *d1,
                         const double *o2, const double *d2)
{
    double c[3] = {0, 0, 0}, s = 0.0, M[16] = {0}, w[4], V[16];
    int k, i, j;
    for (k = 0; k < N; k++)
        for (i = 0; i < 3; i++)
            c[i] += (o1[3 * k + i] + o2[3 * k + i]) / (2.0 * N);
    for (k = 0; k < N; k++)
        for (i = 0; i < 3; i++)
            s += (pow(o1[3 * k + i] - c[i], 2) + pow(o2[3 * k + i] - c[i], 2)) / (2.0 * N);
    s = sqrt(s);
    for (k = 0; k < N; k++) {
        double a[3], b[3], p[3], q[3], m1[3], m2[3], ra[3], rm[3], v[4];
        double na = sqrt(dot3(d1 + 3 * k, d1 + 3 * k)), nb = sqrt(dot3(d2 + 3 * k, d2 + 3 * k));
        for (i = 0; i < 3; i++) {
            a[i] = d1[3 * k + i] / na;
            b[i] = d2[3 * k + i] / nb;
            p[i] = (o1[3 * k + i] - c[i]) / s;
            q[i] = (o2[3 * k + i] - c[i]) / s;
        }
        cross3(p, a, m1);
        cross3(q, b, m2);
        mat_vec(R, a, ra);
        mat_vec(R, m1, rm);
        cross3(ra, b, v);
        v[3] = dot3(b, rm) + dot3(m2, ra);
        for (i = 0; i < 4; i++)
            for (j = 0; j < 4; j++)
                M[4 * i + j] += v[i] * v[j];
    }
    mcg_sym_eig(4, M, w, V);
    return w[0];
}

static void run(int head, double noise, int trials, const char *label)
{
    static double o1[3 * N], d1[3 * N], o2[3 * N], d2[3 * N], work[4096];
    double worst_exact = 0.0, worst_min = -1.0, worst_start = -1.0;
    int trial, fails = 0;
    char what[160];
    for (trial = 0; trial < trials; trial++) {
        double R[9], t[3], w[3], P[9], R0[9], Re[9], te[3], lam, e = 0.0;
        int has, its, st, i, j;
        randn(w, 3);
        for (i = 0; i < 3; i++)
            w[i] *= 0.3;
        mcg_rot_from_angle_axis(w, R);
        randn(t, 3);
        make(head, noise, R, t, o1, d1, o2, d2);
        randn(w, 3);
        for (i = 0; i < 3; i++)
            w[i] *= 0.087 / sqrt(3.0);  /* ~5 degrees */
        mcg_rot_from_angle_axis(w, P);
        mul33(P, R, R0);
        st = mcg_eigensolver(N, o1, d1, o2, d2, R0, 100, Re, te, &lam, &has, &its, work,
                             mcg_eigensolver_work_size(N));
        if (st != MCG_OK || !has) {
            fails++;
            continue;
        }
        if (noise == 0.0) {
            for (i = 0; i < 9; i++)
                e = fmax(e, fabs(Re[i] - R[i]));
            for (i = 0; i < 3; i++)
                e = fmax(e, fabs(te[i] - t[i]) / sqrt(dot3(t, t)));
            worst_exact = fmax(worst_exact, e);
        } else {
            double l0 = lambda_ref(Re, o1, d1, o2, d2), ls = lambda_ref(R0, o1, d1, o2, d2);
            for (j = 0; j < 6; j++) {
                double dw[3] = {0, 0, 0}, D[9], Rp[9];
                dw[j % 3] = j < 3 ? 1e-4 : -1e-4;
                mcg_rot_from_angle_axis(dw, D);
                mul33(D, Re, Rp);
                worst_min = fmax(worst_min, (l0 - lambda_ref(Rp, o1, d1, o2, d2)) / l0);
            }
            worst_start = fmax(worst_start, (l0 - ls) / ls);
        }
    }
    snprintf(what, sizeof what, "%s: solved (status OK, metric t)", label);
    check(fails == 0, what, fails, 0);
    if (noise == 0.0) {
        snprintf(what, sizeof what, "%s: truth recovered from 5 deg off", label);
        check(worst_exact < 1e-9, what, worst_exact, 1e-9);
    } else {
        snprintf(what, sizeof what, "%s: no neighbour 1e-4 rad away is lower", label);
        check(worst_min <= 1e-9, what, worst_min, 1e-9);
        snprintf(what, sizeof what, "%s: lambda not above the start's", label);
        check(worst_start <= 0.0, what, worst_start, 0.0);
    }
}

static void test_status(void)
{
    static double work[4096];
    double o[3 * N] = {0}, d[3 * N], R0[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, R[9], t[3], lam,
           bad[9] = {2, 0, 0, 0, 1, 0, 0, 0, 1};
    int has, its, i;
    for (i = 0; i < 3 * N; i++)
        d[i] = 1.0 + (i % 5);
    check_status(mcg_eigensolver(N, o, d, o, d, bad, 10, R, t, &lam, &has, &its, work, mcg_eigensolver_work_size(N)),
                 MCG_EINVAL, "R0 not a rotation");
    check_status(mcg_eigensolver(N, o, d, o, d, R0, 10, R, t, &lam, &has, &its, work, mcg_eigensolver_work_size(N) - 1),
                 MCG_ENOMEM, "workspace one short");
    check_status(mcg_eigensolver(0, o, d, o, d, R0, 10, R, t, &lam, &has, &its, work, mcg_eigensolver_work_size(N)),
                 MCG_EINVAL, "n = 0");
    check_status(mcg_eigensolver(N, o, d, o, d, R0, -1, R, t, &lam, &has, &its, work, mcg_eigensolver_work_size(N)),
                 MCG_EINVAL, "max_iterations < 0");
    d[7] = NAN;
    check_status(mcg_eigensolver(N, o, d, o, d, R0, 10, R, t, &lam, &has, &its, work, mcg_eigensolver_work_size(N)),
                 MCG_EINVAL, "NaN direction");
    check(mcg_eigensolver_work_size(N) <= 4096, "work size fits the test's buffer",
          (double)mcg_eigensolver_work_size(N), 4096);
}

static void test_no_iterations(void)
{
    static double o1[3 * N], d1[3 * N], o2[3 * N], d2[3 * N], work[4096];
    double R[9], t[3] = {0.3, -0.2, 0.5}, w[3] = {0.1, 0.2, -0.1}, Re[9], te[3], lam, e = 0;
    int has, its, i;
    mcg_rot_from_angle_axis(w, R);
    make(0, 1e-3, R, t, o1, d1, o2, d2);
    mcg_eigensolver(N, o1, d1, o2, d2, R, 0, Re, te, &lam, &has, &its, work, mcg_eigensolver_work_size(N));
    for (i = 0; i < 9; i++)
        e = fmax(e, fabs(Re[i] - R[i]));
    check(e < 1e-14 && its == 0, "max_iterations = 0 keeps R0", e, 1e-14);
}

int main(void)
{
    run(0, 0.0, scaled(200), "4-camera rig, noise-free");
    run(1, 0.0, scaled(200), "2-camera head, noise-free");
    run(0, 2e-3, scaled(100), "4-camera rig, noisy");
    run(1, 2e-3, scaled(100), "2-camera head, noisy");
    test_no_iterations();
    test_status();
    printf("%d checks, %d failed\n", n_checks, n_failed);
    return n_failed != 0;
}
