/*
 * robust_verdict.c -- the scale verdict of the robust estimate
 * (csrc/robust.c, res->scale): is the metric scale of the result supported
 * by the data (thesis ch. 7.3.2), and which t to report. The decisions of
 * mcgeom.robust._verdict.conclude and mcgeom.observability (_verdict,
 * scale_determined, total_scale_std, the no-parallax test) on the evidence
 * the call gathered: the final refinement's relative std of |t| and its
 * covariance, the calibration error's part (mcg_calibration_scale_std on
 * the refinement's pairs), the scale profiles, and mcg_verdict_stats's
 * counts. A C user gets the whole robust job in one call; mcgeom's Python
 * layer only words the reason (issue 19: the verdict in Python was ~1/3 of
 * a cold call's time outside C). The texts and the constants below are
 * those of mcgeom.observability and mcgeom.robust._verdict
 * (tests/test_robust_verdict_c.py checks that the copies agree and that
 * both give the same verdicts).
 */
#include "robust_internal.h"

#include <math.h>
#include <string.h>

#define MOTION_DOF 6             /* observability._MOTION_DOF */
#define NO_PARALLAX_FRACTION 0.9 /* observability.NO_PARALLAX_FRACTION */
#define NO_PARALLAX_MIN 5        /* observability.NO_PARALLAX_MIN */
#define PROFILE_SIGMAS2 9.0      /* a profile excludes a scale at 3 sigma */
#define CRITICAL_DEG 0.05        /* observability._verdict's parallel lines */
#define CONFIRMED 0.5            /* robust._verdict.CONFIRMED */
#define MIRRORED_COS 0.9         /* estimators._common.in_mirrored_minimum */
#define SLID_FACTOR 10.0         /* robust._verdict.conclude: |t| grew 10x */
#define PI 3.14159265358979323846

const char *mcg_scale_reason_string(int reason)
{
    switch (reason) {
    case MCG_SCALE_OBSERVABLE:
        return "scale observable";
    case MCG_SCALE_NO_REDUNDANCY:
        return "no redundancy: no uncertainty can be estimated";
    case MCG_SCALE_ONE_CAMERA:
        return "one camera only and no cross-camera correspondence";
    case MCG_SCALE_CRITICAL:
        return "critical motion: camera displacements parallel";
    case MCG_SCALE_UNCERTAIN:
        return "scale too uncertain for the noise (near-critical motion)";
    case MCG_SCALE_CHEIRALITY:
        return "cheirality fails: most inliers behind the cameras";
    case MCG_SCALE_UNCONFIRMED:
        return "consensus not confirmed: a cap ended the search";
    case MCG_SCALE_STATIC:
        return "no translation detected";
    case MCG_SCALE_UNDECIDED:
        return "undecided: the verdict's evidence is incomplete";
    case MCG_SCALE_CONSENSUS:
        return "not confirmed by the checks of the consensus";
    default:
        return "unknown";
    }
}

/* observability.scale_determined: do the data define a metric scale at all
 * (a relative std of |t| within 1, and a vanishing translation excluded by
 * the zero profile at 3 sigma when it was computed)? */
static int scale_determined(double rel_std, double zero_profile)
{
    if (isfinite(zero_profile) && zero_profile < PROFILE_SIGMAS2)
        return 0;
    return isfinite(rel_std) && rel_std <= UNDETERMINED_REL_STD;
}

/* The calibration error's part of the relative std of |t|
 * (observability.calibration_scale_std on the refinement's pairs, as
 * robust._verdict.conclude hands them over: gathered in input order, the
 * weights of the final refinement or none when they are all equal, the
 * cameras up to the largest id among them); its covariance added to cov.
 * Returns MCG_OK, or the failing call's status. Scratch: the gather buffers
 * (sub, wsub) and rcur (as 2 n ints). */
static int calibration_part(ctx *c, const mcg_robust_result *res, const unsigned char *mask,
                            const double *weights, double *rel, double cov[36])
{
    const size_t n = (size_t)c->n;
    double *so1 = c->sub, *sd1 = c->sub + 3 * n, *so2 = c->sub + 6 * n, *sd2 = c->sub + 9 * n;
    int *id1 = (int *)c->rcur, *id2 = id1 + n, m = 0, top = -1, any = 0, equal = 1, i, st;
    double cal_cov[36];
    size_t k;
    *rel = 0.0;
    if (!c->opt.extrinsic_std)
        return MCG_OK;
    for (k = 0; k < n; k++) {
        if (!(mask[k] & 2))
            continue;
        robust_copy_pair(c, k, m);
        id1[m] = c->cam1[k];
        id2[m] = c->cam2[k];
        top = id1[m] > top ? id1[m] : top;
        top = id2[m] > top ? id2[m] : top;
        c->wsub[m] = weights ? weights[k] : 1.0;
        equal &= c->wsub[m] == c->wsub[0];
        m++;
    }
    for (i = 0; i < 2 * (top + 1); i++)
        any |= c->opt.extrinsic_std[i] > 0.0;
    if (m == 0 || !any)
        return MCG_OK;
    st = mcg_calibration_scale_std(m, so1, sd1, so2, sd2, id1, id2, top + 1,
                                   c->opt.extrinsic_std, res->R, res->t,
                                   c->focal && !equal ? c->wsub : NULL, c->opt.loss,
                                   res->loss_scale, rel, cal_cov, c->cwork,
                                   mcg_calibration_std_work_size(top + 1));
    if (st != MCG_OK)
        return st;
    for (i = 0; i < 36; i++)
        cov[i] += cal_cov[i];
    return MCG_OK;
}

/* Median angle (radians) between d2 and R_fit d1 over the intra-camera
 * inliers: the static verdict's quoted residual (scratch: sub). */
static double still_median(ctx *c, const unsigned char *mask, const double R[9])
{
    int k, m = 0;
    for (k = 0; k < c->n; k++) {
        double a[3], u1[3], u2[3], x[3];
        if (!(mask[k] & 1) || c->cam1[k] != c->cam2[k] ||
            !unit3(c->d1 + 3 * (size_t)k, u1) || !unit3(c->d2 + 3 * (size_t)k, u2))
            continue;
        mat_vec(R, u1, a);
        cross3(a, u2, x);
        c->sub[m++] = atan2(sqrt(dot3(x, x)), dot3(a, u2));
    }
    return m ? median_inplace(c->sub, m) : NAN;
}

int mcg_scale_reason(int n_inliers, int n_cross, int n_cameras_intra, double critical_angle,
                     double rel_std, double max_rel_std, double profile, int n_in_front)
{
    if (n_inliers <= MOTION_DOF)
        return MCG_SCALE_NO_REDUNDANCY;
    if (!isfinite(rel_std) || rel_std > max_rel_std ||
        (isfinite(profile) && profile < PROFILE_SIGMAS2)) {
        if (n_cross == 0 && n_cameras_intra < 2)
            return MCG_SCALE_ONE_CAMERA;
        if (n_cross == 0 && critical_angle < CRITICAL_DEG * (PI / 180.0))
            return MCG_SCALE_CRITICAL;
        return MCG_SCALE_UNCERTAIN;
    }
    /* last guard against a confident wrong answer: a metric motion must put
     * its inliers in front of the cameras (a flipped or twisted solution
     * that survived the search puts most of them behind) */
    if (n_in_front < 0)
        return -1;
    return (double)n_in_front / n_inliers < 0.5 ? MCG_SCALE_CHEIRALITY : MCG_SCALE_OBSERVABLE;
}

/* The verdict of the result (res->scale; see mcg_robust_scale). w: the
 * final refinement's weights per pair (NULL: all equal), those the scale
 * profiles use too. Needs res->have_verdict (else undecided). */
void robust_scale_verdict(ctx *c, mcg_robust_result *res, const unsigned char *mask,
                          const double *w)
{
    mcg_robust_scale *s = &res->scale;
    const mcg_verdict_stats_result *v = &res->verdict;
    const double max_rel = c->opt.max_scale_rel_std, noise_level = res->loss_scale;
    double rel = HUGE_VAL, profile = NAN;
    int unconfirmed, reason, i;

    memset(s, 0, sizeof *s);
    res->have_scale = 1;
    s->reason = MCG_SCALE_UNDECIDED;
    s->slid = -1;
    /* undecided: never a metric-looking t, the unit direction of res->t
     * (scaled by its largest entry first: |t| may be near the doubles' end) */
    {
        double big = 0.0;
        for (i = 0; i < 3; i++)
            big = fabs(res->t[i]) > big ? fabs(res->t[i]) : big;
        if (big > 0.0 && isfinite(big)) {
            for (i = 0; i < 3; i++)
                s->t[i] = res->t[i] / big;
            unit3(s->t, s->t);
        }
    }
    memcpy(s->t_metric, res->t, sizeof s->t_metric);
    memcpy(s->covariance, res->covariance, sizeof s->covariance);
    s->rel_std = s->verdict_rel_std = HUGE_VAL;
    s->rel_std_noise = s->rel_std_calibration = NAN;
    s->profile = s->front_fraction = s->still_median = NAN;
    if (!res->have_verdict)
        return;

    /* the relative std of |t|: the refinement's noise part and the
     * calibration part in quadrature (total_scale_std) */
    if (res->refined) {
        double cal;
        if (calibration_part(c, res, mask, w, &cal, s->covariance) != MCG_OK)
            return;
        s->rel_std_noise = res->refinement.scale_rel_std;
        s->rel_std_calibration = cal;
        rel = combine_rel_std(s->rel_std_noise, cal);
        /* the profile at 1 +- 3 max_scale_rel_std where the std allows a
         * metric verdict (computed by the call already: rel <= max_rel
         * implies the noise part is) */
        if (rel <= max_rel) {
            if (!isfinite(res->scale_profile)) {
                const double k1 = 1.0 + 3.0 * max_rel, f[2] = {1.0 / k1, k1};
                res->scale_profile = robust_scale_profile(c, res, mask, w, f, 2, -HUGE_VAL);
            }
            profile = res->scale_profile;
        }
    }
    s->rel_std = rel;
    s->profile = profile;

    /* no translation detected: a pure rotation explains the intra-camera
     * inliers (observability.scale_verdict_stats; mcg_verdict_stats's fit
     * of rank < 2 is left to the numpy fit: undecided) */
    if (isfinite(noise_level) && noise_level > 0.0 && v->n_intra >= NO_PARALLAX_MIN) {
        if (!v->fit_ok)
            return;
        if ((double)v->n_still / v->n_intra >= NO_PARALLAX_FRACTION) {
            s->reason = MCG_SCALE_STATIC;
            s->verdict_rel_std = HUGE_VAL;
            s->still_median = still_median(c, mask, v->R_fit);
            memset(s->t, 0, sizeof s->t);
            return;
        }
    }
    s->translation_detected = 1;

    /* observability._verdict */
    s->verdict_rel_std = v->n_inliers <= MOTION_DOF ? HUGE_VAL : rel;
    reason = mcg_scale_reason(v->n_inliers, v->n_cross, v->n_cameras_intra, v->critical_angle,
                              rel, max_rel, profile, v->n_in_front);
    if (reason == MCG_SCALE_OBSERVABLE || reason == MCG_SCALE_CHEIRALITY)
        s->front_fraction = (double)v->n_in_front / v->n_inliers;
    /* a cap ended the search below CONFIRMED (unconfirmed_reason) */
    unconfirmed = res->stop != MCG_ROBUST_STOP_CONFIDENCE && !(res->confidence >= CONFIRMED);
    if (unconfirmed)
        reason = MCG_SCALE_UNCONFIRMED;
    s->reason = reason;
    s->observable = reason == MCG_SCALE_OBSERVABLE;
    s->determined = 1;
    memcpy(s->t, res->t, sizeof s->t);
    if (s->observable)
        return;

    /* not observable: t stays the metric estimate only where the data
     * define a scale (robust._verdict.conclude) */
    {
        const double *d = v->t_direction;
        const double n0 = sqrt(dot3(res->t_hypothesis, res->t_hypothesis));
        double nt = sqrt(dot3(res->t, res->t)), zero = NAN;
        /* slid out along the flat valley (|t| grew more than 10x), or into
         * the mirrored minimum (estimators._common.in_mirrored_minimum) */
        int slid = !(nt <= SLID_FACTOR * n0) || dot3(d, res->t) < -MIRRORED_COS * nt;
        s->slid = slid;
        if (slid)
            nt = n0;
        if (res->refined && !slid && !unconfirmed && scale_determined(rel, NAN)) {
            if (!isfinite(res->zero_profile)) {
                const double f0[1] = {ZERO_FACTOR};
                res->zero_profile =
                    robust_scale_profile(c, res, mask, w, f0, 1, ZERO_PROFILE_BOUND);
            }
            zero = res->zero_profile;
        }
        if (slid || unconfirmed || !scale_determined(rel, zero)) {
            for (i = 0; i < 3; i++) {
                if (slid)
                    s->t_metric[i] = nt * d[i];
                s->t[i] = d[i];
            }
            s->determined = 0;
        }
    }
}

/* The checks of the consensus of an observable scale (mcg_consensus_check;
 * mcgeom.robust._verdict.one_pair_checked words them): on the final
 * refinement's weights (weights, the caller's, else made from mask bit 1
 * and wp, the final refinement's pixel weights or NULL for all equal),
 * at (R, t). Workspace: work, the call's, whose residual buffers, gathered
 * subset and index array are free once the verdict is taken: its first n
 * doubles hold the weights made here, the next 15 n + 1 the check's. A
 * refusal makes the scale MCG_SCALE_CONSENSUS and t the unit direction of
 * travel (t_metric kept); a widened std is the scale's rel_std. */
void robust_consensus(ctx *c, mcg_robust_result *res, const unsigned char *mask,
                      const double *weights, const double *wp, double *work)
{
    mcg_robust_scale *s = &res->scale;
    const size_t n = (size_t)c->n;
    const double *w = weights;
    int i;
    size_t k;
    if (!res->have_scale || !s->observable)
        return;
    if (!w) {
        for (k = 0; k < n; k++)
            work[k] = (mask[k] & 2) ? (wp ? wp[k] : 1.0) : 0.0;
        w = work;
    }
    res->have_consensus =
        mcg_consensus_check(c->n, c->o1, c->d1, c->o2, c->d2, w, res->R, res->t, s->rel_std,
                            s->rel_std_calibration, c->opt.max_scale_rel_std, &res->consensus,
                            work + n, mcg_consensus_check_work_size(c->n)) == MCG_OK;
    if (!res->have_consensus)
        return;
    s->rel_std = s->verdict_rel_std = res->consensus.rel_std;
    if (res->consensus.reason == MCG_CONSENSUS_METRIC)
        return;
    s->reason = MCG_SCALE_CONSENSUS;
    s->observable = 0;
    s->determined = 0;
    s->slid = 0;
    for (i = 0; i < 3; i++)
        s->t[i] = res->verdict.t_direction[i];
}
