/*
 * fuzz_refine.c -- libFuzzer harness of mcg_refine_motion, Levenberg-
 * Marquardt on SO(3) x R^3 of the Sampson angular error of the generalized
 * epipolar constraint (thesis eq. 8.15), robust losses by IRLS, weights,
 * fix_scale, and decoded options; and of mcg_refine_translation, the same
 * with R held.
 *
 * Inputs: mode 0 a synthetic rig scene started near the true motion, mode 1
 * arbitrary arrays and start; modes 2 and 3 the same for
 * mcg_refine_translation. Invariants: bad sizes, options, weights or a
 * start that is not a rotation give MCG_EINVAL and leave R, t untouched;
 * NaN/inf inputs never MCG_OK; on MCG_OK R is a rotation, t finite, the
 * cost did not increase, iterations <= max_iterations, the reason is one of
 * MCG_REFINE_STOP_*, n_used <= n, the statistics are not NaN, and with
 * fix_scale |t| is kept. mcg_refine_translation: R is never written,
 * fix_scale gives MCG_EINVAL.
 */
#include "fuzz_input.h"
#include "mcgeom.h"

/* routines selected by the first input byte (fuzz/make_corpus.py writes
 * seeds for each) */
#define FUZZ_MODES 4

#define MAXN 64

static double norm3(const double *v)
{
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in = fz_make(data, size);
    int mode = fz_u8(&in) % FUZZ_MODES, valid, st, use_w, use_opt, held;
    int n = fz_size(&in, 6, MAXN, &valid);
    static double o1[3 * MAXN], d1[3 * MAXN], o2[3 * MAXN], d2[3 * MAXN], w[MAXN];
    double R[9], t[3], R0[9], t0[3];
    mcg_refine_options opt;
    mcg_refine_result res;
    held = mode >= 2; /* mcg_refine_translation */
    mode %= 2;
    if (n == (1 << 21))
        n = (1 << 26) + 1; /* the limit is 2^26 pairs */
    if (!valid && n >= 6 && n <= (1 << 26))
        n = 5;
    mcg_refine_default_options(&opt);
    use_opt = fz_u8(&in) % 4;
    if (use_opt == 1) { /* any option values */
        opt.loss = fz_int(&in, -1, 4);
        opt.loss_scale = fz_double(&in);
        opt.max_iterations = fz_int(&in, -1, 200);
        opt.cost_tolerance = fz_double(&in);
        opt.step_tolerance = fz_double(&in);
        opt.initial_lambda = fz_double(&in);
        opt.fix_scale = fz_int(&in, -1, 2);
    } else if (use_opt >= 2) { /* valid option values */
        opt.loss = fz_int(&in, 0, 3);
        opt.loss_scale = fz_range(&in, 1e-6, 0.5);
        opt.max_iterations = fz_int(&in, 0, 60);
        opt.fix_scale = fz_u8(&in) & 1;
        opt.initial_lambda = fz_range(&in, 0.0, 1e3);
    }
    if (!valid) {
        st = held ? mcg_refine_translation(n, o1, d1, o2, d2, NULL, &opt, R, t, &res)
                  : mcg_refine_motion(n, o1, d1, o2, d2, NULL, &opt, R, t, &res);
        FZ_CHECK(st == MCG_EINVAL, "refine(n = %d) returned %d", n, st);
        return 0;
    }
    /* mode 0: the start is the truth moved by a decoded small rotation and shift */
    if (!fz_fit_input(&in, mode, n, 0.2, 0.3, o1, d1, o2, d2, R, t))
        return 0;
    use_w = fz_weights(&in, n, w);
    memcpy(R0, R, sizeof R);
    memcpy(t0, t, sizeof t);
    if (held)
        st = mcg_refine_translation(n, o1, d1, o2, d2, use_w ? w : NULL, use_opt ? &opt : NULL,
                                    R, t, &res);
    else
        st = mcg_refine_motion(n, o1, d1, o2, d2, use_w ? w : NULL, use_opt ? &opt : NULL, R,
                               t, &res);
    FZ_CHECK(fz_status_known(st), "refine status %d", st);
    if (held) {
        FZ_CHECK(memcmp(R, R0, sizeof R) == 0, "refine_translation wrote R (status %d)", st);
        if (use_opt && opt.fix_scale)
            FZ_CHECK(st == MCG_EINVAL, "refine_translation with fix_scale: %d", st);
    }
    if (st != MCG_OK) {
        FZ_CHECK(memcmp(R, R0, sizeof R) == 0 && memcmp(t, t0, sizeof t) == 0,
                 "refine: R, t modified on error %d", st);
    }
    if (!fz_all_finite(o1, 3 * (size_t)n) || !fz_all_finite(d1, 3 * (size_t)n) ||
        !fz_all_finite(o2, 3 * (size_t)n) || !fz_all_finite(d2, 3 * (size_t)n) ||
        !fz_all_finite(R0, 9) || !fz_all_finite(t0, 3) || (use_w && !fz_all_finite(w, (size_t)n))) {
        FZ_CHECK(st == MCG_EINVAL, "refine of non-finite input: %d", st);
        return 0;
    }
    if (st != MCG_OK)
        return 0;
    FZ_CHECK(held || fz_is_rotation(R, 1e-9), "refine: R not a rotation (%g)", fz_orth_err3(R));
    FZ_CHECK(fz_all_finite(t, 3), "refine: non-finite t");
    FZ_CHECK(isfinite(res.initial_cost) && isfinite(res.final_cost) && isfinite(res.rms) &&
                 res.final_cost >= 0.0,
             "refine: costs %g %g rms %g", res.initial_cost, res.final_cost, res.rms);
    FZ_CHECK(res.final_cost <= res.initial_cost * (1.0 + 1e-12) + 1e-300,
             "refine: cost increased %.17g -> %.17g", res.initial_cost, res.final_cost);
    FZ_CHECK(res.iterations >= 0 &&
                 res.iterations <= (use_opt ? opt.max_iterations : 50),
             "refine: %d iterations", res.iterations);
    FZ_CHECK(res.reason >= MCG_REFINE_STOP_COST && res.reason <= MCG_REFINE_STOP_STALLED,
             "refine: reason %d", res.reason);
    FZ_CHECK(res.n_used >= 0 && res.n_used <= n, "refine: n_used %d", res.n_used);
    FZ_CHECK(fz_all_finite(res.info, 36) && !isnan(res.sigma2) && !isnan(res.scale_rel_std) &&
                 !isnan(res.info_cond),
             "refine: NaN statistics");
    if (use_opt && opt.fix_scale)
        FZ_CHECK(fabs(norm3(t) - norm3(t0)) <= 1e-9 * norm3(t0), "refine: fix_scale |t| %g -> %g",
                 norm3(t0), norm3(t));
    return 0;
}
