/*
 * robust_pinhole.c -- the robust rig motion from pixels (csrc/robust.c's
 * mcg_robust_rig_motion on the rays of mcg_pinhole_ray_pairs): the whole
 * job of mcgeom.cv.estimate for a rig of undistorted pinholes in one call,
 * for C users and for the façade's common case (issue 19: each step of a
 * call's Python layer costs several microseconds once a feature matcher or
 * another library has run; the pixels' own call and the camera ids'
 * conversion were two of them).
 */
#include "mcgeom.h"
#include "internal.h"
#include "robust_internal.h"

#include <stddef.h>
#include <string.h>

#define MAX_CAMERAS 4096 /* mcg_robust_rig_motion's */
#define NEED_DISTINCT 6  /* pairs of the smallest sample (5+1, 6-point) */

size_t mcg_robust_pinhole_work_size(int n, int n_cameras)
{
    int ok = 1;
    size_t s = mcg_robust_work_size(n, n_cameras);
    if (s == 0)
        return 0;
    /* the rays and pixels per radian (13 n), the camera ids as ints (2 n),
     * the optical axes (3 n_cameras) */
    s = add_sz(s, mul_sz(13, (size_t)n, &ok), &ok);
    s = add_sz(s, ints_as_doubles(2 * (size_t)n), &ok);
    s = add_sz(s, 3 * (size_t)n_cameras, &ok);
    return ok ? s : 0;
}

/* Are pairs i and j the same correspondence (every ray entry and both ids
 * equal, as mcgeom.types.RayPairs.n_distinct compares)? */
static int same_pair(const double *rays, size_t n, const int *id1, const int *id2, int i,
                     int j)
{
    int b, e;
    if (id1[i] != id1[j] || id2[i] != id2[j])
        return 0;
    for (b = 0; b < 4; b++)
        for (e = 0; e < 3; e++)
            if (rays[b * 3 * n + 3 * (size_t)i + e] != rays[b * 3 * n + 3 * (size_t)j + e])
                return 0;
    return 1;
}

/* At least NEED_DISTINCT distinct correspondences (the first ones that
 * differ from all kept so far; typically the first six). */
static int enough_distinct(const double *rays, int n, const int *id1, const int *id2)
{
    int kept[NEED_DISTINCT], m = 0, k, j;
    for (k = 0; k < n && m < NEED_DISTINCT; k++) {
        for (j = 0; j < m; j++)
            if (same_pair(rays, (size_t)n, id1, id2, kept[j], k))
                break;
        if (j == m)
            kept[m++] = k;
    }
    return m == NEED_DISTINCT;
}

int mcg_robust_rig_motion_pinhole(int n, int n_cameras, const double *intr, const double *rot,
                                  const double *centres, const double *focal,
                                  const long long *ids1, const long long *ids2,
                                  const double *px1, const double *px2,
                                  const mcg_robust_options *opt, mcg_robust_result *res,
                                  unsigned char *mask, double *weights, double *work,
                                  size_t lwork)
{
    const size_t nn = (size_t)n;
    const double t_start = robust_now_seconds();
    double *o1, *d1, *o2, *d2, *ppr, *axes, *rest, t_rays;
    int *id1, *id2, bad, st, k, i;
    size_t need;
    if (!intr || !rot || !centres || !focal || !ids1 || !ids2 || !px1 || !px2 || !res ||
        !mask || !work)
        return MCG_EINVAL;
    need = mcg_robust_pinhole_work_size(n, n_cameras);
    if (need == 0 || n_cameras > MAX_CAMERAS)
        return MCG_EINVAL;
    if (lwork < need)
        return MCG_ENOMEM;
    memset(res, 0, sizeof *res);
    o1 = work;
    d1 = work + 3 * nn;
    o2 = work + 6 * nn;
    d2 = work + 9 * nn;
    ppr = work + 12 * nn;
    id1 = (int *)(work + 13 * nn);
    id2 = id1 + nn;
    axes = work + 13 * nn + ints_as_doubles(2 * nn);
    rest = axes + 3 * (size_t)n_cameras;
    st = mcg_pinhole_ray_pairs(n, n_cameras, intr, rot, centres, focal, ids1, ids2, px1, px2,
                               o1, d1, o2, d2, ppr, &bad);
    if (st != MCG_OK)
        return st;
    /* (ids checked by the pass above: in [0, n_cameras), so they fit an int) */
    for (k = 0; k < n; k++) {
        id1[k] = (int)ids1[k];
        id2[k] = (int)ids2[k];
    }
    if (!enough_distinct(work, n, id1, id2))
        return MCG_EDEGENERATE;
    /* the optical axes: row 2 of each cam_from_rig */
    for (k = 0; k < n_cameras; k++)
        for (i = 0; i < 3; i++)
            axes[3 * k + i] = rot[9 * k + 6 + i];
    t_rays = robust_now_seconds() - t_start;
    st = mcg_robust_rig_motion(n, o1, d1, o2, d2, id1, id2, n_cameras, ppr, axes, focal, opt, res,
                               mask, weights, rest, lwork - (size_t)(rest - work));
    /* (the search cleared *res: the rays' time is added after it) */
    res->seconds_rays = t_rays;
    res->seconds += t_rays;
    return st;
}
