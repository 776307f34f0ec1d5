/*
 * linalg.c -- small dense linear algebra of libmcgeom (no LAPACK, no BLAS).
 *
 * Implements the "linalg.c" section of mcgeom.h:
 *   - thin Householder QR (Golub & Van Loan 5.2);
 *   - SVD by Householder QR with column pivoting followed by one-sided
 *     (Hestenes) Jacobi on the triangular factor (Drmac & Veselic's
 *     preconditioned Jacobi), which keeps the small singular values of tall thin
 *     matrices (the 17..n x 18 generalized epipolar systems of thesis ch. 8,
 *     eq. 8.16, and the reduced system of eq. 8.36) accurate to working
 *     precision relative to the largest one;
 *   - Moore-Penrose pseudo-inverse (needed by Algorithms 3-4, eq. 8.36);
 *   - Cholesky solve of small SPD systems.
 * The same section of mcgeom.h has two more files: linalg_eig.c, the
 * symmetric eigen-solvers (cyclic Jacobi; tridiagonal QR), and rotations.c,
 * the 3x3 rotation helpers (Rodrigues angle-axis, Hamilton quaternions, the
 * projection onto SO(3)); linalg_internal.h holds what linalg.c and
 * linalg_eig.c share.
 *
 * All matrices are row-major. No globals, no allocation: scratch space comes
 * from the caller's workspace (sizes from the *_work_size functions) or, for
 * the fixed tiny sizes, from the stack. Every loop is bounded.
 */
#include "mcgeom.h"
#include "internal.h"
#include "linalg_internal.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

/* A Jacobi vector whose norm falls below DEAD_REL times the largest initial
 * one (<= s_max) is "dead": it takes part in no further rotation and its
 * singular value is reported as exactly 0 (its singular vector is
 * completed). Dropping dead vectors perturbs R by at most sqrt(n) DEAD_REL
 * s_max, the size of the backward error of the QR step itself, so the
 * accuracy relative to s_max is unchanged. Without this, the noise-level
 * columns of a rank-deficient matrix are orthogonalised among themselves at
 * ever smaller scales (1e-16, 1e-32, ... down to underflow), which took up to
 * 40 sweeps instead of 5-8 in tests. */
#define DEAD_REL DBL_EPSILON
/* Absolute floor of the dead threshold (squared): below it dot products
 * would lose precision to underflow. Inputs are scaled so that max |a_ij|
 * lies in [0.5, 1), so this only matters for an all-zero matrix. */
#define TINY2 (DBL_MIN / DBL_EPSILON)
/* Orthogonality threshold of one-sided Jacobi, in units of eps * sqrt(n):
 * two columns count as orthogonal when |g_i . g_j| <= tol |g_i| |g_j|. A few
 * ulps above the rounding noise of a dot product so that sweeps terminate. */
#define JACOBI_TOL_FACTOR 4.0
/* (the deviation from orthogonality accepted for a rotation: SO3_ROT_TOL,
 * so3.h, shared with refine.c) */

/* ------------------------------------------------------------- helpers */

static int dims_ok(int m, int n)
{
    return m >= 1 && n >= 1 && (size_t)m <= MAX_ROWS && (size_t)n <= MAX_COLS;
}

/* Dot product with four independent partial sums: a single running sum is
 * bound by the latency of the floating-point add (the compiler may not
 * reassociate it), which made this the bottleneck of the QR and Jacobi
 * loops. The rounding error bound is unchanged (slightly smaller). */
static double dot(const double *x, const double *y, size_t n)
{
    double a0 = 0.0, a1 = 0.0, a2 = 0.0, a3 = 0.0;
    size_t i = 0;
    for (; i + 4 <= n; i += 4) {
        a0 += x[i] * y[i];
        a1 += x[i + 1] * y[i + 1];
        a2 += x[i + 2] * y[i + 2];
        a3 += x[i + 3] * y[i + 3];
    }
    for (; i < n; ++i)
        a0 += x[i] * y[i];
    return (a0 + a1) + (a2 + a3);
}

/* Both y . y and x . y in one pass (the Jacobi inner loop). */
static void dot2(const double *x, const double *y, size_t n, double *yy,
                 double *xy)
{
    double b0 = 0.0, b1 = 0.0, g0 = 0.0, g1 = 0.0;
    size_t i = 0;
    for (; i + 2 <= n; i += 2) {
        b0 += y[i] * y[i];
        b1 += y[i + 1] * y[i + 1];
        g0 += x[i] * y[i];
        g1 += x[i + 1] * y[i + 1];
    }
    for (; i < n; ++i) {
        b0 += y[i] * y[i];
        g0 += x[i] * y[i];
    }
    *yy = b0 + b1;
    *xy = g0 + g1;
}

/* Plane rotation of two rows: x <- c x - s y, y <- s x + c y. */
static void rot_rows(double *x, double *y, size_t n, double c, double s)
{
    size_t i;
    for (i = 0; i < n; ++i) {
        double xi = x[i], yi = y[i];
        x[i] = c * xi - s * yi;
        y[i] = s * xi + c * yi;
    }
}

/* ------------------------------------------------------ Householder QR */

/* Householder QR of the len x ncol matrix (len >= ncol) whose COLUMNS are
 * stored as the rows of at: element (i, j) is at[j * len + i]. Storing the
 * transpose makes every column operation a contiguous loop. On return R(i, j)
 * (i <= j) is at[j * len + i], the essential part of reflector k (its first
 * component is an implicit 1) is at[k * len + i] for i > k, and
 * H_k = I - tau[k] v_k v_k^T (LAPACK dgeqr2 convention, tau = 0 for H = I).
 *
 * With perm != NULL, columns are pivoted (Businger-Golub, as LAPACK dgeqp3):
 * at step k the remaining column of largest norm is moved to position k, so
 * a P = Q R with perm[k] = original index of column k (stored as a double:
 * the workspace is all doubles). vn: 2 ncol doubles for the partial column
 * norms, downdated with the safeguard of Drmac & Bujanovic (LAPACK 3.x).
 * Pivoting makes R graded (|R(k,k)| non-increasing), the preconditioning
 * under which one-sided Jacobi on R^T converges in a few sweeps
 * (Drmac & Veselic 2008) and which orders numerically zero columns last. */
static void house_qr(size_t len, size_t ncol, double *at, double *tau,
                     double *perm, double *vn)
{
    const double tol3z = sqrt(DBL_EPSILON);
    double *vn1 = vn, *vn2 = (vn != NULL) ? vn + ncol : NULL;
    size_t k, i, j;

    if (perm != NULL) {
        for (j = 0; j < ncol; ++j) {
            perm[j] = (double)j;
            vn1[j] = sqrt(dot(at + j * len, at + j * len, len));
            vn2[j] = vn1[j];
        }
    }
    for (k = 0; k < ncol; ++k) {
        double *x = at + k * len + k;
        size_t nk = len - k;
        double alpha, xn2, beta, sc, f, xmax;
        int s2;
        if (perm != NULL) {
            size_t best = k;
            for (j = k + 1; j < ncol; ++j)
                if (vn1[j] > vn1[best])
                    best = j;
            if (best != k) {
                double t;
                swap_rows(at + k * len, at + best * len, len);
                t = perm[k];
                perm[k] = perm[best];
                perm[best] = t;
                vn1[best] = vn1[k];
                vn2[best] = vn2[k];
            }
        }
        /* The matrix is scaled to max |a_ij| < 1, but a column can still be
         * tiny next to the others (a graded matrix): below 1e-150 its
         * squares would underflow into the denormals and the reflector lose
         * its orthogonality (found by fuzz_linalg), so such a column is
         * computed scaled by 2^s (exact; the reflector is scale-invariant,
         * beta scales back), s = 0 otherwise. s is applied as an exponent
         * (mul_pow2): for a subnormal column s exceeds 1023 and the factor
         * 2^s itself would be inf, making the reflector NaN (found by
         * fuzz_linalg: a 9 x 4 matrix with entries from 5e-324 to 3e304). */
        s2 = 0;
        xmax = max_abs(x, nk);
        if (xmax > 0.0 && xmax < 1e-150)
            s2 = -scale_exponent(xmax);
        f = pow2_or_zero(s2);
        alpha = mul_pow2(x[0], s2, f);
        if (s2 == 0) {
            xn2 = dot(x + 1, x + 1, nk - 1);
        } else {
            xn2 = 0.0;
            for (i = 1; i < nk; ++i) {
                const double xi = mul_pow2(x[i], s2, f);
                xn2 += xi * xi;
            }
        }
        if (xn2 == 0.0) {
            tau[k] = 0.0; /* already triangular in this column */
        } else {
            /* beta has the sign opposite to alpha: alpha - beta never
             * cancels */
            beta = -copysign(sqrt(alpha * alpha + xn2), alpha);
            tau[k] = (beta - alpha) / beta;
            sc = 1.0 / (alpha - beta);
            for (i = 1; i < nk; ++i)
                x[i] = mul_pow2(x[i], s2, f) * sc;
            x[0] = s2 == 0 ? beta : ldexp(beta, -s2);
            for (j = k + 1; j < ncol; ++j) {
                double *y = at + j * len + k;
                double d = (y[0] + dot(x + 1, y + 1, nk - 1)) * tau[k];
                y[0] -= d;
                for (i = 1; i < nk; ++i)
                    y[i] -= d * x[i];
            }
        }
        if (perm != NULL) {
            /* norms of the remaining parts (rows > k) of columns j > k */
            for (j = k + 1; j < ncol; ++j) {
                double t, t2;
                if (vn1[j] == 0.0)
                    continue;
                t = fabs(at[j * len + k]) / vn1[j];
                t = 1.0 - t * t;
                if (t < 0.0)
                    t = 0.0;
                t2 = t * (vn1[j] / vn2[j]) * (vn1[j] / vn2[j]);
                if (t2 <= tol3z) { /* cancellation: recompute */
                    const double *y = at + j * len + k + 1;
                    vn1[j] = sqrt(dot(y, y, len - k - 1));
                    vn2[j] = vn1[j];
                } else {
                    vn1[j] *= sqrt(t);
                }
            }
        }
    }
}

/* x (len x nc, row-major) <- H_0 H_1 ... H_{nref-1} x with the reflectors of
 * house_qr. With from_identity, x is assumed to start as [I; 0] so that
 * columns c < k are untouched by H_k (it only mixes rows >= k, where those
 * columns are still zero): skipping them halves the cost of forming Q.
 * tmp: nc doubles. */
static void apply_q(size_t len, size_t nref, const double *at,
                    const double *tau, double *x, size_t nc,
                    int from_identity, double *tmp)
{
    size_t kk, i, c;
    for (kk = nref; kk-- > 0;) {
        const double *v = at + kk * len + kk;
        size_t nk = len - kk, c0 = from_identity ? kk : 0;
        double tk = tau[kk];
        double *row = x + kk * nc;
        if (tk == 0.0)
            continue;
        for (c = c0; c < nc; ++c)
            tmp[c] = row[c];
        for (i = 1; i < nk; ++i) {
            const double *ri = x + (kk + i) * nc;
            double vi = v[i];
            for (c = c0; c < nc; ++c)
                tmp[c] += vi * ri[c];
        }
        for (c = c0; c < nc; ++c) {
            tmp[c] *= tk;
            row[c] -= tmp[c];
        }
        for (i = 1; i < nk; ++i) {
            double *ri = x + (kk + i) * nc;
            double vi = v[i];
            for (c = c0; c < nc; ++c)
                ri[c] -= vi * tmp[c];
        }
    }
}

size_t mcg_qr_work_size(int m, int n)
{
    int ok = 1;
    size_t mm, nn, ws;
    if (!dims_ok(m, n) || m < n)
        return 0;
    mm = (size_t)m;
    nn = (size_t)n;
    /* at (n x m) + tau (n) + tmp (n) */
    ws = add_sz(mul_sz(mm, nn, &ok), mul_sz(2, nn, &ok), &ok);
    return ok ? ws : 0;
}

int mcg_qr(int m, int n, const double *a, double *q, double *r,
           double *work, size_t lwork)
{
    size_t mm, nn, ws, i, j;
    double *at, *tau, *tmp;
    int e;

    if (!dims_ok(m, n) || m < n)
        return MCG_EINVAL;
    if (a == NULL || r == NULL || work == NULL)
        return MCG_EINVAL;
    ws = mcg_qr_work_size(m, n);
    if (ws == 0)
        return MCG_EINVAL;
    if (lwork < ws)
        return MCG_ENOMEM;
    mm = (size_t)m;
    nn = (size_t)n;
    if (!all_finite(a, mm * nn))
        return MCG_EINVAL;

    at = work;
    tau = at + mm * nn;
    tmp = tau + nn;
    e = scale_exponent(max_abs(a, mm * nn));
    for (i = 0; i < mm; ++i)
        for (j = 0; j < nn; ++j)
            at[j * mm + i] = ldexp(a[i * nn + j], -e);
    house_qr(mm, nn, at, tau, NULL, NULL);

    for (i = 0; i < nn; ++i)
        for (j = 0; j < nn; ++j)
            r[i * nn + j] = (j >= i) ? ldexp(at[j * mm + i], e) : 0.0;
    if (!all_finite(r, nn * nn))
        return MCG_ENUMERIC; /* |R| beyond the double range */

    if (q != NULL) {
        memset(q, 0, mm * nn * sizeof(double));
        for (i = 0; i < nn; ++i)
            q[i * nn + i] = 1.0;
        apply_q(mm, nn, at, tau, q, nn, 1, tmp);
    }
    return MCG_OK;
}

/* ----------------------------------------------------------------- SVD */

/* One-sided Jacobi (Hestenes) on the columns of M = w^T, i.e. on the nn
 * rows of w: rotate pairs of rows until all are mutually orthogonal to
 * working precision, applying the same rotations to the rows of vt (which
 * starts as I). Then M J = G with J = vt^T orthogonal and G = w^T with
 * orthogonal columns, so M = U_G S J^T. Returns 0 on convergence. Working on
 * the vectors themselves (never forming M^T M) is what resolves singular
 * values down to eps * s_max. Rows with squared norm below dead2 are
 * skipped (see DEAD_REL). */
static int jacobi_rows(size_t nn, double *w, double *vt, double dead2)
{
    const double tol =
        JACOBI_TOL_FACTOR * DBL_EPSILON * sqrt((double)nn);
    int sweep;
    size_t i, j;

    for (sweep = 0; sweep < MAX_SWEEPS; ++sweep) {
        int rotated = 0;
        for (i = 0; i + 1 < nn; ++i) {
            double *gi = w + i * nn;
            double alpha = dot(gi, gi, nn);
            for (j = i + 1; j < nn; ++j) {
                double *gj = w + j * nn;
                double beta, gamma, zeta, t, c, s;
                if (alpha < dead2)
                    break; /* dead column: nothing to orthogonalise */
                dot2(gi, gj, nn, &beta, &gamma);
                if (beta < dead2)
                    continue;
                if (fabs(gamma) <= tol * sqrt(alpha) * sqrt(beta))
                    continue;
                rotated = 1;
                /* Rutishauser's stable formulas: t = tan of the smaller of
                 * the two angles annihilating gamma (|t| <= 1). */
                zeta = (beta - alpha) / (2.0 * gamma);
                if (fabs(zeta) > 1e150)
                    t = 0.5 / zeta; /* zeta^2 would overflow */
                else
                    t = copysign(1.0, zeta) /
                        (fabs(zeta) + sqrt(1.0 + zeta * zeta));
                c = 1.0 / sqrt(1.0 + t * t);
                s = c * t;
                rot_rows(gi, gj, nn, c, s);
                rot_rows(vt + i * nn, vt + j * nn, nn, c, s);
                alpha = dot(gi, gi, nn);
            }
        }
        if (!rotated)
            return 0;
    }
    return -1;
}

/* After jacobi_rows: s[k] = |w_k| (0 if dead); sort descending (swapping
 * rows of w and vt); normalise the rows of w (the columns of U_G) and
 * complete those of zero singular values to an orthonormal basis of R^nn,
 * so that U_G is always orthogonal. tmp: nn doubles. */
static void finish_jacobi(size_t nn, double *w, double *vt, double *s,
                          double *tmp, double dead2)
{
    size_t k, l, j, nz;

    for (k = 0; k < nn; ++k) {
        double a2 = dot(w + k * nn, w + k * nn, nn);
        s[k] = (a2 < dead2) ? 0.0 : sqrt(a2);
    }
    sort_with_rows(nn, s, 1, w, vt); /* singular values descending */
    nz = 0;
    for (k = 0; k < nn; ++k) {
        if (s[k] > 0.0) {
            double inv = 1.0 / s[k];
            for (j = 0; j < nn; ++j)
                w[k * nn + j] *= inv;
            nz = k + 1;
        }
    }
    if (nz == nn)
        return;

    /* Completion. tmp[j] = squared norm of row j of the current basis
     * (= |projection of e_j|^2); the e_j with the smallest one is the best
     * conditioned start for Gram-Schmidt: its residual is >= 1/nn since the
     * tmp[j] sum to the number of basis vectors (< nn). */
    for (j = 0; j < nn; ++j) {
        double acc = 0.0;
        for (l = 0; l < nz; ++l)
            acc += w[l * nn + j] * w[l * nn + j];
        tmp[j] = acc;
    }
    for (k = nz; k < nn; ++k) {
        double *x = w + k * nn, nrm;
        size_t jmin = 0;
        int pass;
        for (j = 1; j < nn; ++j)
            if (tmp[j] < tmp[jmin])
                jmin = j;
        for (j = 0; j < nn; ++j)
            x[j] = 0.0;
        x[jmin] = 1.0;
        for (pass = 0; pass < 2; ++pass) { /* twice is enough (Kahan) */
            for (l = 0; l < k; ++l) {
                const double *b = w + l * nn;
                double d = dot(b, x, nn);
                for (j = 0; j < nn; ++j)
                    x[j] -= d * b[j];
            }
        }
        nrm = sqrt(dot(x, x, nn));
        for (j = 0; j < nn; ++j) {
            x[j] /= nrm;
            tmp[j] += x[j] * x[j];
        }
    }
}

size_t mcg_svd_work_size(int m, int n)
{
    int ok = 1;
    size_t nn, pp, ws;
    if (!dims_ok(m, n))
        return 0;
    nn = (size_t)(m < n ? m : n);
    pp = (size_t)(m < n ? n : m);
    /* at (nn x pp) + tau, perm (nn each) + vn (2 nn) + w, vt (nn x nn each)
     * + tmp (pp) = pp nn + 4 nn + 2 nn^2 + pp <= p n + 3 n^2 + 4 p as
     * promised by the header (4 nn <= n^2 + 3 p since p >= n or nn < n). */
    ws = mul_sz(pp, nn, &ok);
    ws = add_sz(ws, mul_sz(4, nn, &ok), &ok);
    ws = add_sz(ws, mul_sz(2, mul_sz(nn, nn, &ok), &ok), &ok);
    ws = add_sz(ws, pp, &ok);
    return ok ? ws : 0;
}

int mcg_svd(int m, int n, const double *a, double *u, double *s, double *v,
            double *work, size_t lwork)
{
    size_t mm, nn, len, nq, ws, i, j, k;
    double *at, *tau, *perm, *vn, *w, *vt, *tmp, dead2, maxrow2, f2;
    int e, tall;

    if (!dims_ok(m, n))
        return MCG_EINVAL;
    if (a == NULL || s == NULL || v == NULL || work == NULL)
        return MCG_EINVAL;
    ws = mcg_svd_work_size(m, n);
    if (ws == 0)
        return MCG_EINVAL;
    if (lwork < ws)
        return MCG_ENOMEM;
    mm = (size_t)m;
    nn = (size_t)n;
    if (!all_finite(a, mm * nn))
        return MCG_EINVAL;

    /* A wide matrix is handled through its transpose, so the QR is always
     * of a tall len x nq matrix b (len >= nq): b = a (tall) or a^T (wide). */
    tall = (mm >= nn);
    nq = tall ? nn : mm;
    len = tall ? mm : nn;
    at = work;
    tau = at + nq * len;
    perm = tau + nq;
    vn = perm + nq;
    w = vn + 2 * nq;
    vt = w + nq * nq;
    tmp = vt + nq * nq;

    e = scale_exponent(max_abs(a, mm * nn));
    f2 = pow2_or_zero(-e);
    if (tall) {
        for (i = 0; i < mm; ++i)
            for (j = 0; j < nn; ++j)
                at[j * mm + i] = mul_pow2(a[i * nn + j], -e, f2);
    } else {
        /* columns of a^T are the rows of a: a plain copy */
        for (i = 0; i < mm * nn; ++i)
            at[i] = mul_pow2(a[i], -e, f2);
    }
    /* b P = Q R with column pivoting */
    house_qr(len, nq, at, tau, perm, vn);

    /* One-sided Jacobi on the columns of R^T, i.e. on the rows of R, which
     * w holds (row j = row j of R): the preconditioned Jacobi of Drmac &
     * Veselic. It converges in fewer sweeps than Jacobi on the columns of R
     * (graded and Hilbert-like matrices in particular). */
    maxrow2 = 0.0;
    for (j = 0; j < nq; ++j) {
        double r2;
        for (i = 0; i < nq; ++i)
            w[j * nq + i] = (j <= i) ? at[i * len + j] : 0.0;
        r2 = dot(w + j * nq, w + j * nq, nq);
        if (r2 > maxrow2)
            maxrow2 = r2;
    }
    memset(vt, 0, nq * nq * sizeof(double));
    for (i = 0; i < nq; ++i)
        vt[i * nq + i] = 1.0;
    dead2 = DEAD_REL * DEAD_REL * maxrow2;
    if (dead2 < TINY2)
        dead2 = TINY2;
    if (jacobi_rows(nq, w, vt, dead2) != 0)
        return MCG_ENUMERIC;
    /* R^T J = G = U_G S with J = vt^T, so R = J S U_G^T and
     * b = (Q J) S (P U_G)^T, where U_G(l, k) = w[k nq + l] after
     * finish_jacobi and (P U_G)(perm[l], k) = U_G(l, k). */
    finish_jacobi(nq, w, vt, s, tmp, dead2);

    f2 = pow2_or_zero(e);
    for (k = 0; k < nq; ++k)
        s[k] = mul_pow2(s[k], e, f2);
    for (k = nq; k < nn; ++k)
        s[k] = 0.0;
    if (!all_finite(s, nq))
        return MCG_ENUMERIC; /* singular values beyond the double range */

    if (tall) {
        /* a = (Q J) S (P U_G)^T: v = P U_G, u = Q J */
        for (i = 0; i < nn; ++i) {
            size_t row = (size_t)perm[i];
            for (k = 0; k < nn; ++k)
                v[row * nn + k] = w[k * nn + i];
        }
        if (u != NULL) {
            for (i = 0; i < mm; ++i)
                for (k = 0; k < nn; ++k)
                    u[i * nn + k] = (i < nn) ? vt[k * nn + i] : 0.0;
            apply_q(mm, nn, at, tau, u, nn, 0, tmp);
        }
    } else {
        /* a^T = (Q J) S (P U_G)^T, so a = (P U_G) S (Q J)^T: u = P U_G and
         * the full V = Q_full blockdiag(J, I), whose last n - m columns span
         * the complement of range(a^T), i.e. the null space of a. */
        if (u != NULL)
            for (i = 0; i < mm; ++i) {
                size_t row = (size_t)perm[i];
                for (k = 0; k < mm; ++k)
                    u[row * mm + k] = w[k * mm + i];
            }
        for (i = 0; i < nn; ++i)
            for (k = 0; k < nn; ++k) {
                double val;
                if (i < mm && k < mm)
                    val = vt[k * mm + i];
                else
                    val = (i == k) ? 1.0 : 0.0;
                v[i * nn + k] = val;
            }
        apply_q(nn, mm, at, tau, v, nn, 0, tmp);
    }
    /* entries near DBL_MAX can still overflow in the wide-matrix path (found
     * by fuzz_linalg: a 2 x 5 matrix with 1.8e308 gave a non-finite V with
     * MCG_OK): never report success with non-finite output */
    if (!all_finite(s, nn) || !all_finite(v, nn * nn) ||
        (u != NULL && !all_finite(u, mm * min_sz(mm, nn))))
        return MCG_ENUMERIC;
    return MCG_OK;
}

/* ------------------------------------------------------- pseudo-inverse */

size_t mcg_pinv_work_size(int m, int n)
{
    int ok = 1;
    size_t mm, nn, mn, ws;
    if (!dims_ok(m, n))
        return 0;
    mm = (size_t)m;
    nn = (size_t)n;
    mn = mm < nn ? mm : nn;
    /* u (m x min) + s (n) + v (n x n) + svd workspace */
    ws = mcg_svd_work_size(m, n);
    ws = add_sz(ws, mul_sz(mm, mn, &ok), &ok);
    ws = add_sz(ws, nn, &ok);
    ws = add_sz(ws, mul_sz(nn, nn, &ok), &ok);
    return ok ? ws : 0;
}

int mcg_pinv(int m, int n, const double *a, double rcond, double *ainv,
             int *rank, double *work, size_t lwork)
{
    size_t mm, nn, mn, ws, i, j, k, r;
    double *u, *s, *v, *sw, tol;
    int st;

    if (!dims_ok(m, n))
        return MCG_EINVAL;
    if (a == NULL || ainv == NULL || work == NULL || !isfinite(rcond))
        return MCG_EINVAL;
    ws = mcg_pinv_work_size(m, n);
    if (ws == 0)
        return MCG_EINVAL;
    if (lwork < ws)
        return MCG_ENOMEM;
    mm = (size_t)m;
    nn = (size_t)n;
    mn = mm < nn ? mm : nn;
    u = work;
    s = u + mm * mn;
    v = s + nn;
    sw = v + nn * nn;
    st = mcg_svd(m, n, a, u, s, v, sw, lwork - (size_t)(sw - work));
    if (st != MCG_OK)
        return st;

    if (rcond <= 0.0)
        rcond = (double)(mm > nn ? mm : nn) * DBL_EPSILON;
    tol = rcond * s[0];
    r = 0;
    while (r < mn && s[r] > tol)
        ++r;
    /* A^+ = V_r S_r^{-1} U_r^T; fold S_r^{-1} into U first */
    for (i = 0; i < mm; ++i)
        for (k = 0; k < r; ++k)
            u[i * mn + k] /= s[k];
    for (j = 0; j < nn; ++j)
        for (i = 0; i < mm; ++i) {
            double acc = 0.0;
            for (k = 0; k < r; ++k)
                acc += v[j * nn + k] * u[i * mn + k];
            ainv[j * mm + i] = acc;
        }
    if (rank != NULL)
        *rank = (int)r;
    if (!all_finite(ainv, mm * nn))
        return MCG_ENUMERIC; /* rcond so small that 1/s overflowed */
    return MCG_OK;
}

/* ------------------------------------------------------------ Cholesky */

int mcg_spd_solve(int n, const double *a, const double *b, double *x)
{
    double l[SPD_MAX * SPD_MAX], y[SPD_MAX];
    double maxdiag = 0.0;
    size_t nn, i, j, k;

    if (n < 1 || n > SPD_MAX)
        return MCG_EINVAL;
    if (a == NULL || b == NULL || x == NULL)
        return MCG_EINVAL;
    nn = (size_t)n;
    if (!all_finite(a, nn * nn) || !all_finite(b, nn))
        return MCG_EINVAL;

    for (i = 0; i < nn; ++i)
        if (a[i * nn + i] > maxdiag)
            maxdiag = a[i * nn + i];
    if (!(maxdiag > 0.0))
        return MCG_ENUMERIC;
    /* L L^T of the symmetric part (lower triangle of l) */
    for (j = 0; j < nn; ++j) {
        double d = a[j * nn + j];
        for (k = 0; k < j; ++k)
            d -= l[j * nn + k] * l[j * nn + k];
        /* a pivot at rounding level of the largest diagonal entry means the
         * matrix is semi-definite or indefinite to working precision */
        if (!(d > DBL_EPSILON * maxdiag))
            return MCG_ENUMERIC;
        d = sqrt(d);
        l[j * nn + j] = d;
        for (i = j + 1; i < nn; ++i) {
            double acc = 0.5 * a[i * nn + j] + 0.5 * a[j * nn + i];
            for (k = 0; k < j; ++k)
                acc -= l[i * nn + k] * l[j * nn + k];
            l[i * nn + j] = acc / d;
        }
    }
    for (i = 0; i < nn; ++i) { /* L y = b */
        double acc = b[i];
        for (k = 0; k < i; ++k)
            acc -= l[i * nn + k] * y[k];
        y[i] = acc / l[i * nn + i];
    }
    for (i = nn; i-- > 0;) { /* L^T x = y */
        double acc = y[i];
        for (k = i + 1; k < nn; ++k)
            acc -= l[k * nn + i] * x[k];
        x[i] = acc / l[i * nn + i];
    }
    if (!all_finite(x, nn))
        return MCG_ENUMERIC;
    return MCG_OK;
}
