/*
 * fuzz_verdict.c -- libFuzzer harness of mcg_verdict_stats, the O(n)
 * evidence of the scale verdict (csrc/verdict.c).
 *
 * Inputs: mode 0 a synthetic rig scene (fz_scene, cross-camera pairs or
 * not) with an arbitrary inlier mask and a motion near the scene's or any;
 * mode 1 arbitrary arrays, camera ids (some out of range), mask bytes,
 * motion, still angle and workspace size. Invariants: NULL-free bad
 * arguments (sizes, ids, NaN/inf, zero directions, still_angle, a short
 * workspace) give MCG_EINVAL / MCG_ENOMEM; on MCG_OK the counts agree with
 * a recount here (inliers: bit 0 of the mask; intra + cross = inliers;
 * n_still <= n_intra; n_in_front <= inliers; cameras with intra inliers),
 * R_fit is a rotation, the critical angle lies in [0, pi/2] and is 0 for
 * fewer than two such cameras, the travel direction is a unit vector or
 * zero (only for t = 0).
 */
#include "fuzz_input.h"
#include "mcgeom.h"

#define FUZZ_MODES 2

#define MAXN 64
#define MAXC 10

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in = fz_make(data, size);
    int mode = fz_u8(&in) % FUZZ_MODES, valid, st, i, ncam, args_ok = 1;
    int n = fz_size(&in, 0, MAXN, &valid);
    static double o1[3 * MAXN], d1[3 * MAXN], o2[3 * MAXN], d2[3 * MAXN];
    static double work[64];
    static int c1[MAXN], c2[MAXN], seen[MAXC + 8];
    static unsigned char mask[MAXN];
    double R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, t[3] = {0, 0, 0}, still, nd;
    size_t lw;
    mcg_verdict_stats_result s;
    int n_in = 0, n_intra = 0, n_cams = 0;
    if (!valid) {
        st = mcg_verdict_stats(n, o1, d1, o2, d2, c1, c2, 1, mask, R, t, 0.0, &s, work, 64);
        FZ_CHECK(st == MCG_EINVAL, "verdict_stats(n = %d) returned %d", n, st);
        return 0;
    }
    ncam = fz_int(&in, 1, MAXC);
    if (mode == 0) {
        const int cross = fz_u8(&in) & 1;
        fz_rotation(&in, R);
        for (i = 0; i < 3; ++i)
            t[i] = fz_range(&in, -2.0, 2.0);
        fz_scene(&in, n, ncam > 8 ? 8 : ncam, cross, R, t, o1, d1, o2, d2, c1);
        for (i = 0; i < n; ++i)
            c2[i] = (cross && i % 4 == 3) ? (c1[i] + 1) % (ncam > 8 ? 8 : ncam) : c1[i];
        if (fz_u8(&in) & 1) { /* the estimate's motion, a little off or anything */
            fz_rotation_or_any(&in, R);
            for (i = 0; i < 3; ++i)
                t[i] += fz_range(&in, -0.1, 0.1);
        }
    } else {
        fz_rays(&in, (size_t)n, o1, d1, o2, d2);
        for (i = 0; i < n; ++i) {
            c1[i] = fz_int(&in, -1, ncam);
            c2[i] = (fz_u8(&in) & 3) ? c1[i] : fz_int(&in, -1, ncam);
        }
        fz_rotation_or_any(&in, R);
        fz_doubles(&in, t, 3);
    }
    for (i = 0; i < n; ++i)
        mask[i] = fz_u8(&in);
    still = (fz_u8(&in) % 8 == 0) ? fz_double(&in) : fz_range(&in, 0.0, 0.1);
    lw = (fz_u8(&in) % 16 == 0) ? (size_t)fz_int(&in, 0, 8) : sizeof work / sizeof work[0];
    st = mcg_verdict_stats(n, o1, d1, o2, d2, c1, c2, ncam, mask, R, t, still, &s, work, lw);
    FZ_CHECK(fz_status_known(st), "verdict_stats status %d", st);
    for (i = 0; i < n; ++i) {
        args_ok &= c1[i] >= 0 && c1[i] < ncam && c2[i] >= 0 && c2[i] < ncam;
        args_ok &= fz_maxabs(d1 + 3 * i, 3) > 0.0 && fz_maxabs(d2 + 3 * i, 3) > 0.0;
    }
    args_ok &= fz_all_finite(o1, 3 * (size_t)n) && fz_all_finite(d1, 3 * (size_t)n) &&
               fz_all_finite(o2, 3 * (size_t)n) && fz_all_finite(d2, 3 * (size_t)n) &&
               fz_all_finite(R, 9) && fz_all_finite(t, 3) && still >= 0.0 && still < 4.0 &&
               fz_maxabs(R, 9) <= 1e150 && fz_maxabs(t, 3) <= 1e150 &&
               fz_maxabs(o1, 3 * (size_t)n) <= 1e150 && fz_maxabs(o2, 3 * (size_t)n) <= 1e150;
    if (!args_ok) {
        FZ_CHECK(st == MCG_EINVAL, "verdict_stats with bad arguments: %d", st);
        return 0;
    }
    if (lw < mcg_verdict_stats_work_size(ncam)) {
        FZ_CHECK(st == MCG_ENOMEM || st == MCG_EINVAL, "short workspace: %d", st);
        return 0;
    }
    FZ_CHECK(st == MCG_OK, "verdict_stats of valid arguments: %d", st);
    for (i = 0; i < MAXC + 8; ++i)
        seen[i] = 0;
    for (i = 0; i < n; ++i)
        if (mask[i] & 1) {
            n_in++;
            if (c1[i] == c2[i]) {
                n_intra++;
                n_cams += !seen[c1[i]];
                seen[c1[i]] = 1;
            }
        }
    FZ_CHECK(s.n_inliers == n_in && s.n_intra == n_intra && s.n_cross == n_in - n_intra,
             "counts %d %d %d, recounted %d %d", s.n_inliers, s.n_intra, s.n_cross, n_in,
             n_intra);
    FZ_CHECK(s.n_cameras_intra == n_cams, "cameras %d, recounted %d", s.n_cameras_intra, n_cams);
    FZ_CHECK(s.n_still >= 0 && s.n_still <= s.n_intra, "n_still %d of %d", s.n_still, s.n_intra);
    FZ_CHECK(s.n_in_front >= 0 && s.n_in_front <= n_in, "in front %d of %d", s.n_in_front, n_in);
    FZ_CHECK(fz_is_rotation(s.R_fit, 1e-9), "R_fit not a rotation: %g", fz_orth_err3(s.R_fit));
    if (!s.fit_ok)
        FZ_CHECK(s.n_still == 0, "n_still %d without a fit", s.n_still);
    FZ_CHECK(s.critical_angle >= 0.0 && s.critical_angle <= 1.5707963267948968,
             "critical angle %g", s.critical_angle);
    if (n_cams < 2)
        FZ_CHECK(s.critical_angle == 0.0, "critical angle %g over %d cameras", s.critical_angle,
                 n_cams);
    nd = sqrt(fz_dot3(s.t_direction, s.t_direction));
    FZ_CHECK(fabs(nd - 1.0) < 1e-9 || (nd == 0.0 && fz_maxabs(t, 3) == 0.0) ||
                 fz_maxabs(t, 3) < 1e-290,
             "t_direction of length %g", nd);
    return 0;
}
