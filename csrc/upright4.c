/*
 * upright4.c -- the minimal generalized relative pose with a known vertical
 * direction ("upright" 4-point solver; Sweeney, Flynn, Turk, "Solving for
 * relative pose with a partially known rotation is a quadratic eigenvalue
 * problem", 3DV 2014; Lee, Fraundorfer, Pollefeys, "Relative pose estimation
 * for a multi-camera system with known vertical direction", CVPR 2014).
 * The derivation below is our own; it follows the papers' idea (the vertical
 * fixes two rotation degrees of freedom, four generalized correspondences the
 * remaining yaw and the metric translation) but not their elimination.
 *
 * 1. Upright frames. g1 (rig frame 1) and g2 (rig frame 2) are the same
 *    physical vertical, so the motion satisfies R g1 = g2. With rotations Q1,
 *    Q2 such that Q1 g1 = Q2 g2 = e_z (rows (a, g x a, g) of an orthonormal
 *    basis completing the unit g), the motion between the upright frames
 *        R' = Q2 R Q1^T,  t' = Q2 t
 *    fixes e_z: R' = Rz(theta) is a rotation about the vertical. Rays move
 *    with their frames: d1' = Q1 d1, m1' = Q1 m1 (m = o x d, proper rotations
 *    preserve the cross product), likewise d2', m2' with Q2.
 *
 * 2. The generalized epipolar constraint (thesis eq. 8.16 in this library's
 *    convention, d2^T [t]x R d1 + d2^T R m1 + m2^T R d1 = 0) is linear in
 *    (t, 1) for a given R, since d2^T [t]x R d1 = t . (R d1 x d2):
 *        [ (R' d1' x d2')^T ,  d2'^T R' m1' + m2'^T R' d1' ] (t', 1)^T = 0.   (U1)
 *    Four correspondences stack four such rows into M(theta) (4 x 4), and a
 *    solution needs M(theta) (t', 1) = 0, hence det M(theta) = 0.
 *
 * 3. Tangent half-angle q = tan(theta / 2): (1 + q^2) Rz(theta) = P(q) =
 *    P0 + q P1 + q^2 P2 with P0 = I, P1 = 2 [e_z]x, P2 = diag(-1, -1, 1).
 *    Multiplying each row (U1) by 1 + q^2 leaves its roots and makes every
 *    entry of M a quadratic in q (coefficient j from Pj in place of R'):
 *        M_j(k, :) = [ (Pj d1' x d2')^T,  d2'^T Pj m1' + m2'^T Pj d1' ].      (U2)
 *    det M(q) is a polynomial of degree <= 8 in q (up to 8 solutions, as the
 *    papers count), expanded exactly by the Laplace expansion along rows
 *    (0, 1) | (2, 3): det M = sum over column pairs J of
 *    (-1)^(a + b + 1) det M[01, J] det M[23, J^c]                             (U3)
 *    with each 2 x 2 minor a polynomial of degree 4.
 *
 * 4. The real roots q of (U3) (isolated between the real roots of the
 *    derivative, recursively, then safeguarded Newton / bisection), and for
 *    each the null vector v of M(q) (the signed 3 x 3 cofactors of the three
 *    rows that span it best); t' = v[0:3] / v[3]. A root with v[3] ~ 0 has no
 *    finite translation and is dropped. theta = pi (q = infinity) is not
 *    represented: a set of measure zero.
 *
 * 5. Polish: two Newton steps on the square system (U1) in (theta, t') (the
 *    rounding of the polynomial's coefficients otherwise costs digits where
 *    roots are close), kept only when they lower the residual.
 *
 * 6. Back to the rig frames: R = Q2^T Rz(theta) Q1, t = Q2^T t'. The origins
 *    are centred and scaled (the moments are then O(1)) before step 2, and t
 *    mapped back: with o = s u + c, t = s t_u + c - R c.
 */
#include "mcgeom.h"
#include "internal.h"
#include "poly.h"
#include "so3.h"

#include <math.h>
#include <string.h>

#define DIR2_MIN 1e-100 /* smallest squared length of a direction or gravity */

/* ---------------------------------------------------------- polynomials
 * (poly_mul, poly_eval: poly.h) */

/* A root of a (degree n) in [lo, hi] where a(lo), a(hi) differ in sign:
 * Newton steps that stay inside the shrinking bracket, bisection otherwise. */
static double bracket_root(const double *a, const double *da, int n, double lo, double hi,
                           double flo)
{
    double x = 0.5 * (lo + hi);
    int it;
    for (it = 0; it < 200; ++it) {
        double f = poly_eval(a, n, x), df = poly_eval(da, n - 1, x), xn;
        if (f == 0.0)
            return x;
        if ((f < 0.0) == (flo < 0.0)) {
            lo = x;
            flo = f;
        } else {
            hi = x;
        }
        xn = df != 0.0 ? x - f / df : 0.5 * (lo + hi);
        if (!(xn > lo && xn < hi))
            xn = 0.5 * (lo + hi);
        if (fabs(xn - x) <= 4e-16 * fabs(xn) || hi - lo <= 4e-16 * fmax(fabs(lo), fabs(hi)))
            return xn;
        x = xn;
    }
    return x;
}

/* Real roots of a (degree n >= 1, a[n] != 0), increasing, into r; returns
 * their number. The roots of the derivative split the line into intervals on
 * which a is monotone; each holds at most one root (a double root, where a
 * touches 0 without changing sign, is found only if it is exact). */
static int real_roots(const double *a, int n, double *r)
{
    double da[8], crit[8], pts[10], b = 0.0;
    int nc, np, i, nr = 0;
    if (n == 1) {
        r[0] = -a[0] / a[1];
        return 1;
    }
    for (i = 0; i < n; ++i) {
        da[i] = (i + 1) * a[i + 1];
        b = fmax(b, fabs(a[i] / a[n]));
    }
    b = 1.0 + b; /* Cauchy's bound: every root has |x| < b */
    nc = real_roots(da, n - 1, crit);
    np = 0;
    pts[np++] = -b;
    for (i = 0; i < nc; ++i)
        if (crit[i] > -b && crit[i] < b)
            pts[np++] = crit[i];
    pts[np++] = b;
    for (i = 0; i + 1 < np; ++i) {
        double flo = poly_eval(a, n, pts[i]), fhi = poly_eval(a, n, pts[i + 1]);
        if (flo == 0.0) {
            if (nr == 0 || r[nr - 1] != pts[i])
                r[nr++] = pts[i];
        } else if (fhi != 0.0 && (flo < 0.0) != (fhi < 0.0)) {
            r[nr++] = bracket_root(a, da, n, pts[i], pts[i + 1], flo);
        }
    }
    return nr;
}

/* ---------------------------------------------------------- the system */

/* an orthonormal Q (rows a, g x a, g) with Q g = e_z, g unit */
static void upright_rotation(const double g[3], double Q[9])
{
    double a[3] = {0.0, 0.0, 0.0}, b[3], n;
    int k = fabs(g[0]) <= fabs(g[1]) ? (fabs(g[0]) <= fabs(g[2]) ? 0 : 2)
                                     : (fabs(g[1]) <= fabs(g[2]) ? 1 : 2);
    int i;
    a[k] = 1.0; /* the axis least aligned with g */
    n = dot3(a, g);
    for (i = 0; i < 3; ++i)
        a[i] -= n * g[i];
    n = sqrt(dot3(a, a));
    for (i = 0; i < 3; ++i)
        a[i] /= n;
    cross3(g, a, b);
    for (i = 0; i < 3; ++i) {
        Q[i] = a[i];
        Q[3 + i] = b[i];
        Q[6 + i] = g[i];
    }
}

/* the row (U1) of one correspondence for the matrix P in place of R' */
static void row_of(const double P[9], const double d1[3], const double m1[3], const double d2[3],
                   const double m2[3], double row[4])
{
    double pd1[3], pm1[3];
    mat_vec(P, d1, pd1);
    mat_vec(P, m1, pm1);
    cross3(pd1, d2, row);
    row[3] = dot3(d2, pm1) + dot3(m2, pd1);
}

static double det3_rows(const double *a, const double *b, const double *c)
{
    return a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
           a[2] * (b[0] * c[1] - b[1] * c[0]);
}

/* Null vector of the 4 x 4 M (rows): the signed cofactors of the three rows
 * whose cofactor vector is longest (M has rank 3 at a root). */
static void null4(const double M[16], double v[4])
{
    int skip;
    double bn = -1.0;
    v[0] = v[1] = v[2] = v[3] = 0.0;
    for (skip = 0; skip < 4; ++skip) {
        const double *r[3];
        double w[4], sub[3][3], nn;
        int i, j, c, col;
        for (i = 0, j = 0; i < 4; ++i)
            if (i != skip)
                r[j++] = M + 4 * i;
        for (col = 0; col < 4; ++col) {
            for (i = 0; i < 3; ++i)
                for (c = 0, j = 0; c < 4; ++c)
                    if (c != col)
                        sub[i][j++] = r[i][c];
            w[col] = ((col & 1) ? -1.0 : 1.0) * det3_rows(sub[0], sub[1], sub[2]);
        }
        nn = w[0] * w[0] + w[1] * w[1] + w[2] * w[2] + w[3] * w[3];
        if (nn > bn) {
            bn = nn;
            memcpy(v, w, sizeof w);
        }
    }
}

/* Solve the 4 x 4 system A x = b by Gaussian elimination with partial
 * pivoting; 0 if singular. */
static int solve4(double A[16], double b[4], double x[4])
{
    int i, j, k;
    for (k = 0; k < 4; ++k) {
        int p = k;
        double piv;
        for (i = k + 1; i < 4; ++i)
            if (fabs(A[4 * i + k]) > fabs(A[4 * p + k]))
                p = i;
        if (!(fabs(A[4 * p + k]) > 0.0))
            return 0;
        if (p != k) {
            for (j = 0; j < 4; ++j) {
                double s = A[4 * k + j];
                A[4 * k + j] = A[4 * p + j];
                A[4 * p + j] = s;
            }
            piv = b[k];
            b[k] = b[p];
            b[p] = piv;
        }
        for (i = k + 1; i < 4; ++i) {
            double f = A[4 * i + k] / A[4 * k + k];
            for (j = k; j < 4; ++j)
                A[4 * i + j] -= f * A[4 * k + j];
            b[i] -= f * b[k];
        }
    }
    for (k = 3; k >= 0; --k) {
        double s = b[k];
        for (j = k + 1; j < 4; ++j)
            s -= A[4 * k + j] * x[j];
        x[k] = s / A[4 * k + k];
        if (!isfinite(x[k]))
            return 0;
    }
    return 1;
}

static void rot_z(double th, double R[9])
{
    double c = cos(th), s = sin(th);
    double r[9] = {c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0};
    memcpy(R, r, sizeof r);
}

/* residuals (U1) of the four correspondences at (theta, t), and optionally
 * their Jacobian in (theta, t) (rows of 4) */
static void residuals4(const double *d1, const double *m1, const double *d2, const double *m2,
                       double th, const double t[3], double f[4], double *J)
{
    double R[9], Rd[9], row[4], drow[4];
    int k;
    rot_z(th, R);
    /* dRz/dtheta = [e_z]x Rz */
    {
        double c = cos(th), s = sin(th);
        double r[9] = {-s, -c, 0.0, c, -s, 0.0, 0.0, 0.0, 0.0};
        memcpy(Rd, r, sizeof r);
    }
    for (k = 0; k < 4; ++k) {
        row_of(R, d1 + 3 * k, m1 + 3 * k, d2 + 3 * k, m2 + 3 * k, row);
        f[k] = dot3(row, t) + row[3];
        if (J) {
            row_of(Rd, d1 + 3 * k, m1 + 3 * k, d2 + 3 * k, m2 + 3 * k, drow);
            J[4 * k] = dot3(drow, t) + drow[3];
            J[4 * k + 1] = row[0];
            J[4 * k + 2] = row[1];
            J[4 * k + 3] = row[2];
        }
    }
}

static double sumsq4(const double f[4])
{
    return f[0] * f[0] + f[1] * f[1] + f[2] * f[2] + f[3] * f[3];
}

static void polish(const double *d1, const double *m1, const double *d2, const double *m2,
                   double *th, double t[3])
{
    double f[4], J[16], dx[4], cost;
    int it;
    residuals4(d1, m1, d2, m2, *th, t, f, J);
    cost = sumsq4(f);
    for (it = 0; it < 3 && cost > 0.0; ++it) {
        double th2, t2[3], f2[4], c2;
        int i;
        if (!solve4(J, f, dx))
            return;
        th2 = *th - dx[0];
        for (i = 0; i < 3; ++i)
            t2[i] = t[i] - dx[1 + i];
        residuals4(d1, m1, d2, m2, th2, t2, f2, J);
        c2 = sumsq4(f2);
        if (!(c2 < cost))
            return;
        *th = th2;
        memcpy(t, t2, sizeof t2);
        cost = c2;
    }
}

/* One ray in the upright frame Q (vertical along z): its unit direction
 * e = Q d inv_norm and the moment n = (Q (o - c) / s) x e of the line through
 * the normalised origin (Pluecker coordinates, thesis ch. 2.3). */
static void upright_line(const double Q[9], const double d[3], double inv_norm,
                         const double o[3], const double c[3], double s, double e[3],
                         double n[3])
{
    double a[3], b[3], u[3];
    int i;
    for (i = 0; i < 3; ++i) {
        a[i] = d[i] * inv_norm;
        b[i] = (o[i] - c[i]) / s;
    }
    mat_vec(Q, a, e);
    mat_vec(Q, b, u);
    cross3(u, e, n);
}

int mcg_upright4(const double o1[12], const double d1[12], const double o2[12],
                 const double d2[12], const double g1[3], const double g2[3], double R[72],
                 double t[24], int *n_solutions)
{
    double Q1[9], Q2[9], u1[3], u2[3], c[3] = {0.0, 0.0, 0.0}, s = 0.0;
    double e1[12], n1[12], e2[12], n2[12]; /* upright unit directions and moments */
    double Mq[3][16], P[3][9], poly[9], roots[8], lead = 0.0;
    int k, i, j, deg, nr, ns = 0;
    static const int pairs[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

    if (!o1 || !d1 || !o2 || !d2 || !g1 || !g2 || !R || !t || !n_solutions)
        return MCG_EINVAL;
    *n_solutions = 0;
    if (!all_finite(o1, 12) || !all_finite(d1, 12) || !all_finite(o2, 12) ||
        !all_finite(d2, 12) || !all_finite(g1, 3) || !all_finite(g2, 3))
        return MCG_EINVAL;
    {
        double a = dot3(g1, g1), b = dot3(g2, g2);
        if (!(a >= DIR2_MIN && b >= DIR2_MIN && isfinite(a) && isfinite(b)))
            return MCG_EINVAL;
        for (i = 0; i < 3; ++i) {
            u1[i] = g1[i] / sqrt(a);
            u2[i] = g2[i] / sqrt(b);
        }
    }
    upright_rotation(u1, Q1);
    upright_rotation(u2, Q2);
    /* centre c and scale s of the origins (both times, rig frames) */
    for (k = 0; k < 4; ++k)
        for (i = 0; i < 3; ++i)
            c[i] += (o1[3 * k + i] + o2[3 * k + i]) / 8.0;
    for (k = 0; k < 4; ++k)
        for (i = 0; i < 3; ++i)
            s = fmax(s, fmax(fabs(o1[3 * k + i] - c[i]), fabs(o2[3 * k + i] - c[i])));
    if (!isfinite(s))
        return MCG_EINVAL;
    if (!(s > 0.0))
        s = 1.0; /* one centre: central rays, no metric scale (handled below) */
    for (k = 0; k < 4; ++k) {
        double x = dot3(d1 + 3 * k, d1 + 3 * k), y = dot3(d2 + 3 * k, d2 + 3 * k);
        if (!(x >= DIR2_MIN && y >= DIR2_MIN && isfinite(x) && isfinite(y)))
            return MCG_EINVAL;
        upright_line(Q1, d1 + 3 * k, 1.0 / sqrt(x), o1 + 3 * k, c, s, e1 + 3 * k, n1 + 3 * k);
        upright_line(Q2, d2 + 3 * k, 1.0 / sqrt(y), o2 + 3 * k, c, s, e2 + 3 * k, n2 + 3 * k);
    }
    /* (U2): the coefficient matrices of q^0, q^1, q^2 */
    memset(P, 0, sizeof P);
    P[0][0] = P[0][4] = P[0][8] = 1.0;
    P[1][1] = -2.0;
    P[1][3] = 2.0;
    P[2][0] = P[2][4] = -1.0;
    P[2][8] = 1.0;
    for (j = 0; j < 3; ++j)
        for (k = 0; k < 4; ++k)
            row_of(P[j], e1 + 3 * k, n1 + 3 * k, e2 + 3 * k, n2 + 3 * k, Mq[j] + 4 * k);
    /* (U3): det M(q) by the Laplace expansion over rows (0, 1) | (2, 3) */
    for (i = 0; i < 9; ++i)
        poly[i] = 0.0;
    for (j = 0; j < 6; ++j) {
        int a = pairs[j][0], b = pairs[j][1], cc = pairs[5 - j][0], dd = pairs[5 - j][1];
        /* entries (row, column) of the two 2 x 2 minors, each a quadratic in q */
        const int rc[8][2] = {{0, a}, {1, b}, {0, b}, {1, a}, {2, cc}, {3, dd}, {2, dd}, {3, cc}};
        double e[8][3], m01[5], m23[5], x[5], y[5], prod[9];
        double sign = ((a + b + 1) & 1) ? -1.0 : 1.0;
        int q;
        for (q = 0; q < 8; ++q)
            for (i = 0; i < 3; ++i)
                e[q][i] = Mq[i][4 * rc[q][0] + rc[q][1]];
        poly_mul(e[0], 2, e[1], 2, x);
        poly_mul(e[2], 2, e[3], 2, y);
        for (i = 0; i < 5; ++i)
            m01[i] = x[i] - y[i];
        poly_mul(e[4], 2, e[5], 2, x);
        poly_mul(e[6], 2, e[7], 2, y);
        for (i = 0; i < 5; ++i)
            m23[i] = x[i] - y[i];
        poly_mul(m01, 4, m23, 4, prod);
        for (i = 0; i < 9; ++i)
            poly[i] += sign * prod[i];
    }
    for (i = 0; i < 9; ++i)
        lead = fmax(lead, fabs(poly[i]));
    if (!(lead > 0.0) || !isfinite(lead))
        return isfinite(lead) ? MCG_EDEGENERATE : MCG_EINVAL;
    for (i = 0; i < 9; ++i)
        poly[i] /= lead;
    /* drop leading coefficients lost in rounding (roots near q = infinity) */
    deg = 8;
    while (deg > 0 && fabs(poly[deg]) <= 1e-14)
        --deg;
    if (deg == 0)
        return MCG_EDEGENERATE; /* det M identically 0: every yaw fits */
    nr = real_roots(poly, deg, roots);
    for (j = 0; j < nr; ++j) {
        double q = roots[j], M[16], v[4], tu[3], th, Ry[9], Rt[9], Rc[3];
        for (i = 0; i < 16; ++i)
            M[i] = Mq[0][i] + q * (Mq[1][i] + q * Mq[2][i]);
        null4(M, v);
        if (!(fabs(v[3]) > 1e-12 * sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] + v[3] * v[3])))
            continue; /* no finite translation */
        for (i = 0; i < 3; ++i)
            tu[i] = v[i] / v[3];
        th = 2.0 * atan(q);
        polish(e1, n1, e2, n2, &th, tu);
        rot_z(th, Ry);
        /* R = Q2^T Rz Q1 */
        mul33(Ry, Q1, Rt);
        for (i = 0; i < 3; ++i)
            for (k = 0; k < 3; ++k)
                R[9 * ns + 3 * i + k] = Q2[i] * Rt[k] + Q2[3 + i] * Rt[3 + k] +
                                        Q2[6 + i] * Rt[6 + k];
        /* t = s Q2^T t' + c - R c */
        mat_vec(R + 9 * ns, c, Rc);
        for (i = 0; i < 3; ++i)
            t[3 * ns + i] = s * (Q2[i] * tu[0] + Q2[3 + i] * tu[1] + Q2[6 + i] * tu[2]) + c[i] -
                            Rc[i];
        if (!all_finite(R + 9 * ns, 9) || !all_finite(t + 3 * ns, 3))
            continue;
        ++ns;
    }
    *n_solutions = ns;
    return MCG_OK;
}
