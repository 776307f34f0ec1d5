/*
 * fuzz_pixel_rays.c -- libFuzzer harness of mcg_pinhole_ray_pairs, the rays
 * of pinhole pixel correspondences and their pixels per radian.
 *
 * Inputs: mode 0 a plausible rig (rotations, focal lengths 100..3000 px,
 * pixels within a few images of the centre, ids in range), mode 1 arbitrary
 * tables, pixels and ids; ppr asked for or not. Invariants: bad n or m,
 * NULL focal with ppr, ids out of range, NaN/inf in a table or pixel give
 * MCG_EINVAL; *bad is -1 or the index of a pixel whose bearing overflows;
 * on MCG_OK every origin is its camera's centre, every bearing is unit,
 * and every pixels-per-radian value is finite and > 0. With ppr, the same
 * input through mcg_robust_rig_motion_pinhole (the robust estimate from
 * pixels, at most 10 samples): where the ray pass fails it fails with the
 * same status (EINVAL below 6 pairs); otherwise its workspace holds the
 * ray pass's rays and pixels per radian bit for bit, and on MCG_OK R is a
 * rotation, the scale verdict is there and the stage times (the rays'
 * included) sum to seconds.
 */
#include "fuzz_input.h"
#include "mcgeom.h"

#define FUZZ_MODES 2

#define MAXN 64
#define MAXM 8

/* mcg_robust_rig_motion_pinhole on the same input (see the file comment);
 * st_rays: the ray pass's status */
static void robust_from_pixels(int n, int m, const double *intr, const double *rot,
                               const double *cen, const double *foc, const long long *ids1,
                               const long long *ids2, const double *px1, const double *px2,
                               const double *o1, const double *d1, const double *o2,
                               const double *d2, const double *ppr, int st_rays, uint64_t seed)
{
    static unsigned char mask[MAXN];
    static double wts[MAXN];
    const size_t lwork = mcg_robust_pinhole_work_size(n, m);
    mcg_robust_options opt;
    mcg_robust_result res;
    double *work;
    int st;
    if (n < 6) {
        FZ_CHECK(lwork == 0, "pinhole work size %zu for n = %d", lwork, n);
        return;
    }
    mcg_robust_default_options(&opt);
    opt.threshold = 1.0;
    opt.max_iterations = 10;
    opt.max_seconds = 0.2;
    opt.seed = seed;
    opt.max_scale_rel_std = 0.1;
    opt.verdict_still_factor = 1.5;
    work = fz_alloc(lwork);
    st = mcg_robust_rig_motion_pinhole(n, m, intr, rot, cen, foc, ids1, ids2, px1, px2, &opt,
                                       &res, mask, wts, work, lwork);
    FZ_CHECK(fz_status_known(st), "robust_rig_motion_pinhole status %d", st);
    if (st_rays != MCG_OK) {
        FZ_CHECK(st == st_rays, "robust_rig_motion_pinhole %d where the ray pass gave %d", st,
                 st_rays);
    } else {
        const size_t b = 3 * (size_t)n * sizeof(double);
        FZ_CHECK(memcmp(work, o1, b) == 0 && memcmp(work + 3 * n, d1, b) == 0 &&
                     memcmp(work + 6 * n, o2, b) == 0 && memcmp(work + 9 * n, d2, b) == 0 &&
                     memcmp(work + 12 * n, ppr, (size_t)n * sizeof(double)) == 0,
                 "robust_rig_motion_pinhole: rays differ from the ray pass (status %d)", st);
        if (st == MCG_OK) {
            FZ_CHECK(fz_is_rotation(res.R, 1e-9), "robust_rig_motion_pinhole: R not a rotation");
            FZ_CHECK(res.have_scale && (res.have_verdict || res.scale.reason ==
                                                                 MCG_SCALE_UNDECIDED),
                     "robust_rig_motion_pinhole: verdict %d, evidence %d", res.have_scale,
                     res.have_verdict);
            FZ_CHECK(res.seconds_rays >= 0.0 && res.seconds_search >= 0.0 &&
                         res.seconds_final >= 0.0 && res.seconds_verdict >= 0.0 &&
                         fabs(res.seconds_rays + res.seconds_search + res.seconds_final +
                              res.seconds_verdict - res.seconds) <= 1e-9,
                     "robust_rig_motion_pinhole: stage times %g + %g + %g + %g against %g",
                     res.seconds_rays, res.seconds_search, res.seconds_final,
                     res.seconds_verdict, res.seconds);
        }
    }
    free(work);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in = fz_make(data, size);
    int mode = fz_u8(&in) % FUZZ_MODES, valid, st, i, k, bad = 12345, want_ppr, ok_tables = 1;
    int n = fz_size(&in, 0, MAXN, &valid);
    int m = fz_int(&in, 1, MAXM);
    static double intr[5 * MAXM], rot[9 * MAXM], cen[3 * MAXM], foc[MAXM], px1[2 * MAXN],
        px2[2 * MAXN], o1[3 * MAXN], d1[3 * MAXN], o2[3 * MAXN], d2[3 * MAXN], ppr[MAXN];
    static long long ids1[MAXN], ids2[MAXN];
    if (n == (1 << 21))
        n = (1 << 26) + 1; /* the limit is 2^26 pairs */
    want_ppr = fz_u8(&in) & 1;
    if (!valid) {
        st = mcg_pinhole_ray_pairs(n, m, intr, rot, cen, foc, ids1, ids2, px1, px2, o1, d1, o2,
                                   d2, want_ppr ? ppr : NULL, &bad);
        FZ_CHECK(st == MCG_EINVAL, "pinhole_ray_pairs(n = %d) returned %d", n, st);
        return 0;
    }
    if (mode == 0) {
        for (i = 0; i < m; ++i) {
            fz_rotation(&in, rot + 9 * i);
            intr[5 * i] = fz_range(&in, 100.0, 3000.0);
            intr[5 * i + 1] = intr[5 * i] * fz_range(&in, 0.8, 1.25);
            intr[5 * i + 2] = fz_range(&in, 0.0, 2000.0);
            intr[5 * i + 3] = fz_range(&in, 0.0, 2000.0);
            intr[5 * i + 4] = (fz_u8(&in) & 3) == 0 ? fz_range(&in, -5.0, 5.0) : 0.0;
            foc[i] = 0.5 * (intr[5 * i] + intr[5 * i + 1]);
            for (k = 0; k < 3; ++k)
                cen[3 * i + k] = fz_range(&in, -2.0, 2.0);
        }
        for (k = 0; k < n; ++k) {
            ids1[k] = fz_int(&in, 0, m - 1);
            ids2[k] = (fz_u8(&in) & 3) == 0 ? fz_int(&in, 0, m - 1) : ids1[k];
            for (i = 0; i < 2; ++i) {
                px1[2 * k + i] = fz_range(&in, -5000.0, 5000.0);
                px2[2 * k + i] = fz_range(&in, -5000.0, 5000.0);
            }
        }
    } else {
        fz_doubles(&in, intr, 5 * (size_t)m);
        for (i = 0; i < m; ++i)
            fz_rotation_or_any(&in, rot + 9 * i);
        fz_doubles(&in, cen, 3 * (size_t)m);
        fz_doubles(&in, foc, (size_t)m);
        fz_doubles(&in, px1, 2 * (size_t)n);
        fz_doubles(&in, px2, 2 * (size_t)n);
        for (k = 0; k < n; ++k) {
            ids1[k] = (long long)fz_int(&in, -1, m);
            ids2[k] = (long long)fz_int(&in, -1, m);
        }
    }
    st = mcg_pinhole_ray_pairs(n, m, intr, rot, cen, foc, ids1, ids2, px1, px2, o1, d1, o2, d2,
                               want_ppr ? ppr : NULL, &bad);
    FZ_CHECK(fz_status_known(st), "pinhole_ray_pairs status %d", st);
    if (want_ppr)
        robust_from_pixels(n, m, intr, rot, cen, foc, ids1, ids2, px1, px2, o1, d1, o2, d2, ppr,
                           st, fz_u64(&in));
    FZ_CHECK(bad == -1 || (st == MCG_EINVAL && bad >= 0 && bad < 2 * n),
             "pinhole_ray_pairs: bad = %d with status %d", bad, st);
    ok_tables = fz_all_finite(intr, 5 * (size_t)m) && fz_all_finite(rot, 9 * (size_t)m) &&
                fz_all_finite(cen, 3 * (size_t)m);
    for (i = 0; i < m; ++i) {
        ok_tables &= intr[5 * i] != 0.0 && intr[5 * i + 1] != 0.0;
        if (want_ppr)
            ok_tables &= isfinite(foc[i]) && foc[i] > 0.0;
    }
    if (!ok_tables) {
        FZ_CHECK(st == MCG_EINVAL, "pinhole_ray_pairs with bad tables: %d", st);
        return 0;
    }
    for (k = 0; k < n; ++k) {
        int ids_ok = ids1[k] >= 0 && ids1[k] < m && ids2[k] >= 0 && ids2[k] < m;
        if (!ids_ok || !fz_all_finite(px1 + 2 * k, 2) || !fz_all_finite(px2 + 2 * k, 2)) {
            FZ_CHECK(st == MCG_EINVAL, "pinhole_ray_pairs: pair %d bad, status %d", k, st);
            return 0;
        }
    }
    if (st != MCG_OK)
        return 0;
    for (k = 0; k < n; ++k) {
        double e1 = fz_dot3(d1 + 3 * k, d1 + 3 * k) - 1.0, e2 = fz_dot3(d2 + 3 * k, d2 + 3 * k) - 1.0;
        /* unit up to rounding: a rotation decoded in mode 1 may not be one */
        if (fz_is_rotation(rot + 9 * ids1[k], 1e-9) && fz_is_rotation(rot + 9 * ids2[k], 1e-9))
            FZ_CHECK(fabs(e1) < 1e-8 && fabs(e2) < 1e-8, "pair %d: |d|^2 - 1 = %g, %g", k, e1, e2);
        FZ_CHECK(fz_all_finite(d1 + 3 * k, 3) && fz_all_finite(d2 + 3 * k, 3),
                 "pair %d: non-finite bearing with MCG_OK", k);
        for (i = 0; i < 3; ++i)
            FZ_CHECK(o1[3 * k + i] == cen[3 * ids1[k] + i] && o2[3 * k + i] == cen[3 * ids2[k] + i],
                     "pair %d: origin is not the camera centre", k);
        if (want_ppr)
            FZ_CHECK(isfinite(ppr[k]) && ppr[k] > 0.0, "pair %d: ppr = %g", k, ppr[k]);
    }
    return 0;
}
