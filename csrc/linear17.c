/*
 * linear17.c -- linear 17-point relative motion of a generalized camera
 * (thesis ch. 8): generalized epipolar rows (eqs. 8.15-8.18), detection of the
 * four kinds of generalized camera (ch. 8.3), the constrained least squares of
 * Algorithm 4 / eq. 8.36 for the locally-central and axial kinds and the plain
 * SVD for the most-general kind (Algorithm 2), decomposition of E into its
 * rotation candidates, the translation WITH scale from eq. 8.15, and the
 * refinement of ch. 8.4.3.
 *
 * Why the linear step works on the 18 x 18 Gram matrix M = A^T A:
 * |A x|^2 = x^T M x for every x = (vec E, vec R), so after one O(N) pass over
 * the rays the linear step and the candidate choice cost O(18^2) regardless
 * of N. Squaring the condition number is harmless here: rows are normalised
 * (Algorithm 2 step 1) and the refinement re-fits R, t on the rays.
 *
 * Which optimum the refinement seeks: the alternation of ch. 8.4.3
 * (R given t, then t given R) minimises the algebraic cost x^T M x. For a
 * rig whose correspondences stay in one camera, (0, I) is in the null space
 * of A, so that cost vanishes at R = I, t = 0, and its minimiser is biased
 * towards a short t: on the cases of issue 22 (mcgeom experiment
 * linear17_accuracy) it doubled the median scale error of the linear step,
 * which is itself worse than OpenGV's seventeenpt there. The refinement
 * therefore minimises the Sampson angular error of each correspondence
 * (the residual of refine.c), a first-order geometric error with no such
 * trivial minimum (Levenberg-Marquardt, a few O(N) passes). When only the
 * direction of t is determined (unit mode) the alternation is kept: with
 * |t| = 1 fixed the algebraic cost has no trivial zero.
 *
 * Frames: inputs and outputs in the rig frame; internally the normalised frame
 * X' = s (X - o) (o = centroid of the ray origins, s = 1 / RMS distance), which
 * keeps the rig axis through the origin for axial rigs, as eqs. 8.24-8.33
 * assume. A motion (R, t') there is (R, t'/s + o - R o) in the rig frame.
 */
#include "mcgeom.h"
#include "internal.h"

#include <float.h>
#include <math.h>
#include <string.h>

#define NX 18
#define NXP 20 /* NX rounded up to a multiple of 4 */

/* The loops over the rays (the accumulation of M, the Sampson passes) are
 * written in lanes of 4 doubles for the vectoriser and carry MCG_AVX2_CLONE
 * (internal.h: AVX2's 4-double registers hold a whole lane block, the same
 * bits on every CPU; issue 22: 8 % of the instructions of the public call
 * at 100 rays). */
#define MAX_RAYS (1 << 26)
#define DIR2_MIN 1e-100 /* smallest squared length of a direction (|d| >= 1e-50) */

/* ---------------------------------------------------------- small helpers */

static void matvec(int n, const double *m, const double *x, double *y)
{
    int i, j;
    for (i = 0; i < n; i++) {
        double acc = 0.0;
        for (j = 0; j < n; j++)
            acc += m[i * n + j] * x[j];
        y[i] = acc;
    }
}

static double quad18(const double *m, const double *x)
{
    double y[NX], acc = 0.0;
    int i;
    matvec(NX, m, x, y);
    for (i = 0; i < NX; i++)
        acc += x[i] * y[i];
    return acc;
}

/* x = (vec([t]x R), vec(R)): the unknown vector of eq. 8.18 for a motion. */
static void motion_vector(const double r[9], const double t[3], double x[NX])
{
    skew_times(t, r, x);
    memcpy(x + 9, r, 9 * sizeof(double));
}

/* -------------------------------------------------- accumulation of M */

/* Generalized epipolar row (eq. 8.16, row-major vec) of one ray pair in the
 * normalised frame X' = s (X - o); 0 if a direction has zero length. */
static inline int make_row(const double *o1, const double *d1, const double *o2,
                    const double *d2, const double o[3], double s, double row[NX])
{
    double a[3], b[3], p[3], q[3], m1[3], m2[3], na, nb;
    int i, j;
    for (i = 0; i < 3; i++) {
        a[i] = d1[i];
        b[i] = d2[i];
        p[i] = s * (o1[i] - o[i]);
        q[i] = s * (o2[i] - o[i]);
    }
    na = dot3(a, a);
    nb = dot3(b, b);
    /* |d| < 1e-50 is a zero-length direction, the one rule of every kernel
     * and of mcgeom.validation.check_directions (the wrapper then need not
     * look at the directions before the call) */
    if (!(na >= DIR2_MIN) || !(nb >= DIR2_MIN) || !isfinite(na) || !isfinite(nb))
        return 0;
    na = 1.0 / sqrt(na);
    nb = 1.0 / sqrt(nb);
    for (i = 0; i < 3; i++) {
        a[i] *= na;
        b[i] *= nb;
    }
    cross3(p, a, m1);
    cross3(q, b, m2);
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) {
            row[3 * i + j] = b[i] * a[j];
            row[9 + 3 * i + j] = b[i] * m1[j] + m2[i] * a[j];
        }
    return 1;
}

/* 1 if none of the 12 n inputs is NaN or +-inf: 0 x is NaN exactly for
 * those and a sum of signed zeros is zero. Four partial sums so that the
 * loop vectorises, and no branch per value (issue 22: the per-value test
 * and branch of all_finite cost about 5 instructions per input here, more
 * than the rest of the check on the whole input). */
static int finite_rays(int n, const double *o1, const double *d1, const double *o2,
                       const double *d2)
{
    double acc[4] = {0.0, 0.0, 0.0, 0.0};
    size_t i, m = 3 * (size_t)n, l;
    for (i = 0; i + 4 <= m; i += 4)
        for (l = 0; l < 4; l++)
            acc[l] += 0.0 * o1[i + l] + 0.0 * d1[i + l] + 0.0 * o2[i + l] + 0.0 * d2[i + l];
    for (; i < m; i++)
        acc[0] += 0.0 * o1[i] + 0.0 * d1[i] + 0.0 * o2[i] + 0.0 * d2[i];
    return acc[0] + acc[1] + acc[2] + acc[3] == 0.0;
}

/* One pass over the rays: validate, normalise (Algorithm 2 step 1) and add
 * each generalized epipolar row (eq. 8.16) to the Gram matrix. */
MCG_AVX2_CLONE
static int accumulate(int n, const double *o1, const double *d1,
                      const double *o2, const double *d2,
                      double *m, double origin[3], double *scale)
{
    double o[3], ss, s, mp[NX][NXP];
    int k, i, j;

    if (!finite_rays(n, o1, d1, o2, d2))
        return MCG_EINVAL;
    ss = origin_spread(n, o1, o2, o);
    /* A central camera (all origins equal) has nothing to scale. */
    s = (ss > 1e-12 * (1.0 + sqrt(dot3(o, o)))) ? 1.0 / ss : 1.0;
    memcpy(origin, o, sizeof o);
    *scale = s;

    /* rank-4 updates of the upper triangle: a quarter of the loads and
     * stores of M per row, the products of 4 rows summed in registers.
     * Rows padded to NXP (zeros) and each row of M updated from the
     * multiple of 4 at or below the diagonal: whole 4-double vectors, no
     * loop prologue or epilogue (issue 22: the triangular loop's were half
     * of this pass). The few entries left of the diagonal are discarded;
     * each upper entry is the same sum of the same products as before. */
    memset(mp, 0, sizeof mp);
    for (k = 0; k < n; k += 4) {
        double rows[4][NXP];
        int r, nb = n - k < 4 ? n - k : 4;
        for (r = 0; r < 4; r++) {
            rows[r][NX] = rows[r][NX + 1] = 0.0;
            if (r >= nb) {
                memset(rows[r], 0, sizeof rows[r]);
                continue;
            }
            if (!make_row(o1 + 3 * (k + r), d1 + 3 * (k + r), o2 + 3 * (k + r),
                          d2 + 3 * (k + r), o, s, rows[r]))
                return MCG_EINVAL;
        }
        for (i = 0; i < NX; i++) {
            double a0 = rows[0][i], a1 = rows[1][i], a2 = rows[2][i], a3 = rows[3][i];
            double *mi = mp[i];
            int l;
            for (j = i & ~3; j < NXP; j += 4)
                for (l = 0; l < 4; l++)
                    mi[j + l] += a0 * rows[0][j + l] + a1 * rows[1][j + l] +
                                 a2 * rows[2][j + l] + a3 * rows[3][j + l];
        }
    }
    for (i = 0; i < NX; i++)
        for (j = i; j < NX; j++)
            m[i * NX + j] = m[j * NX + i] = mp[i][j];
    return MCG_OK;
}

/* ------------------------------------------- case detection (ch. 8.3) */

static void block(const double *m, int r0, int c0, double *out)
{
    int i, j;
    for (i = 0; i < 9; i++)
        for (j = 0; j < 9; j++)
            out[9 * i + j] = m[(r0 + i) * NX + c0 + j];
}

/* Classify from the null space of A_R^T A_R (= M_RR): the structural
 * solutions (0, I), (0, w w^T), (0, [w]x) of eqs. 8.20-8.33 all have E = 0,
 * so they live in null(A_R); the true solution does not (E != 0). */
static int classify(const double *wr, const double *vr, double rtol,
                    double tr_m, int *nullity)
{
    int k, i, nul = 0;
    double wmax = wr[8];
    if (!(wmax > 1e-14 * tr_m)) {
        *nullity = 9;
        return MCG_GC_CENTRAL;
    }
    for (k = 0; k < 9; k++)
        if (wr[k] <= rtol * wmax)
            nul++;
    *nullity = nul;
    if (nul == 0)
        return MCG_GC_MOST_GENERAL;
    if (nul == 1) {
        double nv[9], tr, off = 0.0, asym = 0.0, w3[3], v3[9], sym[9];
        for (i = 0; i < 9; i++)
            nv[i] = vr[9 * i];
        tr = (nv[0] + nv[4] + nv[8]) / 3.0;
        for (i = 0; i < 9; i++) {
            double d = nv[i] - ((i % 4 == 0) ? tr : 0.0);
            off += d * d;
        }
        if (sqrt(off) < 1e-4)
            return MCG_GC_LOCALLY_CENTRAL;
        for (i = 0; i < 3; i++) {
            int j;
            for (j = 0; j < 3; j++) {
                double d = nv[3 * i + j] - nv[3 * j + i];
                asym += d * d;
                sym[3 * i + j] = 0.5 * (nv[3 * i + j] + nv[3 * j + i]);
            }
        }
        if (sqrt(asym) < 1e-4 && mcg_sym_eig(3, sym, w3, v3) == MCG_OK) {
            double big = fabs(w3[0]) > fabs(w3[2]) ? fabs(w3[0]) : fabs(w3[2]);
            int small = 0;
            for (i = 0; i < 3; i++)
                if (fabs(w3[i]) < 1e-4 * big)
                    small++;
            if (small == 2)
                return MCG_GC_AXIAL;
        }
        return MCG_GC_DEGENERATE;
    }
    if (nul == 3) {
        /* vec(I)/sqrt(3) must lie in the null space: project and compare */
        double res = 0.0;
        for (i = 0; i < 9; i++) {
            double acc = (i % 4 == 0) ? 1.0 / sqrt(3.0) : 0.0;
            for (k = 0; k < 3; k++) {
                double c = (vr[0 * 9 + k] + vr[4 * 9 + k] + vr[8 * 9 + k]) / sqrt(3.0);
                acc -= c * vr[9 * i + k];
            }
            res += acc * acc;
        }
        return sqrt(res) < 1e-4 ? MCG_GC_LOCALLY_CENTRAL_AXIAL : MCG_GC_DEGENERATE;
    }
    return MCG_GC_DEGENERATE;
}

/* ------------------------------------------- translation given R (eq 8.15) */

typedef struct {
    double t[3];        /* minimiser (metric mode) or unit direction */
    double cost;        /* x^T M x at (R, t) */
    double cond;        /* lambda_min(H) / lambda_max(H) */
    double h[3], hv[9]; /* eigen-decomposition of H */
    double hm[9], g[3], c0; /* the quadratic t^T H t + 2 g^T t + c0 */
} tsolve;

/* Cost in t for fixed R is t^T H t + 2 g^T t + c0 with
 * H_kl = b_k^T M_EE b_l, b_k = vec([e_k]x R), g_k = b_k^T M_ER vec R. */
static int solve_t(const double *m, const double r[9], int unit_mode,
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

/* ------------------------------------------- rotation given t (ch. 8.4.3) */

/* One Gauss-Newton step on SO(3) for min_R x(R,t)^T M x(R,t) with t fixed,
 * R = exp([w]x) R0; accepted only if it lowers the cost (step halving). */
static int step_r(const double *m, double r[9], const double t[3], double *cost)
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

/* ------------------------------------- geometric refinement (ch. 8.4.3) */

/* The rays and their normalisation (Algorithm 2 step 1), for the passes over
 * the rays after the linear step. */
typedef struct {
    int n;
    const double *o1, *d1, *o2, *d2, *origin;
    double scale;
} raydata;

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
static int geometric_refine(const raydata *rd, const mcg_linear17_options *o,
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
static double geometric_rel_std(const double h[36], double cost, int n, const double t[3])
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

/* ------------------------------------------------- cheirality */

/* Number of correspondences whose rays, moved by (R, t) into the time-2 rig
 * frame, meet in front of both origins (mid-point triangulation). */
static int count_in_front(int n, const double *o1, const double *d1,
                          const double *o2, const double *d2,
                          const double r[9], const double t[3])
{
    int k, i, cnt = 0;
    for (k = 0; k < n; k++) {
        double p[3], a[3], w[3], aa, ab, bb, aw, bw, den, s1, s2;
        const double *b = d2 + 3 * k;
        for (i = 0; i < 3; i++) {
            p[i] = r[3 * i] * o1[3 * k] + r[3 * i + 1] * o1[3 * k + 1] +
                   r[3 * i + 2] * o1[3 * k + 2] + t[i];
            a[i] = r[3 * i] * d1[3 * k] + r[3 * i + 1] * d1[3 * k + 1] +
                   r[3 * i + 2] * d1[3 * k + 2];
            w[i] = o2[3 * k + i] - p[i];
        }
        aa = dot3(a, a); ab = dot3(a, b); bb = dot3(b, b);
        aw = dot3(a, w); bw = dot3(b, w);
        den = aa * bb - ab * ab;
        if (!(den > 1e-14 * aa * bb))
            continue; /* parallel rays: no depth information */
        s1 = (aw * bb - bw * ab) / den;
        s2 = (aw * ab - bw * aa) / den;
        if (s1 > 0.0 && s2 > 0.0)
            cnt++;
    }
    return cnt;
}

/* -------------------------------------------------------------- driver */

void mcg_linear17_default_options(mcg_linear17_options *opt)
{
    if (!opt)
        return;
    opt->refine = 1;
    opt->max_iterations = 100;
    opt->tolerance = 1e-10;
    opt->rank_rtol = 1e-10;
    opt->min_scale_conditioning = 1e-10;
    opt->max_scale_rel_std = 0.1;
}

static int check_options(const mcg_linear17_options *o)
{
    if (o->refine != 0 && o->refine != 1)
        return 0;
    if (o->max_iterations < 0 || o->max_iterations > 10000)
        return 0;
    if (!isfinite(o->tolerance) || o->tolerance < 0.0)
        return 0;
    if (!isfinite(o->rank_rtol) || o->rank_rtol <= 0.0 || o->rank_rtol >= 1.0)
        return 0;
    if (!isfinite(o->min_scale_conditioning) || o->min_scale_conditioning < 0.0)
        return 0;
    if (isnan(o->max_scale_rel_std) || o->max_scale_rel_std <= 0.0)
        return 0;
    return 1;
}

/* Most-general case (rank 17): the plain SVD solution, min |A x| with
 * |x| = 1, is the eigenvector of the smallest eigenvalue of M. It is reached
 * by inverse iteration started from the constrained solution (e, r), which is
 * close to it; this avoids a full 18 x 18 eigen-decomposition. */
static int plain_svd_refine(const double *m, double e[9], double r[9])
{
    double ms[NX * NX], x[NX], y[NX], tr = 0.0, nx = 0.0;
    int i, it;
    memcpy(ms, m, sizeof ms);
    for (i = 0; i < NX; i++)
        tr += m[i * NX + i];
    for (i = 0; i < NX; i++)
        ms[i * NX + i] += 1e-13 * tr; /* keeps the factorisation definite */
    for (i = 0; i < 9; i++) {
        x[i] = e[i];
        x[9 + i] = r[i];
    }
    for (i = 0; i < NX; i++)
        nx += x[i] * x[i];
    nx = sqrt(nx);
    for (i = 0; i < NX; i++)
        x[i] /= nx;
    for (it = 0; it < 50; it++) {
        double ny = 0.0, dd = 0.0, sg;
        if (mcg_spd_solve(NX, ms, x, y) != MCG_OK)
            return MCG_ENUMERIC;
        for (i = 0; i < NX; i++)
            ny += y[i] * y[i];
        ny = sqrt(ny);
        if (!(ny > 0.0) || !isfinite(ny))
            return MCG_ENUMERIC;
        sg = 0.0;
        for (i = 0; i < NX; i++)
            sg += y[i] * x[i];
        sg = sg < 0.0 ? -1.0 : 1.0;
        for (i = 0; i < NX; i++) {
            double v = sg * y[i] / ny;
            dd += (v - x[i]) * (v - x[i]);
            x[i] = v;
        }
        if (dd < 1e-30)
            break;
    }
    for (i = 0; i < 9; i++) {
        e[i] = x[i];
        r[i] = x[9 + i];
    }
    return MCG_OK;
}

/* Linear step: the 9-vector e of E (and the R part r) minimising |A x|. */
MCG_AVX2_CLONE
static int linear_step(const double *m, int gc_case,
                       const double *wr, const double *vr, double pinv_rtol,
                       double rtol, double tr_m, double e[9], double r[9],
                       mcg_linear17_result *res)
{
    int i, j, k;
    {
        /* Algorithm 4 / eq. 8.36: r = -M_RR^+ M_RE e, and e minimises
         * e^T (M_EE - M_ER M_RR^+ M_RE) e with |e| = 1 (the Schur complement
         * equals A''^T A'' with A'' = (A_R A_R^+ - I) A_E). */
        double pinv[81], mer[81], q[81], s[81], ws[9], vs[81];
        double wmax = wr[8];
        memset(pinv, 0, sizeof pinv);
        if (gc_case != MCG_GC_CENTRAL) {
            for (k = 0; k < 9; k++) {
                if (!(wr[k] > pinv_rtol * wmax))
                    continue;
                for (i = 0; i < 9; i++)
                    for (j = 0; j < 9; j++)
                        pinv[9 * i + j] += vr[9 * i + k] * vr[9 * j + k] / wr[k];
            }
        }
        block(m, 0, 9, mer);
        for (i = 0; i < 9; i++)          /* q = M_RR^+ M_RE = pinv mer^T */
            for (j = 0; j < 9; j++) {
                double acc = 0.0;
                for (k = 0; k < 9; k++)
                    acc += pinv[9 * i + k] * mer[9 * j + k];
                q[9 * i + j] = acc;
            }
        block(m, 0, 0, s);
        for (i = 0; i < 9; i++)
            for (j = 0; j < 9; j++) {
                double acc = 0.0;
                for (k = 0; k < 9; k++)
                    acc += mer[9 * i + k] * q[9 * k + j];
                s[9 * i + j] -= acc;
            }
        if (mcg_sym_eig_tridiag(9, s, ws, vs) != MCG_OK)
            return MCG_ENUMERIC;
        for (k = 0; k < 9; k++)
            res->schur_eig[k] = ws[8] > 0.0 ? ws[k] / ws[8] : 0.0;
        /* E not unique (e.g. no translation, or too few distinct rays: a
         * duplicated ray adds no rank). The second eigenvalue is measured
         * against the whole Gram matrix, not the Schur complement's own
         * largest: when the reduced system is tiny next to M, ws[1] / ws[8]
         * looked well above rtol for a rank-deficient A (16 distinct rays,
         * second singular value 1e-11 of the largest; found by fuzz_linear17) */
        if (!(ws[1] > rtol * tr_m))
            return MCG_EDEGENERATE;
        for (i = 0; i < 9; i++)
            e[i] = vs[9 * i];
        for (i = 0; i < 9; i++) {
            double acc = 0.0;
            for (k = 0; k < 9; k++)
                acc += q[9 * i + k] * e[k];
            r[i] = -acc;
        }
    }
    if (gc_case == MCG_GC_MOST_GENERAL)
        return plain_svd_refine(m, e, r);
    return MCG_OK;
}

/* Rotation candidates: the two rotations of E = [t]x R (twisted pair) and,
 * where the R part is not ambiguous (most-general case), the projection of
 * the R part itself. */
static int rotation_candidates(const double e[9], const double r[9], int use_r,
                               double cand[4][9], int *ncand)
{
    double u[9], s[3], v[9], work[64], w[9] = {0, -1, 0, 1, 0, 0, 0, 0, 1};
    double uw[9];
    int nc = 0, i;
    size_t lw = mcg_svd_work_size(3, 3);
    if (lw > 64)
        return MCG_ENOMEM;
    if (mcg_svd(3, 3, e, u, s, v, work, lw) != MCG_OK)
        return MCG_ENUMERIC;
    mul33(u, w, uw);
    mul33_abt(uw, v, cand[nc]);
    if (det33(cand[nc]) < 0.0)
        for (i = 0; i < 9; i++)
            cand[nc][i] = -cand[nc][i];
    nc++;
    {
        double wt[9] = {0, 1, 0, -1, 0, 0, 0, 0, 1};
        mul33(u, wt, uw);
        mul33_abt(uw, v, cand[nc]);
        if (det33(cand[nc]) < 0.0)
            for (i = 0; i < 9; i++)
                cand[nc][i] = -cand[nc][i];
        nc++;
    }
    if (use_r) {
        double rr[9], sg = det33(r) < 0.0 ? -1.0 : 1.0;
        for (i = 0; i < 9; i++)
            rr[i] = sg * r[i];
        if (mcg_project_so3(rr, cand[nc]) == MCG_OK)
            nc++;
    }
    *ncand = nc;
    return MCG_OK;
}

/* The motion being estimated, in the normalised frame: R, t, the algebraic
 * cost x^T M x at them, and unit_mode: 1 when |t| is not determined (only
 * its direction is solved for, ch. 7.3.2). */
typedef struct {
    double r[9], t[3], cost;
    int unit_mode;
    double geo_cost;  /* Sampson cost (rad^2) after the geometric refinement */
    double h[36];     /* its Gauss-Newton information J^T J (upper triangle) */
    int have_h;       /* 1 once h and geo_cost are set */
} motion;

/* A translation in the normalised frame (t' = s (t - o + R o)) back to the
 * rig frame: t = t' / s + o - R o (Algorithm 2 step 1 undone). */
static void to_rig_frame(const mcg_linear17_result *res, const double r[9],
                         const double tn[3], double t[3])
{
    double ro[3];
    int i;
    matvec(3, r, res->norm_origin, ro);
    for (i = 0; i < 3; i++)
        t[i] = tn[i] / res->norm_scale + res->norm_origin[i] - ro[i];
}

/* The translation with scale of each rotation candidate (eq. 8.15), the
 * candidate of least algebraic cost kept. For a critical motion (ch. 7.3.2)
 * or a central camera |t| is not determined: then (unit mode) the rotation
 * is chosen among the equally good candidates, and the sign of the unit
 * direction, by cheirality. */
static int choose_candidate(const double *m, const raydata *rays,
                            const mcg_linear17_options *o, int gc, double tiny,
                            double cand[4][9], int ncand, mcg_linear17_result *res,
                            motion *mo)
{
    double bestcost = HUGE_VAL;
    int k, i, best = -1;
    tsolve ts;
    res->n_candidates = ncand;
    mo->unit_mode = 0;
    for (k = 0; k < ncand; k++) {
        if (solve_t(m, cand[k], 0, NULL, 0, &ts) != MCG_OK)
            return MCG_ENUMERIC;
        res->candidate_cost[k] = ts.cost;
        if (ts.cost < bestcost) {
            bestcost = ts.cost;
            best = k;
        }
    }
    memcpy(mo->r, cand[best], sizeof mo->r);
    if (solve_t(m, mo->r, 0, NULL, 1, &ts) != MCG_OK)
        return MCG_ENUMERIC;
    memcpy(mo->t, ts.t, sizeof mo->t);
    mo->cost = ts.cost;
    if (gc == MCG_GC_CENTRAL || ts.cond < o->min_scale_conditioning) {
        /* critical motion (ch. 7.3.2) or a central camera: |t| is not
         * determined. (A central camera has g = 0 and c0 = 0, so the
         * free solve returns t = 0 for every candidate and cannot tell
         * them apart; with noise its H is well conditioned, so cond
         * alone does not flag it.) Choose the rotation among equally
         * good candidates and the sign of the direction by cheirality,
         * in the normalised frame. */
        int bestcnt = -1;
        mo->unit_mode = 1;
        for (k = 0; k < ncand; k++) {
            int sg;
            if (res->candidate_cost[k] > 10.0 * bestcost + tiny)
                continue;
            if (solve_t(m, cand[k], 1, NULL, 1, &ts) != MCG_OK)
                return MCG_ENUMERIC;
            for (sg = -1; sg <= 1; sg += 2) {
                double tt[3], tr[3];
                int cnt;
                for (i = 0; i < 3; i++)
                    tt[i] = sg * ts.t[i];
                /* undo normalisation of the translation direction */
                to_rig_frame(res, cand[k], tt, tr);
                cnt = count_in_front(rays->n, rays->o1, rays->d1, rays->o2, rays->d2,
                                     cand[k], tr);
                if (cnt > bestcnt) {
                    bestcnt = cnt;
                    memcpy(mo->r, cand[k], sizeof mo->r);
                    for (i = 0; i < 3; i++)
                        mo->t[i] = sg * ts.t[i];
                    mo->cost = ts.cost;
                }
            }
        }
    }
    return MCG_OK;
}

/* The refinement of ch. 8.4.3 from the linear estimate. Metric mode: the
 * geometric refinement (Levenberg-Marquardt on the Sampson error, see
 * geometric_refine); mo->cost becomes the algebraic cost x^T M x at the
 * refined motion (the residual scale of the scale evidence) and mo->h the
 * information of the Sampson error there. Unit mode (|t| not determined: a
 * central camera or a critical motion, ch. 7.3.2): the alternation (R given
 * t, then the unit t given R) on the algebraic cost, which has no trivial
 * zero once |t| = 1 is fixed. */
static int refine_motion(const double *m, const raydata *rd,
                         const mcg_linear17_options *o, double tiny,
                         mcg_linear17_result *res, motion *mo, double *cost0)
{
    int k;
    tsolve ts;
    if (!mo->unit_mode) {
        double x[NX];
        res->iterations = geometric_refine(rd, o, mo->r, mo->t, &mo->geo_cost, mo->h,
                                           &res->converged, cost0);
        mo->have_h = 1;
        motion_vector(mo->r, mo->t, x);
        mo->cost = quad18(m, x);
        return MCG_OK;
    }
    for (k = 0; k < o->max_iterations; k++) {
        double prev = mo->cost;
        if (mo->cost <= tiny) {
            res->converged = 1;
            break;
        }
        if (step_r(m, mo->r, mo->t, &mo->cost) != MCG_OK)
            return MCG_ENUMERIC;
        if (solve_t(m, mo->r, 1, mo->t, 0, &ts) != MCG_OK)
            return MCG_ENUMERIC;
        if (ts.cost <= mo->cost) {
            memcpy(mo->t, ts.t, sizeof mo->t);
            mo->cost = ts.cost;
        }
        res->iterations = k + 1;
        if (prev - mo->cost <= o->tolerance * prev) {
            res->converged = 1;
            break;
        }
    }
    return MCG_OK;
}

/* Scale observability: the conditioning of the scale equation (eq. 8.15)
 * and the relative std of |t|, the larger of the first-order std from the
 * residual and the errors-in-variables bias bound (normalised frame). */
static int scale_evidence(const double *m, const mcg_linear17_options *o, int n,
                          const motion *mo, mcg_linear17_result *res)
{
    double nt = sqrt(dot3(mo->t, mo->t)), var = 0.0, sigma2;
    int dof = n > 6 ? n - 6 : 1, i, k;
    tsolve ts;
    if (solve_t(m, mo->r, mo->unit_mode, mo->t, 1, &ts) != MCG_OK)
        return MCG_ENUMERIC;
    /* (t stays as refined: ts only supplies H for the evidence) */
    res->scale_conditioning = ts.cond;
    sigma2 = mo->cost / dof;
    if (mo->unit_mode || !(nt > 0.0)) {
        res->scale_rel_std = HUGE_VAL;
    } else {
        double u[3], hu[3], uhu, gu, rho2;
        for (k = 0; k < 3; k++) {
            double vk[3] = {ts.hv[k], ts.hv[3 + k], ts.hv[6 + k]};
            double c = dot3(vk, mo->t) / nt;
            if (ts.h[k] > 0.0)
                var += c * c / ts.h[k];
            else if (c != 0.0)
                var = HUGE_VAL;
        }
        res->scale_rel_std = sqrt(sigma2 * var) / nt;
        /* Errors-in-variables check: along u = t/|t|, eq. 8.15 reads
         * (J u) s = b. Regressing b on J u (least squares, what we do)
         * and J u on b bracket the true s when both are noisy; their
         * ratio is rho^2 = (g.u)^2 / ((u^T H u) c0). 1 - rho^2 bounds the
         * relative bias of |t| that the first-order std cannot see. */
        for (i = 0; i < 3; i++)
            u[i] = mo->t[i] / nt;
        matvec(3, ts.hm, u, hu);
        uhu = dot3(u, hu);
        gu = dot3(ts.g, u);
        rho2 = (uhu > 0.0 && ts.c0 > 0.0) ? gu * gu / (uhu * ts.c0) : 1.0;
        if (rho2 > 1.0)
            rho2 = 1.0;
        if (1.0 - rho2 > res->scale_rel_std)
            res->scale_rel_std = 1.0 - rho2;
        /* and the first-order std of the geometric (Sampson) fit, whose
         * optimum the refinement returns */
        if (mo->have_h) {
            double gs = geometric_rel_std(mo->h, mo->geo_cost, n, mo->t);
            if (!(gs <= res->scale_rel_std))
                res->scale_rel_std = gs;
        }
    }
    res->scale_observable = !mo->unit_mode &&
                            res->scale_conditioning >= o->min_scale_conditioning &&
                            res->scale_rel_std <= o->max_scale_rel_std;
    return MCG_OK;
}

/* An unobservable scale from the free solve (near-critical motion, e.g. a
 * pure translation seen by intra-camera rays: e = t . (R d1 x d2) is
 * nearly homogeneous in t) leaves the sign of t to the noise. Only the
 * direction is reported then: choose its sign by cheirality, as unit
 * mode does, at a length (100 in the normalised frame, where the origins
 * spread over ~1) that dwarfs the rotation-induced part o - R o. */
static void orient_by_cheirality(const raydata *rays, const mcg_linear17_result *res,
                                 motion *mo)
{
    double nt = sqrt(dot3(mo->t, mo->t)), ro[3], tp[3], tm[3];
    int i;
    if (!(nt > 0.0))
        return;
    matvec(3, mo->r, res->norm_origin, ro);
    for (i = 0; i < 3; i++) {
        double step = 100.0 * mo->t[i] / nt / res->norm_scale;
        tp[i] = step + res->norm_origin[i] - ro[i];
        tm[i] = -step + res->norm_origin[i] - ro[i];
    }
    if (count_in_front(rays->n, rays->o1, rays->d1, rays->o2, rays->d2, mo->r, tm) >
        count_in_front(rays->n, rays->o1, rays->d1, rays->o2, rays->d2, mo->r, tp))
        for (i = 0; i < 3; i++)
            mo->t[i] = -mo->t[i];
}

/* The motion into res in the rig frame: t_metric always (metric mode), t
 * with unit norm when only its direction is meaningful. */
static void report_motion(const raydata *rays, const motion *mo, mcg_linear17_result *res)
{
    int i;
    memcpy(res->R, mo->r, sizeof mo->r);
    to_rig_frame(res, mo->r, mo->t, res->t);
    if (!mo->unit_mode)
        memcpy(res->t_metric, res->t, sizeof res->t_metric);
    if (!res->scale_observable) {
        /* only the direction is meaningful: report it with unit norm */
        double nt;
        if (mo->unit_mode)
            memcpy(res->t, mo->t, sizeof mo->t);
        nt = sqrt(dot3(res->t, res->t));
        if (nt > 0.0)
            for (i = 0; i < 3; i++)
                res->t[i] /= nt;
    }
    res->n_in_front = count_in_front(rays->n, rays->o1, rays->d1, rays->o2, rays->d2,
                                     res->R, res->t);
}

/* Everything after the case detection, for the kind gc (nullity of A_R):
 * the linear step (Algorithm 2), the rotation candidates, the translation
 * with scale (eq. 8.15), the refinement (ch. 8.4.3), and the
 * scale evidence; res (whose eigenvalue diagnostics are already filled)
 * gets the motion in the rig frame.
 * pinv_rtol: eigenvalues of M_RR at or below pinv_rtol * max are treated as
 * structural zeros in the elimination of the R part (0: none is). */
static int solve_case(int n, const double *origins1, const double *dirs1,
                      const double *origins2, const double *dirs2,
                      const mcg_linear17_options *opt, const double *m,
                      const double *wr, const double *vr, double tr_m, int gc,
                      int nullity, double pinv_rtol, mcg_linear17_result *res)
{
    double e[9], rpart[9], cand[4][9], tiny = 1e-26 * tr_m, ne = 0.0;
    int st, i, ncand = 0;
    raydata rays;
    motion mo;

    rays.n = n;
    rays.o1 = origins1; rays.d1 = dirs1; rays.o2 = origins2; rays.d2 = dirs2;
    rays.origin = res->norm_origin;
    rays.scale = res->norm_scale;
    mo.have_h = 0;
    res->gc_case = gc;
    res->rank_ar = 9 - nullity;
    res->rank_a = 17 - (gc == MCG_GC_CENTRAL ? 9 : nullity);
    if (gc == MCG_GC_DEGENERATE)
        return MCG_EDEGENERATE;
    if (n < res->rank_a)
        return MCG_EDEGENERATE; /* too few rays for the detected kind */

    st = linear_step(m, gc, wr, vr, pinv_rtol, opt->rank_rtol, tr_m, e, rpart, res);
    if (st != MCG_OK)
        return st;
    for (i = 0; i < 9; i++)
        ne += e[i] * e[i];
    ne = sqrt(ne);
    for (i = 0; i < 9; i++)
        res->E[i] = e[i] / ne;
    st = rotation_candidates(res->E, rpart, gc == MCG_GC_MOST_GENERAL, cand, &ncand);
    if (st != MCG_OK)
        return st;
    st = choose_candidate(m, &rays, opt, gc, tiny, cand, ncand, res, &mo);
    if (st != MCG_OK)
        return st;
    /* the cost is the quadratic form x^T M x of the Gram matrix: on exact
     * data it rounds to a tiny negative number (found by fuzz_linear17) */
    if (mo.cost < 0.0)
        mo.cost = 0.0;
    /* reported costs: RMS Sampson angular error (radians), the same
     * measure before and after the refinement and in every frame */
    res->converged = 0;
    if (opt->refine && !mo.unit_mode) {
        /* the geometric refinement's first pass is at the linear estimate:
         * its cost is cost_linear (one pass over the rays fewer) */
        double cost0;
        st = refine_motion(m, &rays, opt, tiny, res, &mo, &cost0);
        if (st != MCG_OK)
            return st;
        res->cost_linear = sqrt(cost0 / n);
        res->cost_final = sqrt(mo.geo_cost / n);
    } else {
        res->cost_linear = sqrt(sampson_pass(&rays, mo.r, mo.t, NULL, NULL) / n);
        res->cost_final = res->cost_linear;
        if (opt->refine) {
            double unused;
            st = refine_motion(m, &rays, opt, tiny, res, &mo, &unused);
            if (st != MCG_OK)
                return st;
            res->cost_final = sqrt(sampson_pass(&rays, mo.r, mo.t, NULL, NULL) / n);
        }
    }
    /* rays of extreme magnitudes (~1e200: found by fuzz_linear17) can
     * overflow the Sampson terms of the refinement: a NaN or inf cost is
     * no estimate, and a NaN would also lose every comparison with the
     * other kind's solution in mcg_linear17 */
    if (!isfinite(res->cost_final) || !isfinite(res->cost_linear))
        return MCG_ENUMERIC;
    if (mo.cost < 0.0)
        mo.cost = 0.0; /* rounding of x^T M x, as above */
    st = scale_evidence(m, opt, n, &mo, res);
    if (st != MCG_OK)
        return st;
    if (!mo.unit_mode && !res->scale_observable)
        orient_by_cheirality(&rays, res, &mo);
    report_motion(&rays, &mo, res);
    return MCG_OK;
}

/* 1 if every ray pair has the same origin at both times (to 1e-12 of the
 * normalised rig size): the rows of such pairs annihilate (0, I) exactly,
 * the locally-central case of ch. 8.3. A cross-camera pair (distinct
 * origins) annihilates it only by accident, e.g. when the rig hardly moves:
 * then the eigenvalue can be as small as rounding (|t| ~ 3e-5 of the rig). */
static int same_origins(int n, const double *o1, const double *o2, double scale)
{
    int i, k;
    for (i = 0; i < n; i++)
        for (k = 0; k < 3; k++)
            if (!(fabs(o1[3 * i + k] - o2[3 * i + k]) * scale <= 1e-12))
                return 0;
    return 1;
}

/* The minimal sample of the most-general kind: with n >= 17 pairs, fewer
 * distinct ones than this is reported as degenerate (the registry's
 * check_distinct, done here in O(n)). */
#define MIN_DISTINCT 17

static int same_pair(const double *o1, const double *d1, const double *o2,
                     const double *d2, int i, int j)
{
    int k;
    for (k = 0; k < 3; k++)
        if (o1[3 * i + k] != o1[3 * j + k] || d1[3 * i + k] != d1[3 * j + k] ||
            o2[3 * i + k] != o2[3 * j + k] || d2[3 * i + k] != d2[3 * j + k])
            return 0;
    return 1;
}

/* Number of distinct pairs (exact repeats counted once), counted up to
 * `enough`: each pair is compared with the distinct ones kept so far (at
 * most enough - 1), so the cost is O(n enough) at worst and a handful of
 * comparisons per pair when the data have no repeats. */
static int count_distinct(int n, const double *o1, const double *d1, const double *o2,
                          const double *d2, int enough)
{
    int kept[MIN_DISTINCT], nk = 0, i, j;
    if (enough > MIN_DISTINCT)
        enough = MIN_DISTINCT;
    for (i = 0; i < n && nk < enough; i++) {
        for (j = 0; j < nk; j++)
            if (same_pair(o1, d1, o2, d2, i, kept[j]))
                break;
        if (j == nk)
            kept[nk++] = i;
    }
    return nk;
}

/* Below this ratio to the largest eigenvalue of A_R^T A_R an eigenvalue is a
 * structural zero: the rows of a locally-central or axial camera annihilate
 * (0, I) etc. exactly, so their eigenvalue is rounding (~1e-16 and below).
 * Between it and rank_rtol the small eigenvalue may instead be accidental:
 * a cross-camera rig that hardly moves (R ~ I, |t| ~ 1e-5 of the rig) makes
 * (0, I) nearly annihilated by every row, as exact data with R = I, t = 0
 * do, and treating it as structural then removes the true solution
 * (found by fuzz_linear17: rotation 2 deg off on exact data, scale
 * "observable"). */
#define STRUCTURAL_RTOL 1e-14
/* Eigenvalues of A_R^T A_R below this ratio to the largest may be a nearly
 * structural null space (see the end of mcg_linear17) */
#define NEAR_RTOL 1e-8

int mcg_linear17(int n, const double *origins1, const double *dirs1,
                 const double *origins2, const double *dirs2,
                 const mcg_linear17_options *opt, mcg_linear17_result *res)
{
    mcg_linear17_options o;
    double m[NX * NX], mrr[81], wr[9], vr[81], tr_m = 0.0;
    int st, i, k, nullity = 0, gc;

    if (!res)
        return MCG_EINVAL;
    memset(res, 0, sizeof *res);
    res->gc_case = MCG_GC_DEGENERATE;
    if (!origins1 || !dirs1 || !origins2 || !dirs2)
        return MCG_EINVAL;
    if (n < 14 || n > MAX_RAYS)
        return MCG_EINVAL;
    if (opt) {
        if (!check_options(opt))
            return MCG_EINVAL;
        o = *opt;
    } else {
        mcg_linear17_default_options(&o);
    }

    st = accumulate(n, origins1, dirs1, origins2, dirs2, m, res->norm_origin,
                    &res->norm_scale);
    if (st != MCG_OK)
        return st;
    res->n_distinct = count_distinct(n, origins1, dirs1, origins2, dirs2, MIN_DISTINCT);
    if (n >= MIN_DISTINCT && res->n_distinct < MIN_DISTINCT)
        return MCG_EDEGENERATE;
    for (i = 0; i < NX; i++)
        tr_m += m[i * NX + i];
    if (!(tr_m > 0.0) || !isfinite(tr_m))
        return MCG_EINVAL;

    /* generalized camera kind from the structural null space of A_R */
    block(m, 9, 9, mrr);
    if (mcg_sym_eig_tridiag(9, mrr, wr, vr) != MCG_OK)
        return MCG_ENUMERIC;
    for (k = 0; k < 9; k++)
        res->ar_eig[k] = wr[8] > 0.0 ? (wr[k] > 0.0 ? wr[k] / wr[8] : 0.0) : 0.0;
    gc = classify(wr, vr, o.rank_rtol, tr_m, &nullity);
    st = solve_case(n, origins1, dirs1, origins2, dirs2, &o, m, wr, vr, tr_m, gc,
                    nullity, o.rank_rtol, res);
    if (gc != MCG_GC_MOST_GENERAL && gc != MCG_GC_CENTRAL &&
        (wr[0] > STRUCTURAL_RTOL * wr[8] ||
         ((gc == MCG_GC_LOCALLY_CENTRAL || gc == MCG_GC_LOCALLY_CENTRAL_AXIAL) &&
          !same_origins(n, origins1, origins2, res->norm_scale)))) {
        /* the small eigenvalues may be accidental: solve also as the most
         * general kind, with nothing eliminated as structural, and keep the
         * motion of lower algebraic cost (both costs are x^T M x of a valid
         * motion in the same normalised frame) */
        mcg_linear17_result alt;
        int st_alt = MCG_EDEGENERATE, unique;
        double wm[NX], vm[NX * NX], mc[NX * NX];
        memcpy(&alt, res, sizeof alt);
        memcpy(mc, m, sizeof mc); /* the decomposition overwrites its input */
        /* ... only where that kind's solution is unique: a second null
         * vector of the whole M at rounding level means too few independent
         * rays (duplicates add no rank), and the plain SVD would return an
         * arbitrary mix of the two */
        unique = mcg_sym_eig_tridiag(NX, mc, wm, vm) == MCG_OK &&
                 wm[1] > STRUCTURAL_RTOL * tr_m;
        if (unique)
            st_alt = solve_case(n, origins1, dirs1, origins2, dirs2, &o, m, wr, vr,
                            tr_m, MCG_GC_MOST_GENERAL, 0, 0.0, &alt);
        if (st_alt == MCG_OK && (st != MCG_OK || alt.cost_final < res->cost_final)) {
            memcpy(res, &alt, sizeof alt);
            st = MCG_OK;
        } else if (st_alt == MCG_EDEGENERATE && st == MCG_OK) {
            /* neither reading is sound: the small eigenvalue of A_R is not
             * (or need not be) structural, and without eliminating it E is
             * not unique: too few independent rays for the most general
             * kind (seen on exact data: residuals 4e-5 rad, "observable") */
            st = MCG_EDEGENERATE;
        }
    }
    /* The next eigenvalues of A_R may be nearly structural as well: a rig
     * nearly of a more special kind (two camera centres 1e-4 apart make a
     * locally-central rig nearly locally-central and axial). Inverting them
     * in M_RR^+ amplifies rounding beyond the gap of the reduced system,
     * and its E is then an arbitrary mix (fuzz_linear17, finding 19: 18
     * distinct rays of three cameras, eigenvalues 1.8e-10 and 9.6e-10 of
     * the largest; on exact data the motion came out 1.6 deg off, a local
     * minimum of the Sampson error, with its scale "observable"). So where
     * the kind read at NEAR_RTOL differs, solve also as that kind, with
     * those eigenvalues eliminated, and keep the motion of lower Sampson
     * cost (on that input: 6.7e-4 -> 4e-17 rad). Only as a second opinion
     * on a motion found: where the kind read at rank_rtol gives none, the
     * near kind's elimination is an approximation whose motion the data
     * need not support (a later input: four nearly coincident centres,
     * EDEGENERATE at rank_rtol, and the near kind's motion 0.07 deg off,
     * residuals 3e-4 rad, "observable") -- the failure stands. */
    if (st == MCG_OK) {
        int near_nullity, near_gc = classify(wr, vr, NEAR_RTOL, tr_m, &near_nullity);
        if (near_gc != gc && near_gc != MCG_GC_DEGENERATE && near_gc != MCG_GC_CENTRAL &&
            near_gc != MCG_GC_MOST_GENERAL && near_nullity > nullity) {
            mcg_linear17_result near;
            int st_near;
            memcpy(&near, res, sizeof near);
            st_near = solve_case(n, origins1, dirs1, origins2, dirs2, &o, m, wr, vr, tr_m,
                                 near_gc, near_nullity, NEAR_RTOL, &near);
            if (st_near == MCG_OK && near.cost_final < res->cost_final)
                memcpy(res, &near, sizeof near);
        }
    }
    return st;
}
