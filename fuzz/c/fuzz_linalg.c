/*
 * fuzz_linalg.c -- libFuzzer harness of the dense algebra of linalg.c:
 * mcg_qr, mcg_svd, mcg_pinv, mcg_sym_eig, mcg_sym_eig_tridiag,
 * mcg_spd_solve, the rotation helpers and mcg_project_so3 (rotations.c; and
 * mcg_status_message). The first byte picks the routine.
 *
 * Invariants (on MCG_OK): finite outputs; QR: Q orthonormal columns, R upper
 * triangular, QR = A; SVD: s descending >= 0, V orthogonal, U orthonormal
 * columns where s > 0, U diag(s) V^T = A; pinv: A A+ A = A; eig: ascending
 * w, V orthogonal, A V = V diag(w); spd: the residual is backward stable;
 * rotations: orthonormal with det +1, round trips agree. Sizes outside the
 * documented range must give MCG_EINVAL, work sizes below the required one
 * MCG_ENOMEM.
 */
#include "fuzz_input.h"
#include "mcgeom.h"

/* routines selected by the first input byte (fuzz/make_corpus.py writes
 * seeds for each) */
#define FUZZ_MODES 8

#define MAXD 12 /* matrices up to 12 x 12: every code path, fast */

/* |A - B|_max over n entries relative to scale, for finite inputs */
static double rel_diff(const double *a, const double *b, size_t n, double scale)
{
    double e = 0.0;
    size_t i;
    for (i = 0; i < n; ++i) {
        double d = fabs(a[i] - b[i]);
        if (!(d <= e))
            e = d;
    }
    return scale > 0.0 ? e / scale : e;
}

/* Outputs of a matrix whose entries are near the denormal range are
 * themselves denormal, with an absolute precision of the smallest denormal:
 * relative to the scale sc of the input, that is a floor on every error. */
static double denormal_floor(double sc)
{
    return 64.0 * 4.9406564584124654e-324 / sc;
}

/* Scaled copy so that the products of the checks cannot overflow: every
 * invariant below is homogeneous in A. */
static double scaled_copy(const double *a, double *as, size_t n)
{
    double s = fz_maxabs(a, n);
    size_t i;
    if (!(s > 0.0) || !isfinite(s))
        s = 1.0;
    for (i = 0; i < n; ++i)
        as[i] = a[i] / s;
    return s;
}

static void check_orthonormal_columns(const double *q, int m, int k, double tol,
                                      const char *what)
{
    int i, j, r;
    for (i = 0; i < k; ++i)
        for (j = 0; j < k; ++j) {
            double s = 0.0;
            for (r = 0; r < m; ++r)
                s += q[r * k + i] * q[r * k + j];
            FZ_CHECK(fabs(s - (i == j ? 1.0 : 0.0)) <= tol, "%s: column %d . %d = %.17g (m %d, k %d)", what, i,
                     j, s, m, k);
        }
}

static void fuzz_qr(fz_in *in)
{
    int vm, vn;
    int m = fz_size(in, 1, MAXD, &vm), n = fz_size(in, 1, MAXD, &vn);
    int valid = vm && vn && m >= n;
    size_t ws = mcg_qr_work_size(m, n), lw;
    double a[MAXD * MAXD], q[MAXD * MAXD], r[MAXD * MAXD], as[MAXD * MAXD], *work;
    int st, i, j, k;
    int short_work = (fz_u8(in) % 16) == 0;
    FZ_CHECK(valid ? ws > 0 : ws == 0, "qr_work_size(%d, %d) = %zu", m, n, ws);
    if (!valid) {
        double dummy[4] = {0, 0, 0, 0};
        st = mcg_qr(m, n, dummy, dummy, dummy, dummy, 4);
        FZ_CHECK(st == MCG_EINVAL, "qr(%d, %d) returned %d", m, n, st);
        return;
    }
    fz_matrix(in, a, (size_t)m, (size_t)n);
    lw = short_work ? ws - 1 : ws;
    work = fz_alloc(lw);
    st = mcg_qr(m, n, a, q, r, work, lw);
    free(work);
    FZ_CHECK(fz_status_known(st), "qr status %d", st);
    if (short_work) {
        FZ_CHECK(st == MCG_ENOMEM || st == MCG_EINVAL, "qr with short work: %d", st);
        return;
    }
    if (!fz_all_finite(a, (size_t)(m * n))) {
        FZ_CHECK(st == MCG_EINVAL, "qr of non-finite input: %d", st);
        return;
    }
    if (st != MCG_OK)
        return;
    FZ_CHECK(fz_all_finite(q, (size_t)(m * n)) && fz_all_finite(r, (size_t)(n * n)),
             "qr: non-finite output");
    check_orthonormal_columns(q, m, n, 1e-10, "qr Q");
    for (i = 0; i < n; ++i)
        for (j = 0; j < i; ++j)
            FZ_CHECK(r[i * n + j] == 0.0, "qr R not upper triangular at %d,%d", i, j);
    {
        double s = scaled_copy(a, as, (size_t)(m * n)), qr[MAXD * MAXD];
        for (i = 0; i < m; ++i)
            for (j = 0; j < n; ++j) {
                double v = 0.0;
                for (k = 0; k < n; ++k)
                    v += q[i * n + k] * (r[k * n + j] / s);
                qr[i * n + j] = v;
            }
        FZ_CHECK(rel_diff(qr, as, (size_t)(m * n), 1.0) <= 1e-11 + denormal_floor(s), "qr: |QR - A| / |A| = %g",
                 rel_diff(qr, as, (size_t)(m * n), 1.0));
    }
}

static void fuzz_svd(fz_in *in)
{
    int vm, vn;
    int m = fz_size(in, 1, MAXD, &vm), n = fz_size(in, 1, MAXD, &vn);
    int valid = vm && vn, want_u = fz_u8(in) & 1;
    size_t ws = mcg_svd_work_size(m, n);
    double a[MAXD * MAXD], u[MAXD * MAXD], s[MAXD], v[MAXD * MAXD], as[MAXD * MAXD], *work;
    int st, i, j, k, p;
    FZ_CHECK(valid ? ws > 0 : ws == 0, "svd_work_size(%d, %d) = %zu", m, n, ws);
    if (!valid) {
        double dummy[4] = {0, 0, 0, 0};
        st = mcg_svd(m, n, dummy, dummy, dummy, dummy, dummy, 4);
        FZ_CHECK(st == MCG_EINVAL, "svd(%d, %d) returned %d", m, n, st);
        return;
    }
    p = m < n ? m : n;
    fz_matrix(in, a, (size_t)m, (size_t)n);
    work = fz_alloc(ws);
    st = mcg_svd(m, n, a, want_u ? u : NULL, s, v, work, ws);
    free(work);
    FZ_CHECK(fz_status_known(st), "svd status %d", st);
    if (!fz_all_finite(a, (size_t)(m * n))) {
        FZ_CHECK(st == MCG_EINVAL, "svd of non-finite input: %d", st);
        return;
    }
    if (st != MCG_OK)
        return;
    FZ_CHECK(fz_all_finite(s, (size_t)n) && fz_all_finite(v, (size_t)(n * n)),
             "svd: non-finite s or v");
    for (i = 0; i < n; ++i) {
        FZ_CHECK(s[i] >= 0.0, "svd: s[%d] = %g < 0", i, s[i]);
        if (i > 0)
            FZ_CHECK(s[i] <= s[i - 1], "svd: s not descending at %d", i);
        if (i >= m)
            FZ_CHECK(s[i] == 0.0, "svd: s[%d] = %g for m = %d < n", i, s[i], m);
    }
    check_orthonormal_columns(v, n, n, 1e-10, "svd V");
    {
        double sc = scaled_copy(a, as, (size_t)(m * n));
        /* A V = U S, checked as |A v_k - s_k u_k| and, without U, as
         * |A|_F^2 = sum s_k^2 (with the scaled A) */
        if (want_u) {
            FZ_CHECK(fz_all_finite(u, (size_t)(m * p)), "svd: non-finite u");
            check_orthonormal_columns(u, m, p, 1e-10, "svd U");
            for (i = 0; i < m; ++i)
                for (j = 0; j < n; ++j) {
                    double x = 0.0;
                    for (k = 0; k < p; ++k)
                        x += u[i * p + k] * (s[k] / sc) * v[j * n + k];
                    FZ_CHECK(fabs(x - as[i * n + j]) <= 1e-11 * (double)(m + n) + denormal_floor(sc),
                             "svd: |U S V^T - A| = %g at %d,%d", fabs(x - as[i * n + j]), i, j);
                }
        } else {
            double f2 = 0.0, s2 = 0.0;
            for (i = 0; i < m * n; ++i)
                f2 += as[i] * as[i];
            for (k = 0; k < p; ++k)
                s2 += (s[k] / sc) * (s[k] / sc);
            FZ_CHECK(fabs(f2 - s2) <= 1e-11 * (double)(m + n) * (f2 + 1e-300) +
                         (double)n * denormal_floor(sc),
                     "svd: |A|_F^2 %g != sum s^2 %g", f2, s2);
        }
    }
}

static void fuzz_pinv(fz_in *in)
{
    int vm, vn, rank = -1;
    int m = fz_size(in, 1, MAXD, &vm), n = fz_size(in, 1, MAXD, &vn);
    int valid = vm && vn;
    double rcond = (fz_u8(in) & 1) ? fz_double(in) : 0.0;
    size_t ws = mcg_pinv_work_size(m, n);
    double a[MAXD * MAXD], ai[MAXD * MAXD], as[MAXD * MAXD], *work;
    int st, i, j, k, l;
    FZ_CHECK(valid ? ws > 0 : ws == 0, "pinv_work_size(%d, %d) = %zu", m, n, ws);
    if (!valid) {
        double dummy[4] = {0, 0, 0, 0};
        st = mcg_pinv(m, n, dummy, 0.0, dummy, &rank, dummy, 4);
        FZ_CHECK(st == MCG_EINVAL, "pinv(%d, %d) returned %d", m, n, st);
        return;
    }
    fz_matrix(in, a, (size_t)m, (size_t)n);
    work = fz_alloc(ws);
    st = mcg_pinv(m, n, a, rcond, ai, &rank, work, ws);
    free(work);
    FZ_CHECK(fz_status_known(st), "pinv status %d", st);
    if (!fz_all_finite(a, (size_t)(m * n))) {
        FZ_CHECK(st == MCG_EINVAL, "pinv of non-finite input: %d", st);
        return;
    }
    if (st != MCG_OK)
        return;
    FZ_CHECK(rank >= 0 && rank <= (m < n ? m : n), "pinv rank %d", rank);
    FZ_CHECK(fz_all_finite(ai, (size_t)(m * n)), "pinv: non-finite output");
    /* With the default rcond (and rcond <= 1), A A+ A = A up to the dropped
     * singular values (< rcond s_max): |A A+ A - A| <= (rcond + eps) s_max. */
    if (!(rcond <= 1.0) && rcond == rcond)
        return;
    {
        double sc = scaled_copy(a, as, (size_t)(m * n)), t[MAXD * MAXD], tol;
        double r_eff = rcond > 0.0 ? rcond : (double)(m > n ? m : n) * DBL_EPSILON;
        /* plus the rounding of the products, which grows with |A+| (the
         * condition number: A A+ A is not a backward-stable quantity; the
         * long run found ill-conditioned inputs at 1e-6 without it) */
        tol = (double)(m + n) * (r_eff + 1e-12) * 4.0 * (double)(m > n ? m : n) +
              (double)(m * n) * denormal_floor(sc) +
              64.0 * DBL_EPSILON * (double)((m + n) * (m + n)) * fz_maxabs(ai, (size_t)(m * n)) * sc;
        /* t = A+ A (n x n), then A t */
        for (i = 0; i < n; ++i)
            for (j = 0; j < n; ++j) {
                double x = 0.0;
                for (k = 0; k < m; ++k)
                    x += (ai[i * m + k] * sc) * as[k * n + j];
                t[i * n + j] = x;
            }
        for (i = 0; i < m; ++i)
            for (j = 0; j < n; ++j) {
                double x = 0.0;
                for (l = 0; l < n; ++l)
                    x += as[i * n + l] * t[l * n + j];
                FZ_CHECK(fabs(x - as[i * n + j]) <= tol, "pinv: |A A+ A - A| = %g (tol %g)",
                         fabs(x - as[i * n + j]), tol);
            }
    }
}

static void fuzz_eig(fz_in *in, int tridiag)
{
    int vn, alias = (fz_u8(in) % 32) == 0;
    int n = fz_size(in, 1, MAXD, &vn);
    double a[MAXD * MAXD], a0[MAXD * MAXD], w[MAXD], v[MAXD * MAXD];
    int st, i, j, k;
    if (!vn) {
        double dummy[4] = {0, 0, 0, 0}, dw[2], dv[4];
        st = tridiag ? mcg_sym_eig_tridiag(n, dummy, dw, dv) : mcg_sym_eig(n, dummy, dw, dv);
        FZ_CHECK(st == MCG_EINVAL, "sym_eig(%d) returned %d", n, st);
        return;
    }
    fz_matrix(in, a, (size_t)n, (size_t)n);
    memcpy(a0, a, sizeof(double) * (size_t)(n * n));
    if (alias) {
        st = tridiag ? mcg_sym_eig_tridiag(n, a, w, a) : mcg_sym_eig(n, a, w, a);
        FZ_CHECK(st == MCG_EINVAL, "sym_eig with v == a returned %d", st);
        return;
    }
    st = tridiag ? mcg_sym_eig_tridiag(n, a, w, v) : mcg_sym_eig(n, a, w, v);
    FZ_CHECK(fz_status_known(st), "sym_eig status %d", st);
    if (!fz_all_finite(a0, (size_t)(n * n))) {
        FZ_CHECK(st == MCG_EINVAL, "sym_eig of non-finite input: %d", st);
        return;
    }
    if (st != MCG_OK)
        return;
    FZ_CHECK(fz_all_finite(w, (size_t)n) && fz_all_finite(v, (size_t)(n * n)),
             "sym_eig: non-finite output");
    for (i = 1; i < n; ++i)
        FZ_CHECK(w[i] >= w[i - 1], "sym_eig: w not ascending at %d", i);
    check_orthonormal_columns(v, n, n, 1e-10, "sym_eig V");
    {
        /* symmetric part, scaled; |S v_k - w_k v_k| <= tol |S| */
        double as[MAXD * MAXD], sc = scaled_copy(a0, as, (size_t)(n * n));
        for (i = 0; i < n; ++i)
            for (j = 0; j < i; ++j)
                as[i * n + j] = as[j * n + i] = 0.5 * (as[i * n + j] + as[j * n + i]);
        for (k = 0; k < n; ++k)
            for (i = 0; i < n; ++i) {
                double x = 0.0;
                for (j = 0; j < n; ++j)
                    x += as[i * n + j] * v[j * n + k];
                x -= (w[k] / sc) * v[i * n + k];
                FZ_CHECK(fabs(x) <= 1e-11 * (double)n + denormal_floor(sc), "sym_eig: |A v - w v| = %g (k %d)",
                         fabs(x), k);
            }
    }
}

static void fuzz_spd(fz_in *in)
{
    int vn, st, i, j;
    int n = fz_size(in, 1, 64, &vn);
    double *a, b[64], x[64], L[64 * 64];
    if (!vn) {
        double dummy[4] = {1, 0, 0, 1};
        st = mcg_spd_solve(n, dummy, dummy, dummy);
        FZ_CHECK(st == MCG_EINVAL, "spd_solve(%d) returned %d", n, st);
        return;
    }
    if (n > 16)
        n = 1 + n % 16;
    a = fz_alloc((size_t)(n * n));
    /* half the time a = L L^T + shift (SPD by construction) */
    if (fz_u8(in) & 1) {
        int k;
        double shift = fz_double(in);
        fz_matrix(in, L, (size_t)n, (size_t)n);
        for (i = 0; i < n; ++i)
            for (j = 0; j < n; ++j) {
                double s = 0.0;
                for (k = 0; k < n; ++k)
                    s += L[i * n + k] * L[j * n + k];
                a[i * n + j] = s + (i == j ? fabs(shift) : 0.0);
            }
    } else {
        fz_matrix(in, a, (size_t)n, (size_t)n);
    }
    fz_doubles(in, b, (size_t)n);
    st = mcg_spd_solve(n, a, b, x);
    FZ_CHECK(fz_status_known(st), "spd_solve status %d", st);
    if (!fz_all_finite(a, (size_t)(n * n)) || !fz_all_finite(b, (size_t)n)) {
        FZ_CHECK(st == MCG_EINVAL, "spd_solve of non-finite input: %d", st);
    } else if (st == MCG_OK) {
        FZ_CHECK(fz_all_finite(x, (size_t)n), "spd_solve: non-finite x");
    }
    free(a);
}

static void fuzz_rotations(fz_in *in)
{
    double w[3], q[4], m[9], r[9], r2[9], w2[3], q2[4];
    int st, i;
    uint8_t what = fz_u8(in) % 4;
    if (what == 0) {
        fz_doubles(in, w, 3);
        st = mcg_rot_from_angle_axis(w, r);
        FZ_CHECK(fz_all_finite(w, 3) || st == MCG_EINVAL, "rot_from_angle_axis(NaN) = %d", st);
        if (st != MCG_OK)
            return;
        FZ_CHECK(fz_is_rotation(r, 1e-12), "rot_from_angle_axis: not a rotation (%g, det %g)",
                 fz_orth_err3(r), fz_det3(r));
        st = mcg_angle_axis_from_rot(r, w2);
        FZ_CHECK(st == MCG_OK, "angle_axis_from_rot of a rotation: %d", st);
        FZ_CHECK(fz_all_finite(w2, 3), "angle_axis_from_rot: non-finite");
        FZ_CHECK(sqrt(w2[0] * w2[0] + w2[1] * w2[1] + w2[2] * w2[2]) <= 3.141592653589793 + 1e-12,
                 "angle_axis_from_rot: angle above pi");
        st = mcg_rot_from_angle_axis(w2, r2);
        FZ_CHECK(st == MCG_OK, "rot_from_angle_axis round trip: %d", st);
        for (i = 0; i < 9; ++i)
            FZ_CHECK(fabs(r[i] - r2[i]) <= 1e-9, "angle-axis round trip differs by %g",
                     fabs(r[i] - r2[i]));
    } else if (what == 1) {
        fz_doubles(in, q, 4);
        st = mcg_rot_from_quat(q, r);
        FZ_CHECK(fz_all_finite(q, 4) || st == MCG_EINVAL, "rot_from_quat(NaN) = %d", st);
        if (st != MCG_OK)
            return;
        FZ_CHECK(fz_is_rotation(r, 1e-12), "rot_from_quat: not a rotation (%g)",
                 fz_orth_err3(r));
        st = mcg_quat_from_rot(r, q2);
        FZ_CHECK(st == MCG_OK, "quat_from_rot of a rotation: %d", st);
        FZ_CHECK(q2[0] >= 0.0, "quat_from_rot: q0 = %g < 0", q2[0]);
        FZ_CHECK(fabs(q2[0] * q2[0] + q2[1] * q2[1] + q2[2] * q2[2] + q2[3] * q2[3] - 1.0) <=
                     1e-12,
                 "quat_from_rot: not unit");
        st = mcg_rot_from_quat(q2, r2);
        FZ_CHECK(st == MCG_OK, "rot_from_quat round trip: %d", st);
        for (i = 0; i < 9; ++i)
            FZ_CHECK(fabs(r[i] - r2[i]) <= 1e-9, "quaternion round trip differs by %g",
                     fabs(r[i] - r2[i]));
    } else {
        /* arbitrary 3 x 3: the checks of angle_axis_from_rot / quat_from_rot
         * and the projection onto SO(3) */
        fz_matrix(in, m, 3, 3);
        if (what == 3) { /* a near-rotation: perturbed rotation */
            double e = fz_double(in);
            fz_rotation(in, r);
            for (i = 0; i < 9; ++i)
                m[i] = r[i] + (i == (int)(fz_u8(in) % 9) ? e : 0.0);
        }
        st = mcg_angle_axis_from_rot(m, w);
        if (st == MCG_OK) {
            FZ_CHECK(fz_orth_err3(m) <= 1e-6 * 1.01 && fz_det3(m) > 0.0,
                     "angle_axis_from_rot accepted a non-rotation (%g)", fz_orth_err3(m));
            FZ_CHECK(fz_all_finite(w, 3), "angle_axis_from_rot: non-finite");
        }
        st = mcg_quat_from_rot(m, q);
        if (st == MCG_OK)
            FZ_CHECK(fz_all_finite(q, 4) && q[0] >= 0.0, "quat_from_rot: bad q");
        st = mcg_project_so3(m, r);
        FZ_CHECK(fz_status_known(st), "project_so3 status %d", st);
        if (!fz_all_finite(m, 9))
            FZ_CHECK(st == MCG_EINVAL, "project_so3 of non-finite input: %d", st);
        if (st == MCG_OK)
            FZ_CHECK(fz_is_rotation(r, 1e-12), "project_so3: not a rotation (%g, det %g)",
                     fz_orth_err3(r), fz_det3(r));
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in = fz_make(data, size);
    switch (fz_u8(&in) % FUZZ_MODES) {
    case 0:
        fuzz_qr(&in);
        break;
    case 1:
        fuzz_svd(&in);
        break;
    case 2:
        fuzz_pinv(&in);
        break;
    case 3:
        fuzz_eig(&in, 0);
        break;
    case 4:
        fuzz_eig(&in, 1);
        break;
    case 5:
        fuzz_spd(&in);
        break;
    case 6:
        fuzz_rotations(&in);
        break;
    default: {
        int st = (int)(int8_t)fz_u8(&in);
        const char *msg = mcg_status_message(st);
        FZ_CHECK(msg != NULL && strlen(msg) > 0, "status_message(%d) empty", st);
        break;
    }
    }
    return 0;
}
