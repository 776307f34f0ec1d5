/*
 * fuzz_upright4.c -- libFuzzer harness of mcg_upright4, the minimal
 * generalized relative pose with a known vertical direction.
 *
 * Inputs: mode 0 a synthetic rig scene of 4 pairs (1-4 cameras, intra- or
 * cross-camera, fz_scene's noise and replaced entries) with the gravity of
 * frame 2 consistent with the motion (R g1) or perturbed; mode 1 arbitrary
 * rays and gravity vectors. Invariants: NaN/inf or zero-length inputs give
 * MCG_EINVAL, the status is always a known one; on MCG_OK 0 <= n <= 8 and
 * every solution is finite, a rotation (orthonormal, det +1) and maps the
 * unit g1 onto the unit g2 (the constraint that defines the solver).
 * Modes 2 and 3: the same for the central 3-point solver of upright4.c
 * (mcg_upright3_central, internal.h; robust_sample_5p1.c's upright 3+1 samples) on a
 * one-camera scene (3 intra-camera pairs) and on arbitrary bearings: on
 * MCG_OK 0 <= n <= 6, each rotation maps g1 onto g2 and each direction is
 * finite and of unit length.
 */
#include "fuzz_input.h"
#include "mcgeom.h"
#include "internal.h"

/* routines selected by the first input byte (fuzz/make_corpus.py writes
 * seeds for each) */
#define FUZZ_MODES 4

/* Solution s (rotation R) of `who`: a rotation mapping the unit g1 onto
 * the unit g2 (|g1|, |g2| = n1, n2: the constraint of both solvers). */
static void check_vertical(const char *who, int s, const double R[9], const double g1[3],
                           const double g2[3], double n1, double n2)
{
    double Rg[3], e = 0.0;
    int i;
    FZ_CHECK(fz_is_rotation(R, 1e-9), "%s: solution %d not a rotation (%g)", who, s,
             fz_orth_err3(R));
    for (i = 0; i < 3; ++i)
        Rg[i] = (R[3 * i] * g1[0] + R[3 * i + 1] * g1[1] + R[3 * i + 2] * g1[2]) / n1;
    for (i = 0; i < 3; ++i)
        e = fmax(e, fabs(Rg[i] - g2[i] / n2));
    FZ_CHECK(e < 1e-9, "%s: solution %d maps g1 off g2 by %g", who, s, e);
}

/* The status checks of both solvers: MCG_EINVAL exactly for non-finite
 * input (inputs_finite 0) or a zero vertical, at most max_n solutions; 1
 * when the solutions are to be checked, with n1, n2 = |g1|, |g2| (not for
 * an overflowing |g|^2: the unit vertical would be 0). */
static int solutions_to_check(const char *who, int st, int inputs_finite, const double g1[3],
                              const double g2[3], int n, int max_n, double *n1, double *n2)
{
    const double a = fz_dot3(g1, g1), b = fz_dot3(g2, g2);
    if (!inputs_finite || !(a >= 1e-100 && b >= 1e-100)) {
        FZ_CHECK(st == MCG_EINVAL, "%s of non-finite input or a zero vertical: %d", who, st);
        return 0;
    }
    if (st != MCG_OK)
        return 0;
    FZ_CHECK(n >= 0 && n <= max_n, "%s: %d solutions", who, n);
    if (!isfinite(a) || !isfinite(b))
        return 0;
    *n1 = sqrt(a);
    *n2 = sqrt(b);
    return 1;
}

/* The central solver (modes 2 and 3): its invariants, as above. */
static int central(fz_in *in, int mode)
{
    double o1[9], d1[9], o2[9], d2[9], g1[3], g2[3], Rm[9], t[3], Rs[54], us[18], n1, n2;
    int st, n = -1, s, i;
    if (mode == 2) {
        fz_rotation(in, Rm);
        for (i = 0; i < 3; ++i)
            t[i] = fz_range(in, -2.0, 2.0);
        fz_scene(in, 3, 1, 0, Rm, t, o1, d1, o2, d2, NULL);
        for (i = 0; i < 3; ++i)
            g1[i] = fz_range(in, -1.0, 1.0);
        for (i = 0; i < 3; ++i)
            g2[i] = Rm[3 * i] * g1[0] + Rm[3 * i + 1] * g1[1] + Rm[3 * i + 2] * g1[2];
    } else {
        fz_doubles(in, d1, 9);
        fz_doubles(in, d2, 9);
        fz_doubles(in, g1, 3);
        fz_doubles(in, g2, 3);
    }
    st = mcg_upright3_central(d1, d2, g1, g2, Rs, us, &n);
    FZ_CHECK(st == MCG_OK || st == MCG_EINVAL || st == MCG_EDEGENERATE,
             "upright3_central status %d", st);
    if (!solutions_to_check("upright3_central", st,
                            fz_all_finite(d1, 9) && fz_all_finite(d2, 9) &&
                                fz_all_finite(g1, 3) && fz_all_finite(g2, 3),
                            g1, g2, n, MCG_UPRIGHT3_MAX_SOLUTIONS, &n1, &n2))
        return 0;
    for (s = 0; s < n; ++s) {
        const double *u = us + 3 * s;
        FZ_CHECK(fz_all_finite(Rs + 9 * s, 9) && fz_all_finite(u, 3),
                 "upright3_central: solution %d not finite", s);
        FZ_CHECK(fabs(fz_dot3(u, u) - 1.0) < 1e-9, "upright3_central: |u| of %d is %g", s,
                 sqrt(fz_dot3(u, u)));
        check_vertical("upright3_central", s, Rs + 9 * s, g1, g2, n1, n2);
    }
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in = fz_make(data, size);
    int mode = fz_u8(&in) % FUZZ_MODES, st, n = -1, s, i;
    double o1[12], d1[12], o2[12], d2[12], g1[3], g2[3], Rm[9], t[3], Rs[72], ts[24];
    double n1, n2;
    if (mode >= 2)
        return central(&in, mode);
    if (mode == 0) {
        fz_rotation(&in, Rm);
        for (i = 0; i < 3; ++i)
            t[i] = fz_range(&in, -2.0, 2.0);
        {   /* decoded in this order (not as arguments of one call) */
            const int ncams = fz_int(&in, 1, 4), cross = fz_u8(&in) & 1;
            fz_scene(&in, 4, ncams, cross, Rm, t, o1, d1, o2, d2, NULL);
        }
        for (i = 0; i < 3; ++i)
            g1[i] = fz_range(&in, -1.0, 1.0);
        for (i = 0; i < 3; ++i)
            g2[i] = Rm[3 * i] * g1[0] + Rm[3 * i + 1] * g1[1] + Rm[3 * i + 2] * g1[2];
        if (fz_u8(&in) % 4 == 0)
            g2[fz_u8(&in) % 3] += fz_double(&in);
    } else {
        fz_rays(&in, 4, o1, d1, o2, d2);
        fz_doubles(&in, g1, 3);
        fz_doubles(&in, g2, 3);
    }
    st = mcg_upright4(o1, d1, o2, d2, g1, g2, Rs, ts, &n);
    FZ_CHECK(fz_status_known(st), "upright4 status %d", st);
    if (!solutions_to_check("upright4", st,
                            fz_all_finite(o1, 12) && fz_all_finite(d1, 12) &&
                                fz_all_finite(o2, 12) && fz_all_finite(d2, 12) &&
                                fz_all_finite(g1, 3) && fz_all_finite(g2, 3),
                            g1, g2, n, MCG_UPRIGHT4_MAX_SOLUTIONS, &n1, &n2))
        return 0;
    for (s = 0; s < n; ++s) {
        FZ_CHECK(fz_all_finite(Rs + 9 * s, 9) && fz_all_finite(ts + 3 * s, 3),
                 "upright4: solution %d not finite", s);
        check_vertical("upright4", s, Rs + 9 * s, g1, g2, n1, n2);
    }
    return 0;
}
