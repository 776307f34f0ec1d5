/*
 * fuzz_translation.c -- libFuzzer harness of csrc/translation.c (thesis
 * ch. 6): bilinear (eq. 6.5) and trilinear (eq. 6.11) relation rows, their
 * per-block Gram matrices, and the skyline (envelope) Cholesky, solve and
 * smallest eigenpairs of a pencil used for min |A G c| s.t. |G c| = 1.
 *
 * Invariants (on MCG_OK): finite outputs; a bilinear row dotted with
 * (c_1, c_2, 1) equals (x1 x x2) . (c_2 + w2 - c_1 - w1) evaluated directly,
 * a trilinear row with (a, b, 1) equals M_st of its header comment; Gram
 * blocks are symmetric with a non-negative diagonal; the Cholesky of a
 * diagonally dominant matrix in any valid profile succeeds and its solve
 * satisfies A x = b; the eigenpairs of such a pencil are ascending, above
 * zero and B-orthonormal. Bad sizes, profiles, NULLs and non-finite inputs
 * give MCG_EINVAL; arbitrary matrices give a known status, never a crash.
 */
#include "fuzz_input.h"
#include "mcgeom.h"

/* routines selected by the first input byte (fuzz/make_corpus.py writes
 * seeds for each) */
#define FUZZ_MODES 3

#define MAXN 24
#define MAXSKY 40

/* |lhs - rhs| within rounding of sums of products of magnitude mag; floor:
 * the absolute error of products that fall into the denormal range (a
 * product of two tiny bearing components loses precision there, then gets
 * multiplied by a large one), with mx the largest |bearing component| and
 * mc the largest |centre or offset| involved */
static int close_to(double lhs, double rhs, double mag, double mx, double mc)
{
    const double denorm = 4.9406564584124654e-324 * 64.0;
    const double floor = denorm * fmax(mx, 1.0) * fmax(mx, 1.0) * fmax(mc, 1.0);
    return fabs(lhs - rhs) <= 1e-11 * mag + floor + 1e-300;
}

static void fuzz_rows(fz_in *in)
{
    int valid, st, k, s, t, i;
    const int tri = fz_u8(in) & 1, offsets = fz_u8(in) & 1;
    int n = fz_size(in, 1, MAXN, &valid);
    double x[3][3 * MAXN], w[3][3 * MAXN], rows[9 * 7 * MAXN], c[3][3];
    if (!valid) {
        double dummy[64] = {0};
        FZ_CHECK(mcg_bilinear_rows(n, dummy, dummy, NULL, NULL, dummy) == MCG_EINVAL,
                 "bilinear_rows(n = %d) accepted", n);
        FZ_CHECK(mcg_trilinear_rows(n, dummy, dummy, dummy, NULL, NULL, NULL, dummy) ==
                     MCG_EINVAL, "trilinear_rows(n = %d) accepted", n);
        return;
    }
    for (i = 0; i < 3; ++i) {
        fz_matrix(in, x[i], (size_t)n, 3);
        fz_matrix(in, w[i], (size_t)n, 3);
    }
    if (!tri) {
        st = mcg_bilinear_rows(n, x[0], x[1], offsets ? w[0] : NULL, offsets ? w[1] : NULL,
                               rows);
        FZ_CHECK(fz_status_known(st), "bilinear status %d", st);
        if (!fz_all_finite(x[0], 3 * (size_t)n) || !fz_all_finite(x[1], 3 * (size_t)n))
            FZ_CHECK(st == MCG_EINVAL, "bilinear_rows of non-finite bearings: %d", st);
        if (st != MCG_OK)
            return;
        FZ_CHECK(fz_all_finite(rows, 7 * (size_t)n), "bilinear: non-finite row");
        for (i = 0; i < 3; ++i) {
            c[0][i] = fz_range(in, -4.0, 4.0);
            c[1][i] = fz_range(in, -4.0, 4.0);
        }
        for (k = 0; k < n; ++k) {
            const double *r = rows + 7 * k;
            double u[3], d[3], lhs = r[6], mag = fabs(r[6]), rhs;
            fz_cross3(x[0] + 3 * k, x[1] + 3 * k, u);
            for (i = 0; i < 3; ++i) {
                lhs += r[i] * c[0][i] + r[3 + i] * c[1][i];
                mag += fabs(r[i] * c[0][i]) + fabs(r[3 + i] * c[1][i]);
                d[i] = c[1][i] - c[0][i] +
                       (offsets ? w[1][3 * k + i] - w[0][3 * k + i] : 0.0);
            }
            rhs = fz_dot3(u, d);
            /* a bound on every product either side forms (cancellation
             * inside the row coefficients included) */
            mag += 8.0 * fz_maxabs(x[0] + 3 * k, 3) * fz_maxabs(x[1] + 3 * k, 3) *
                   (fz_maxabs(c[0], 3) + fz_maxabs(c[1], 3) +
                    (offsets ? fz_maxabs(w[0] + 3 * k, 3) + fz_maxabs(w[1] + 3 * k, 3) : 0.0));
            if (!isfinite(rhs) || !isfinite(mag))
                continue; /* the direct evaluation overflowed, not the kernel */
            FZ_CHECK(close_to(lhs, rhs, mag,
                              fmax(fz_maxabs(x[0] + 3 * k, 3), fz_maxabs(x[1] + 3 * k, 3)),
                              fz_maxabs(d, 3) + fz_maxabs(c[0], 3) + fz_maxabs(c[1], 3)),
                     "bilinear row %d: %.17g vs %.17g", k, lhs, rhs);
        }
        return;
    }
    st = mcg_trilinear_rows(n, x[0], x[1], x[2], offsets ? w[0] : NULL,
                            offsets ? w[1] : NULL, offsets ? w[2] : NULL, rows);
    FZ_CHECK(fz_status_known(st), "trilinear status %d", st);
    for (i = 0; i < 3; ++i)
        if (!fz_all_finite(x[i], 3 * (size_t)n))
            FZ_CHECK(st == MCG_EINVAL, "trilinear_rows of non-finite bearings: %d", st);
    if (st != MCG_OK)
        return;
    FZ_CHECK(fz_all_finite(rows, 63 * (size_t)n), "trilinear: non-finite row");
    for (i = 0; i < 3; ++i) {
        c[0][i] = fz_range(in, -4.0, 4.0); /* a */
        c[1][i] = fz_range(in, -4.0, 4.0); /* b */
    }
    for (k = 0; k < n; ++k) {
        const double *x1 = x[0] + 3 * k, *x2 = x[1] + 3 * k, *x3 = x[2] + 3 * k;
        double u[3], v[3], A[3], B[3], xb[3], xa[3];
        for (i = 0; i < 3; ++i) {
            A[i] = c[0][i] + (offsets ? w[1][3 * k + i] - w[0][3 * k + i] : 0.0);
            B[i] = c[1][i] + (offsets ? w[2][3 * k + i] - w[0][3 * k + i] : 0.0);
        }
        /* a bound on every product either side forms */
        const double scale =
            16.0 * fz_maxabs(x1, 3) * fz_maxabs(x2, 3) * fz_maxabs(x3, 3) *
            (fz_maxabs(c[0], 3) + fz_maxabs(c[1], 3) + fz_maxabs(A, 3) + fz_maxabs(B, 3) +
             (offsets ? fz_maxabs(w[0] + 3 * k, 3) : 0.0));
        const double mx = fmax(fz_maxabs(x1, 3), fmax(fz_maxabs(x2, 3), fz_maxabs(x3, 3)));
        const double mc = fz_maxabs(A, 3) + fz_maxabs(B, 3) + fz_maxabs(c[0], 3) +
                          fz_maxabs(c[1], 3);
        fz_cross3(x1, x2, u);
        fz_cross3(x1, x3, v);
        fz_cross3(x3, B, xb);
        fz_cross3(x2, A, xa);
        for (s = 0; s < 3; ++s)
            for (t = 0; t < 3; ++t) {
                const double *r = rows + 7 * (9 * k + 3 * s + t);
                double lhs = r[6], mag = fabs(r[6]);
                double rhs = u[s] * xb[t] - xa[s] * v[t];
                for (i = 0; i < 3; ++i) {
                    lhs += r[i] * c[0][i] + r[3 + i] * c[1][i];
                    mag += fabs(r[i] * c[0][i]) + fabs(r[3 + i] * c[1][i]);
                }
                if (!isfinite(rhs) || !isfinite(mag) || !isfinite(scale))
                    continue;
                FZ_CHECK(close_to(lhs, rhs, mag + scale, mx, mc),
                         "trilinear row %d (%d, %d): %.17g vs %.17g (scale %g)", k, s, t, lhs, rhs,
                         scale);
            }
    }
}

static void fuzz_grams(fz_in *in)
{
    int valid, st, k, i, j;
    const int q = (fz_u8(in) & 1) ? 3 : 2, dim = 3 * q + 1;
    const int use_w = fz_u8(in) & 1;
    int n = fz_size(in, 0, MAXN, &valid);
    int n_blocks = fz_int(in, -1, 6);
    int block[MAXN];
    double x[3 * 3 * MAXN], w[3 * 3 * MAXN], grams[7 * 10 * 10];
    if (!valid) {
        double dummy[64] = {0};
        int b0[4] = {0, 0, 0, 0};
        if (n != 0) /* n = 0 is a valid empty call */
            FZ_CHECK(mcg_relation_grams(q, n, dummy, NULL, b0, 1, dummy) == MCG_EINVAL,
                     "relation_grams(n = %d) accepted", n);
        return;
    }
    fz_matrix(in, x, (size_t)n * q, 3);
    fz_matrix(in, w, (size_t)n * q, 3);
    for (k = 0; k < n; ++k)
        block[k] = fz_int(in, -1, 6); /* sometimes out of range */
    st = mcg_relation_grams(q, n, x, use_w ? w : NULL, block, n_blocks, grams);
    FZ_CHECK(fz_status_known(st), "relation_grams status %d", st);
    if (n_blocks < 1)
        FZ_CHECK(st == MCG_EINVAL, "relation_grams(n_blocks = %d) accepted", n_blocks);
    for (k = 0; k < n; ++k)
        if (block[k] < 0 || block[k] >= n_blocks)
            FZ_CHECK(st == MCG_EINVAL, "relation_grams: block %d of %d accepted", block[k],
                     n_blocks);
    if (st != MCG_OK)
        return;
    FZ_CHECK(fz_all_finite(grams, (size_t)n_blocks * dim * dim), "grams: non-finite");
    for (k = 0; k < n_blocks; ++k) {
        const double *g = grams + (size_t)k * dim * dim;
        for (i = 0; i < dim; ++i) {
            FZ_CHECK(g[i * dim + i] >= 0.0, "gram %d diagonal %d = %g", k, i, g[i * dim + i]);
            for (j = 0; j < i; ++j)
                FZ_CHECK(g[i * dim + j] == g[j * dim + i], "gram %d not symmetric", k);
        }
    }
}

/* A valid skyline profile of size n decoded from the input. */
static void decode_profile(fz_in *in, int n, int *first, int *ptr)
{
    int r;
    ptr[0] = 0;
    for (r = 0; r < n; ++r) {
        int band = fz_int(in, 0, 6);
        first[r] = r - band < 0 ? 0 : r - band;
        ptr[r + 1] = ptr[r] + (r - first[r]) + 1;
    }
}

static void fuzz_skyline(fz_in *in)
{
    int valid, st, r, c, j, k, iters = 0;
    const int raw = (fz_u8(in) % 4) == 0, corrupt = (fz_u8(in) % 8) == 0;
    int n = fz_size(in, 1, MAXSKY, &valid);
    int first[MAXSKY], ptr[MAXSKY + 1];
    double a[MAXSKY * 7], bm[MAXSKY * 7], fac[MAXSKY * 7], rhs[MAXSKY], x[MAXSKY];
    double vals[8], vecs[8 * MAXSKY], resid[8], shift;
    double *work;
    size_t lwork;
    int p, env;
    if (!valid) {
        int f0[2] = {0, 0}, p0[3] = {0, 1, 3};
        double dummy[8] = {1, 0, 1, 0, 0, 0, 0, 0};
        FZ_CHECK(mcg_skyline_cholesky(n, f0, p0, dummy) == MCG_EINVAL,
                 "skyline_cholesky(n = %d) accepted", n);
        FZ_CHECK(mcg_skyline_eig_work_size(n, 1, 3) == 0 || n > 0,
                 "skyline_eig_work_size(n = %d) nonzero", n);
        return;
    }
    decode_profile(in, n, first, ptr);
    env = ptr[n];
    /* symmetric matrices in the profile: raw values, or strictly diagonally
     * dominant (hence positive definite) ones that every call must handle */
    for (r = 0; r < n; ++r) {
        for (c = first[r]; c < r; ++c) {
            double v = raw ? fz_double(in) : fz_range(in, -1.0, 1.0);
            a[ptr[r] + c - first[r]] = v;
            bm[ptr[r] + c - first[r]] = raw ? v : 0.1 * fz_range(in, -1.0, 1.0);
        }
    }
    for (r = 0; r < n; ++r) { /* diagonal: dominant over the full symmetric row */
        double sa = 0.0, sb = 0.0;
        for (c = 0; c < n; ++c) {
            const int lo = c < r ? c : r, hi = c < r ? r : c;
            if (c == r || lo < first[hi])
                continue;
            sa += fabs(a[ptr[hi] + lo - first[hi]]);
            sb += fabs(bm[ptr[hi] + lo - first[hi]]);
        }
        a[ptr[r] + r - first[r]] = raw ? fz_double(in) : sa + fz_range(in, 0.01, 4.0);
        bm[ptr[r] + r - first[r]] = raw ? fabs(fz_double(in)) : sb + fz_range(in, 0.5, 2.0);
    }
    if (corrupt) { /* a profile that breaks the rules */
        int r0 = fz_int(in, 0, n - 1);
        ptr[r0 + 1] += fz_int(in, 1, 3);
        FZ_CHECK(mcg_skyline_cholesky(n, first, ptr, a) == MCG_EINVAL,
                 "skyline_cholesky accepted a broken profile");
        return;
    }
    memcpy(fac, a, sizeof(double) * (size_t)env);
    st = mcg_skyline_cholesky(n, first, ptr, fac);
    FZ_CHECK(fz_status_known(st), "skyline_cholesky status %d", st);
    if (!raw)
        FZ_CHECK(st == MCG_OK, "skyline_cholesky of a dominant matrix: %d", st);
    if (st == MCG_OK) {
        FZ_CHECK(fz_all_finite(fac, (size_t)env), "skyline_cholesky: non-finite factor");
        for (r = 0; r < n; ++r)
            rhs[r] = x[r] = fz_range(in, -2.0, 2.0);
        st = mcg_skyline_solve(n, first, ptr, fac, x);
        FZ_CHECK(st == MCG_OK || st == MCG_ENUMERIC, "skyline_solve status %d", st);
        if (!raw) {
            FZ_CHECK(st == MCG_OK, "skyline_solve of a dominant matrix: %d", st);
            for (r = 0; r < n; ++r) { /* (A x)_r against b_r */
                double s = 0.0, mag = 0.0;
                for (c = 0; c < n; ++c) {
                    const int lo = c < r ? c : r, hi = c < r ? r : c;
                    double v;
                    if (lo < first[hi])
                        continue;
                    v = a[ptr[hi] + lo - first[hi]] * x[c];
                    s += v;
                    mag += fabs(v);
                }
                FZ_CHECK(fabs(s - rhs[r]) <= 1e-10 * (mag + fabs(rhs[r]) + 1.0),
                         "skyline_solve: residual %g at row %d", s - rhs[r], r);
            }
        }
    }
    p = fz_int(in, 1, 3);
    if (p > n)
        p = n;
    shift = raw ? fz_double(in) : 0.0;
    lwork = mcg_skyline_eig_work_size(n, p, env);
    FZ_CHECK(lwork > 0, "skyline_eig_work_size(%d, %d, %d) = 0", n, p, env);
    work = fz_alloc(lwork);
    if (work == NULL)
        return;
    st = mcg_skyline_eig(n, first, ptr, a, bm, shift, p, 200, 1e-10, vals, vecs, resid, &iters,
                         work, lwork);
    FZ_CHECK(fz_status_known(st), "skyline_eig status %d", st);
    if (!isfinite(shift) || shift < 0.0)
        FZ_CHECK(st == MCG_EINVAL, "skyline_eig accepted shift %g", shift);
    if (st == MCG_OK) {
        FZ_CHECK(fz_all_finite(vals, (size_t)p) && fz_all_finite(vecs, (size_t)p * n),
                 "skyline_eig: non-finite output");
        FZ_CHECK(iters >= 1 && iters <= 200, "skyline_eig: %d iterations", iters);
        for (j = 1; j < p; ++j)
            FZ_CHECK(vals[j] >= vals[j - 1] - 1e-12 * (fabs(vals[j]) + 1.0),
                     "skyline_eig: values not ascending");
        if (!raw) {
            /* positive definite pencil: positive values; rows B-orthonormal */
            for (j = 0; j < p; ++j) {
                FZ_CHECK(vals[j] > 0.0, "skyline_eig: value %g of a definite pencil", vals[j]);
                for (k = 0; k <= j; ++k) {
                    double s = 0.0;
                    for (r = 0; r < n; ++r)
                        for (c = first[r]; c <= r; ++c) {
                            const double bv = bm[ptr[r] + c - first[r]];
                            s += bv * vecs[j * n + r] * vecs[k * n + c];
                            if (c != r)
                                s += bv * vecs[j * n + c] * vecs[k * n + r];
                        }
                    FZ_CHECK(fabs(s - (j == k ? 1.0 : 0.0)) <= 1e-8,
                             "skyline_eig: B-inner product (%d, %d) = %g", j, k, s);
                }
            }
        }
    }
    /* too small a workspace */
    st = mcg_skyline_eig(n, first, ptr, a, bm, 0.0, p, 10, 1e-10, vals, vecs, resid, &iters, work,
                         lwork - 1);
    FZ_CHECK(st == MCG_ENOMEM, "skyline_eig with lwork - 1: %d", st);
    free(work);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in = fz_make(data, size);
    switch (fz_u8(&in) % FUZZ_MODES) {
    case 0:
        fuzz_rows(&in);
        break;
    case 1:
        fuzz_grams(&in);
        break;
    default:
        fuzz_skyline(&in);
        break;
    }
    return 0;
}
