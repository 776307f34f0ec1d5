/*
 * fuzz_static_test.c -- libFuzzer harness of mcg_static_noise, the noise
 * level of the shared static-rig test (per-camera least-median-of-squares
 * directions and their Sampson residuals).
 *
 * Inputs: mode 0 a synthetic rig scene (cross-camera pairs left out with
 * group -1), mode 1 arbitrary arrays and group ids in -3..8; min_rows and
 * samples valid or not; mode 2 the scene of mode 0 through mcg_static_check
 * (the whole test: estimate's and given rotation present or not, a given or
 * estimated noise level) with the invariants: R_fit a rotation, a positive
 * finite noise level, explained in [0, 1], n_intra the pairs of group >= 0,
 * a static answer explains at least the fraction of at least min_pairs. Invariants: bad sizes, options, group ids below -1
 * and NaN/inf inputs give MCG_EINVAL; on MCG_OK a pair of group -1 or of a
 * camera with fewer than min_rows pairs has residual -1, every other one a
 * finite residual in [0, pi/2], n_used counts them and the median lies
 * between their smallest and largest value.
 */
#include "fuzz_input.h"
#include "mcgeom.h"

/* routines selected by the first input byte (fuzz/make_corpus.py writes
 * seeds for each) */
#define FUZZ_MODES 3

#define MAXN 96

static int check_whole_test(fz_in *in, int n, const int *group, const double R[9],
                            const double *o1, const double *d1, const double *o2,
                            const double *d2, double *work, size_t lw_noise)
{
    static double w2[32 * MAXN + 16]; /* 29 n + 1 since issue 22 */
    mcg_static_options opt;
    mcg_static_result out;
    double level = (fz_u8(in) & 1) ? fz_range(in, 0.0, 0.01) : 0.0, r_fit_err;
    const int with_est = fz_u8(in) & 1, with_given = fz_u8(in) & 1;
    size_t lw = mcg_static_check_work_size(n);
    int st, i, n_intra = 0;
    (void)work;
    (void)lw_noise;
    FZ_CHECK(lw > 0 && lw <= sizeof(w2) / sizeof(w2[0]), "check work size %zu", lw);
    mcg_static_default_options(&opt);
    opt.min_rows = fz_int(in, 1, 20);
    opt.samples = fz_int(in, 0, 64);
    st = mcg_static_check(n, o1, d1, o2, d2, group, with_est ? R : NULL, with_given ? R : NULL,
                          level, &opt, &out, w2, lw);
    FZ_CHECK(fz_status_known(st), "static_check status %d", st);
    if (!fz_all_finite(o1, 3 * (size_t)n) || !fz_all_finite(d1, 3 * (size_t)n) ||
        !fz_all_finite(o2, 3 * (size_t)n) || !fz_all_finite(d2, 3 * (size_t)n)) {
        FZ_CHECK(st == MCG_EINVAL, "static_check of non-finite input: %d", st);
        return 0;
    }
    if (st != MCG_OK)
        return 0;
    for (i = 0; i < n; ++i)
        n_intra += group[i] >= 0;
    r_fit_err = fz_orth_err3(out.R_fit);
    FZ_CHECK(r_fit_err < 1e-9 && fz_det3(out.R_fit) > 0.0, "R_fit not a rotation: %g",
             r_fit_err);
    FZ_CHECK(isfinite(out.noise_level) && out.noise_level > 0.0, "noise level %g",
             out.noise_level);
    FZ_CHECK(out.n_intra == n_intra, "n_intra %d, counted %d", out.n_intra, n_intra);
    FZ_CHECK(out.explained >= 0.0 && out.explained <= 1.0, "explained %g", out.explained);
    if (out.is_static)
        FZ_CHECK(out.explained >= opt.fraction && out.n_intra >= opt.min_pairs,
                 "static with %g explained of %d", out.explained, out.n_intra);
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in = fz_make(data, size);
    int mode = fz_u8(&in) % FUZZ_MODES, valid, st, i, k, used, count, min_rows, samples;
    int n = fz_size(&in, 0, MAXN, &valid);
    static double o1[3 * MAXN], d1[3 * MAXN], o2[3 * MAXN], d2[3 * MAXN], res[MAXN];
    static double work[24 * MAXN + 8]; /* 21 n + 1 since issue 22 */
    static int group[MAXN], size_of[16];
    double R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, t[3] = {0, 0, 0}, med, lo = HUGE_VAL, hi = 0.0;
    size_t lw;
    int args_ok = 1;
    if (!valid) {
        st = mcg_static_noise(n, o1, d1, o2, d2, group, R, 1, 1, res, &med, &used, work, 1);
        FZ_CHECK(st == MCG_EINVAL, "static_noise(n = %d) returned %d", n, st);
        return 0;
    }
    lw = mcg_static_noise_work_size(n);
    FZ_CHECK(lw > 0 && lw <= sizeof(work) / sizeof(work[0]), "work size %zu for n = %d", lw, n);
    if (mode == 0 || mode == 2) {
        fz_rotation(&in, R);
        for (i = 0; i < 3; ++i)
            t[i] = fz_range(&in, -2.0, 2.0);
        {   /* decoded in this order (not as arguments of one call) */
            const int ncams = fz_int(&in, 1, 8), cross = fz_u8(&in) & 1;
            fz_scene(&in, n, ncams, cross, R, t, o1, d1, o2, d2, group);
            for (i = 0; i < n; ++i)
                if (cross && i % 4 == 3)
                    group[i] = -1;
        }
    } else {
        fz_rays(&in, (size_t)n, o1, d1, o2, d2);
        for (i = 0; i < n; ++i)
            group[i] = fz_int(&in, -3, 8);
        fz_rotation_or_any(&in, R);
    }
    if (mode == 2)
        return check_whole_test(&in, n, group, R, o1, d1, o2, d2, work, lw);
    min_rows = (fz_u8(&in) % 8 == 0) ? fz_int(&in, -2, 2) : fz_int(&in, 1, 20);
    /* out of range now and then (a valid count near the cap would spend
     * ~65536 medians per camera: slow, not more thorough) */
    samples = (fz_u8(&in) % 8 == 0) ? ((fz_u8(&in) & 1) ? -1 : 65537) : fz_int(&in, 0, 64);
    st = mcg_static_noise(n, o1, d1, o2, d2, group, R, min_rows, samples, res, &med, &used,
                          work, lw);
    FZ_CHECK(fz_status_known(st), "static_noise status %d", st);
    for (i = 0; i < n; ++i)
        args_ok &= group[i] >= -1;
    args_ok &= min_rows >= 1 && samples >= 0 && samples <= 65536;
    if (!args_ok) {
        FZ_CHECK(st == MCG_EINVAL, "static_noise with bad group / options: %d", st);
        return 0;
    }
    if (!fz_all_finite(o1, 3 * (size_t)n) || !fz_all_finite(d1, 3 * (size_t)n) ||
        !fz_all_finite(o2, 3 * (size_t)n) || !fz_all_finite(d2, 3 * (size_t)n) ||
        !fz_all_finite(R, 9)) {
        FZ_CHECK(st == MCG_EINVAL, "static_noise of non-finite input: %d", st);
        return 0;
    }
    if (st != MCG_OK)
        return 0;
    for (k = 0; k < 16; ++k)
        size_of[k] = 0;
    for (i = 0; i < n; ++i)
        if (group[i] >= 0)
            size_of[group[i]]++;
    count = 0;
    for (i = 0; i < n; ++i) {
        if (group[i] < 0 || size_of[group[i]] < min_rows) {
            FZ_CHECK(res[i] == -1.0, "static_noise: pair %d left out has res %g", i, res[i]);
            continue;
        }
        FZ_CHECK(isfinite(res[i]) && res[i] >= 0.0 && res[i] <= 1.5707963267948968,
                 "static_noise: res[%d] = %g", i, res[i]);
        lo = res[i] < lo ? res[i] : lo;
        hi = res[i] > hi ? res[i] : hi;
        count++;
    }
    FZ_CHECK(used == count, "static_noise: n_used %d, counted %d", used, count);
    if (count)
        FZ_CHECK(med >= lo && med <= hi, "static_noise: median %g outside [%g, %g]", med, lo,
                 hi);
    else
        FZ_CHECK(med == 0.0, "static_noise: median %g with no pair used", med);
    return 0;
}
