/*
 * fuzz_sixpt.c -- libFuzzer harness of mcg_sixpt, the generic minimal
 * 6-point generalized relative pose, and of mcg_sixpt_local, its local
 * search (same input, same invariants, the same status).
 *
 * Inputs: mode 0 a synthetic rig scene of 6 pairs (1-6 cameras, intra- or
 * cross-camera, fz_scene's noise and replaced entries); mode 1 arbitrary
 * rays. Invariants: NaN/inf or zero-length directions give MCG_EINVAL, the
 * status is always a known one; on MCG_OK 0 <= n <= 64 and every solution is
 * finite and a rotation (orthonormal, det +1); for an exact scene every
 * solution satisfies the six generalized epipolar constraints (triple
 * product (R d1 x d2) . (t + R o1 - o2) over |d1| |d2| and the rig's size)
 * to 1e-8, and a scene of more than one camera contains the true motion
 * unless its data are ill-conditioned (not asserted: a homotopy path may
 * fail there).
 */
#include "fuzz_input.h"
#include "mcgeom.h"

/* routines selected by the first input byte (fuzz/make_corpus.py writes
 * seeds for each) */
#define FUZZ_MODES 2

/* the invariants of n solutions (Rs, ts) of the solver `who` (at most max) */
static void check_solutions(const char *who, const double *Rs, const double *ts, int n, int max,
                            int exact, const double *o1, const double *d1, const double *o2,
                            const double *d2)
{
    int s, i, k;
    FZ_CHECK(n >= 0 && n <= max, "%s: %d solutions", who, n);
    for (s = 0; s < n; ++s) {
        const double *R = Rs + 9 * s, *tt = ts + 3 * s;
        FZ_CHECK(fz_all_finite(R, 9) && fz_all_finite(tt, 3), "%s: solution %d not finite", who,
                 s);
        FZ_CHECK(fz_is_rotation(R, 1e-9), "%s: solution %d not a rotation (%g)", who, s,
                 fz_orth_err3(R));
        if (exact) {
            double size = 1.0, worst = 0.0;
            for (i = 0; i < 18; ++i)
                size = fmax(size, fmax(fabs(o1[i]), fabs(o2[i])));
            for (k = 0; k < 6; ++k) {
                const double *a = d1 + 3 * k, *b = d2 + 3 * k, *p = o1 + 3 * k, *q = o2 + 3 * k;
                double Ra[3], Rp[3], c[3], base[3];
                for (i = 0; i < 3; ++i) {
                    Ra[i] = R[3 * i] * a[0] + R[3 * i + 1] * a[1] + R[3 * i + 2] * a[2];
                    Rp[i] = R[3 * i] * p[0] + R[3 * i + 1] * p[1] + R[3 * i + 2] * p[2];
                }
                c[0] = Ra[1] * b[2] - Ra[2] * b[1];
                c[1] = Ra[2] * b[0] - Ra[0] * b[2];
                c[2] = Ra[0] * b[1] - Ra[1] * b[0];
                for (i = 0; i < 3; ++i)
                    base[i] = tt[i] + Rp[i] - q[i];
                worst = fmax(worst, fabs(fz_dot3(c, base)) /
                                        sqrt(fz_dot3(a, a) * fz_dot3(b, b)));
            }
            worst /= size + sqrt(fz_dot3(tt, tt));
            FZ_CHECK(worst <= 1e-8, "%s: solution %d GEC residual %g", who, s, worst);
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in = fz_make(data, size);
    int mode = fz_u8(&in) % FUZZ_MODES, st, stl, n = -1, nl = -1, i, k, exact = 0;
    double o1[18], d1[18], o2[18], d2[18], Rm[9], t[3];
    static double Rs[9 * MCG_SIXPT_MAX_SOLUTIONS], ts[3 * MCG_SIXPT_MAX_SOLUTIONS];
    static double Rl[9 * MCG_SIXPT_LOCAL_MAX_SOLUTIONS], tl[3 * MCG_SIXPT_LOCAL_MAX_SOLUTIONS];
    if (mode == 0) {
        fz_rotation(&in, Rm);
        for (i = 0; i < 3; ++i)
            t[i] = fz_range(&in, -2.0, 2.0);
        {   /* decoded in this order (not as arguments of one call) */
            const int ncams = fz_int(&in, 1, 6), cross = fz_u8(&in) & 1;
            exact = fz_scene(&in, 6, ncams, cross, Rm, t, o1, d1, o2, d2, NULL);
        }
    } else {
        fz_rays(&in, 6, o1, d1, o2, d2);
        fz_rotation(&in, Rm);
    }
    st = mcg_sixpt(o1, d1, o2, d2, Rs, ts, &n);
    /* the local search, from the scene's rotation as its extra start (mode
     * 0) or from a decoded one */
    stl = mcg_sixpt_local(o1, d1, o2, d2, Rm, Rl, tl, &nl);
    FZ_CHECK(fz_status_known(st), "sixpt status %d", st);
    FZ_CHECK(stl == st, "sixpt_local status %d where sixpt's is %d", stl, st);
    if (!fz_all_finite(o1, 18) || !fz_all_finite(d1, 18) || !fz_all_finite(o2, 18) ||
        !fz_all_finite(d2, 18)) {
        FZ_CHECK(st == MCG_EINVAL, "sixpt of non-finite input: %d", st);
        return 0;
    }
    for (k = 0; k < 6; ++k)
        if (!(fz_dot3(d1 + 3 * k, d1 + 3 * k) >= 1e-100 &&
              fz_dot3(d2 + 3 * k, d2 + 3 * k) >= 1e-100)) {
            FZ_CHECK(st == MCG_EINVAL, "sixpt with a zero direction: %d", st);
            return 0;
        }
    if (st != MCG_OK)
        return 0;
    check_solutions("sixpt", Rs, ts, n, MCG_SIXPT_MAX_SOLUTIONS, exact, o1, d1, o2, d2);
    check_solutions("sixpt_local", Rl, tl, nl, MCG_SIXPT_LOCAL_MAX_SOLUTIONS, exact, o1, d1, o2,
                    d2);
    return 0;
}
