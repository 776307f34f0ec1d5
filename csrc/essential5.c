/*
 * essential5.c -- the minimal 5-point essential-matrix solver (the 5-point
 * camera of the 5+1 method, thesis ch. 7.4) and the decomposition of an
 * essential matrix into the motion with cheirality.
 *
 * Formulation: D. Nister, "An efficient solution to the five-point relative
 * pose problem", IEEE PAMI 26(6), 2004 (sections 3.1-3.3), written here from
 * the paper:
 *   1. the five epipolar constraints d2^T E d1 = 0 are linear in the nine
 *      entries of E; E lies in their 4-dimensional null space,
 *      E = x X + y Y + z Z + W (eq. 9), found by Householder QR of the 9 x 5
 *      transposed constraint matrix (more stable than Gauss-Jordan on 5 x 9
 *      when two correspondences are nearly equal);
 *   2. det E = 0 (eq. 3) and the trace constraint 2 E E^T E - tr(E E^T) E = 0
 *      (eq. 4) give ten cubics in (x, y, z): a 10 x 20 matrix over the
 *      monomials in Nister's order (x^3, y^3, x^2y, xy^2, x^2z, x^2, y^2z, y^2,
 *      xyz, xy | xz^2, xz, x, yz^2, yz, y, z^3, z^2, z, 1);
 *   3. elimination of the first ten columns (partial pivoting); the rows
 *      <e>-z<f>, <g>-z<h>, <i>-z<j> (the paper's <k>, <l>, <m>) are
 *      [x y 1] B(z) with B of degrees 3, 3, 4 in its columns, and the real
 *      roots of the degree-10 polynomial det B(z) are the solutions' z;
 *   4. x, y from the null vector of B(z) (cross product of two of its rows);
 *      a solution that violates eqs. 3-4 by more than 1e-11 (unit-norm E) is
 *      polished by Gauss-Newton on the ten original cubics (the elimination
 *      and a clustered root lose digits), and one that still violates them
 *      by more than 1e-6 is dropped (a root made up by rounding).
 *
 * Roots of the degree-10 polynomial: Sturm sequences with bisection to
 * isolate every real root (from Fujiwara's bound), then a bracketed Newton
 * iteration (Nister's section 3.3 recommends Sturm sequences). Why not
 * companion-matrix eigenvalues: they need a nonsymmetric QR eigenvalue
 * solver (the library has no LAPACK, and a 10 x 10 Hessenberg QR costs
 * more than the whole solver), and they compute the complex roots too (on
 * average about 5.3 of the 10 are complex and discarded), whereas a Sturm
 * count costs one Horner pass over the chain (66 multiply-adds) and only
 * the real roots are refined.
 */
#include "mcgeom.h"
#include "internal.h"
#include "poly.h"

#include <float.h>
#include <math.h>
#include <stddef.h>
#include <string.h>

#define DEG 10            /* degree of det B(z) */
#define MAX_BISECT 80     /* bisection levels when isolating roots */
#define MAX_POLISH 60     /* bracketed Newton steps per root */
#define NEWTON_DONE 1e-9  /* relative Newton step after which a root is final */
#define DIR2_MIN 1e-100   /* smallest squared length of a bearing */
#define RANK_TOL 1e-11    /* relative pivot below which the data is degenerate */
#define MAX_VIOLATION 1e-6 /* of eqs. 3, 4 by a returned unit-norm E */
/* Violation above which a solution is polished. 1e-13 before (issue 19):
 * on 5-point samples of a RANSAC (noisy pairs, a third of the samples with
 * an outlier) 23 % of the roots were polished, most of them violating by
 * 1e-13..1e-11, and the polish was a tenth of the solver's time; at 1e-11,
 * 9 % (time per call -7 %). The solutions stay far more exact than any
 * data: test_essential5's noise-free motions are recovered to 1.7e-9 in R
 * and 6.4e-9 in t (6.6e-10 and 2.5e-9 before). */
#define POLISH_TRIGGER 1e-11

/* ----------------------------------------------------- polynomial helpers */

/* Index in the 20 cubic monomials (Nister's column order) of the product of
 * the quadratic monomial q (x^2, xy, xz, y^2, yz, z^2, x, y, z, 1) and the
 * linear monomial l (x, y, z, 1). */
static const unsigned char CUB_OF[10][4] = {
    {0, 2, 4, 5},     /* x^2 */
    {2, 3, 8, 9},     /* xy  */
    {4, 8, 10, 11},   /* xz  */
    {3, 1, 6, 7},     /* y^2 */
    {8, 6, 13, 14},   /* yz  */
    {10, 13, 16, 17}, /* z^2 */
    {5, 9, 11, 12},   /* x   */
    {9, 7, 14, 15},   /* y   */
    {11, 14, 17, 18}, /* z   */
    {12, 15, 18, 19}, /* 1   */
};

/* Index in the 10 quadratic monomials of the product of two linear ones. */
static const unsigned char QUAD_OF[4][4] = {
    {0, 1, 2, 6}, {1, 3, 4, 7}, {2, 4, 5, 8}, {6, 7, 8, 9}};

/* q += a * b for linear a, b (coefficients of x, y, z, 1) */
static void lin_mul_add(const double a[4], const double b[4], double q[10], double sign)
{
    int i, j;
    for (i = 0; i < 4; ++i)
        for (j = 0; j < 4; ++j)
            q[QUAD_OF[i][j]] += sign * a[i] * b[j];
}

/* c += q * a for quadratic q and linear a */
static void quad_mul_add(const double q[10], const double a[4], double c[20])
{
    int i, j;
    for (i = 0; i < 10; ++i)
        for (j = 0; j < 4; ++j)
            c[CUB_OF[i][j]] += q[i] * a[j];
}

/* c += sum_k q_k * a_k (k = 0..2) for quadratic q_k and linear a_k: an entry
 * of the product of a quadratic row and a linear column. The 40 sums are
 * formed first and scattered once (a third of the indexed updates of three
 * quad_mul_add calls; this product is most of the cost of step 2). */
static void row_times_col(const double q0[10], const double q1[10], const double q2[10],
                          const double a0[4], const double a1[4], const double a2[4],
                          double c[20])
{
    double s[10][4];
    int i, j;
    for (i = 0; i < 10; ++i)
        for (j = 0; j < 4; ++j)
            s[i][j] = q0[i] * a0[j] + q1[i] * a1[j] + q2[i] * a2[j];
    for (i = 0; i < 10; ++i)
        for (j = 0; j < 4; ++j)
            c[CUB_OF[i][j]] += s[i][j];
}


/* ------------------------------------------------- step 1: the null space */

/* The four null vectors of the 5 x 9 constraint matrix A (row k: coefficient
 * of E_ij is d2_i d1_j, E row-major), as rows of basis (4 x 9): the last four
 * columns of the orthogonal factor of A^T = Q R (Householder). Returns 0 when
 * A has rank < 5 (repeated or degenerate correspondences). */
static int null_space(const double *d1, const double *d2, double basis[36])
{
    double a[9][5], v[5][9], beta[5], s[5], rmax = 0.0;
    int k, i, j, c;
    for (k = 0; k < 5; ++k) {
        double u1[3], u2[3];
        /* lengths without overflow: bearings of any non-zero length */
        double n1 = norm_scaled(d1 + 3 * k, 3), n2 = norm_scaled(d2 + 3 * k, 3);
        for (i = 0; i < 3; ++i) {
            u1[i] = d1[3 * k + i] / n1;
            u2[i] = d2[3 * k + i] / n2;
        }
        for (i = 0; i < 3; ++i)
            for (j = 0; j < 3; ++j)
                a[3 * i + j][k] = u2[i] * u1[j];
    }
    /* Householder reflections H_c = I - beta_c v_c v_c^T, v_c zero above c */
    for (c = 0; c < 5; ++c) {
        double norm = 0.0, alpha, vnorm2;
        for (i = c; i < 9; ++i)
            norm += a[i][c] * a[i][c];
        norm = sqrt(norm);
        for (i = 0; i < 9; ++i)
            v[c][i] = 0.0;
        alpha = a[c][c] > 0.0 ? -norm : norm;
        for (i = c; i < 9; ++i)
            v[c][i] = a[i][c];
        v[c][c] -= alpha;
        vnorm2 = 0.0;
        for (i = c; i < 9; ++i)
            vnorm2 += v[c][i] * v[c][i];
        beta[c] = vnorm2 > 0.0 ? 2.0 / vnorm2 : 0.0;
        /* H_c on the columns c..4: their dot products with v_c side by side
         * (independent sums, each in the order of i) */
        for (j = c; j < 5; ++j)
            s[j] = 0.0;
        for (i = c; i < 9; ++i)
            for (j = c; j < 5; ++j)
                s[j] += v[c][i] * a[i][j];
        for (j = c; j < 5; ++j) {
            s[j] *= beta[c];
            for (i = c; i < 9; ++i)
                a[i][j] -= s[j] * v[c][i];
        }
        if (fabs(a[c][c]) > rmax)
            rmax = fabs(a[c][c]);
    }
    for (c = 0; c < 5; ++c)
        if (!(fabs(a[c][c]) > RANK_TOL * rmax))
            return 0;
    /* basis row r = H_0 H_1 ... H_4 e_{5 + r}, the four rows side by side */
    for (k = 0; k < 4; ++k)
        for (i = 0; i < 9; ++i)
            basis[9 * k + i] = (i == 5 + k) ? 1.0 : 0.0;
    for (c = 4; c >= 0; --c) {
        for (k = 0; k < 4; ++k)
            s[k] = 0.0;
        for (i = c; i < 9; ++i)
            for (k = 0; k < 4; ++k)
                s[k] += v[c][i] * basis[9 * k + i];
        for (k = 0; k < 4; ++k) {
            s[k] *= beta[c];
            for (i = c; i < 9; ++i)
                basis[9 * k + i] -= s[k] * v[c][i];
        }
    }
    return 1;
}

/* ----------------------------------- step 2: the ten cubic constraints */

/* m (10 x 20): rows 0..8 the entries of E E^T E - tr(E E^T) E / 2 (eq. 4,
 * halved), row 9 det E (eq. 3), over the monomials in Nister's order, for
 * E_ij = x X_ij + y Y_ij + z Z_ij + W_ij (basis rows X, Y, Z, W). */
static void cubic_constraints(const double basis[36], double m[10][20])
{
    double e[9][4], p[9][10], cof[3][10], tr[10];
    int i, j, k, r;
    for (i = 0; i < 9; ++i)
        for (k = 0; k < 4; ++k)
            e[i][k] = basis[9 * k + i];
    /* P = E E^T - tr(E E^T) / 2 I (quadratic entries) */
    for (i = 0; i < 9; ++i)
        for (k = 0; k < 10; ++k)
            p[i][k] = 0.0;
    for (i = 0; i < 3; ++i)
        for (j = i; j < 3; ++j) {
            for (k = 0; k < 3; ++k)
                lin_mul_add(e[3 * i + k], e[3 * j + k], p[3 * i + j], 1.0);
            if (j > i)
                for (k = 0; k < 10; ++k)
                    p[3 * j + i][k] = p[3 * i + j][k];
        }
    for (k = 0; k < 10; ++k)
        tr[k] = 0.5 * (p[0][k] + p[4][k] + p[8][k]);
    for (i = 0; i < 3; ++i)
        for (k = 0; k < 10; ++k)
            p[4 * i][k] -= tr[k];
    for (r = 0; r < 10; ++r)
        for (k = 0; k < 20; ++k)
            m[r][k] = 0.0;
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j)
            row_times_col(p[3 * i], p[3 * i + 1], p[3 * i + 2], e[j], e[3 + j], e[6 + j],
                          m[3 * i + j]);
    /* det E along the first row: cofactors of E_00, E_01, E_02 */
    for (i = 0; i < 3; ++i)
        for (k = 0; k < 10; ++k)
            cof[i][k] = 0.0;
    lin_mul_add(e[4], e[8], cof[0], 1.0);
    lin_mul_add(e[5], e[7], cof[0], -1.0);
    lin_mul_add(e[5], e[6], cof[1], 1.0);
    lin_mul_add(e[3], e[8], cof[1], -1.0);
    lin_mul_add(e[3], e[7], cof[2], 1.0);
    lin_mul_add(e[4], e[6], cof[2], -1.0);
    for (i = 0; i < 3; ++i)
        quad_mul_add(cof[i], e[i], m[9]);
}

/* Elimination of the first ten columns with partial pivoting, reduced only
 * as far as step 3 needs: afterwards rows 4..9 (Nister's <e> .. <j>) read
 * monomial_r + sum_k m[r][10 + k] monomial_{10 + k}. Forward elimination
 * makes the 10 x 10 block upper triangular; back substitution then only
 * involves rows 4..9 (rows 0..3 are never used). scale: max |m| (the
 * caller has it). Returns 0 on a (relatively) zero pivot. */
static int gauss_jordan(double m[10][20], double scale)
{
    int c, r, k, piv;
    if (!(scale > 0.0))
        return 0;
    for (c = 0; c < 10; ++c) {
        double best = 0.0, inv;
        piv = -1;
        for (r = c; r < 10; ++r)
            if (fabs(m[r][c]) > best) {
                best = fabs(m[r][c]);
                piv = r;
            }
        if (piv < 0 || !(best > RANK_TOL * scale))
            return 0;
        if (piv != c)
            for (k = c; k < 20; ++k) {
                double tmp = m[c][k];
                m[c][k] = m[piv][k];
                m[piv][k] = tmp;
            }
        inv = 1.0 / m[c][c];
        for (k = c; k < 20; ++k)
            m[c][k] *= inv;
        for (r = c + 1; r < 10; ++r) {
            double f = m[r][c];
            if (f == 0.0)
                continue;
            for (k = c; k < 20; ++k)
                m[r][k] -= f * m[c][k];
        }
    }
    for (c = 9; c > 4; --c)
        for (r = 4; r < c; ++r) {
            double f = m[r][c];
            if (f == 0.0)
                continue;
            for (k = 10; k < 20; ++k)
                m[r][k] -= f * m[c][k];
            m[r][c] = 0.0;
        }
    return 1;
}

/* ------------------------------- step 3: B(z) and the degree-10 polynomial */

/* Row <a> - z <b> of Nister's section 3.2 as [x y 1] coefficients: bx, by
 * (degree 3 in z), b1 (degree 4), rising powers. */
static void b_row(const double *ra, const double *rb, double bx[4], double by[4], double b1[5])
{
    /* the eliminated columns: xz^2 xz x | yz^2 yz y | z^3 z^2 z 1 */
    const double *a = ra + 10, *b = rb + 10;
    bx[0] = a[2];
    bx[1] = a[1] - b[2];
    bx[2] = a[0] - b[1];
    bx[3] = -b[0];
    by[0] = a[5];
    by[1] = a[4] - b[5];
    by[2] = a[3] - b[4];
    by[3] = -b[3];
    b1[0] = a[9];
    b1[1] = a[8] - b[9];
    b1[2] = a[7] - b[8];
    b1[3] = a[6] - b[7];
    b1[4] = -b[6];
}

/* p += sign f (a b - c d) for polynomials in z (rising powers) of degrees
 * nf, na, nb, nc, nd with na + nb = nc + nd and nf + na + nb = DEG: one
 * term of the cofactor expansion of det B(z) */
static void add_cofactor_term(const double *f, int nf, const double *a, int na, const double *b,
                              int nb, const double *c, int nc, const double *d, int nd,
                              double sign, double p[DEG + 1])
{
    double ab[DEG + 1], cd[DEG + 1], s[DEG + 1];
    int i;
    poly_mul(a, na, b, nb, ab);
    poly_mul(c, nc, d, nd, cd);
    for (i = 0; i <= na + nb; ++i)
        ab[i] -= cd[i];
    poly_mul(f, nf, ab, na + nb, s);
    for (i = 0; i <= DEG; ++i)
        p[i] += sign * s[i];
}

/* det of B(z) = [bx by b1] (rows k, l, m): degree 10, 11 coefficients, by
 * cofactors along the first row */
static void b_det(double bx[3][4], double by[3][4], double b1[3][5], double p[DEG + 1])
{
    int i;
    for (i = 0; i <= DEG; ++i)
        p[i] = 0.0;
    add_cofactor_term(bx[0], 3, by[1], 3, b1[2], 4, b1[1], 4, by[2], 3, 1.0, p);
    add_cofactor_term(by[0], 3, bx[1], 3, b1[2], 4, b1[1], 4, bx[2], 3, -1.0, p);
    add_cofactor_term(b1[0], 4, bx[1], 3, by[2], 3, by[1], 3, bx[2], 3, 1.0, p);
}

/* --------------------------------------------- real roots: Sturm chains */

/* The Sturm chain of a monic p of degree n: s_0 = p, s_1 = p', s_{k+1} =
 * -rem(s_{k-1}, s_k). Generic chains drop one degree per step; the chain is
 * cut at a remainder at rounding level (p and p' then share a factor: the
 * last element kept is gcd(p, p') up to sign and the chain still counts the
 * distinct real roots). Each element is kept and evaluated by Horner: the
 * shorter three-term recurrence s_{k+1} = q_k s_k - s_{k-1} loses the sign of
 * the last elements to cancellation away from the origin (tried: wrong
 * root counts on ~5 % of the 5-point problems). */
typedef struct {
    int len;               /* number of elements */
    int deg[DEG + 1];      /* degree of each element */
    double s[DEG + 1][DEG + 1];
} sturm_chain;

static void sturm_build(const double *p, int n, sturm_chain *sc)
{
    int i, k;
    for (i = 0; i <= n; ++i)
        sc->s[0][i] = p[i];
    for (i = 0; i < n; ++i)
        sc->s[1][i] = (i + 1) * p[i + 1];
    sc->deg[0] = n;
    sc->deg[1] = n - 1;
    sc->len = 2;
    for (k = 1; k < n && sc->deg[k] >= 1; ++k) {
        /* s_{k-1} = q s_k + rem by long division, rem of degree < deg s_k */
        double r[DEG + 1], scale = 0.0, rm = 0.0;
        int da = sc->deg[k - 1], db = sc->deg[k], j, dr;
        const double *b = sc->s[k];
        for (i = 0; i <= da; ++i) {
            r[i] = sc->s[k - 1][i];
            if (fabs(r[i]) > scale)
                scale = fabs(r[i]);
        }
        for (j = da - db; j >= 0; --j) {
            double q = r[db + j] / b[db];
            for (i = 0; i <= db; ++i)
                r[i + j] -= q * b[i];
            r[db + j] = 0.0;
        }
        for (i = 0; i < db; ++i)
            if (fabs(r[i]) > rm)
                rm = fabs(r[i]);
        if (!(rm > 1e-14 * scale) || !isfinite(rm))
            break;
        dr = db - 1;
        while (dr > 0 && !(fabs(r[dr]) > 1e-14 * rm))
            --dr;
        for (i = 0; i <= dr; ++i)
            sc->s[k + 1][i] = -r[i];
        sc->deg[k + 1] = dr;
        sc->len = k + 2;
    }
}

/* sign changes of the chain at z */
static int sturm_changes(const sturm_chain *sc, double z)
{
    double last = 0.0;
    int k, changes = 0;
    for (k = 0; k < sc->len; ++k) {
        double v = poly_eval(sc->s[k], sc->deg[k], z);
        if (v != 0.0) {
            if (last != 0.0 && (last < 0.0) != (v < 0.0))
                ++changes;
            last = v;
        }
    }
    return changes;
}

/* The root of p in the bracket [lo, hi] (p(lo), p(hi) of opposite signs or
 * one of them 0) by Newton steps kept inside the bracket, bisection when a
 * step leaves it or does not halve the bracket. */
static double polish_root(const sturm_chain *sc, double lo, double hi)
{
    double flo = poly_eval(sc->s[0], sc->deg[0], lo), fhi = poly_eval(sc->s[0], sc->deg[0], hi), x, dxold;
    int it, newton;
    if (flo == 0.0)
        return lo;
    if (fhi == 0.0)
        return hi;
    if ((flo < 0.0) == (fhi < 0.0))
        return 0.5 * (lo + hi); /* an even-multiplicity root (rounding) */
    if (flo > 0.0) {            /* orient: p(lo) < 0 < p(hi) */
        double t = lo;
        lo = hi;
        hi = t;
    }
    x = 0.5 * (lo + hi);
    dxold = fabs(hi - lo);
    for (it = 0; it < MAX_POLISH; ++it) {
        double f, df, dx, xn;
        poly_eval2(sc->s[0], sc->s[1], sc->deg[0], x, &f, &df);
        if (f == 0.0)
            return x;
        if (f < 0.0)
            lo = x;
        else
            hi = x;
        xn = df != 0.0 ? x - f / df : 0.5 * (lo + hi);
        newton = (xn - lo) * (xn - hi) < 0.0 && fabs(2.0 * (xn - x)) <= dxold;
        if (!newton) {
            xn = 0.5 * (lo + hi);
            dxold = fabs(hi - lo);
        } else {
            dxold = fabs(xn - x);
        }
        dx = xn - x;
        x = xn;
        /* a Newton step of relative size 1e-9 leaves an error of order its
         * square: converged (further steps only chase rounding noise) */
        if ((newton && fabs(dx) <= NEWTON_DONE * fabs(x)) || fabs(dx) <= 4.0 * DBL_EPSILON * fabs(x) ||
            lo == hi)
            break;
    }
    return x;
}

/* The distinct real roots of the monic polynomial of degree n (n <= DEG):
 * isolated by bisection of the Cauchy bound interval with Sturm counts.
 * Returns their number (<= n). */
static int real_roots(const double *p, int n, double *roots)
{
    sturm_chain sc;
    /* depth-first: one pop pushes at most two, so the stack never holds
     * more than MAX_BISECT + 2 intervals */
    double stack_lo[MAX_BISECT + 2], stack_hi[MAX_BISECT + 2];
    int stack_clo[MAX_BISECT + 2], stack_chi[MAX_BISECT + 2], depth[MAX_BISECT + 2];
    double bound = 0.0;
    int i, top = 0, nr = 0;
    if (n < 1)
        return 0;
    /* Fujiwara's bound: every root satisfies |z| <= 2 max(|p_{n-1}|,
     * |p_{n-2}|^(1/2), ..., |p_0 / 2|^(1/n)); far tighter than Cauchy's
     * 1 + max |p_i| when the coefficients are large, so fewer bisections */
    for (i = 0; i < n; ++i) {
        double c = fabs(p[i]) * (i == 0 ? 0.5 : 1.0);
        double r = (n - i == 1) ? c : pow(c, 1.0 / (n - i));
        if (r > bound)
            bound = r;
    }
    bound = 2.0 * bound * (1.0 + 1e-12) + DBL_MIN; /* strictly outside every root */
    if (!isfinite(bound))
        return 0;
    sturm_build(p, n, &sc);
    stack_lo[0] = -bound;
    stack_hi[0] = bound;
    stack_clo[0] = sturm_changes(&sc, -bound);
    stack_chi[0] = sturm_changes(&sc, bound);
    depth[0] = 0;
    top = 1;
    while (top > 0 && nr < n) {
        double lo, hi, mid;
        int clo, chi, cmid, cnt, d;
        --top;
        lo = stack_lo[top];
        hi = stack_hi[top];
        clo = stack_clo[top];
        chi = stack_chi[top];
        d = depth[top];
        cnt = clo - chi;
        if (cnt <= 0)
            continue;
        if (cnt == 1) {
            roots[nr++] = polish_root(&sc, lo, hi);
            continue;
        }
        mid = 0.5 * (lo + hi);
        if (d >= MAX_BISECT || mid <= lo || mid >= hi) {
            roots[nr++] = mid; /* a cluster below resolution: one root */
            continue;
        }
        cmid = sturm_changes(&sc, mid);
        if (top + 2 > MAX_BISECT + 2)
            break; /* cannot happen (see above) */
        stack_lo[top] = lo;
        stack_hi[top] = mid;
        stack_clo[top] = clo;
        stack_chi[top] = cmid;
        depth[top++] = d + 1;
        stack_lo[top] = mid;
        stack_hi[top] = hi;
        stack_clo[top] = cmid;
        stack_chi[top] = chi;
        depth[top++] = d + 1;
    }
    return nr;
}

/* ---------------------------------------- step 4: polishing the solutions */

/* The 20 monomials at (x, y, z) in Nister's order and their partial
 * derivatives */
static void monomials(double x, double y, double z, double m[20], double mx[20], double my[20],
                      double mz[20])
{
    int i;
    m[0] = x * x * x; m[1] = y * y * y; m[2] = x * x * y; m[3] = x * y * y;
    m[4] = x * x * z; m[5] = x * x; m[6] = y * y * z; m[7] = y * y;
    m[8] = x * y * z; m[9] = x * y; m[10] = x * z * z; m[11] = x * z;
    m[12] = x; m[13] = y * z * z; m[14] = y * z; m[15] = y;
    m[16] = z * z * z; m[17] = z * z; m[18] = z; m[19] = 1.0;
    for (i = 0; i < 20; ++i)
        mx[i] = my[i] = mz[i] = 0.0;
    mx[0] = 3 * x * x; mx[2] = 2 * x * y; mx[3] = y * y; mx[4] = 2 * x * z; mx[5] = 2 * x;
    mx[8] = y * z; mx[9] = y; mx[10] = z * z; mx[11] = z; mx[12] = 1.0;
    my[1] = 3 * y * y; my[2] = x * x; my[3] = 2 * x * y; my[6] = 2 * y * z; my[7] = 2 * y;
    my[8] = x * z; my[9] = x; my[13] = z * z; my[14] = z; my[15] = 1.0;
    mz[4] = x * x; mz[6] = y * y; mz[8] = x * y; mz[10] = 2 * x * z; mz[11] = x;
    mz[13] = 2 * y * z; mz[14] = y; mz[16] = 3 * z * z; mz[17] = 2 * z; mz[18] = 1.0;
}

/* Relative residual |M m(x, y, z)| / (max|M| |m|) of the ten cubics, their
 * values in r and, when jac is not NULL, their Jacobian (10 x 3) */
static double cubic_residual(double m0[10][20], double mmax, const double v[3], double r[10],
                             double jac[10][3])
{
    double m[20], mx[20], my[20], mz[20], rr = 0.0, mm = 0.0;
    int i, k;
    monomials(v[0], v[1], v[2], m, mx, my, mz);
    for (i = 0; i < 10; ++i) {
        double a = 0.0;
        for (k = 0; k < 20; ++k)
            a += m0[i][k] * m[k];
        r[i] = a;
        rr += a * a;
    }
    if (jac != NULL)
        for (i = 0; i < 10; ++i) {
            double bx = 0.0, by = 0.0, bz = 0.0;
            for (k = 0; k < 20; ++k) {
                bx += m0[i][k] * mx[k];
                by += m0[i][k] * my[k];
                bz += m0[i][k] * mz[k];
            }
            jac[i][0] = bx;
            jac[i][1] = by;
            jac[i][2] = bz;
        }
    for (k = 0; k < 20; ++k)
        mm += m[k] * m[k];
    return sqrt(rr) / (mmax * sqrt(mm));
}

/* Gauss-Newton on the ten cubics (eqs. 3, 4) in (x, y, z) from the root of
 * the univariate polynomial: the elimination and a root of a clustered
 * degree-10 polynomial lose digits that the original system gives back.
 * A step is kept only when it lowers the residual; at most POLISH_STEPS. */
#define POLISH_STEPS 4
#define POLISH_TOL 1e-12
static void polish_xyz(double m0[10][20], double mmax, double v[3])
{
    double r[10], jac[10][3], res = cubic_residual(m0, mmax, v, r, NULL);
    int it, i, j, k;
    if (res <= POLISH_TOL)
        return; /* most roots: the elimination kept enough digits */
    res = cubic_residual(m0, mmax, v, r, jac);
    for (it = 0; it < POLISH_STEPS && res > POLISH_TOL; ++it) {
        double a[9], g[3], dv[3], vn[3], rn[10], jn[10][3], resn, det;
        for (i = 0; i < 3; ++i) {
            g[i] = 0.0;
            for (j = 0; j < 3; ++j) {
                a[3 * i + j] = 0.0;
                for (k = 0; k < 10; ++k)
                    a[3 * i + j] += jac[k][i] * jac[k][j];
            }
            for (k = 0; k < 10; ++k)
                g[i] -= jac[k][i] * r[k];
        }
        det = det33(a);
        if (!(fabs(det) > 0.0) || !isfinite(det))
            return;
        /* Cramer's rule on the 3 x 3 normal equations */
        for (i = 0; i < 3; ++i) {
            double b[9];
            for (j = 0; j < 9; ++j)
                b[j] = a[j];
            for (j = 0; j < 3; ++j)
                b[3 * j + i] = g[j];
            dv[i] = det33(b) / det;
        }
        for (i = 0; i < 3; ++i)
            vn[i] = v[i] + dv[i];
        resn = cubic_residual(m0, mmax, vn, rn, jn);
        if (!(resn < res))
            return;
        res = resn;
        for (i = 0; i < 3; ++i)
            v[i] = vn[i];
        for (k = 0; k < 10; ++k) {
            r[k] = rn[k];
            for (j = 0; j < 3; ++j)
                jac[k][j] = jn[k][j];
        }
    }
}

/* Largest violation of det E = 0 (eq. 3) and 2 E E^T E - tr(E E^T) E = 0
 * (eq. 4) by a unit-norm E */
static double essential_violation(const double e[9])
{
    double eet[9], m[9], tr, worst = fabs(det33(e));
    int i;
    mul33_abt(e, e, eet);
    tr = eet[0] + eet[4] + eet[8];
    mul33(eet, e, m);
    for (i = 0; i < 9; ++i)
        if (!(fabs(2.0 * m[i] - tr * e[i]) <= worst))
            worst = fabs(2.0 * m[i] - tr * e[i]);
    return worst;
}

/* The null vector of a 3 x 3 matrix of rank 2 (rows r): the largest of the
 * cross products of two of its rows, in v; returns its squared length (0
 * or less: rank <= 1; -1 when no product is finite). */
static double largest_cross(double r[3][3], double v[3])
{
    double best = -1.0;
    int a;
    v[0] = v[1] = v[2] = 0.0;
    for (a = 0; a < 3; ++a) {
        double c[3], nn;
        cross3(r[a], r[(a + 1) % 3], c);
        nn = dot3(c, c);
        if (nn > best) {
            best = nn;
            v[0] = c[0];
            v[1] = c[1];
            v[2] = c[2];
        }
    }
    return best;
}

/* e = v0 X + v1 Y + v2 (z Z + W) scaled to unit Frobenius norm; 0 if that
 * is impossible (zero or not finite) */
static int unit_e(const double basis[36], const double v[3], double z, double e[9])
{
    double norm = 0.0;
    int i;
    for (i = 0; i < 9; ++i) {
        e[i] = v[0] * basis[i] + v[1] * basis[9 + i] + v[2] * (z * basis[18 + i] + basis[27 + i]);
        norm += e[i] * e[i];
    }
    norm = sqrt(norm);
    if (!(norm > 0.0) || !isfinite(norm))
        return 0;
    for (i = 0; i < 9; ++i)
        e[i] /= norm;
    return 1;
}

/* ------------------------------------------------------------ entry point */

int mcg_essential5(const double d1[15], const double d2[15], double E[90], int *n_solutions)
{
    double basis[36], m[10][20], bx[3][4], by[3][4], b1[3][5], poly[DEG + 1], roots[DEG];
    double m0[10][20], lead, pmax = 0.0, mmax = 0.0;
    int k, i, n, nr, deg, ns = 0;
    if (d1 == NULL || d2 == NULL || E == NULL || n_solutions == NULL)
        return MCG_EINVAL;
    *n_solutions = 0;
    if (!all_finite(d1, 15) || !all_finite(d2, 15))
        return MCG_EINVAL;
    for (k = 0; k < 5; ++k)
        if (!(dot3(d1 + 3 * k, d1 + 3 * k) > DIR2_MIN) ||
            !(dot3(d2 + 3 * k, d2 + 3 * k) > DIR2_MIN))
            return MCG_EINVAL;
    if (!null_space(d1, d2, basis))
        return MCG_OK;
    cubic_constraints(basis, m);
    memcpy(m0, m, sizeof m0);
    for (i = 0; i < 10; ++i)
        for (k = 0; k < 20; ++k)
            if (fabs(m[i][k]) > mmax)
                mmax = fabs(m[i][k]);
    if (!gauss_jordan(m, mmax))
        return MCG_OK;
    /* <k> = <e> - z<f>, <l> = <g> - z<h>, <m> = <i> - z<j>: rows 4..9 */
    b_row(m[4], m[5], bx[0], by[0], b1[0]);
    b_row(m[6], m[7], bx[1], by[1], b1[1]);
    b_row(m[8], m[9], bx[2], by[2], b1[2]);
    b_det(bx, by, b1, poly);
    for (i = 0; i <= DEG; ++i)
        if (fabs(poly[i]) > pmax)
            pmax = fabs(poly[i]);
    if (!(pmax > 0.0) || !isfinite(pmax))
        return MCG_OK;
    /* leading coefficients at rounding level: roots at infinity (solutions
     * with w = 0, on a measure-zero set of data) are dropped */
    deg = DEG;
    while (deg > 0 && !(fabs(poly[deg]) > 1e-14 * pmax))
        --deg;
    if (deg == 0)
        return MCG_OK;
    lead = poly[deg];
    for (i = 0; i <= deg; ++i)
        poly[i] /= lead;
    nr = real_roots(poly, deg, roots);
    for (n = 0; n < nr; ++n) {
        double z = roots[n], z2 = z * z, z3 = z2 * z, z4 = z3 * z;
        double row[3][3], v[3], best;
        double *e = E + 9 * ns;
        for (k = 0; k < 3; ++k) {
            row[k][0] = bx[k][0] + bx[k][1] * z + bx[k][2] * z2 + bx[k][3] * z3;
            row[k][1] = by[k][0] + by[k][1] * z + by[k][2] * z2 + by[k][3] * z3;
            row[k][2] = b1[k][0] + b1[k][1] * z + b1[k][2] * z2 + b1[k][3] * z3 +
                        b1[k][4] * z4;
        }
        /* B(z) [x y 1]^T = 0: the null vector of B(z) */
        best = largest_cross(row, v);
        if (!(best > 0.0))
            continue;
        if (!unit_e(basis, v, z, e))
            continue;
        /* the digits the elimination lost on ill-conditioned roots come
         * back from Gauss-Newton on the original cubics (when the solution
         * is at a finite (x, y); most roots skip this) */
        if (essential_violation(e) > POLISH_TRIGGER && fabs(v[2]) > 1e-8 * sqrt(best)) {
            double xyz[3];
            xyz[0] = v[0] / v[2];
            xyz[1] = v[1] / v[2];
            xyz[2] = z;
            polish_xyz(m0, mmax, xyz);
            v[0] = xyz[0];
            v[1] = xyz[1];
            v[2] = 1.0;
            if (!unit_e(basis, v, xyz[2], e))
                continue;
        }
        /* a root that rounding made up, or one too ill-conditioned to give
         * an essential matrix, is not a solution */
        if (!(essential_violation(e) <= MAX_VIOLATION))
            continue;
        ++ns;
    }
    *n_solutions = ns;
    return MCG_OK;
}

/* ---------------------------------------------- decomposition with cheirality */

/* Number of the n pairs for which the point triangulated by (R, t) lies in
 * front of both cameras (*pos) and, for (R, -t), behind both (*neg: in
 * front for -t). Depths: least squares of lam2 d2 = lam1 R d1 + t; their
 * signs are those of -((a.t)(b.b) - (a.b)(b.t)) and -((a.b)(a.t) - (a.a)(b.t))
 * with a = R d1, b = d2 (the 2 x 2 normal equations have determinant
 * -|a x b|^2 < 0). Parallel rays (a point at infinity) count for neither. */
static void count_front(const double R[9], const double t[3], const double *d1, const double *d2,
                        int n, int *pos, int *neg)
{
    int k, np = 0, nn = 0;
    for (k = 0; k < n; ++k) {
        double a[3], aa, bb, ab, at, bt, l1, l2;
        const double *b = d2 + 3 * k;
        mat_vec(R, d1 + 3 * k, a);
        aa = dot3(a, a);
        bb = dot3(b, b);
        ab = dot3(a, b);
        at = dot3(a, t);
        bt = dot3(b, t);
        l1 = -(at * bb - ab * bt);
        l2 = -(ab * at - aa * bt);
        if (l1 > 0.0 && l2 > 0.0)
            ++np;
        else if (l1 < 0.0 && l2 < 0.0)
            ++nn;
    }
    *pos = np;
    *neg = nn;
}

/* max |R R^T - I| (entrywise) + |det R - 1| */
static double orth_error(const double r[9])
{
    double err = fabs(det33(r) - 1.0);
    int i, j;
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) {
            double d = dot3(r + 3 * i, r + 3 * j) - (i == j ? 1.0 : 0.0);
            if (isnan(d))
                return INFINITY;
            if (fabs(d) > err)
                err = fabs(d);
        }
    return err;
}

int mcg_essential_decompose(const double E[9], const double *d1, const double *d2, int n,
                            double R[9], double t[3], int *n_front)
{
    double e[9], cof[9], te[9], ra[9], rb[9], tt[3], c[3][3], s2 = 0.0, scale, best = -1.0;
    double *cands[2];
    int i, j, k, pos[2], neg[2], bestc = 0, bests = 1;
    if (E == NULL || d1 == NULL || d2 == NULL || R == NULL || t == NULL || n_front == NULL)
        return MCG_EINVAL;
    if (n < 1 || n > (1 << 26))
        return MCG_EINVAL;
    if (!all_finite(E, 9) || !all_finite(d1, (size_t)3 * n) || !all_finite(d2, (size_t)3 * n))
        return MCG_EINVAL;
    /* scale E so that E E^T = I - t t^T with |t| = 1 (trace 2), computed
     * with the largest entry factored out against overflow */
    scale = 0.0;
    for (i = 0; i < 9; ++i)
        if (fabs(E[i]) > scale)
            scale = fabs(E[i]);
    if (!(scale > 0.0))
        return MCG_EDEGENERATE;
    for (i = 0; i < 9; ++i) {
        e[i] = E[i] / scale;
        s2 += e[i] * e[i];
    }
    s2 = sqrt(2.0 / s2);
    for (i = 0; i < 9; ++i)
        e[i] *= s2;
    /* t^T E = 0: t is orthogonal to the columns of E; cross product of the
     * pair of columns with the largest one (E has rank 2) */
    for (j = 0; j < 3; ++j)
        for (i = 0; i < 3; ++i)
            c[j][i] = e[3 * i + j];
    best = largest_cross(c, tt);
    if (!(best > 0.0))
        return MCG_EDEGENERATE; /* rank <= 1: not an essential matrix */
    best = sqrt(best);
    for (i = 0; i < 3; ++i)
        tt[i] /= best;
    /* With E = [t]x R, |t| = 1: cof(E) = cof([t]x) cof(R) = t t^T R and
     * [t]x E = (t t^T - I) R, so R = cof(E) - [t]x E; the other sign of t
     * gives the twisted pair (2 t t^T - I) R = cof(E) + [t]x E. (Horn, "Recovering
     * baseline and orientation from essential matrix", JOSA 1990.) */
    cross3(e + 3, e + 6, cof);
    cross3(e + 6, e + 0, cof + 3);
    cross3(e + 0, e + 3, cof + 6);
    skew_times(tt, e, te);
    for (i = 0; i < 9; ++i) {
        ra[i] = cof[i] - te[i];
        rb[i] = cof[i] + te[i];
    }
    cands[0] = ra;
    cands[1] = rb;
    for (k = 0; k < 2; ++k) {
        /* E from the 5-point solver is essential to rounding and the R above
         * orthonormal to rounding; a noisy E is projected onto SO(3) */
        if (orth_error(cands[k]) > 1e-10) {
            double rr[9];
            if (mcg_project_so3(cands[k], rr) != MCG_OK)
                return MCG_EDEGENERATE;
            for (i = 0; i < 9; ++i)
                cands[k][i] = rr[i];
        }
        count_front(cands[k], tt, d1, d2, n, &pos[k], &neg[k]);
    }
    best = -1.0;
    for (k = 0; k < 2; ++k) {
        if (pos[k] > best) {
            best = pos[k];
            bestc = k;
            bests = 1;
        }
        if (neg[k] > best) {
            best = neg[k];
            bestc = k;
            bests = -1;
        }
    }
    for (i = 0; i < 9; ++i)
        R[i] = cands[bestc][i];
    for (i = 0; i < 3; ++i)
        t[i] = bests * tt[i];
    *n_front = (int)best;
    return MCG_OK;
}
