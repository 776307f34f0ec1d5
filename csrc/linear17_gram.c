/*
 * linear17_gram.c -- the linear step of linear17 (thesis ch. 8, csrc/linear17.c):
 * one pass over the rays builds the 18 x 18 Gram matrix M = A^T A of the
 * normalised generalized epipolar rows (eqs. 8.15-8.18; Algorithm 2 step 1),
 * the kind of generalized camera is read from the null space of M_RR
 * (ch. 8.3), E (and the R part) minimise |A x| by the constrained least
 * squares of Algorithm 4 / eq. 8.36 (the plain SVD for the most-general
 * kind), and E gives its rotation candidates.
 */
#include "linear17_internal.h"

#include <float.h>
#include <math.h>
#include <string.h>

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

/* the plain entry of the static clone above (internal.h, MCG_AVX2_CLONE) */
int linear17_accumulate(int n, const double *o1, const double *d1,
                        const double *o2, const double *d2,
                        double *m, double origin[3], double *scale)
{
    return accumulate(n, o1, d1, o2, d2, m, origin, scale);
}

/* Classify from the null space of A_R^T A_R (= M_RR): the structural
 * solutions (0, I), (0, w w^T), (0, [w]x) of eqs. 8.20-8.33 all have E = 0,
 * so they live in null(A_R); the true solution does not (E != 0). */
int linear17_classify(const double *wr, const double *vr, double rtol,
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

/* the plain entry of the static clone above (internal.h, MCG_AVX2_CLONE) */
int linear17_linear_step(const double *m, int gc_case,
                         const double *wr, const double *vr, double pinv_rtol,
                         double rtol, double tr_m, double e[9], double r[9],
                         mcg_linear17_result *res)
{
    return linear_step(m, gc_case, wr, vr, pinv_rtol, rtol, tr_m, e, r, res);
}

/* One rotation of E's twisted pair: U w V^T from E's SVD, negated when its
 * determinant is negative (E's sign is free). */
static void twisted(const double u[9], const double w[9], const double v[9], double out[9])
{
    double uw[9];
    int i;
    mul33(u, w, uw);
    mul33_abt(uw, v, out);
    if (det33(out) < 0.0)
        for (i = 0; i < 9; i++)
            out[i] = -out[i];
}

/* Rotation candidates: the two rotations of E = [t]x R (twisted pair: W and
 * W^T) and, where the R part is not ambiguous (most-general case), the
 * projection of the R part itself. */
int linear17_rotation_candidates(const double e[9], const double r[9], int use_r,
                                 double cand[4][9], int *ncand)
{
    static const double w[9] = {0, -1, 0, 1, 0, 0, 0, 0, 1};
    static const double wt[9] = {0, 1, 0, -1, 0, 0, 0, 0, 1};
    double u[9], s[3], v[9], work[64];
    int nc = 2, i;
    size_t lw = mcg_svd_work_size(3, 3);
    if (lw > 64)
        return MCG_ENOMEM;
    if (mcg_svd(3, 3, e, u, s, v, work, lw) != MCG_OK)
        return MCG_ENUMERIC;
    twisted(u, w, v, cand[0]);
    twisted(u, wt, v, cand[1]);
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
