/*
 * fuzz_consensus.c -- libFuzzer harness of mcg_consensus_check, the checks
 * of a robust estimate's consensus (leverage, the refits without the pairs
 * of high leverage, the residuals' HC3 std).
 *
 * Inputs: mode 0 a synthetic rig scene at a motion near the true one, mode 1
 * arbitrary arrays and motion; no weights (all 1), weights in [0, 3], or
 * any; rel_std, its calibration part and max_rel_std any doubles.
 * Invariants: a bad size, weight, std or max_rel_std gives MCG_EINVAL, a
 * short workspace MCG_ENOMEM; NaN/inf inputs never MCG_OK; on MCG_OK the
 * reason is one of MCG_CONSENSUS_*, the reported std is at least rel_std
 * (the checks only widen it) and not NaN, a metric answer's std is within
 * max_rel_std unless no check could widen it (the fit singular or no
 * widening), at most 3 pairs dropped, each a used pair (weight > 0) and
 * distinct, the widening flags only on a metric answer or the std's own
 * refusals; the same call gives the same result.
 */
#include "fuzz_input.h"
#include <float.h>
#include <string.h>
#include "mcgeom.h"

/* routines selected by the first input byte (fuzz/make_corpus.py writes
 * seeds for each) */
#define FUZZ_MODES 2

#define MAXN 64

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in = fz_make(data, size);
    int mode = fz_u8(&in) % FUZZ_MODES, valid, st, st2, i, j, use_w, bad = 0;
    int n = fz_size(&in, 0, MAXN, &valid);
    static double o1[3 * MAXN], d1[3 * MAXN], o2[3 * MAXN], d2[3 * MAXN], w[MAXN];
    static double work[15 * MAXN + 1];
    double R[9], t[3], rel, cal, max_rel;
    size_t lw;
    mcg_consensus_result c, c2;
    if (n == (1 << 21))
        n = (1 << 26) + 1; /* the limit is 2^26 pairs */
    if (!valid) {
        st = mcg_consensus_check(n, o1, d1, o2, d2, w, R, t, 0.01, 0.0, 0.1, &c, work, 0);
        FZ_CHECK(st == MCG_EINVAL, "consensus(n = %d) returned %d", n, st);
        return 0;
    }
    if (!fz_fit_input(&in, mode, n, 0.05, 0.1, o1, d1, o2, d2, R, t))
        return 0;
    use_w = fz_weights(&in, n, w);
    rel = fz_u8(&in) < 200 ? fz_range(&in, 0.0, 0.2) : fz_double(&in);
    cal = fz_u8(&in) < 200 ? fz_range(&in, 0.0, 0.05) : fz_double(&in);
    max_rel = fz_u8(&in) < 200 ? fz_range(&in, 1e-3, 0.3) : fz_double(&in);
    lw = mcg_consensus_check_work_size(n);
    FZ_CHECK(lw >= 15 * (size_t)n && lw <= 15 * (size_t)MAXN + 1, "work size %zu for %d", lw, n);
    if (fz_u8(&in) == 0 && lw > 0) {
        st = mcg_consensus_check(n, o1, d1, o2, d2, w, R, t, rel, cal, max_rel, &c, work, lw - 1);
        FZ_CHECK(st == MCG_ENOMEM || st == MCG_EINVAL, "short workspace: %d", st);
    }
    st = mcg_consensus_check(n, o1, d1, o2, d2, w, R, t, rel, cal, max_rel, &c, work, lw);
    FZ_CHECK(fz_status_known(st), "consensus status %d", st);
    for (i = 0; use_w && i < n; ++i)
        bad |= !(w[i] >= 0.0 && w[i] <= 1e100);
    if (bad || !(isfinite(rel) && rel >= 0.0) || !(isfinite(cal) && cal >= 0.0) ||
        !(isfinite(max_rel) && max_rel > 0.0)) {
        FZ_CHECK(st == MCG_EINVAL, "consensus with weight/std/max out of range: %d", st);
        return 0;
    }
    if (!fz_all_finite(o1, 3 * (size_t)n) || !fz_all_finite(d1, 3 * (size_t)n) ||
        !fz_all_finite(o2, 3 * (size_t)n) || !fz_all_finite(d2, 3 * (size_t)n) ||
        !fz_all_finite(R, 9) || !fz_all_finite(t, 3)) {
        FZ_CHECK(st != MCG_OK, "consensus of non-finite input: %d", st);
        return 0;
    }
    if (st != MCG_OK)
        return 0;
    FZ_CHECK(c.reason >= MCG_CONSENSUS_METRIC && c.reason <= MCG_CONSENSUS_RESIDUALS_STD,
             "reason %d", c.reason);
    FZ_CHECK(c.rel_std >= rel && !isnan(c.rel_std), "std %g below the given %g", c.rel_std,
             rel);
    FZ_CHECK(c.reason != MCG_CONSENSUS_METRIC ||
                 !(c.widened_by_lever || c.widened_by_residuals) || c.rel_std <= max_rel,
             "metric with a widened std %g > %g", c.rel_std, max_rel);
    FZ_CHECK(c.n_dropped >= 0 && c.n_dropped <= 3, "%d pairs dropped", c.n_dropped);
    for (i = 0; i < c.n_dropped; ++i) {
        FZ_CHECK(c.dropped[i] >= 0 && c.dropped[i] < n && w[c.dropped[i]] > 0.0,
                 "dropped pair %d (weight %g)", c.dropped[i],
                 c.dropped[i] >= 0 && c.dropped[i] < n ? w[c.dropped[i]] : -1.0);
        for (j = 0; j < i; ++j)
            FZ_CHECK(c.dropped[j] != c.dropped[i], "pair %d dropped twice", c.dropped[i]);
    }
    FZ_CHECK(c.have_stats || (c.reason == MCG_CONSENSUS_METRIC && c.rel_std == rel &&
                              c.n_dropped == 0),
             "no statistics, yet reason %d, std %g", c.reason, c.rel_std);
    st2 = mcg_consensus_check(n, o1, d1, o2, d2, w, R, t, rel, cal, max_rel, &c2, work, lw);
    FZ_CHECK(st2 == MCG_OK && c2.reason == c.reason && c2.n_dropped == c.n_dropped &&
                 memcmp(&c2.rel_std, &c.rel_std, sizeof c.rel_std) == 0 &&
                 memcmp(c2.dropped, c.dropped, sizeof c.dropped) == 0,
             "the same call: status %d, another result", st2);
    return 0;
}
