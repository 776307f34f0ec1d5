/*
 * fuzz_bnb.c -- libFuzzer harness of mcg_bnb_linf, the globally optimal
 * L-infinity rig motion by branch and bound over angle-axis cubes (thesis
 * ch. 10, Algorithm 7), with small decoded budgets (max_blocks <= 300, a
 * small queue, coarse resolution) so that one input runs in milliseconds,
 * both LP backends, and the local search options.
 *
 * Inputs: mode 0 a synthetic rig scene (1-6 cameras, intra- and cross-camera
 * pairs, groups from the cameras), mode 1 arbitrary arrays and groups.
 * Invariants: bad sizes, groups out of range, NaN/inf, zero bearings, bad
 * options give MCG_EINVAL (work size 0 for bad sizes/options); a short
 * workspace MCG_ENOMEM; on MCG_OK R is a rotation, t finite,
 * 0 <= lower_bound <= linf <= initial_linf (to the LP tolerances),
 * gap = linf - lower_bound, blocks <= max_blocks, stop one of
 * MCG_BNB_*, counters >= 0; on exact data (a zero-error motion exists) the
 * certified lower bound is ~0 and, when the search converged over all
 * rotations, linf is within the resolution's reach of 0.
 */
#include "fuzz_input.h"
#include "mcgeom.h"

/* routines selected by the first input byte (fuzz/make_corpus.py writes
 * seeds for each) */
#define FUZZ_MODES 2

#define MAXN 32

static int glpk_ok = 0;

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    glpk_ok = mcg_lp_glpk_load(NULL) == MCG_OK;
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in = fz_make(data, size);
    int mode = fz_u8(&in) % FUZZ_MODES, valid, st, i, exact = 0, ng, short_work;
    int n = fz_size(&in, 1, MAXN, &valid);
    static double d1[3 * MAXN], a1[3 * MAXN], d2[3 * MAXN], a2[3 * MAXN];
    int group[MAXN];
    double R[9], t[3], Rinit[9], *work;
    mcg_bnb_options opt;
    mcg_bnb_result res;
    mcg_lp_backend be;
    size_t ws;
    mcg_bnb_default_options(&opt);
    /* small budgets, always; sometimes any value of one option */
    opt.max_blocks = fz_int(&in, 0, 300);
    opt.max_queue = fz_int(&in, 1, 2000);
    opt.grid = fz_int(&in, 1, 5);
    opt.resolution = fz_range(&in, 0.01, 0.9);
    opt.tol = fz_range(&in, 1e-9, 1e-3);
    opt.preemptive = fz_u8(&in) & 1;
    opt.working_sets = fz_u8(&in) & 1;
    opt.polish_tol = (fz_u8(&in) & 1) ? fz_range(&in, 1e-9, 1e-4) : 0.0;
    opt.bound_steps = fz_int(&in, 0, 3);
    opt.gap = (fz_u8(&in) & 3) == 0 ? fz_range(&in, 0.0, 0.1) : 0.0;
    if (fz_u8(&in) & 1) { /* a local search around a decoded centre */
        for (i = 0; i < 3; ++i)
            opt.centre[i] = fz_range(&in, -1.0, 1.0);
        opt.half_side = fz_range(&in, 0.001, 0.5);
    }
    if ((fz_u8(&in) & 1) && glpk_ok && mcg_lp_glpk_backend(&be) == MCG_OK)
        opt.lp = &be;
    if ((fz_u8(&in) % 16) == 0) { /* one option at an arbitrary value */
        switch (fz_u8(&in) % 8) {
        case 0: opt.resolution = fz_double(&in); break;
        case 1: opt.gap = fz_double(&in); break;
        case 2: opt.tol = fz_double(&in); break;
        case 3: opt.max_blocks = (long)(int16_t)fz_u16(&in); break;
        case 4: opt.max_queue = (int)(int16_t)fz_u16(&in); break;
        case 5: opt.grid = (int)(int8_t)fz_u8(&in); break;
        case 6: opt.polish_tol = fz_double(&in); break;
        default: opt.half_side = fz_double(&in); break;
        }
    }
    ng = fz_size(&in, 1, 8, NULL);
    short_work = (fz_u8(&in) % 32) == 0;
    ws = mcg_bnb_work_size(n, ng, &opt);
    if (!valid) {
        FZ_CHECK(ws == 0, "bnb work size %zu for n = %d", ws, n);
        work = fz_alloc(16);
        st = mcg_bnb_linf(n, d1, a1, d2, a2, group, ng, R, &opt, &res, work, 16);
        free(work);
        FZ_CHECK(st == MCG_EINVAL, "bnb(n = %d) returned %d", n, st);
        return 0;
    }
    if (ws == 0) { /* invalid options or n_groups */
        double w1[16];
        st = mcg_bnb_linf(n, d1, a1, d2, a2, group, ng, R, &opt, &res, w1, 16);
        FZ_CHECK(st == MCG_EINVAL, "bnb: work size 0 but status %d", st);
        return 0;
    }
    if (ws > ((size_t)1 << 24))
        return 0; /* a large queue: beyond what one fuzz input may allocate */
    if (mode == 0) {
        int ncams = ng < 1 ? 1 : ng > 6 ? 6 : ng;
        fz_rotation(&in, R);
        for (i = 0; i < 3; ++i)
            t[i] = fz_range(&in, -1.0, 1.0);
        /* the wedge apexes: origins a1 (time 1) and a2 (time 2) */
        exact = fz_scene(&in, n, ncams, 0, R, t, a1, d1, a2, d2, group);
        for (i = 0; i < n; ++i)
            if (group[i] >= ng)
                group[i] = ng - 1;
    } else {
        fz_matrix(&in, d1, (size_t)n, 3);
        fz_matrix(&in, a1, (size_t)n, 3);
        fz_matrix(&in, d2, (size_t)n, 3);
        fz_matrix(&in, a2, (size_t)n, 3);
        for (i = 0; i < n; ++i)
            group[i] = (int)(int8_t)fz_u8(&in) % (ng + 1);
    }
    if (fz_u8(&in) & 1)
        fz_rotation(&in, Rinit);
    else
        fz_doubles(&in, Rinit, 9);
    work = fz_alloc(short_work ? ws - 1 : ws);
    st = mcg_bnb_linf(n, d1, a1, d2, a2, group, ng, Rinit, &opt, &res, work,
                      short_work ? ws - 1 : ws);
    free(work);
    FZ_CHECK(fz_status_known(st), "bnb status %d", st);
    if (!fz_all_finite(d1, 3 * (size_t)n) || !fz_all_finite(a1, 3 * (size_t)n) ||
        !fz_all_finite(d2, 3 * (size_t)n) || !fz_all_finite(a2, 3 * (size_t)n) ||
        !fz_all_finite(Rinit, 9)) {
        FZ_CHECK(st == MCG_EINVAL || (short_work && st == MCG_ENOMEM), "bnb of non-finite input: %d", st);
        return 0;
    }
    for (i = 0; i < n; ++i)
        if (group[i] < 0 || group[i] >= ng)
            FZ_CHECK(st == MCG_EINVAL || (short_work && st == MCG_ENOMEM), "bnb accepted group %d of %d: %d", group[i], ng, st);
    if (short_work)
        FZ_CHECK(st == MCG_ENOMEM || st == MCG_EINVAL, "bnb with short work: %d", st);
    if (st != MCG_OK)
        return 0;
    FZ_CHECK(fz_is_rotation(res.R, 1e-9), "bnb: R not a rotation (%g)", fz_orth_err3(res.R));
    FZ_CHECK(fz_all_finite(res.t, 3), "bnb: non-finite t");
    FZ_CHECK(isfinite(res.linf) && isfinite(res.initial_linf) && isfinite(res.lower_bound),
             "bnb: non-finite bounds");
    FZ_CHECK(res.lower_bound >= 0.0 && res.lower_bound <= res.linf + 1e-7,
             "bnb: lower_bound %.17g > linf %.17g", res.lower_bound, res.linf);
    FZ_CHECK(res.linf <= res.initial_linf + 1e-7, "bnb: linf %.17g > initial %.17g", res.linf,
             res.initial_linf);
    FZ_CHECK(fabs(res.gap - (res.linf - res.lower_bound)) <= 1e-12,
             "bnb: gap %g != linf - lower_bound", res.gap);
    FZ_CHECK(res.stop >= MCG_BNB_CONVERGED && res.stop <= MCG_BNB_QUEUE_FULL, "bnb: stop %d",
             res.stop);
    FZ_CHECK(res.blocks >= 0 && res.blocks <= opt.max_blocks + 1, "bnb: %ld blocks of %ld",
             res.blocks, opt.max_blocks);
    FZ_CHECK(res.queued >= 0 && res.lps_2var >= 0 && res.lps_3var >= 0 && res.hints >= 0 &&
                 res.leaves >= 0 && res.polish_tests >= 0 && res.undecided >= 0 &&
                 res.seconds >= 0.0,
             "bnb: negative counters");
    if (exact && opt.half_side == 0.0 && res.undecided == 0)
        FZ_CHECK(res.lower_bound <= 1e-6, "bnb: exact data but certified lower bound %g",
                 res.lower_bound);
    return 0;
}
