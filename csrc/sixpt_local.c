/*
 * sixpt_local.c -- motions of 6 generalized correspondences found by local
 * search from a fixed set of start rotations: the 6-point sample of RANSAC
 * at a fraction of the cost of the complete solver (csrc/sixpt.c, whose
 * parameter homotopy tracks 64 paths, 27-30 ms a call on a 2.0 GHz core).
 * Incomplete by design: a solution is found only if some start lies in its
 * basin, so the robust search that uses it measures how often it finds the
 * motion of an all-inlier sample of the consensus, and draws that many more
 * samples (csrc/robust.c, MCG_SAMPLER_6PT_LOCAL).
 *
 * 1. The objective is that of Kneip and Li's eigensolver ("Efficient
 *    computation of relative pose for multi-camera systems", CVPR 2014; our
 *    csrc/eigensolver.c): for a rotation R the generalized epipolar
 *    constraint of pair k (thesis eq. 8.16) is linear in (t, 1),
 *        v_k(R) . (t, 1) = 0,  v_k = (R d1 x d2, d2 . R m1 + m2 . R d1),  (L1)
 *    m = o x d, and with M(R) = sum_k v_k v_k^T (4 x 4) the motions of the
 *    sample are the rotations where the smallest eigenvalue lambda(R) of M
 *    vanishes, (t, 1) along its eigenvector u. With 6 pairs (6 equations,
 *    6 unknowns) lambda = 0 at every real solution of csrc/sixpt.c's system
 *    (S1), noise or not.
 *
 * 2. Levenberg-Marquardt on the residuals r_k = u . v_k over left
 *    increments R <- exp([w]x) R, u held at the current eigenvector
 *    (variable projection: the gradient of lambda is that of sum r_k^2 with
 *    u fixed, as in csrc/eigensolver.c). With u = (u3, u4) and a = R d1,
 *    b = R m1, the row of pair k is
 *        dr_k/dw = a x (d2 x u3) + u4 (b x d2 + a x m2),                 (L2)
 *    from d(R x)/dw_j = e_j x R x and the scalar triple product. With u held
 *    these steps converge only linearly, so after MAX_STEPS of them (or as
 *    soon as every constraint v_k . (t_u, 1), t_u = u3 / u4, is below NEAR)
 *    Newton's method on the square system v_k(R) . (t_u, 1) = 0 in (w, t_u)
 *    jointly takes over (polish(): quadratic at an isolated solution).
 *    Measured on 150 noise-free samples of each family (the tools of
 *    `mcgeom experiment peer_solvers`): the truth among the solutions in
 *    0.63 of 12-camera ring samples (rotations of 3-17 deg), 0.15-0.44 of
 *    the generic and 2-camera families (rotations up to 180 deg), with 2, 4
 *    and 8 steps 0.51 / 0.63 / 0.72 on the ring at 0.56 / 0.98 / 1.13 ms a
 *    call (4 is kept).
 *
 * 3. Accepted: a rotation whose every normalised constraint is below 1e-10
 *    (1 + |t_u|) (the test of csrc/sixpt.c's step 4, on the same normalised
 *    rays: unit directions, origins centred on their mean c and divided by
 *    their RMS spread s) where the Jacobian of the square system is regular
 *    (an isolated solution: on the critical family of thesis ch. 7.3.2, no
 *    rotation with intra-camera rays, every |t| fits) and no pair is
 *    trivially satisfied (its camera only turned about its centre: the
 *    pair's essential matrix vanishes). Every motion returned is then one of
 *    mcg_sixpt's (checked in csrc/tests/test_sixpt.c). Duplicates are
 *    merged; t = s t_u + c - R c back in the rig frames. Rays from one
 *    centre (s = 0) have no metric scale: no solution, as mcg_sixpt.
 *
 * 4. Starts: the identity, and rotations of 0.25 and 0.6 rad about the six
 *    signed axes, 0.4 and 0.9 rad about the eight cube diagonals, 1.5 rad
 *    about the axes and 2.2 rad about the diagonals, and the 13 half turns
 *    about the axes, the cube and the face diagonals (56: without the half
 *    turns a rotation of 180 deg was never found), plus an optional caller's
 *    start (e.g. the best motion of the search so far, near which the next
 *    all-inlier sample's solution lies).
 */
#include "mcgeom.h"
#include "internal.h"

#include <math.h>
#include <string.h>

#define DIR2_MIN 1e-100  /* smallest squared length of a direction */
#define PI 3.14159265358979323846
#define MAX_STEPS 4      /* Levenberg-Marquardt steps per start */
#define ACCEPT 1e-10     /* normalised constraint left, relative to 1 + |t_u| */
#define NEAR 1e-3        /* ... below which Newton in (R, t_u) takes over */
#define POLISH_STEPS 6   /* its steps at most */
#define ISOLATED 1e-7    /* smallest relative pivot of an isolated solution's Jacobian */
#define TRIVIAL 1e-6     /* a pair whose camera moved less (normalised) is trivial */

/* the start rotations' angle-axis vectors (step 4) */
static void start_axes(double w[MCG_SIXPT_LOCAL_STARTS][3])
{
    static const double ax_angle[3] = {0.25, 0.6, 1.5}, diag_angle[3] = {0.4, 0.9, 2.2};
    int k = 0, g, i, s, a, b, c;
    memset(w, 0, sizeof(double) * 3 * MCG_SIXPT_LOCAL_STARTS);
    k = 1; /* the identity */
    for (g = 0; g < 3; g++) {
        for (i = 0; i < 3; i++)
            for (s = -1; s <= 1; s += 2)
                w[k++][i] = s * ax_angle[g];
        for (a = -1; a <= 1; a += 2)
            for (b = -1; b <= 1; b += 2)
                for (c = -1; c <= 1; c += 2) {
                    double f = diag_angle[g] / sqrt(3.0);
                    w[k][0] = a * f;
                    w[k][1] = b * f;
                    w[k++][2] = c * f;
                }
    }
    /* half turns (pi about an axis and about its opposite are one rotation):
     * the 3 axes, the 4 cube diagonals and the 6 face diagonals */
    for (i = 0; i < 3; i++)
        w[k++][i] = PI;
    for (b = -1; b <= 1; b += 2)
        for (c = -1; c <= 1; c += 2) {
            w[k][0] = PI / sqrt(3.0);
            w[k][1] = b * PI / sqrt(3.0);
            w[k++][2] = c * PI / sqrt(3.0);
        }
    for (i = 0; i < 3; i++)
        for (s = -1; s <= 1; s += 2) {
            w[k][i] = PI / sqrt(2.0);
            w[k++][(i + 1) % 3] = s * PI / sqrt(2.0);
        }
}

/* M(R) of (L1), the per-pair a = R d1, b = R m1 kept for (L2) */
static void build_m(const double R[9], const double *p, double M[16], double a[6][3],
                    double b[6][3], double v[6][4])
{
    int k, i, j;
    memset(M, 0, 16 * sizeof(double));
    for (k = 0; k < 6; k++) {
        const double *d1 = p + 12 * k, *m1 = d1 + 3, *d2 = d1 + 6, *m2 = d1 + 9;
        mat_vec(R, d1, a[k]);
        mat_vec(R, m1, b[k]);
        cross3(a[k], d2, v[k]);
        v[k][3] = dot3(d2, b[k]) + dot3(m2, a[k]);
        for (i = 0; i < 4; i++)
            for (j = i; j < 4; j++)
                M[4 * i + j] += v[k][i] * v[k][j];
    }
    for (i = 0; i < 4; i++)
        for (j = 0; j < i; j++)
            M[4 * i + j] = M[4 * j + i];
}

/* x = J^-1 e (6 x 6, partial pivoting; J and e overwritten); 0 when a pivot
 * falls below tiny times J's largest entry: a singular Jacobian */
static int solve6(double J[36], double e[6], double x[6], double tiny)
{
    double big = 0.0;
    int k, i, j;
    for (i = 0; i < 36; i++)
        big = fmax(big, fabs(J[i]));
    if (!(big > 0.0) || !isfinite(big))
        return 0;
    for (k = 0; k < 6; k++) {
        int piv = k;
        for (i = k + 1; i < 6; i++)
            if (fabs(J[6 * i + k]) > fabs(J[6 * piv + k]))
                piv = i;
        if (!(fabs(J[6 * piv + k]) > tiny * big))
            return 0;
        if (piv != k) {
            double tmp;
            for (j = 0; j < 6; j++) {
                tmp = J[6 * k + j];
                J[6 * k + j] = J[6 * piv + j];
                J[6 * piv + j] = tmp;
            }
            tmp = e[k];
            e[k] = e[piv];
            e[piv] = tmp;
        }
        for (i = k + 1; i < 6; i++) {
            double f = J[6 * i + k] / J[6 * k + k];
            for (j = k + 1; j < 6; j++)
                J[6 * i + j] -= f * J[6 * k + j];
            e[i] -= f * e[k];
        }
    }
    for (k = 5; k >= 0; k--) {
        double acc = e[k];
        for (j = k + 1; j < 6; j++)
            acc -= J[6 * k + j] * x[j];
        x[k] = acc / J[6 * k + k];
    }
    return 1;
}

/* Newton on the square system e_k = v_k(R) . (t_u, 1) = 0 in (w, t_u)
 * jointly (6 x 6: csrc/sixpt.c's (S1) in the eigensolver's variables),
 * quadratic where the Jacobian is regular: the rows are (L2) with u =
 * (t_u, 1) and v_k[0:3]. Returns 1 when every |e_k| <= ACCEPT (1 + |t_u|). */
static int polish(double R[9], const double *p, double t_u[3])
{
    int it, k, i;
    for (it = 0; it <= POLISH_STEPS; it++) {
        double M[16], a[6][3], b[6][3], v[6][4], J[36], e[6], x[6], dR[9], Rn[9], worst = 0.0;
        build_m(R, p, M, a, b, v);
        for (k = 0; k < 6; k++) {
            const double *d2 = p + 12 * k + 6, *m2 = d2 + 3;
            double y[3], z[3], q[3], row[3];
            e[k] = dot3(v[k], t_u) + v[k][3];
            worst = fmax(worst, fabs(e[k]));
            cross3(d2, t_u, y);
            cross3(a[k], y, row);
            cross3(b[k], d2, z);
            cross3(a[k], m2, q);
            for (i = 0; i < 3; i++) {
                J[6 * k + i] = row[i] + z[i] + q[i];
                J[6 * k + 3 + i] = v[k][i];
            }
        }
        /* a solution on a family (e.g. no rotation with intra-camera pairs:
         * |t| free, thesis ch. 7.3.2) has a singular Jacobian: within
         * ISOLATED, measured on that family (pivots of 1e-10..1e-9 where
         * the rotation was 1e-12..1e-7 deg from I), it is not isolated and
         * not reported, as mcg_sixpt does not */
        if (worst <= ACCEPT * (1.0 + sqrt(dot3(t_u, t_u))))
            return solve6(J, e, x, ISOLATED);
        if (it == POLISH_STEPS || !solve6(J, e, x, 1e-12) || !all_finite(x, 6))
            return 0;
        for (i = 0; i < 3; i++) {
            x[i] = -x[i];
            t_u[i] -= x[3 + i];
        }
        if (mcg_rot_from_angle_axis(x, dR) != MCG_OK)
            return 0;
        mul33(dR, R, Rn);
        memcpy(R, Rn, sizeof Rn);
    }
    return 0;
}

/* Is (R, t_u) trivial for some pair: its origin carried onto its time-2
 * origin (the camera only turned about its centre: its essential matrix
 * vanishes and the pair's constraint holds for every rotation, a family of
 * solutions, not an isolated one -- mcg_sixpt never reports those)? */
static int trivial_pair(const double R[9], const double t_u[3], const double *q)
{
    int k, i;
    for (k = 0; k < 6; k++) {
        double y[3], s = 0.0;
        mat_vec(R, q + 6 * k, y);
        for (i = 0; i < 3; i++)
            s += (y[i] + t_u[i] - q[6 * k + 3 + i]) * (y[i] + t_u[i] - q[6 * k + 3 + i]);
        if (s <= TRIVIAL * TRIVIAL)
            return 1;
    }
    return 0;
}

/* lambda(R), its eigenvector u and M's rows v (with a, b for (L2)); 0 when
 * the eigen-solver fails */
static int smallest(const double R[9], const double *p, double *lam, double u[4],
                    double a[6][3], double b[6][3], double v[6][4])
{
    double M[16], w[4], V[16];
    int i;
    build_m(R, p, M, a, b, v);
    if (mcg_sym_eig(4, M, w, V) != MCG_OK)
        return 0;
    for (i = 0; i < 4; i++)
        u[i] = V[4 * i]; /* column 0: the smallest eigenvalue's */
    *lam = w[0];
    return 1;
}

/* Levenberg-Marquardt on lambda from R (overwritten): each step raises the
 * damping mu (times diag(H)) tenfold until lambda falls, and lowers it
 * after (as csrc/eigensolver.c); the start is given up when no damping
 * lowers it. After MAX_STEPS steps, or once the constraints hold within
 * NEAR, polish(). Returns 1 with t_u when R is an isolated, non-trivial
 * solution. */
static int descend(double R[9], const double *p, const double *q, double t_u[3])
{
    double lam, u[4], a[6][3], b[6][3], v[6][4], mu = 1e-3;
    int it, k, i, j;
    if (!smallest(R, p, &lam, u, a, b, v))
        return 0;
    for (it = 0;; it++) {
        double H[9], g[3], worst = 0.0;
        int kept = 0;
        if (fabs(u[3]) > 1e-12) {
            for (i = 0; i < 3; i++)
                t_u[i] = u[i] / u[3];
            for (k = 0; k < 6; k++)
                worst = fmax(worst, fabs(dot3(v[k], t_u) + v[k][3]));
            if (worst <= NEAR * (1.0 + sqrt(dot3(t_u, t_u))) && it < MAX_STEPS) {
                /* Newton from a copy: where it fails (an ill-conditioned
                 * sample, e.g. a planar ring turned by ~180 deg) the
                 * descent goes on and Newton is tried again at its end */
                double Rp[9], tp[3];
                memcpy(Rp, R, sizeof Rp);
                memcpy(tp, t_u, sizeof tp);
                if (polish(Rp, p, tp)) {
                    memcpy(R, Rp, sizeof Rp);
                    memcpy(t_u, tp, sizeof tp);
                    return !trivial_pair(R, t_u, q);
                }
            }
        }
        if (it == MAX_STEPS)   /* (t_u of the last eigenvector with u4 != 0) */
            return fabs(u[3]) > 1e-12 && polish(R, p, t_u) && !trivial_pair(R, t_u, q);
        memset(H, 0, sizeof H);
        g[0] = g[1] = g[2] = 0.0;
        for (k = 0; k < 6; k++) {
            const double *d2 = p + 12 * k + 6, *m2 = d2 + 3;
            double x[3], y[3], z[3], row[3];
            double r = u[0] * v[k][0] + u[1] * v[k][1] + u[2] * v[k][2] + u[3] * v[k][3];
            cross3(d2, u, x); /* d2 x u3 */
            cross3(a[k], x, row);
            cross3(b[k], d2, y);
            cross3(a[k], m2, z);
            for (i = 0; i < 3; i++)
                row[i] += u[3] * (y[i] + z[i]);
            for (i = 0; i < 3; i++) {
                g[i] -= row[i] * r;
                for (j = 0; j < 3; j++)
                    H[3 * i + j] += row[i] * row[j];
            }
        }
        while (mu < 1e12 && !kept) {
            double Hd[9], dw[3], dR[9], Rn[9], lam_n, un[4], an[6][3], bn[6][3], vn[6][4];
            memcpy(Hd, H, sizeof H);
            for (i = 0; i < 3; i++)
                Hd[4 * i] += mu * H[4 * i] + 1e-300;
            if (mcg_spd_solve(3, Hd, g, dw) != MCG_OK || !all_finite(dw, 3) ||
                mcg_rot_from_angle_axis(dw, dR) != MCG_OK) {
                mu *= 10.0;
                continue;
            }
            mul33(dR, R, Rn);
            if (!smallest(Rn, p, &lam_n, un, an, bn, vn))
                return 0;
            if (lam_n < lam) {
                memcpy(R, Rn, sizeof Rn);
                memcpy(u, un, sizeof un);
                memcpy(a, an, sizeof an);
                memcpy(b, bn, sizeof bn);
                memcpy(v, vn, sizeof vn);
                lam = lam_n;
                mu = fmax(mu * 0.1, 1e-12);
                kept = 1;
            } else {
                mu *= 10.0;
            }
        }
        if (!kept)
            return 0;
    }
}

int mcg_sixpt_local(const double o1[18], const double d1[18], const double o2[18],
                    const double d2[18], const double *R_start, double *R, double *t,
                    int *n_solutions)
{
    double c[3], sc, p[72], q[36], wst[MCG_SIXPT_LOCAL_STARTS][3], tus[MCG_SIXPT_LOCAL_MAX_SOLUTIONS][3];
    int k, i, j, ns = 0;

    if (!o1 || !d1 || !o2 || !d2 || !R || !t || !n_solutions)
        return MCG_EINVAL;
    *n_solutions = 0;
    if (!all_finite(o1, 18) || !all_finite(d1, 18) || !all_finite(o2, 18) ||
        !all_finite(d2, 18) || (R_start && (!all_finite(R_start, 9) || !is_rotation(R_start))))
        return MCG_EINVAL;
    sc = origin_spread(6, o1, o2, c);
    if (!isfinite(sc))
        return MCG_EINVAL;
    /* normalised pairs (step 3): per pair d1, m1, d2, m2 */
    for (k = 0; k < 6; k++) {
        double a = dot3(d1 + 3 * k, d1 + 3 * k), b = dot3(d2 + 3 * k, d2 + 3 * k), q1[3], q2[3];
        double s = sc > 0.0 ? sc : 1.0;
        if (!(a >= DIR2_MIN && b >= DIR2_MIN && isfinite(a) && isfinite(b)))
            return MCG_EINVAL;
        for (i = 0; i < 3; i++) {
            p[12 * k + i] = d1[3 * k + i] / sqrt(a);
            p[12 * k + 6 + i] = d2[3 * k + i] / sqrt(b);
            q1[i] = (o1[3 * k + i] - c[i]) / s;
            q2[i] = (o2[3 * k + i] - c[i]) / s;
            q[6 * k + i] = q1[i];
            q[6 * k + 3 + i] = q2[i];
        }
        cross3(q1, p + 12 * k, p + 12 * k + 3);
        cross3(q2, p + 12 * k + 6, p + 12 * k + 9);
    }
    if (!(sc > 0.0))
        return MCG_OK; /* one centre: a central camera, no metric scale */
    start_axes(wst);
    for (j = 0; j <= MCG_SIXPT_LOCAL_STARTS; j++) {
        double Rj[9], tu[3], Rc[3];
        int dup = 0;
        if (j == MCG_SIXPT_LOCAL_STARTS) {
            if (!R_start)
                break;
            memcpy(Rj, R_start, sizeof Rj);
        } else if (mcg_rot_from_angle_axis(wst[j], Rj) != MCG_OK) {
            continue;
        }
        if (!descend(Rj, p, q, tu))
            continue;
        for (k = 0; k < ns && !dup; k++) {
            double dr = 0.0, dt = 0.0;
            for (i = 0; i < 9; i++)
                dr = fmax(dr, fabs(R[9 * k + i] - Rj[i]));
            for (i = 0; i < 3; i++)
                dt = fmax(dt, fabs(tus[k][i] - tu[i]));
            dup = dr <= 1e-8 && dt <= 1e-8 * (1.0 + sqrt(dot3(tu, tu)));
        }
        if (dup)
            continue;
        memcpy(R + 9 * ns, Rj, sizeof Rj);
        memcpy(tus[ns], tu, sizeof tu);
        mat_vec(Rj, c, Rc);
        for (i = 0; i < 3; i++)
            t[3 * ns + i] = sc * tu[i] + c[i] - Rc[i];
        ns++;
    }
    *n_solutions = ns;
    return MCG_OK;
}
