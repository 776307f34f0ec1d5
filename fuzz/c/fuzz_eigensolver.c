/*
 * fuzz_eigensolver.c -- libFuzzer harness of mcg_eigensolver (Kneip and
 * Li's eigensolver) and mcg_eigensolver_work_size.
 *
 * Inputs: mode 0 a synthetic rig scene (1-8 cameras, intra- or cross-camera,
 * fz_scene's noise and replaced entries) with a start rotation near or far
 * from the truth; mode 1 arbitrary rays and start. max_iterations 0..50, the
 * workspace sometimes one double short. Invariants: a bad size, a short
 * workspace, NaN/inf or a start that is no rotation never give MCG_OK; on
 * MCG_OK R is a rotation, t finite, lambda_min finite and >= -1e-9 (an
 * eigenvalue of a positive semi-definite matrix, scaled), iterations within
 * the cap, and with max_iterations = 0 R is the start.
 */
#include "fuzz_input.h"
#include "mcgeom.h"

/* routines selected by the first input byte (fuzz/make_corpus.py writes
 * seeds for each) */
#define FUZZ_MODES 2

#define MAXN 48

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in = fz_make(data, size);
    int mode = fz_u8(&in) % FUZZ_MODES, valid, st, i, has = -1, its = -1, maxit;
    int n = fz_size(&in, 1, MAXN, &valid);
    static double o1[3 * MAXN], d1[3 * MAXN], o2[3 * MAXN], d2[3 * MAXN];
    double Rm[9], t[3], R0[9], R[9], te[3], lam = 0.0, *work;
    size_t lw;
    int short_ws;
    if (!valid) {
        double w1[1];
        FZ_CHECK(mcg_eigensolver_work_size(n) == 0, "eigensolver_work_size(%d) != 0", n);
        st = mcg_eigensolver(n, o1, d1, o2, d2, R0, 1, R, te, &lam, &has, &its, w1, 1);
        FZ_CHECK(st == MCG_EINVAL || st == MCG_ENOMEM, "eigensolver(n = %d) returned %d", n,
                 st);
        return 0;
    }
    if (mode == 0) {
        fz_rotation(&in, Rm);
        for (i = 0; i < 3; ++i)
            t[i] = fz_range(&in, -2.0, 2.0);
        {   /* decoded in this order (not as arguments of one call) */
            const int ncams = fz_int(&in, 1, 8), cross = fz_u8(&in) & 1;
            fz_scene(&in, n, ncams, cross, Rm, t, o1, d1, o2, d2, NULL);
        }
        if (fz_u8(&in) & 1) {
            double P[9];
            fz_rotation(&in, P);
            fz_matmul3(P, Rm, R0);
        } else {
            fz_rotation_or_any(&in, R0);
        }
    } else {
        fz_rays(&in, (size_t)n, o1, d1, o2, d2);
        fz_rotation_or_any(&in, R0);
    }
    maxit = fz_int(&in, 0, 50);
    lw = mcg_eigensolver_work_size(n);
    FZ_CHECK(lw > 0, "eigensolver_work_size(%d) = 0", n);
    short_ws = fz_u8(&in) % 16 == 0;
    work = fz_alloc(lw - (size_t)short_ws);
    st = mcg_eigensolver(n, o1, d1, o2, d2, R0, maxit, R, te, &lam, &has, &its, work,
                         lw - (size_t)short_ws);
    free(work);
    FZ_CHECK(fz_status_known(st), "eigensolver status %d", st);
    if (short_ws) {
        FZ_CHECK(st == MCG_ENOMEM || st == MCG_EINVAL, "eigensolver short workspace: %d", st);
        return 0;
    }
    if (!fz_all_finite(o1, 3 * (size_t)n) || !fz_all_finite(d1, 3 * (size_t)n) ||
        !fz_all_finite(o2, 3 * (size_t)n) || !fz_all_finite(d2, 3 * (size_t)n) ||
        !fz_all_finite(R0, 9)) {
        FZ_CHECK(st == MCG_EINVAL, "eigensolver of non-finite input: %d", st);
        return 0;
    }
    if (!fz_is_rotation(R0, 1e-6)) {
        FZ_CHECK(st != MCG_OK, "eigensolver accepted a start that is no rotation");
        return 0;
    }
    if (st != MCG_OK)
        return 0;
    FZ_CHECK(fz_is_rotation(R, 1e-9), "eigensolver: R not a rotation (%g)", fz_orth_err3(R));
    FZ_CHECK(fz_all_finite(te, 3), "eigensolver: t not finite");
    FZ_CHECK(isfinite(lam) && lam >= -1e-9, "eigensolver: lambda_min = %g", lam);
    FZ_CHECK(its >= 0 && its <= maxit, "eigensolver: %d iterations of %d", its, maxit);
    FZ_CHECK(has == 0 || has == 1, "eigensolver: has_scale = %d", has);
    if (maxit == 0) {
        double e = 0.0;
        for (i = 0; i < 9; ++i)
            e = fmax(e, fabs(R[i] - R0[i]));
        FZ_CHECK(e < 1e-6, "eigensolver: 0 iterations moved R by %g", e);
    }
    return 0;
}
