/*
 * test_verdict.c -- plain-C checks of csrc/verdict.c (mcg_verdict_stats)
 * against independent references: the counts recounted here; a pure
 * rotation of the bearings recovered (R_fit = the true rotation, every angle
 * "still") and, after a translation, no longer still; the critical angle of
 * a rig driving straight (no rotation: parallel displacements, 0) and of a
 * turning rig against the angle computed by acos here over every pair of
 * centres; cheirality by explicit least-squares triangulation here; the
 * travel direction of a straight drive (the true direction, also with the
 * bearings swapped end for end: the sign); the no-parallax count recounted
 * with atan2 at many thresholds, also exactly at the angles; the same
 * evidence from directions of any length; the status codes of invalid
 * arguments. Exit status 0 iff every check passes.
 */
#include "mcgeom.h"

#define TEST_SEED 0x7e7d1c75ULL
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define NC 4
#define PER 30
#define N (NC * PER)

static double o1[3 * N], d1[3 * N], o2[3 * N], d2[3 * N], cen[3 * NC];
static int c1[N], c2[N];
static unsigned char inl[N];
static double work[64];

/* A rig of NC cameras on a ring (radius 0.5 m), points 2..20 m out, moving by
 * (R, t); every fifth pair cross-camera when cross != 0. */
static void scene(const double R[9], const double t[3], int cross)
{
    int i, k, g, h;
    for (g = 0; g < NC; ++g) {
        cen[3 * g] = 0.5 * cos(2.0 * 3.141592653589793 * g / NC);
        cen[3 * g + 1] = 0.5 * sin(2.0 * 3.141592653589793 * g / NC);
        cen[3 * g + 2] = 0.1 * g;
    }
    for (i = 0; i < N; ++i) {
        double X[3], X2[3], depth = 2.0 + 18.0 * urand();
        g = i % NC;
        h = (cross && i % 5 == 4) ? (g + 1) % NC : g;
        for (k = 0; k < 3; ++k)
            X[k] = cen[3 * g + k] * (1.0 + depth) + (urand() - 0.5) * depth;
        for (k = 0; k < 3; ++k)
            X2[k] = R[3 * k] * X[0] + R[3 * k + 1] * X[1] + R[3 * k + 2] * X[2] + t[k];
        for (k = 0; k < 3; ++k) {
            o1[3 * i + k] = cen[3 * g + k];
            d1[3 * i + k] = (X[k] - cen[3 * g + k]) * (1.0 + urand()); /* any length */
            o2[3 * i + k] = cen[3 * h + k];
            d2[3 * i + k] = X2[k] - cen[3 * h + k];
        }
        c1[i] = g;
        c2[i] = h;
        inl[i] = (unsigned char)(urand() < 0.8 ? 1 : 0) | (urand() < 0.5 ? 2 : 0);
    }
}

/* Depths along the two rays of the least-squares closest points (normal
 * equations solved by Cramer's rule): the reference for cheirality. */
static int front_ref(const double R[9], const double t[3], int k)
{
    double a[3], p[3], b[3], w[3], A11 = 0, A12 = 0, A22 = 0, r1 = 0, r2 = 0, det, s1, s2;
    int i, j;
    for (i = 0; i < 3; ++i) {
        a[i] = p[i] = 0.0;
        for (j = 0; j < 3; ++j) {
            a[i] += R[3 * i + j] * d1[3 * k + j];
            p[i] += R[3 * i + j] * o1[3 * k + j];
        }
        p[i] += t[i];
        b[i] = d2[3 * k + i];
        w[i] = o2[3 * k + i] - p[i];
    }
    /* p + s1 a = o2 + s2 b in least squares: [a -b] [s1 s2]^T = w */
    for (i = 0; i < 3; ++i) {
        A11 += a[i] * a[i];
        A12 -= a[i] * b[i];
        A22 += b[i] * b[i];
        r1 += a[i] * w[i];
        r2 -= b[i] * w[i];
    }
    det = A11 * A22 - A12 * A12;
    s1 = (r1 * A22 - A12 * r2) / det;
    s2 = (A11 * r2 - A12 * r1) / det;
    return s1 > 0.0 && s2 > 0.0;
}

static double crit_ref(const double R[9], const double t[3])
{
    double u[3 * NC], best = 0.0;
    int g, i, j, m = 0;
    for (g = 0; g < NC; ++g) {
        double d[3], n;
        for (i = 0; i < 3; ++i) {
            d[i] = -cen[3 * g + i];
            for (j = 0; j < 3; ++j)
                d[i] += R[3 * j + i] * (cen[3 * g + j] - t[j]);
        }
        n = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (n > 0) {
            for (i = 0; i < 3; ++i)
                u[3 * m + i] = d[i] / n;
            m++;
        }
    }
    for (i = 0; i < m; ++i)
        for (j = i + 1; j < m; ++j) {
            double c = fabs(u[3 * i] * u[3 * j] + u[3 * i + 1] * u[3 * j + 1] +
                            u[3 * i + 2] * u[3 * j + 2]);
            double a = acos(c > 1.0 ? 1.0 : c);
            best = a > best ? a : best;
        }
    return best;
}

static void test_counts_crit_front(void)
{
    double R[9], t[3] = {0.3, -0.2, 0.9}, axis[3] = {0.2, 1.0, 0.1};
    mcg_verdict_stats_result s;
    int k, n_in = 0, n_intra = 0, n_front = 0, st;
    rot_about(axis, 0.2, R);
    scene(R, t, 1);
    for (k = 0; k < N; ++k)
        if (inl[k] & 1) {
            n_in++;
            n_intra += c1[k] == c2[k];
        }
    /* a wrong translation so that some pairs are behind */
    t[2] = -0.9;
    for (k = 0; k < N; ++k)
        if (inl[k] & 1)
            n_front += front_ref(R, t, k);
    st = mcg_verdict_stats(N, o1, d1, o2, d2, c1, c2, NC, inl, R, t, 1e-3, &s, work, 64);
    check_status(st, MCG_OK, "verdict_stats on a turning ring");
    check(s.n_inliers == n_in && s.n_intra == n_intra && s.n_cross == n_in - n_intra,
          "inlier / intra / cross counts", (double)s.n_inliers, 0);
    check(s.n_cameras_intra == NC, "every camera has intra inliers", s.n_cameras_intra, 0);
    check(fabs(s.critical_angle - crit_ref(R, t)) < 1e-9, "critical angle vs acos reference",
          fabs(s.critical_angle - crit_ref(R, t)), 1e-9);
    check(s.n_in_front == n_front && n_front > 0 && n_front < n_in,
          "cheirality vs least-squares triangulation", (double)(s.n_in_front - n_front), 0);
    check(s.fit_ok && s.n_still < s.n_intra / 2, "a translating rig is not still",
          (double)s.n_still, 0);
}

static void test_pure_rotation(void)
{
    double R[9], t[3] = {0, 0, 0}, axis[3] = {1.0, -0.3, 0.5}, err = 0.0;
    mcg_verdict_stats_result s;
    int k, st;
    rot_about(axis, 0.4, R);
    scene(R, t, 0);
    for (k = 0; k < N; ++k) { /* d2 = R d1: a pure rotation, no parallax */
        int i, j;
        for (i = 0; i < 3; ++i) {
            d2[3 * k + i] = 0.0;
            for (j = 0; j < 3; ++j)
                d2[3 * k + i] += R[3 * i + j] * d1[3 * k + j];
        }
    }
    st = mcg_verdict_stats(N, o1, d1, o2, d2, c1, c2, NC, inl, R, t, 1e-9, &s, work, 64);
    check_status(st, MCG_OK, "verdict_stats of a pure rotation");
    for (k = 0; k < 9; ++k)
        err = fmax(err, fabs(s.R_fit[k] - R[k]));
    check(s.fit_ok && err < 1e-12, "R_fit is the rotation", err, 1e-12);
    check(s.n_still == s.n_intra && s.n_intra > 0, "every angle still", (double)s.n_still, 0);
}

/* The no-parallax count against a recount here (atan2 of |R_fit e1 x e2|
 * and its dot, the definition) at thresholds spread over the angles and at
 * each of a few angles exactly (the count must then leave that pair out:
 * "below", the kernel's shortcut must fall back at the boundary). */
static void test_still_count(void)
{
    double R[9], t[3] = {0.05, -0.02, 0.01}, axis[3] = {0.2, 1.0, -0.4}, ang[N];
    mcg_verdict_stats_result s;
    int k, j, m = 0, st, bad = 0;
    rot_about(axis, 0.3, R);
    scene(R, t, 1);
    st = mcg_verdict_stats(N, o1, d1, o2, d2, c1, c2, NC, inl, R, t, 1e-3, &s, work, 64);
    check(st == MCG_OK && s.fit_ok, "verdict_stats of a small translation", (double)st, 0);
    for (k = 0; k < N; ++k) {
        double e1[3], e2[3], a[3], x[3], n1 = 0, n2 = 0;
        int i;
        if (!(inl[k] & 1) || c1[k] != c2[k])
            continue;
        for (i = 0; i < 3; ++i) {
            n1 += d1[3 * k + i] * d1[3 * k + i];
            n2 += d2[3 * k + i] * d2[3 * k + i];
        }
        n1 = 1.0 / sqrt(n1); /* (as the kernel scales: the same rounding) */
        n2 = 1.0 / sqrt(n2);
        for (i = 0; i < 3; ++i) {
            e1[i] = d1[3 * k + i] * n1;
            e2[i] = d2[3 * k + i] * n2;
        }
        for (i = 0; i < 3; ++i)
            a[i] = s.R_fit[3 * i] * e1[0] + s.R_fit[3 * i + 1] * e1[1] + s.R_fit[3 * i + 2] * e1[2];
        x[0] = a[1] * e2[2] - a[2] * e2[1];
        x[1] = a[2] * e2[0] - a[0] * e2[2];
        x[2] = a[0] * e2[1] - a[1] * e2[0];
        ang[m++] = atan2(sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]),
                         a[0] * e2[0] + a[1] * e2[1] + a[2] * e2[2]);
    }
    for (j = 0; j < 60 + m; ++j) {
        /* 60 thresholds from 1e-6 to 3.5 rad, then each angle itself */
        const double still = j < 60 ? 1e-6 * pow(3.5e6, j / 59.0) : ang[j - 60];
        int ref = 0;
        for (k = 0; k < m; ++k)
            ref += ang[k] < still;
        st = mcg_verdict_stats(N, o1, d1, o2, d2, c1, c2, NC, inl, R, t, still, &s, work, 64);
        bad += st != MCG_OK || s.n_still != ref;
    }
    check(m > 10 && bad == 0, "no-parallax count = recount at every threshold", (double)bad, 0);
}

static void test_straight_drive(void)
{
    double R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, t[3] = {-1.5, 0.0, 0.0}, e;
    mcg_verdict_stats_result s;
    int st, k;
    scene(R, t, 0);
    st = mcg_verdict_stats(N, o1, d1, o2, d2, c1, c2, NC, inl, R, t, 1e-3, &s, work, 64);
    check_status(st, MCG_OK, "verdict_stats of a straight drive");
    check(s.critical_angle < 1e-12, "no rotation: critical angle 0", s.critical_angle, 1e-12);
    e = fabs(s.t_direction[0] + 1.0) + fabs(s.t_direction[1]) + fabs(s.t_direction[2]);
    check(e < 1e-12, "travel direction of the straight drive", e, 1e-12);
    /* the direction given with the wrong sign: cheirality turns it round */
    t[0] = 1e-3; /* tiny: tau = t is taken, and its sign decided by the rays */
    st = mcg_verdict_stats(N, o1, d1, o2, d2, c1, c2, NC, inl, R, t, 1e-3, &s, work, 64);
    e = fabs(s.t_direction[0] + 1.0);
    check(st == MCG_OK && e < 1e-12, "travel direction's sign by cheirality", e, 1e-12);
    for (k = 0; k < N; ++k)
        inl[k] = 2; /* used, no inlier */
    st = mcg_verdict_stats(N, o1, d1, o2, d2, c1, c2, NC, inl, R, t, 1e-3, &s, work, 64);
    check(st == MCG_OK && s.n_inliers == 0 && !s.fit_ok && s.critical_angle == 0.0,
          "no inlier: nothing counted", (double)s.n_inliers, 0);
}

/* fuzz finding 23: where the centroid's travel tau = t + R c - c is exactly 0
 * the direction falls back to t's own; t ~ 1e-161 has |t|^2 subnormal,
 * and t / sqrt(t.t) was 1e-5 off unit length. One inlier at c = (x, 0, 0)
 * (so that R c = x R e1 and the shift are exact) and t = -(R c - c). */
static void test_tiny_travel_direction(void)
{
    double R[9], t[3] = {0, 0, 1}, x = 1e-160, shift[3], nd;
    const double a = 0.5;
    mcg_verdict_stats_result s;
    int st, k;
    double rr[9] = {cos(a), -sin(a), 0, sin(a), cos(a), 0, 0, 0, 1};
    memcpy(R, rr, sizeof R);
    scene(R, t, 0);
    for (k = 0; k < N; ++k)
        inl[k] = 2; /* used, no inlier */
    inl[0] = 1;
    o1[0] = o2[0] = x;
    o1[1] = o2[1] = o1[2] = o2[2] = 0.0;
    shift[0] = R[0] * x - x;
    shift[1] = R[3] * x;
    shift[2] = R[6] * x;
    for (k = 0; k < 3; ++k)
        t[k] = -shift[k];
    st = mcg_verdict_stats(N, o1, d1, o2, d2, c1, c2, NC, inl, R, t, 1e-3, &s, work, 64);
    nd = sqrt(s.t_direction[0] * s.t_direction[0] + s.t_direction[1] * s.t_direction[1] +
              s.t_direction[2] * s.t_direction[2]);
    check(st == MCG_OK && fabs(nd - 1.0) < 1e-12,
          "t ~ 1e-161 with tau = 0: t_direction of unit length", fabs(nd - 1.0), 1e-12);
}

static void test_invalid(void)
{
    double R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, t[3] = {0, 0, 1}, keep;
    mcg_verdict_stats_result s;
    scene(R, t, 1);
    check(mcg_verdict_stats_work_size(0) == 0 && mcg_verdict_stats_work_size(4097) == 0 &&
              mcg_verdict_stats_work_size(NC) > 0,
          "work size of bad camera counts is 0", 0, 0);
    check_status(mcg_verdict_stats(N, NULL, d1, o2, d2, c1, c2, NC, inl, R, t, 1e-3, &s, work,
                                   64), MCG_EINVAL, "NULL origins");
    check_status(mcg_verdict_stats(-1, o1, d1, o2, d2, c1, c2, NC, inl, R, t, 1e-3, &s, work,
                                   64), MCG_EINVAL, "negative n");
    check_status(mcg_verdict_stats(N, o1, d1, o2, d2, c1, c2, NC - 1, inl, R, t, 1e-3, &s,
                                   work, 64), MCG_EINVAL, "camera id out of range");
    check_status(mcg_verdict_stats(N, o1, d1, o2, d2, c1, c2, NC, inl, R, t, -1.0, &s, work,
                                   64), MCG_EINVAL, "negative still_angle");
    check_status(mcg_verdict_stats(N, o1, d1, o2, d2, c1, c2, NC, inl, R, t, 1e-3, &s, work,
                                   1), MCG_ENOMEM, "workspace too small");
    keep = d2[7];
    d2[7] = NAN;
    check_status(mcg_verdict_stats(N, o1, d1, o2, d2, c1, c2, NC, inl, R, t, 1e-3, &s, work,
                                   64), MCG_EINVAL, "NaN direction");
    d2[7] = keep;
    keep = o1[5];
    o1[5] = INFINITY;
    check_status(mcg_verdict_stats(N, o1, d1, o2, d2, c1, c2, NC, inl, R, t, 1e-3, &s, work,
                                   64), MCG_EINVAL, "infinite origin");
    o1[5] = NAN;
    check_status(mcg_verdict_stats(N, o1, d1, o2, d2, c1, c2, NC, inl, R, t, 1e-3, &s, work,
                                   64), MCG_EINVAL, "NaN origin");
    o1[5] = keep;
    keep = o2[N];
    o2[N] = -1e200;
    check_status(mcg_verdict_stats(N, o1, d1, o2, d2, c1, c2, NC, inl, R, t, 1e-3, &s, work,
                                   64), MCG_EINVAL, "origin beyond 1e150");
    o2[N] = keep;
    memset(d1, 0, 3 * sizeof(double));
    check_status(mcg_verdict_stats(N, o1, d1, o2, d2, c1, c2, NC, inl, R, t, 1e-3, &s, work,
                                   64), MCG_EINVAL, "zero direction");
    check_status(mcg_verdict_stats(0, o1, d1, o2, d2, c1, c2, NC, inl, R, t, 1e-3, &s, work,
                                   64), MCG_OK, "no pairs at all");
}

/* every third d1 times f1, every fourth d2 times f2 */
static void scale_directions(double f1, double f2)
{
    int k, i;
    for (k = 0; k < N; ++k)
        for (i = 0; i < 3; ++i) {
            if (k % 3 == 0)
                d1[3 * k + i] *= f1;
            if (k % 4 == 0)
                d2[3 * k + i] *= f2;
        }
}

/* Directions of any length give the same evidence: every third d1 scaled
 * by 1e-150 and every fourth d2 by 1e145 (squared lengths outside the
 * kernel's fast range of unit(), its other path), against the same scene
 * unscaled; the counts exactly, the rotation fit, the critical angle and
 * the direction of travel to rounding. */
static void test_scaled_directions(void)
{
    double R[9], t[3] = {0.3, -0.2, 0.4}, axis[3] = {0.5, 1.0, -0.3}, dev = 0.0;
    mcg_verdict_stats_result a, b;
    int i, sa, sb;
    rot_about(axis, 0.15, R);
    scene(R, t, 1);
    sa = mcg_verdict_stats(N, o1, d1, o2, d2, c1, c2, NC, inl, R, t, 0.05, &a, work, 64);
    scale_directions(1e-150, 1e145);
    sb = mcg_verdict_stats(N, o1, d1, o2, d2, c1, c2, NC, inl, R, t, 0.05, &b, work, 64);
    for (i = 0; i < 9; ++i)
        dev = fmax(dev, fabs(a.R_fit[i] - b.R_fit[i]));
    for (i = 0; i < 3; ++i)
        dev = fmax(dev, fabs(a.t_direction[i] - b.t_direction[i]));
    dev = fmax(dev, fabs(a.critical_angle - b.critical_angle));
    check(sa == MCG_OK && sb == MCG_OK && a.n_inliers == b.n_inliers && a.n_intra == b.n_intra &&
              a.n_still == b.n_still && a.n_in_front == b.n_in_front &&
              a.n_cameras_intra == b.n_cameras_intra && a.fit_ok == b.fit_ok && a.n_still > 0 &&
              a.n_still < a.n_intra,
          "tiny and huge directions: the same counts", (double)(a.n_still - b.n_still), 0);
    check(dev < 1e-12, "tiny and huge directions: the same fit and angles", dev, 1e-12);
    /* lengths whose squares under- and overflow (1e-170, 1e170): the unit
     * bearings still the same (cheirality, on the raw directions, is not
     * compared: its products leave the doubles) */
    scale_directions(1e-20, 1e25);
    sb = mcg_verdict_stats(N, o1, d1, o2, d2, c1, c2, NC, inl, R, t, 0.05, &b, work, 64);
    dev = 0.0;
    for (i = 0; i < 9; ++i)
        dev = fmax(dev, fabs(a.R_fit[i] - b.R_fit[i]));
    check(sb == MCG_OK && a.n_still == b.n_still && a.n_intra == b.n_intra && dev < 1e-12,
          "squared lengths beyond the doubles: the same bearings", dev, 1e-12);
}

int main(void)
{
    test_counts_crit_front();
    test_pure_rotation();
    test_still_count();
    test_straight_drive();
    test_scaled_directions();
    test_tiny_travel_direction();
    test_invalid();
    printf("%d checks, %d failed\n", n_checks, n_failed);
    return n_failed ? 1 : 0;
}
