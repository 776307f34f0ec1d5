/* test_fuzz_regressions.c -- one check per finding of the libFuzzer harnesses
 * of fuzz/c/ (fuzz/README.md lists them), on the input that triggered it
 * (reduced to its meaning), so a fixed bug stays fixed. */
#include "mcgeom.h"
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

int main(void)
{
    test_angle_axis_overflow();
    printf("%d checks, %d failed\n", n_checks, n_failed);
    return n_failed != 0;
}
