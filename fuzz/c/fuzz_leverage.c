/*
 * fuzz_leverage.c -- libFuzzer harness of mcg_sampson_leverage, each pair's
 * leverage J_k (J^T J)^-1 J_k^T in the least-squares fit of a rig motion
 * (Sampson angular residuals, thesis eq. 8.15), 6 parameters or t alone.
 *
 * Inputs: mode 0 a synthetic rig scene at a motion near the true one, mode 1
 * arbitrary arrays and motion; no weights, weights in [0, 3], or any.
 * Invariants: a bad size, weight or hold_rotation gives MCG_EINVAL; NaN/inf
 * inputs never MCG_OK; on MCG_OK every leverage
 * is in [0, 1], they sum to the number of parameters (the trace of the hat
 * matrix), max_leverage is the largest and leverage_pair a pair that has
 * it; the influence is finite and >= 0 with a pair in range, the travel
 * finite and >= 0, its std >= 0, the HC3 std >= 0 and at least the largest
 * deletion move (a root sum of squares of the moves); the same call without the per-pair array
 * gives the same result.
 */
#include "fuzz_input.h"
#include <float.h>
#include "mcgeom.h"

/* routines selected by the first input byte (fuzz/make_corpus.py writes
 * seeds for each) */
#define FUZZ_MODES 2

#define MAXN 64

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in = fz_make(data, size);
    int mode = fz_u8(&in) % FUZZ_MODES, valid, st, st2, i, hold, use_w;
    int n = fz_size(&in, 0, MAXN, &valid);
    static double o1[3 * MAXN], d1[3 * MAXN], o2[3 * MAXN], d2[3 * MAXN], lev[MAXN], w[MAXN];
    double R[9], t[3], sum = 0.0;
    mcg_leverage_result lr, lr2;
    hold = fz_int(&in, -1, 2);
    if (n == (1 << 21))
        n = (1 << 26) + 1; /* the limit is 2^26 pairs */
    if (!valid) {
        st = mcg_sampson_leverage(n, o1, d1, o2, d2, NULL, R, t, 0, lev, &lr);
        FZ_CHECK(st == MCG_EINVAL, "leverage(n = %d) returned %d", n, st);
        return 0;
    }
    if (!fz_fit_input(&in, mode, n, 0.05, 0.1, o1, d1, o2, d2, R, t))
        return 0;
    use_w = fz_weights(&in, n, w);
    st = mcg_sampson_leverage(n, o1, d1, o2, d2, use_w ? w : NULL, R, t, hold, lev, &lr);
    FZ_CHECK(fz_status_known(st), "leverage status %d", st);
    if (hold != 0 && hold != 1) {
        FZ_CHECK(st == MCG_EINVAL, "leverage with hold_rotation %d: %d", hold, st);
        return 0;
    }
    if (!fz_all_finite(o1, 3 * (size_t)n) || !fz_all_finite(d1, 3 * (size_t)n) ||
        !fz_all_finite(o2, 3 * (size_t)n) || !fz_all_finite(d2, 3 * (size_t)n) ||
        !fz_all_finite(R, 9) || !fz_all_finite(t, 3)) {
        FZ_CHECK(st == MCG_EINVAL, "leverage of non-finite input: %d", st);
        return 0;
    }
    for (i = 0; use_w && i < n; ++i)
        if (!(w[i] >= 0.0 && w[i] <= 1e100)) {
            FZ_CHECK(st == MCG_EINVAL, "leverage with weight %g: %d", w[i], st);
            return 0;
        }
    if (st != MCG_OK)
        return 0;
    FZ_CHECK(n >= (hold ? 3 : 6), "leverage OK with %d pairs", n);
    for (i = 0; i < n; ++i) {
        FZ_CHECK(lev[i] >= 0.0 && lev[i] <= 1.0, "leverage %d = %g", i, lev[i]);
        sum += lev[i];
    }
    FZ_CHECK(fabs(sum - (hold ? 3.0 : 6.0)) <= 1e-5, "leverages sum to %.17g", sum);
    FZ_CHECK(lr.leverage_pair >= 0 && lr.leverage_pair < n &&
                 lev[lr.leverage_pair] == lr.max_leverage,
             "leverage_pair %d, max_leverage %g", lr.leverage_pair, lr.max_leverage);
    for (i = 0; i < n; ++i)
        FZ_CHECK(lev[i] <= lr.max_leverage, "leverage %d = %g above max_leverage %g", i, lev[i],
                 lr.max_leverage);
    FZ_CHECK(lr.max_influence <= DBL_MAX && lr.max_influence >= 0.0 &&
                 lr.max_influence_stds <= DBL_MAX && lr.max_influence_stds >= 0.0 &&
                 lr.influence_pair >= 0 && lr.influence_pair < n,
             "influence %g (%g stds) at %d", lr.max_influence, lr.max_influence_stds,
             lr.influence_pair);
    FZ_CHECK(isfinite(lr.travel) && lr.travel >= 0.0 && lr.travel_std >= 0.0 &&
                 !isnan(lr.travel_std),
             "travel %g, std %g", lr.travel, lr.travel_std);
    {
        /* (the largest move, back from its share of the travel: not
         * compared when that share is subnormal -- a move of 1e-12 m on a
         * travel of 1e307 m keeps a few digits -- or the move comes back
         * beyond the doubles, the share capped at DBL_MAX) */
        const double move = lr.max_influence * lr.travel;
        FZ_CHECK(lr.travel_std_hc >= 0.0 &&
                     (lr.travel == 0.0 || !(move <= DBL_MAX) || lr.max_influence < DBL_MIN ||
                      lr.travel_std_hc >= move * (1.0 - 1e-9)),
                 "HC3 std %g, largest move %g", lr.travel_std_hc, move);
    }
    st2 = mcg_sampson_leverage(n, o1, d1, o2, d2, use_w ? w : NULL, R, t, hold, NULL, &lr2);
    FZ_CHECK(st2 == MCG_OK && memcmp(&lr, &lr2, sizeof lr) == 0,
             "without lev: status %d, another result", st2);
    return 0;
}
