/*
 * eigensolver.c -- generalized relative pose by minimising the smallest
 * eigenvalue of the generalized-epipolar matrix over the rotation (Kneip and
 * Li, "Efficient computation of relative pose for multi-camera systems",
 * CVPR 2014). Our own formulation and minimiser, written from the paper's idea.
 *
 * 1. For a rotation R, the generalized epipolar constraint of correspondence
 *    k (thesis eq. 8.16 in this library's convention) is linear in (t, 1),
 *    since d2^T [t]x R d1 = t . (R d1 x d2):
 *        v_k(R) . (t, 1) = 0,
 *        v_k(R) = ( R d1 x d2 ,  d2 . R m1 + m2 . R d1 ).                   (E1)
 *    With M(R) = sum_k v_k v_k^T (4 x 4, symmetric, positive semi-definite)
 *    the least-squares (t, 1) for R is the eigenvector u of the smallest
 *    eigenvalue lambda(R), and lambda(R) = sum_k (u . v_k)^2 is the algebraic
 *    cost left: the rotation minimises lambda(R) (the paper's objective,
 *    there written with the translation eliminated the same way).
 *
 * 2. Minimisation: Levenberg-Marquardt on the residuals r_k = u . v_k(R) over
 *    a left increment R <- exp([w]x) R (three parameters, like the paper's
 *    Cayley parameters: a local chart of SO(3)), u held at the current
 *    eigenvector (variable projection: the derivative of lambda with respect
 *    to R is that of sum r_k^2 with u fixed, since u minimises it for each R).
 *    With d(R x)/dw_j = e_j x (R x):
 *        dr_k/dw_j = u . ( (e_j x R d1) x d2 ,
 *                          d2 . (e_j x R m1) + m2 . (e_j x R d1) ).          (E2)
 *    A step is kept only if lambda decreases by more than its rounding (the
 *    damping grows otherwise); it stops when the step or the relative
 *    decrease is at rounding level; then Gauss-Newton steps jointly in R and
 *    u (quadratic where the residuals vanish) polish R while they shrink.
 *
 *    Trap: with rays that each stay in one camera, R = I, t = 0 (no motion)
 *    satisfies every constraint (v_k[3] = 0 at R = I), so lambda has a
 *    global minimum 0 there whatever the true motion; a start near a small
 *    true rotation can slide into it. The caller compares the travel of the
 *    result with that of the start (mcgeom.estimators.eigensolver).
 *
 * 3. Conditioning and invariance: the directions are normalised, the origins
 *    centred on their mean c and divided by their RMS distance s from it
 *    (both invariant to a change of the rig frame and to a global scale), so
 *    the minimiser and its optimum do not depend on where the user put the
 *    rig origin; t = s t_u + c - R c maps back.
 *
 * 4. The translation: t_u = u[0:3] / u[3]. When the smallest two eigenvalues
 *    both vanish and their eigenspace holds (0, 0, 0, 1) -- every row has
 *    v[3] = 0: no rotation and rays that each stay in one camera, the
 *    critical motion of thesis ch. 7.3.2 -- or u[3] ~ 0, |t| is not
 *    determined: t is returned as the unit direction of the null space with
 *    u[3] = 0 and *has_scale = 0. Rays from one centre (s = 0: every moment
 *    vanishes) use the 3 x 3 block: the direction of travel only.
 */
#include "mcgeom.h"
#include "internal.h"
#include "so3.h"

#include <float.h>
#include <math.h>
#include <string.h>

#define DIR2_MIN 1e-100 /* smallest squared length of a direction */
#define MAX_PAIRS (1 << 20) /* the rows mcg_svd takes */

size_t mcg_eigensolver_work_size(int n)
{
    int ok = 1;
    size_t s, sv;
    if (n < 1 || n > MAX_PAIRS)
        return 0;
    sv = mcg_svd_work_size(n, 4);
    s = add_sz(mul_sz((size_t)n, 16, &ok), sv, &ok); /* rows data, V, SVD work */
    return ok && sv > 0 ? s : 0;
}

/* The row v (E1) of correspondence a (a, m1, b, m2: 12 doubles) at R, and,
 * when J != NULL, the derivatives (E2) of u . v along the three rotation
 * increments. */
static void row_at(const double *a, const double R[9], const double *u, int dim, double v[4],
                   double *J)
{
    const double *m1 = a + 3, *b = a + 6, *m2 = a + 9;
    double ra[3], rm[3];
    int i, j;
    mat_vec(R, a, ra);
    mat_vec(R, m1, rm);
    cross3(ra, b, v);
    v[3] = dot3(b, rm) + dot3(m2, ra);
    if (!J)
        return;
    for (j = 0; j < 3; ++j) {
        double e[3] = {0.0, 0.0, 0.0}, era[3], erm[3], dv[4];
        e[j] = 1.0;
        cross3(e, ra, era);
        cross3(e, rm, erm);
        cross3(era, b, dv);
        dv[3] = dot3(b, erm) + dot3(m2, era);
        J[j] = 0.0;
        for (i = 0; i < dim; ++i)
            J[j] += u[i] * dv[i];
    }
}

/* rows v_k of (E1) accumulated into M (dim x dim, dim = 4, or 3 when the
 * moments vanish); also the residuals' normal equations (A = J^T J, g = J^T r)
 * for the eigenvector u when A != NULL */
static void accumulate(int n, const double *w, const double R[9], int dim, const double *u,
                       double *M, double *A, double *g)
{
    int k, i, j;
    memset(M, 0, sizeof(double) * 16);
    if (A) {
        memset(A, 0, sizeof(double) * 9);
        memset(g, 0, sizeof(double) * 3);
    }
    for (k = 0; k < n; ++k) {
        double v[4], J[3];
        row_at(w + 12 * k, R, u, dim, v, A ? J : NULL);
        for (i = 0; i < dim; ++i)
            for (j = 0; j < dim; ++j)
                M[dim * i + j] += v[i] * v[j];
        if (A) {
            double r = 0.0;
            for (i = 0; i < dim; ++i)
                r += u[i] * v[i];
            for (i = 0; i < 3; ++i) {
                g[i] += J[i] * r;
                for (j = 0; j < 3; ++j)
                    A[3 * i + j] += J[i] * J[j];
            }
        }
    }
}

/* The eigenvalues of M(R) (ascending: lam, lam2, ..., top) and the
 * eigenvector u of the smallest, as the squared singular values and right
 * singular vectors of the n x dim matrix V of the rows v_k: forming M squares
 * the condition number (measured: R only to 1e-9 on noise-free data), the
 * SVD of V keeps u accurate to eps * cond(V). ev holds the three eigenvalues
 * and the second smallest's eigenvector follows u in un2 (may be NULL). */
static int smallest(int n, const double *w, const double R[9], int dim, double *vbuf,
                    double *swork, size_t lsw, double ev[3], double *u, double *u2,
                    double *Vout)
{
    double sv[4], V[16];
    int k, i, st;
    for (k = 0; k < n; ++k) {
        double v[4];
        row_at(w + 12 * k, R, NULL, dim, v, NULL);
        for (i = 0; i < dim; ++i)
            vbuf[dim * k + i] = v[i];
    }
    st = mcg_svd(n, dim, vbuf, NULL, sv, V, swork, lsw);
    if (st != MCG_OK)
        return st;
    ev[0] = sv[dim - 1] * sv[dim - 1];
    ev[1] = sv[dim - 2] * sv[dim - 2];
    ev[2] = sv[0] * sv[0];
    for (i = 0; i < dim; ++i) {
        u[i] = V[dim * i + dim - 1];
        if (u2)
            u2[i] = V[dim * i + dim - 2];
    }
    if (Vout)
        memcpy(Vout, V, sizeof(double) * (size_t)(dim * dim));
    return MCG_OK;
}

/* solve the 3 x 3 SPD system (A + mu diag(A)) x = -g by Cholesky; 0 if it fails */
static int damped_step(const double A[9], const double g[3], double mu, double x[3])
{
    double L[9] = {0}, y[3];
    int i, j, k;
    for (i = 0; i < 3; ++i)
        for (j = 0; j <= i; ++j) {
            double s = A[3 * i + j] + (i == j ? mu * (A[3 * i + i] + 1e-300) : 0.0);
            for (k = 0; k < j; ++k)
                s -= L[3 * i + k] * L[3 * j + k];
            if (i == j) {
                if (!(s > 0.0))
                    return 0;
                L[3 * i + i] = sqrt(s);
            } else {
                L[3 * i + j] = s / L[3 * j + j];
            }
        }
    for (i = 0; i < 3; ++i) {
        double s = -g[i];
        for (k = 0; k < i; ++k)
            s -= L[3 * i + k] * y[k];
        y[i] = s / L[3 * i + i];
    }
    for (i = 2; i >= 0; --i) {
        double s = y[i];
        for (k = i + 1; k < 3; ++k)
            s -= L[3 * k + i] * x[k];
        x[i] = s / L[3 * i + i];
    }
    return all_finite(x, 3);
}

/* Solve the q x q (q <= 6) SPD system N x = b by Cholesky with a relative
 * diagonal floor; 0 if it fails. */
static int spd_solve_small(int q, const double *N, const double *b, double *x)
{
    double L[36] = {0}, y[6];
    int i, j, k;
    for (i = 0; i < q; ++i)
        for (j = 0; j <= i; ++j) {
            double s = N[q * i + j] + (i == j ? 1e-14 * N[q * i + i] : 0.0);
            for (k = 0; k < j; ++k)
                s -= L[6 * i + k] * L[6 * j + k];
            if (i == j) {
                if (!(s > 0.0))
                    return 0;
                L[6 * i + i] = sqrt(s);
            } else {
                L[6 * i + j] = s / L[6 * j + j];
            }
        }
    for (i = 0; i < q; ++i) {
        double s = b[i];
        for (k = 0; k < i; ++k)
            s -= L[6 * i + k] * y[k];
        y[i] = s / L[6 * i + i];
    }
    for (i = q - 1; i >= 0; --i) {
        double s = y[i];
        for (k = i + 1; k < q; ++k)
            s -= L[6 * k + i] * x[k];
        x[i] = s / L[6 * i + i];
    }
    return all_finite(x, (size_t)q);
}

int mcg_eigensolver(int n, const double *o1, const double *d1, const double *o2,
                    const double *d2, const double R0[9], int max_iterations, double R[9],
                    double t[3], double *lambda_min, int *has_scale, int *iterations,
                    double *work, size_t lwork)
{
    double c[3] = {0.0, 0.0, 0.0}, s = 0.0, M[16], A[9], g[3], u[4], u2[4], ev[3], Vb[16];
    double mu = 1e-3;
    double *vbuf, *swork; /* carved from work once n is checked */
    size_t lsw;
    int k, i, dim, it, st;
    if (!o1 || !d1 || !o2 || !d2 || !R0 || !R || !t || !lambda_min || !has_scale ||
        !iterations || !work)
        return MCG_EINVAL;
    if (n < 1 || n > MAX_PAIRS || max_iterations < 0 || max_iterations > 100000)
        return MCG_EINVAL;
    if (mcg_eigensolver_work_size(n) == 0)
        return MCG_EINVAL;
    if (lwork < mcg_eigensolver_work_size(n))
        return MCG_ENOMEM;
    vbuf = work + 12 * (size_t)n;
    swork = vbuf + 4 * (size_t)n;
    lsw = lwork - 16 * (size_t)n;
    if (!all_finite(R0, 9) || !is_rotation(R0))
        return MCG_EINVAL;
    for (k = 0; k < n; ++k) {
        if (!all_finite(o1 + 3 * k, 3) || !all_finite(d1 + 3 * k, 3) ||
            !all_finite(o2 + 3 * k, 3) || !all_finite(d2 + 3 * k, 3))
            return MCG_EINVAL;
        for (i = 0; i < 3; ++i)
            c[i] += (o1[3 * k + i] + o2[3 * k + i]) / (2.0 * n);
    }
    for (k = 0; k < n; ++k)
        for (i = 0; i < 3; ++i) {
            double x = o1[3 * k + i] - c[i], y = o2[3 * k + i] - c[i];
            s += (x * x + y * y) / (2.0 * n);
        }
    s = sqrt(s);
    if (!isfinite(s) || !all_finite(c, 3))
        return MCG_EINVAL;
    dim = s > 1e-12 * (1.0 + fabs(c[0]) + fabs(c[1]) + fabs(c[2])) ? 4 : 3;
    if (dim == 3)
        s = 1.0;
    for (k = 0; k < n; ++k) {
        double *wk = work + 12 * k, x = dot3(d1 + 3 * k, d1 + 3 * k),
               y = dot3(d2 + 3 * k, d2 + 3 * k), p[3];
        if (!(x >= DIR2_MIN && y >= DIR2_MIN && isfinite(x) && isfinite(y)))
            return MCG_EINVAL;
        x = 1.0 / sqrt(x);
        y = 1.0 / sqrt(y);
        for (i = 0; i < 3; ++i) {
            wk[i] = d1[3 * k + i] * x;
            wk[6 + i] = d2[3 * k + i] * y;
            p[i] = (o1[3 * k + i] - c[i]) / s;
        }
        cross3(p, wk, wk + 3);
        for (i = 0; i < 3; ++i)
            p[i] = (o2[3 * k + i] - c[i]) / s;
        cross3(p, wk + 6, wk + 9);
        if (dim == 3)
            for (i = 0; i < 3; ++i)
                wk[3 + i] = wk[9 + i] = 0.0;
    }
    memcpy(R, R0, sizeof(double) * 9);
    accumulate(n, work, R, dim, NULL, M, NULL, NULL);
    if (!all_finite(M, 16))
        return MCG_EINVAL; /* magnitudes that overflow */
    if ((st = smallest(n, work, R, dim, vbuf, swork, lsw, ev, u, u2, Vb)) != MCG_OK)
        return st;
    for (it = 0; it < max_iterations; ++it) {
        double x[3], Rn[9], Rx[9], un[4], un2[4], evn[3], Vn[16];
        int improved = 0;
        accumulate(n, work, R, dim, u, M, A, g);
        while (mu < 1e12) {
            if (!damped_step(A, g, mu, x)) {
                mu *= 10.0;
                continue;
            }
            if (mcg_rot_from_angle_axis(x, Rx) != MCG_OK)
                break;
            mul33(Rx, R, Rn);
            if (smallest(n, work, Rn, dim, vbuf, swork, lsw, evn, un, un2, Vn) != MCG_OK)
                break;
            /* a decrease above the rounding of the eigenvalue (relative to
             * the largest): steps within it only wander */
            if (evn[0] < ev[0] - 16.0 * DBL_EPSILON * ev[2]) {
                double step = sqrt(dot3(x, x)), dec = ev[0] - evn[0];
                memcpy(R, Rn, sizeof Rn);
                memcpy(u, un, sizeof un);
                memcpy(u2, un2, sizeof un2);
                memcpy(ev, evn, sizeof evn);
                memcpy(Vb, Vn, sizeof Vn);
                mu = fmax(mu / 10.0, 1e-12);
                improved = 1 + (step < 1e-14 || dec <= 1e-15 * ev[0]);
                break;
            }
            mu *= 10.0;
        }
        if (improved != 1)
            break; /* no decrease left, or the last one at rounding level */
    }
    /* Polish: Gauss-Newton steps on the residuals r_k = u . v_k(R) jointly in
     * the rotation and in u (moved in the span of the other singular vectors,
     * the tangent of the unit sphere at u), taken while they shrink. The LM
     * steps above hold u fixed (exact for the gradient, but only linearly
     * convergent: measured 1e-9 rad left on noise-free data); the joint step
     * converges quadratically where the residuals vanish. Only its rotation
     * part is applied: u is then recomputed as the singular vector. */
    {
        double prev = HUGE_VAL;
        int p;
        for (p = 0; p < 8 && it > 0; ++p) {
            double x[6], Rx[9], Rn[9], nx, N6[36], b6[6];
            int q = 3 + dim - 1, a2, b2;
            memset(N6, 0, sizeof N6);
            memset(b6, 0, sizeof b6);
            for (k = 0; k < n; ++k) {
                double v[4], row[6], r = 0.0;
                int j;
                row_at(work + 12 * k, R, u, dim, v, row); /* (E1), (E2) */
                for (i = 0; i < dim; ++i)
                    r += u[i] * v[i];
                for (j = 0; j < dim - 1; ++j) { /* d r / d (basis coordinate j) */
                    row[3 + j] = 0.0;
                    for (i = 0; i < dim; ++i)
                        row[3 + j] += Vb[dim * i + j] * v[i];
                }
                for (a2 = 0; a2 < q; ++a2) {
                    b6[a2] -= row[a2] * r;
                    for (b2 = 0; b2 < q; ++b2)
                        N6[q * a2 + b2] += row[a2] * row[b2];
                }
            }
            if (!spd_solve_small(q, N6, b6, x))
                break;
            nx = sqrt(dot3(x, x));
            if (!(nx < prev) || mcg_rot_from_angle_axis(x, Rx) != MCG_OK)
                break;
            mul33(Rx, R, Rn);
            memcpy(R, Rn, sizeof Rn);
            if ((st = smallest(n, work, R, dim, vbuf, swork, lsw, ev, u, u2, Vb)) != MCG_OK)
                return st;
            prev = nx;
            if (nx < 1e-15)
                break;
        }
    }
    *iterations = it;
    *lambda_min = ev[0];
    /* re-orthonormalise the product of the increments */
    if (mcg_project_so3(R, A) == MCG_OK)
        memcpy(R, A, sizeof A);
    {
        double tu[3], Rc[3], nt;
        int scale = 0;
        if (dim == 4 && (ev[1] <= 1e-10 * ev[2] || !(fabs(u[3]) > 1e-12))) {
            /* |t| free: the direction in the span of the two smallest
             * singular vectors with no homogeneous part */
            for (i = 0; i < 3; ++i)
                tu[i] = u[i] * u2[3] - u2[i] * u[3];
            if (!(dot3(tu, tu) > 0.0))
                for (i = 0; i < 3; ++i)
                    tu[i] = u[i];
        } else if (dim == 4) {
            for (i = 0; i < 3; ++i)
                tu[i] = u[i] / u[3];
            scale = 1;
        } else {
            for (i = 0; i < 3; ++i)
                tu[i] = u[i];
        }
        if (!scale) {
            nt = sqrt(dot3(tu, tu));
            for (i = 0; i < 3; ++i)
                tu[i] /= nt;
        }
        mat_vec(R, c, Rc);
        for (i = 0; i < 3; ++i)
            t[i] = s * tu[i] + c[i] - Rc[i];
        *has_scale = scale;
    }
    if (!all_finite(R, 9) || !all_finite(t, 3))
        return MCG_ENUMERIC;
    return MCG_OK;
}
