/* test_fuzz_regressions.c -- one check per finding of the libFuzzer harnesses
 * of fuzz/c/ (fuzz/README.md lists them), on the input that triggered it
 * (reduced to its meaning), so a fixed bug stays fixed. */
#include "mcgeom.h"
#include "../internal.h"
#include "testutil.h"

#include <float.h>

/* fuzz_linalg: an angle-axis vector with finite components whose norm
 * overflows (-DBL_MAX, ...) gave a NaN matrix with MCG_OK. */
static void test_angle_axis_overflow(void)
{
    double w[3] = {-DBL_MAX, -1.3e232, DBL_MAX}, r[9];
    check_status(mcg_rot_from_angle_axis(w, r), MCG_EINVAL,
                 "rot_from_angle_axis: |w| > DBL_MAX rejected");
    w[0] = 1e300;
    w[2] = -1e300;
    check_status(mcg_rot_from_angle_axis(w, r), MCG_OK,
                 "rot_from_angle_axis: |w| = 1.4e300 still a rotation");
    check(isfinite(r[0] + r[1] + r[2] + r[3] + r[4] + r[5] + r[6] + r[7] + r[8]),
          "rot_from_angle_axis: |w| = 1.4e300 finite", 0.0, 0.0);
}

/* fuzz_linalg: a 9 x 3 matrix with a column of size 1e-8 next to one of
 * 1e150 (a graded matrix): the reflector of the small column was computed
 * from squares in the denormal range, Q lost its orthonormality (2.7e-9). */
static void test_qr_graded_columns(void)
{
    double a[27], q[27], r[9], w[64], e = 0.0;
    int i, j, k;
    for (i = 0; i < 9; ++i) {
        a[3 * i] = (i % 2) ? 1e-8 * (i + 1) : 0.0;
        a[3 * i + 1] = 2.5 * (i + 1) - 0.3 * i * i;
        a[3 * i + 2] = (i % 2) ? 1e150 * (i + 1) : -1.27e126 * (i + 1);
    }
    check_status(mcg_qr(9, 3, a, q, r, w, 64), MCG_OK, "qr of a graded 9 x 3 matrix");
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) {
            double s = 0.0;
            for (k = 0; k < 9; ++k)
                s += q[3 * k + i] * q[3 * k + j];
            s = fabs(s - (i == j ? 1.0 : 0.0));
            if (s > e)
                e = s;
        }
    check(e <= 1e-14, "qr of a graded matrix: |Q^T Q - I|", e, 1e-14);
}

/* fuzz_linear17: a central camera (all rays through one centre, gc_case
 * CENTRAL) with exact correspondences: the algebraic cost x^T M x rounds to
 * slightly below 0 and cost_final = sqrt(cost / n) was NaN with MCG_OK. */
static void test_linear17_central_exact_cost(void)
{
    double o1[3 * 55], d1[3 * 55], o2[3 * 55], d2[3 * 55], w[3], R[9], t[3];
    int trial, i, k, bad = 0, ok = 0;
    mcg_linear17_result res;
    for (trial = 0; trial < 200; ++trial) {
        double c[3] = {2 * urand() - 1, 2 * urand() - 1, 2 * urand() - 1};
        for (k = 0; k < 3; ++k) {
            w[k] = 0.3 * (2 * urand() - 1);
            t[k] = 2 * (2 * urand() - 1);
        }
        mcg_rot_from_angle_axis(w, R);
        for (i = 0; i < 55; ++i) {
            double X[3] = {10 * urand() - 5, 10 * urand() - 5, 1 + 19 * urand()};
            for (k = 0; k < 3; ++k) {
                o1[3 * i + k] = o2[3 * i + k] = c[k];
                d1[3 * i + k] = X[k] - c[k];
                d2[3 * i + k] = R[3 * k] * X[0] + R[3 * k + 1] * X[1] + R[3 * k + 2] * X[2] +
                                t[k] - c[k];
            }
        }
        if (mcg_linear17(55, o1, d1, o2, d2, NULL, &res) != MCG_OK)
            continue;
        ++ok;
        if (!isfinite(res.cost_final) || !isfinite(res.cost_linear) || isnan(res.scale_rel_std))
            ++bad;
    }
    check(ok > 0 && bad == 0, "linear17: central exact data, costs never NaN (of MCG_OK)",
          (double)bad, 0.0);
}

/* fuzz_linf_local: n < 0 computed the work layout (work + 8 n) before
 * rejecting n: a pointer overflow (undefined behaviour; UBSan reports it,
 * the plain build passed by luck). Now MCG_EINVAL before any arithmetic. */
static void test_linf_local_negative_n(void)
{
    double u[3] = {0, 0, 1}, R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, t[3] = {0, 0, 0}, w[9], f;
    int steps;
    check_status(mcg_linf_local(-1, u, u, u, u, R, t, 1.0, 0.1, 5, w, &f, &steps), MCG_EINVAL,
                 "linf_local: n = -1 rejected");
    check_status(mcg_linf_local(-2147483647 - 1, u, u, u, u, R, t, 1.0, 0.1, 5, w, &f, &steps),
                 MCG_EINVAL, "linf_local: n = INT_MIN rejected");
}

int main(void)
{
    test_linf_local_negative_n();
    test_linear17_central_exact_cost();
    test_angle_axis_overflow();
    test_qr_graded_columns();
    printf("%d checks, %d failed\n", n_checks, n_failed);
    return n_failed != 0;
}
