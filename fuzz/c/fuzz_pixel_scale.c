/*
 * fuzz_pixel_scale.c -- libFuzzer harness of mcg_sampson_pixel_scale, the
 * pixels per radian of each Sampson residual for pinhole cameras.
 *
 * Inputs: mode 0 a synthetic rig scene (optical axes towards the points,
 * focal lengths 100..2000 px), mode 1 arbitrary arrays; min_var_ratio and
 * the focal lengths valid or not. Invariants: bad n, focal lengths or
 * min_var_ratio give MCG_EINVAL, NaN/inf inputs never MCG_OK; on MCG_OK
 * every scale is finite and >= 0 (0 = no first-order constraint).
 */
#include "fuzz_input.h"
#include "mcgeom.h"

/* routines selected by the first input byte (fuzz/make_corpus.py writes
 * seeds for each) */
#define FUZZ_MODES 2

#define MAXN 64

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in = fz_make(data, size);
    int mode = fz_u8(&in) % FUZZ_MODES, valid, st, i, k;
    int n = fz_size(&in, 0, MAXN, &valid);
    static double o1[3 * MAXN], d1[3 * MAXN], o2[3 * MAXN], d2[3 * MAXN], z1[3 * MAXN],
        z2[3 * MAXN], f1[MAXN], f2[MAXN], sc[MAXN];
    double R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, t[3] = {0, 0, 0}, mvr;
    int args_ok = 1;
    if (n == (1 << 21))
        n = (1 << 26) + 1; /* the limit is 2^26 pairs */
    if (!valid) {
        st = mcg_sampson_pixel_scale(n, o1, d1, o2, d2, R, t, z1, z2, f1, f2, 0.0, sc);
        FZ_CHECK(st == MCG_EINVAL, "pixel_scale(n = %d) returned %d", n, st);
        return 0;
    }
    if (mode == 0) {
        fz_rotation(&in, R);
        for (i = 0; i < 3; ++i)
            t[i] = fz_range(&in, -2.0, 2.0);
        {   /* decoded in this order (not as arguments of one call) */
            const int ncams = fz_int(&in, 1, 8), cross = fz_u8(&in) & 1;
            fz_scene(&in, n, ncams, cross, R, t, o1, d1, o2, d2, NULL);
        }
        for (k = 0; k < n; ++k) {
            /* the axis of each camera: roughly along its bearing */
            for (i = 0; i < 3; ++i) {
                z1[3 * k + i] = d1[3 * k + i] + fz_range(&in, -0.5, 0.5);
                z2[3 * k + i] = d2[3 * k + i] + fz_range(&in, -0.5, 0.5);
            }
            f1[k] = fz_range(&in, 100.0, 2000.0);
            f2[k] = fz_range(&in, 100.0, 2000.0);
        }
    } else {
        fz_rays(&in, (size_t)n, o1, d1, o2, d2);
        fz_matrix(&in, z1, (size_t)n, 3);
        fz_matrix(&in, z2, (size_t)n, 3);
        fz_doubles(&in, f1, (size_t)n);
        fz_doubles(&in, f2, (size_t)n);
        fz_rotation_or_any(&in, R);
        fz_doubles(&in, t, 3);
    }
    mvr = (fz_u8(&in) % 8 == 0) ? fz_double(&in) : fz_range(&in, 0.0, 1e-6);
    st = mcg_sampson_pixel_scale(n, o1, d1, o2, d2, R, t, z1, z2, f1, f2, mvr, sc);
    FZ_CHECK(fz_status_known(st), "pixel_scale status %d", st);
    for (k = 0; k < n; ++k)
        args_ok &= isfinite(f1[k]) && f1[k] > 0.0 && isfinite(f2[k]) && f2[k] > 0.0;
    args_ok &= isfinite(mvr) && mvr >= 0.0;
    if (!args_ok) {
        FZ_CHECK(st == MCG_EINVAL, "pixel_scale with bad focal / min_var_ratio: %d", st);
        return 0;
    }
    if (!fz_all_finite(o1, 3 * (size_t)n) || !fz_all_finite(d1, 3 * (size_t)n) ||
        !fz_all_finite(o2, 3 * (size_t)n) || !fz_all_finite(d2, 3 * (size_t)n) ||
        !fz_all_finite(z1, 3 * (size_t)n) || !fz_all_finite(z2, 3 * (size_t)n) ||
        !fz_all_finite(R, 9) || !fz_all_finite(t, 3)) {
        FZ_CHECK(st == MCG_EINVAL, "pixel_scale of non-finite input: %d", st);
        return 0;
    }
    if (st != MCG_OK)
        return 0;
    for (k = 0; k < n; ++k)
        FZ_CHECK(isfinite(sc[k]) && sc[k] >= 0.0, "pixel_scale: scale[%d] = %g", k, sc[k]);
    return 0;
}
