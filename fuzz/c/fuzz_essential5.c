/*
 * fuzz_essential5.c -- libFuzzer harness of mcg_essential5 (the 5-point
 * solver of Nister 2004) and mcg_essential_decompose.
 *
 * Inputs: mode 0 a consistent problem (decoded rotation, translation and
 * five points, a few entries sometimes replaced by arbitrary doubles),
 * mode 1 thirty arbitrary doubles, mode 2 a degenerate variant of a
 * consistent problem (repeated pairs, pure rotation d2 = R d1, collinear
 * points, or bearings scaled to 1e-40 / 1e150). Invariants: the status is
 * known; NaN/inf or a zero-length bearing gives MCG_EINVAL and anything else
 * MCG_OK; 0 <= n_solutions <= 10; every returned E is finite, of unit
 * Frobenius norm, rank 2 (det E and the trace constraint 2 E E^T E -
 * tr(E E^T) E at most 1e-6, the solver's documented acceptance) and
 * satisfies the five epipolar constraints of the normalised bearings to
 * 1e-9 (E lies in their null space, computed by Householder QR: the residual
 * is rounding of unit-norm rows); the decomposition of each E returns MCG_OK
 * with R a rotation to 1e-9, |t| = 1, 0 <= n_front <= 5, and E = +-[t]x R / sqrt(2)
 * to 1e-5. Never a crash, never a sanitizer report.
 */
#include "fuzz_input.h"
#include "mcgeom.h"

/* routines selected by the first input byte (fuzz/make_corpus.py writes
 * seeds for each) */
#define FUZZ_MODES 3

static void unit(const double *v, double *u)
{
    double mx = fz_maxabs(v, 3), w[3], n;
    w[0] = v[0] / mx;
    w[1] = v[1] / mx;
    w[2] = v[2] / mx;
    n = mx * sqrt(fz_dot3(w, w));
    u[0] = v[0] / n;
    u[1] = v[1] / n;
    u[2] = v[2] / n;
}

/* a consistent problem: points in a box in front of camera 1 */
static void consistent(fz_in *in, double d1[15], double d2[15], double R[9])
{
    double t[3];
    int k, i;
    fz_rotation(in, R);
    for (i = 0; i < 3; ++i)
        t[i] = fz_range(in, -2.0, 2.0);
    for (k = 0; k < 5; ++k) {
        double X[3], X2[3];
        X[0] = fz_range(in, -4.0, 4.0);
        X[1] = fz_range(in, -4.0, 4.0);
        X[2] = fz_range(in, 0.5, 8.0);
        for (i = 0; i < 3; ++i)
            X2[i] = R[3 * i] * X[0] + R[3 * i + 1] * X[1] + R[3 * i + 2] * X[2] + t[i];
        for (i = 0; i < 3; ++i) {
            d1[3 * k + i] = X[i];
            d2[3 * k + i] = X2[i];
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in = fz_make(data, size);
    int mode = fz_u8(&in) % FUZZ_MODES, st, ns = -1, s, k, i, bad_input = 0;
    double d1[15], d2[15], R[9], E[90];
    if (mode == 0) {
        consistent(&in, d1, d2, R);
        if (fz_u8(&in) % 8 == 0) { /* a few arbitrary entries */
            int nrep = fz_int(&in, 1, 3);
            for (k = 0; k < nrep; ++k) {
                int j = fz_int(&in, 0, 29);
                double v = fz_double(&in);
                if (j < 15)
                    d1[j] = v;
                else
                    d2[j - 15] = v;
            }
        }
    } else if (mode == 1) {
        fz_doubles(&in, d1, 15);
        fz_doubles(&in, d2, 15);
    } else {
        int kind = fz_u8(&in) % 5;
        consistent(&in, d1, d2, R);
        if (kind == 0) { /* a repeated pair */
            int a = fz_int(&in, 0, 4), b = fz_int(&in, 0, 4);
            memcpy(d1 + 3 * a, d1 + 3 * b, 3 * sizeof(double));
            memcpy(d2 + 3 * a, d2 + 3 * b, 3 * sizeof(double));
        } else if (kind == 1) { /* pure rotation */
            for (k = 0; k < 5; ++k)
                for (i = 0; i < 3; ++i)
                    d2[3 * k + i] = R[3 * i] * d1[3 * k] + R[3 * i + 1] * d1[3 * k + 1] +
                                    R[3 * i + 2] * d1[3 * k + 2];
        } else if (kind == 2) { /* one pair five times */
            for (k = 1; k < 5; ++k) {
                memcpy(d1 + 3 * k, d1, 3 * sizeof(double));
                memcpy(d2 + 3 * k, d2, 3 * sizeof(double));
            }
        } else { /* bearings of extreme length (scale-free constraint) */
            double f = kind == 3 ? 1e-40 : 1e150;
            for (i = 0; i < 15; ++i) {
                d1[i] *= f;
                d2[i] *= f;
            }
        }
    }
    for (k = 0; k < 5; ++k)
        if (!(fz_dot3(d1 + 3 * k, d1 + 3 * k) > 1e-100) ||
            !(fz_dot3(d2 + 3 * k, d2 + 3 * k) > 1e-100))
            bad_input = 1; /* includes NaN, and lengths whose square overflows */
    if (!fz_all_finite(d1, 15) || !fz_all_finite(d2, 15))
        bad_input = 2;
    st = mcg_essential5(d1, d2, E, &ns);
    FZ_CHECK(fz_status_known(st), "essential5 returned unknown status %d", st);
    if (bad_input == 2) {
        FZ_CHECK(st == MCG_EINVAL, "essential5 on NaN/inf input returned %d", st);
        return 0;
    }
    if (bad_input == 1) {
        /* |d|^2 underflowing or overflowing: the library tests the same
         * expression, so the status must be EINVAL too */
        FZ_CHECK(st == MCG_EINVAL, "essential5 on a zero-length bearing returned %d", st);
        return 0;
    }
    FZ_CHECK(st == MCG_OK, "essential5 on valid input returned %d", st);
    FZ_CHECK(ns >= 0 && ns <= 10, "essential5 returned %d solutions", ns);
    for (s = 0; s < ns; ++s) {
        const double *e = E + 9 * s;
        double nrm = 0.0, eet[9], m[9], tr, viol, Rd[9], td[3], sk[9], tx[9], ep = 0.0, em = 0.0;
        double u1[15], u2[15];
        int nf = -1;
        FZ_CHECK(fz_all_finite(e, 9), "essential5 solution %d not finite", s);
        for (i = 0; i < 9; ++i)
            nrm += e[i] * e[i];
        FZ_CHECK(fabs(sqrt(nrm) - 1.0) < 1e-12, "solution %d has norm %g", s, sqrt(nrm));
        for (i = 0; i < 3; ++i)
            for (k = 0; k < 3; ++k)
                eet[3 * i + k] = fz_dot3(e + 3 * i, e + 3 * k);
        tr = eet[0] + eet[4] + eet[8];
        fz_matmul3(eet, e, m);
        viol = fabs(fz_det3(e));
        for (i = 0; i < 9; ++i)
            viol = fmax(viol, fabs(2.0 * m[i] - tr * e[i]));
        FZ_CHECK(viol <= 1.01e-6, "solution %d violates det / trace constraints by %g", s, viol);
        for (k = 0; k < 5; ++k) {
            double Ev[3], r;
            unit(d1 + 3 * k, u1 + 3 * k);
            unit(d2 + 3 * k, u2 + 3 * k);
            for (i = 0; i < 3; ++i)
                Ev[i] = fz_dot3(e + 3 * i, u1 + 3 * k);
            r = fabs(fz_dot3(u2 + 3 * k, Ev));
            FZ_CHECK(r <= 1e-9, "solution %d: epipolar residual %g of pair %d", s, r, k);
        }
        st = mcg_essential_decompose(e, d1, d2, 5, Rd, td, &nf);
        FZ_CHECK(st == MCG_OK, "decompose of solution %d returned %d", s, st);
        FZ_CHECK(fz_is_rotation(Rd, 1e-9), "decompose: R not a rotation (err %g)", fz_orth_err3(Rd));
        FZ_CHECK(fabs(sqrt(fz_dot3(td, td)) - 1.0) < 1e-9, "decompose: |t| = %g",
                 sqrt(fz_dot3(td, td)));
        FZ_CHECK(nf >= 0 && nf <= 5, "decompose: n_front = %d", nf);
        /* E = +-[t]x R / sqrt(2) */
        sk[0] = 0.0; sk[1] = -td[2]; sk[2] = td[1];
        sk[3] = td[2]; sk[4] = 0.0; sk[5] = -td[0];
        sk[6] = -td[1]; sk[7] = td[0]; sk[8] = 0.0;
        fz_matmul3(sk, Rd, tx);
        for (i = 0; i < 9; ++i) {
            ep = fmax(ep, fabs(e[i] - tx[i] / sqrt(2.0)));
            em = fmax(em, fabs(e[i] + tx[i] / sqrt(2.0)));
        }
        FZ_CHECK(fmin(ep, em) <= 1e-5, "decompose: |E -+ [t]x R| = %g", fmin(ep, em));
    }
    return 0;
}
