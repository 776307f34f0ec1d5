/*
 * refine.c -- nonlinear refinement of the relative motion of a generalized
 * camera (multi-camera rig): Levenberg-Marquardt on SO(3) x R^3 minimising a
 * robust function of the Sampson (first-order geometric) angular error of the
 * generalized epipolar constraint (thesis eq. 8.15). The thesis uses its
 * linear method (ch. 8, Algorithm 2) as the initial estimate of such a
 * non-linear refinement (ch. 8.5); this file is that refinement.
 *
 * Residual. A correspondence is a ray (o1, d1) in the rig frame at time 1 and
 * a ray (o2, d2) in the rig frame at time 2; the motion is rig2_from_rig1,
 * X2 = R X1 + t. With unit bearings and m = o x d, eq. 8.15 reads
 *     e = d2^T [t]x R d1 + d2^T R m1 + m2^T R d1 = d2^T F d1,
 *     F = [c]x R,   c = t + R o1 - o2,
 * i.e. the ordinary epipolar constraint of the camera pair whose baseline c
 * (in the time-2 rig frame) joins camera 2's centre to camera 1's moved one.
 * Its Sampson angular error, with the tangent projector P(d) = I - d d^T, is
 *     r = e / sqrt(D),   D = |P(d1) F^T d2|^2 + |P(d2) F d1|^2.
 * In the time-2 frame, with a = R d1, q = F d1 = c x a, h = R F^T d2 = d2 x c
 * and e = d2.q = a.h, D = |q|^2 + |h|^2 - 2 e^2. r is in radians: to first
 * order it is the smallest root-sum-square rotation of the two bearings that
 * satisfies the constraint. The kernels evaluate it on the raw directions
 * A = R d1, B = d2 (r is homogeneous of degree 0 in them), which needs one
 * square root and one division per pair:
 *     E = B.(c x A),  den = |B|^2 |c x A|^2 + |A|^2 |B x c|^2 - 2 E^2,
 *     r = E / sqrt(den).
 * The subtraction is harmless where it matters: for a small residual E^2 is
 * negligible against den.
 *
 * Where D vanishes: D = 0 iff both gradients of e on the bearing spheres
 * vanish. Either c = 0 (the camera centre does not move: F = 0, no epipolar
 * constraint, e = 0 too) or e is stationary at its extreme |e| = |c| (d2
 * normal to the epipolar plane): no first-order error exists. Hence
 *     r = e / sqrt(max(D, (2/pi)^2 e^2, DBL_MIN)),
 * the Sampson error while it is below pi/2 (the largest angle a bearing ever
 * has to turn to reach the epipolar plane), then +-pi/2, and 0 when
 * e = D = 0: continuous except at e = D = 0, never inf/NaN. A residual on the
 * cap (or from e = D = 0) has a zero Jacobian row and is not "used".
 *
 * Jacobian (left perturbation R <- exp([dw]x) R, t <- t + dt, as in
 * linear17.c): derived on the raw form, see block_rows().
 *
 * Optimisation: minimise C = sum_i w_i rho(r_i^2) by Gauss-Newton with IRLS
 * weights omega_i = w_i rho'(r_i^2) and Marquardt damping
 * (J^T W J + lambda diag(J^T W J)) dx = -J^T W r, lambda updated by the gain
 * ratio (Nielsen's rule), inside a trust region (a step turns R by at most
 * 0.5 rad and moves t by at most max(|t|, L) / 2, L the rig size) that keeps
 * steps along a weakly observable |t| from overshooting. Each step is
 * lengthened by the curvature the previous one measured, and the loop stops
 * once the next step is expected to gain less than cost_tolerance (see
 * curvature_ratio). Each evaluation
 * loops once over the rays in blocks of BLK pairs and accumulates the 6 x 6
 * normal equations directly (no caller workspace, 2.3 KB of stack). The
 * block passes (block_rows, cauchy_block, evaluate) and mcg_gec_residuals
 * carry MCG_AVX2_CLONE (internal.h; issue 19: the LM evaluations were ~2/3
 * of the robust entry point's instructions): the same bits, 36 % fewer
 * instructions per evaluation on an AVX2 CPU. Their array arguments are
 * restrict: a clone does not inline its callees, and without it the
 * vectoriser gave up on block_rows' aliasing checks (scalar code). fix_scale
 * keeps |t| = |t0|: t moves on that sphere through a 2-dof tangent basis and
 * the retraction t <- |t0| (t + B u) / |t + B u|. mcg_refine_translation
 * holds R: the steps move t alone, and its std is read from H_tt (the
 * known-rotation estimator's t: the linear one of thesis ch. 6 is biased).
 *
 * Uncertainty at the solution: the information matrix H = J^T W J (6 x 6,
 * [dw, dt]); sigma2 = sum omega r^2 / (sum omega - p) (p = 6, 5 with
 * fix_scale, 3 with R held); the t-block of H^-1 is the inverse of the
 * Schur complement S = H_tt - H_tw H_ww^-1 H_wt, so var|t| = sigma2 u^T S^-1 u
 * with u = t/|t| (R held: S = H_tt).
 *
 * The parts (refine_internal.h: what they share): this file, the
 * Levenberg-Marquardt driver (options, checks, steps, trust region,
 * extrapolation, the statistics at the solution); refine_eval.c, the
 * residual of every pair and one evaluation of the robust cost and its
 * normal equations.
 */
#include "refine_internal.h"
#include "sampson.h"

#include <float.h>
#include <math.h>
#include <string.h>

#define LAMBDA_MAX 1e32                  /* damping beyond: no descent exists */
#define SING_RTOL 1e-10                  /* eigenvalue ratio treated as singular */
#define MAX_TURN 0.5                     /* largest rotation step, radians */

/* What a refinement moves (the step's parametrisation, reduced_system):
 * all six degrees of freedom, t on the sphere |t| = |t0| (fix_scale), or t
 * alone with R held (mcg_refine_translation: a rotation known from a gyro
 * or ground truth). */
enum { MOVE_ALL = 0, MOVE_FIX_SCALE = 1, MOVE_T_ONLY = 2 };

void mcg_refine_default_options(mcg_refine_options *opt)
{
    if (!opt)
        return;
    opt->loss = MCG_LOSS_NONE;
    opt->loss_scale = 1e-3;
    opt->max_iterations = 50;
    opt->cost_tolerance = 1e-10;
    opt->step_tolerance = 1e-10;
    opt->initial_lambda = 1e-4;
    opt->fix_scale = 0;
}

static int check_options(const mcg_refine_options *o)
{
    if (o->loss < MCG_LOSS_NONE || o->loss > MCG_LOSS_SOFT_L1)
        return 0;
    if (!isfinite(o->loss_scale) || !(o->loss_scale > 0.0))
        return 0;
    if (o->max_iterations < 0 || o->max_iterations > 10000)
        return 0;
    if (!isfinite(o->cost_tolerance) || o->cost_tolerance < 0.0)
        return 0;
    if (!isfinite(o->step_tolerance) || o->step_tolerance < 0.0)
        return 0;
    if (!isfinite(o->initial_lambda) || o->initial_lambda < 0.0 ||
        o->initial_lambda > 1e16)
        return 0;
    if (o->fix_scale != 0 && o->fix_scale != 1)
        return 0;
    return 1;
}

/* Orthonormal basis (columns b[:, 0], b[:, 1], stored as two 3-vectors) of
 * the plane orthogonal to u (unit). */
static void tangent_basis(const double u[3], double b1[3], double b2[3])
{
    double ax[3] = {0.0, 0.0, 0.0}, nb;
    int i, k = 0;
    for (i = 1; i < 3; i++)
        if (fabs(u[i]) < fabs(u[k]))
            k = i;
    ax[k] = 1.0;
    cross3(u, ax, b1);
    nb = sqrt(dot3(b1, b1));
    for (i = 0; i < 3; i++)
        b1[i] /= nb;
    cross3(u, b1, b2);
}

/* info_cond = lambda_min / lambda_max of a 3 x 3 information s of t, and
 * var = u^T s^-1 u, u = t / |t| (HUGE_VAL when s is singular along u). */
static void evidence_of(double s[9], const double t[3], double *cond, double *var)
{
    double w[3], v[9], nt, u[3];
    int i, k;
    *cond = 0.0;
    *var = HUGE_VAL;
    if (mcg_sym_eig(3, s, w, v) != MCG_OK || !(w[2] > 0.0))
        return;
    *cond = w[0] > 0.0 ? w[0] / w[2] : 0.0;
    nt = sqrt(dot3(t, t));
    if (!(nt > 0.0))
        return;
    for (i = 0; i < 3; i++)
        u[i] = t[i] / nt;
    {
        double acc = 0.0;
        for (k = 0; k < 3; k++) {
            double pk = v[k] * u[0] + v[3 + k] * u[1] + v[6 + k] * u[2];
            if (w[k] <= SING_RTOL * w[2]) {
                if (pk * pk > 1e-8)
                    return; /* |t| lies (partly) in the null space */
                continue;
            }
            acc += pk * pk / w[k];
        }
        *var = acc;
    }
}

/* Evidence on |t| from H at (R, t) (evidence_of): of the Schur complement
 * S = H_tt - H_tw H_ww^-1 H_wt of the t-block where R is estimated too,
 * of H_tt itself where R is held (move = MOVE_T_ONLY: a known rotation has
 * no uncertainty to marginalise). */
static void scale_evidence(const double *h, const double t[3], int move, double *cond,
                           double *var)
{
    double hww[9], hwt[9], z[3], col[3], s[9];
    int i, k;
    *cond = 0.0;
    *var = HUGE_VAL;
    for (i = 0; i < 3; i++)
        for (k = 0; k < 3; k++) {
            hww[3 * i + k] = h[6 * i + k];
            hwt[3 * i + k] = h[6 * i + 3 + k];
            s[3 * i + k] = h[6 * (3 + i) + 3 + k];
        }
    for (k = 0; k < 3 && move != MOVE_T_ONLY; k++) { /* S -= H_tw H_ww^-1 H_wt */
        for (i = 0; i < 3; i++)
            col[i] = hwt[3 * i + k];
        if (mcg_spd_solve(3, hww, col, z) != MCG_OK)
            return;
        for (i = 0; i < 3; i++)
            s[3 * i + k] -= hwt[0 + i] * z[0] + hwt[3 + i] * z[1] + hwt[6 + i] * z[2];
    }
    for (i = 0; i < 3; i++) /* symmetrise the rounding */
        for (k = 0; k < i; k++)
            s[3 * i + k] = s[3 * k + i] = 0.5 * (s[3 * i + k] + s[3 * k + i]);
    evidence_of(s, t, cond, var);
}

/* The argument checks of mcg_refine_motion (its header comment lists them);
 * *o receives the options (the defaults for NULL). */
static int check_inputs(int n, const double *o1, const double *d1, const double *o2,
                        const double *d2, const double *weights,
                        const mcg_refine_options *opt, const double R[9],
                        const double t[3], mcg_refine_options *o)
{
    int k;
    if (!o1 || !d1 || !o2 || !d2 || !R || !t)
        return MCG_EINVAL;
    if (n < 6 || n > MAX_RAYS)
        return MCG_EINVAL;
    if (opt) {
        if (!check_options(opt))
            return MCG_EINVAL;
        *o = *opt;
    } else {
        mcg_refine_default_options(o);
    }
    if (!all_finite(R, 9) || !all_finite(t, 3) || !is_rotation(R))
        return MCG_EINVAL;
    if (weights) {
        if (!all_finite(weights, (size_t)n))
            return MCG_EINVAL;
        for (k = 0; k < n; k++)
            if (weights[k] < 0.0)
                return MCG_EINVAL;
    }
    return MCG_OK;
}

/* The Gauss-Newton system of one iteration in the step's parameters: with
 * P (6 x m) the parametrisation of the step [dw; dt] (the identity; [dw; B u]
 * with fix_scale, B an orthonormal basis of the tangent plane of the sphere
 * |t| = rho0 at t; [0; dt] with R held), hm = P^T H P and gm = P^T g
 * (m x m, m). Returns m. */
static int reduced_system(const accum *cur, int move, const double tv[3], double rho0,
                          double pm[6][6], double *hm, double *gm)
{
    int i, m = move == MOVE_ALL ? 6 : (move == MOVE_FIX_SCALE ? 5 : 3);
    memset(pm, 0, 36 * sizeof(double));
    for (i = 0; i < 3; i++)
        pm[move == MOVE_T_ONLY ? 3 + i : i][i] = 1.0;
    if (move == MOVE_FIX_SCALE) {
        double u[3], b1[3] = {0, 0, 0}, b2[3] = {0, 0, 0};
        for (i = 0; i < 3; i++)
            u[i] = tv[i] / rho0;
        tangent_basis(u, b1, b2);
        for (i = 0; i < 3; i++) {
            pm[3 + i][3] = b1[i];
            pm[3 + i][4] = b2[i];
        }
    } else if (move == MOVE_ALL) {
        for (i = 3; i < 6; i++)
            pm[i][i] = 1.0;
    }
    if (move == MOVE_ALL) {
        memcpy(hm, cur->h, 36 * sizeof(double));
        memcpy(gm, cur->g, 6 * sizeof(double));
    } else { /* hm = P^T H P, gm = P^T g */
        double hp[6][5];
        int jj, p;
        for (p = 0; p < 6; p++)
            for (jj = 0; jj < m; jj++) {
                double acc = 0.0;
                for (i = 0; i < 6; i++)
                    acc += cur->h[6 * p + i] * pm[i][jj];
                hp[p][jj] = acc;
            }
        for (i = 0; i < m; i++) {
            gm[i] = 0.0;
            for (p = 0; p < 6; p++)
                gm[i] += pm[p][i] * cur->g[p];
            for (jj = 0; jj < m; jj++) {
                double acc = 0.0;
                for (p = 0; p < 6; p++)
                    acc += pm[p][i] * hp[p][jj];
                hm[m * i + jj] = acc;
            }
        }
    }
    return m;
}

/* The Levenberg-Marquardt step dx of (hm + lambda D) dx = -gm, D = diag(hm)
 * floored at 1e-12 maxd so that directions the data do not constrain at all
 * still get a finite step. gm is negated in place (the predicted decrease
 * uses -g). Returns the status of the Cholesky solve. */
static int marquardt_step(const double *hm, double *gm, int m, double maxd,
                          double lambda, double *dx)
{
    double a[36], dmp;
    int i;
    memcpy(a, hm, sizeof a);
    for (i = 0; i < m; i++) {
        dmp = hm[m * i + i] > 1e-12 * maxd ? hm[m * i + i] : 1e-12 * maxd;
        a[m * i + i] += lambda * dmp;
    }
    for (i = 0; i < m; i++)
        gm[i] = -gm[i];
    return mcg_spd_solve(m, a, gm, dx);
}

/* dfull = P dx, then the trust region on top of the damping: a step may
 * turn R by at most MAX_TURN and move t by at most max(|t|, L) / 2
 * (L = rig size); dx and dfull are scaled together. In weakly
 * scale-observable configurations a step along the flat |t| direction
 * otherwise overshoots, even through t = 0. */
static void limit_step(double pm[6][6], int m, const double tv[3], double ell,
                       double *dx, double dfull[6])
{
    double nw0, nt0, ntv, alpha = 1.0, lim;
    int i, jj;
    for (i = 0; i < 6; i++) {
        dfull[i] = 0.0;
        for (jj = 0; jj < m; jj++)
            dfull[i] += pm[i][jj] * dx[jj];
    }
    nw0 = sqrt(dot3(dfull, dfull));
    nt0 = sqrt(dot3(dfull + 3, dfull + 3));
    ntv = sqrt(dot3(tv, tv));
    lim = 0.5 * (ntv > ell ? ntv : ell);
    if (nw0 > MAX_TURN)
        alpha = MAX_TURN / nw0;
    if (lim > 0.0 && nt0 * alpha > lim)
        alpha = lim / nt0;
    for (i = 0; i < m; i++)
        dx[i] *= alpha;
    for (i = 0; i < 6; i++)
        dfull[i] *= alpha;
}

/* predicted decrease of the IRLS model, -2 g.dx - dx^T H dx (ngm = -g) */
static double predicted_decrease(const double *hm, const double *ngm, const double *dx,
                                 int m)
{
    double pred = 0.0;
    int i, jj;
    for (i = 0; i < m; i++) {
        double acc = 0.0;
        for (jj = 0; jj < m; jj++)
            acc += hm[m * i + jj] * dx[jj];
        pred += 2.0 * ngm[i] * dx[i] - dx[i] * acc;
    }
    return pred;
}

/* The candidate motion: R <- exp([dw]x) R (R itself, to the bit, when it
 * is held), t <- t + dt, retracted onto the sphere |t| = rho0 with
 * fix_scale. 0 if the rotation cannot be formed. */
static int candidate_motion(const double dfull[6], const double r[9], const double tv[3],
                            int move, double rho0, double rn[9], double tn[3])
{
    double dr[9];
    int i;
    if (move == MOVE_T_ONLY) {
        memcpy(rn, r, 9 * sizeof(double));
    } else {
        if (mcg_rot_from_angle_axis(dfull, dr) != MCG_OK)
            return 0;
        mul33(dr, r, rn);
    }
    for (i = 0; i < 3; i++)
        tn[i] = tv[i] + dfull[3 + i];
    if (move == MOVE_FIX_SCALE) {
        double nn = sqrt(dot3(tn, tn));
        for (i = 0; i < 3; i++)
            tn[i] *= rho0 / nn;
    }
    return 1;
}

/* Extrapolation of an accepted step whose actual decrease exceeded
 * EXTRAP_GAIN times the predicted one: the IRLS model J^T W J, W = w rho',
 * leaves out the negative curvature w (rho' + 2 z rho'') of a redescending
 * loss (Cauchy: (1 - u) / (1 + u)^2 < rho' = 1 / (1 + u)), so where many
 * residuals lie beyond the loss scale its steps fall short and LM crawls
 * (measured: the zero-factor scale profile of robust.c lost ~12 % of the
 * cost gap per step over 25+ steps, each decreasing the cost twice as much
 * as predicted). The cost along the step, phi(a), is known at a = 0 (value
 * and exact slope 2 g.dx) and at a = 1; the minimiser of the parabola
 * through them, capped at EXTRAP_MAX and at the trust region, is tried once
 * and kept only if its cost is lower (a safeguarded quadratic line search,
 * Nocedal & Wright 2006, ch. 3.5). ngm: -g reduced; dx, dfull: the step. */
#define EXTRAP_GAIN 1.5

#define EXTRAP_MAX 4.0

static void extrapolate(int n, const double *o1, const double *d1, const double *o2,
                        const double *d2, const double *weights, const lossfn *lf,
                        const double *ngm, const double *dx, int m, const double dfull[6],
                        const double r[9], const double tv[3], int move, double rho0,
                        double t_lim, double cost0, double rn[9], double tn[3], accum *trial)
{
    double slope = 0.0, curv, a, nw, ndt, d2f[6], r2[9], t2[3];
    accum ext;
    int i;
    for (i = 0; i < m; i++)
        slope -= 2.0 * ngm[i] * dx[i];
    curv = trial->cost - cost0 - slope;
    if (!(slope < 0.0) || !(curv > 0.0))
        return;
    a = -slope / (2.0 * curv);
    nw = sqrt(dot3(dfull, dfull));
    ndt = sqrt(dot3(dfull + 3, dfull + 3));
    a = a < EXTRAP_MAX ? a : EXTRAP_MAX;
    if (nw > 0.0 && a * nw > MAX_TURN)
        a = MAX_TURN / nw;
    if (t_lim > 0.0 && ndt > 0.0 && a * ndt > t_lim)
        a = t_lim / ndt;
    if (!(a > EXTRAP_GAIN))
        return;
    for (i = 0; i < 6; i++)
        d2f[i] = a * dfull[i];
    if (!candidate_motion(d2f, r, tv, move, rho0, r2, t2))
        return;
    refine_evaluate(n, o1, d1, o2, d2, weights, lf, r2, t2, &ext);
    if (ext.bad || !(ext.cost < trial->cost))
        return;
    memcpy(rn, r2, sizeof r2);
    memcpy(tn, t2, sizeof t2);
    *trial = ext;
}

/* Relaxed steps. The same missing curvature shortens every step, not only
 * those beyond EXTRAP_GAIN: along the Cauchy refinements of robust.c the
 * cost fell 1.2-1.45 times as much as the model predicted, step after step,
 * and each step left ~1/15 of the cost gap (linear convergence, 4-6 steps
 * per refinement). If the cost along the step dx (the model's minimiser) is
 * the model's with its curvature divided by c, a step a dx decreases the
 * model by (2a - a^2) G and the cost by (2a - a^2 / c) G, G the model's
 * decrease at a = 1; an accepted step's gain ratio q = actual / predicted
 * therefore measures c = a / (2 - q (2 - a)), and the step that minimises
 * the cost is a = c. The next step is taken at a = c, clamped to
 * [1, CURV_MAX] (a relaxation factor from the previous step, as in
 * over-relaxed Gauss-Newton; LM's acceptance test still guards every step):
 * issue 19, 2-4 steps per refinement instead of 4-6. */
#define CURV_MAX 1.6

static double curvature_ratio(double a, double gain)
{
    double den = 2.0 - gain * (2.0 - a);
    return den > 0.0 ? a / den : HUGE_VAL;
}

/* The step length a of the next step: the ratio clamped to [1, CURV_MAX]
 * (NaN, no measurement: 1) */
static double relaxation(double ratio)
{
    return ratio > CURV_MAX ? CURV_MAX : (ratio > 1.0 ? ratio : 1.0);
}

/* Below this damping the Marquardt step is the Gauss-Newton one to 0.1 %:
 * its predicted decrease may stop the loop (lm_iteration). */
#define TRUST_LAMBDA 1e-3

/* The damping and stopping state of the Levenberg-Marquardt loop. */
typedef struct {
    double lambda, nu;
    double ratio; /* the IRLS model's curvature over the cost's along the
                     last accepted step (curvature_ratio); NaN after a
                     rejected step and at the start. The next step is
                     lengthened by relaxation(ratio); the model is trusted
                     (its prediction may stop the loop) when the ratio is
                     within a factor 2 of 1 */
    int reason, converged;
    int trials; /* steps tried, accepted or not (res->iterations) */
    int move;   /* MOVE_*: the parameters the steps move */
} lm_state;

/* A failed step (not solvable, or not decreasing the cost): raise the
 * damping (Nielsen's rule); 1 when it exceeds LAMBDA_MAX (stalled). */
static int lm_reject(lm_state *lm)
{
    lm->ratio = NAN;
    lm->lambda = lm->lambda > 0.0 ? lm->lambda * lm->nu : 1e-12;
    lm->nu *= 2.0;
    if (lm->lambda > LAMBDA_MAX) {
        lm->reason = MCG_REFINE_STOP_STALLED;
        return 1;
    }
    return 0;
}

/* One Levenberg-Marquardt iteration from (r, tv) with the normal equations
 * *cur at it: reduced system, damped step, trust region, candidate, and its
 * acceptance (gain ratio update of lambda). Returns 1 when the loop stops
 * (lm->reason, lm->converged set), else 0. */
static int lm_iteration(int n, const double *o1, const double *d1, const double *o2,
                        const double *d2, const double *weights, const lossfn *lf,
                        const mcg_refine_options *o, double ell, double rho0, double r[9],
                        double tv[3], accum *cur, lm_state *lm)
{
    double pm[6][6], hm[36], gm[6], dx[6], dfull[6], rn[9], tn[3];
    double maxd = 0.0, gmax = 0.0, pred, nw, ndt, nt, actual, a = relaxation(lm->ratio);
    int i, m, accepted, small, move = lm->move;
    accum trial;

    m = reduced_system(cur, move, tv, rho0, pm, hm, gm);
    for (i = 0; i < m; i++) {
        if (hm[m * i + i] > maxd)
            maxd = hm[m * i + i];
        if (fabs(gm[i]) > gmax)
            gmax = fabs(gm[i]);
    }
    if (gmax == 0.0) { /* exact stationary point (e.g. zero cost) */
        lm->converged = 1;
        lm->reason = MCG_REFINE_STOP_GRADIENT;
        return 1;
    }
    if (!(maxd > 0.0)) {
        lm->reason = MCG_REFINE_STOP_STALLED;
        return 1;
    }
    if (marquardt_step(hm, gm, m, maxd, lm->lambda, dx) != MCG_OK) {
        lm->trials++;
        return lm_reject(lm);
    }
    /* converged, without trying it, when the step is expected to lower the
     * cost by at most the tolerance: the relaxed step's decrease
     * (2 a - a^2 / c) G (see curvature_ratio; a = c unless clamped),
     * once the model has just predicted a step to that factor and the
     * damping no longer shortens the step (the stop of an accepted step
     * below the tolerance, one evaluation earlier) */
    pred = predicted_decrease(hm, gm, dx, m);
    if (lm->ratio >= 0.5 && lm->ratio <= 2.0 && lm->lambda <= TRUST_LAMBDA &&
        (2.0 * a - a * a / lm->ratio) * pred <= o->cost_tolerance * cur->cost) {
        lm->converged = 1;
        lm->reason = MCG_REFINE_STOP_COST;
        return 1;
    }
    lm->trials++;
    for (i = 0; i < m; i++)
        dx[i] *= a;
    limit_step(pm, m, tv, ell, dx, dfull);
    pred = predicted_decrease(hm, gm, dx, m);
    if (!candidate_motion(dfull, r, tv, move, rho0, rn, tn)) {
        lm->reason = MCG_REFINE_STOP_STALLED;
        return 1;
    }
    refine_evaluate(n, o1, d1, o2, d2, weights, lf, rn, tn, &trial);
    actual = cur->cost - trial.cost;
    nw = sqrt(dot3(dfull, dfull));
    ndt = sqrt(dot3(dfull + 3, dfull + 3));
    nt = sqrt(dot3(tv, tv));
    small = nw <= o->step_tolerance &&
            ndt <= o->step_tolerance * (nt + ell > 0.0 ? nt + ell : 1.0);
    accepted = !trial.bad && trial.cost <= cur->cost;
    if (accepted) {
        double gain = pred > 0.0 ? actual / pred : 0.0, f;
        double c0 = cur->cost;
        lm->ratio = curvature_ratio(a, gain);
        /* (a step short even at CURV_MAX: the line search) */
        if (lm->ratio > CURV_MAX && gain > EXTRAP_GAIN)
            extrapolate(n, o1, d1, o2, d2, weights, lf, gm, dx, m, dfull, r, tv, move, rho0,
                        0.5 * (nt > ell ? nt : ell), cur->cost, rn, tn, &trial);
        actual = cur->cost - trial.cost;
        memcpy(r, rn, sizeof rn);
        memcpy(tv, tn, sizeof tn);
        *cur = trial;
        f = 2.0 * gain - 1.0;
        f = 1.0 - f * f * f;
        lm->lambda *= f > 1.0 / 3.0 ? f : 1.0 / 3.0;
        lm->nu = 2.0;
        if (small) {
            lm->converged = 1;
            lm->reason = MCG_REFINE_STOP_STEP;
            return 1;
        }
        if (actual <= o->cost_tolerance * c0) {
            lm->converged = 1;
            lm->reason = MCG_REFINE_STOP_COST;
            return 1;
        }
        return 0;
    }
    if (small) { /* even a negligible step does not help: at the floor */
        lm->converged = 1;
        lm->reason = MCG_REFINE_STOP_STEP;
        return 1;
    }
    return lm_reject(lm);
}

/* Statistics at the solution: information matrix, rms, the residual
 * variance sigma2 = sum W r^2 / (sum W - p) and the first-order relative
 * std of |t| (scale_evidence). With weights (or coordinates) near the top
 * of the double range the information matrix J^T W J overflows although
 * every step's cost stayed finite: no statistics can be given, and a motion
 * without them is not returned as MCG_OK. */
static int final_statistics(const accum *cur, const double tv[3], double pdim,
                            const lm_state *lm, mcg_refine_result *res)
{
    double var, nt;
    if (!all_finite(cur->h, 36) || !isfinite(cur->cost))
        return MCG_ENUMERIC;
    res->final_cost = cur->cost;
    res->converged = lm->converged;
    res->reason = lm->reason;
    res->n_used = cur->n_used;
    memcpy(res->info, cur->h, sizeof res->info);
    res->rms = sqrt(cur->swr2 / cur->sw);
    res->sigma2 = cur->som > pdim ? cur->somr2 / (cur->som - pdim) : HUGE_VAL;
    nt = sqrt(dot3(tv, tv));
    scale_evidence(cur->h, tv, lm->move, &res->info_cond, &var);
    if (isfinite(var) && isfinite(res->sigma2) && nt > 0.0)
        res->scale_rel_std = sqrt(res->sigma2 * var) / nt;
    else
        res->scale_rel_std = HUGE_VAL;
    return MCG_OK;
}

/* mcg_refine_motion that also stops (converged, MCG_REFINE_STOP_COST) as
 * soon as the cost is at most cost_target, or once it stays above it by more
 * than ABOVE_STEPS times the decrease of the last accepted step
 * (internal.h): for a statistic that is only compared with a bound,
 * robust.c's zero profile. */
#define ABOVE_STEPS 100.0

/* The refinement of (R, t) (move: MOVE_ALL or MOVE_FIX_SCALE from
 * opt->fix_scale, or MOVE_T_ONLY), stopping at cost_target as
 * mcg_refine_motion_until does. */
static int refine_run(int n, const double *o1, const double *d1, const double *o2,
                      const double *d2, const double *weights, const mcg_refine_options *opt,
                      int t_only, double cost_target, double R[9], double t[3],
                      mcg_refine_result *res)
{
    mcg_refine_options o;
    lossfn lf;
    accum cur;
    lm_state lm;
    double r[9], tv[3], rho0 = 0.0, ell, pdim, c[3];
    int i, it, st;

    if (!res)
        return MCG_EINVAL;
    memset(res, 0, sizeof *res);
    res->sigma2 = HUGE_VAL;
    res->scale_rel_std = HUGE_VAL;
    st = check_inputs(n, o1, d1, o2, d2, weights, opt, R, t, &o);
    if (st != MCG_OK)
        return st;
    if (t_only && o.fix_scale)
        return MCG_EINVAL; /* R held and |t| held: mcg_refine_translation refuses */
    if (mcg_project_so3(R, r) != MCG_OK) /* exact rotation from here on */
        return MCG_EINVAL;
    memcpy(tv, t, sizeof tv);
    if (o.fix_scale) {
        rho0 = sqrt(dot3(tv, tv));
        if (!(rho0 > 0.0))
            return MCG_EINVAL; /* no sphere to stay on */
    }
    lm.move = t_only ? MOVE_T_ONLY : (o.fix_scale ? MOVE_FIX_SCALE : MOVE_ALL);
    pdim = lm.move == MOVE_ALL ? 6.0 : (lm.move == MOVE_FIX_SCALE ? 5.0 : 3.0);
    lf.loss = o.loss;
    lf.s = o.loss_scale;
    lf.s2 = o.loss_scale * o.loss_scale;
    lf.inv_s2 = 1.0 / lf.s2;
    if (!(lf.s2 > 0.0) || !isfinite(lf.inv_s2))
        return MCG_EINVAL;

    refine_evaluate(n, o1, d1, o2, d2, weights, &lf, r, tv, &cur);
    if (cur.bad)
        return MCG_EINVAL;
    res->initial_cost = cur.cost;
    res->final_cost = cur.cost;
    res->n_used = cur.n_used;
    if (!(cur.sw > 0.0))
        return MCG_EDEGENERATE; /* every weight is zero */
    {
        double tr = 0.0;
        for (i = t_only ? 3 : 0; i < 6; i++) /* (of the parameters that move) */
            tr += cur.h[7 * i];
        if (!(tr > 0.0))
            return MCG_EDEGENERATE; /* no ray constrains the motion here */
    }
    /* characteristic length L of the rig (independent of the rig frame) */
    ell = origin_spread(n, o1, o2, c);

    lm.lambda = o.initial_lambda;
    lm.nu = 2.0;
    lm.reason = MCG_REFINE_STOP_MAX_ITERATIONS;
    lm.converged = 0;
    lm.trials = 0;
    lm.ratio = NAN;
    for (it = 0; it < o.max_iterations; it++) {
        const double before = cur.cost;
        if (cur.cost <= cost_target) {
            lm.converged = 1;
            lm.reason = MCG_REFINE_STOP_COST;
            break;
        }
        if (lm_iteration(n, o1, d1, o2, d2, weights, &lf, &o, ell, rho0, r, tv, &cur, &lm))
            break;
        /* ... or once it is evidently above it: a descent at a linear rate
         * q <= 0.99 has at most ABOVE_STEPS times its last decrease left
         * (the zero profile's fits crept down by ~1e-4 of their cost per
         * step for 50 steps, 10-20x above the bound: issue 19) */
        if (cost_target > -HUGE_VAL && cur.cost < before &&
            cur.cost - ABOVE_STEPS * (before - cur.cost) > cost_target) {
            lm.converged = 1;
            lm.reason = MCG_REFINE_STOP_COST;
            break;
        }
    }
    res->iterations = lm.trials;

    st = final_statistics(&cur, tv, pdim, &lm, res);
    if (st != MCG_OK)
        return st;
    memcpy(R, r, sizeof r); /* (held: r is R projected, and R a copy) */
    memcpy(t, tv, sizeof tv);
    return MCG_OK;
}

int mcg_refine_motion_until(int n, const double *o1, const double *d1, const double *o2,
                            const double *d2, const double *weights,
                            const mcg_refine_options *opt, double cost_target, double R[9],
                            double t[3], mcg_refine_result *res)
{
    return refine_run(n, o1, d1, o2, d2, weights, opt, 0, cost_target, R, t, res);
}

int mcg_refine_motion(int n, const double *o1, const double *d1,
                      const double *o2, const double *d2, const double *weights,
                      const mcg_refine_options *opt, double R[9], double t[3],
                      mcg_refine_result *res)
{
    return refine_run(n, o1, d1, o2, d2, weights, opt, 0, -HUGE_VAL, R, t, res);
}

/* R held: the driver works on a copy of it (R is const; the driver writes
 * its projection onto SO(3) back into the copy) */
int mcg_refine_translation(int n, const double *o1, const double *d1, const double *o2,
                           const double *d2, const double *weights,
                           const mcg_refine_options *opt, const double R[9], double t[3],
                           mcg_refine_result *res)
{
    double r[9];
    if (!R)
        return refine_run(n, o1, d1, o2, d2, weights, opt, 1, -HUGE_VAL, NULL, t, res);
    memcpy(r, R, sizeof r);
    return refine_run(n, o1, d1, o2, d2, weights, opt, 1, -HUGE_VAL, r, t, res);
}
