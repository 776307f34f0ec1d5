/*
 * sixpt.c -- the generic minimal generalized relative pose from 6
 * correspondences of any cameras (Stewenius, Nister, Oskarsson, Astrom,
 * "Solutions to minimal generalized relative pose problems", OMNIVIS 2005:
 * 64 complex solutions for generic data). Our own formulation and solver:
 * a parameter homotopy (Morgan and Sommese, "Coefficient-parameter polynomial
 * continuation", Appl. Math. Comput. 1989) from one generic complex problem
 * whose 64 solutions are tabulated (csrc/sixpt_start.h, found offline by
 * monodromy in tools/sixpt_start.py) to the given real problem. No code of
 * PoseLib, OpenGV or COLMAP is used.
 *
 * 1. Unknowns x = (s, t): the Cayley vector s of the rotation,
 *        R = Rt(s) / (1 + s.s),  Rt(s) = (1 - s.s) I + 2 [s]x + 2 s s^T,
 *    and the translation t (rig2_from_rig1, X2 = R X1 + t). Rotations by
 *    exactly 180 degrees (s at infinity) are not represented.
 *
 * 2. The generalized epipolar constraint of correspondence i (thesis eq.
 *    8.16, d2^T [t]x R d1 + d2^T R m1 + m2^T R d1 = 0, m = o x d) times
 *    1 + s.s is linear in Rt:
 *        F_i(x) = <Rt(s), G_i>,  G_i = (d2 x t) d1^T + d2 m1^T + m2 d1^T,   (S1)
 *    with <A, B> = sum_ab A_ab B_ab. Six equations (S1) in the six unknowns:
 *    for generic data 64 isolated complex solutions (tools/sixpt_start.py
 *    finds exactly 64 for a random complex problem; 1 + s.s = 0 adds a
 *    seventh equation, so no spurious root there for generic data). For a
 *    given R, (S1) is the 6 x 4 system M(R) [t; 1] = 0, so t of a root is
 *    M(R)'s null vector.
 *
 * 3. Homotopy: the problem data p = (o1, d1, o2, d2) of the 6
 *    correspondences (72 numbers) move on the straight segment p(tau) = p0 +
 *    tau (p1 - p0), tau in [0, 1], from the complex start p0 to the real,
 *    normalised problem p1. As p0 is random complex, the segment meets the
 *    discriminant (where solutions meet or go to infinity) with probability
 *    zero, and the 64 solution paths x(tau) of H(x, tau) = F(x; p(tau)) = 0
 *    end at every isolated solution of p1 (Morgan-Sommese). Each path is
 *    tracked by a fourth-order Runge-Kutta predictor on dx/dtau = -J^-1
 *    dH/dtau and Newton corrector steps. A step is accepted when the
 *    corrector converges (first correction below 1e-3 of 1 + |x|, last below
 *    1e-5) -- the usual guard against jumping between paths; the first
 *    correction, the predictor's error, also sets the next step (track()).
 *    The data along the segment are polynomials in tau (d linear, m = o x d
 *    quadratic), expanded once per problem (struct seg).
 *    Paths whose |x| exceeds 1e7 go to infinity (e.g. a rotation of 180
 *    degrees, or a degenerate problem) and are dropped.
 *
 * 4. At tau = 1 the real endpoints (|Im x| <= 1e-6 (1 + |x|)) are polished by
 *    Newton steps in real arithmetic and kept when the Jacobian is not
 *    singular (a singular one means a non-isolated solution, e.g. the metric
 *    scale of a central camera is free: never reported) and every normalised
 *    constraint (unit directions, origins centred and scaled by their RMS
 *    spread) holds to 1e-10 (1 + |t|); duplicates are merged.
 *
 * 5. Back to the rig frames: with o = sc u + c, t = sc t_u + c - R c.
 *
 * Cost: 64 paths of about 65 steps (a sixth rejected), each about five
 * evaluations and complex 6 x 6 solves: some 14 ms per call on a 2-core
 * machine (50 ms before the step control of track() and the vectorised
 * eval_h), 27-30 ms on a 2.0 GHz EPYC core, still far slower than an
 * elimination template (PoseLib's gen_relpose_6pt: 1.6-4.2 ms there). A
 * multistep predictor (the Hermite extrapolation through the last 2 or 3
 * points of a path and their velocities, one new velocity per step)
 * instead of Runge-Kutta was tried in session 20: 3 points took 17.7 k
 * evaluations a call against ~20.8 k, within the timing noise, 2 points
 * more than Runge-Kutta; not kept. Nor was a looser acceptance (FIRST_TOL
 * 2e-3, session 21: 10 % fewer evaluations, 200 configurations of each
 * family: the same solutions in all but 3; one found another solution
 * instead of one, two on 2-camera heads with cross-camera rays lost one,
 * in one of them the true motion).
 * No allocation (all work is on the stack). Every solution returned is
 * checked (step 4); a miss (a path that failed or jumped) is possible in
 * ill-conditioned problems and its rate is measured by `mcgeom experiment
 * peer_solvers --part minimal`.
 */
#include "mcgeom.h"
#include "internal.h"
#include "sixpt_start.h"

#include <complex.h>
#include <math.h>
#include <string.h>

#define DIR2_MIN 1e-100  /* smallest squared length of a direction */
#define X_MAX 1e7        /* |x| beyond which a path goes to infinity */
#define H_MAX 0.1        /* largest step in tau */
#define H_MIN 1e-9       /* smallest step in tau before a path is given up */
#define H_GROW 2.0       /* largest growth of the step after an accepted one */
#define MAX_STEPS 600    /* steps (accepted or not) per path: bounds the time */
/* The corrector (step 3): its first Newton step measures the predictor's
 * error, which decides the acceptance (FIRST_TOL) and the next step size
 * (PRED_TOL); it ends when a Newton step is below LAST_TOL. All relative to
 * 1 + |x|. Newton converges quadratically from within FIRST_TOL, so a last
 * step of 1e-5 leaves the point some 1e-10 from its path. PRED_TOL was chosen
 * from 3e-5..1e-3 by the evaluations per path (the fewest at 1e-4..3e-4), at
 * an unchanged count of solutions found. */
#define FIRST_TOL 1e-3
#define PRED_TOL 3e-4
#define LAST_TOL 1e-5

typedef double complex cplx;

/* re + i im, built from its parts: the C99 spelling re + im * I multiplies
 * im by the complex I, which Annex G makes a full complex product (0 * im
 * kept for infinities) and which costs about a tenth of this solver's time */
#if defined(__GNUC__) && !defined(__clang__)
#define MCG_BUILTIN_COMPLEX 1
#elif defined(__has_builtin)
#if __has_builtin(__builtin_complex)
#define MCG_BUILTIN_COMPLEX 1
#endif
#endif
static inline cplx mkc(double re, double im)
{
#ifdef MCG_BUILTIN_COMPLEX
    return __builtin_complex(re, im);
#else
    cplx z; /* C99 6.2.5p13: a complex has the layout of double[2] */
    ((double *)&z)[0] = re;
    ((double *)&z)[1] = im;
    return z;
#endif
}

/* a b without the C99 Annex G infinity/NaN recovery (a library call per
 * product otherwise; the values here are finite) */
static inline cplx cm(cplx a, cplx b)
{
    double ar = creal(a), ai = cimag(a), br = creal(b), bi = cimag(b);
    return mkc(ar * br - ai * bi, ar * bi + ai * br);
}

/* |re| + |im|: a cheap magnitude for pivoting */
static inline double cabs1(cplx a) { return fabs(creal(a)) + fabs(cimag(a)); }

/* c = a x b (complex) */
static void ccross(const cplx *a, const cplx *b, cplx *c)
{
    c[0] = cm(a[1], b[2]) - cm(a[2], b[1]);
    c[1] = cm(a[2], b[0]) - cm(a[0], b[2]);
    c[2] = cm(a[0], b[1]) - cm(a[1], b[0]);
}

/* The problem along the segment, per correspondence, as polynomials in tau:
 * d(tau) = D + tau dD, m(tau) = o(tau) x d(tau) = M0 + tau M1 + tau^2 M2.
 * Stored by polynomial, component and part, the LANES = 6 correspondences
 * last, so that eval_h's loops over the correspondences are vector loops
 * (the same arithmetic in each lane: results do not depend on the width). */
#define LANES 6
enum { SD1, SdD1, SD2, SdD2, SM10, SM11, SM12, SM20, SM21, SM22, NSEG };
struct seg {
    double re[NSEG][3][LANES], im[NSEG][3][LANES];
};

static void seg_put(struct seg *sg, int q, int i, const cplx *v)
{
    int a;
    for (a = 0; a < 3; ++a) {
        sg->re[q][a][i] = creal(v[a]);
        sg->im[q][a][i] = cimag(v[a]);
    }
}

/* the moment m = o x d along the segment, o = o0 + tau dlo, d = d0 + tau
 * dld: its coefficients M0 = o0 x d0, M1 = dlo x d0 + o0 x dld and M2 = dlo x
 * dld, stored as polynomials q, q + 1, q + 2 of correspondence i */
static void seg_put_moment(struct seg *sg, int q, int i, const cplx *o0, const cplx *d0,
                           const cplx *dlo, const cplx *dld)
{
    cplx u[3], v[3], w[3];
    int a;
    ccross(o0, d0, w);
    seg_put(sg, q, i, w);
    ccross(dlo, d0, u);
    ccross(o0, dld, v);
    for (a = 0; a < 3; ++a)
        w[a] = u[a] + v[a];
    seg_put(sg, q + 1, i, w);
    ccross(dlo, dld, w);
    seg_put(sg, q + 2, i, w);
}

static void seg_init(struct seg *sg, const cplx *p0, const cplx *dp)
{
    int i;
    for (i = 0; i < 6; ++i) {
        const cplx *o1 = p0 + 12 * i, *d1 = o1 + 3, *o2 = o1 + 6, *d2 = o1 + 9;
        const cplx *do1 = dp + 12 * i, *dd1 = do1 + 3, *do2 = do1 + 6, *dd2 = do1 + 9;
        seg_put(sg, SD1, i, d1);
        seg_put(sg, SdD1, i, dd1);
        seg_put(sg, SD2, i, d2);
        seg_put(sg, SdD2, i, dd2);
        seg_put_moment(sg, SM10, i, o1, d1, do1, dd1);
        seg_put_moment(sg, SM20, i, o2, d2, do2, dd2);
    }
}

/* Complex scalars as two doubles inside eval_h's lane loops: the compiler
 * keeps them in registers and vectorises across the lanes, which it does not
 * for C99 complex values. cx_fma is a product and a sum, never fused. */
typedef struct {
    double r, i;
} cx;
static inline cx cx_mul(cx a, cx b)
{
    cx c = {a.r * b.r - a.i * b.i, a.r * b.i + a.i * b.r};
    return c;
}
static inline cx cx_add(cx a, cx b)
{
    cx c = {a.r + b.r, a.i + b.i};
    return c;
}
static inline cx cx_sub(cx a, cx b)
{
    cx c = {a.r - b.r, a.i - b.i};
    return c;
}
static inline cx cx_fma(cx acc, cx a, cx b) { return cx_add(acc, cx_mul(a, b)); }
static inline cx cx_of(cplx z)
{
    cx c = {creal(z), cimag(z)};
    return c;
}
static inline void cx_cross(const cx *a, const cx *b, cx *c)
{
    c[0] = cx_sub(cx_mul(a[1], b[2]), cx_mul(a[2], b[1]));
    c[1] = cx_sub(cx_mul(a[2], b[0]), cx_mul(a[0], b[2]));
    c[2] = cx_sub(cx_mul(a[0], b[1]), cx_mul(a[1], b[0]));
}
static inline void cx_mv3(const cx *A, const cx *x, cx *y)
{
    int a;
    for (a = 0; a < 3; ++a)
        y[a] = cx_fma(cx_fma(cx_mul(A[3 * a], x[0]), A[3 * a + 1], x[1]), A[3 * a + 2], x[2]);
}
static inline cx cx_dot3(const cx *a, const cx *b)
{
    return cx_fma(cx_fma(cx_mul(a[0], b[0]), a[1], b[1]), a[2], b[2]);
}
/* Rt(s) (S1) and its derivatives dRt/ds_k (row-major 3 x 3 each), in the
 * two-double form of eval_h */
static void cayley(const cx *s, cx Rt[9], cx dR[3][9])
{
    cx ss = cx_fma(cx_fma(cx_mul(s[0], s[0]), s[1], s[1]), s[2], s[2]);
    int a, b, k;
    for (a = 0; a < 3; ++a)
        for (b = 0; b < 3; ++b) {
            cx p = cx_mul(s[a], s[b]);
            Rt[3 * a + b].r = (a == b ? 1.0 - ss.r : 0.0) + 2.0 * p.r;
            Rt[3 * a + b].i = (a == b ? -ss.i : 0.0) + 2.0 * p.i;
        }
    /* + 2 [s]x */
    for (k = 0; k < 3; ++k) {
        int a1 = (k + 1) % 3, a2 = (k + 2) % 3;
        Rt[3 * a2 + a1].r += 2.0 * s[k].r;
        Rt[3 * a2 + a1].i += 2.0 * s[k].i;
        Rt[3 * a1 + a2].r -= 2.0 * s[k].r;
        Rt[3 * a1 + a2].i -= 2.0 * s[k].i;
    }
    for (k = 0; k < 3; ++k)
        for (a = 0; a < 3; ++a)
            for (b = 0; b < 3; ++b) {
                cx d = {0.0, 0.0};
                if (a == b)
                    d = cx_add(d, (cx){-2.0 * s[k].r, -2.0 * s[k].i});
                if (a == k)
                    d = cx_add(d, (cx){2.0 * s[b].r, 2.0 * s[b].i});
                if (b == k)
                    d = cx_add(d, (cx){2.0 * s[a].r, 2.0 * s[a].i});
                dR[k][3 * a + b] = d;
            }
    /* d[s]x/ds_k = [e_k]x */
    dR[0][5].r -= 2.0;
    dR[0][7].r += 2.0;
    dR[1][2].r += 2.0;
    dR[1][6].r -= 2.0;
    dR[2][1].r -= 2.0;
    dR[2][3].r += 2.0;
}

/* component a of polynomial q's coefficient at lane l */
static inline cx seg_at(const struct seg *sg, int q, int a, int l)
{
    cx c = {sg->re[q][a][l], sg->im[q][a][l]};
    return c;
}
/* c0 + tau c1 */
static inline cx lin(cx c0, cx c1, double tau)
{
    cx c = {c0.r + tau * c1.r, c0.i + tau * c1.i};
    return c;
}

/* H(x, tau) = F(x; p(tau)) (S1): Fv (6), J = dH/dx (6 x 6 row-major) and,
 * when Ft is not NULL, dH/dtau (6). With a = d2 x t + m2,
 *   F_i = a^T Rt d1 + d2^T Rt m1,   dF_i/dt = (Rt d1) x d2,
 *   dF_i/ds_k = a^T dRt_k d1 + d2^T dRt_k m1 = <dRt_k, a d1^T + d2 m1^T>.
 * Most of the solver's time is here; vectorised over the correspondences
 * (and 4 wide with AVX2) it takes a call from 20 to 15 ms. */
MCG_AVX2_CLONE static void eval_h(const cplx *x, const struct seg *sg, double tau, cplx Fv[6],
                                  cplx J[36], cplx *Ft)
{
    cx Rt[9], dR[3][9], s[3], t[3];
    double fr[LANES], fi[LANES], jr[6][LANES], ji[6][LANES], ftr[LANES], fti[LANES];
    cx kept[4][3][LANES]; /* u, v, a, d2 of each correspondence, for dH/dtau */
    double t2 = tau * tau;
    int i, k, a, l;
    for (a = 0; a < 3; ++a) {
        s[a] = cx_of(x[a]);
        t[a] = cx_of(x[3 + a]);
    }
    cayley(s, Rt, dR);
    for (l = 0; l < LANES; ++l) {
        cx d1[3], d2[3], m1[3], m2[3], av[3], u[3], v[3], G[9], F, w[3];
        for (a = 0; a < 3; ++a) {
            cx m;
            d1[a] = lin(seg_at(sg, SD1, a, l), seg_at(sg, SdD1, a, l), tau);
            d2[a] = lin(seg_at(sg, SD2, a, l), seg_at(sg, SdD2, a, l), tau);
            m = lin(seg_at(sg, SM10, a, l), seg_at(sg, SM11, a, l), tau);
            m1[a] = lin(m, seg_at(sg, SM12, a, l), t2);
            m = lin(seg_at(sg, SM20, a, l), seg_at(sg, SM21, a, l), tau);
            m2[a] = lin(m, seg_at(sg, SM22, a, l), t2);
        }
        cx_cross(d2, t, av);
        for (a = 0; a < 3; ++a)
            av[a] = cx_add(av[a], m2[a]);
        cx_mv3(Rt, d1, u);
        cx_mv3(Rt, m1, v);
        F = cx_add(cx_dot3(av, u), cx_dot3(d2, v));
        fr[l] = F.r;
        fi[l] = F.i;
        for (a = 0; a < 3; ++a)
            for (k = 0; k < 3; ++k)
                G[3 * a + k] = cx_fma(cx_mul(av[a], d1[k]), d2[a], m1[k]);
        for (k = 0; k < 3; ++k) {
            cx r = cx_mul(dR[k][0], G[0]);
            for (a = 1; a < 9; ++a)
                r = cx_fma(r, dR[k][a], G[a]);
            jr[k][l] = r.r;
            ji[k][l] = r.i;
        }
        cx_cross(u, d2, w);
        for (k = 0; k < 3; ++k) {
            jr[3 + k][l] = w[k].r;
            ji[3 + k][l] = w[k].i;
        }
        for (a = 0; a < 3; ++a) {
            kept[0][a][l] = u[a];
            kept[1][a][l] = v[a];
            kept[2][a][l] = av[a];
            kept[3][a][l] = d2[a];
        }
    }
    if (Ft)
        for (l = 0; l < LANES; ++l) {
            /* d/dtau: d' = dD, m' = M1 + 2 tau M2, a' = d2' x t + m2' */
            cx ap[3], dm1[3], ud[3], vd[3], dd1[3], dd2[3], f, u[3], v[3], av[3], d2[3];
            for (a = 0; a < 3; ++a) {
                dd1[a] = seg_at(sg, SdD1, a, l);
                dd2[a] = seg_at(sg, SdD2, a, l);
                u[a] = kept[0][a][l];
                v[a] = kept[1][a][l];
                av[a] = kept[2][a][l];
                d2[a] = kept[3][a][l];
            }
            cx_cross(dd2, t, ap);
            for (a = 0; a < 3; ++a) {
                ap[a] = cx_add(ap[a],
                               lin(seg_at(sg, SM21, a, l), seg_at(sg, SM22, a, l), 2.0 * tau));
                dm1[a] = lin(seg_at(sg, SM11, a, l), seg_at(sg, SM12, a, l), 2.0 * tau);
            }
            cx_mv3(Rt, dd1, ud);
            cx_mv3(Rt, dm1, vd);
            f = cx_add(cx_add(cx_dot3(ap, u), cx_dot3(av, ud)),
                       cx_add(cx_dot3(dd2, v), cx_dot3(d2, vd)));
            ftr[l] = f.r;
            fti[l] = f.i;
        }
    for (i = 0; i < 6; ++i) {
        Fv[i] = mkc(fr[i], fi[i]);
        for (k = 0; k < 6; ++k)
            J[6 * i + k] = mkc(jr[k][i], ji[k][i]);
        if (Ft)
            Ft[i] = mkc(ftr[i], fti[i]);
    }
}

/* b := U^-1 b for the upper triangle U of csolve6's factors (the inverses of
 * the pivots on its diagonal) */
static void back_substitute(const cplx J[36], cplx b[6])
{
    int k, j;
    for (k = 5; k >= 0; --k) {
        cplx acc = b[k];
        for (j = k + 1; j < 6; ++j)
            acc -= cm(J[6 * k + j], b[j]);
        b[k] = cm(acc, J[6 * k + k]);
    }
}

/* Solve J y = b and, when c is not NULL, J z = c (6 x 6, partial pivoting;
 * J, b and c are overwritten, y = b, z = c). Returns 0 when a pivot vanishes
 * relative to the largest entry. */
static int csolve6(cplx J[36], cplx b[6], cplx *c)
{
    int k, i, j;
    double big = 0.0;
    for (i = 0; i < 36; ++i) {
        double m = cabs1(J[i]);
        big = m > big ? m : big;
    }
    if (!(big > 0.0) || !isfinite(big))
        return 0;
    for (k = 0; k < 6; ++k) {
        int p = k;
        double best = cabs1(J[6 * k + k]);
        cplx inv;
        for (i = k + 1; i < 6; ++i)
            if (cabs1(J[6 * i + k]) > best) {
                best = cabs1(J[6 * i + k]);
                p = i;
            }
        if (!(best > 1e-14 * big))
            return 0;
        if (p != k) {
            cplx tmp;
            for (j = 0; j < 6; ++j) {
                tmp = J[6 * k + j];
                J[6 * k + j] = J[6 * p + j];
                J[6 * p + j] = tmp;
            }
            tmp = b[k];
            b[k] = b[p];
            b[p] = tmp;
            if (c) {
                tmp = c[k];
                c[k] = c[p];
                c[p] = tmp;
            }
        }
        {
            double pr = creal(J[6 * k + k]), pi = cimag(J[6 * k + k]), q = pr * pr + pi * pi;
            inv = mkc(pr / q, -pi / q); /* 1 / pivot */
            J[6 * k + k] = inv;            /* kept for the back substitution */
        }
        for (i = k + 1; i < 6; ++i) {
            cplx f = cm(J[6 * i + k], inv);
            for (j = k + 1; j < 6; ++j)
                J[6 * i + j] -= cm(f, J[6 * k + j]);
            b[i] -= cm(f, b[k]);
            if (c)
                c[i] -= cm(f, c[k]);
        }
    }
    back_substitute(J, b);
    if (c)
        back_substitute(J, c);
    return 1;
}

static double cnorm6(const cplx *x)
{
    double s = 0.0;
    int i;
    for (i = 0; i < 6; ++i)
        s += creal(x[i]) * creal(x[i]) + cimag(x[i]) * cimag(x[i]);
    return sqrt(s);
}

/* dx/dtau at (x, tau); 0 when J is singular */
static int velocity(const cplx *x, const struct seg *sg, double tau, cplx v[6])
{
    cplx Fv[6], J[36];
    int i;
    eval_h(x, sg, tau, Fv, J, v);
    if (!csolve6(J, v, NULL))
        return 0;
    for (i = 0; i < 6; ++i)
        v[i] = -v[i];
    return 1;
}

/* Newton corrector at tau: up to 3 steps; returns 1 when it converged
 * (first correction <= FIRST_TOL (1 + |x|), last <= LAST_TOL (1 + |x|)).
 * *d1 is the first correction relative to 1 + |x|. From the second step on,
 * the evaluation also gives dH/dtau and the solve J^-1 dH/dtau with the same
 * factors: when the corrector ends there (*have_vn), -vn is the velocity at
 * the new point up to the last correction, the next step's first stage at
 * no cost (14 % fewer evaluations per path). */
static int correct(cplx *x, const struct seg *sg, double tau, double *d1, cplx vn[6],
                   int *have_vn)
{
    int it, i;
    *d1 = 1.0;
    *have_vn = 0;
    for (it = 0; it < 3; ++it) {
        cplx Fv[6], J[36];
        double nd, nx;
        eval_h(x, sg, tau, Fv, J, it > 0 ? vn : NULL);
        if (!csolve6(J, Fv, it > 0 ? vn : NULL))
            return 0;
        *have_vn = it > 0;
        for (i = 0; i < 6; ++i)
            x[i] -= Fv[i];
        nd = cnorm6(Fv);
        nx = 1.0 + cnorm6(x);
        if (it == 0) {
            *d1 = nd / nx;
            if (!(nd <= FIRST_TOL * nx))
                return 0;
        }
        if (nd <= LAST_TOL * nx)
            return 1;
    }
    return 0;
}

/* Track one path from x (a solution at tau = 0) to tau = 1; 1 on success.
 * Fourth-order Runge-Kutta predictor and Newton corrector (step 3). The
 * first corrector step d1 is the predictor's local error, O(h^5), so the next
 * step is h (PRED_TOL / d1)^(1/5) (times 0.9 for safety, at most H_GROW h); a
 * rejected step halves h. The velocity at the start of a step is kept when
 * the step is rejected (x and tau have not moved) and comes from the
 * corrector when it is accepted (correct()). */
static int track(cplx x[6], const struct seg *sg)
{
    double tau = 0.0, h = 0.05;
    int steps, i, have_k1 = 0, have_vn = 0;
    cplx k1[6], vn[6];
    for (steps = 0; steps < MAX_STEPS && tau < 1.0; ++steps) {
        cplx k2[6], k3[6], k4[6], y[6];
        double hh = fmin(h, 1.0 - tau), d1 = 1.0;
        int ok = 1;
        if (!have_k1)
            ok = have_k1 = velocity(x, sg, tau, k1);
        if (ok) {
            for (i = 0; i < 6; ++i)
                y[i] = x[i] + 0.5 * hh * k1[i];
            ok = velocity(y, sg, tau + 0.5 * hh, k2);
        }
        if (ok) {
            for (i = 0; i < 6; ++i)
                y[i] = x[i] + 0.5 * hh * k2[i];
            ok = velocity(y, sg, tau + 0.5 * hh, k3);
        }
        if (ok) {
            for (i = 0; i < 6; ++i)
                y[i] = x[i] + hh * k3[i];
            ok = velocity(y, sg, tau + hh, k4);
        }
        if (ok) {
            for (i = 0; i < 6; ++i)
                y[i] = x[i] + hh / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            ok = correct(y, sg, tau + hh, &d1, vn, &have_vn);
        }
        if (ok) {
            double grow = 0.9 * pow(PRED_TOL / fmax(d1, 1e-300), 0.2);
            memcpy(x, y, sizeof y);
            have_k1 = have_vn;
            if (have_k1)
                for (i = 0; i < 6; ++i)
                    k1[i] = -vn[i];
            tau = (1.0 - tau <= hh) ? 1.0 : tau + hh;
            h = fmin(hh * fmin(grow, H_GROW), H_MAX);
            if (cnorm6(x) > X_MAX)
                return 0;
        } else {
            h *= 0.5;
            if (h < H_MIN)
                return 0;
        }
    }
    return tau >= 1.0;
}

/* Real Newton polish of x at the target (tau = 1); returns 0 when J is
 * singular (relative pivot below 1e-14) or the steps do not settle. */
static int polish_real(double x[6], const struct seg *sg1)
{
    int it, i;
    for (it = 0; it < 6; ++it) {
        cplx xc[6], Fv[6], J[36];
        double nd = 0.0, nx = 0.0;
        for (i = 0; i < 6; ++i)
            xc[i] = x[i];
        eval_h(xc, sg1, 0.0, Fv, J, NULL);
        if (!csolve6(J, Fv, NULL))
            return 0;
        for (i = 0; i < 6; ++i) {
            x[i] -= creal(Fv[i]);
            nd += creal(Fv[i]) * creal(Fv[i]);
            nx += x[i] * x[i];
        }
        if (nd <= 1e-30 * (1.0 + nx))
            return 1;
    }
    return 1; /* the residual test decides */
}

/* R = Rt(s) / (1 + s.s) (real) */
static void rot_from_cayley(const double s[3], double R[9])
{
    double ss = dot3(s, s), k = 1.0 / (1.0 + ss);
    int a, b;
    for (a = 0; a < 3; ++a)
        for (b = 0; b < 3; ++b)
            R[3 * a + b] = k * ((a == b ? 1.0 - ss : 0.0) + 2.0 * s[a] * s[b]);
    R[1] -= k * 2.0 * s[2];
    R[2] += k * 2.0 * s[1];
    R[5] -= k * 2.0 * s[0];
    R[3] += k * 2.0 * s[2];
    R[6] -= k * 2.0 * s[1];
    R[7] += k * 2.0 * s[0];
}

/* The largest normalised GEC residual of (R, t) on the normalised data p
 * (72 real: o1, d1, o2, d2 per correspondence, unit directions) */
static double gec_max(const double R[9], const double t[3], const double *p)
{
    double worst = 0.0;
    int i;
    for (i = 0; i < 6; ++i) {
        const double *o1 = p + 12 * i, *d1 = o1 + 3, *o2 = o1 + 6, *d2 = o1 + 9;
        double m1[3], m2[3], Rd1[3], Rm1[3], c[3], e;
        cross3(o1, d1, m1);
        cross3(o2, d2, m2);
        mat_vec(R, d1, Rd1);
        mat_vec(R, m1, Rm1);
        cross3(t, Rd1, c);
        e = dot3(d2, c) + dot3(d2, Rm1) + dot3(m2, Rd1);
        worst = fmax(worst, fabs(e));
    }
    return worst;
}

int mcg_sixpt(const double o1[18], const double d1[18], const double o2[18], const double d2[18],
              double R[576], double t[192], int *n_solutions)
{
    double c[3], sc, p1r[72];
    cplx p0[72], p1[72], dp[72], zero[72];
    struct seg sg, sg1;
    double sols[MCG_SIXPT_MAX_SOLUTIONS][6];
    int ns = 0, k, i, j;

    if (!o1 || !d1 || !o2 || !d2 || !R || !t || !n_solutions)
        return MCG_EINVAL;
    *n_solutions = 0;
    if (!all_finite(o1, 18) || !all_finite(d1, 18) || !all_finite(o2, 18) ||
        !all_finite(d2, 18))
        return MCG_EINVAL;
    /* normalised problem: unit directions, origins centred on their mean and
     * scaled by their RMS spread (both times, one transform) */
    sc = origin_spread(6, o1, o2, c);
    if (!isfinite(sc))
        return MCG_EINVAL;
    for (k = 0; k < 6; ++k) {
        double a = dot3(d1 + 3 * k, d1 + 3 * k), b = dot3(d2 + 3 * k, d2 + 3 * k);
        if (!(a >= DIR2_MIN && b >= DIR2_MIN && isfinite(a) && isfinite(b)))
            return MCG_EINVAL;
        for (i = 0; i < 3; ++i) {
            double s = sc > 0.0 ? sc : 1.0;
            p1r[12 * k + i] = (o1[3 * k + i] - c[i]) / s;
            p1r[12 * k + 3 + i] = d1[3 * k + i] / sqrt(a);
            p1r[12 * k + 6 + i] = (o2[3 * k + i] - c[i]) / s;
            p1r[12 * k + 9 + i] = d2[3 * k + i] / sqrt(b);
        }
    }
    if (!(sc > 0.0))
        return MCG_OK; /* one centre: a central camera, no metric scale */
    for (i = 0; i < 72; ++i) {
        p0[i] = mkc(sixpt_p0_re[i], sixpt_p0_im[i]);
        p1[i] = p1r[i];
        dp[i] = p1[i] - p0[i];
        zero[i] = 0.0;
    }
    seg_init(&sg, p0, dp);
    seg_init(&sg1, p1, zero);
    for (j = 0; j < SIXPT_N_START; ++j) {
        cplx x[6];
        double xr[6], Rn[9], nx = 0.0, ni = 0.0;
        int dup = 0;
        for (i = 0; i < 6; ++i)
            x[i] = mkc(sixpt_x0_re[6 * j + i], sixpt_x0_im[6 * j + i]);
        if (!track(x, &sg))
            continue;
        for (i = 0; i < 6; ++i) {
            nx += creal(x[i]) * creal(x[i]) + cimag(x[i]) * cimag(x[i]);
            ni += cimag(x[i]) * cimag(x[i]);
        }
        if (!(sqrt(ni) <= 1e-6 * (1.0 + sqrt(nx))))
            continue; /* a complex solution */
        for (i = 0; i < 6; ++i)
            xr[i] = creal(x[i]);
        if (!polish_real(xr, &sg1))
            continue;
        rot_from_cayley(xr, Rn);
        if (!(gec_max(Rn, xr + 3, p1r) <= 1e-10 * (1.0 + sqrt(dot3(xr + 3, xr + 3)))))
            continue;
        for (k = 0; k < ns && !dup; ++k) {
            double dd = 0.0, nn = 0.0;
            for (i = 0; i < 6; ++i) {
                dd += (sols[k][i] - xr[i]) * (sols[k][i] - xr[i]);
                nn += xr[i] * xr[i];
            }
            dup = dd <= 1e-16 * (1.0 + nn);
        }
        if (dup || ns >= MCG_SIXPT_MAX_SOLUTIONS)
            continue;
        memcpy(sols[ns], xr, sizeof xr);
        /* back to the rig frames: t = sc t_u + c - R c */
        {
            double *Ro = R + 9 * ns, *to = t + 3 * ns, Rc[3];
            memcpy(Ro, Rn, sizeof Rn);
            mat_vec(Rn, c, Rc);
            for (i = 0; i < 3; ++i)
                to[i] = sc * xr[3 + i] + c[i] - Rc[i];
        }
        ++ns;
    }
    *n_solutions = ns;
    return MCG_OK;
}
