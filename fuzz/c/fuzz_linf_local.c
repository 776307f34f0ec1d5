/*
 * fuzz_linf_local.c -- libFuzzer harness of mcg_linf_local (csrc/internal.h,
 * not public: the polish of mcg_bnb_linf), the trust-region sequential LP
 * (Madsen) minimising the L-infinity error of the closed-form
 * per-correspondence errors over (R, t), thesis ch. 10.
 *
 * Its contract is internal: the caller (bnb.c) has validated the rays and
 * passes UNIT bearings u1, u2 and 9 n doubles of work, so the harness does
 * the same (bearings normalised, zero or non-finite ones replaced), and
 * fuzzes what the function checks itself: n, R, t, delta0, delta_min,
 * max_steps. Invariants: bad arguments give MCG_EINVAL and leave R, t
 * alone; on MCG_OK from a rotation R stays a rotation, t finite, f_out finite in [0, 1]
 * (a maximum of sines), steps in [0, max_steps], and the maximum never
 * increases (f_out <= the value at the start, from a max_steps = 0 call).
 */
#include "fuzz_input.h"
#include "mcgeom.h"
#include "internal.h"

/* routines selected by the first input byte (fuzz/make_corpus.py writes
 * seeds for each): one, this harness reads no selector byte */
#define FUZZ_MODES 1

#define MAXN 32

static void unit_rows(double *u, int n)
{
    int k;
    for (k = 0; k < n; ++k) {
        double *v = u + 3 * k, s = fz_maxabs(v, 3), l;
        if (!(s > 0.0) || !isfinite(s)) {
            v[0] = 0.0;
            v[1] = 0.0;
            v[2] = 1.0;
            continue;
        }
        v[0] /= s;
        v[1] /= s;
        v[2] /= s;
        l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        v[0] /= l;
        v[1] /= l;
        v[2] /= l;
    }
}

static void finite_rows(double *a, int n)
{
    int k;
    for (k = 0; k < 3 * n; ++k)
        if (!isfinite(a[k]) || fabs(a[k]) > 1e6)
            a[k] = 0.0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in = fz_make(data, size);
    int valid, st, i, steps = -1, steps0 = -1, max_steps;
    int n = fz_size(&in, 1, MAXN, &valid);
    static double u1[3 * MAXN], a1[3 * MAXN], u2[3 * MAXN], a2[3 * MAXN];
    double Rt[9], tt[3], R[9], t[3], R0[9], t0[3], *work, f = NAN, f0 = NAN, delta0, delta_min;
    if (!valid && n > 0)
        n = -5; /* no upper limit here: the caller's workspace bounds n (bnb.c
                   checks n), so only n < 1 must be rejected */
    if (!valid) {
        double w[9];
        st = mcg_linf_local(n, u1, a1, u2, a2, R, t, 1.0, 0.1, 5, w, &f, &steps);
        FZ_CHECK(st == MCG_EINVAL, "linf_local(n = %d) returned %d", n, st);
        return 0;
    }
    fz_rotation(&in, Rt);
    for (i = 0; i < 3; ++i)
        tt[i] = fz_range(&in, -1.0, 1.0);
    {   /* decoded in this order (arguments of one call would be evaluated in
         * an order that depends on the compiler) */
        const int ncams = fz_int(&in, 1, 6), cross = fz_u8(&in) & 1;
        fz_scene(&in, n, ncams, cross, Rt, tt, a1, u1, a2, u2, NULL);
    }
    finite_rows(a1, n);
    finite_rows(a2, n);
    unit_rows(u1, n);
    unit_rows(u2, n);
    if (fz_u8(&in) % 8 == 0) { /* any start: the function checks R, t itself */
        fz_doubles(&in, R, 9);
        fz_doubles(&in, t, 3);
    } else { /* the truth moved a little, as the block centre of bnb.c */
        double dw[3], Rd[9];
        for (i = 0; i < 3; ++i)
            dw[i] = fz_range(&in, -0.05, 0.05);
        mcg_rot_from_angle_axis(dw, Rd);
        fz_matmul3(Rd, Rt, R);
        for (i = 0; i < 3; ++i)
            t[i] = tt[i] + fz_range(&in, -0.05, 0.05);
    }
    if (fz_u8(&in) % 16 == 0) {
        delta0 = fz_double(&in);
        delta_min = fz_double(&in);
        max_steps = fz_int(&in, -2, 50);
    } else {
        delta0 = fz_range(&in, 1e-6, 0.5);
        delta_min = delta0 * fz_range(&in, 1e-9, 1.0);
        max_steps = fz_int(&in, 0, 60);
    }
    work = fz_alloc(9 * (size_t)n);
    memcpy(R0, R, sizeof R);
    memcpy(t0, t, sizeof t);
    st = mcg_linf_local(n, u1, a1, u2, a2, R0, t0, delta0, delta_min, 0, work, &f0, &steps0);
    FZ_CHECK(st == MCG_OK || st == MCG_EINVAL, "linf_local status %d", st);
    if (!fz_all_finite(R, 9) || !fz_all_finite(t, 3) || !(delta0 > 0.0) || !isfinite(delta0) ||
        !(delta_min > 0.0) || !(delta_min <= delta0))
        FZ_CHECK(st == MCG_EINVAL, "linf_local accepted bad arguments: %d", st);
    if (st != MCG_OK) {
        free(work);
        return 0;
    }
    FZ_CHECK(steps0 == 0 && memcmp(R0, R, sizeof R) == 0 && memcmp(t0, t, sizeof t) == 0,
             "linf_local: max_steps = 0 moved the motion");
    st = mcg_linf_local(n, u1, a1, u2, a2, R, t, delta0, delta_min, max_steps, work, &f, &steps);
    free(work);
    if (max_steps < 0) {
        FZ_CHECK(st == MCG_EINVAL, "linf_local accepted max_steps %d: %d", max_steps, st);
        return 0;
    }
    FZ_CHECK(st == MCG_OK, "linf_local: status %d after a valid first call", st);
    if (!fz_is_rotation(R0, 1e-9))
        return 0; /* the caller passes rotations: no promise about the values otherwise */
    FZ_CHECK(isfinite(f) && f >= 0.0 && f <= 1.0 + 1e-12 && isfinite(f0),
             "linf_local: f_out %g (start %g)", f, f0);
    FZ_CHECK(f <= f0 * (1.0 + 1e-12) + 1e-300, "linf_local: maximum increased %.17g -> %.17g",
             f0, f);
    FZ_CHECK(steps >= 0 && steps <= max_steps, "linf_local: %d steps of %d", steps, max_steps);
    FZ_CHECK(fz_all_finite(t, 3), "linf_local: non-finite t");
    FZ_CHECK(fz_is_rotation(R, 1e-9), "linf_local: R no longer a rotation (%g)", fz_orth_err3(R));
    return 0;
}
