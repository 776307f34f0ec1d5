/*
 * linear17_sampson.c -- the geometric refinement of linear17 (csrc/linear17.c):
 * Levenberg-Marquardt on the Sampson angular error of the generalized
 * epipolar constraint (eq. 8.15 read as each camera pair's epipolar
 * constraint), from the linear estimate, and the relative std of |t| from
 * its Gauss-Newton information.
 */
#include "linear17_internal.h"

#include <float.h>
#include <math.h>
#include <string.h>

#define HALF_PI 1.5707963267948966
#define INV_HALF_PI2 0.40528473456935109 /* (2 / pi)^2 */

/* One pass over the rays at the motion (R, t) of the normalised frame: the
 * sum of the squared Sampson angular errors of the generalized epipolar
 * constraint (eq. 8.15 read as the epipolar constraint of the camera pair,
 * F = [c]x R with c = t + R o1 - o2; the residual of csrc/refine.c and
 * mcg_gec_residuals, radians, invariant to the normalisation), and with h
 * and g non-NULL the Gauss-Newton normal equations J^T J (6 x 6, upper
 * triangle, order [dw, dt] of R <- exp([dw]x) R, t <- t + dt) and J^T r.
 * r is homogeneous of degree 0 in the directions, so they are used as given
 * (no square root to normalise them). With a = R d1, b = d2, p = R o1'
 * (o1' the normalised origin) and the dot products aa = |a|^2, bb = |b|^2,
 * cc = |c|^2, ac = a.c, bc = b.c, ab = a.b, n = a x b:
 *   e = b.(c x a) = c.n,
 *   D = bb |c x a|^2 + aa |b x c|^2 - 2 e^2
 *     = c.s - 2 e^2,  s = 2 aa bb c - bb ac a - aa bc b,
 *   r = e / sqrt(D),
 *   de/dw = p x n + a x (b x c) = p x n + ac b - ab c,   de/dt = n,
 *   dD/dt = 2 s - 4 e n,
 *   dD/dw = 2 (p x s + bb ac (c x a)) - 4 e de/dw
 * (the identities a x (c x a) = aa c - ac a, (b x c) x b = bb c - bc b and
 * a x ((c x a) x c) = ac (c x a) turn the cross products of the direct
 * derivation into dot products), dr = de / sqrt(D) - e dD / (2 D^(3/2)).
 * Where D vanishes the residual is capped at +-pi/2 (as in refine.c) and
 * contributes no Jacobian row.
 * Why blocks of SAMPSON_LANES rays, one array element per ray: every
 * quantity above is computed for the whole block by loops of fixed length
 * that the compiler turns into SIMD instructions (issue 22: this pass is
 * most of the kernel's cost per ray); a ray that fails the test above is
 * masked out of the sums instead of branched around. The sums are kept per
 * lane and added at the end. */
#define SAMPSON_LANES 4

MCG_AVX2_CLONE
static double sampson_pass(const raydata *rd, const double r[9], const double t[3],
                           double h[36], double g[6])
{
    double hl[21][SAMPSON_LANES], gl[6][SAMPSON_LANES], cl[SAMPSON_LANES];
    double ro[3], sr[9];
    int k0, i, j, l, q;
    /* p = R o1' = s R o1 - s R o: s R and s R o once per pass */
    for (i = 0; i < 9; i++)
        sr[i] = rd->scale * r[i];
    mat_vec(sr, rd->origin, ro);
    memset(hl, 0, sizeof hl);
    memset(gl, 0, sizeof gl);
    memset(cl, 0, sizeof cl);
    for (k0 = 0; k0 < rd->n; k0 += SAMPSON_LANES) {
        double a[3][SAMPSON_LANES], b[3][SAMPSON_LANES], p[3][SAMPSON_LANES];
        double c[3][SAMPSON_LANES], nn[3][SAMPSON_LANES];
        double aa[SAMPSON_LANES], bb[SAMPSON_LANES], e[SAMPSON_LANES];
        double dd[SAMPSON_LANES], res[SAMPSON_LANES], isd[SAMPSON_LANES];
        double ok[SAMPSON_LANES], cap[SAMPSON_LANES];
        double o1[3][SAMPSON_LANES], d1[3][SAMPSON_LANES], q2[3][SAMPSON_LANES];
        int nb = rd->n - k0 < SAMPSON_LANES ? rd->n - k0 : SAMPSON_LANES;
        /* the block by coordinate; lanes past the end get zero directions
         * (e = 0: they add nothing) */
        for (l = 0; l < SAMPSON_LANES; l++) {
            int kk = k0 + (l < nb ? l : 0);
            double z = l < nb ? 1.0 : 0.0;
            for (i = 0; i < 3; i++) {
                o1[i][l] = rd->o1[3 * kk + i];
                d1[i][l] = z * rd->d1[3 * kk + i];
                b[i][l] = z * rd->d2[3 * kk + i];
                q2[i][l] = rd->scale * (rd->o2[3 * kk + i] - rd->origin[i]);
            }
        }
        for (i = 0; i < 3; i++)
            for (l = 0; l < SAMPSON_LANES; l++) {
                a[i][l] = r[3 * i] * d1[0][l] + r[3 * i + 1] * d1[1][l] + r[3 * i + 2] * d1[2][l];
                p[i][l] = sr[3 * i] * o1[0][l] + sr[3 * i + 1] * o1[1][l] +
                          sr[3 * i + 2] * o1[2][l] - ro[i];
                c[i][l] = t[i] + p[i][l] - q2[i][l];
            }
        for (l = 0; l < SAMPSON_LANES; l++) {
            nn[0][l] = a[1][l] * b[2][l] - a[2][l] * b[1][l];
            nn[1][l] = a[2][l] * b[0][l] - a[0][l] * b[2][l];
            nn[2][l] = a[0][l] * b[1][l] - a[1][l] * b[0][l];
            aa[l] = a[0][l] * a[0][l] + a[1][l] * a[1][l] + a[2][l] * a[2][l];
            bb[l] = b[0][l] * b[0][l] + b[1][l] * b[1][l] + b[2][l] * b[2][l];
            e[l] = c[0][l] * nn[0][l] + c[1][l] * nn[1][l] + c[2][l] * nn[2][l];
        }
        {
            double s[3][SAMPSON_LANES], ac[SAMPSON_LANES], bc[SAMPSON_LANES];
            double ab[SAMPSON_LANES], ee[SAMPSON_LANES], ca[3][SAMPSON_LANES];
            /* (no inner loops and no && in the lane loops: either keeps
             * the compiler from vectorising them) */
            for (l = 0; l < SAMPSON_LANES; l++) {
                double f2 = 2.0 * aa[l] * bb[l], c0, c1, c2, x0, x1, x2;
                double y0, y1, y2;
                c0 = c[0][l];
                c1 = c[1][l];
                c2 = c[2][l];
                ac[l] = a[0][l] * c0 + a[1][l] * c1 + a[2][l] * c2;
                bc[l] = b[0][l] * c0 + b[1][l] * c1 + b[2][l] * c2;
                ab[l] = a[0][l] * b[0][l] + a[1][l] * b[1][l] + a[2][l] * b[2][l];
                s[0][l] = f2 * c0 - bb[l] * ac[l] * a[0][l] - aa[l] * bc[l] * b[0][l];
                s[1][l] = f2 * c1 - bb[l] * ac[l] * a[1][l] - aa[l] * bc[l] * b[1][l];
                s[2][l] = f2 * c2 - bb[l] * ac[l] * a[2][l] - aa[l] * bc[l] * b[2][l];
                /* D from the cross products themselves, not as c.s - 2 e^2:
                 * near the epipole (forward motion) |c x a|^2 is small and
                 * cc aa - ac^2 would lose it to cancellation */
                x0 = c1 * a[2][l] - c2 * a[1][l];
                x1 = c2 * a[0][l] - c0 * a[2][l];
                x2 = c0 * a[1][l] - c1 * a[0][l];
                ca[0][l] = x0;
                ca[1][l] = x1;
                ca[2][l] = x2;
                y0 = b[1][l] * c2 - b[2][l] * c1;
                y1 = b[2][l] * c0 - b[0][l] * c2;
                y2 = b[0][l] * c1 - b[1][l] * c0;
                ee[l] = e[l] * e[l];
                dd[l] = bb[l] * (x0 * x0 + x1 * x1 + x2 * x2) +
                        aa[l] * (y0 * y0 + y1 * y1 + y2 * y2) - 2.0 * ee[l];
            }
            /* which rays have a first-order error (D > (2/pi)^2 e^2 and
             * D > DBL_MIN): a loop of its own, since a comparison whose
             * result enters the arithmetic keeps the compiler from
             * vectorising the loop around it */
            for (l = 0; l < SAMPSON_LANES; l++) {
                double dm = INV_HALF_PI2 * ee[l];
                ok[l] = dd[l] > dm && dd[l] > DBL_MIN ? 1.0 : 0.0;
                cap[l] = ok[l] == 0.0 && e[l] != 0.0 ? HALF_PI * HALF_PI : 0.0;
            }
            for (l = 0; l < SAMPSON_LANES; l++) {
                isd[l] = ok[l] / sqrt(ok[l] * dd[l] + (1.0 - ok[l]));
                res[l] = e[l] * isd[l];
                cl[l] += res[l] * res[l] + cap[l];
            }
            if (h) {
                double jr[6][SAMPSON_LANES];
                for (l = 0; l < SAMPSON_LANES; l++) {
                    double p0 = p[0][l], p1 = p[1][l], p2 = p[2][l], fd, dw0, dw1, dw2;
                    double s0 = s[0][l], s1 = s[1][l], s2 = s[2][l];
                    double n0 = nn[0][l], n1 = nn[1][l], n2 = nn[2][l];
                    double k1 = bb[l] * ac[l], k2 = 4.0 * e[l];
                    fd = -0.5 * res[l] * isd[l] * isd[l];
                    dw0 = p1 * n2 - p2 * n1 + ac[l] * b[0][l] - ab[l] * c[0][l];
                    dw1 = p2 * n0 - p0 * n2 + ac[l] * b[1][l] - ab[l] * c[1][l];
                    dw2 = p0 * n1 - p1 * n0 + ac[l] * b[2][l] - ab[l] * c[2][l];
                    jr[0][l] = isd[l] * dw0 +
                               fd * (2.0 * (p1 * s2 - p2 * s1 + k1 * ca[0][l]) - k2 * dw0);
                    jr[1][l] = isd[l] * dw1 +
                               fd * (2.0 * (p2 * s0 - p0 * s2 + k1 * ca[1][l]) - k2 * dw1);
                    jr[2][l] = isd[l] * dw2 +
                               fd * (2.0 * (p0 * s1 - p1 * s0 + k1 * ca[2][l]) - k2 * dw2);
                    jr[3][l] = isd[l] * n0 + fd * (2.0 * s0 - k2 * n0);
                    jr[4][l] = isd[l] * n1 + fd * (2.0 * s1 - k2 * n1);
                    jr[5][l] = isd[l] * n2 + fd * (2.0 * s2 - k2 * n2);
                }
                for (i = 0; i < 6; i++)
                    for (l = 0; l < SAMPSON_LANES; l++)
                        gl[i][l] += jr[i][l] * res[l];
                for (l = 0; l < SAMPSON_LANES; l++) {
                    /* the upper triangle of J^T J, row by row */
                    hl[0][l] += jr[0][l] * jr[0][l];
                    hl[1][l] += jr[0][l] * jr[1][l];
                    hl[2][l] += jr[0][l] * jr[2][l];
                    hl[3][l] += jr[0][l] * jr[3][l];
                    hl[4][l] += jr[0][l] * jr[4][l];
                    hl[5][l] += jr[0][l] * jr[5][l];
                    hl[6][l] += jr[1][l] * jr[1][l];
                    hl[7][l] += jr[1][l] * jr[2][l];
                    hl[8][l] += jr[1][l] * jr[3][l];
                    hl[9][l] += jr[1][l] * jr[4][l];
                    hl[10][l] += jr[1][l] * jr[5][l];
                    hl[11][l] += jr[2][l] * jr[2][l];
                    hl[12][l] += jr[2][l] * jr[3][l];
                    hl[13][l] += jr[2][l] * jr[4][l];
                    hl[14][l] += jr[2][l] * jr[5][l];
                    hl[15][l] += jr[3][l] * jr[3][l];
                    hl[16][l] += jr[3][l] * jr[4][l];
                    hl[17][l] += jr[3][l] * jr[5][l];
                    hl[18][l] += jr[4][l] * jr[4][l];
                    hl[19][l] += jr[4][l] * jr[5][l];
                    hl[20][l] += jr[5][l] * jr[5][l];
                }
            }
        }
    }
    if (h) {
        for (i = 0, q = 0; i < 6; i++) {
            g[i] = 0.0;
            for (l = 0; l < SAMPSON_LANES; l++)
                g[i] += gl[i][l];
            for (j = 0; j < i; j++)
                h[6 * i + j] = 0.0;
            for (j = i; j < 6; j++, q++) {
                h[6 * i + j] = 0.0;
                for (l = 0; l < SAMPSON_LANES; l++)
                    h[6 * i + j] += hl[q][l];
            }
        }
    }
    {
        double cost = 0.0;
        for (l = 0; l < SAMPSON_LANES; l++)
            cost += cl[l];
        return cost;
    }
}

/* the plain entry of the static clone above (internal.h, MCG_AVX2_CLONE) */
double linear17_sampson_pass(const raydata *rd, const double r[9], const double t[3],
                             double h[36], double g[6])
{
    return sampson_pass(rd, r, t, h, g);
}

/* Levenberg-Marquardt on the Sampson angular error from the linear estimate
 * (R, t) of the normalised frame: the alternation of ch. 8.4.3 taken to the
 * geometric optimum instead of the algebraic one. The algebraic cost
 * x^T M x of a locally-central or axial rig vanishes at the trivial motion
 * R = I, t = 0 ((0, I) is in the null space of A), so its minimisers are
 * biased towards a short t (linear17_accuracy: median scale errors 2-3 x
 * those of the linear step); the Sampson error divides each residual by
 * its first-order sensitivity, which vanishes there, and has no such
 * minimum. A step turns R by at most 0.5 rad and moves t by at most half of
 * max(|t|, 1) (the rig size is 1 in this frame), so that a weakly observable
 * |t| does not overshoot.
 * Stopping rule: each pass over the rays costs as much as the linear step,
 * so the last step is taken without its own Gauss-Newton pass. The model
 * predicts the decrease pred = -g.d - d^T H d / 2 of the step d; near the
 * optimum pred = m^2 sigma^2 / 2, with m the length of d in standard
 * deviations of the estimate (covariance sigma^2 H^-1, sigma^2 =
 * cost / (n - 6)). A step shorter than STEP_STD standard deviations is in
 * the region where the Gauss-Newton model is accurate (the next step is
 * smaller by about m^2: 0.1 -> 4e-4 on the cases of issue 22): it is taken
 * and checked by a pass that computes the cost only (no Jacobian), and the
 * iteration stops; if the cost rose instead, the step is rejected as usual.
 * The step must also be local in absolute terms (LOCAL_STEP: 0.01 rad and
 * 1 % of |t|): where |t| is only weakly determined (near-critical motion,
 * relative std of |t| above 1) a fraction of a standard deviation is a
 * long way along a cost that is far from quadratic in |t|, and the estimate
 * slides over many steps (bad_input's pure translation: 33 steps, |t| x 30).
 * The information h is then that of the previous point, at most STEP_STD
 * standard deviations away (it only feeds the relative std of |t|). From
 * the linear step this takes two full passes and one cost pass on the
 * cases of issue 22 (five full passes before). A step whose decrease is
 * below `tolerance` of the cost is taken without any pass (it corrects the
 * last digits: exact data).
 * Returns the iterations (trial steps) taken; *cost0 is the Sampson cost at
 * the start (the linear estimate); on return h holds J^T J at (R, t) (for
 * the scale evidence) and *cost the Sampson cost there. */
#define STEP_STD 0.3

#define LOCAL_STEP 1e-2

int linear17_geometric_refine(const raydata *rd, const mcg_linear17_options *o,
                              double r[9], double t[3], double *cost, double h[36],
                              int *converged, double *cost0)
{
    double g[6], lambda = 1e-8, hn[36], gn[6];
    double negligible = 0.5 * STEP_STD * STEP_STD / (rd->n > 6 ? rd->n - 6 : 1);
    int it, i, j;
    *converged = 0;
    *cost = sampson_pass(rd, r, t, h, g);
    *cost0 = *cost;
    for (it = 0; it < o->max_iterations; it++) {
        double a[36], rhs[6], d[6], dr[9], rn[9], tn[3], cn, nw, nt, lim, sc;
        int small;
        for (i = 0; i < 6; i++) {
            for (j = i; j < 6; j++)
                a[6 * i + j] = a[6 * j + i] = h[6 * i + j];
            a[7 * i] += lambda * h[7 * i] + 1e-300;
            rhs[i] = -g[i];
        }
        if (!(*cost > 0.0)) {
            *converged = 1;
            break;
        }
        if (mcg_spd_solve(6, a, rhs, d) != MCG_OK) {
            lambda = lambda < 1e-6 ? 1e-6 : 10.0 * lambda;
            if (lambda > 1e16)
                break;
            continue;
        }
        nw = sqrt(dot3(d, d));
        nt = sqrt(dot3(d + 3, d + 3));
        lim = 0.5 * (sqrt(dot3(t, t)) > 1.0 ? sqrt(dot3(t, t)) : 1.0);
        sc = 1.0;
        if (nw > 0.5)
            sc = 0.5 / nw;
        if (nt * sc > lim)
            sc = lim / nt;
        for (i = 0; i < 6; i++)
            d[i] *= sc;
        if (mcg_rot_from_angle_axis(d, dr) != MCG_OK)
            break;
        mul33(dr, r, rn);
        for (i = 0; i < 3; i++)
            tn[i] = t[i] + d[3 + i];
        {   /* the decrease the Gauss-Newton model predicts for the step */
            double hd[6], pred = 0.0;
            for (i = 0; i < 6; i++) {
                hd[i] = 0.0;
                for (j = 0; j < 6; j++)
                    hd[i] += h[i <= j ? 6 * i + j : 6 * j + i] * d[j];
            }
            for (i = 0; i < 6; i++)
                pred -= g[i] * d[i] + 0.5 * d[i] * hd[i];
            small = !(pred > o->tolerance * *cost);
            if (!small && lambda <= 1e-4 && pred <= negligible * *cost &&
                nw * sc <= LOCAL_STEP && nt * sc <= LOCAL_STEP * sqrt(dot3(t, t))) {
                /* shorter than STEP_STD standard deviations: the last step */
                cn = sampson_pass(rd, rn, tn, NULL, NULL);
                if (cn <= *cost) {
                    memcpy(r, rn, sizeof rn);
                    memcpy(t, tn, sizeof tn);
                    *cost = cn;
                    *converged = 1;
                    it++;
                    break;
                }
                lambda = lambda < 1e-6 ? 1e-6 : 10.0 * lambda;
                continue;
            }
        }
        if (small) {
            /* the step would lower the cost by less than the tolerance: take
             * it (it is the Newton correction of the last digits) without
             * another pass over the rays; h and the cost stay those of the
             * previous point, which differ by the square of the step */
            memcpy(r, rn, sizeof rn);
            memcpy(t, tn, sizeof tn);
            *converged = 1;
            it++;
            break;
        }
        cn = sampson_pass(rd, rn, tn, hn, gn);
        if (cn <= *cost) {
            double dec = *cost - cn;
            memcpy(r, rn, sizeof rn);
            memcpy(t, tn, sizeof tn);
            memcpy(h, hn, sizeof hn);
            memcpy(g, gn, sizeof gn);
            *cost = cn;
            lambda = lambda * 0.1 > 1e-12 ? lambda * 0.1 : 1e-12;
            if (dec <= o->tolerance * (dec + cn) ||
                (nw * sc <= 1e-12 && nt * sc <= 1e-12 * (1.0 + sqrt(dot3(t, t))))) {
                *converged = 1;
                it++;
                break;
            }
        } else {
            lambda = lambda < 1e-6 ? 1e-6 : 10.0 * lambda;
            if (lambda > 1e16)
                break;
        }
    }
    return it;
}

/* Relative std of |t| from the Gauss-Newton information J^T J of the
 * Sampson error (upper triangle of h) at the refined motion: sigma2 =
 * cost / (n - 6), var|t| = sigma2 u^T S^-1 u with S = H_tt - H_tw H_ww^-1
 * H_wt the information of t with the rotation marginalised out, u = t/|t|.
 * HUGE_VAL where S is singular along u. */
double linear17_geometric_rel_std(const double h[36], double cost, int n, const double t[3])
{
    double hww[9], hwt[9], x[3], s[9], u[3], su[3], nt = sqrt(dot3(t, t));
    int i, j, k;
    if (!(nt > 0.0) || n <= 6)
        return HUGE_VAL;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) {
            int a = i < j ? i : j, b = i < j ? j : i;
            hww[3 * i + j] = h[6 * a + b];
            hwt[3 * i + j] = h[6 * i + 3 + j];
            s[3 * i + j] = h[6 * (3 + a) + 3 + b];
        }
    for (j = 0; j < 3; j++) {       /* s -= H_tw H_ww^-1 H_wt, column j */
        double col[3] = {hwt[j], hwt[3 + j], hwt[6 + j]};
        if (mcg_spd_solve(3, hww, col, x) != MCG_OK)
            return HUGE_VAL;
        for (i = 0; i < 3; i++)
            for (k = 0; k < 3; k++)
                s[3 * i + j] -= hwt[3 * k + i] * x[k];
    }
    for (i = 0; i < 3; i++)
        u[i] = t[i] / nt;
    if (mcg_spd_solve(3, s, u, su) != MCG_OK)
        return HUGE_VAL;
    return sqrt(cost / (n - 6) * dot3(u, su)) / nt;
}
