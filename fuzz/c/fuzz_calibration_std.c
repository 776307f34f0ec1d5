/*
 * fuzz_calibration_std.c -- libFuzzer harness of mcg_calibration_scale_std,
 * the rig calibration error's share of the std of |t| (csrc/calibration_std.c).
 *
 * Inputs: mode 0 a synthetic rig scene (fz_scene, cross-camera pairs or
 * not, a few entries possibly damaged) at its motion or one near it, with
 * per-camera stds (some zero), weights or none, and a loss; mode 1
 * arbitrary arrays, ids (some out of range), stds, weights, motion, loss,
 * loss scale and workspace size. Invariants: bad arguments (sizes, ids,
 * NaN/inf, negative stds or weights, the loss, a loss scale not > 0, a
 * short workspace) give MCG_EINVAL / MCG_ENOMEM; valid ones of moderate
 * magnitude give MCG_OK or MCG_ENUMERIC (or MCG_EINVAL for a zero
 * direction); on MCG_OK rel_std >= 0 (HUGE_VAL: singular), cov is
 * symmetric with a non-negative diagonal, all stds zero give 0, and the
 * result is linear in the stds (twice the stds: twice rel_std, four times
 * cov -- the first-order propagation).
 */
#include "fuzz_input.h"
#include "mcgeom.h"

#define FUZZ_MODES 2

#define MAXN 48
#define MAXC 8

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in = fz_make(data, size);
    int mode = fz_u8(&in) % FUZZ_MODES, valid, st, st2, i, ncam, loss, args_ok = 1, any = 0;
    int n = fz_size(&in, 1, MAXN, &valid);
    static double o1[3 * MAXN], d1[3 * MAXN], o2[3 * MAXN], d2[3 * MAXN], w[MAXN];
    static double work[36 * MAXC], sig[2 * MAXC], sig2[2 * MAXC];
    static int c1[MAXN], c2[MAXN];
    double R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, t[3] = {0, 0, 0}, cov[36], cov2[36];
    double rel = -1.0, rel2 = -1.0, ls, *wp;
    size_t lw;
    if (!valid) {
        st = mcg_calibration_scale_std(n, o1, d1, o2, d2, c1, c2, 1, sig, R, t, NULL,
                                       MCG_LOSS_NONE, 1e-3, &rel, cov, work, 36);
        FZ_CHECK(st == MCG_EINVAL, "calibration_scale_std(n = %d) returned %d", n, st);
        return 0;
    }
    ncam = fz_int(&in, 1, MAXC);
    if (mode == 0) {
        const int cross = fz_u8(&in) & 1;
        fz_rotation(&in, R);
        for (i = 0; i < 3; ++i)
            t[i] = fz_range(&in, -2.0, 2.0);
        fz_scene(&in, n, ncam, cross, R, t, o1, d1, o2, d2, c1);
        for (i = 0; i < n; ++i)
            c2[i] = (cross && i % 4 == 3) ? (c1[i] + 1) % ncam : c1[i];
        if (fz_u8(&in) & 1) /* the estimate a little off the scene's motion */
            for (i = 0; i < 3; ++i)
                t[i] += fz_range(&in, -0.1, 0.1);
        for (i = 0; i < 2 * ncam; ++i)
            sig[i] = (fz_u8(&in) & 3) ? fz_range(&in, 0.0, 1e-2) : 0.0;
    } else {
        fz_rays(&in, (size_t)n, o1, d1, o2, d2);
        for (i = 0; i < n; ++i) {
            c1[i] = fz_int(&in, -1, ncam);
            c2[i] = (fz_u8(&in) & 3) ? c1[i] : fz_int(&in, -1, ncam);
        }
        fz_rotation_or_any(&in, R);
        fz_doubles(&in, t, 3);
        for (i = 0; i < 2 * ncam; ++i)
            sig[i] = (fz_u8(&in) & 1) ? fz_range(&in, 0.0, 1e-2) : fz_double(&in);
    }
    wp = (fz_u8(&in) & 1) ? w : NULL;
    for (i = 0; i < n && wp; ++i)
        w[i] = (fz_u8(&in) % 16 == 0) ? fz_double(&in) : fz_range(&in, 0.0, 2.0);
    loss = fz_int(&in, -1, 4);
    ls = (fz_u8(&in) % 8 == 0) ? fz_double(&in) : fz_range(&in, 1e-4, 1e-2);
    lw = (fz_u8(&in) % 16 == 0) ? (size_t)fz_int(&in, 0, 36 * MAXC) : 36 * MAXC;
    st = mcg_calibration_scale_std(n, o1, d1, o2, d2, c1, c2, ncam, sig, R, t, wp, loss, ls,
                                   &rel, cov, work, lw);
    FZ_CHECK(fz_status_known(st), "calibration_scale_std status %d", st);
    for (i = 0; i < n; ++i) {
        args_ok &= c1[i] >= 0 && c1[i] < ncam && c2[i] >= 0 && c2[i] < ncam;
        if (wp)
            args_ok &= isfinite(w[i]) && w[i] >= 0.0;
    }
    for (i = 0; i < 2 * ncam; ++i) {
        args_ok &= isfinite(sig[i]) && sig[i] >= 0.0;
        any |= sig[i] > 0.0;
    }
    args_ok &= fz_all_finite(o1, 3 * (size_t)n) && fz_all_finite(d1, 3 * (size_t)n) &&
               fz_all_finite(o2, 3 * (size_t)n) && fz_all_finite(d2, 3 * (size_t)n) &&
               fz_all_finite(R, 9) && fz_all_finite(t, 3) && loss >= MCG_LOSS_NONE &&
               loss <= MCG_LOSS_SOFT_L1 && (loss == MCG_LOSS_NONE || (isfinite(ls) && ls > 0.0));
    if (!args_ok) {
        FZ_CHECK(st == MCG_EINVAL, "calibration_scale_std with bad arguments: %d", st);
        return 0;
    }
    if (lw < mcg_calibration_std_work_size(ncam)) {
        FZ_CHECK(st == MCG_ENOMEM || st == MCG_EINVAL, "short workspace: %d", st);
        return 0;
    }
    if (fz_maxabs(o1, 3 * (size_t)n) <= 1e6 && fz_maxabs(o2, 3 * (size_t)n) <= 1e6 &&
        fz_maxabs(d1, 3 * (size_t)n) <= 1e6 && fz_maxabs(d2, 3 * (size_t)n) <= 1e6 &&
        fz_maxabs(t, 3) <= 1e6 && fz_maxabs(R, 9) <= 1e3)
        FZ_CHECK(st == MCG_OK || st == MCG_ENUMERIC || st == MCG_EINVAL,
                 "calibration_scale_std of valid moderate arguments: %d", st);
    if (st != MCG_OK)
        return 0;
    FZ_CHECK(rel >= 0.0, "rel_std %g", rel);
    if (rel == HUGE_VAL)
        return 0;
    for (i = 0; i < 6; ++i) {
        int j;
        FZ_CHECK(cov[7 * i] >= 0.0, "cov diagonal %g", cov[7 * i]);
        for (j = 0; j < 6; ++j)
            FZ_CHECK(fabs(cov[6 * i + j] - cov[6 * j + i]) <=
                         1e-12 * (fabs(cov[6 * i + j]) + fabs(cov[6 * j + i])) + 1e-300,
                     "cov not symmetric: %g vs %g", cov[6 * i + j], cov[6 * j + i]);
    }
    if (!any)
        FZ_CHECK(rel == 0.0, "all stds zero, rel_std %g", rel);
    /* first order: linear in the stds */
    for (i = 0; i < 2 * ncam; ++i)
        sig2[i] = 2.0 * sig[i];
    st2 = mcg_calibration_scale_std(n, o1, d1, o2, d2, c1, c2, ncam, sig2, R, t, wp, loss, ls,
                                    &rel2, cov2, work, lw);
    FZ_CHECK(st2 == MCG_OK || st2 == MCG_ENUMERIC, "twice the stds: status %d", st2);
    if (st2 == MCG_OK && isfinite(rel2) && rel > 1e-150 && rel < 1e150)
        FZ_CHECK(fabs(rel2 - 2.0 * rel) <= 1e-9 * rel2, "twice the stds: %g vs 2 x %g", rel2,
                 rel);
    return 0;
}
