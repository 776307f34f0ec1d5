/*
 * bnb_feasible.c -- the feasibility test of the branch and bound over
 * rotations (thesis ch. 10.3, csrc/bnb.c): the rows of each correspondence's
 * wedge (eqs. 10.9-10.13, wedge.c) and cap at a rotation and bound, the
 * single-camera cone test (an LP in 2 variables per group) and the common
 * translation (the LP in 3 variables), decided on growing working sets of
 * rows; and the smallest bound at which a rotation is feasible (bisection,
 * FindMinError).
 */
#include "bnb_internal.h"

#include <math.h>
#include <string.h>

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

/* bnb_feasible(R, eps) relaxed by slack s (see the file comment): 1 with t set
 * (when feasible), 0 infeasible, negative status on error. */
int bnb_feasible(bnb_ctx *c, const double R[9], double eps, double s, double t[3])
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
int bnb_find_min_error(bnb_ctx *c, const double R[9], double s, double lo,
                       double *hi, double t_hi[3], double tol, int lower)
{
    double t[3];
    int it;
    for (it = 0; it < BISECT_MAX && *hi - lo > tol; ++it) {
        double mid = 0.5 * (lo + *hi);
        int r = bnb_feasible(c, R, mid, s, t);
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
