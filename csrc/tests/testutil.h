/* testutil.h -- shared by the plain-C kernel tests: check counters that print
 * one line per check, and a deterministic splitmix64 generator. Define
 * TEST_SEED before including to give each test its own stream. */
#ifndef MCGEOM_TESTUTIL_H
#define MCGEOM_TESTUTIL_H

#include "mcgeom.h" /* mcg_rot_from_angle_axis (rot_about) */

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#ifndef TEST_SEED
#define TEST_SEED 0x9e3779b97f4a7c15ULL
#endif

static int n_checks = 0, n_failed = 0;

static inline void check(int ok, const char *what, double val, double tol)
{
    ++n_checks;
    if (!ok)
        ++n_failed;
    printf("%s  %-60s  %.3e (tol %.1e)\n", ok ? "ok  " : "FAIL", what, val,
           tol);
}

static inline void check_status(int got, int want, const char *what)
{
    ++n_checks;
    if (got != want)
        ++n_failed;
    printf("%s  %-60s  status %d (want %d)\n", got == want ? "ok  " : "FAIL",
           what, got, want);
}

/* A repetition count n scaled by $MCG_TEST_SCALE, a number in (0, 1]
 * (default 1): the valgrind run of csrc/tests/run_checks.sh uses fewer random
 * trials and timing repetitions, with the same checks. Never below 1. */
static inline int scaled(int n)
{
    const char *env = getenv("MCG_TEST_SCALE");
    double f = env ? strtod(env, NULL) : 1.0;
    if (!(f > 0.0 && f <= 1.0))
        f = 1.0;
    return n * f < 1.0 ? 1 : (int)(n * f);
}

static uint64_t rng_state = TEST_SEED;
static inline uint64_t rng_next(void)
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

static inline double urand(void) /* uniform in (0, 1) */
{
    return ((double)(rng_next() >> 11) + 0.5) * (1.0 / 9007199254740992.0);
}

static inline double nrand(void) /* standard normal (Box-Muller) */
{
    return sqrt(-2.0 * log(urand())) * cos(6.283185307179586 * urand());
}

/* R = exp([th axis/|axis|]x) (the library's Rodrigues, tested in
 * test_linalg.c) */
static inline void rot_about(const double axis[3], double th, double r[9])
{
    double n = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]), w[3];
    int i;
    for (i = 0; i < 3; ++i)
        w[i] = th * axis[i] / n;
    mcg_rot_from_angle_axis(w, r);
}

static inline void randn(double *a, int n) /* n standard normal values */
{
    int i;
    for (i = 0; i < n; ++i)
        a[i] = nrand();
}

/* max |Q^T Q - I| of the m x n row-major q (NaN if any entry is NaN) */
static inline double orthonormality_error(const double *q, int m, int n)
{
    double e = 0.0;
    int i, j, k;
    for (i = 0; i < n; ++i)
        for (j = 0; j < n; ++j) {
            double s = 0.0;
            for (k = 0; k < m; ++k)
                s += q[n * k + i] * q[n * k + j];
            s = fabs(s - (i == j ? 1.0 : 0.0));
            if (!(s <= e))
                e = s; /* (NaN propagates into e) */
        }
    return e;
}

/* c (m x n) = a (m x k) b (k x n), row-major, the textbook triple loop */
static inline void matmul(int m, int k, int n, const double *a, const double *b,
                   double *c)
{
    int i, j, l;
    for (i = 0; i < m; ++i)
        for (j = 0; j < n; ++j) {
            double acc = 0.0;
            for (l = 0; l < k; ++l)
                acc += a[i * k + l] * b[l * n + j];
            c[i * n + j] = acc;
        }
}

/* One correspondence of a synthetic rig scene: a point 2..10 m from the
 * camera centre c1 in a uniformly random direction, seen from c1 at time 1
 * and, after the motion X2 = R X + t (rig2_from_rig1, R row-major), from the
 * camera centre c2 at time 2. Outputs the origins and the (unnormalised)
 * directions, each direction coordinate perturbed by noise * N(0, 1) when
 * noise > 0. Shared by the minimal- and non-minimal-solver tests. */
static inline void scene_correspondence(const double c1[3], const double c2[3], const double R[9],
                                        const double t[3], double noise, double o1[3],
                                        double d1[3], double o2[3], double d2[3])
{
    double dir[3], X[3], depth, n;
    int i;
    randn(dir, 3);
    n = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    depth = 2.0 + 8.0 * urand();
    for (i = 0; i < 3; ++i)
        X[i] = c1[i] + depth * dir[i] / n;
    for (i = 0; i < 3; ++i) {
        double X2 = R[3 * i] * X[0] + R[3 * i + 1] * X[1] + R[3 * i + 2] * X[2] + t[i];
        o1[i] = c1[i];
        o2[i] = c2[i];
        d1[i] = X[i] - c1[i];
        d2[i] = X2 - c2[i];
    }
    if (noise > 0.0)
        for (i = 0; i < 3; ++i) {
            d1[i] += noise * nrand();
            d2[i] += noise * nrand();
        }
}

#endif /* MCGEOM_TESTUTIL_H */
