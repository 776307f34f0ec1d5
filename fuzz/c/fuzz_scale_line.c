/*
 * fuzz_scale_line.c -- libFuzzer harness of mcg_scale_ransac (and its work
 * size), the 1-point scale search of the 5+1 method along t0 + lam w
 * (thesis ch. 7.4, eq. 7.4).
 *
 * Inputs: mode 0 a synthetic rig scene with t0 decoded and w towards the
 * true translation, mode 1 arbitrary arrays; a decoded order (indices, 1 in
 * 16 out of range), max_proposals, threshold and prob (valid or not), and a
 * workspace 1 double short 1 in 16 times. Invariants: the status is known;
 * bad sizes, indices, threshold or prob give MCG_EINVAL, a short workspace
 * MCG_ENOMEM, NaN/inf inputs never MCG_OK; on MCG_OK lam is finite and > 0,
 * 0 <= score <= n threshold^2, 0 <= n_inliers <= n, and (finite scene)
 * the score equals the MSAC of mcg_gec_residuals at t0 + lam w (unless a
 * pair's camera centre stops moving there, where both are rounding noise).
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
    int mode = fz_u8(&in) % FUZZ_MODES, valid, st, i, n_order, max_prop, m = -1, idx_ok = 1;
    int n = fz_size(&in, 1, MAXN, &valid);
    static double o1[3 * MAXN], d1[3 * MAXN], o2[3 * MAXN], d2[3 * MAXN], res[MAXN];
    static int order[2 * MAXN];
    double R[9] = {0}, tt[3], t0[3] = {0}, w[3] = {0}, thr, prob, lam = NAN, score = NAN, *work;
    size_t lwork;
    int args_ok;
    if (n == (1 << 21))
        n = (1 << 26) + 1; /* the limit is 2^26 pairs */
    if (!valid) {
        int dummy[1] = {0};
        st = mcg_scale_ransac(n, o1, d1, o2, d2, R, t0, w, 1, dummy, 1, 1e-3, 0.99, &lam, &score,
                              NULL, res, MAXN);
        FZ_CHECK(st == MCG_EINVAL, "scale_ransac(n = %d) returned %d", n, st);
        FZ_CHECK(mcg_scale_ransac_work_size(n) == 0, "work size of n = %d not 0", n);
        return 0;
    }
    if (mode == 0) {
        double dt[3], nd;
        fz_rotation(&in, R);
        for (i = 0; i < 3; ++i)
            tt[i] = fz_range(&in, -2.0, 2.0);
        {   /* decoded in this order (not as arguments of one call) */
            const int ncams = fz_int(&in, 1, 8), cross = fz_u8(&in) & 1;
            fz_scene(&in, n, ncams, cross, R, tt, o1, d1, o2, d2, NULL);
        }
        for (i = 0; i < 3; ++i) {
            t0[i] = fz_range(&in, -1.0, 1.0);
            dt[i] = tt[i] - t0[i];
        }
        nd = sqrt(fz_dot3(dt, dt));
        for (i = 0; i < 3; ++i)
            w[i] = nd > 0.0 ? dt[i] / nd : 0.0;
    } else {
        fz_rays(&in, (size_t)n, o1, d1, o2, d2);
        fz_rotation_or_any(&in, R);
        fz_doubles(&in, t0, 3);
        fz_doubles(&in, w, 3);
    }
    n_order = fz_int(&in, 0, 2 * MAXN);
    for (i = 0; i < n_order; ++i) {
        order[i] = (fz_u8(&in) % 16 == 0) ? fz_int(&in, -2, n + 2) : fz_int(&in, 0, n - 1);
        idx_ok &= order[i] >= 0 && order[i] < n;
    }
    if (fz_u8(&in) % 8 == 0) {
        max_prop = fz_int(&in, -1, 3);
        thr = fz_double(&in);
        prob = fz_double(&in);
    } else {
        max_prop = fz_int(&in, 1, 80);
        thr = fz_range(&in, 1e-6, 0.5);
        prob = fz_range(&in, 0.5, 0.9999);
    }
    lwork = mcg_scale_ransac_work_size(n);
    FZ_CHECK(lwork == 5 * (size_t)n, "work size %zu for n = %d", lwork, n);
    if (fz_u8(&in) % 16 == 0)
        lwork -= 1;
    work = fz_alloc(lwork);
    if (!work)
        return 0;
    st = mcg_scale_ransac(n, o1, d1, o2, d2, R, t0, w, n_order, order, max_prop, thr, prob, &lam,
                          &score, (fz_u8(&in) & 1) ? NULL : &m, work, lwork);
    free(work);
    FZ_CHECK(fz_status_known(st), "scale_ransac status %d", st);
    args_ok = idx_ok && max_prop >= 1 && max_prop <= (1 << 20) && isfinite(thr) && thr > 0.0 &&
              prob > 0.0 && prob < 1.0;
    if (!args_ok) {
        FZ_CHECK(st == MCG_EINVAL, "scale_ransac with bad arguments: %d", st);
        return 0;
    }
    if (!fz_all_finite(o1, 3 * (size_t)n) || !fz_all_finite(d1, 3 * (size_t)n) ||
        !fz_all_finite(o2, 3 * (size_t)n) || !fz_all_finite(d2, 3 * (size_t)n) ||
        !fz_all_finite(R, 9) || !fz_all_finite(t0, 3) || !fz_all_finite(w, 3)) {
        FZ_CHECK(st == MCG_EINVAL, "scale_ransac of non-finite input: %d", st);
        return 0;
    }
    if (lwork < mcg_scale_ransac_work_size(n)) {
        FZ_CHECK(st == MCG_ENOMEM || st == MCG_EINVAL, "short workspace: %d", st);
        return 0;
    }
    if (st != MCG_OK)
        return 0;
    FZ_CHECK(isfinite(lam) && lam > 0.0, "scale_ransac: lam %g", lam);
    FZ_CHECK(isfinite(score) && score >= 0.0 && score <= n * thr * thr * (1.0 + 1e-12),
             "scale_ransac: score %g of %d pairs at threshold %g", score, n, thr);
    FZ_CHECK(m == -1 || (m >= 0 && m <= n), "scale_ransac: %d inliers of %d", m, n);
    if (mode == 0 && fz_is_rotation(R, 1e-9)) {
        double t[3], direct = 0.0;
        for (i = 0; i < 3; ++i)
            t[i] = t0[i] + lam * w[i];
        /* skipped where a pair's camera centre (nearly) stops moving at lam,
         * s = t + R o1 - o2 ~ 0: its residual e / sqrt(D), a ratio of two
         * quantities that vanish with s, is then the rounding noise of s in
         * both formulas (the LS step can land there: seen at t = 0 with R
         * about the axis through the centre) */
        int moving = 1, k;
        for (i = 0; i < n && moving; ++i) {
            double sv[3], mag = fz_maxabs(t0, 3) + fabs(lam) * fz_maxabs(w, 3) +
                                fz_maxabs(o1 + 3 * i, 3) + fz_maxabs(o2 + 3 * i, 3);
            for (k = 0; k < 3; ++k)
                sv[k] = t[k] + R[3 * k] * o1[3 * i] + R[3 * k + 1] * o1[3 * i + 1] +
                        R[3 * k + 2] * o1[3 * i + 2] - o2[3 * i + k];
            moving = fz_maxabs(sv, 3) > 1e-6 * mag;
        }
        if (moving && mcg_gec_residuals(n, o1, d1, o2, d2, R, t, res) == MCG_OK) {
            for (i = 0; i < n; ++i)
                direct += res[i] * res[i] < thr * thr ? res[i] * res[i] : thr * thr;
            /* (plus the rounding of residuals at the noise floor, ~1e-15 rad,
             * where two formulas of one residual differ by 100 %) */
            FZ_CHECK(fabs(direct - score) <= 1e-6 * n * thr * thr + 1e-20 * n,
                     "scale_ransac: score %.17g, MSAC of gec_residuals %.17g", score, direct);
        }
    }
    return 0;
}
