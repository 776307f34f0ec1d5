/*
 * verdict.c -- the O(n) evidence of the scale verdict
 * (mcgeom/observability.py, scale_verdict; thesis ch. 7.3.2) in one pass
 * over the rays, so that the verdict of a robust estimate costs no Python
 * loop over the correspondences (issue 19).
 *
 * For the inliers of an estimate (R, t), rig2_from_rig1:
 *   - the no-parallax statistic: the best pure rotation of the unit
 *     intra-camera inlier bearings (Wahba's problem: the rotation nearest to
 *     sum d2 d1^T, mcg_project_so3) and the number of rotation-only angles
 *     between d2 and R_fit d1 below a given angle;
 *   - the cross-camera inliers (they fix the scale whatever the motion) and
 *     the cameras with intra-camera inliers;
 *   - the critical angle of ch. 7.5.2 over those cameras: each centre c
 *     (the origin of its first intra-camera inlier) moves by
 *     delta(c) = R^T (c - t) - c seen from the time-1 rig frame; the angle
 *     between two displacement lines (folded to [0, pi/2]: Theorem 3 asks
 *     for parallel lines, whatever their sense), largest over the pairs;
 *   - cheirality: the inliers whose rays, the time-1 ray moved by (R, t),
 *     meet (mid-point) in front of both origins;
 *   - the direction of travel reported when |t| is not observable
 *     (mcgeom.estimators._common.travel_direction): the translation of the
 *     centroid c of the inliers' origins, tau = t + R c - c (t itself when
 *     |t| >= 20 |R c - c|), its sign by cheirality at a length where the
 *     rotation-induced part is negligible.
 */
#include "mcgeom.h"
#include "internal.h"
#include "so3.h"

#include <float.h>
#include <math.h>
#include <stddef.h>

#define MAX_VERDICT_CAMERAS 4096
/* origins, R and t beyond this overflow the products of the mid-point test */
#define MAX_MAGNITUDE 1e150

size_t mcg_verdict_stats_work_size(int n_cameras)
{
    if (n_cameras < 1 || n_cameras > MAX_VERDICT_CAMERAS)
        return 0;
    /* the index of each camera's first intra-camera inlier (ints) and the
     * unit displacements of the cameras (3 doubles each) */
    return ((size_t)n_cameras * sizeof(int) + sizeof(double) - 1) / sizeof(double) +
           3 * (size_t)n_cameras + 1;
}

/* Unit copy of a 3-vector; 0 when its length is not positive and finite
 * (outside the safe range of the squared length, scaled by its largest
 * entry first: no underflow of tiny vectors, no overflow of huge ones). */
static int unit(const double *v, double u[3])
{
    double m, s = dot3(v, v);
    if (s > 1e-280 && s < 1e280) {
        s = 1.0 / sqrt(s);
        u[0] = v[0] * s;
        u[1] = v[1] * s;
        u[2] = v[2] * s;
        return 1;
    }
    m = fmax(fabs(v[0]), fmax(fabs(v[1]), fabs(v[2])));
    if (!(m > 0.0 && isfinite(m)))
        return 0;
    u[0] = v[0] / m;
    u[1] = v[1] / m;
    u[2] = v[2] / m;
    s = sqrt(dot3(u, u));
    u[0] /= s;
    u[1] /= s;
    u[2] /= s;
    return 1;
}

/* pairs per block of the passes below (their unit bearings on the stack) */
#define VBLOCK 64

/* The unit copies e1, e2 (3 nb each) of the nb directions d1, d2 as unit()
 * makes them: its common case (squared length within (1e-280, 1e280)) in
 * one pass without branches, so that it vectorises, then unit() itself for
 * the others (zeros where it fails), so the same bits (issue 19: the
 * verdict's unit bearings were made one at a time, twice). */
MCG_AVX2_CLONE
static void unit_block(const double *restrict d1, const double *restrict d2, int nb,
                      double *restrict e1, double *restrict e2)
{
    int k, i, slow = 0;
    for (k = 0; k < nb; ++k) {
        const double s1 = dot3(d1 + 3 * k, d1 + 3 * k), s2 = dot3(d2 + 3 * k, d2 + 3 * k);
        const double r1 = 1.0 / sqrt(s1), r2 = 1.0 / sqrt(s2);
        slow += !((s1 > 1e-280) & (s1 < 1e280) & (s2 > 1e-280) & (s2 < 1e280));
        for (i = 0; i < 3; ++i) {
            e1[3 * k + i] = d1[3 * k + i] * r1;
            e2[3 * k + i] = d2[3 * k + i] * r2;
        }
    }
    if (slow)
        for (k = 0; k < nb; ++k) {
            const double s1 = dot3(d1 + 3 * k, d1 + 3 * k), s2 = dot3(d2 + 3 * k, d2 + 3 * k);
            if (!(s1 > 1e-280 && s1 < 1e280)) {
                e1[3 * k] = e1[3 * k + 1] = e1[3 * k + 2] = 0.0;
                (void)unit(d1 + 3 * k, e1 + 3 * k);
            }
            if (!(s2 > 1e-280 && s2 < 1e280)) {
                e2[3 * k] = e2[3 * k + 1] = e2[3 * k + 2] = 0.0;
                (void)unit(d2 + 3 * k, e2 + 3 * k);
            }
        }
}

/* y = |R e1 x e2| and c = (R e1) . e2 of one pair of unit bearings: its
 * rotation-only angle is atan2(y, c) */
static inline void angle_terms(const double R[9], const double *e1, const double *e2, double *y,
                               double *c)
{
    double a[3], x[3];
    mat_vec(R, e1, a);
    cross3(a, e2, x);
    *y = sqrt(dot3(x, x));
    *c = dot3(a, e2);
}

/* The rotation-only angles between d2 and R_fit d1 of the intra-camera
 * inliers of a block (unit bearings e1, e2): the number below the still
 * angle s, decided by the sign of D = c sin(s) - y cos(s) (see
 * mcg_verdict_stats) without branches, so that it vectorises; the pairs
 * within the margin, if any, by atan2 in a second pass. Integer counts:
 * the same in any order. */
MCG_AVX2_CLONE
static int still_block(int nb, const double *restrict e1, const double *restrict e2,
                       const unsigned char *restrict inlier, const int *restrict cam1,
                       const int *restrict cam2, const double R_fit[9], double sn, double cs,
                       double still_angle)
{
    double Rl[9];
    long long still = 0, unsure = 0;
    int k, i;
    for (i = 0; i < 9; ++i)
        Rl[i] = R_fit[i];
    for (k = 0; k < nb; ++k) {
        double y, c, D, margin;
        long long use = (long long)(inlier[k] & 1) & (cam1[k] == cam2[k] ? 1LL : 0LL), above;
        angle_terms(Rl, e1 + 3 * k, e2 + 3 * k, &y, &c);
        D = c * sn - y * cs;
        margin = 1e-9 * (fabs(c) + y);
        above = D > margin ? 1LL : 0LL;
        still += use & above;
        unsure += use & (above ^ 1LL) & (D < -margin ? 0LL : 1LL);
    }
    for (k = 0; unsure > 0 && k < nb; ++k) {
        double y, c, D, margin;
        if (!(inlier[k] & 1) || cam1[k] != cam2[k])
            continue;
        angle_terms(Rl, e1 + 3 * k, e2 + 3 * k, &y, &c);
        D = c * sn - y * cs;
        margin = 1e-9 * (fabs(c) + y);
        if (!(D > margin) && !(D < -margin))
            still += atan2(y, c) < still_angle;
    }
    return (int)still;
}

/* Inliers in front at each of the nt (<= 3) translations T (nt x 3), in
 * one pass (R d1 and d2 as they are): the translation enters the mid-point
 * depths only through a.w and b.w, w = o2 - R o1 - T, affine in T. The
 * depths are s1 = (aw bb - bw ab) / den and s2 = (aw ab - bw aa) / den
 * with den > 0: their signs are those of the numerators (no division;
 * issue 19). Without branches, three translations always (the unused ones
 * zero), so that the pass vectorises (issue 19: the verdict's passes ran a
 * pair at a time); integer counts, the same in any order. */
MCG_AVX2_CLONE
static void count_front(int n, const double *restrict o1, const double *restrict d1,
                        const double *restrict o2, const double *restrict d2,
                        const unsigned char *restrict inlier, const double R[9],
                        const double *T, int nt, int *count)
{
    double Rl[9], Tl[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
    long long cnt[3] = {0, 0, 0};
    int k, i, j;
    for (i = 0; i < 9; ++i)
        Rl[i] = R[i];
    for (i = 0; i < 3 * nt; ++i)
        Tl[i] = T[i];
    for (k = 0; k < n; ++k) {
        double a[3], p[3], w[3], aa, bb, ab, aw0, bw0;
        const double *b = d2 + 3 * k;
        long long ok;
        mat_vec(Rl, d1 + 3 * k, a);
        mat_vec(Rl, o1 + 3 * k, p);
        for (i = 0; i < 3; ++i)
            w[i] = o2[3 * k + i] - p[i];
        aa = dot3(a, a);
        bb = dot3(b, b);
        ab = dot3(a, b);
        /* parallel rays: no depth (mcgeom.geometry.counts_in_front) */
        ok = (long long)(inlier[k] & 1) & (aa * bb - ab * ab > 1e-14 * aa * bb ? 1LL : 0LL);
        aw0 = dot3(a, w);
        bw0 = dot3(b, w);
        for (j = 0; j < 3; ++j) {
            const double aw = aw0 - dot3(a, Tl + 3 * j), bw = bw0 - dot3(b, Tl + 3 * j);
            cnt[j] += ok & (aw * bb - bw * ab > 0.0 ? 1LL : 0LL) &
                      (aw * ab - bw * aa > 0.0 ? 1LL : 0LL);
        }
    }
    for (j = 0; j < nt; ++j)
        count[j] = (int)cnt[j];
}

/* The largest folded angle between the displacement lines of the centres
 * (n_c unit rows u): the pair with the smallest |cos|, its angle by atan2 of
 * |cross| and |dot| (accurate near 0 and pi/2). 0 for fewer than two. */
static double largest_angle(const double *u, int n_c)
{
    int i, j, bi = -1, bj = -1;
    double best = INFINITY, x[3];
    for (i = 0; i < n_c; ++i)
        for (j = i + 1; j < n_c; ++j) {
            const double c = fabs(dot3(u + 3 * i, u + 3 * j));
            if (c < best) {
                best = c;
                bi = i;
                bj = j;
            }
        }
    if (bi < 0)
        return 0.0;
    cross3(u + 3 * bi, u + 3 * bj, x);
    return atan2(sqrt(dot3(x, x)), best);
}

/* the per-row checks of check_args: 1 if every row passes */
MCG_AVX2_CLONE
static int rows_ok(int n, const double *restrict o1, const double *restrict d1,
                   const double *restrict o2, const double *restrict d2,
                   const int *restrict cam1, const int *restrict cam2, int n_cameras)
{
    long long bad = 0;
    int k, i;
    for (k = 0; k < n; ++k) {
        const double *a = d1 + 3 * k, *b = d2 + 3 * k, *p = o1 + 3 * k, *q = o2 + 3 * k;
        for (i = 0; i < 3; ++i)
            bad |= ((fabs(p[i]) <= MAX_MAGNITUDE) & (fabs(q[i]) <= MAX_MAGNITUDE) &
                    (fabs(a[i]) <= DBL_MAX) & (fabs(b[i]) <= DBL_MAX))
                       ? 0LL : 1LL;
        bad |= ((cam1[k] < 0) | (cam1[k] >= n_cameras) | (cam2[k] < 0) | (cam2[k] >= n_cameras))
                   ? 1LL : 0LL;
        bad |= (((a[0] == 0.0) & (a[1] == 0.0) & (a[2] == 0.0)) |
                ((b[0] == 0.0) & (b[1] == 0.0) & (b[2] == 0.0)))
                   ? 1LL : 0LL;
    }
    return !bad;
}

static int check_args(int n, const double *o1, const double *d1, const double *o2,
                      const double *d2, const int *cam1, const int *cam2, int n_cameras,
                      const unsigned char *inlier, const double R[9], const double t[3],
                      double still_angle, const mcg_verdict_stats_result *out,
                      const double *work)
{
    int k;
    if (!o1 || !d1 || !o2 || !d2 || !cam1 || !cam2 || !inlier || !R || !t || !out || !work)
        return 0;
    if (n < 0 || (size_t)n > MAX_ROWS || n_cameras < 1 || n_cameras > MAX_VERDICT_CAMERAS)
        return 0;
    if (!all_finite(R, 9) || !all_finite(t, 3) || !(still_angle >= 0.0 && still_angle < 4.0))
        return 0;
    for (k = 0; k < 9; ++k)
        if (fabs(R[k]) > MAX_MAGNITUDE || (k < 3 && fabs(t[k]) > MAX_MAGNITUDE))
            return 0;
    /* one pass over the rows (issue 19: four finiteness passes, a magnitude
     * pass and this one were a fifth of the call at 1e4 rows): origins
     * finite and within MAX_MAGNITUDE (false for NaN and inf), directions
     * finite (|x| <= DBL_MAX) and not zero, ids in range; without branches,
     * so that it vectorises */
    return rows_ok(n, o1, d1, o2, d2, cam1, cam2, n_cameras);
}

int mcg_verdict_stats(int n, const double *o1, const double *d1, const double *o2,
                      const double *d2, const int *cam1, const int *cam2, int n_cameras,
                      const unsigned char *inlier, const double R[9], const double t[3],
                      double still_angle, mcg_verdict_stats_result *out, double *work,
                      size_t lwork)
{
    int k, k0, j, i, *first, n_c = 0;
    double B[9] = {0}, *disp, c[3] = {0, 0, 0}, rc[3], shift[3], tau[3], nt, ns, spread = 0.0;
    double e1[3 * VBLOCK], e2[3 * VBLOCK];
    if (!check_args(n, o1, d1, o2, d2, cam1, cam2, n_cameras, inlier, R, t, still_angle, out,
                    work))
        return MCG_EINVAL;
    if (lwork < mcg_verdict_stats_work_size(n_cameras))
        return MCG_ENOMEM;
    first = (int *)(void *)work;
    disp = work + (mcg_verdict_stats_work_size(n_cameras) - 3 * (size_t)n_cameras - 1);
    out->n_inliers = out->n_intra = out->n_cameras_intra = out->n_still = 0;
    out->n_in_front = 0;
    out->fit_ok = 0;
    out->critical_angle = 0.0;
    for (i = 0; i < 9; ++i)
        out->R_fit[i] = (i % 4 == 0) ? 1.0 : 0.0;
    for (k = 0; k < n_cameras; ++k)
        first[k] = -1;

    /* pass 1: counts, first intra-camera inlier per camera, sum d2 d1^T,
     * centroid of the inliers' origins */
    for (k0 = 0; k0 < n; k0 += VBLOCK) {
        const int nb = n - k0 < VBLOCK ? n - k0 : VBLOCK;
        unit_block(d1 + 3 * (size_t)k0, d2 + 3 * (size_t)k0, nb, e1, e2);
        for (j = 0; j < nb; ++j) {
            k = k0 + j;
            if (!(inlier[k] & 1))
                continue;
            out->n_inliers++;
            for (i = 0; i < 3; ++i)
                c[i] += 0.5 * (o1[3 * k + i] + o2[3 * k + i]);
            if (cam1[k] != cam2[k])
                continue;
            out->n_intra++;
            if (first[cam1[k]] < 0)
                first[cam1[k]] = k;
            for (i = 0; i < 9; ++i)
                B[i] += e2[3 * j + i / 3] * e1[3 * j + i % 3];
        }
    }
    out->n_cross = out->n_inliers - out->n_intra;

    /* the no-parallax statistic: Wahba's rotation, then its angles */
    if (out->n_intra >= 2 && mcg_project_so3(B, out->R_fit) == MCG_OK) {
        /* angle = atan2(y, c) < still_angle, y = |R_fit e1 x e2|, c = its
         * dot: with y = r sin(angle), c = r cos(angle), the sign of
         * D = c sin(s) - y cos(s) = r sin(s - angle) decides it (s in
         * (0, 3)); atan2 (~20 ns) only where |D| is within 1e-9 r of 0,
         * far beyond the rounding of atan2, sin and cos (~1e-16): the same
         * count as atan2 everywhere (issue 19) */
        const int fast = still_angle > 0.0 && still_angle < 3.0;
        const double sn = fast ? sin(still_angle) : 0.0, cs = fast ? cos(still_angle) : 0.0;
        out->fit_ok = 1;
        for (k0 = 0; k0 < n; k0 += VBLOCK) {
            const int nb = n - k0 < VBLOCK ? n - k0 : VBLOCK;
            unit_block(d1 + 3 * (size_t)k0, d2 + 3 * (size_t)k0, nb, e1, e2);
            if (fast) {
                out->n_still += still_block(nb, e1, e2, inlier + k0, cam1 + k0, cam2 + k0,
                                            out->R_fit, sn, cs, still_angle);
                continue;
            }
            for (j = 0; j < nb; ++j) {
                double y, c;
                k = k0 + j;
                if (!(inlier[k] & 1) || cam1[k] != cam2[k])
                    continue;
                angle_terms(out->R_fit, e1 + 3 * j, e2 + 3 * j, &y, &c);
                out->n_still += atan2(y, c) < still_angle;
            }
        }
    } else {
        for (i = 0; i < 9; ++i)
            out->R_fit[i] = (i % 4 == 0) ? 1.0 : 0.0;
    }

    /* the critical angle over the cameras with intra-camera inliers, in id
     * order: R^T (c - t) - c, zero displacements left out */
    for (k = 0; k < n_cameras; ++k) {
        double d[3], u[3];
        const double *o;
        if (first[k] < 0)
            continue;
        out->n_cameras_intra++;
        o = o1 + 3 * first[k];
        for (i = 0; i < 3; ++i)
            d[i] = R[i] * (o[0] - t[0]) + R[3 + i] * (o[1] - t[1]) + R[6 + i] * (o[2] - t[2]) -
                   o[i];
        if (unit(d, u)) {
            for (i = 0; i < 3; ++i)
                disp[3 * n_c + i] = u[i];
            n_c++;
        }
    }
    out->critical_angle = out->n_cameras_intra >= 2 ? largest_angle(disp, n_c) : 0.0;

    /* the direction of travel (travel_direction): the centroid's motion,
     * its sign by cheirality at a length L where the rotation-induced part
     * is negligible; cheirality at (R, t) in the same pass */
    if (out->n_inliers > 0)
        for (i = 0; i < 3; ++i)
            c[i] /= out->n_inliers;
    mat_vec(R, c, rc);
    for (i = 0; i < 3; ++i)
        shift[i] = rc[i] - c[i];
    nt = sqrt(dot3(t, t));
    ns = sqrt(dot3(shift, shift));
    for (i = 0; i < 3; ++i)
        tau[i] = nt >= 20.0 * ns ? t[i] : t[i] + shift[i];
    if (!unit(tau, out->t_direction)) {
        int count;
        /* t itself, made unit by unit()'s rescaling: t / |t| with |t| from
         * dot3 lost precision where |t|^2 is subnormal (t ~ 1e-160: a
         * direction of length 1.00001, fuzz finding 23); zero for t = 0 */
        if (!unit(t, out->t_direction))
            for (i = 0; i < 3; ++i)
                out->t_direction[i] = 0.0;
        count_front(n, o1, d1, o2, d2, inlier, R, t, 1, &count);
        out->n_in_front = count;
        return MCG_OK;
    }
    for (k = 0; k < n; ++k)
        if (inlier[k] & 1) {
            double e[3];
            for (i = 0; i < 3; ++i)
                e[i] = o1[3 * k + i] - c[i];
            spread += dot3(e, e);
        }
    spread = out->n_inliers > 0 ? sqrt(spread / out->n_inliers) : 1.0;
    {
        double L = fmax(1.0, fmax(100.0 * spread, 100.0 * ns)), T[9];
        int count[3];
        for (i = 0; i < 3; ++i) {
            T[i] = t[i];
            T[3 + i] = -shift[i] + L * out->t_direction[i];
            T[6 + i] = -shift[i] - L * out->t_direction[i];
        }
        count_front(n, o1, d1, o2, d2, inlier, R, T, 3, count);
        out->n_in_front = count[0];
        if (count[1] < count[2])
            for (i = 0; i < 3; ++i)
                out->t_direction[i] = -out->t_direction[i];
    }
    return MCG_OK;
}
