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
 *   - cyclic Jacobi eigen-solver for symmetric matrices (the 9x9 and 18x18
 *     normal matrices of the linear 17-point estimator, Algorithm 2);
 *   - Cholesky solve of small SPD systems.
 * The 3x3 rotation helpers of the same section of mcgeom.h (Rodrigues
 * angle-axis, Hamilton quaternions, the projection onto SO(3)) are in
 * rotations.c.
 *
 * All matrices are row-major. No globals, no allocation: scratch space comes
 * from the caller's workspace (sizes from the *_work_size functions) or, for
 * the fixed tiny sizes, from the stack. Every loop is bounded.
 */
#include "mcgeom.h"
#include "internal.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

/* The Householder reduction and the QR rotations of mcg_sym_eig_tridiag
 * (linear17's two 9 x 9 decompositions per call) carry MCG_AVX2_CLONE
 * (internal.h: the same bits on every CPU). */

/* Jacobi converges quadratically: a handful of sweeps in practice. The cap
 * only turns a pathological input into MCG_ENUMERIC instead of a hang. */
#define MAX_SWEEPS 60
#define SPD_MAX 64
/* Rotations of one Jacobi round whose parameters are computed together. */
#define EIG_CHUNK 16
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

/* Exponent e with max_abs * 2^-e in [0.5, 1) (0 for a zero array). Scaling
 * by a power of two is exact, and it keeps every sum of squares below away
 * from overflow and harmful underflow whatever the magnitude of the input. */
static int scale_exponent(double amax)
{
    int e = 0;
    if (amax > 0.0)
        (void)frexp(amax, &e);
    return e;
}

/* 2^e where it is a normal double, else 0 (then mul_pow2 calls ldexp). */
static double pow2_or_zero(int e)
{
    return (e >= DBL_MIN_EXP - 1 && e <= DBL_MAX_EXP - 1) ? ldexp(1.0, e) : 0.0;
}

/* x 2^e, f = pow2_or_zero(e): where 2^e is a normal double one
 * multiplication by it, whose result is the exact x 2^e rounded once --
 * ldexp's result, so the same bits (subnormal, overflowing, inf and NaN
 * values included) -- instead of a libm call per value (issue 22: ldexp was
 * ~1.2k instructions of a public linear17 call at 100 rays). */
static inline double mul_pow2(double x, int e, double f)
{
    return f != 0.0 ? x * f : ldexp(x, e);
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

static void swap_rows(double *x, double *y, size_t n)
{
    size_t i;
    for (i = 0; i < n; ++i) {
        double t = x[i];
        x[i] = y[i];
        y[i] = t;
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
    /* selection sort: O(nn^2) comparisons, nn row swaps, no index array */
    for (k = 0; k + 1 < nn; ++k) {
        size_t best = k;
        for (l = k + 1; l < nn; ++l)
            if (s[l] > s[best])
                best = l;
        if (best != k) {
            double t = s[k];
            s[k] = s[best];
            s[best] = t;
            swap_rows(w + k * nn, w + best * nn, nn);
            swap_rows(vt + k * nn, vt + best * nn, nn);
        }
    }
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

/* -------------------------------------------------- symmetric eigen */

/* Overwrite the upper triangle (diagonal included) of the n x n matrix a
 * with its symmetric part 0.5 (a + a^T) scaled by 2^-e so that max |a_ij| is
 * in [0.5, 1); returns e. A power of two scales exactly: multiplying by it is
 * exact whenever the factor is a normal number, ldexp is used otherwise. */
static int scaled_symmetric_part(size_t n, double *a)
{
    int e = scale_exponent(max_abs(a, n * n));
    double f = 0.5 * ldexp(1.0, -e);
    int exact = f >= DBL_MIN && f <= 1e300;
    size_t i, j;
    for (i = 0; i < n; ++i)
        for (j = i; j < n; ++j)
            a[i * n + j] = exact ? f * a[i * n + j] + f * a[j * n + i]
                                 : 0.5 * ldexp(a[i * n + j], -e) +
                                       0.5 * ldexp(a[j * n + i], -e);
    return e;
}

/* One round of the tournament ordering (see jacobi_sweeps): the np / 2
 * disjoint pairs (p, q) of round `round`, each rotation annihilating a_pq
 * of the upper triangle of a (nn x nn) and accumulated into the rows of v
 * (V^T). The rotation parameters of a pair depend only on a_pp, a_qq,
 * a_pq, which the other rotations of the same round do not touch, so they
 * are computed in chunks of EIG_CHUNK before being applied: the square
 * roots and divisions of a chunk overlap instead of forming one long
 * dependency chain. Results equal applying the rotations one by one. */
static void jacobi_round(size_t nn, size_t np, size_t round, double thresh, double *a,
                         double *v)
{
    size_t rp_[EIG_CHUNK], rq_[EIG_CHUNK];
    double rc_[EIG_CHUNK], rs_[EIG_CHUNK], rt_[EIG_CHUNK];
    size_t pi = 0, half = np / 2, p, q, r;
    while (pi < half) {
        size_t cnt = 0, jj;
        /* gather: parameters of up to EIG_CHUNK rotations */
        for (; pi < half && cnt < EIG_CHUNK; ++pi) {
            size_t x0 = (pi == 0) ? 0 : 1 + (pi - 1 + round) % (np - 1);
            size_t y0 = 1 + (np - 2 - pi + round) % (np - 1);
            double apq, g, app, aqq, d, h, den, t, c;
            if (x0 >= nn || y0 >= nn)
                continue;
            p = x0 < y0 ? x0 : y0;
            q = x0 < y0 ? y0 : x0;
            apq = a[p * nn + q];
            g = fabs(apq);
            if (g == 0.0)
                continue;
            app = a[p * nn + p];
            aqq = a[q * nn + q];
            /* Relative criterion (Demmel & Veselic): zeroing a_pq
             * moves the eigenvalues by at most eps sqrt|a_pp a_qq|,
             * which keeps the small eigenvalues of graded PSD
             * matrices (A^T A near a null space) accurate, and
             * guarantees termination. Squared to save a square
             * root; g^2 underflows only for g < 1e-154 max|a|. */
            if (g * g <= DBL_EPSILON * DBL_EPSILON * fabs(app * aqq)) {
                a[p * nn + q] = 0.0;
                continue;
            }
            if (g <= thresh)
                continue;
            /* t = tan of the smaller angle that annihilates a_pq
             * (Rutishauser), as 2 a_pq sgn(d) / (|d| + h) with
             * d = a_qq - a_pp, h = sqrt(d^2 + 4 a_pq^2); no overflow
             * since |a_ij| <= n after scaling */
            d = aqq - app;
            h = sqrt(d * d + 4.0 * apq * apq);
            den = d + copysign(h, d);
            t = (den != 0.0) ? 2.0 * apq / den : copysign(1.0, apq);
            c = 1.0 / sqrt(1.0 + t * t);
            rp_[cnt] = p;
            rq_[cnt] = q;
            rc_[cnt] = c;
            rs_[cnt] = t * c;
            rt_[cnt] = t * apq;
            ++cnt;
        }
        /* apply */
        for (jj = 0; jj < cnt; ++jj) {
            double c = rc_[jj], s = rs_[jj];
            p = rp_[jj];
            q = rq_[jj];
            a[p * nn + p] -= rt_[jj];
            a[q * nn + q] += rt_[jj];
            a[p * nn + q] = 0.0;
#define MCG_JROT(x, y)                                                        \
    do {                                                                      \
        double xx_ = (x), yy_ = (y);                                          \
        (x) = c * xx_ - s * yy_;                                              \
        (y) = s * xx_ + c * yy_;                                              \
    } while (0)
            for (r = 0; r < p; ++r)
                MCG_JROT(a[r * nn + p], a[r * nn + q]);
            for (r = p + 1; r < q; ++r)
                MCG_JROT(a[p * nn + r], a[r * nn + q]);
            for (r = q + 1; r < nn; ++r)
                MCG_JROT(a[p * nn + r], a[q * nn + r]);
            for (r = 0; r < nn; ++r)
                MCG_JROT(v[p * nn + r], v[q * nn + r]);
#undef MCG_JROT
        }
    }
}

/* Cyclic Jacobi on the upper triangle of a (nn x nn), rotations accumulated
 * into v (V^T, rows = eigenvectors, so that they touch contiguous memory),
 * in the round-robin ("tournament") ordering: each sweep is np - 1 rounds
 * of np / 2 disjoint pairs (np = n rounded up to even, pairs with the dummy
 * index n skipped); chunking the rounds removed the dependency chain that
 * dominated the run time of the row-cyclic order at n = 9 and 18. Returns
 * 1 once the off-diagonal part is exactly 0, 0 after MAX_SWEEPS. */
static int jacobi_sweeps(size_t nn, double *a, double *v)
{
    size_t np = nn + (nn & 1), p, q, round;
    int sweep;
    for (sweep = 0; sweep <= MAX_SWEEPS; ++sweep) {
        double thresh, off = 0.0;
        for (p = 0; p + 1 < nn; ++p)
            for (q = p + 1; q < nn; ++q)
                off += fabs(a[p * nn + q]);
        if (off == 0.0)
            return 1;
        if (sweep == MAX_SWEEPS)
            break;
        /* threshold Jacobi (Rutishauser): during the first sweeps skip the
         * rotations that would gain little; saves work on dense matrices
         * without changing the (quadratic) final convergence */
        thresh = (sweep < 3) ? 0.2 * off / (double)(nn * nn) : 0.0;
        for (round = 0; round + 1 < np; ++round)
            jacobi_round(nn, np, round, thresh, a, v);
    }
    return 0;
}

int mcg_sym_eig(int n, double *a, double *w, double *v)
{
    size_t nn, i, j;
    int e;
    double f2;

    if (n < 1 || (size_t)n > MAX_COLS)
        return MCG_EINVAL;
    if (a == NULL || w == NULL || v == NULL || a == v)
        return MCG_EINVAL;
    nn = (size_t)n;
    if (!all_finite(a, nn * nn))
        return MCG_EINVAL;

    /* Symmetric part, scaled so that max |a_ij| is in [0.5, 1): no overflow
     * in (a_qq - a_pp) below, exact (power of two) and undone at the end.
     * Only the upper triangle is used from here on: each rotation then
     * updates n - 2 pairs of entries instead of mirroring 2 (n - 2). */
    e = scaled_symmetric_part(nn, a);
    /* v holds V^T during the iteration; transposed at the end. */
    memset(v, 0, nn * nn * sizeof(double));
    for (i = 0; i < nn; ++i)
        v[i * nn + i] = 1.0;
    if (!jacobi_sweeps(nn, a, v))
        return MCG_ENUMERIC;

    for (i = 0; i < nn; ++i)
        w[i] = a[i * nn + i];
    /* ascending order, moving the eigenvector rows along */
    for (i = 0; i + 1 < nn; ++i) {
        size_t best = i;
        for (j = i + 1; j < nn; ++j)
            if (w[j] < w[best])
                best = j;
        if (best != i) {
            double t = w[i];
            w[i] = w[best];
            w[best] = t;
            swap_rows(v + i * nn, v + best * nn, nn);
        }
    }
    f2 = pow2_or_zero(e);
    for (i = 0; i < nn; ++i) {
        w[i] = mul_pow2(w[i], e, f2);
        for (j = i + 1; j < nn; ++j) {
            double t = v[i * nn + j];
            v[i * nn + j] = v[j * nn + i];
            v[j * nn + i] = t;
        }
    }
    if (!all_finite(w, nn))
        return MCG_ENUMERIC;
    return MCG_OK;
}

/* ------------------------------------- symmetric eigen, tridiagonal QR */

/* Householder reduction of the symmetric n x n matrix a (upper triangle
 * holding the symmetric part, overwritten) to tridiagonal form
 * Q^T A Q = T: diagonal d[0..n-1], sub-diagonal e[0..n-2]; q (n x n,
 * row-major) accumulates Q. Each reflector H = I - v v^T 2 / (v^T v)
 * annihilates column k below the sub-diagonal and is applied to the
 * trailing block as A - v w^T - w v^T with w = p - (v^T p / v^T v) v,
 * p = 2 A v / (v^T v) (Golub & Van Loan, ch. 8.3.1). */
MCG_AVX2_CLONE
static void tridiagonalize(size_t n, double *a, double *d, double *e, double *q)
{
    double v[SPD_MAX], p[SPD_MAX];
    size_t i, j, k;
    for (i = 0; i < n; ++i) /* full symmetric storage from the upper triangle */
        for (j = 0; j < i; ++j)
            a[i * n + j] = a[j * n + i];
    memset(q, 0, n * n * sizeof(double));
    for (i = 0; i < n; ++i)
        q[i * n + i] = 1.0;
    for (k = 0; k + 2 < n; ++k) {
        size_t m = n - k - 1; /* length of the column part below the diagonal */
        double norm2 = 0.0, alpha, beta, vp = 0.0, kk;
        for (i = 0; i < m; ++i) {
            v[i] = a[(k + 1 + i) * n + k];
            norm2 += v[i] * v[i];
        }
        if (norm2 == 0.0) {
            e[k] = 0.0;
            continue;
        }
        /* alpha has the sign opposite to v0: no cancellation in v0 - alpha */
        alpha = -copysign(sqrt(norm2), v[0]);
        v[0] -= alpha;
        beta = 2.0 * (norm2 - alpha * (v[0] + alpha)); /* v^T v */
        e[k] = alpha;
        for (i = 0; i < m; ++i) { /* p = 2 A22 v / beta */
            double acc = 0.0;
            const double *row = a + (k + 1 + i) * n + (k + 1);
            for (j = 0; j < m; ++j)
                acc += row[j] * v[j];
            p[i] = 2.0 * acc / beta;
            vp += v[i] * p[i];
        }
        kk = vp / beta;
        for (i = 0; i < m; ++i) /* w = p - K v, stored in p */
            p[i] -= kk * v[i];
        for (i = 0; i < m; ++i) {
            double *row = a + (k + 1 + i) * n + (k + 1);
            for (j = 0; j < m; ++j)
                row[j] -= v[i] * p[j] + p[i] * v[j];
        }
        for (i = 0; i < n; ++i) { /* Q <- Q H on columns k+1.. */
            double *row = q + i * n + (k + 1), acc = 0.0;
            for (j = 0; j < m; ++j)
                acc += row[j] * v[j];
            acc *= 2.0 / beta;
            for (j = 0; j < m; ++j)
                row[j] -= acc * v[j];
        }
    }
    for (i = 0; i < n; ++i)
        d[i] = a[i * n + i];
    if (n >= 2)
        e[n - 2] = a[(n - 1) * n + (n - 2)];
}

/* Implicit symmetric QR with Wilkinson shift on the tridiagonal (d, e),
 * rotations accumulated into the rows of qt = Q^T (Golub & Van Loan,
 * Algorithm 8.3.3). Why the transpose: a rotation of columns k, k+1 of Q
 * touches two strided columns, one of Q^T two contiguous rows, which the
 * compiler vectorises; the products per entry are the same, so the result
 * is the same to the bit (issue 22: this loop was a third of the 9 x 9
 * decomposition). Returns 0 if the iteration budget ran out. */
MCG_AVX2_CLONE
static int tridiagonal_qr(size_t n, double *d, double *e, double *qt)
{
    size_t hi = n - 1, budget = 40 * n, i;
    while (hi > 0) {
        size_t lo, k;
        double delta, b, mu, x, z;
        /* deflate negligible couplings at the bottom */
        if (fabs(e[hi - 1]) <= DBL_EPSILON * (fabs(d[hi - 1]) + fabs(d[hi]))) {
            e[hi - 1] = 0.0;
            --hi;
            continue;
        }
        if (budget-- == 0)
            return 0;
        lo = hi - 1;
        while (lo > 0 && fabs(e[lo - 1]) > DBL_EPSILON * (fabs(d[lo - 1]) + fabs(d[lo])))
            --lo;
        if (lo > 0)
            e[lo - 1] = 0.0;
        /* Wilkinson shift: the eigenvalue of the trailing 2 x 2 nearer d[hi] */
        delta = 0.5 * (d[hi - 1] - d[hi]);
        b = e[hi - 1];
        mu = d[hi] - b * b / (delta + copysign(sqrt(delta * delta + b * b), delta));
        x = d[lo] - mu;
        z = e[lo];
        for (k = lo; k < hi; ++k) {
            /* rotation G = [c s; -s c] on (k, k+1) with s x + c z = 0 */
            /* sqrt of squares unless they could underflow (hypot is slow) */
            double r = sqrt(x * x + z * z), c, s, a0, b0, c0;
            if (r < 1e-150)
                r = hypot(x, z);
            if (r == 0.0) {
                c = 1.0;
                s = 0.0;
            } else {
                double inv = 1.0 / r;
                c = x * inv;
                s = -z * inv;
            }
            if (k > lo)
                e[k - 1] = c * x - s * z; /* the bulge is annihilated */
            a0 = d[k];
            b0 = e[k];
            c0 = d[k + 1];
            /* the 2 x 2 block of G^T T G */
            d[k] = c * c * a0 - 2.0 * c * s * b0 + s * s * c0;
            d[k + 1] = s * s * a0 + 2.0 * c * s * b0 + c * c * c0;
            e[k] = c * s * (a0 - c0) + (c * c - s * s) * b0;
            if (k + 1 < hi) {
                z = -s * e[k + 1]; /* new bulge at (k, k+2) */
                e[k + 1] *= c;
                x = e[k];
            }
            {
                double *rk = qt + k * n, *rl = rk + n;
                for (i = 0; i < n; ++i) {
                    double qk = rk[i], ql = rl[i];
                    rk[i] = c * qk - s * ql;
                    rl[i] = s * qk + c * ql;
                }
            }
        }
    }
    return 1;
}

int mcg_sym_eig_tridiag(int n, double *a, double *w, double *v)
{
    double e[SPD_MAX];
    size_t nn, i, j;
    int ex;
    if (n < 1 || n > SPD_MAX)
        return MCG_EINVAL;
    if (a == NULL || w == NULL || v == NULL || a == v)
        return MCG_EINVAL;
    nn = (size_t)n;
    if (!all_finite(a, nn * nn))
        return MCG_EINVAL;
    /* no overflow or harmful underflow in the rotations */
    ex = scaled_symmetric_part(nn, a);
    tridiagonalize(nn, a, w, e, v);
    /* Q^T into a (free after the reduction) for the QR, then back into v */
    for (i = 0; i < nn; ++i)
        for (j = 0; j < nn; ++j)
            a[j * nn + i] = v[i * nn + j];
    if (!tridiagonal_qr(nn, w, e, a))
        return MCG_ENUMERIC;
    for (i = 0; i < nn; ++i)
        for (j = 0; j < nn; ++j)
            v[j * nn + i] = a[i * nn + j];
    for (i = 0; i + 1 < nn; ++i) { /* ascending, columns of v along */
        size_t best = i;
        for (j = i + 1; j < nn; ++j)
            if (w[j] < w[best])
                best = j;
        if (best != i) {
            double t = w[i];
            w[i] = w[best];
            w[best] = t;
            for (j = 0; j < nn; ++j) {
                t = v[j * nn + i];
                v[j * nn + i] = v[j * nn + best];
                v[j * nn + best] = t;
            }
        }
    }
    {
        double f2 = pow2_or_zero(ex);
        for (i = 0; i < nn; ++i)
            w[i] = mul_pow2(w[i], ex, f2);
    }
    if (!all_finite(w, nn) || !all_finite(v, nn * nn))
        return MCG_ENUMERIC;
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
