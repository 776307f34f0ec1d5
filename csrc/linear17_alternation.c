/*
 * linear17_alternation.c -- the algebraic alternation of thesis ch. 8.4.3 on
 * the Gram matrix M of csrc/linear17.c: the translation given R (eq. 8.15,
 * with scale, or its direction in unit mode) and the rotation given t.
 */
#include "linear17_internal.h"

#include <float.h>
#include <math.h>
#include <string.h>

/* Cost in t for fixed R is t^T H t + 2 g^T t + c0 with
 * H_kl = b_k^T M_EE b_l, b_k = vec([e_k]x R), g_k = b_k^T M_ER vec R. */
int linear17_solve_t(const double *m, const double r[9], int unit_mode,
                     const double tprev[3], int want_eig, tsolve *out)
{
    double b[3][9], mb[3][9], mervr[9], h[9], g[3];
    double c0 = 0.0, hmax;
    int k, l, i, j;
    for (k = 0; k < 3; k++) {
        double e[3] = {0.0, 0.0, 0.0};
        e[k] = 1.0;
        skew_times(e, r, b[k]);
    }
    /* the blocks of M read in place (M_EE b_k, M_ER r, r^T M_RR r), in the
     * summation order of matvec on copied blocks */
    for (i = 0; i < 9; i++) {
        const double *mi = m + i * NX, *ri = m + (9 + i) * NX + 9;
        double a0 = 0.0, a1 = 0.0, a2 = 0.0, ar = 0.0, rr = 0.0;
        for (j = 0; j < 9; j++) {
            a0 += mi[j] * b[0][j];
            a1 += mi[j] * b[1][j];
            a2 += mi[j] * b[2][j];
            ar += mi[9 + j] * r[j];
            rr += ri[j] * r[j];
        }
        mb[0][i] = a0;
        mb[1][i] = a1;
        mb[2][i] = a2;
        mervr[i] = ar;
        c0 += r[i] * rr;
    }
    for (k = 0; k < 3; k++) {
        g[k] = 0.0;
        for (i = 0; i < 9; i++)
            g[k] += b[k][i] * mervr[i];
        for (l = 0; l < 3; l++) {
            double acc = 0.0;
            for (i = 0; i < 9; i++)
                acc += b[k][i] * mb[l][i];
            h[3 * k + l] = acc;
        }
    }
    memcpy(out->hm, h, sizeof out->hm);
    memcpy(out->g, g, sizeof out->g);
    out->c0 = c0;
    if (!unit_mode && !want_eig) {
        /* Fast path (candidate costs, alternation): Cholesky solve of
         * H t = -g; the eigen-decomposition (for the scale evidence) is only
         * needed for the final estimate. cond/h/hv are left unset (-1). */
        double mg[3] = {-g[0], -g[1], -g[2]};
        if (mcg_spd_solve(3, h, mg, out->t) == MCG_OK) {
            double ht[3];
            out->cond = -1.0;
            matvec(3, h, out->t, ht);
            out->cost = dot3(out->t, ht) + 2.0 * dot3(g, out->t) + c0;
            if (out->cost < 0.0)
                out->cost = 0.0;
            return MCG_OK;
        }
        /* H (numerically) singular: the eigen route truncates its null space */
    }
    {
        double hc[9];
        memcpy(hc, h, sizeof hc);
        if (mcg_sym_eig(3, hc, out->h, out->hv) != MCG_OK)
            return MCG_ENUMERIC;
    }
    hmax = out->h[2];
    out->cond = hmax > 0.0 ? (out->h[0] > 0.0 ? out->h[0] / hmax : 0.0) : 0.0;
    if (unit_mode || !(hmax > 0.0)) {
        /* scale unobservable: keep |t| = 1 along the least-constrained
         * direction, with the sign of the previous estimate */
        double sgn = 1.0;
        for (i = 0; i < 3; i++)
            out->t[i] = out->hv[3 * i];
        if (tprev && dot3(out->t, tprev) < 0.0)
            sgn = -1.0;
        for (i = 0; i < 3; i++)
            out->t[i] *= sgn;
    } else {
        for (i = 0; i < 3; i++)
            out->t[i] = 0.0;
        for (k = 0; k < 3; k++) {
            double vk[3] = {out->hv[k], out->hv[3 + k], out->hv[6 + k]};
            double c;
            if (!(out->h[k] > 1e-15 * hmax))
                continue;
            c = -dot3(vk, g) / out->h[k];
            for (i = 0; i < 3; i++)
                out->t[i] += c * vk[i];
        }
    }
    {
        double ht[3];
        matvec(3, h, out->t, ht);
        out->cost = dot3(out->t, ht) + 2.0 * dot3(g, out->t) + c0;
        if (out->cost < 0.0)
            out->cost = 0.0;
    }
    return MCG_OK;
}

/* One Gauss-Newton step on SO(3) for min_R x(R,t)^T M x(R,t) with t fixed,
 * R = exp([w]x) R0; accepted only if it lowers the cost (step halving). */
int linear17_step_r(const double *m, double r[9], const double t[3], double *cost)
{
    double x0[NX], c[3][NX], mc[3][NX], mx0[NX], a[9], rhs[3], w[3];
    int k, l, i, tries;
    motion_vector(r, t, x0);
    matvec(NX, m, x0, mx0);
    for (k = 0; k < 3; k++) {
        double e[3] = {0.0, 0.0, 0.0}, dr[9];
        e[k] = 1.0;
        skew_times(e, r, dr);          /* d R / d w_k = [e_k]x R */
        skew_times(t, dr, c[k]);       /* d ([t]x R) / d w_k */
        memcpy(c[k] + 9, dr, sizeof dr);
        matvec(NX, m, c[k], mc[k]);
    }
    for (k = 0; k < 3; k++) {
        rhs[k] = 0.0;
        for (i = 0; i < NX; i++)
            rhs[k] -= c[k][i] * mx0[i];
        for (l = 0; l < 3; l++) {
            double acc = 0.0;
            for (i = 0; i < NX; i++)
                acc += c[k][i] * mc[l][i];
            a[3 * k + l] = acc;
        }
    }
    {   /* tiny Levenberg damping keeps the 3x3 system positive definite */
        double tr = a[0] + a[4] + a[8];
        if (!(tr > 0.0))
            return MCG_OK;
        for (k = 0; k < 3; k++)
            a[4 * k] += 1e-12 * tr;
        if (mcg_spd_solve(3, a, rhs, w) != MCG_OK)
            return MCG_OK;
    }
    for (tries = 0; tries < 8; tries++) {
        double dr[9], rn[9], xn[NX], cn;
        if (mcg_rot_from_angle_axis(w, dr) != MCG_OK)
            return MCG_ENUMERIC;
        mul33(dr, r, rn);
        motion_vector(rn, t, xn);
        cn = quad18(m, xn);
        if (cn <= *cost) {
            memcpy(r, rn, sizeof rn);
            *cost = cn;
            return MCG_OK;
        }
        for (k = 0; k < 3; k++)
            w[k] *= 0.5;
    }
    return MCG_OK;
}
