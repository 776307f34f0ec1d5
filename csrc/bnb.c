/*
 * bnb.c -- globally optimal L-infinity rig motion by branch and bound over
 * rotations with LP feasibility tests (thesis ch. 10, Algorithm 7), in the
 * convention of mcgeom.h: X2 = R X1 + t.
 *
 * The objective. For a rotation R and a bound eps, correspondence i (ray
 * a1 + l d1 at time 1, a2 + l' d2 at time 2, rig frames) constrains the
 * translation to its wedge (wedge.c, eqs. 10.9-10.12):
 *     n.(t - (a2 - R a1)) >= 0   for n in {n1, n2}(R d1, d2, eps, eps),
 * eq. 10.13 written for t (the apex a2 - R a1 is c_k - R c_k for an
 * intra-camera correspondence; the thesis writes the same rows for the new
 * centre of the first camera, which differs from t by a known rigid map).
 * bnb_feasible(R, eps) holds when
 *   (a) for every group g of correspondences that share the apex (one camera
 *       at both times, or one ordered pair of cameras), the polyhedral cone
 *       of its wedges contains a non-zero direction (the single-camera test
 *       of ch. 10.3, an LP in 2 variables), and
 *   (b) all wedges have a common point t (the LP in 3 variables of ch. 10.3).
 * Where R d1 and d2 are far apart (the cone about the mid-axis of d2 and
 * -R d1 that holds both bearing cones is narrower than CAP_MAX) each wedge
 * is capped by two more rows (cap_rows: that cone's tangent planes along
 * the epipolar plane), a relaxation of eq. 10.5 as the wedge is, which keeps
 * the relaxed tests of far blocks from passing on the wedges' far ends.
 * The L-infinity error at R is f(R) = min { eps : bnb_feasible(R, eps) } (the
 * thesis's residual, found by bisection: FindMinError). (a) matters: the
 * wedges are closed cones at their apexes, so without (a) t could sit on a
 * camera's apex and "explain" its correspondences with a zero baseline (at
 * R = I every apex is the origin and (b) alone is always feasible).
 *
 * The bound (ch. 10.1-10.2, with the rig's apexes). Blocks are cubes of
 * half-side sigma in angle-axis space. Every rotation R of the block with
 * centre R0 is within angle sqrt(3) sigma of R0 (Hartley and Kahl), so
 * R d1 lies within s = sqrt(3) sigma of R0 d1 and the apex moves by
 * |(R - R0) a1| <= s |a1|. Hence bnb_feasible(R, eps) for some R of the block
 * implies that the tests pass at R0 with the bound eps + s on the rotated
 * bearing (eps on d2) and every right-hand side lowered by s |a1|. If that
 * relaxed test fails at eps = eps_best - gap, no rotation of the block can
 * improve the incumbent by more than gap and the block is discarded.
 *
 * Preemptive tests (ch. 10.3, "Feasibility test"). A test is decided by its
 * first failing part: first every group's 2-variable test on the few
 * correspondences with the widest angle alpha between R0 d1 and d2 (their
 * wedges are the narrowest, so infeasibility shows there first), then each
 * group's 2-variable test on all its correspondences, then the 3-variable
 * LP. With preemption off the same parts run in the order 3-variable LP
 * first, then the groups: the same answers, the thesis's "pure LP" cost.
 *
 * The 2-variable test. Every wedge contains its central direction z (the
 * sum n1 + n2 is along z) and, for a non-zero b in the wedge, z.b >= 0 with
 * equality only on the wedge's edge. With w the sum of the unit z of a
 * group, a non-zero b of the group's cone has w.b > 0 unless b lies on every
 * edge (all edges parallel); so the cone is non-trivial iff it meets the
 * plane w.b = 1: b = w / |w|^2 + P y, y in R^2 (P an orthonormal basis of
 * the plane orthogonal to w). A group with fewer than two wedges, or whose
 * edges are all parallel, always passes.
 *
 * Search. Best-first on a binary heap keyed by a lower bound of f over the
 * block (inherited from the parent, tightened by two bisection steps of the
 * relaxed test); the initial blocks tile [-pi, pi]^3 (grid^3 cubes, those
 * outside the ball of radius pi dropped). A block that survives is tested
 * at its centre (sigma = 0) against the incumbent, and FindMinError
 * improves the incumbent when it passes. Blocks with sqrt(3) sigma at or
 * below the resolution are not split: their lower bound is bisected to the
 * tolerance. The certified lower bound is the smallest of the leaves'
 * bounds, the bounds of blocks still queued, and the levels at which blocks
 * were discarded; it bounds f over all rotations, and f is a relaxation of
 * the exact L-infinity problem (eq. 10.5), so it bounds that too.
 *
 * Memory: the caller's workspace (mcg_bnb_work_size) holds the wedge rows,
 * the LP workspace and a heap of at most max_queue blocks; when the heap is
 * full a block is closed as a leaf with its current (weaker) bound, which
 * keeps the lower bound certified and widens the reported gap.
 *
 * The parts (bnb_internal.h: what they share): this file, the options, the
 * workspace, the search frame, the best-first search and the certificate;
 * bnb_feasible.c, feasible(R, eps) and FindMinError; bnb_polish.c, the
 * incumbent's polish.
 */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */
#include "bnb_internal.h"

#include <math.h>
#include <string.h>
#include <time.h>

#define CLOCK_EVERY 16      /* blocks between two reads of the clock */

double bnb_now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void heap_swap(double *h, int i, int j)
{
    double tmp[BLOCK_DOUBLES];
    memcpy(tmp, h + BLOCK_DOUBLES * i, sizeof tmp);
    memcpy(h + BLOCK_DOUBLES * i, h + BLOCK_DOUBLES * j, sizeof tmp);
    memcpy(h + BLOCK_DOUBLES * j, tmp, sizeof tmp);
}

/* key: lower bound (ascending), ties: larger blocks first */
static int heap_less(const double *h, int i, int j)
{
    const double *a = h + BLOCK_DOUBLES * i, *b = h + BLOCK_DOUBLES * j;
    if (a[4] != b[4])
        return a[4] < b[4];
    return a[3] > b[3];
}

static void heap_push(double *h, int *size, const double blk[BLOCK_DOUBLES])
{
    int i = (*size)++;
    memcpy(h + BLOCK_DOUBLES * i, blk, BLOCK_DOUBLES * sizeof(double));
    while (i > 0 && heap_less(h, i, (i - 1) / 2)) {
        heap_swap(h, i, (i - 1) / 2);
        i = (i - 1) / 2;
    }
}

static void heap_pop(double *h, int *size, double blk[BLOCK_DOUBLES])
{
    int i = 0;
    memcpy(blk, h, BLOCK_DOUBLES * sizeof(double));
    --*size;
    if (*size == 0)
        return;
    memcpy(h, h + BLOCK_DOUBLES * *size, BLOCK_DOUBLES * sizeof(double));
    for (;;) {
        int l = 2 * i + 1, r = l + 1, m = i;
        if (l < *size && heap_less(h, l, m))
            m = l;
        if (r < *size && heap_less(h, r, m))
            m = r;
        if (m == i)
            break;
        heap_swap(h, i, m);
        i = m;
    }
}

/* distance from the origin to the cube (centre, half-side) */
static double cube_distance(const double ctr[3], double sig)
{
    double d2 = 0.0;
    int k;
    for (k = 0; k < 3; ++k) {
        double e = fabs(ctr[k]) - sig;
        if (e > 0.0)
            d2 += e * e;
    }
    return sqrt(d2);
}

void mcg_bnb_default_options(mcg_bnb_options *opt)
{
    if (!opt)
        return;
    opt->resolution = 1e-4;
    opt->gap = 0.0;
    opt->tol = 1e-9;
    opt->max_blocks = 2000000;
    opt->max_queue = 200000;
    opt->grid = 5;
    opt->preemptive = 1;
    opt->working_sets = 1;
    opt->polish_tol = 1e-9;
    opt->bound_steps = 1;
    opt->leaf_gap = -1.0;
    opt->centre[0] = opt->centre[1] = opt->centre[2] = 0.0;
    opt->half_side = 0.0;
    opt->lp = NULL;
    opt->max_seconds = 0.0;
}

static int check_options(const mcg_bnb_options *o)
{
    if (!(isfinite(o->resolution) && o->resolution > 0.0 && o->resolution < 1.0))
        return 0;
    if (!(isfinite(o->gap) && o->gap >= 0.0 && o->gap < 1.0))
        return 0;
    if (!(isfinite(o->tol) && o->tol >= 1e-15 && o->tol < 1e-2))
        return 0;
    if (o->max_blocks < 0 || o->max_queue < 1 || o->max_queue > (1 << 26))
        return 0;
    if (o->grid < 1 || o->grid > 64 || o->bound_steps < 0 || o->bound_steps > 60)
        return 0;
    if (!(isfinite(o->leaf_gap) && o->leaf_gap < 1.0))
        return 0;
    if (!(isfinite(o->polish_tol) && o->polish_tol >= 0.0 && o->polish_tol < 1.0))
        return 0;
    if (!(isfinite(o->half_side) && o->half_side >= 0.0 && o->half_side <= PI) ||
        !all_finite(o->centre, 3) || fabs(o->centre[0]) > 2 * PI ||
        fabs(o->centre[1]) > 2 * PI || fabs(o->centre[2]) > 2 * PI)
        return 0;
    if (!(isfinite(o->max_seconds) && o->max_seconds >= 0.0 && o->max_seconds <= 1e9))
        return 0;
    return 1;
}

size_t mcg_bnb_work_size(int n, int n_groups, const mcg_bnb_options *opt)
{
    mcg_bnb_options d;
    size_t lp2, lp3, lp, total;
    int ok = 1;
    if (n < 1 || n > (1 << 20) || n_groups < 1 || n_groups > n)
        return 0;
    if (!opt) {
        mcg_bnb_default_options(&d);
        opt = &d;
    }
    if (!check_options(opt))
        return 0;
    if (opt->lp) {
        lp2 = mcg_lp_work_size(opt->lp, 2, ROWS_PER * n);
        lp3 = mcg_lp_work_size(opt->lp, 3, ROWS_PER * n);
    } else {
        lp2 = mcg_lp_native_work_size(2, ROWS_PER * n);
        lp3 = mcg_lp_native_work_size(3, ROWS_PER * n);
    }
    if (lp2 == 0 || lp3 == 0)
        return 0;
    lp = max_sz(lp2, lp3);
    /* rows r = ROWS_PER n: A3 3r, b3 r, A2 2r, b2 r, rid where 2r; a1n n,
     * a1 a2 u1 u2 12n, zsum gapex 6G, ws (G+1) WS_CAP, nws G+1, Asub bsub
     * 4 WS_CAP, ints (order n, gstart G+1, grows G, gfirst G) one per double,
     * heap, LP */
    total = add_sz(mul_sz(9 * ROWS_PER + 14, (size_t)n, &ok), mul_sz(10 + WS_CAP, (size_t)n_groups + 1, &ok), &ok);
    total = add_sz(total, 4 * WS_CAP, &ok);
    total = add_sz(total, mul_sz(BLOCK_DOUBLES, (size_t)opt->max_queue, &ok), &ok);
    total = add_sz(total, lp, &ok);
    return ok ? total : 0;
}

/* sort order[lo, hi) by key descending (insertion sort: groups are small
 * relative to the search cost; stable) */
static void sort_desc(int *order, const double *key, int lo, int hi)
{
    int i, j;
    for (i = lo + 1; i < hi; ++i) {
        int v = order[i];
        for (j = i; j > lo && key[order[j - 1]] < key[v]; --j)
            order[j] = order[j - 1];
        order[j] = v;
    }
}

/* The argument checks of mcg_bnb_linf (its header comment lists them). */
static int check_inputs(int n, const double *d1, const double *a1, const double *d2,
                        const double *a2, const int *group, int n_groups,
                        const double R_init[9], const mcg_bnb_options *o,
                        const double *work, size_t lwork)
{
    size_t need;
    int i, k;
    if (!check_options(o))
        return MCG_EINVAL;
    if (n < 1 || n > (1 << 20) || n_groups < 1 || n_groups > n)
        return MCG_EINVAL;
    if (!d1 || !a1 || !d2 || !a2 || !group || !R_init || !work)
        return MCG_EINVAL;
    need = mcg_bnb_work_size(n, n_groups, o);
    if (need == 0)
        return MCG_EINVAL;
    if (lwork < need)
        return MCG_ENOMEM;
    if (!all_finite(d1, 3 * (size_t)n) || !all_finite(a1, 3 * (size_t)n) ||
        !all_finite(d2, 3 * (size_t)n) || !all_finite(a2, 3 * (size_t)n) ||
        !all_finite(R_init, 9))
        return MCG_EINVAL;
    for (i = 0; i < n; ++i) {
        if (group[i] < 0 || group[i] >= n_groups)
            return MCG_EINVAL;
        if (!(dot3(d1 + 3 * i, d1 + 3 * i) > 1e-200) || !(dot3(d2 + 3 * i, d2 + 3 * i) > 1e-200))
            return MCG_EINVAL;
        /* |value| <= 1e150: squares and products of bearings and origins
         * stay finite (a bearing of 1e200 would normalise to 0 or NaN) */
        for (k = 0; k < 3; ++k)
            if (fabs(a1[3 * i + k]) > 1e150 || fabs(a2[3 * i + k]) > 1e150 ||
                fabs(d1[3 * i + k]) > 1e150 || fabs(d2[3 * i + k]) > 1e150)
                return MCG_EINVAL;
    }
    return MCG_OK;
}

/* Carve the caller's workspace (sized by mcg_bnb_work_size) into the arrays
 * of the context, the correspondence order, the group offsets and the block
 * heap, and reset the counters and working sets. */
static void carve_workspace(bnb_ctx *c, int n, int n_groups, const mcg_bnb_options *o,
                            double *work, size_t lwork, int **order, int **gstart,
                            double **heap)
{
    double *w = work;
    int i, g;
    c->n = n;
    c->G = n_groups;
    c->a1 = w;
    w += 3 * (size_t)n;
    c->a2 = w;
    w += 3 * (size_t)n;
    c->A3 = w;
    w += 3 * ROWS_PER * (size_t)n;
    c->b3 = w;
    w += ROWS_PER * (size_t)n;
    c->A2 = w;
    w += 2 * ROWS_PER * (size_t)n;
    c->b2 = w;
    w += ROWS_PER * (size_t)n;
    c->a1n = w;
    w += (size_t)n;
    c->u1 = w;
    w += 3 * (size_t)n;
    c->u2 = w;
    w += 3 * (size_t)n;
    c->rid = (int *)w;
    w += ROWS_PER * (size_t)n;
    c->where = (int *)w;
    w += ROWS_PER * (size_t)n;
    c->ws = (int *)w;
    w += WS_CAP * ((size_t)n_groups + 1);
    c->nws = (int *)w;
    w += (size_t)n_groups + 1;
    c->Asub = w;
    w += 3 * WS_CAP;
    c->bsub = w;
    w += WS_CAP;
    c->zsum = w;
    w += 3 * (size_t)n_groups;
    c->gapex = w;
    w += 3 * (size_t)n_groups;
    *order = (int *)w;
    w += (size_t)n;
    *gstart = (int *)w;
    w += (size_t)n_groups + 1;
    c->grows = (int *)w;
    w += (size_t)n_groups;
    c->gfirst = (int *)w;
    w += (size_t)n_groups;
    *heap = w;
    w += BLOCK_DOUBLES * (size_t)o->max_queue;
    c->lpw = w;
    c->lplen = lwork - (size_t)(w - work);
    c->lp = o->lp;
    c->preemptive = o->preemptive != 0;
    c->working_sets = o->working_sets != 0;
    c->lp2 = c->lp3 = c->hints = c->undecided = 0;
    for (i = 0; i < ROWS_PER * n; ++i)
        c->where[i] = -1;
    for (g = 0; g <= n_groups; ++g)
        c->nws[g] = 0;
    c->have_hint = 0;
    c->order = *order;
    c->gstart = *gstart;
}

/* Work in a frame centred on the ray origins and scaled by their spread
 * (t' = (t + R oc - oc) / L): the LPs' tolerances are relative to the
 * scene, so the answers do not depend on the rig frame's origin or unit
 * (up to rounding). Fills the centred origins, their norms |a1| (the apex
 * motion bound s |a1| of ch. 10.1-10.2) and the unit bearings; returns L,
 * oc the centroid. */
static double to_search_frame(bnb_ctx *c, int n, const double *d1, const double *a1,
                              const double *d2, const double *a2, double oc[3])
{
    double L = origin_spread(n, a1, a2, oc);
    int i, k;
    if (!(L > 1e-150))
        L = 1.0;
    for (i = 0; i < n; ++i) {
        double n1 = sqrt(dot3(d1 + 3 * i, d1 + 3 * i));
        double n2 = sqrt(dot3(d2 + 3 * i, d2 + 3 * i));
        for (k = 0; k < 3; ++k) {
            c->a1[3 * i + k] = (a1[3 * i + k] - oc[k]) / L;
            c->a2[3 * i + k] = (a2[3 * i + k] - oc[k]) / L;
        }
        c->a1n[i] = sqrt(dot3(c->a1 + 3 * i, c->a1 + 3 * i));
        for (k = 0; k < 3; ++k) {
            c->u1[3 * i + k] = d1[3 * i + k] / n1;
            c->u2[3 * i + k] = d2[3 * i + k] / n2;
        }
    }
    return L;
}

/* The correspondence order: by group, then by the angle alpha between
 * R_init d1 and d2 descending (the widest, narrowest wedges first: the
 * preemptive test of ch. 10.3); the alphas live in the 2-variable rows'
 * slot until the search starts. */
static void order_correspondences(bnb_ctx *c, int n, int n_groups, const int *group,
                                  const double Rb[9], const double *d1, const double *d2,
                                  int *order, int *gstart)
{
    double *alpha;
    int i, g;
    for (g = 0; g <= n_groups; ++g)
        gstart[g] = 0;
    for (i = 0; i < n; ++i)
        ++gstart[group[i] + 1];
    for (g = 0; g < n_groups; ++g)
        gstart[g + 1] += gstart[g];
    for (g = 0; g < n_groups; ++g)
        c->grows[g] = gstart[g];
    for (i = 0; i < n; ++i)
        order[c->grows[group[i]]++] = i;
    alpha = c->A2;
    for (i = 0; i < n; ++i) {
        double v[3], cr[3];
        const double *q = d2 + 3 * i;
        mat_vec(Rb, d1 + 3 * i, v);
        cross3(v, q, cr);
        alpha[i] = atan2(sqrt(dot3(cr, cr)), dot3(v, q));
    }
    for (g = 0; g < n_groups; ++g)
        sort_desc(order, alpha, gstart[g], gstart[g + 1]);
}

/* The incumbent f(R_init) by doubling then bisection (Algorithm 5, line 1):
 * res->R, t, linf and initial_linf. */
static int initial_incumbent(bnb_ctx *c, const double Rb[9], double tol,
                             mcg_bnb_result *res)
{
    double eps = 1e-3, lo = 0.0, t[3];
    int r, st;
    for (;;) {
        r = bnb_feasible(c, Rb, eps, 0.0, t);
        if (r < 0)
            return -r;
        if (r == 1)
            break;
        lo = eps;
        eps *= 2.0;
        if (eps >= EPS_MAX)
            return MCG_ENUMERIC; /* every bound up to ~86 deg infeasible */
    }
    st = bnb_find_min_error(c, Rb, 0.0, lo, &eps, t, tol, 0);
    if (st != MCG_OK)
        return st;
    memcpy(res->R, Rb, sizeof res->R);
    memcpy(res->t, t, sizeof res->t);
    res->linf = eps;
    res->initial_linf = eps;
    return MCG_OK;
}

/* The state of the best-first search: the block heap and the bounds of the
 * blocks that left it (the certified lower bound is the smallest of these
 * and of the queued blocks' bounds). */
typedef struct {
    double *heap;
    int hsize;
    long blocks, leaves;
    double leaf_lb;  /* smallest bound of a block closed as a leaf */
    double prune_lb; /* smallest level at which a block was discarded */
} bnb_search;

/* The initial tiling of [-pi, pi]^3 (or of the region cube) into grid^3
 * cubes, those outside the ball of radius pi dropped. */
static void initial_tiling(bnb_search *q, const mcg_bnb_options *o)
{
    double half = o->half_side > 0.0 ? o->half_side : PI, sig = half / o->grid;
    double blk[BLOCK_DOUBLES];
    const double zero[3] = {0.0, 0.0, 0.0};
    const double *ctr = o->half_side > 0.0 ? o->centre : zero;
    int gi, gj, gk;
    for (gi = 0; gi < o->grid; ++gi)
        for (gj = 0; gj < o->grid; ++gj)
            for (gk = 0; gk < o->grid; ++gk) {
                blk[0] = ctr[0] - half + (2 * gi + 1) * sig;
                blk[1] = ctr[1] - half + (2 * gj + 1) * sig;
                blk[2] = ctr[2] - half + (2 * gk + 1) * sig;
                blk[3] = sig;
                blk[4] = 0.0;
                if (cube_distance(blk, sig) > PI)
                    continue;
                if (q->hsize < o->max_queue)
                    heap_push(q->heap, &q->hsize, blk);
                else if (q->leaf_lb > 0.0)
                    q->leaf_lb = 0.0; /* no room: an unexplored block */
            }
}

/* A block at the resolution (or with no queue space for its children):
 * close it at linf - leaf_gap with one relaxed test if it fails there, else
 * bisect its bound to the tolerance (FindMinError on the relaxed test). */
static int close_leaf(bnb_ctx *c, const mcg_bnb_options *o, mcg_bnb_result *res,
                      bnb_search *q, const double R0[9], double s, double lb,
                      double target, double leaf_gap)
{
    double level = res->linf - leaf_gap, hi, tt[3];
    int r, st;
    ++q->leaves;
    if (q->hsize + 8 > o->max_queue && s > o->resolution)
        res->stop = MCG_BNB_QUEUE_FULL;
    if (level > lb) {
        r = bnb_feasible(c, R0, level, s, tt);
        if (r < 0)
            return -r;
        if (!r) {
            if (level < q->leaf_lb)
                q->leaf_lb = level;
            return MCG_OK;
        }
        hi = level;
    } else {
        hi = target;
    }
    st = bnb_find_min_error(c, R0, s, lb, &hi, tt, o->tol, 1);
    if (st != MCG_OK)
        return st;
    lb = hi - o->tol;
    if (lb < q->leaf_lb)
        q->leaf_lb = lb;
    return MCG_OK;
}

/* Split a surviving block: tighten its lower bound (the best-first key) by
 * bound_steps bisection steps of the relaxed test, then queue the children
 * that meet the ball of radius pi with that bound. */
static int split_block(bnb_ctx *c, const mcg_bnb_options *o, bnb_search *q,
                       const double blk[BLOCK_DOUBLES], const double R0[9], double s,
                       double target)
{
    double lb = blk[4], hi = target, tt[3];
    int k, gi, r;
    for (k = 0; k < o->bound_steps && hi > lb; ++k) {
        double mid = 0.5 * (lb + hi);
        r = bnb_feasible(c, R0, mid, s, tt);
        if (r < 0)
            return -r;
        if (r)
            hi = mid;
        else
            lb = mid;
    }
    for (gi = 0; gi < 8; ++gi) {
        double ch[BLOCK_DOUBLES], hs = 0.5 * blk[3];
        ch[0] = blk[0] + ((gi & 1) ? hs : -hs);
        ch[1] = blk[1] + ((gi & 2) ? hs : -hs);
        ch[2] = blk[2] + ((gi & 4) ? hs : -hs);
        ch[3] = hs;
        ch[4] = lb;
        if (cube_distance(ch, hs) <= PI)
            heap_push(q->heap, &q->hsize, ch);
    }
    return MCG_OK;
}

/* One block of the search (Algorithm 5's loop body): discard it if the
 * relaxed test (eps + s on the rotated bearings, right-hand sides lowered
 * by s |a1|, ch. 10.1-10.2) fails at linf - gap; else try its centre
 * against the incumbent (lines 11-13), then close it as a leaf or split it. */
static int process_block(bnb_ctx *c, const mcg_bnb_options *o, mcg_bnb_result *res,
                         bnb_search *q, const double blk[BLOCK_DOUBLES], double leaf_gap)
{
    double R0[9], s = SQRT3 * blk[3], target, hi, tt[3];
    int r, st;
    st = mcg_rot_from_angle_axis(blk, R0);
    if (st != MCG_OK)
        return st;
    target = res->linf - o->gap;
    r = bnb_feasible(c, R0, target, s, tt);
    if (r < 0)
        return -r;
    if (!r) {
        if (target < q->prune_lb)
            q->prune_lb = target;
        return MCG_OK;
    }
    r = bnb_feasible(c, R0, res->linf, 0.0, tt);
    if (r < 0)
        return -r;
    if (r == 1) {
        hi = res->linf;
        st = bnb_find_min_error(c, R0, 0.0, blk[4], &hi, tt, o->tol, 0);
        if (st != MCG_OK)
            return st;
        if (hi < res->linf) {
            res->linf = hi;
            memcpy(res->R, R0, sizeof R0);
            memcpy(res->t, tt, sizeof tt);
            target = res->linf - o->gap;
        }
    }
    if (s <= o->resolution || q->hsize + 8 > o->max_queue)
        return close_leaf(c, o, res, q, R0, s, blk[4], target, leaf_gap);
    return split_block(c, o, q, blk, R0, s, target);
}

/* The best-first search (Algorithm 7): pop the block of smallest lower bound
 * until none can improve the incumbent by more than gap or a budget
 * (max_blocks, max_seconds) is spent; res->stop says which. */
static int best_first_search(bnb_ctx *c, const mcg_bnb_options *o, mcg_bnb_result *res,
                             bnb_search *q, double deadline)
{
    double leaf_gap = o->leaf_gap < 0.0 ? 0.5 * o->resolution : o->leaf_gap;
    double blk[BLOCK_DOUBLES];
    int st;
    res->stop = MCG_BNB_CONVERGED;
    while (q->hsize > 0) {
        if (q->heap[4] >= res->linf - o->gap)
            break; /* best-first: no queued block can improve by > gap */
        if (q->blocks >= o->max_blocks) {
            res->stop = MCG_BNB_MAX_BLOCKS;
            break;
        }
        if (o->max_seconds > 0.0 && q->blocks % CLOCK_EVERY == 0 &&
            bnb_now_seconds() > deadline) {
            res->stop = MCG_BNB_TIME_LIMIT; /* the queue's bounds stay certified */
            break;
        }
        heap_pop(q->heap, &q->hsize, blk);
        ++q->blocks;
        st = process_block(c, o, res, q, blk, leaf_gap);
        if (st != MCG_OK)
            return st;
    }
    return MCG_OK;
}

/* The certified lower bound over all rotations: the smallest of the
 * incumbent, the queued blocks' bounds, the leaves' bounds and the levels
 * at which blocks were discarded (never below 0). */
static double certified_lower_bound(const bnb_search *q, double linf)
{
    double lo = linf;
    if (q->hsize > 0 && q->heap[4] < lo)
        lo = q->heap[4];
    if (q->leaf_lb < lo)
        lo = q->leaf_lb;
    if (q->prune_lb < lo)
        lo = q->prune_lb;
    if (lo < 0.0)
        lo = 0.0;
    return lo;
}

int mcg_bnb_linf(int n, const double *d1, const double *a1, const double *d2,
                 const double *a2, const int *group, int n_groups,
                 const double R_init[9], const mcg_bnb_options *opt,
                 mcg_bnb_result *res, double *work, size_t lwork)
{
    mcg_bnb_options o;
    mcg_lp_backend native;
    bnb_ctx c;
    bnb_search q;
    double lo, Rb[9], t0, L, oc[3], deadline;
    int *order, *gstart, k, st;

    t0 = bnb_now_seconds();
    if (!res)
        return MCG_EINVAL;
    memset(res, 0, sizeof *res);
    if (opt)
        o = *opt;
    else
        mcg_bnb_default_options(&o);
    st = check_inputs(n, d1, a1, d2, a2, group, n_groups, R_init, &o, work, lwork);
    if (st != MCG_OK)
        return st;
    deadline = o.max_seconds > 0.0 ? t0 + o.max_seconds : INFINITY;
    if (!o.lp) {
        mcg_lp_native_backend(&native);
        o.lp = &native;
    }
    st = mcg_project_so3(R_init, Rb);
    if (st != MCG_OK)
        return st;

    carve_workspace(&c, n, n_groups, &o, work, lwork, &order, &gstart, &q.heap);
    L = to_search_frame(&c, n, d1, a1, d2, a2, oc);
    order_correspondences(&c, n, n_groups, group, Rb, d1, d2, order, gstart);
    st = initial_incumbent(&c, Rb, o.tol, res);
    if (st != MCG_OK)
        return st;

    q.hsize = 0;
    q.blocks = q.leaves = 0;
    q.leaf_lb = q.prune_lb = INFINITY;
    initial_tiling(&q, &o);
    st = best_first_search(&c, &o, res, &q, deadline);
    if (st != MCG_OK)
        return st;
    lo = certified_lower_bound(&q, res->linf);
    res->lower_bound = lo;
    /* the polish bisects f from this floor: below the certified bound by the
     * tolerance, but never below 0 (f is an angle; a negative floor let the
     * relaxed tests pass at negative bounds and linf came out < 0, found by
     * fuzz_bnb) */
    c.floor = lo - 2.0 * o.tol > 0.0 ? lo - 2.0 * o.tol : 0.0;
    if (o.polish_tol > 0.0 && o.polish_tol < o.resolution && o.max_blocks > 0) {
        long tests = 0;
        st = bnb_polish_slp(&c, &o, res, &tests, deadline);
        if (st != MCG_OK)
            return st;
        res->polish_tests = tests;
        if (res->linf < lo) /* only within the LPs' tolerances */
            lo = res->lower_bound = res->linf;
    }
    res->gap = res->linf - lo;
    /* back to the caller's frame: t = L t' - R oc + oc */
    {
        double ro[3];
        mat_vec(res->R, oc, ro);
        for (k = 0; k < 3; ++k)
            res->t[k] = L * res->t[k] - ro[k] + oc[k];
    }
    res->blocks = q.blocks;
    res->queued = q.hsize;
    res->lps_2var = c.lp2;
    res->lps_3var = c.lp3;
    res->hints = c.hints;
    res->undecided = c.undecided;
    res->leaves = q.leaves;
    res->seconds = bnb_now_seconds() - t0;
    return MCG_OK;
}
