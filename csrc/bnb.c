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
 * feasible(R, eps) holds when
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
 * The L-infinity error at R is f(R) = min { eps : feasible(R, eps) } (the
 * thesis's residual, found by bisection: FindMinError). (a) matters: the
 * wedges are closed cones at their apexes, so without (a) t could sit on a
 * camera's apex and "explain" its correspondences with a zero baseline (at
 * R = I every apex is the origin and (b) alone is always feasible).
 *
 * The bound (ch. 10.1-10.2, with the rig's apexes). Blocks are cubes of
 * half-side sigma in angle-axis space. Every rotation R of the block with
 * centre R0 is within angle sqrt(3) sigma of R0 (Hartley and Kahl), so
 * R d1 lies within s = sqrt(3) sigma of R0 d1 and the apex moves by
 * |(R - R0) a1| <= s |a1|. Hence feasible(R, eps) for some R of the block
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
 */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */

#include "mcgeom.h"
#include "internal.h"

#include <math.h>
#include <string.h>
#include <time.h>

#define SQRT3 1.7320508075688772
#define PI 3.14159265358979323846
#define EPS_MAX 1.5         /* a bound beyond this (rad) constrains nothing */
#define SUBSET 32           /* widest-angle correspondences tested first: a
                               subset's infeasibility proves the group's, and
                               most blocks of a search are discarded by one;
                               measured on 300 KITTI raw inliers (two groups
                               of ~150, gap 1e-4): 8 -> 32 took the 2-variable
                               LPs from 190k to 100k and the search from 1.05
                               to 0.84 s CPU (16: 0.96, 64: 0.88 s) */
#define ROWS_PER 4          /* rows of a correspondence: its wedge and its cap */
#define CAP_MAX 1.5         /* caps only of radius below this (rad, ~75 deg) */
#define BLOCK_DOUBLES 5     /* centre (3), half-side, lower bound */
#define WS_CAP 48           /* rows of a working set before a full LP */
#define WS_ADD 4            /* most violated rows added per round */
#define BISECT_MAX 200      /* bisection steps: (0, 1.5] to tol >= 1e-15
                               takes <= 51; the cap only guards the loop */
#define CLOCK_EVERY 16      /* blocks between two reads of the clock */
/* A test the LP backend could not decide (MCG_ENUMERIC: its point failed the
 * verification, seen only at bounds ~1e-10 rad on noise-free data): taken as
 * feasible where a lower bound is at stake (no block is wrongly discarded)
 * and as infeasible where an upper bound is (no error is wrongly claimed). */
#define UNDECIDED 2

typedef struct {
    int n, G;
    double *a1, *a2;        /* origins, centred and scaled (work) */
    double *u1, *u2;        /* unit bearings d1, d2 (work) */
    const int *order;       /* by group, then alpha descending (work) */
    const int *gstart;      /* G + 1 offsets into order (work) */
    double *a1n;            /* |a1_i| */
    double *A3, *b3;        /* <= 4n rows of the 3-variable LP (ROWS_PER) */
    double *A2, *b2;        /* rows of one 2-variable LP (2 n_g) */
    double *zsum;           /* 3 G: sum of unit wedge centres per group */
    int *grows;             /* rows of each group in A3 (count) */
    int *gfirst;            /* first row of each group in A3 */
    double *lpw;
    size_t lplen;
    const mcg_lp_backend *lp;
    int preemptive;
    int working_sets;       /* 0: every LP on all its rows, no hints */
    long lp2, lp3, hints, undecided;
    double floor;           /* certified lower bound of f (for the polish) */
    double apex[3];         /* apex of the group being built */
    double *gapex;          /* 3 G: each group's apex */
    double t_hint[3];       /* the last feasible translation */
    int have_hint;
    /* working sets of the constraint-generation LPs (see lp_working_set) */
    int *rid;               /* 4n: stable id (4 i + k) of each row of A3 */
    int *where;             /* 4n: row of an id in the current view */
    int *ws;                /* (G + 1) x WS_CAP ids: slot 0 the 3-variable
                               LP, slot 1 + g group g's 2-variable LP */
    int *nws;               /* G + 1 sizes */
    double *Asub, *bsub;    /* WS_CAP rows */
} bnb_ctx;

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The sines of the two half-angles at (eps, s), enlarged as in wedge.c so
 * that rounding never tightens a wedge; 0 if the cones are too wide to
 * constrain anything (then no rows). */
static int wedge_sines(double eps, double s, double *sb, double *sa)
{
    double e1 = eps + s;
    if (e1 >= EPS_MAX)
        return 0; /* such cones leave (almost) every direction open */
    *sb = sin(e1 * (1.0 + 1e-12) + 1e-15);  /* the rotated bearing R d1 */
    *sa = sin(eps * (1.0 + 1e-12) + 1e-15); /* the bearing d2 */
    return 1;
}

/* A unit vector orthogonal to the non-zero v: v x e_k, normalised, with
 * e_k the axis of v's smallest component (never nearly parallel to v). */
static void unit_orthogonal(const double v[3], double p[3])
{
    double e[3] = {0.0, 0.0, 0.0}, n;
    int k, imin = 0;
    for (k = 1; k < 3; ++k)
        if (fabs(v[k]) < fabs(v[imin]))
            imin = k;
    e[imin] = 1.0;
    cross3(v, e, p);
    n = sqrt(dot3(p, p));
    for (k = 0; k < 3; ++k)
        p[k] /= n;
}

/* The cap of a wedge (this library's tightening of eqs. 10.9-10.13). The
 * wedge of correspondence i, two planes through its apex, stands for the
 * baselines b = l x1 - m x2 (l, m >= 0) with x1 within eps_1 of R d1 and x2
 * within eps_2 of d2: the conic hull of the cones about the axes a = d2 and
 * c = -R d1 (as wedge_rows orients them). The planes bound that hull across
 * the epipolar plane only; along the plane the wedge runs on to the
 * antipodes. Every direction of either cone is within th = gamma / 2 +
 * max(eps_1, eps_2) of the mid-axis m = (a + c) / |a + c| (gamma =
 * angle(a, c)), so the hull lies in the cone about m of half-angle th and,
 * when th < pi/2, in both half-spaces n.b >= 0, n = sin(th) m +- cos(th) p,
 * p = (a - c) / |a - c| (for b at angle phi <= th from m: n.b >= sin(th -
 * phi) >= 0). These two rows cap the wedge along the epipolar plane. Like
 * the wedge, they never cut a baseline the exact problem (eq. 10.5) allows,
 * and the relaxed rows of a block (eps_1 + s about R0 d1, apex lowered by
 * s |a1|) hold the hulls of all its rotations (each within s of R0 d1): the
 * certificate is unchanged. Where the bearings nearly agree (gamma near pi,
 * the usual case near the motion) th reaches pi/2 and the cap would be a
 * half-space: no rows then (th >= CAP_MAX). Without caps, the relaxed test
 * keeps the far ends of the wedges open until s falls below the axes'
 * misalignment: on KITTI raw (300 inliers of the stereo pair, gap 1e-4)
 * the whole search took 286667 blocks, 94 % of them in the cubes near
 * |w| = pi where f exceeds 0.17 rad; with caps 26352 (measured). Writes 0
 * or 2 rows at A, the cap's axis at z_cap. */
static int cap_rows(const double a[3], const double cax[3], double sa, double sb, double *A,
                    double z_cap[3])
{
    double m[3], p[3], nm, np_, th, st, ct, e1;
    int k;
    for (k = 0; k < 3; ++k) {
        m[k] = a[k] + cax[k];
        p[k] = a[k] - cax[k];
    }
    nm = sqrt(dot3(m, m));
    np_ = sqrt(dot3(p, p));
    /* gamma / 2 = atan2(|a - c|, |a + c|); the wider cone sets the radius */
    e1 = asin(sb > sa ? sb : sa);
    if (!(nm > 0.0) || atan2(np_, nm) + e1 >= CAP_MAX)
        return 0; /* the cap would be (nearly) a half-space: not worth its rows */
    th = atan2(np_, nm) + e1;
    th = th * (1.0 + 1e-12) + 1e-15; /* rounding never tightens it */
    for (k = 0; k < 3; ++k)
        m[k] /= nm;
    if (np_ > 1e-12) {
        for (k = 0; k < 3; ++k)
            p[k] /= np_;
    } else {
        unit_orthogonal(m, p); /* the axes coincide: any direction orthogonal to them */
    }
    st = sin(th);
    ct = cos(th);
    for (k = 0; k < 3; ++k) {
        A[k] = st * m[k] + ct * p[k];
        A[3 + k] = st * m[k] - ct * p[k];
        z_cap[k] = m[k];
    }
    return 2;
}

/* Rows of correspondence i at rotation R (sines from wedge_sines, apex
 * slack s): its wedge (2 rows, none when the cones overlap) and its cap
 * (2 rows where the bearings are far apart, cap_rows), written at row `row` of
 * A3/b3; returns the number (0-4). z: a direction every allowed baseline
 * meets with z.b >= 0, zero only on the edge (the wedge's centre n1 + n2,
 * else the cap's axis). */
static int wedge_rows(bnb_ctx *c, int i, const double R[9], double sb, double sa,
                      double s, int row, double z[3])
{
    double *A = c->A3 + 3 * row, *b = c->b3 + row;
    double v[3], ap[3], n1[3], n2[3], zc[3], off;
    int k, m = 0, j;
    mat_vec(R, c->u1 + 3 * i, v);
    v[0] = -v[0];
    v[1] = -v[1];
    v[2] = -v[2];
    if (mcg_wedge_unit(c->u2 + 3 * i, v, sa, sb, n1, n2) == MCG_OK) {
        memcpy(A, n1, sizeof n1);
        memcpy(A + 3, n2, sizeof n2);
        for (k = 0; k < 3; ++k)
            z[k] = n1[k] + n2[k];
        m = 2;
    }
    if (cap_rows(c->u2 + 3 * i, v, sa, sb, A + 3 * m, zc)) {
        if (m == 0)
            memcpy(z, zc, sizeof zc);
        m += 2;
    }
    if (m == 0)
        return 0; /* cones overlap: no constraint */
    mat_vec(R, c->a1 + 3 * i, ap);
    for (k = 0; k < 3; ++k)
        ap[k] = c->a2[3 * i + k] - ap[k];
    memcpy(c->apex, ap, sizeof ap);
    off = s * c->a1n[i];
    for (j = 0; j < m; ++j) {
        b[j] = dot3(A + 3 * j, ap) - off;
        c->rid[row + j] = ROWS_PER * i + j;
    }
    return m;
}

/* The LP on all m rows (the working set of the slot is emptied). */
static int full_lp(bnb_ctx *c, int dim, int m, const double *A, const double *b,
                   double *x, int *nws)
{
    int st;
    if (dim == 2)
        ++c->lp2;
    else
        ++c->lp3;
    st = mcg_lp_feasible(c->lp, dim, m, A, b, x, c->lpw, c->lplen);
    *nws = 0;
    if (st == MCG_ENUMERIC) {
        ++c->undecided;
        return UNDECIDED; /* the backend could not verify its answer */
    }
    if (st != MCG_OK && st != MCG_EINFEASIBLE)
        return -st;
    return st == MCG_OK;
}

/* LP feasibility of {x : A_j . x >= b_j, j < m} (dim 2 or 3) by constraint
 * generation: solve on the working set of the slot (rows that decided the
 * previous, nearby tests), check every row at the solution, add the most
 * violated ones and repeat. An infeasible subset proves infeasibility; a
 * solution that violates no row is feasible. Consecutive tests differ by a
 * small rotation or bound, so the working set is usually already right and
 * a 400-row LP costs an LP on a dozen rows plus one pass over the rows.
 * ids: the rows' stable ids. 1 feasible (x set), 0 not, < 0 status. */
static int lp_working_set(bnb_ctx *c, int dim, int m, const double *A, const double *b,
                          const int *ids, int slot, double *x)
{
    int *ws = c->ws + (size_t)slot * WS_CAP, *nws = c->nws + slot;
    int S[WS_CAP], ns = 0, j, k, st, na;
    if (m == 0) {
        for (k = 0; k < dim; ++k)
            x[k] = 0.0;
        return 1;
    }
    if (!c->working_sets)
        return full_lp(c, dim, m, A, b, x, nws);
    for (j = 0; j < m; ++j)
        c->where[ids[j]] = j;
    for (k = 0; k < *nws; ++k) {
        j = c->where[ws[k]];
        if (j >= 0 && j < m && ids[j] == ws[k])
            S[ns++] = j;
    }
    for (;;) {
        int add[WS_ADD];
        double viol[WS_ADD];
        na = 0;
        if (ns > 0) {
            for (k = 0; k < ns; ++k) {
                memcpy(c->Asub + dim * k, A + dim * S[k], (size_t)dim * sizeof(double));
                c->bsub[k] = b[S[k]];
            }
            if (dim == 2)
                ++c->lp2;
            else
                ++c->lp3;
            st = mcg_lp_feasible(c->lp, dim, ns, c->Asub, c->bsub, x, c->lpw, c->lplen);
            if (st == MCG_EINFEASIBLE)
                break; /* a subset is infeasible: so is the whole */
            if (st == MCG_ENUMERIC) /* decide on all rows */
                return full_lp(c, dim, m, A, b, x, nws);
            if (st != MCG_OK)
                return -st;
        } else {
            for (k = 0; k < dim; ++k)
                x[k] = c->have_hint && dim == 3 ? c->t_hint[k] : 0.0;
        }
        /* the WS_ADD most violated rows outside the set */
        for (j = 0; j < m; ++j) {
            const double *a = A + dim * j;
            double v = b[j] - (dim == 3 ? a[0] * x[0] + a[1] * x[1] + a[2] * x[2]
                                        : a[0] * x[0] + a[1] * x[1]);
            if (!(v > 0.0))
                continue;
            for (k = 0; k < ns; ++k)
                if (S[k] == j)
                    break;
            if (k < ns)
                continue; /* in the set: satisfied within the LP tolerance */
            if (na < WS_ADD) {
                add[na] = j;
                viol[na++] = v;
            } else {
                int w = 0;
                for (k = 1; k < WS_ADD; ++k)
                    if (viol[k] < viol[w])
                        w = k;
                if (v > viol[w]) {
                    add[w] = j;
                    viol[w] = v;
                }
            }
        }
        if (na == 0) {
            st = MCG_OK;
            break;
        }
        if (ns + na > WS_CAP) /* the set would overflow: decide on all rows */
            return full_lp(c, dim, m, A, b, x, nws);
        for (k = 0; k < na; ++k)
            S[ns++] = add[k];
    }
    for (k = 0; k < ns; ++k)
        ws[k] = ids[S[k]];
    *nws = ns;
    return st == MCG_OK;
}

/* Does the direction b satisfy every row of A (m rows) with w.b > 0? */
static int direction_ok(int m, const double *A, const double b[3], const double w[3])
{
    int j;
    if (!(dot3(w, b) > 0.0))
        return 0;
    for (j = 0; j < m; ++j)
        if (dot3(A + 3 * j, b) < 0.0)
            return 0;
    return 1;
}

/* 2-variable test of one group's rows (m rows of A, zc = sum of unit wedge
 * centres, ap = the group's apex): 1 feasible, 0 not, < 0 status. The last
 * feasible translation, seen from the apex, is tried first: near the
 * optimum it usually lies in the cone and saves the LP. */
static int cone_nontrivial(bnb_ctx *c, int m, const double *A, const double zc[3],
                           const double ap[3], const int *ids, int slot)
{
    double w2 = dot3(zc, zc), P[6], nn;
    int k, j;
    double y[2];
    if (m < 4 || !(w2 > 1e-24))
        return 1; /* fewer than two wedges, or degenerate: always non-trivial */
    if (c->have_hint && ap && c->working_sets) {
        double b[3];
        b[0] = c->t_hint[0] - ap[0];
        b[1] = c->t_hint[1] - ap[1];
        b[2] = c->t_hint[2] - ap[2];
        if (direction_ok(m, A, b, zc)) {
            ++c->hints;
            return 1;
        }
    }
    /* P: orthonormal basis of the plane orthogonal to zc */
    unit_orthogonal(zc, P);
    P[3] = zc[1] * P[2] - zc[2] * P[1];
    P[4] = zc[2] * P[0] - zc[0] * P[2];
    P[5] = zc[0] * P[1] - zc[1] * P[0];
    nn = sqrt(dot3(P + 3, P + 3));
    for (k = 3; k < 6; ++k)
        P[k] /= nn;
    for (j = 0; j < m; ++j) {
        const double *a = A + 3 * j;
        c->A2[2 * j] = dot3(a, P);
        c->A2[2 * j + 1] = dot3(a, P + 3);
        c->b2[j] = -dot3(a, zc) / w2;
    }
    return lp_working_set(c, 2, m, c->A2, c->b2, ids, slot, y);
}

static void add_unit(double acc[3], const double z[3])
{
    double nz = sqrt(dot3(z, z));
    if (nz > 0.0) {
        acc[0] += z[0] / nz;
        acc[1] += z[1] / nz;
        acc[2] += z[2] / nz;
    }
}

static int test_groups(bnb_ctx *c)
{
    int g, r, verdict = 1;
    for (g = 0; g < c->G; ++g) {
        r = cone_nontrivial(c, c->grows[g], c->A3 + 3 * c->gfirst[g], c->zsum + 3 * g,
                            c->gapex + 3 * g, c->rid + c->gfirst[g], 1 + g);
        if (r <= 0)
            return r;
        if (r == UNDECIDED)
            verdict = UNDECIDED;
    }
    return verdict;
}

static int test_all3(bnb_ctx *c, int m, double t[3])
{
    int k, r;
    if (c->have_hint && c->working_sets) {
        for (k = 0; k < m; ++k)
            if (dot3(c->A3 + 3 * k, c->t_hint) < c->b3[k])
                break;
        if (k == m) {
            ++c->hints;
            memcpy(t, c->t_hint, 3 * sizeof(double));
            return 1;
        }
    }
    r = lp_working_set(c, 3, m, c->A3, c->b3, c->rid, 0, t);
    if (r == 1) { /* (an undecided point is no hint) */
        memcpy(c->t_hint, t, 3 * sizeof(double));
        c->have_hint = 1;
    }
    return r;
}

/* feasible(R, eps) relaxed by slack s (see the file comment): 1 with t set
 * (when feasible), 0 infeasible, negative status on error. */
static int feasible(bnb_ctx *c, const double R[9], double eps, double s, double t[3])
{
    int g, j, m = 0, r, verdict = 1;
    double z[3], sb, sa;
    if (!wedge_sines(eps, s, &sb, &sa)) {
        /* no constraint at all: any t will do (the last one) */
        for (j = 0; j < 3; ++j)
            t[j] = c->have_hint ? c->t_hint[j] : 0.0;
        return 1;
    }
    if (c->preemptive) {
        /* stage 1: the widest-angle correspondences of every group */
        for (g = 0; g < c->G; ++g) {
            int cnt = c->gstart[g + 1] - c->gstart[g], mg = 0;
            double zs[3] = {0, 0, 0};
            if (cnt <= SUBSET)
                continue; /* stage 2 tests the whole group anyway */
            for (j = 0; j < SUBSET; ++j) {
                int i = c->order[c->gstart[g] + j];
                r = wedge_rows(c, i, R, sb, sa, s, mg, z);
                if (r)
                    add_unit(zs, z);
                mg += r;
            }
            r = cone_nontrivial(c, mg, c->A3, zs, mg ? c->apex : NULL, c->rid, 1 + g);
            if (r <= 0)
                return r;
            if (r == UNDECIDED)
                verdict = UNDECIDED;
        }
    }
    /* all rows, group by group (stage 2 after each group when preemptive) */
    for (g = 0; g < c->G; ++g) {
        double *zs = c->zsum + 3 * g;
        zs[0] = zs[1] = zs[2] = 0.0;
        c->gfirst[g] = m;
        for (j = c->gstart[g]; j < c->gstart[g + 1]; ++j) {
            r = wedge_rows(c, c->order[j], R, sb, sa, s, m, z);
            if (r)
                add_unit(zs, z);
            m += r;
        }
        c->grows[g] = m - c->gfirst[g];
        memcpy(c->gapex + 3 * g, c->apex, sizeof c->apex);
        if (c->preemptive) {
            r = cone_nontrivial(c, c->grows[g], c->A3 + 3 * c->gfirst[g], zs,
                                c->gapex + 3 * g, c->rid + c->gfirst[g], 1 + g);
            if (r <= 0)
                return r;
            if (r == UNDECIDED)
                verdict = UNDECIDED;
        }
    }
    r = test_all3(c, m, t);
    if (r <= 0)
        return r;
    if (r == UNDECIDED)
        verdict = UNDECIDED;
    if (!c->preemptive) {
        r = test_groups(c); /* "pure LP" order: the same answer, later */
        if (r <= 0)
            return r;
        if (r == UNDECIDED)
            verdict = UNDECIDED;
    }
    return verdict;
}

/* FindMinError: bisection of f(R) in (lo, hi], hi known feasible (t_hi its
 * point). Returns the status; *out_hi, t_hi updated. For a lower bound
 * (lower = 1) an undecided test counts as feasible, for an upper bound as
 * infeasible. */
static int find_min_error(bnb_ctx *c, const double R[9], double s, double lo,
                          double *hi, double t_hi[3], double tol, int lower)
{
    double t[3];
    int it;
    for (it = 0; it < BISECT_MAX && *hi - lo > tol; ++it) {
        double mid = 0.5 * (lo + *hi);
        int r = feasible(c, R, mid, s, t);
        if (r < 0)
            return -r;
        if (r == UNDECIDED)
            r = lower;
        if (r) {
            *hi = mid;
            memcpy(t_hi, t, sizeof t);
        } else {
            lo = mid;
        }
    }
    return MCG_OK;
}

/* The polish (after the search): the local L-infinity minimum over (R, t)
 * by sequential LP (linf_local.c) from the incumbent and from POLISH_STARTS
 * - 1 rotations around it at 3, 10, 30 and 100 x the resolution (fixed
 * pseudo-random directions). The bound of the search cannot tell apart
 * basins whose minima differ by less than the certified gap (about half the
 * resolution): f has shallow valleys whose separate minima can lie some
 * resolutions apart (measured: two minima 6e-4 rad apart, 6.6e-7 rad
 * different, over a ridge 8e-7 high); local minimisations started across
 * that neighbourhood find the lower one. A start costs about 1 ms for 200
 * correspondences. */
#define POLISH_STARTS 13
#define POLISH_MAX_STEPS 200 /* sequential-LP steps per start */

static double lcg_uniform(unsigned long long *state)
{
    *state = *state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*state >> 11) * (1.0 / 9007199254740992.0);
}

/* a pseudo-random unit direction */
static void random_direction(unsigned long long *state, double dir[3])
{
    double n = 0.0;
    int tries;
    /* rejection sampling in the unit ball: a draw is accepted with
     * probability ~0.52, so 1000 tries never all fail in practice; the last
     * draw is kept regardless (any non-zero direction would do) */
    for (tries = 0; tries < 1000; ++tries) {
        dir[0] = 2.0 * lcg_uniform(state) - 1.0;
        dir[1] = 2.0 * lcg_uniform(state) - 1.0;
        dir[2] = 2.0 * lcg_uniform(state) - 1.0;
        n = dot3(dir, dir);
        if (n <= 1.0 && n >= 1e-4)
            break;
    }
    if (n < 1e-4) {
        dir[0] = 1.0;
        dir[1] = dir[2] = 0.0;
        n = 1.0;
    }
    n = sqrt(n);
    dir[0] /= n;
    dir[1] /= n;
    dir[2] /= n;
}

/* f at angle-axis w if it is below level (then 1, *f and t set), else 0
 * (f >= level up to the tolerance): one exact test decides, a bisection
 * above the certified lower bound, to tol, follows only when it passes. */
static int f_below(bnb_ctx *c, const mcg_bnb_options *o, const double w[3], double level,
                   double tol, double *f, double t[3], long *tests)
{
    double Rn[9], hi = level - 2.0 * o->tol;
    int st, r;
    if (hi <= 0.0)
        return 0;
    st = mcg_rot_from_angle_axis(w, Rn);
    if (st != MCG_OK)
        return -st;
    ++*tests;
    r = feasible(c, Rn, hi, 0.0, t);
    if (r < 0)
        return r;
    if (r != 1)
        return 0;
    st = find_min_error(c, Rn, 0.0, c->floor, &hi, t, tol, 0);
    if (st != MCG_OK)
        return -st;
    *f = hi;
    return 1;
}

/* f just below the incumbent at angle-axis w? If so, the incumbent moves
 * there: 1; not: 0; < 0 status. */
static int try_move(bnb_ctx *c, const mcg_bnb_options *o, mcg_bnb_result *res,
                    const double w[3], long *tests)
{
    double f = 0.0, tt[3];
    int r = f_below(c, o, w, res->linf, o->tol, &f, tt, tests);
    if (r != 1)
        return r;
    r = mcg_rot_from_angle_axis(w, res->R);
    if (r != MCG_OK)
        return -r;
    res->linf = f;
    memcpy(res->t, tt, sizeof tt);
    return 1;
}

/* The polish: each start's local minimum verified by the exact test (the
 * incumbent moves only where f is lower; never increases f). Its workspace
 * is the 3- and 2-variable rows' space (9 of their 6 ROWS_PER n doubles). */
static int polish_slp(bnb_ctx *c, const mcg_bnb_options *o, mcg_bnb_result *res,
                      long *tests, double deadline)
{
    unsigned long long state = 0x2545f4914f6cdd1dULL;
    double w0[3];
    int st, k, start;
    st = mcg_angle_axis_from_rot(res->R, w0);
    if (st != MCG_OK)
        return st;
    for (start = 0; start < POLISH_STARTS; ++start) {
        double R[9], t[3], w[3], fs, dir[3];
        int steps;
        if (start > 0 && now_seconds() > deadline) {
            res->stop = MCG_BNB_TIME_LIMIT;
            break; /* the incumbent so far stands: never worse */
        }
        memcpy(w, w0, sizeof w);
        if (start > 0) {
            static const double scales[4] = {100.0, 3.0, 10.0, 30.0};
            double scale = o->resolution * scales[start % 4];
            random_direction(&state, dir);
            for (k = 0; k < 3; ++k)
                w[k] += scale * dir[k];
        }
        st = mcg_rot_from_angle_axis(w, R);
        if (st != MCG_OK)
            return st;
        memcpy(t, res->t, sizeof t);
        st = mcg_linf_local(c->n, c->u1, c->a1, c->u2, c->a2, R, t, 10.0 * o->resolution,
                            o->polish_tol, POLISH_MAX_STEPS, c->A3, &fs, &steps);
        if (st != MCG_OK)
            return st;
        *tests += steps;
        if (!(asin(fs < 1.0 ? fs : 1.0) < res->linf - o->tol))
            continue;
        st = mcg_angle_axis_from_rot(R, w);
        if (st != MCG_OK)
            return st;
        st = try_move(c, o, res, w, tests);
        if (st < 0)
            return -st;
        if (start == 0)
            memcpy(w0, w, sizeof w);
    }
    return MCG_OK;
}

/* ---------------------------------------------------------------- heap */

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

/* ------------------------------------------------------------ interface */

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
        r = feasible(c, Rb, eps, 0.0, t);
        if (r < 0)
            return -r;
        if (r == 1)
            break;
        lo = eps;
        eps *= 2.0;
        if (eps >= EPS_MAX)
            return MCG_ENUMERIC; /* every bound up to ~86 deg infeasible */
    }
    st = find_min_error(c, Rb, 0.0, lo, &eps, t, tol, 0);
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
        r = feasible(c, R0, level, s, tt);
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
    st = find_min_error(c, R0, s, lb, &hi, tt, o->tol, 1);
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
        r = feasible(c, R0, mid, s, tt);
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
    r = feasible(c, R0, target, s, tt);
    if (r < 0)
        return -r;
    if (!r) {
        if (target < q->prune_lb)
            q->prune_lb = target;
        return MCG_OK;
    }
    r = feasible(c, R0, res->linf, 0.0, tt);
    if (r < 0)
        return -r;
    if (r == 1) {
        hi = res->linf;
        st = find_min_error(c, R0, 0.0, blk[4], &hi, tt, o->tol, 0);
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
            now_seconds() > deadline) {
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

    t0 = now_seconds();
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
        st = polish_slp(&c, &o, res, &tests, deadline);
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
    res->seconds = now_seconds() - t0;
    return MCG_OK;
}
