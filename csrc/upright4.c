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
 * 4. The real roots q of (U3): isolated by bisection on the sign changes of
 *    its Sturm chain, each then refined by safeguarded Newton inside its
 *    interval (real_roots below); for each the null vector v of M(q) (the
 *    signed 3 x 3 cofactors of three of its rows); t' = v[0:3] / v[3]. A
 *    root with v[3] ~ 0 has no finite translation and is dropped.
 *    theta = pi (q = infinity) is not represented: a set of measure zero.
 *
 * 5. Polish: Newton steps on the square system (U2) M(q) (t', 1) = 0 in
 *    (q, t') (the rounding of the polynomial's coefficients otherwise costs
 *    digits where roots are close), kept only when they lower the residual.
 *
 * 6. Back to the rig frames: R = Q2^T Rz(theta) Q1, t = Q2^T t', Rz from
 *    q without trigonometry (cos = (1 - q^2) / (1 + q^2), sin = 2 q /
 *    (1 + q^2)). The origins are centred and scaled (the moments are then
 *    O(1)) before step 2, and t mapped back: with o = s u + c,
 *    t = s t_u + c - R c.
 */
#include "mcgeom.h"
#include "internal.h"
#include "poly.h"
#include "so3.h"

#include <math.h>
#include <string.h>

#define DIR2_MIN 1e-100 /* smallest squared length of a direction or gravity */

/* ---------------------------------------------------------- polynomials
 * (poly_mul, poly_eval, poly_eval2: poly.h) */

/* Real roots by Sturm's theorem. The Sturm chain s_0 = a, s_1 = a',
 * s_{k+1} = -rem(s_{k-1}, s_k) (each divided by a positive factor, which
 * keeps its signs) has V(x), the number of sign changes of s_0(x), s_1(x),
 * ..., such that V(lo) - V(hi) is the number of distinct real roots in
 * (lo, hi] (Sturm 1835; e.g. Basu, Pollack, Roy, "Algorithms in Real
 * Algebraic Geometry", Thm. 2.50). Bisection on V isolates each root in an
 * interval of its own; there a has a simple root with a sign change, which
 * safeguarded Newton converges to. This replaced the recursive isolation
 * between the roots of the derivatives (a root search on each of a', a'',
 * ..., 18 Newton/bisection steps each, ~60 % of the solver's time). */

#define STURM_MAX 9 /* polynomials of a chain of degree <= 8 */

typedef struct {
    double c[STURM_MAX][9]; /* coefficients, rising powers */
    int deg[STURM_MAX];
    int len;
} sturm_chain;

/* The chain of a (degree n >= 1, a[n] != 0). A remainder that is zero to
 * rounding (relative to the dividend's coefficients) ends it: a then has a
 * multiple root and the last polynomial is gcd(a, a'), whose roots V does
 * not count twice. Leading coefficients lost to rounding are dropped. */
static void sturm_build(const double *a, int n, sturm_chain *sc)
{
    double inv = 1.0 / fabs(a[n]);
    int i, k;
    for (i = 0; i <= n; ++i)
        sc->c[0][i] = a[i] * inv;
    sc->deg[0] = n;
    inv = 1.0 / (n * fabs(a[n]));
    for (i = 0; i < n; ++i)
        sc->c[1][i] = (i + 1) * a[i + 1] * inv;
    sc->deg[1] = n - 1;
    sc->len = 2;
    for (k = 1; sc->deg[k] > 0 && k + 1 < STURM_MAX; ++k) {
        double r[9], big = 0.0, ref = 0.0;
        const double *p = sc->c[k - 1], *q = sc->c[k];
        int dp = sc->deg[k - 1], dq = sc->deg[k], d;
        for (i = 0; i <= dp; ++i) {
            r[i] = p[i];
            ref = fmax(ref, fabs(p[i]));
        }
        for (d = dp; d >= dq; --d) { /* long division by q */
            double f = r[d] / q[dq];
            for (i = 0; i <= dq; ++i)
                r[d - dq + i] -= f * q[i];
        }
        for (i = 0; i < dq; ++i)
            big = fmax(big, fabs(r[i]));
        if (!(big > 1e-13 * ref))
            break; /* remainder 0: a has a multiple root */
        d = dq - 1;
        while (d > 0 && fabs(r[d]) <= 1e-14 * big)
            --d;
        for (i = 0; i <= d; ++i)
            sc->c[k + 1][i] = -r[i] / big;
        sc->deg[k + 1] = d;
        sc->len = k + 2;
    }
}

/* V(x): sign changes along the chain at x (zeros skipped) */
static int sturm_changes(const sturm_chain *sc, double x)
{
    int k, v = 0, prev = 0;
    for (k = 0; k < sc->len; ++k) {
        double f = poly_eval(sc->c[k], sc->deg[k], x);
        int sg = (f > 0.0) - (f < 0.0);
        if (sg != 0) {
            v += prev != 0 && sg != prev;
            prev = sg;
        }
    }
    return v;
}

/* V at -infinity (dir < 0) or +infinity: the signs of the leading terms */
static int sturm_changes_inf(const sturm_chain *sc, int dir)
{
    int k, v = 0, prev = 0;
    for (k = 0; k < sc->len; ++k) {
        double l = sc->c[k][sc->deg[k]];
        int sg = (l > 0.0) - (l < 0.0);
        if (dir < 0 && (sc->deg[k] & 1))
            sg = -sg;
        if (sg != 0) {
            v += prev != 0 && sg != prev;
            prev = sg;
        }
    }
    return v;
}

/* The root of a (degree n, derivative da) in (lo, hi), where a(hi) = fhi
 * and flo (a(lo), or when lo is itself a root a value of the sign of a just
 * right of lo) differ in sign: Newton steps inside the shrinking bracket,
 * bisection when a step leaves it; to a few ulps. */
static double bracket_root(const double *a, const double *da, int n, double lo, double hi,
                           double flo, double fhi)
{
    double x = lo - flo * (hi - lo) / (fhi - flo); /* regula falsi start */
    int it;
    if (!(x > lo && x < hi))
        x = 0.5 * (lo + hi);
    for (it = 0; it < 100; ++it) {
        double f, df, xn;
        poly_eval2(a, da, n, x, &f, &df);
        if (f == 0.0)
            return x;
        if ((f < 0.0) == (flo < 0.0))
            lo = x;
        else
            hi = x;
        xn = df != 0.0 ? x - f / df : 0.5 * (lo + hi);
        /* converged: in the quadratic regime a step below 1e-10 |x| leaves
         * an error of order 1e-20 |x| (the polish in (q, t) follows); tested
         * before the bracket, of which x itself has just become an end */
        if (fabs(xn - x) <= 1e-10 * fabs(xn) + 1e-300)
            return xn;
        if (!(xn > lo && xn < hi))
            xn = 0.5 * (lo + hi);
        if (!(hi - lo > 4e-16 * fmax(fabs(lo), fabs(hi))))
            return xn;
        x = xn;
    }
    return x;
}

/* Real roots of a (degree n in 1..8, a[n] != 0), into r (increasing);
 * returns their number. A multiple root is returned once. Roots beyond
 * |x| = ROOT_MAX (a yaw within 2e-12 rad of pi) are not searched. */
#define ROOT_MAX 1e12
#define STURM_EVALS 512
static int real_roots(const double *a, int n, double *r)
{
    sturm_chain sc;
    double da[8], lo[72], hi[72], bound = 4.0;
    int vlo[72], vhi[72], top = 0, nr = 0, i, vm_inf, vp_inf, v_lo, v_hi, evals = 0;
    if (n == 1) {
        r[0] = -a[0] / a[1];
        return 1;
    }
    for (i = 0; i < n; ++i)
        da[i] = (i + 1) * a[i + 1];
    sturm_build(a, n, &sc);
    /* an interval [-bound, bound] that holds every real root: its ends see
     * the sign changes of the infinities (cheaper and tighter, for the
     * bisection below, than a bound from the coefficients) */
    vm_inf = sturm_changes_inf(&sc, -1);
    vp_inf = sturm_changes_inf(&sc, 1);
    for (;;) {
        v_lo = sturm_changes(&sc, -bound);
        v_hi = sturm_changes(&sc, bound);
        if ((v_lo == vm_inf && v_hi == vp_inf) || bound >= ROOT_MAX)
            break;
        bound *= 16.0;
    }
    lo[0] = -bound;
    hi[0] = bound;
    vlo[0] = v_lo;
    vhi[0] = v_hi;
    top = 1;
    /* at most STURM_EVALS bisections: with rounding, V need not be monotone
     * along the line and the splits of a counted interval could otherwise
     * multiply (generic configurations take ~12 per call) */
    while (top > 0 && evals < STURM_EVALS) {
        double l, h, m;
        int cl, ch, cm;
        --top;
        l = lo[top];
        h = hi[top];
        cl = vlo[top];
        ch = vhi[top];
        if (cl - ch <= 0)
            continue;
        if (cl - ch == 1) {
            double fl = poly_eval(a, n, l), fh = poly_eval(a, n, h);
            /* l itself may be a root, counted in the interval to its left
             * (e.g. q = 0 exactly, where the first split falls): just
             * right of a simple root a has the sign of a'(l) */
            if (fl == 0.0)
                fl = poly_eval(da, n - 1, l);
            if (fh == 0.0)
                r[nr++] = h;
            else if (fl != 0.0 && (fl < 0.0) != (fh < 0.0))
                r[nr++] = bracket_root(a, da, n, l, h, fl, fh);
            /* else: no sign change in a counted interval (rounding in the
             * chain); a double root, which a minimal problem does not have
             * generically, is found only at its exact value */
            if (nr == n)
                break;
            continue;
        }
        m = 0.5 * (l + h);
        if (!(h - l > 1e-14 * fmax(fabs(l), fabs(h))) || top + 2 > 72) {
            r[nr++] = m; /* roots closer than rounding: one (multiple) root */
            if (nr == n)
                break;
            continue;
        }
        cm = sturm_changes(&sc, m);
        ++evals;
        /* the upper half first onto the stack: the lower is taken next */
        lo[top] = m;
        hi[top] = h;
        vlo[top] = cm;
        vhi[top] = ch;
        lo[top + 1] = l;
        hi[top + 1] = m;
        vlo[top + 1] = cl;
        vhi[top + 1] = cm;
        top += 2;
    }
    return nr;
}

/* The real roots of poly (degree <= n) divided by lead (> 0, its largest
 * coefficient), leading coefficients lost in rounding dropped (roots near
 * q = infinity); -1 when nothing but a constant is left (det M identically
 * 0: every yaw fits). poly is scaled in place. */
static int scaled_roots(double *poly, int n, double lead, double *roots)
{
    int i, deg = n;
    for (i = 0; i <= n; ++i)
        poly[i] /= lead;
    while (deg > 0 && fabs(poly[deg]) <= 1e-14)
        --deg;
    return deg == 0 ? -1 : real_roots(poly, deg, roots);
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

/* The upright frames Q1, Q2 (Q g = e_z) of the verticals g1, g2 (any
 * non-zero finite lengths); 0 when either is zero or not finite. */
static int upright_frames(const double g1[3], const double g2[3], double Q1[9], double Q2[9])
{
    double a = dot3(g1, g1), b = dot3(g2, g2), u1[3], u2[3];
    int i;
    if (!(a >= DIR2_MIN && b >= DIR2_MIN && isfinite(a) && isfinite(b)))
        return 0;
    for (i = 0; i < 3; ++i) {
        u1[i] = g1[i] / sqrt(a);
        u2[i] = g2[i] / sqrt(b);
    }
    upright_rotation(u1, Q1);
    upright_rotation(u2, Q2);
    return 1;
}

/* R = Q2^T Rz(theta) Q1 (rig frames) for q = tan(theta / 2), without
 * trigonometry: cos = (1 - q^2) / (1 + q^2), sin = 2 q / (1 + q^2). With
 * A = Rz Q1 (rows: cos a - sin b, sin a + cos b, g1),
 * R = sum_k (row k of Q2)^T (row k of A). */
static void rig_rotation(const double Q1[9], const double Q2[9], double q, double R[9])
{
    const double w = 1.0 / (1.0 + q * q), cs = (1.0 - q * q) * w, sn = 2.0 * q * w;
    double A[9];
    int i, k;
    for (i = 0; i < 3; ++i) {
        A[i] = cs * Q1[i] - sn * Q1[3 + i];
        A[3 + i] = sn * Q1[i] + cs * Q1[3 + i];
        A[6 + i] = Q1[6 + i];
    }
    for (i = 0; i < 3; ++i)
        for (k = 0; k < 3; ++k)
            R[3 * i + k] = Q2[i] * A[k] + Q2[3 + i] * A[3 + k] + Q2[6 + i] * A[6 + k];
}

/* The rows (U2) of one correspondence (upright unit directions e1, e2,
 * moments n1, n2): the coefficients of q^0, q^1, q^2, i.e. (U1) with
 * P0 = I, P1 = 2 [e_z]x, P2 = diag(-1, -1, 1) in place of R', whose
 * images of a vector v are v, 2 (-v_y, v_x, 0) and (-v_x, -v_y, v_z). */
static void rows_of(const double e1[3], const double n1[3], const double e2[3],
                    const double n2[3], double r0[4], double r1[4], double r2[4])
{
    const double pe1[3] = {-2.0 * e1[1], 2.0 * e1[0], 0.0};
    const double pn1[3] = {-2.0 * n1[1], 2.0 * n1[0], 0.0};
    const double qe1[3] = {-e1[0], -e1[1], e1[2]};
    const double qn1[3] = {-n1[0], -n1[1], n1[2]};
    cross3(e1, e2, r0);
    r0[3] = dot3(e2, n1) + dot3(n2, e1);
    cross3(pe1, e2, r1);
    r1[3] = dot3(e2, pn1) + dot3(n2, pe1);
    cross3(qe1, e2, r2);
    r2[3] = dot3(e2, qn1) + dot3(n2, qe1);
}

static double det3_rows(const double *a, const double *b, const double *c)
{
    return a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
           a[2] * (b[0] * c[1] - b[1] * c[0]);
}

/* The signed cofactors w of the three rows of M other than `skip`: the
 * generalized cross product, orthogonal to those rows (M w = 0 when M has
 * rank 3 and they span its row space); |w| is the 3-volume they span. */
static double cofactors(const double M[16], int skip, double w[4])
{
    const double *r[3];
    double sub[3][3];
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
    return w[0] * w[0] + w[1] * w[1] + w[2] * w[2] + w[3] * w[3];
}

/* Null vector of the 4 x 4 M (rows) of rank 3 at a root: the cofactors of
 * three rows (M w = 0). Rows 0-2 are taken when their volume is at least
 * 1e-3 of the product of their lengths (well conditioned: the usual case,
 * 4 determinants of 3 x 3); else the three rows of the largest volume (the
 * other choices too). Returns 0 when M has rank < 3 (every volume 0). */
static int null4(const double M[16], double v[4])
{
    double w[4], best, len[4];
    int i, skip;
    for (i = 0; i < 4; ++i)
        len[i] = M[4 * i] * M[4 * i] + M[4 * i + 1] * M[4 * i + 1] +
                 M[4 * i + 2] * M[4 * i + 2] + M[4 * i + 3] * M[4 * i + 3];
    best = cofactors(M, 3, v);
    if (best >= 1e-6 * len[0] * len[1] * len[2])
        return 1;
    for (skip = 0; skip < 3; ++skip) {
        double nn = cofactors(M, skip, w);
        if (nn > best) {
            best = nn;
            memcpy(v, w, sizeof w);
        }
    }
    return best > 0.0;
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

/* M(q) = Mq[0] + q Mq[1] + q^2 Mq[2] (U2) */
static void matrix_at(const double Mq[3][16], double q, double M[16])
{
    int i;
    for (i = 0; i < 16; ++i)
        M[i] = Mq[0][i] + q * (Mq[1][i] + q * Mq[2][i]);
}

/* f = M (t, 1) */
static void residual_of(const double M[16], const double t[3], double f[4])
{
    int k;
    for (k = 0; k < 4; ++k)
        f[k] = M[4 * k] * t[0] + M[4 * k + 1] * t[1] + M[4 * k + 2] * t[2] + M[4 * k + 3];
}

static double sumsq4(const double f[4])
{
    return f[0] * f[0] + f[1] * f[1] + f[2] * f[2] + f[3] * f[3];
}

/* Polish: Newton steps on the square system (U2) M(q) (t, 1) = 0 in
 * (q, t) (the Jacobian [M'(q) (t, 1) | M(q)[:, 0:3]], no trigonometry),
 * each kept only when it lowers the residual: the root of the expanded
 * polynomial carries the rounding of its coefficients, which costs digits
 * where roots are close (without the polish 3 and 1 of 2000 noise-free
 * 2-camera-head configurations missed the truth at 1e-8). A second step is
 * taken only when the first reduced the residual by less than 1e4 (not yet
 * quadratic convergence); none when the residual is already below 1e-15 of
 * the scale of M and (t, 1). */
static void polish(const double Mq[3][16], double *q, double t[3], const double M0[16],
                   const double f0[4])
{
    double M[16], f[4], J[16], dx[4], cost, scale = 0.0;
    int it, i, k;
    memcpy(M, M0, sizeof M);
    memcpy(f, f0, sizeof f);
    cost = sumsq4(f);
    for (i = 0; i < 16; ++i)
        scale = fmax(scale, fabs(M[i]));
    scale *= 1.0 + fabs(t[0]) + fabs(t[1]) + fabs(t[2]);
    for (it = 0; it < 2 && cost > 1e-30 * scale * scale; ++it) {
        double q2, t2[3], f2[4], c2, rhs[4];
        for (k = 0; k < 4; ++k) {
            double dm[4];
            for (i = 0; i < 4; ++i)
                dm[i] = Mq[1][4 * k + i] + 2.0 * *q * Mq[2][4 * k + i];
            J[4 * k] = dm[0] * t[0] + dm[1] * t[1] + dm[2] * t[2] + dm[3];
            J[4 * k + 1] = M[4 * k];
            J[4 * k + 2] = M[4 * k + 1];
            J[4 * k + 3] = M[4 * k + 2];
            rhs[k] = f[k];
        }
        if (!solve4(J, rhs, dx))
            return;
        q2 = *q - dx[0];
        for (i = 0; i < 3; ++i)
            t2[i] = t[i] - dx[1 + i];
        matrix_at(Mq, q2, M);
        residual_of(M, t2, f2);
        c2 = sumsq4(f2);
        if (!(c2 < cost))
            return;
        *q = q2;
        memcpy(t, t2, sizeof t2);
        memcpy(f, f2, sizeof f2);
        if (c2 < 1e-8 * cost)
            return;
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
    double Q1[9], Q2[9], c[3] = {0.0, 0.0, 0.0}, s = 0.0;
    double e1[12], n1[12], e2[12], n2[12]; /* upright unit directions and moments */
    double Mq[3][16], poly[9], roots[8], lead = 0.0;
    int k, i, j, nr, ns = 0;
    static const int pairs[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

    if (!o1 || !d1 || !o2 || !d2 || !g1 || !g2 || !R || !t || !n_solutions)
        return MCG_EINVAL;
    *n_solutions = 0;
    if (!all_finite(o1, 12) || !all_finite(d1, 12) || !all_finite(o2, 12) ||
        !all_finite(d2, 12) || !all_finite(g1, 3) || !all_finite(g2, 3) ||
        !upright_frames(g1, g2, Q1, Q2))
        return MCG_EINVAL;
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
    for (k = 0; k < 4; ++k)
        rows_of(e1 + 3 * k, n1 + 3 * k, e2 + 3 * k, n2 + 3 * k, Mq[0] + 4 * k, Mq[1] + 4 * k,
                Mq[2] + 4 * k);
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
    nr = scaled_roots(poly, 8, lead, roots);
    if (nr < 0)
        return MCG_EDEGENERATE;
    for (j = 0; j < nr; ++j) {
        double q = roots[j], M[16], f[4], v[4], tu[3];
        matrix_at((const double(*)[16])Mq, q, M);
        if (!null4(M, v))
            continue;
        if (!(fabs(v[3]) > 1e-12 * sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] + v[3] * v[3])))
            continue; /* no finite translation */
        for (i = 0; i < 3; ++i)
            tu[i] = v[i] / v[3];
        residual_of(M, tu, f);
        polish((const double(*)[16])Mq, &q, tu, M, f);
        rig_rotation(Q1, Q2, q, R + 9 * ns);
        /* t = s Q2^T t' + c - R c */
        {
            double Rc[3];
            mat_vec(R + 9 * ns, c, Rc);
            for (i = 0; i < 3; ++i)
                t[3 * ns + i] = s * (Q2[i] * tu[0] + Q2[3 + i] * tu[1] + Q2[6 + i] * tu[2]) +
                                c[i] - Rc[i];
        }
        if (!all_finite(R + 9 * ns, 9) || !all_finite(t + 3 * ns, 3))
            continue;
        ++ns;
    }
    *n_solutions = ns;
    return MCG_OK;
}

/* ------------------------------------------- the central 3-point solver
 *
 * One camera (rays through one centre) whose vertical is known at both
 * times: its rotation R (the rig's) and the direction u of its centre's
 * travel (s2 d2 = s1 R d1 + u, the essential matrix [u]x R) from 3
 * correspondences (Fraundorfer, Tanskanen, Pollefeys, "A minimal case
 * solution to the calibrated relative pose problem for the case of two
 * known orientation angles", ECCV 2010; Kalantari, Hashemi, Jung, Guedon,
 * "A new solution to the relative orientation problem using only 3 points
 * and the vertical direction", JMIV 2011). Our own derivation, in the
 * upright frames of mcg_upright4 (step 1 above):
 *
 *   C1. The epipolar constraint d2'^T [u']x Rz(theta) d1' = 0 reads
 *       u' . (Rz d1' x d2') = 0, one row of u's 3 x 3 system per
 *       correspondence; with q = tan(theta / 2) each row times 1 + q^2 is
 *       (P0 d1' x d2') + q (P1 d1' x d2') + q^2 (P2 d1' x d2') (P_j of (U2):
 *       the first three entries of rows_of's rows, with no moments).
 *   C2. A direction u' != 0 exists iff det M(q) = 0: by multilinearity in
 *       the rows, det M(q) = sum over (j0, j1, j2) of q^(j0 + j1 + j2)
 *       det[row0_j0; row1_j1; row2_j2], a polynomial of degree <= 6 (up to
 *       6 real roots; the papers' elimination reaches a quartic, the two
 *       extra roots of ours being spurious only where every row vanishes).
 *   C3. Real roots by real_roots; u' the longest cross product of two rows
 *       of M(q) (normalised), R = Q2^T Rz(theta) Q1 and u = Q2^T u' as in
 *       mcg_upright4. The sign of u is the caller's (cheirality). A root
 *       whose rows all vanish (the camera only rotated: every direction
 *       fits) gives no direction and is dropped.
 */
int mcg_upright3_central(const double d1[9], const double d2[9], const double g1[3],
                         const double g2[3], double R[54], double u[18], int *n_solutions)
{
    static const double no_moment[3] = {0.0, 0.0, 0.0};
    double Q1[9], Q2[9], rows[3][3][4], poly[7], roots[6], lead = 0.0, size = 0.0;
    int k, i, j0, j1, j2, nr, ns = 0;
    *n_solutions = 0;
    if (!upright_frames(g1, g2, Q1, Q2))
        return MCG_EINVAL;
    for (k = 0; k < 3; ++k) { /* C1: the rows' coefficients of q^0, q^1, q^2 */
        double e1[3], e2[3], a[3], b[3], x = dot3(d1 + 3 * k, d1 + 3 * k),
                                          y = dot3(d2 + 3 * k, d2 + 3 * k);
        if (!(x >= DIR2_MIN && y >= DIR2_MIN && isfinite(x) && isfinite(y)))
            return MCG_EINVAL;
        for (i = 0; i < 3; ++i) {
            a[i] = d1[3 * k + i] / sqrt(x);
            b[i] = d2[3 * k + i] / sqrt(y);
        }
        mat_vec(Q1, a, e1);
        mat_vec(Q2, b, e2);
        rows_of(e1, no_moment, e2, no_moment, rows[k][0], rows[k][1], rows[k][2]);
        for (j0 = 0; j0 < 3; ++j0)
            size = fmax(size, dot3(rows[k][j0], rows[k][j0]));
    }
    for (i = 0; i < 7; ++i) /* C2 */
        poly[i] = 0.0;
    for (j0 = 0; j0 < 3; ++j0)
        for (j1 = 0; j1 < 3; ++j1)
            for (j2 = 0; j2 < 3; ++j2)
                poly[j0 + j1 + j2] += det3_rows(rows[0][j0], rows[1][j1], rows[2][j2]);
    for (i = 0; i < 7; ++i)
        lead = fmax(lead, fabs(poly[i]));
    /* (det M is a product of three rows of length <= ~2 sqrt(size)) */
    if (!isfinite(lead) || !(lead > 1e-13 * size * sqrt(size)))
        return MCG_EDEGENERATE; /* det M identically 0 (e.g. repeated pairs) */
    nr = scaled_roots(poly, 6, lead, roots);
    if (nr < 0)
        return MCG_EDEGENERATE;
    for (k = 0; k < nr; ++k) { /* C3 */
        double q = roots[k], M[3][3], c01[3], c02[3], c12[3], *best, nb, up[3];
        for (i = 0; i < 3; ++i) {
            int j;
            for (j = 0; j < 3; ++j)
                M[i][j] = rows[i][0][j] + q * (rows[i][1][j] + q * rows[i][2][j]);
        }
        cross3(M[0], M[1], c01);
        cross3(M[0], M[2], c02);
        cross3(M[1], M[2], c12);
        best = c01;
        if (dot3(c02, c02) > dot3(best, best))
            best = c02;
        if (dot3(c12, c12) > dot3(best, best))
            best = c12;
        nb = sqrt(dot3(best, best));
        /* rows of length ~ (1 + q^2) sqrt(size): their cross product is
         * that squared times the sine of their angle */
        if (!(nb > 1e-10 * (1.0 + q * q) * (1.0 + q * q) * size))
            continue;
        rig_rotation(Q1, Q2, q, R + 9 * ns);
        for (i = 0; i < 3; ++i)
            up[i] = best[i] / nb;
        for (i = 0; i < 3; ++i) /* u = Q2^T u' */
            u[3 * ns + i] = Q2[i] * up[0] + Q2[3 + i] * up[1] + Q2[6 + i] * up[2];
        if (!all_finite(R + 9 * ns, 9) || !all_finite(u + 3 * ns, 3))
            continue;
        ++ns;
    }
    *n_solutions = ns;
    return MCG_OK;
}
