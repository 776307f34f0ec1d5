/*
 * fuzz_robust.c -- libFuzzer harness of mcg_robust_rig_motion (and its work
 * size), the whole robust 5+1 estimate of csrc/robust.c.
 *
 * Inputs: mode 0 a synthetic rig scene (1-8 cameras, intra- and
 * cross-camera pairs, a few entries arbitrary), mode 1 arbitrary arrays;
 * camera ids (1 in 16 out of range), optional per-pair focal lengths and
 * camera table, options valid or not (threshold, prob, iteration budgets,
 * LO rounds, loss), the calibration table of the verdict (none, or 2 per
 * camera, 1 in 16 arbitrary), the sampler (a byte: 5+1, upright 4-point with the
 * true vertical in mode 0 and arbitrary vectors in mode 1 -- zero, NaN,
 * huge --, 6-point, AUTO, the eigensolver, linear17, the local 6-point, or 1 in 16 an
 * unknown one), the verdict's evidence asked for or not, and a workspace 1
 * double short 1 in 16 times.
 * Mode 1 gives every camera one origin half of the time.
 * Invariants: the status is known; bad sizes give MCG_EINVAL and a work
 * size of 0, a short workspace MCG_ENOMEM, bad options, ids or focal
 * lengths, a zero direction, an unknown sampler or an upright one without
 * a finite non-zero vertical MCG_EINVAL, NaN/inf inputs never MCG_OK, an
 * origin coordinate beyond 1e150 MCG_EINVAL, 5+1
 * on a camera whose rays have several origins MCG_EINVAL, the eigensolver
 * and linear17 samplers on fewer than 17 pairs MCG_EDEGENERATE; on MCG_OK R
 * is a rotation (orthonormal to 1e-9, det +1), t is finite, the iterations stay
 * within max_iterations, mask bit 0 agrees with the residuals of
 * mcg_gec_residuals at (R, t) (|r| focal < threshold; pairs within rounding
 * of the threshold excepted), the confidence lies in [0, 1], the stage
 * times (seconds_*) are >= 0 and sum to seconds (no rays' time on rays, no
 * verdict's without one), n_inliers counts it, n_used counts bit 1 and
 * the scale profile is NaN (not asked) or >= 0, the sampler used is the
 * one asked for (AUTO: 5+1 or the local 6-point), its found_rate in (0, 1]
 * (1 but for the local 6-point), the verdict's evidence is there
 * exactly when asked for and counts the mask's inliers, and the covariance
 * is finite (or HUGE_VAL everywhere). The scale verdict (res.scale, with
 * the evidence): a known reason; observable exactly for
 * MCG_SCALE_OBSERVABLE, and then determined with rel_std <=
 * max_scale_rel_std; a determined t is res.t, an undetermined one (not
 * static, not undecided) a unit vector (0 for res.t = 0), a static one 0,
 * an undecided one unit (or 0); rel_std never
 * negative or NaN; unconfirmed exactly when a cap ended the search below a
 * confidence of 0.5 (reasons other than static and undecided); the checks
 * of the consensus (res.consensus) ran only on an observable scale, which
 * they left observable or made MCG_SCALE_CONSENSUS, their std the
 * verdict's. A negative
 * or non-finite calibration std is MCG_EINVAL.
 * Bounded time: max_iterations <= 200 (<= 3 with the 6-point sampler,
 * whose solver takes about a second per sample under the sanitizers, <= 20
 * with the local one) and
 * max_seconds = 0.5 here, and
 * libFuzzer's timeout catches any loop that ignores them.
 */
#include "fuzz_input.h"
#include "mcgeom.h"

/* routines selected by the first input byte (fuzz/make_corpus.py writes
 * seeds for each) */
#define FUZZ_MODES 2

#define MAXN 64
#define MAXCAM 8

/* first[g]: 2 i + t of camera g's first ray (pair i, time t = 0 or 1), -1
 * for a camera without rays. */
static void first_rays(int n, const int *cam1, const int *cam2, int first[MAXCAM])
{
    int i, t;
    for (i = 0; i < MAXCAM; ++i)
        first[i] = -1;
    for (i = 0; i < n; ++i)
        for (t = 0; t < 2; ++t) {
            const int g = t ? cam2[i] : cam1[i];
            if (first[g] < 0)
                first[g] = 2 * i + t;
        }
}

/* the origin of ray j = 2 i + t */
static double *origin(double *o1, double *o2, int j)
{
    return ((j & 1) ? o2 : o1) + 3 * (j >> 1);
}

/* Every ray of a camera (at either time) takes the origin of that camera's
 * first ray: mode 1's arbitrary rays past the central samples' check. */
static void one_origin_per_camera(int n, const int *cam1, const int *cam2, double *o1,
                                  double *o2)
{
    int first[MAXCAM], j, k;
    first_rays(n, cam1, cam2, first);
    for (j = 0; j < 2 * n; ++j) {
        const double *ref = origin(o1, o2, first[(j & 1) ? cam2[j >> 1] : cam1[j >> 1]]);
        double *o = origin(o1, o2, j);
        for (k = 0; k < 3; ++k)
            o[k] = ref[k];
    }
}

/* 1 when every origin coordinate lies within 1e150 in magnitude (the
 * kernel refuses others: mcg_verdict_stats's bound) */
static int origins_within(int n, const double *o1, const double *o2)
{
    size_t k;
    for (k = 0; k < 3 * (size_t)n; ++k)
        if (!(fabs(o1[k]) <= 1e150 && fabs(o2[k]) <= 1e150))
            return 0;
    return 1;
}

/* 1 when every direction has a squared length of at least 1e-100 (the
 * kernel's test of a zero direction, MCG_EINVAL) */
static int directions_nonzero(int n, const double *d1, const double *d2)
{
    int k;
    for (k = 0; k < n; ++k) {
        const double *a = d1 + 3 * k, *b = d2 + 3 * k;
        if (!(a[0] * a[0] + a[1] * a[1] + a[2] * a[2] >= 1e-100) ||
            !(b[0] * b[0] + b[1] * b[1] + b[2] * b[2] >= 1e-100))
            return 0;
    }
    return 1;
}

/* Do the origins of each camera agree (the rule of mcg_robust_rig_motion:
 * within 1e-9 (1 + the largest |coordinate|) of its first ray's)? */
static int centres_agree(int n, const int *cam1, const int *cam2, double *o1, double *o2)
{
    int first[MAXCAM], j, k;
    double big = 0.0, tol;
    for (j = 0; j < 3 * n; ++j)
        big = fmax(big, fmax(fabs(o1[j]), fabs(o2[j])));
    tol = 1e-9 * (1.0 + big);
    first_rays(n, cam1, cam2, first);
    for (j = 0; j < 2 * n; ++j) {
        const double *ref = origin(o1, o2, first[(j & 1) ? cam2[j >> 1] : cam1[j >> 1]]);
        const double *o = origin(o1, o2, j);
        for (k = 0; k < 3; ++k)
            if (!(fabs(o[k] - ref[k]) <= tol))
                return 0;
    }
    return 1;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in = fz_make(data, size);
    int mode = fz_u8(&in) % FUZZ_MODES, valid, st, i, ncams, ids_ok = 1, opt_ok, f_ok = 1;
    int ext_ok = 1;
    int n = fz_size(&in, 6, MAXN, &valid), use_focal, use_table, short_work, cnt0, cnt1;
    static double o1[3 * MAXN], d1[3 * MAXN], o2[3 * MAXN], d2[3 * MAXN], res_chk[MAXN];
    static double focal[MAXN], axes[3 * MAXCAM], cfocal[MAXCAM], wts[MAXN], ext[2 * MAXCAM];
    static int cam1[MAXN], cam2[MAXN];
    static unsigned char mask[MAXN];
    double R[9], tt[3], *work;
    size_t lwork;
    mcg_robust_options opt;
    mcg_robust_result res;

    if (n == (1 << 21))
        n = (1 << 26) + 1; /* the limit is 2^26 pairs */
    ncams = fz_int(&in, 1, MAXCAM);
    if (!valid) {
        double w1[1];
        st = mcg_robust_rig_motion(n, o1, d1, o2, d2, cam1, cam2, ncams, NULL, NULL, NULL, NULL,
                                   &res, mask, NULL, w1, 1);
        FZ_CHECK(st == MCG_EINVAL, "robust_rig_motion(n = %d) returned %d", n, st);
        FZ_CHECK(mcg_robust_work_size(n, ncams) == 0, "work size of n = %d not 0", n);
        return 0;
    }
    if (mode == 0) {
        fz_rotation(&in, R);
        for (i = 0; i < 3; ++i)
            tt[i] = fz_range(&in, -2.0, 2.0);
        {
            const int cross = fz_u8(&in) & 1;
            fz_scene(&in, n, ncams, cross, R, tt, o1, d1, o2, d2, NULL);
            for (i = 0; i < n; ++i) { /* the pairing of fz_scene */
                cam1[i] = i % ncams;
                cam2[i] = cross && i % 4 == 3 ? (cam1[i] + 1) % ncams : cam1[i];
            }
        }
    } else {
        fz_rays(&in, (size_t)n, o1, d1, o2, d2);
        for (i = 0; i < n; ++i) {
            cam1[i] = fz_int(&in, 0, ncams - 1);
            cam2[i] = fz_u8(&in) % 4 == 0 ? fz_int(&in, 0, ncams - 1) : cam1[i];
        }
        if (fz_u8(&in) & 1) /* one origin per camera: past the central samples' check */
            one_origin_per_camera(n, cam1, cam2, o1, o2);
    }
    if (fz_u8(&in) % 16 == 0) {
        i = fz_int(&in, 0, n - 1);
        cam2[i] = fz_u8(&in) & 1 ? ncams : -1;
        ids_ok = 0;
    }
    use_focal = fz_u8(&in) & 1;
    use_table = use_focal && (fz_u8(&in) & 1);
    for (i = 0; use_focal && i < n; ++i) {
        focal[i] = fz_u8(&in) % 32 == 0 ? fz_double(&in) : fz_range(&in, 100.0, 2000.0);
        f_ok &= isfinite(focal[i]) && focal[i] > 0.0;
    }
    for (i = 0; use_table && i < ncams; ++i) {
        fz_doubles(&in, axes + 3 * i, 3);
        cfocal[i] = fz_range(&in, 100.0, 2000.0);
    }
    mcg_robust_default_options(&opt);
    opt.max_iterations = fz_int(&in, 1, 200);
    opt.min_iterations = fz_int(&in, 0, opt.max_iterations);
    opt.max_seconds = 0.5;
    opt.seed = fz_u64(&in);
    opt.lo_rounds = fz_int(&in, 0, 3);
    opt.refine = fz_u8(&in) & 1;
    opt.loss = fz_int(&in, 0, 3);
    opt.threshold = use_focal ? fz_range(&in, 0.1, 5.0) : fz_range(&in, 1e-5, 0.1);
    opt.prob = fz_range(&in, 0.5, 0.9999);
    opt.max_scale_rel_std = fz_u8(&in) & 1 ? fz_range(&in, 0.0, 0.5) : 0.0;
    opt_ok = 1;
    {
        const int sb = fz_u8(&in);
        opt.sampler = sb % 16 == 15 ? 7 + sb % 5 : sb % 7;
        if (opt.sampler == MCG_SAMPLER_UPRIGHT4) {
            if (mode == 0) { /* the true vertical: g2 = R g1 */
                double g[3];
                fz_doubles(&in, g, 3);
                for (i = 0; i < 3; ++i) {
                    opt.g1[i] = g[i];
                    opt.g2[i] = R[3 * i] * g[0] + R[3 * i + 1] * g[1] + R[3 * i + 2] * g[2];
                }
            } else {
                fz_doubles(&in, opt.g1, 3);
                fz_doubles(&in, opt.g2, 3);
            }
            opt_ok = fz_all_finite(opt.g1, 3) && fz_all_finite(opt.g2, 3) &&
                     opt.g1[0] * opt.g1[0] + opt.g1[1] * opt.g1[1] + opt.g1[2] * opt.g1[2] >=
                         1e-100 &&
                     opt.g2[0] * opt.g2[0] + opt.g2[1] * opt.g2[1] + opt.g2[2] * opt.g2[2] >=
                         1e-100;
        }
        opt_ok &= opt.sampler <= MCG_SAMPLER_6PT_LOCAL;
        /* (AUTO picks the 6-point sampler where no camera has 5 intra pairs) */
        if (opt.sampler == MCG_SAMPLER_6PT) {
            /* mcg_sixpt: ~1 s a sample here */
            opt.max_iterations = 1 + opt.max_iterations % 3;
            opt.min_iterations = opt.min_iterations % (opt.max_iterations + 1);
        } else if (opt.sampler == MCG_SAMPLER_6PT_LOCAL || opt.sampler == MCG_SAMPLER_AUTO) {
            /* mcg_sixpt_local: ~1 ms a sample, 20-50x that here, and 16
             * more samples to measure its rate of success */
            opt.max_iterations = 1 + opt.max_iterations % 20;
            opt.min_iterations = opt.min_iterations % (opt.max_iterations + 1);
        }
    }
    opt.verdict_still_factor = fz_u8(&in) & 1 ? fz_range(&in, 0.0, 10.0) : 0.0;
    if (fz_u8(&in) & 1) { /* the verdict's calibration table */
        for (i = 0; i < 2 * ncams; ++i) {
            ext[i] = fz_u8(&in) % 16 == 0 ? fz_double(&in) : fz_range(&in, 0.0, 0.01);
            ext_ok &= isfinite(ext[i]) && ext[i] >= 0.0;
        }
        opt.extrinsic_std = ext;
    }
    if (fz_u8(&in) % 16 == 0) {
        switch (fz_u8(&in) % 4) {
        case 0: opt.threshold = fz_double(&in); break;
        case 1: opt.prob = fz_double(&in); break;
        case 2: opt.min_iterations = opt.max_iterations + 1; break;
        default: opt.loss = 7; break;
        }
        opt_ok = opt_ok && isfinite(opt.threshold) && opt.threshold > 0.0 && opt.prob > 0.0 &&
                 opt.prob < 1.0 && opt.min_iterations <= opt.max_iterations && opt.loss <= 3;
    }
    lwork = mcg_robust_work_size(n, ncams);
    FZ_CHECK(lwork > 0, "work size 0 for n = %d, %d cameras", n, ncams);
    short_work = fz_u8(&in) % 16 == 0;
    work = fz_alloc(lwork - (size_t)short_work);
    st = mcg_robust_rig_motion(n, o1, d1, o2, d2, cam1, cam2, ncams, use_focal ? focal : NULL,
                               use_table ? axes : NULL, use_table ? cfocal : NULL, &opt, &res,
                               mask, wts, work, lwork - (size_t)short_work);
    free(work);
    FZ_CHECK(fz_status_known(st), "unknown status %d", st);
    if (!ids_ok || !opt_ok || !f_ok || !ext_ok ||
        (use_table && !fz_all_finite(axes, 3 * (size_t)ncams))) {
        FZ_CHECK(st == MCG_EINVAL, "bad ids/options/focal/axes/calibration gave status %d", st);
        return 0;
    }
    if (!fz_all_finite(o1, 3 * (size_t)n) || !fz_all_finite(d1, 3 * (size_t)n) ||
        !fz_all_finite(o2, 3 * (size_t)n) || !fz_all_finite(d2, 3 * (size_t)n)) {
        FZ_CHECK(st == MCG_EINVAL, "NaN/inf input gave status %d", st);
        return 0;
    }
    if (!origins_within(n, o1, o2)) {
        FZ_CHECK(st == MCG_EINVAL, "an origin beyond 1e150 gave status %d", st);
        return 0;
    }
    if (!directions_nonzero(n, d1, d2)) {
        FZ_CHECK(st == MCG_EINVAL, "a zero direction gave status %d", st);
        return 0;
    }
    if (short_work && st != MCG_EINVAL) {
        FZ_CHECK(st == MCG_ENOMEM, "short workspace gave status %d", st);
        return 0;
    }
    if (opt.sampler == MCG_SAMPLER_5P1 && !centres_agree(n, cam1, cam2, o1, o2)) {
        FZ_CHECK(st == MCG_EINVAL, "5+1 with a camera of several origins gave status %d", st);
        return 0;
    }
    if ((opt.sampler == MCG_SAMPLER_EIGEN || opt.sampler == MCG_SAMPLER_LINEAR17) && n < 17) {
        FZ_CHECK(st == MCG_EDEGENERATE, "17-pair sampler %d on %d < 17 pairs gave status %d",
                 opt.sampler, n, st);
        return 0;
    }
    if (st != MCG_OK)
        return 0;
    FZ_CHECK(fz_is_rotation(res.R, 1e-9), "R not a rotation (orthogonality error %g)",
             fz_orth_err3(res.R));
    FZ_CHECK(fz_all_finite(res.t, 3), "t not finite");
    FZ_CHECK(res.iterations >= 1 && res.iterations <= opt.max_iterations,
             "iterations %d outside [1, %d]", res.iterations, opt.max_iterations);
    FZ_CHECK(res.confidence >= 0.0 && res.confidence <= 1.0,
             "confidence %g outside [0, 1]", res.confidence);
    FZ_CHECK(res.seconds_rays == 0.0 && res.seconds_search >= 0.0 && res.seconds_final >= 0.0 &&
                 res.seconds_verdict >= 0.0 && (opt.verdict_still_factor > 0.0 ||
                                                res.seconds_verdict == 0.0) &&
                 fabs(res.seconds_search + res.seconds_final + res.seconds_verdict -
                      res.seconds) <= 1e-9,
             "stage times %g + %g + %g (rays %g) against seconds %g", res.seconds_search,
             res.seconds_final, res.seconds_verdict, res.seconds_rays, res.seconds);
    st = mcg_gec_residuals(n, o1, d1, o2, d2, res.R, res.t, res_chk);
    FZ_CHECK(st == MCG_OK, "residuals at the result: status %d", st);
    cnt0 = cnt1 = 0;
    for (i = 0; i < n; ++i) {
        double r = fabs(res_chk[i]) * (use_focal ? focal[i] : 1.0);
        int in_mask = mask[i] & 1;
        cnt0 += in_mask;
        cnt1 += (mask[i] >> 1) & 1;
        FZ_CHECK(in_mask == (r < opt.threshold) ||
                     fabs(r - opt.threshold) <= 1e-9 * opt.threshold,
                 "mask bit 0 of pair %d is %d but |r| = %.17g vs threshold %.17g", i, in_mask,
                 r, opt.threshold);
    }
    FZ_CHECK(cnt0 == res.n_inliers, "n_inliers %d, mask bit 0 set %d times", res.n_inliers,
             cnt0);
    FZ_CHECK(!res.refined || cnt1 == res.n_used, "n_used %d, mask bit 1 set %d times",
             res.n_used, cnt1);
    FZ_CHECK(isnan(res.scale_profile) || res.scale_profile >= 0.0,
             "scale profile %g is negative", res.scale_profile);
    FZ_CHECK(res.sampler >= MCG_SAMPLER_5P1 && res.sampler <= MCG_SAMPLER_6PT_LOCAL &&
                 res.sampler != MCG_SAMPLER_AUTO &&
                 (opt.sampler == MCG_SAMPLER_AUTO
                      ? res.sampler == MCG_SAMPLER_5P1 || res.sampler == MCG_SAMPLER_6PT_LOCAL
                      : res.sampler == opt.sampler),
             "sampler used %d for the option %d", res.sampler, opt.sampler);
    /* the local 6-point solver's measured rate of success: in (0, 1), 1 for
     * the complete solvers */
    FZ_CHECK(res.sampler == MCG_SAMPLER_6PT_LOCAL
                 ? res.found_rate > 0.0 && res.found_rate <= 1.0
                 : res.found_rate == 1.0,
             "found_rate %g with sampler %d", res.found_rate, res.sampler);
    /* the verdict's evidence (asked for, n <= 2^20 here): over the inliers */
    FZ_CHECK((opt.verdict_still_factor > 0.0) == (res.have_verdict != 0),
             "verdict evidence %d with factor %g", res.have_verdict, opt.verdict_still_factor);
    FZ_CHECK(!res.have_verdict || (res.verdict.n_inliers == res.n_inliers &&
                                   res.verdict.n_in_front <= res.n_inliers),
             "verdict counts %d inliers (%d in front), the mask %d", res.verdict.n_inliers,
             res.verdict.n_in_front, res.n_inliers);
    /* the scale verdict */
    FZ_CHECK(res.have_scale == (opt.verdict_still_factor > 0.0) &&
                 (!res.have_scale || res.have_verdict || res.scale.reason == MCG_SCALE_UNDECIDED),
             "verdict %d (reason %d) with evidence %d, factor %g", res.have_scale,
             res.scale.reason, res.have_verdict, opt.verdict_still_factor);
    if (res.have_scale) {
        const mcg_robust_scale *v = &res.scale;
        const double nt = sqrt(v->t[0] * v->t[0] + v->t[1] * v->t[1] + v->t[2] * v->t[2]);
        FZ_CHECK(v->reason >= MCG_SCALE_OBSERVABLE && v->reason <= MCG_SCALE_CONSENSUS,
                 "scale reason %d", v->reason);
        /* the checks of the consensus: run on an observable scale, their
         * refusal the verdict's reason, their std the verdict's */
        FZ_CHECK(res.have_consensus
                     ? (res.consensus.reason == MCG_CONSENSUS_METRIC
                            ? v->reason == MCG_SCALE_OBSERVABLE
                            : v->reason == MCG_SCALE_CONSENSUS) &&
                           v->rel_std == res.consensus.rel_std
                     : v->reason != MCG_SCALE_CONSENSUS,
                 "consensus %d (reason %d, std %g) with scale reason %d, std %g",
                 res.have_consensus, res.consensus.reason, res.consensus.rel_std, v->reason,
                 v->rel_std);
        FZ_CHECK(v->observable == (v->reason == MCG_SCALE_OBSERVABLE),
                 "observable %d with reason %d", v->observable, v->reason);
        FZ_CHECK(!v->observable || (v->determined && v->rel_std <= opt.max_scale_rel_std),
                 "observable with determined %d, rel_std %g", v->determined, v->rel_std);
        FZ_CHECK(!(v->rel_std < 0.0) && !isnan(v->rel_std), "rel_std %g", v->rel_std);
        FZ_CHECK((v->reason == MCG_SCALE_STATIC) == (!v->translation_detected &&
                                                      v->reason != MCG_SCALE_UNDECIDED),
                 "static reason %d, translation detected %d", v->reason,
                 v->translation_detected);
        if (v->reason == MCG_SCALE_STATIC)
            FZ_CHECK(nt == 0.0, "static verdict with |t| %g", nt);
        else if (v->reason == MCG_SCALE_UNDECIDED) /* never metric-looking */
            FZ_CHECK(fabs(nt - 1.0) <= 1e-9 || nt == 0.0, "undecided t of length %.17g", nt);
        else if (v->determined)
            FZ_CHECK(memcmp(v->t, res.t, sizeof res.t) == 0, "determined t is not res.t");
        else if (v->reason != MCG_SCALE_UNDECIDED) /* (the travel direction of t = 0 is 0) */
            FZ_CHECK(fabs(nt - 1.0) <= 1e-9 || (nt == 0.0 && res.t[0] == 0.0 && res.t[1] == 0.0 &&
                                                res.t[2] == 0.0),
                     "undetermined t of length %.17g", nt);
        if (v->reason != MCG_SCALE_STATIC && v->reason != MCG_SCALE_UNDECIDED)
            FZ_CHECK((v->reason == MCG_SCALE_UNCONFIRMED) ==
                         (res.stop != MCG_ROBUST_STOP_CONFIDENCE && !(res.confidence >= 0.5)),
                     "reason %d with stop %d and confidence %g", v->reason, res.stop,
                     res.confidence);
    }
    /* the covariance: finite, or HUGE_VAL everywhere (no SPD information) */
    {
        int n_huge = 0, n_fin = 0;
        for (i = 0; i < 36; ++i) {
            n_huge += res.covariance[i] == HUGE_VAL;
            n_fin += isfinite(res.covariance[i]) != 0;
        }
        FZ_CHECK(n_fin == 36 || n_huge == 36, "covariance: %d finite, %d HUGE_VAL entries",
                 n_fin, n_huge);
    }
    return 0;
}
