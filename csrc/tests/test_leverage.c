/*
 * test_leverage.c -- plain-C checks of csrc/leverage.c (mcg_sampson_leverage)
 * against an independent reference: the Jacobian of the public residual
 * mcg_gec_residuals by central differences (rotation perturbed on the left,
 * exp([dw]x) R, as mcg_refine_motion's parameters; the leverage does not
 * depend on that choice), J^T J inverted by Gauss-Jordan here, and
 * J_k (J^T J)^-1 J_k^T per pair; with R held, the 3 translation columns.
 * Also: the leverages sum to the number of parameters; they do not change
 * when the world is scaled (metres to millimetres); max_lev / argmax are
 * the array's; a cross-camera pair that alone fixes the scale of a
 * one-camera rig has leverage 1; the status codes (too few pairs, a flat
 * direction, invalid arguments). Exit status 0 iff every check passes.
 */
#include "mcgeom.h"

#define TEST_SEED 0x1e7e1a6eULL
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define NC 4
#define PER 12
#define N (NC * PER + 3) /* three cross-camera pairs at the end */

static double o1[3 * N], d1[3 * N], o2[3 * N], d2[3 * N];

static void mat_vec3(const double r[9], const double x[3], double y[3])
{
    int i;
    for (i = 0; i < 3; ++i)
        y[i] = r[3 * i] * x[0] + r[3 * i + 1] * x[1] + r[3 * i + 2] * x[2];
}

/* Pair k: camera centre c1 at time 1, c2 at time 2 (rig frames), a point
 * 2..20 m out of c1 along a random direction around axis, moved by (R, t),
 * the bearings with 1e-3 rad of noise. */
static void make_pair(int k, const double c1[3], const double c2[3], const double axis[3],
                      const double R[9], const double t[3])
{
    double x[3], y[3], dist = 2.0 + 18.0 * urand();
    int i;
    for (i = 0; i < 3; ++i) {
        o1[3 * k + i] = c1[i];
        o2[3 * k + i] = c2[i];
        d1[3 * k + i] = axis[i] + 0.5 * (urand() - 0.5);
    }
    for (i = 0; i < 3; ++i)
        x[i] = c1[i] + dist * d1[3 * k + i];
    mat_vec3(R, x, y);
    for (i = 0; i < 3; ++i) {
        d2[3 * k + i] = y[i] + t[i] - c2[i] + 1e-3 * dist * nrand();
        d1[3 * k + i] += 1e-3 * nrand();
    }
}

/* 4 cameras on a ring (radius 0.5 m, looking out), PER intra-camera pairs
 * each, and 3 pairs from camera g at time 1 to camera g + 1 at time 2 */
static void ring_scene(const double R[9], const double t[3])
{
    int g, k;
    for (g = 0; g < NC; ++g) {
        double c[3] = {0.5 * cos(1.5707963267948966 * g), 0.5 * sin(1.5707963267948966 * g),
                       0.0};
        double ax[3] = {c[0] * 2.0, c[1] * 2.0, 0.2};
        for (k = 0; k < PER; ++k)
            make_pair(PER * g + k, c, c, ax, R, t);
    }
    for (k = 0; k < 3; ++k) {
        double ca[3] = {0.5 * cos(1.5707963267948966 * k), 0.5 * sin(1.5707963267948966 * k),
                        0.0};
        double cb[3] = {0.5 * cos(1.5707963267948966 * (k + 1)),
                        0.5 * sin(1.5707963267948966 * (k + 1)), 0.0};
        double ax[3] = {ca[0] * 2.0, ca[1] * 2.0, 0.0};
        make_pair(NC * PER + k, ca, cb, ax, R, t);
    }
}

/* the reference: J by central differences of mcg_gec_residuals, then
 * J_k (J^T J)^-1 J_k^T with (J^T J)^-1 by Gauss-Jordan (partial pivoting) */
static double jac[N][6], hinv[6][6];

/* |t + R c - c|, c the mean of all origins */
static double travel_of(int n, const double R[9], const double t[3])
{
    double c[3] = {0, 0, 0}, rc[3], v[3];
    int k, i;
    for (k = 0; k < n; ++k)
        for (i = 0; i < 3; ++i)
            c[i] += (o1[3 * k + i] + o2[3 * k + i]) / (2.0 * n);
    mat_vec3(R, c, rc);
    for (i = 0; i < 3; ++i)
        v[i] = t[i] + rc[i] - c[i];
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

/* left-perturbed rotation exp([w]x) R */
static void left(const double w[3], const double R[9], double out[9])
{
    double dr[9];
    int i, j, q;
    mcg_rot_from_angle_axis(w, dr);
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) {
            out[3 * i + j] = 0.0;
            for (q = 0; q < 3; ++q)
                out[3 * i + j] += dr[3 * i + q] * R[3 * q + j];
        }
}

/* the motion moved by +-eps along parameter a of [dw, dt] (the rotation on
 * the left): (Rp, tp) and (Rm, tm) */
static void perturbed(int a, double eps, const double R[9], const double t[3], double Rp[9],
                      double tp[3], double Rm[9], double tm[3])
{
    double w[3] = {0, 0, 0};
    memcpy(Rp, R, 9 * sizeof(double));
    memcpy(Rm, R, 9 * sizeof(double));
    memcpy(tp, t, 3 * sizeof(double));
    memcpy(tm, t, 3 * sizeof(double));
    if (a < 3) {
        w[a] = eps;
        left(w, R, Rp);
        w[a] = -eps;
        left(w, R, Rm);
    } else {
        tp[a - 3] += eps;
        tm[a - 3] -= eps;
    }
}

static int reference(int n, const double R[9], const double t[3], int hold, double *lev)
{
    static double rp[N], rm[N];
    double h[6][12], eps = 1e-6;
    int p0 = hold ? 3 : 0, np = 6 - p0, a, b, k, c;
    for (a = p0; a < 6; ++a) {
        double Rp[9], Rm[9], tp[3], tm[3];
        perturbed(a, eps, R, t, Rp, tp, Rm, tm);
        if (mcg_gec_residuals(n, o1, d1, o2, d2, Rp, tp, rp) != MCG_OK ||
            mcg_gec_residuals(n, o1, d1, o2, d2, Rm, tm, rm) != MCG_OK)
            return -1;
        for (k = 0; k < n; ++k)
            jac[k][a] = (rp[k] - rm[k]) / (2.0 * eps);
    }
    for (a = 0; a < np; ++a)
        for (b = 0; b < 2 * np; ++b) {
            h[a][b] = b == np + a ? 1.0 : 0.0;
            if (b < np)
                for (k = 0; k < n; ++k)
                    h[a][b] += jac[k][p0 + a] * jac[k][p0 + b];
        }
    for (c = 0; c < np; ++c) {
        int piv = c;
        double f;
        for (a = c + 1; a < np; ++a)
            if (fabs(h[a][c]) > fabs(h[piv][c]))
                piv = a;
        for (b = 0; b < 2 * np; ++b) {
            double tmp = h[c][b];
            h[c][b] = h[piv][b];
            h[piv][b] = tmp;
        }
        f = h[c][c];
        for (b = 0; b < 2 * np; ++b)
            h[c][b] /= f;
        for (a = 0; a < np; ++a)
            if (a != c) {
                f = h[a][c];
                for (b = 0; b < 2 * np; ++b)
                    h[a][b] -= f * h[c][b];
            }
    }
    for (a = 0; a < np; ++a)
        for (b = 0; b < np; ++b)
            hinv[a][b] = h[a][np + b];
    for (k = 0; k < n; ++k) {
        double s = 0.0;
        for (a = 0; a < np; ++a)
            for (b = 0; b < np; ++b)
                s += jac[k][p0 + a] * h[a][np + b] * jac[k][p0 + b];
        lev[k] = s;
    }
    return 0;
}

/* the reference's largest |change of the travel| on deleting one pair,
 * g^T H^-1 J_k^T r_k / (1 - h_k) with g by central differences of
 * travel_of, the travel's std and the root sum of squares of the changes
 * (travel_std_hc); after reference() */
static double reference_influence(int n, const double R[9], const double t[3], int hold,
                                  const double *lev, int *at, double *sd, double *hc)
{
    static double r[N];
    double g[6], eps = 1e-6, best = -1.0, ssr = 0.0, gg = 0.0, sq = 0.0;
    int p0 = hold ? 3 : 0, np = 6 - p0, a, b, k;
    for (a = 0; a < 6; ++a) {
        double Rp[9], Rm[9], tp[3], tm[3];
        perturbed(a, eps, R, t, Rp, tp, Rm, tm);
        g[a] = (travel_of(n, Rp, tp) - travel_of(n, Rm, tm)) / (2.0 * eps);
    }
    mcg_gec_residuals(n, o1, d1, o2, d2, R, t, r);
    for (k = 0; k < n; ++k) {
        double q = 0.0;
        ssr += r[k] * r[k];
        for (a = 0; a < np; ++a)
            for (b = 0; b < np; ++b)
                q += g[p0 + a] * hinv[a][b] * jac[k][p0 + b];
        q = fabs(q * r[k]) / (1.0 - lev[k]);
        sq += q * q;
        if (q > best) {
            best = q;
            *at = k;
        }
    }
    for (a = 0; a < np; ++a)
        for (b = 0; b < np; ++b)
            gg += g[p0 + a] * hinv[a][b] * g[p0 + b];
    *sd = sqrt(ssr / (n - np) * gg);
    *hc = sqrt(sq);
    return best;
}

int main(void)
{
    double R[9], t[3] = {0.6, -0.3, 0.1}, axis[3] = {0.2, 0.3, 1.0}, lev[N], ref[N], big;
    double top, sum, err;
    int hold, k, at, st;
    mcg_leverage_result lr;

    rot_about(axis, 0.2, R);
    ring_scene(R, t);
    for (hold = 0; hold <= 1; ++hold) {
        char what[96];
        st = mcg_sampson_leverage(N, o1, d1, o2, d2, NULL, R, t, hold, lev, &lr);
        top = lr.max_leverage;
        at = lr.leverage_pair;
        check_status(st, MCG_OK, hold ? "ring, R held: status" : "ring: status");
        if (reference(N, R, t, hold, ref) != 0)
            check(0, "reference residuals", 0.0, 0.0);
        err = 0.0;
        sum = 0.0;
        big = -1.0;
        for (k = 0; k < N; ++k) {
            err = fmax(err, fabs(lev[k] - ref[k]));
            sum += lev[k];
            big = fmax(big, lev[k]);
        }
        snprintf(what, sizeof what, "%s: leverage against finite differences",
                 hold ? "R held" : "6 dof");
        check(err < 1e-6, what, err, 1e-6);
        snprintf(what, sizeof what, "%s: leverages sum to the parameters", hold ? "R held"
                                                                            : "6 dof");
        check(fabs(sum - (hold ? 3.0 : 6.0)) < 1e-9, what, fabs(sum - (hold ? 3.0 : 6.0)),
              1e-9);
        check(top == big && at >= 0 && lev[at] == top, "max_leverage and its pair are the array's",
              fabs(top - big), 0.0);
        {
            int kr = -1;
            double sd, hc, inf = reference_influence(N, R, t, hold, ref, &kr, &sd, &hc);
            double trv = travel_of(N, R, t);
            snprintf(what, sizeof what,
                     "%s: largest deletion influence, its pair, the std, the HC3 std",
                     hold ? "R held" : "6 dof");
            err = fmax(fmax(fabs(lr.max_influence - inf / trv) / (inf / trv),
                            fabs(lr.travel_std - sd) / sd),
                       fabs(lr.travel_std_hc - hc) / hc);
            check(err < 1e-5 && lr.influence_pair == kr && fabs(lr.travel - trv) < 1e-12 &&
                      fabs(lr.max_influence_stds - inf / sd) < 1e-5 * inf / sd,
                  what, err, 1e-5);
        }
    }
    /* the world in millimetres: the same leverages */
    {
        double tm[3];
        static double lev_mm[N];
        for (k = 0; k < 3 * N; ++k) {
            o1[k] *= 1000.0;
            o2[k] *= 1000.0;
        }
        for (k = 0; k < 3; ++k)
            tm[k] = 1000.0 * t[k];
        (void)mcg_sampson_leverage(N, o1, d1, o2, d2, NULL, R, tm, 0, lev_mm, NULL);
        for (k = 0; k < 3 * N; ++k) {
            o1[k] /= 1000.0;
            o2[k] /= 1000.0;
        }
        (void)mcg_sampson_leverage(N, o1, d1, o2, d2, NULL, R, t, 0, lev, NULL);
        for (k = 0; k < 3 * N; ++k) {
            o1[k] *= 1000.0;
            o2[k] *= 1000.0;
        }
        st = mcg_sampson_leverage(N, o1, d1, o2, d2, NULL, R, tm, 0, lev_mm, NULL);
        err = 0.0;
        for (k = 0; k < N; ++k)
            err = fmax(err, fabs(lev_mm[k] - lev[k]));
        check(st == MCG_OK && err < 1e-8, "metres -> millimetres: the same leverages", err,
              1e-8);
        for (k = 0; k < 3 * N; ++k) {
            o1[k] /= 1000.0;
            o2[k] /= 1000.0;
        }
    }
    /* weights: all 1 as none, all 2 the same leverages, a zero weight as
     * the pair deleted; negative or NaN weights refused */
    {
        static double wt[N], lev_w[N], lev_d[N];
        static double so1[3 * N], sd1[3 * N], so2[3 * N], sd2[3 * N];
        mcg_leverage_result l1, l2;
        int m = 0, q;
        ring_scene(R, t);
        (void)mcg_sampson_leverage(N, o1, d1, o2, d2, NULL, R, t, 0, lev, &l1);
        for (k = 0; k < N; ++k)
            wt[k] = 1.0;
        st = mcg_sampson_leverage(N, o1, d1, o2, d2, wt, R, t, 0, lev_w, &l2);
        check(st == MCG_OK && memcmp(lev, lev_w, sizeof lev) == 0 &&
                  memcmp(&l1, &l2, sizeof l1) == 0,
              "weights of 1: the same as none", 0.0, 0.0);
        for (k = 0; k < N; ++k)
            wt[k] = 2.0;
        st = mcg_sampson_leverage(N, o1, d1, o2, d2, wt, R, t, 0, lev_w, &l2);
        err = 0.0;
        for (k = 0; k < N; ++k)
            err = fmax(err, fabs(lev_w[k] - lev[k]));
        check(st == MCG_OK && err < 1e-12 &&
                  fabs(l2.travel_std - l1.travel_std) < 1e-12 * l1.travel_std &&
                  fabs(l2.travel_std_hc - l1.travel_std_hc) < 1e-12 * l1.travel_std_hc,
              "weights of 2: the same leverages, std and HC3 std", err, 1e-12);
        for (k = 0; k < N; ++k) {
            wt[k] = k == 9 ? 0.0 : 1.0;
            if (k != 9) {
                for (q = 0; q < 3; ++q) {
                    so1[3 * m + q] = o1[3 * k + q];
                    sd1[3 * m + q] = d1[3 * k + q];
                    so2[3 * m + q] = o2[3 * k + q];
                    sd2[3 * m + q] = d2[3 * k + q];
                }
                ++m;
            }
        }
        st = mcg_sampson_leverage(N, o1, d1, o2, d2, wt, R, t, 0, lev_w, &l1);
        (void)mcg_sampson_leverage(m, so1, sd1, so2, sd2, NULL, R, t, 0, lev_d, &l2);
        err = fabs(lev_w[9]);
        for (k = 0, m = 0; k < N; ++k)
            if (k != 9)
                err = fmax(err, fabs(lev_w[k] - lev_d[m++]));
        check(st == MCG_OK && err < 1e-12 && fabs(l1.travel - l2.travel) < 1e-12 &&
                  fabs(l1.travel_std - l2.travel_std) < 1e-12 * l2.travel_std &&
                  fabs(l1.max_influence - l2.max_influence) < 1e-12 &&
                  fabs(l1.travel_std_hc - l2.travel_std_hc) < 1e-12 * l2.travel_std_hc,
              "a zero weight: the pair deleted", err, 1e-12);
        wt[3] = -1.0;
        check_status(mcg_sampson_leverage(N, o1, d1, o2, d2, wt, R, t, 0, lev, NULL), MCG_EINVAL,
                     "a negative weight");
        wt[3] = NAN;
        check_status(mcg_sampson_leverage(N, o1, d1, o2, d2, wt, R, t, 0, lev, NULL), MCG_EINVAL,
                     "a NaN weight");
    }
    /* a gross outlier among the pairs that fix the scale: the last
     * cross-camera pair's time-2 bearing turned away, the motion refined on
     * every pair (least squares): the fit absorbs it, and the outlier has
     * the largest influence on the travel, many stds */
    {
        double Rf[9], tf[3];
        mcg_refine_result rr;
        rng_state = TEST_SEED; /* the scene of the first checks */
        ring_scene(R, t);
        d2[3 * (N - 1)] += 1.0;
        d2[3 * (N - 1) + 2] -= 1.0;
        memcpy(Rf, R, sizeof Rf);
        memcpy(tf, t, sizeof tf);
        st = mcg_refine_motion(N, o1, d1, o2, d2, NULL, NULL, Rf, tf, &rr);
        check_status(st, MCG_OK, "least-squares fit with the outlier");
        st = mcg_sampson_leverage(N, o1, d1, o2, d2, NULL, Rf, tf, 0, NULL, &lr);
        check(st == MCG_OK && lr.influence_pair == N - 1 && lr.max_influence_stds > 4.0,
              "the outlier has the largest influence, > 4 stds", lr.max_influence_stds, 4.0);
        /* its own residual, far beyond the others', tells a larger std
         * than the common noise level does */
        check(lr.travel_std_hc > 2.0 * lr.travel_std,
              "the outlier: the HC3 std > 2 x the std of one noise level",
              lr.travel_std_hc / lr.travel_std, 2.0);
    }
    /* one camera at the origin (its pairs fix R and the direction of t) and
     * one pair from another centre: that pair alone fixes |t| */
    {
        double c0[3] = {0, 0, 0}, ca[3] = {0.4, 0.1, 0.0}, cb[3] = {0.4, 0.1, 0.0};
        double ax[3] = {1.0, 0.2, 0.1}, ax2[3] = {0.2, 1.0, 0.1};
        for (k = 0; k < 30; ++k)
            make_pair(k, c0, c0, ax, R, t);
        make_pair(30, ca, cb, ax2, R, t);
        st = mcg_sampson_leverage(31, o1, d1, o2, d2, NULL, R, t, 0, lev, &lr);
        top = lr.max_leverage;
        at = lr.leverage_pair;
        check(st == MCG_OK && at == 30 && top > 1.0 - 1e-6,
              "the only pair off the centre: leverage 1", 1.0 - top, 1e-6);
        st = mcg_sampson_leverage(30, o1, d1, o2, d2, NULL, R, t, 0, lev, &lr);
        check_status(st, MCG_EDEGENERATE, "one centre alone: |t| undetermined");
    }
    ring_scene(R, t);
    check_status(mcg_sampson_leverage(5, o1, d1, o2, d2, NULL, R, t, 0, lev, NULL),
                 MCG_EDEGENERATE, "5 pairs, 6 parameters");
    check_status(mcg_sampson_leverage(0, o1, d1, o2, d2, NULL, R, t, 0, lev, &lr),
                 MCG_EDEGENERATE, "no pairs");
    check_status(mcg_sampson_leverage(N, NULL, d1, o2, d2, NULL, R, t, 0, lev, NULL),
                 MCG_EINVAL, "NULL origins");
    check_status(mcg_sampson_leverage(N, o1, d1, o2, d2, NULL, R, t, 2, lev, NULL), MCG_EINVAL,
                 "hold_rotation 2");
    check_status(mcg_sampson_leverage(-1, o1, d1, o2, d2, NULL, R, t, 0, lev, NULL),
                 MCG_EINVAL, "n = -1");
    {
        double Rn[9];
        memcpy(Rn, R, sizeof Rn);
        Rn[4] = NAN;
        check_status(mcg_sampson_leverage(N, o1, d1, o2, d2, NULL, Rn, t, 0, lev, NULL),
                     MCG_EINVAL, "NaN in R");
        d2[3 * 7] = d2[3 * 7 + 1] = d2[3 * 7 + 2] = 0.0;
        check_status(mcg_sampson_leverage(N, o1, d1, o2, d2, NULL, R, t, 0, lev, NULL),
                     MCG_EINVAL, "a zero direction");
    }
    printf("%d checks, %d failed\n", n_checks, n_failed);
    return n_failed != 0;
}
