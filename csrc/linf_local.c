/*
 * linf_local.c -- local minimisation of the L-infinity angular error of a
 * rig motion over (R, t) jointly: the bottom of the basin the branch and
 * bound of bnb.c has located to its resolution (thesis ch. 10; the thesis
 * stops at the block centre).
 *
 * Per-correspondence error in closed form. For rotation R and translation t
 * (X2 = R X1 + t), correspondence i with unit bearings u1, u2 and origins
 * a1, a2 has the rotated bearing v = R u1, the baseline b = t - (a2 - R a1)
 * (t relative to the wedge's apex, bnb.c) and, with m = u2 - v (the wedge's
 * centre direction, wedge.c) and w = v x u2 (the epipolar plane's normal),
 * both of its wedges of eqs. 10.9-10.12 at equal half-angles e hold iff
 *     sin e >= sin(alpha / 2) |w^.b| / sqrt((m^.b)^2 + (w^.b)^2),  m^.b > 0
 * (hats: unit vectors; alpha = angle(v, u2), |m| = 2 sin(alpha / 2)): with
 * eps = eps' the wedge normals are n = y +- r w^, y = sin(e) m^ / sin(alpha/2)
 * and r = sqrt(1 - |y|^2), and n.b >= 0 for both signs squares to the bound.
 * So the error of correspondence i is e_i(R, t) = asin of the right-hand
 * side, and the L-infinity problem of bnb.c is min over (R, t) of max_i e_i
 * (where every m^.b > 0; the per-camera non-zero-direction condition of
 * bnb.c is then inactive).
 *
 * Method: Madsen's trust-region sequential linear programming for minimax
 * problems. The functions are the signed g_i = sin(alpha/2) (w^.b) / rho
 * and -g_i (their maximum is sin e_i), differentiated numerically (central
 * differences) in x = (omega, t), R = exp([omega]x) R_0. Each step solves
 *     min eta  s.t.  g_j + grad g_j . h <= eta,  |h|_inf <= Delta
 * (a 7-variable LP, solved through its dual by a dense revised simplex: 7
 * equality rows, one column per function and per box side) and the step is
 * kept when the true maximum decreases by a fair share of the predicted
 * decrease. It converges to a stationary point of the maximum (zero in the
 * convex hull of the active gradients), quadratically where 7 functions are
 * active, where a Nelder-Mead on f(R) stalls on the ridges of a maximum of
 * smooth functions. The caller verifies the result with the exact LP test
 * (bnb.c), so an invalid model (a baseline leaving a wedge's front) can
 * only cost the step, never give a wrong answer.
 */
#include "mcgeom.h"
#include "internal.h"

#include <math.h>
#include <string.h>

#define NV 6            /* omega (3), t (3) */
#define NR (NV + 1)     /* rows of the dual LP */
#define LP_MAX_ITER 400 /* simplex pivots per step */

/* g of one correspondence from the rotated bearing v, the rotated origin
 * ra1 = R a1 and t, and its gradient in (omega, t) (grad may be NULL):
 * 1 and *g set where m^.b > 0 and the rays are not parallel, else 0 (then
 * *g = sin(alpha / 2), the error for every b). With P = m^.b, Q = w^.b,
 * rho^2 = P^2 + Q^2 and g = |m| Q / (2 rho):
 *   dg = d|m| Q / (2 rho) + |m| P (P dQ - Q dP) / (2 rho^3),
 * dP = dm^.b + m^.db, dQ = dw^.b + w^.db, dx^ = (dx - x^ (x^.dx)) / |x|;
 * a rotation delta about e_k (R -> exp([delta]x) R) moves v by e_k x v and
 * b by e_k x (R a1) per unit angle; t moves b by e_k. */
static int signed_error(const double v[3], const double ra1[3], const double u2[3],
                        const double a2[3], const double t[3], double *g, double grad[NV])
{
    double m[3], w[3], b[3], mh[3], wh[3], nm, nw, p, q, rho, c1, c2;
    int k, j;
    for (k = 0; k < 3; ++k) {
        m[k] = u2[k] - v[k];
        b[k] = t[k] - a2[k] + ra1[k];
    }
    cross3(v, u2, w);
    nm = sqrt(dot3(m, m));
    nw = sqrt(dot3(w, w));
    *g = 0.5 * nm;
    if (!(nw > 1e-12 && nm > 1e-12))
        return 0;
    for (k = 0; k < 3; ++k) {
        mh[k] = m[k] / nm;
        wh[k] = w[k] / nw;
    }
    p = dot3(mh, b);
    q = dot3(wh, b);
    rho = sqrt(p * p + q * q);
    if (!(p > 1e-12 * rho) || !(rho > 0.0))
        return 0;
    *g = 0.5 * nm * q / rho;
    if (!grad)
        return 1;
    c1 = 0.5 * q / rho;                     /* coefficient of d|m| */
    c2 = 0.5 * nm * p / (rho * rho * rho);  /* of (P dQ - Q dP) */
    for (k = 0; k < 3; ++k) {
        /* translation: db = e_k */
        grad[3 + k] = c2 * (p * wh[k] - q * mh[k]);
    }
    for (k = 0; k < 3; ++k) {
        double e[3] = {0.0, 0.0, 0.0}, dv[3], db[3], dm[3], dw[3], dmh[3], dwh[3], dnm, dp, dq, s;
        e[k] = 1.0;
        cross3(e, v, dv);
        cross3(e, ra1, db);
        for (j = 0; j < 3; ++j)
            dm[j] = -dv[j];
        cross3(dv, u2, dw);
        dnm = dot3(mh, dm);
        s = dot3(wh, dw);
        for (j = 0; j < 3; ++j) {
            dmh[j] = (dm[j] - mh[j] * dnm) / nm;
            dwh[j] = (dw[j] - wh[j] * s) / nw;
        }
        dp = dot3(dmh, b) + dot3(mh, db);
        dq = dot3(dwh, b) + dot3(wh, db);
        grad[k] = c1 * dnm + c2 * (p * dq - q * dp);
    }
    return 1;
}

/* The values g (n; NaN where invalid) and gradients G (n x 6, may be NULL)
 * at (R, t); returns the maximum of |g| over all correspondences, an
 * invalid one counting with sin(alpha / 2); *n_bad: how many invalid ones
 * reach that maximum (no linear model represents them). */
static double evaluate(int n, const double *u1, const double *a1, const double *u2,
                       const double *a2, const double R[9], const double t[3],
                       double *g, double *G, int *n_bad)
{
    double fmax = 0.0, bad_max = 0.0;
    int i, bad = 0;
    for (i = 0; i < n; ++i) {
        double v[3], ra1[3], gi;
        mat_vec(R, u1 + 3 * i, v);
        mat_vec(R, a1 + 3 * i, ra1);
        if (!signed_error(v, ra1, u2 + 3 * i, a2 + 3 * i, t, &gi, G ? G + NV * i : NULL)) {
            g[i] = NAN;
            if (gi > bad_max)
                bad_max = gi;
            ++bad;
            continue;
        }
        g[i] = gi;
        if (fabs(gi) > fmax)
            fmax = fabs(gi);
    }
    *n_bad = bad_max >= fmax ? bad : 0;
    return bad_max > fmax ? bad_max : fmax;
}

/* Gaussian elimination with partial pivoting on the NR x NR system
 * A x = b (A destroyed, x over b); 0 if singular. */
static int solve_small(double A[NR][NR], double b[NR])
{
    int i, j, k;
    for (k = 0; k < NR; ++k) {
        int p = k;
        double big = fabs(A[k][k]);
        for (i = k + 1; i < NR; ++i)
            if (fabs(A[i][k]) > big) {
                big = fabs(A[i][k]);
                p = i;
            }
        if (!(big > 1e-300))
            return 0;
        if (p != k) {
            double tmp;
            for (j = 0; j < NR; ++j) {
                tmp = A[k][j];
                A[k][j] = A[p][j];
                A[p][j] = tmp;
            }
            tmp = b[k];
            b[k] = b[p];
            b[p] = tmp;
        }
        for (i = k + 1; i < NR; ++i) {
            double f = A[i][k] / A[k][k];
            if (f == 0.0)
                continue;
            for (j = k; j < NR; ++j)
                A[i][j] -= f * A[k][j];
            b[i] -= f * b[k];
        }
    }
    for (k = NR - 1; k >= 0; --k) {
        double s = b[k];
        for (j = k + 1; j < NR; ++j)
            s -= A[k][j] * b[j];
        b[k] = s / A[k][k];
    }
    return 1;
}

/* Column `col` of the dual LP: columns 0 .. 2 nf - 1 are the functions
 * (+g_i, then -g_i, of the nf valid ones listed in idx), then the box
 * sides mu+_k (e_k) and mu-_k (-e_k). Objective coefficient in *p. */
static void dual_column(int col, int nf, const int *idx, const double *g, const double *G,
                        double delta, double c[NR], double *p)
{
    int k;
    memset(c, 0, NR * sizeof(double));
    if (col < 2 * nf) {
        int i = idx[col < nf ? col : col - nf];
        double s = col < nf ? 1.0 : -1.0;
        for (k = 0; k < NV; ++k)
            c[k] = s * G[NV * i + k];
        c[NV] = 1.0;
        *p = s * g[i];
    } else {
        int b = col - 2 * nf;
        c[b % NV] = b < NV ? 1.0 : -1.0;
        *p = -delta;
    }
}

/* Basis matrix, its transpose system for the multipliers, and the basic
 * values: B y_B = q (q = e_last), B^T pi = p_B. */
static int basis_solve(const int basis[NR], int nf, const int *idx, const double *g,
                       const double *G, double delta, double yB[NR], double pi[NR])
{
    double B[NR][NR], BT[NR][NR], col[NR], pB[NR];
    int i, j;
    for (j = 0; j < NR; ++j) {
        dual_column(basis[j], nf, idx, g, G, delta, col, &pB[j]);
        for (i = 0; i < NR; ++i) {
            B[i][j] = col[i];
            BT[j][i] = col[i];
        }
    }
    for (i = 0; i < NR; ++i)
        yB[i] = i == NV ? 1.0 : 0.0;
    if (!solve_small(B, yB))
        return 0;
    memcpy(pi, pB, sizeof pB);
    return solve_small(BT, pi);
}

/* The step h (|h|_inf <= delta) minimising max_j (g_j + G_j h) over the nf
 * valid functions (both signs), from the dual: max p.y s.t. M y = e_last,
 * y >= 0, whose multipliers are (-h, eta). Returns 1 with h set, 0 if the
 * simplex failed (singular basis or the pivot budget). */
static int minimax_step(int nf, const int *idx, const double *g, const double *G,
                        double delta, double h[NV])
{
    int basis[NR], it, k, j0 = 0, degenerate = 0, ncol = 2 * nf + 2 * NV;
    double yB[NR], pi[NR], best = -INFINITY;
    /* start: the largest function alone, the box sides balancing its
     * gradient (feasible: y = 1 on it, |grad| on the sides) */
    for (k = 0; k < 2 * nf; ++k) {
        double gv = (k < nf ? 1.0 : -1.0) * g[idx[k < nf ? k : k - nf]];
        if (gv > best) {
            best = gv;
            j0 = k;
        }
    }
    {
        double c[NR], p;
        dual_column(j0, nf, idx, g, G, delta, c, &p);
        basis[NV] = j0;
        for (k = 0; k < NV; ++k)
            basis[k] = 2 * nf + (c[k] <= 0.0 ? k : NV + k);
    }
    for (it = 0; it < LP_MAX_ITER; ++it) {
        double dmax = 0.0, scale = 0.0, c[NR], p, dir[NR], B[NR][NR], theta = INFINITY;
        int enter = -1, leave = -1, i, j, in_basis;
        if (!basis_solve(basis, nf, idx, g, G, delta, yB, pi))
            return 0;
        for (k = 0; k < NR; ++k)
            if (fabs(pi[k]) > scale)
                scale = fabs(pi[k]);
        /* pricing: Dantzig's rule, Bland's (first improving) after a run of
         * degenerate pivots so that the simplex cannot cycle */
        for (j = 0; j < ncol; ++j) {
            double d, mag = 0.0;
            for (in_basis = 0, i = 0; i < NR; ++i)
                if (basis[i] == j)
                    in_basis = 1;
            if (in_basis)
                continue;
            dual_column(j, nf, idx, g, G, delta, c, &p);
            d = p;
            for (i = 0; i < NR; ++i) {
                d -= pi[i] * c[i];
                mag += fabs(pi[i] * c[i]);
            }
            if (d > 1e-13 * (fabs(p) + mag) + 1e-300 && d > dmax) {
                dmax = d;
                enter = j;
                if (degenerate > 20)
                    break;
            }
        }
        if (enter < 0)
            break; /* optimal */
        dual_column(enter, nf, idx, g, G, delta, c, &p);
        for (j = 0; j < NR; ++j) {
            double cj[NR], pj;
            dual_column(basis[j], nf, idx, g, G, delta, cj, &pj);
            for (i = 0; i < NR; ++i)
                B[i][j] = cj[i];
        }
        memcpy(dir, c, sizeof dir);
        if (!solve_small(B, dir))
            return 0;
        for (i = 0; i < NR; ++i)
            if (dir[i] > 1e-12) {
                double r = (yB[i] > 0.0 ? yB[i] : 0.0) / dir[i];
                if (r < theta || (r == theta && leave >= 0 && basis[i] < basis[leave])) {
                    theta = r;
                    leave = i;
                }
            }
        if (leave < 0)
            return 0; /* unbounded: impossible with the box, numerics */
        degenerate = theta <= 0.0 ? degenerate + 1 : 0;
        basis[leave] = enter;
        (void)scale;
    }
    if (it == LP_MAX_ITER)
        return 0;
    for (k = 0; k < NV; ++k) {
        h[k] = -pi[k];
        if (h[k] > delta)
            h[k] = delta;
        if (h[k] < -delta)
            h[k] = -delta;
    }
    return 1;
}

static void rotate_by(const double w[3], const double R[9], double out[9])
{
    double E[9];
    int i, j, k;
    mcg_rot_from_angle_axis(w, E);
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) {
            double s = 0.0;
            for (k = 0; k < 3; ++k)
                s += E[3 * i + k] * R[3 * k + j];
            out[3 * i + j] = s;
        }
}

int mcg_linf_local(int n, const double *u1, const double *a1, const double *u2,
                   const double *a2, double R[9], double t[3], double delta0,
                   double delta_min, int max_steps, double *work, double *f_out,
                   int *steps_out)
{
    double *g, *G, *gt, F, delta = delta0;
    int *idx;
    int step, nbad;
    if (n < 1 || (size_t)n > MAX_ROWS || !u1 || !a1 || !u2 || !a2 || !R || !t || !work ||
        max_steps < 0 || !(delta0 > 0.0) || !isfinite(delta0) || !(delta_min > 0.0) ||
        !(delta_min <= delta0) || !all_finite(R, 9) || !all_finite(t, 3))
        return MCG_EINVAL;
    /* carved only once work is known to be non-NULL (offsets from NULL are
     * undefined behaviour) */
    g = work;
    G = work + n;
    idx = (int *)(void *)(work + 7 * (size_t)n);
    gt = work + 8 * (size_t)n;
    F = evaluate(n, u1, a1, u2, a2, R, t, g, G, &nbad);
    for (step = 0; step < max_steps; ++step) {
        double h[NV], Rn[9], tn[3], Fn, pred, model = 0.0;
        int nf = 0, i, k, nbad_n;
        if (nbad > 0)
            break; /* an invalid function at the maximum: no model */
        for (i = 0; i < n; ++i)
            if (!isnan(g[i]))
                idx[nf++] = i;
        if (nf == 0 || !minimax_step(nf, idx, g, G, delta, h))
            break;
        for (i = 0; i < nf; ++i) {
            double v = g[idx[i]];
            for (k = 0; k < NV; ++k)
                v += G[NV * idx[i] + k] * h[k];
            if (fabs(v) > model)
                model = fabs(v);
        }
        pred = F - model;
        if (!(pred > 1e-16 * (F + 1e-300)))
            break; /* stationary to rounding */
        rotate_by(h, R, Rn);
        for (k = 0; k < 3; ++k)
            tn[k] = t[k] + h[3 + k];
        /* values only (gt); values and gradients again if the step is kept */
        Fn = evaluate(n, u1, a1, u2, a2, Rn, tn, gt, NULL, &nbad_n);
        if (nbad_n == 0 && F - Fn > 0.01 * pred) {
            memcpy(R, Rn, sizeof Rn);
            memcpy(t, tn, sizeof tn);
            if (F - Fn > 0.75 * pred)
                delta *= 2.0;
            F = evaluate(n, u1, a1, u2, a2, R, t, g, G, &nbad);
        } else {
            delta *= 0.25;
        }
        if (delta < delta_min)
            break;
    }
    if (f_out)
        *f_out = F;
    if (steps_out)
        *steps_out = step;
    return MCG_OK;
}
