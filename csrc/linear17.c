/*
 * linear17.c -- linear 17-point relative motion of a generalized camera
 * (thesis ch. 8): generalized epipolar rows (eqs. 8.15-8.18), detection of the
 * four kinds of generalized camera (ch. 8.3), the constrained least squares of
 * Algorithm 4 / eq. 8.36 for the locally-central and axial kinds and the plain
 * SVD for the most-general kind (Algorithm 2), decomposition of E into its
 * rotation candidates, the translation WITH scale from eq. 8.15, and the
 * refinement of ch. 8.4.3.
 *
 * Why the linear step works on the 18 x 18 Gram matrix M = A^T A:
 * |A x|^2 = x^T M x for every x = (vec E, vec R), so after one O(N) pass over
 * the rays the linear step and the candidate choice cost O(18^2) regardless
 * of N. Squaring the condition number is harmless here: rows are normalised
 * (Algorithm 2 step 1) and the refinement re-fits R, t on the rays.
 *
 * Which optimum the refinement seeks: the alternation of ch. 8.4.3
 * (R given t, then t given R) minimises the algebraic cost x^T M x. For a
 * rig whose correspondences stay in one camera, (0, I) is in the null space
 * of A, so that cost vanishes at R = I, t = 0, and its minimiser is biased
 * towards a short t: on the cases of issue 22 (mcgeom experiment
 * linear17_accuracy) it doubled the median scale error of the linear step,
 * which is itself worse than OpenGV's seventeenpt there. The refinement
 * therefore minimises the Sampson angular error of each correspondence
 * (the residual of refine.c), a first-order geometric error with no such
 * trivial minimum (Levenberg-Marquardt, a few O(N) passes). When only the
 * direction of t is determined (unit mode) the alternation is kept: with
 * |t| = 1 fixed the algebraic cost has no trivial zero.
 *
 * Frames: inputs and outputs in the rig frame; internally the normalised frame
 * X' = s (X - o) (o = centroid of the ray origins, s = 1 / RMS distance), which
 * keeps the rig axis through the origin for axial rigs, as eqs. 8.24-8.33
 * assume. A motion (R, t') there is (R, t'/s + o - R o) in the rig frame.
 *
 * The parts (linear17_internal.h: what they share):
 *   linear17.c              options, checks, the candidate choice, the scale
 *                           evidence and the result (this file);
 *   linear17_gram.c         M, the camera kind (ch. 8.3), the linear step
 *                           (Algorithm 2 / 4) and E's rotation candidates;
 *   linear17_alternation.c  t given R (eq. 8.15), R given t (ch. 8.4.3);
 *   linear17_sampson.c      the geometric (Sampson) refinement.
 */
#include "linear17_internal.h"

#include <float.h>
#include <math.h>
#include <string.h>

#define MAX_RAYS (1 << 26)

/* The motion being estimated, in the normalised frame: R, t, the algebraic
 * cost x^T M x at them, and unit_mode: 1 when |t| is not determined (only
 * its direction is solved for, ch. 7.3.2). */
typedef struct {
    double r[9], t[3], cost;
    int unit_mode;
    double geo_cost;  /* Sampson cost (rad^2) after the geometric refinement */
    double h[36];     /* its Gauss-Newton information J^T J (upper triangle) */
    int have_h;       /* 1 once h and geo_cost are set */
} motion;

/* Number of correspondences whose rays, moved by (R, t) into the time-2 rig
 * frame, meet in front of both origins (mid-point triangulation). */
static int count_in_front(int n, const double *o1, const double *d1,
                          const double *o2, const double *d2,
                          const double r[9], const double t[3])
{
    int k, i, cnt = 0;
    for (k = 0; k < n; k++) {
        double p[3], a[3], w[3], aa, ab, bb, aw, bw, den, s1, s2;
        const double *b = d2 + 3 * k;
        for (i = 0; i < 3; i++) {
            p[i] = r[3 * i] * o1[3 * k] + r[3 * i + 1] * o1[3 * k + 1] +
                   r[3 * i + 2] * o1[3 * k + 2] + t[i];
            a[i] = r[3 * i] * d1[3 * k] + r[3 * i + 1] * d1[3 * k + 1] +
                   r[3 * i + 2] * d1[3 * k + 2];
            w[i] = o2[3 * k + i] - p[i];
        }
        aa = dot3(a, a); ab = dot3(a, b); bb = dot3(b, b);
        aw = dot3(a, w); bw = dot3(b, w);
        den = aa * bb - ab * ab;
        if (!(den > 1e-14 * aa * bb))
            continue; /* parallel rays: no depth information */
        s1 = (aw * bb - bw * ab) / den;
        s2 = (aw * ab - bw * aa) / den;
        if (s1 > 0.0 && s2 > 0.0)
            cnt++;
    }
    return cnt;
}

void mcg_linear17_default_options(mcg_linear17_options *opt)
{
    if (!opt)
        return;
    opt->refine = 1;
    opt->max_iterations = 100;
    opt->tolerance = 1e-10;
    opt->rank_rtol = 1e-10;
    opt->min_scale_conditioning = 1e-10;
    opt->max_scale_rel_std = 0.1;
}

static int check_options(const mcg_linear17_options *o)
{
    if (o->refine != 0 && o->refine != 1)
        return 0;
    if (o->max_iterations < 0 || o->max_iterations > 10000)
        return 0;
    if (!isfinite(o->tolerance) || o->tolerance < 0.0)
        return 0;
    if (!isfinite(o->rank_rtol) || o->rank_rtol <= 0.0 || o->rank_rtol >= 1.0)
        return 0;
    if (!isfinite(o->min_scale_conditioning) || o->min_scale_conditioning < 0.0)
        return 0;
    if (isnan(o->max_scale_rel_std) || o->max_scale_rel_std <= 0.0)
        return 0;
    return 1;
}

/* A translation in the normalised frame (t' = s (t - o + R o)) back to the
 * rig frame: t = t' / s + o - R o (Algorithm 2 step 1 undone). */
static void to_rig_frame(const mcg_linear17_result *res, const double r[9],
                         const double tn[3], double t[3])
{
    double ro[3];
    int i;
    matvec(3, r, res->norm_origin, ro);
    for (i = 0; i < 3; i++)
        t[i] = tn[i] / res->norm_scale + res->norm_origin[i] - ro[i];
}

/* The translation with scale of each rotation candidate (eq. 8.15), the
 * candidate of least algebraic cost kept. For a critical motion (ch. 7.3.2)
 * or a central camera |t| is not determined: then (unit mode) the rotation
 * is chosen among the equally good candidates, and the sign of the unit
 * direction, by cheirality. */
static int choose_candidate(const double *m, const raydata *rays,
                            const mcg_linear17_options *o, int gc, double tiny,
                            double cand[4][9], int ncand, mcg_linear17_result *res,
                            motion *mo)
{
    double bestcost = HUGE_VAL;
    int k, i, best = -1;
    tsolve ts;
    res->n_candidates = ncand;
    mo->unit_mode = 0;
    for (k = 0; k < ncand; k++) {
        if (linear17_solve_t(m, cand[k], 0, NULL, 0, &ts) != MCG_OK)
            return MCG_ENUMERIC;
        res->candidate_cost[k] = ts.cost;
        if (ts.cost < bestcost) {
            bestcost = ts.cost;
            best = k;
        }
    }
    memcpy(mo->r, cand[best], sizeof mo->r);
    if (linear17_solve_t(m, mo->r, 0, NULL, 1, &ts) != MCG_OK)
        return MCG_ENUMERIC;
    memcpy(mo->t, ts.t, sizeof mo->t);
    mo->cost = ts.cost;
    if (gc == MCG_GC_CENTRAL || ts.cond < o->min_scale_conditioning) {
        /* critical motion (ch. 7.3.2) or a central camera: |t| is not
         * determined. (A central camera has g = 0 and c0 = 0, so the
         * free solve returns t = 0 for every candidate and cannot tell
         * them apart; with noise its H is well conditioned, so cond
         * alone does not flag it.) Choose the rotation among equally
         * good candidates and the sign of the direction by cheirality,
         * in the normalised frame. */
        int bestcnt = -1;
        mo->unit_mode = 1;
        for (k = 0; k < ncand; k++) {
            int sg;
            if (res->candidate_cost[k] > 10.0 * bestcost + tiny)
                continue;
            if (linear17_solve_t(m, cand[k], 1, NULL, 1, &ts) != MCG_OK)
                return MCG_ENUMERIC;
            for (sg = -1; sg <= 1; sg += 2) {
                double tt[3], tr[3];
                int cnt;
                for (i = 0; i < 3; i++)
                    tt[i] = sg * ts.t[i];
                /* undo normalisation of the translation direction */
                to_rig_frame(res, cand[k], tt, tr);
                cnt = count_in_front(rays->n, rays->o1, rays->d1, rays->o2, rays->d2,
                                     cand[k], tr);
                if (cnt > bestcnt) {
                    bestcnt = cnt;
                    memcpy(mo->r, cand[k], sizeof mo->r);
                    for (i = 0; i < 3; i++)
                        mo->t[i] = sg * ts.t[i];
                    mo->cost = ts.cost;
                }
            }
        }
    }
    return MCG_OK;
}

/* The refinement of ch. 8.4.3 from the linear estimate. Metric mode: the
 * geometric refinement (Levenberg-Marquardt on the Sampson error, see
 * geometric_refine); mo->cost becomes the algebraic cost x^T M x at the
 * refined motion (the residual scale of the scale evidence) and mo->h the
 * information of the Sampson error there. Unit mode (|t| not determined: a
 * central camera or a critical motion, ch. 7.3.2): the alternation (R given
 * t, then the unit t given R) on the algebraic cost, which has no trivial
 * zero once |t| = 1 is fixed. */
static int refine_motion(const double *m, const raydata *rd,
                         const mcg_linear17_options *o, double tiny,
                         mcg_linear17_result *res, motion *mo, double *cost0)
{
    int k;
    tsolve ts;
    if (!mo->unit_mode) {
        double x[NX];
        res->iterations = linear17_geometric_refine(rd, o, mo->r, mo->t, &mo->geo_cost, mo->h,
                                                    &res->converged, cost0);
        mo->have_h = 1;
        motion_vector(mo->r, mo->t, x);
        mo->cost = quad18(m, x);
        return MCG_OK;
    }
    for (k = 0; k < o->max_iterations; k++) {
        double prev = mo->cost;
        if (mo->cost <= tiny) {
            res->converged = 1;
            break;
        }
        if (linear17_step_r(m, mo->r, mo->t, &mo->cost) != MCG_OK)
            return MCG_ENUMERIC;
        if (linear17_solve_t(m, mo->r, 1, mo->t, 0, &ts) != MCG_OK)
            return MCG_ENUMERIC;
        if (ts.cost <= mo->cost) {
            memcpy(mo->t, ts.t, sizeof mo->t);
            mo->cost = ts.cost;
        }
        res->iterations = k + 1;
        if (prev - mo->cost <= o->tolerance * prev) {
            res->converged = 1;
            break;
        }
    }
    return MCG_OK;
}

/* Scale observability: the conditioning of the scale equation (eq. 8.15)
 * and the relative std of |t|, the larger of the first-order std from the
 * residual and the errors-in-variables bias bound (normalised frame). */
static int scale_evidence(const double *m, const mcg_linear17_options *o, int n,
                          const motion *mo, mcg_linear17_result *res)
{
    double nt = sqrt(dot3(mo->t, mo->t)), var = 0.0, sigma2;
    int dof = n > 6 ? n - 6 : 1, i, k;
    tsolve ts;
    if (linear17_solve_t(m, mo->r, mo->unit_mode, mo->t, 1, &ts) != MCG_OK)
        return MCG_ENUMERIC;
    /* (t stays as refined: ts only supplies H for the evidence) */
    res->scale_conditioning = ts.cond;
    sigma2 = mo->cost / dof;
    if (mo->unit_mode || !(nt > 0.0)) {
        res->scale_rel_std = HUGE_VAL;
    } else {
        double u[3], hu[3], uhu, gu, rho2;
        for (k = 0; k < 3; k++) {
            double vk[3] = {ts.hv[k], ts.hv[3 + k], ts.hv[6 + k]};
            double c = dot3(vk, mo->t) / nt;
            if (ts.h[k] > 0.0)
                var += c * c / ts.h[k];
            else if (c != 0.0)
                var = HUGE_VAL;
        }
        res->scale_rel_std = sqrt(sigma2 * var) / nt;
        /* Errors-in-variables check: along u = t/|t|, eq. 8.15 reads
         * (J u) s = b. Regressing b on J u (least squares, what we do)
         * and J u on b bracket the true s when both are noisy; their
         * ratio is rho^2 = (g.u)^2 / ((u^T H u) c0). 1 - rho^2 bounds the
         * relative bias of |t| that the first-order std cannot see. */
        for (i = 0; i < 3; i++)
            u[i] = mo->t[i] / nt;
        matvec(3, ts.hm, u, hu);
        uhu = dot3(u, hu);
        gu = dot3(ts.g, u);
        rho2 = (uhu > 0.0 && ts.c0 > 0.0) ? gu * gu / (uhu * ts.c0) : 1.0;
        if (rho2 > 1.0)
            rho2 = 1.0;
        if (1.0 - rho2 > res->scale_rel_std)
            res->scale_rel_std = 1.0 - rho2;
        /* and the first-order std of the geometric (Sampson) fit, whose
         * optimum the refinement returns */
        if (mo->have_h) {
            double gs = linear17_geometric_rel_std(mo->h, mo->geo_cost, n, mo->t);
            if (!(gs <= res->scale_rel_std))
                res->scale_rel_std = gs;
        }
    }
    res->scale_observable = !mo->unit_mode &&
                            res->scale_conditioning >= o->min_scale_conditioning &&
                            res->scale_rel_std <= o->max_scale_rel_std;
    return MCG_OK;
}

/* An unobservable scale from the free solve (near-critical motion, e.g. a
 * pure translation seen by intra-camera rays: e = t . (R d1 x d2) is
 * nearly homogeneous in t) leaves the sign of t to the noise. Only the
 * direction is reported then: choose its sign by cheirality, as unit
 * mode does, at a length (100 in the normalised frame, where the origins
 * spread over ~1) that dwarfs the rotation-induced part o - R o. */
static void orient_by_cheirality(const raydata *rays, const mcg_linear17_result *res,
                                 motion *mo)
{
    double nt = sqrt(dot3(mo->t, mo->t)), ro[3], tp[3], tm[3];
    int i;
    if (!(nt > 0.0))
        return;
    matvec(3, mo->r, res->norm_origin, ro);
    for (i = 0; i < 3; i++) {
        double step = 100.0 * mo->t[i] / nt / res->norm_scale;
        tp[i] = step + res->norm_origin[i] - ro[i];
        tm[i] = -step + res->norm_origin[i] - ro[i];
    }
    if (count_in_front(rays->n, rays->o1, rays->d1, rays->o2, rays->d2, mo->r, tm) >
        count_in_front(rays->n, rays->o1, rays->d1, rays->o2, rays->d2, mo->r, tp))
        for (i = 0; i < 3; i++)
            mo->t[i] = -mo->t[i];
}

/* The motion into res in the rig frame: t_metric always (metric mode), t
 * with unit norm when only its direction is meaningful. */
static void report_motion(const raydata *rays, const motion *mo, mcg_linear17_result *res)
{
    int i;
    memcpy(res->R, mo->r, sizeof mo->r);
    to_rig_frame(res, mo->r, mo->t, res->t);
    if (!mo->unit_mode)
        memcpy(res->t_metric, res->t, sizeof res->t_metric);
    if (!res->scale_observable) {
        /* only the direction is meaningful: report it with unit norm */
        double nt;
        if (mo->unit_mode)
            memcpy(res->t, mo->t, sizeof mo->t);
        nt = sqrt(dot3(res->t, res->t));
        if (nt > 0.0)
            for (i = 0; i < 3; i++)
                res->t[i] /= nt;
    }
    res->n_in_front = count_in_front(rays->n, rays->o1, rays->d1, rays->o2, rays->d2,
                                     res->R, res->t);
}

/* Everything after the case detection, for the kind gc (nullity of A_R):
 * the linear step (Algorithm 2), the rotation candidates, the translation
 * with scale (eq. 8.15), the refinement (ch. 8.4.3), and the
 * scale evidence; res (whose eigenvalue diagnostics are already filled)
 * gets the motion in the rig frame.
 * pinv_rtol: eigenvalues of M_RR at or below pinv_rtol * max are treated as
 * structural zeros in the elimination of the R part (0: none is). */
static int solve_case(int n, const double *origins1, const double *dirs1,
                      const double *origins2, const double *dirs2,
                      const mcg_linear17_options *opt, const double *m,
                      const double *wr, const double *vr, double tr_m, int gc,
                      int nullity, double pinv_rtol, mcg_linear17_result *res)
{
    double e[9], rpart[9], cand[4][9], tiny = 1e-26 * tr_m, ne = 0.0;
    int st, i, ncand = 0;
    raydata rays;
    motion mo;

    rays.n = n;
    rays.o1 = origins1; rays.d1 = dirs1; rays.o2 = origins2; rays.d2 = dirs2;
    rays.origin = res->norm_origin;
    rays.scale = res->norm_scale;
    mo.have_h = 0;
    res->gc_case = gc;
    res->rank_ar = 9 - nullity;
    res->rank_a = 17 - (gc == MCG_GC_CENTRAL ? 9 : nullity);
    if (gc == MCG_GC_DEGENERATE)
        return MCG_EDEGENERATE;
    if (n < res->rank_a)
        return MCG_EDEGENERATE; /* too few rays for the detected kind */

    st = linear17_linear_step(m, gc, wr, vr, pinv_rtol, opt->rank_rtol, tr_m, e, rpart, res);
    if (st != MCG_OK)
        return st;
    for (i = 0; i < 9; i++)
        ne += e[i] * e[i];
    ne = sqrt(ne);
    for (i = 0; i < 9; i++)
        res->E[i] = e[i] / ne;
    st = linear17_rotation_candidates(res->E, rpart, gc == MCG_GC_MOST_GENERAL, cand, &ncand);
    if (st != MCG_OK)
        return st;
    st = choose_candidate(m, &rays, opt, gc, tiny, cand, ncand, res, &mo);
    if (st != MCG_OK)
        return st;
    /* the cost is the quadratic form x^T M x of the Gram matrix: on exact
     * data it rounds to a tiny negative number (found by fuzz_linear17) */
    if (mo.cost < 0.0)
        mo.cost = 0.0;
    /* reported costs: RMS Sampson angular error (radians), the same
     * measure before and after the refinement and in every frame */
    res->converged = 0;
    if (opt->refine && !mo.unit_mode) {
        /* the geometric refinement's first pass is at the linear estimate:
         * its cost is cost_linear (one pass over the rays fewer) */
        double cost0;
        st = refine_motion(m, &rays, opt, tiny, res, &mo, &cost0);
        if (st != MCG_OK)
            return st;
        res->cost_linear = sqrt(cost0 / n);
        res->cost_final = sqrt(mo.geo_cost / n);
    } else {
        res->cost_linear = sqrt(linear17_sampson_pass(&rays, mo.r, mo.t, NULL, NULL) / n);
        res->cost_final = res->cost_linear;
        if (opt->refine) {
            double unused;
            st = refine_motion(m, &rays, opt, tiny, res, &mo, &unused);
            if (st != MCG_OK)
                return st;
            res->cost_final = sqrt(linear17_sampson_pass(&rays, mo.r, mo.t, NULL, NULL) / n);
        }
    }
    /* rays of extreme magnitudes (~1e200: found by fuzz_linear17) can
     * overflow the Sampson terms of the refinement: a NaN or inf cost is
     * no estimate, and a NaN would also lose every comparison with the
     * other kind's solution in mcg_linear17 */
    if (!isfinite(res->cost_final) || !isfinite(res->cost_linear))
        return MCG_ENUMERIC;
    if (mo.cost < 0.0)
        mo.cost = 0.0; /* rounding of x^T M x, as above */
    st = scale_evidence(m, opt, n, &mo, res);
    if (st != MCG_OK)
        return st;
    if (!mo.unit_mode && !res->scale_observable)
        orient_by_cheirality(&rays, res, &mo);
    report_motion(&rays, &mo, res);
    return MCG_OK;
}

/* 1 if every ray pair has the same origin at both times (to 1e-12 of the
 * normalised rig size): the rows of such pairs annihilate (0, I) exactly,
 * the locally-central case of ch. 8.3. A cross-camera pair (distinct
 * origins) annihilates it only by accident, e.g. when the rig hardly moves:
 * then the eigenvalue can be as small as rounding (|t| ~ 3e-5 of the rig). */
static int same_origins(int n, const double *o1, const double *o2, double scale)
{
    int i, k;
    for (i = 0; i < n; i++)
        for (k = 0; k < 3; k++)
            if (!(fabs(o1[3 * i + k] - o2[3 * i + k]) * scale <= 1e-12))
                return 0;
    return 1;
}

/* The minimal sample of the most-general kind: with n >= 17 pairs, fewer
 * distinct ones than this is reported as degenerate (the registry's
 * check_distinct, done here in O(n)). */
#define MIN_DISTINCT 17

static int same_pair(const double *o1, const double *d1, const double *o2,
                     const double *d2, int i, int j)
{
    int k;
    for (k = 0; k < 3; k++)
        if (o1[3 * i + k] != o1[3 * j + k] || d1[3 * i + k] != d1[3 * j + k] ||
            o2[3 * i + k] != o2[3 * j + k] || d2[3 * i + k] != d2[3 * j + k])
            return 0;
    return 1;
}

/* Number of distinct pairs (exact repeats counted once), counted up to
 * `enough`: each pair is compared with the distinct ones kept so far (at
 * most enough - 1), so the cost is O(n enough) at worst and a handful of
 * comparisons per pair when the data have no repeats. */
static int count_distinct(int n, const double *o1, const double *d1, const double *o2,
                          const double *d2, int enough)
{
    int kept[MIN_DISTINCT], nk = 0, i, j;
    if (enough > MIN_DISTINCT)
        enough = MIN_DISTINCT;
    for (i = 0; i < n && nk < enough; i++) {
        for (j = 0; j < nk; j++)
            if (same_pair(o1, d1, o2, d2, i, kept[j]))
                break;
        if (j == nk)
            kept[nk++] = i;
    }
    return nk;
}

/* Below this ratio to the largest eigenvalue of A_R^T A_R an eigenvalue is a
 * structural zero: the rows of a locally-central or axial camera annihilate
 * (0, I) etc. exactly, so their eigenvalue is rounding (~1e-16 and below).
 * Between it and rank_rtol the small eigenvalue may instead be accidental:
 * a cross-camera rig that hardly moves (R ~ I, |t| ~ 1e-5 of the rig) makes
 * (0, I) nearly annihilated by every row, as exact data with R = I, t = 0
 * do, and treating it as structural then removes the true solution
 * (found by fuzz_linear17: rotation 2 deg off on exact data, scale
 * "observable"). */
#define STRUCTURAL_RTOL 1e-14

/* Eigenvalues of A_R^T A_R below this ratio to the largest may be a nearly
 * structural null space (see the end of mcg_linear17) */
#define NEAR_RTOL 1e-8

int mcg_linear17(int n, const double *origins1, const double *dirs1,
                 const double *origins2, const double *dirs2,
                 const mcg_linear17_options *opt, mcg_linear17_result *res)
{
    mcg_linear17_options o;
    double m[NX * NX], mrr[81], wr[9], vr[81], tr_m = 0.0;
    int st, i, k, nullity = 0, gc;

    if (!res)
        return MCG_EINVAL;
    memset(res, 0, sizeof *res);
    res->gc_case = MCG_GC_DEGENERATE;
    if (!origins1 || !dirs1 || !origins2 || !dirs2)
        return MCG_EINVAL;
    if (n < 14 || n > MAX_RAYS)
        return MCG_EINVAL;
    if (opt) {
        if (!check_options(opt))
            return MCG_EINVAL;
        o = *opt;
    } else {
        mcg_linear17_default_options(&o);
    }

    st = linear17_accumulate(n, origins1, dirs1, origins2, dirs2, m, res->norm_origin,
                             &res->norm_scale);
    if (st != MCG_OK)
        return st;
    res->n_distinct = count_distinct(n, origins1, dirs1, origins2, dirs2, MIN_DISTINCT);
    if (n >= MIN_DISTINCT && res->n_distinct < MIN_DISTINCT)
        return MCG_EDEGENERATE;
    for (i = 0; i < NX; i++)
        tr_m += m[i * NX + i];
    if (!(tr_m > 0.0) || !isfinite(tr_m))
        return MCG_EINVAL;

    /* generalized camera kind from the structural null space of A_R */
    block(m, 9, 9, mrr);
    if (mcg_sym_eig_tridiag(9, mrr, wr, vr) != MCG_OK)
        return MCG_ENUMERIC;
    for (k = 0; k < 9; k++)
        res->ar_eig[k] = wr[8] > 0.0 ? (wr[k] > 0.0 ? wr[k] / wr[8] : 0.0) : 0.0;
    gc = linear17_classify(wr, vr, o.rank_rtol, tr_m, &nullity);
    st = solve_case(n, origins1, dirs1, origins2, dirs2, &o, m, wr, vr, tr_m, gc,
                    nullity, o.rank_rtol, res);
    if (gc != MCG_GC_MOST_GENERAL && gc != MCG_GC_CENTRAL &&
        (wr[0] > STRUCTURAL_RTOL * wr[8] ||
         ((gc == MCG_GC_LOCALLY_CENTRAL || gc == MCG_GC_LOCALLY_CENTRAL_AXIAL) &&
          !same_origins(n, origins1, origins2, res->norm_scale)))) {
        /* the small eigenvalues may be accidental: solve also as the most
         * general kind, with nothing eliminated as structural, and keep the
         * motion of lower algebraic cost (both costs are x^T M x of a valid
         * motion in the same normalised frame) */
        mcg_linear17_result alt;
        int st_alt = MCG_EDEGENERATE, unique;
        double wm[NX], vm[NX * NX], mc[NX * NX];
        memcpy(&alt, res, sizeof alt);
        memcpy(mc, m, sizeof mc); /* the decomposition overwrites its input */
        /* ... only where that kind's solution is unique: a second null
         * vector of the whole M at rounding level means too few independent
         * rays (duplicates add no rank), and the plain SVD would return an
         * arbitrary mix of the two */
        unique = mcg_sym_eig_tridiag(NX, mc, wm, vm) == MCG_OK &&
                 wm[1] > STRUCTURAL_RTOL * tr_m;
        if (unique)
            st_alt = solve_case(n, origins1, dirs1, origins2, dirs2, &o, m, wr, vr,
                            tr_m, MCG_GC_MOST_GENERAL, 0, 0.0, &alt);
        if (st_alt == MCG_OK && (st != MCG_OK || alt.cost_final < res->cost_final)) {
            memcpy(res, &alt, sizeof alt);
            st = MCG_OK;
        } else if (st_alt == MCG_EDEGENERATE && st == MCG_OK) {
            /* neither reading is sound: the small eigenvalue of A_R is not
             * (or need not be) structural, and without eliminating it E is
             * not unique: too few independent rays for the most general
             * kind (seen on exact data: residuals 4e-5 rad, "observable") */
            st = MCG_EDEGENERATE;
        }
    }
    /* The next eigenvalues of A_R may be nearly structural as well: a rig
     * nearly of a more special kind (two camera centres 1e-4 apart make a
     * locally-central rig nearly locally-central and axial). Inverting them
     * in M_RR^+ amplifies rounding beyond the gap of the reduced system,
     * and its E is then an arbitrary mix (fuzz_linear17, finding 19: 18
     * distinct rays of three cameras, eigenvalues 1.8e-10 and 9.6e-10 of
     * the largest; on exact data the motion came out 1.6 deg off, a local
     * minimum of the Sampson error, with its scale "observable"). So where
     * the kind read at NEAR_RTOL differs, solve also as that kind, with
     * those eigenvalues eliminated, and keep the motion of lower Sampson
     * cost (on that input: 6.7e-4 -> 4e-17 rad). Only as a second opinion
     * on a motion found: where the kind read at rank_rtol gives none, the
     * near kind's elimination is an approximation whose motion the data
     * need not support (a later input: four nearly coincident centres,
     * EDEGENERATE at rank_rtol, and the near kind's motion 0.07 deg off,
     * residuals 3e-4 rad, "observable") -- the failure stands. */
    if (st == MCG_OK) {
        int near_nullity, near_gc = linear17_classify(wr, vr, NEAR_RTOL, tr_m, &near_nullity);
        if (near_gc != gc && near_gc != MCG_GC_DEGENERATE && near_gc != MCG_GC_CENTRAL &&
            near_gc != MCG_GC_MOST_GENERAL && near_nullity > nullity) {
            mcg_linear17_result near;
            int st_near;
            memcpy(&near, res, sizeof near);
            st_near = solve_case(n, origins1, dirs1, origins2, dirs2, &o, m, wr, vr, tr_m,
                                 near_gc, near_nullity, NEAR_RTOL, &near);
            if (st_near == MCG_OK && near.cost_final < res->cost_final)
                memcpy(res, &near, sizeof near);
        }
    }
    return st;
}
