/*
 * fuzz_linear17.c -- libFuzzer harness of mcg_linear17, the linear 17-point
 * generalized essential matrix estimator (thesis ch. 8, Algorithm 2, the
 * constrained SVD of Algorithm 4, eq. 8.15 for the scale), with decoded
 * options.
 *
 * Inputs: mode 0 a synthetic rig scene (fz_scene: 1-8 cameras, intra- and
 * cross-camera pairs, optional noise, a few entries replaced by arbitrary
 * doubles), mode 1 arbitrary arrays. Invariants: n < 14 or invalid options
 * give MCG_EINVAL; NaN/inf inputs never MCG_OK; on MCG_OK R is a rotation,
 * t, t_metric and E are finite, the diagnostics are in range (gc_case,
 * n_in_front <= n, n_candidates <= 4); on exact data with the default
 * options and an observable scale, the returned motion satisfies the
 * generalized epipolar constraint (Sampson residuals, mcg_gec_residuals).
 */
#include "fuzz_input.h"
#include "mcgeom.h"

/* routines selected by the first input byte (fuzz/make_corpus.py writes
 * seeds for each) */
#define FUZZ_MODES 2

#define MAXN 96

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in = fz_make(data, size);
    int mode = fz_u8(&in) % FUZZ_MODES, valid, st, i, exact = 0, defaults, ncams = 1;
    int n = fz_size(&in, 14, MAXN, &valid);
    static double o1[3 * MAXN], d1[3 * MAXN], o2[3 * MAXN], d2[3 * MAXN], res_k[MAXN];
    double R[9], t[3];
    mcg_linear17_options opt;
    mcg_linear17_result res;
    if (n == (1 << 21))
        n = (1 << 26) + 1; /* mcg_linear17 accepts up to 2^26 rays */
    if (!valid && n >= 14 && n <= (1 << 26))
        n = 13;
    mcg_linear17_default_options(&opt);
    defaults = (fz_u8(&in) & 3) != 0;
    if (!defaults) {
        opt.refine = fz_int(&in, -1, 2);
        opt.max_iterations = fz_int(&in, -2, 300);
        opt.tolerance = fz_double(&in);
        opt.rank_rtol = fz_double(&in);
        opt.min_scale_conditioning = fz_double(&in);
        opt.max_scale_rel_std = fz_double(&in);
    }
    if (!valid) {
        st = mcg_linear17(n, o1, d1, o2, d2, &opt, &res);
        FZ_CHECK(st == MCG_EINVAL, "linear17(n = %d) returned %d", n, st);
        return 0;
    }
    if (mode == 0) {
        fz_rotation(&in, R);
        for (i = 0; i < 3; ++i)
            t[i] = fz_range(&in, -2.0, 2.0);
        ncams = fz_int(&in, 1, 8);
        exact = fz_scene(&in, n, ncams, fz_u8(&in) & 1, R, t, o1, d1, o2, d2, NULL);
    } else {
        fz_rays(&in, (size_t)n, o1, d1, o2, d2);
    }
    st = mcg_linear17(n, o1, d1, o2, d2, (fz_u8(&in) & 7) == 0 && defaults ? NULL : &opt, &res);
    FZ_CHECK(fz_status_known(st), "linear17 status %d", st);
    if (!fz_all_finite(o1, 3 * (size_t)n) || !fz_all_finite(d1, 3 * (size_t)n) ||
        !fz_all_finite(o2, 3 * (size_t)n) || !fz_all_finite(d2, 3 * (size_t)n)) {
        FZ_CHECK(st == MCG_EINVAL, "linear17 of non-finite input: %d", st);
        return 0;
    }
    if (st != MCG_OK)
        return 0;
    FZ_CHECK(fz_is_rotation(res.R, 1e-9), "linear17: R not a rotation (%g, det %g)",
             fz_orth_err3(res.R), fz_det3(res.R));
    FZ_CHECK(fz_all_finite(res.t, 3) && fz_all_finite(res.t_metric, 3) && fz_all_finite(res.E, 9),
             "linear17: non-finite t, t_metric or E");
    FZ_CHECK(res.gc_case >= MCG_GC_MOST_GENERAL && res.gc_case <= MCG_GC_DEGENERATE,
             "linear17: gc_case %d", res.gc_case);
    FZ_CHECK(res.n_in_front >= 0 && res.n_in_front <= n, "linear17: n_in_front %d",
             res.n_in_front);
    FZ_CHECK(res.n_candidates >= 0 && res.n_candidates <= 4, "linear17: n_candidates %d",
             res.n_candidates);
    FZ_CHECK(res.rank_ar >= 0 && res.rank_ar <= 9, "linear17: rank_ar %d", res.rank_ar);
    FZ_CHECK(!isnan(res.scale_rel_std) && !isnan(res.scale_conditioning) &&
                 isfinite(res.cost_final) && isfinite(res.norm_scale),
             "linear17: NaN diagnostics (rel_std %g, cond %g, cost %g, norm_scale %g)",
             res.scale_rel_std, res.scale_conditioning, res.cost_final, res.norm_scale);
    FZ_CHECK(res.scale_observable == 0 || res.scale_observable == 1,
             "linear17: scale_observable %d", res.scale_observable);
    /* Also where the decoder ran out of bytes and the points repeat: the
     * kernel must then detect the rank loss (MCG_EDEGENERATE) or still fit
     * the data (finding 9 of fuzz/README.md) */
    if (exact && defaults && res.scale_observable && ncams >= 2 && n >= 20) {
        /* exact data: the estimate must satisfy the constraint, unless the
         * synthetic points are too close to a camera centre for the check */
        double worst = 0.0;
        int ok = 1;
        for (i = 0; i < 3 * n && ok; ++i)
            ok = fabs(d1[i]) + fabs(d1[i - i % 3 + (i + 1) % 3]) > 1e-3;
        if (mcg_gec_residuals(n, o1, d1, o2, d2, res.R, res.t, res_k) == MCG_OK && ok) {
            for (i = 0; i < n; ++i)
                if (fabs(res_k[i]) > worst)
                    worst = fabs(res_k[i]);
            FZ_CHECK(worst <= 1e-5, "linear17: exact data, observable scale, residual %g "
                     "(gc_case %d)", worst, res.gc_case);
        }
    }
    return 0;
}
