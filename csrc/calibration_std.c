/*
 * calibration_std.c -- the relative std of |t| that the rig's extrinsic
 * calibration error induces in a refined motion (issue 18: the verdict
 * decides on noise and calibration together; mcgeom/observability.py,
 * calibration_scale_std, documents the model and calls this kernel).
 *
 * First-order propagation through the least-squares estimate (the implicit
 * function theorem on its normal equations): with theta = (w, tau) the
 * motion's parameters (a left rotation increment w, radians, and the
 * translation of the cameras' centroid c, tau = t + R c - c, metres), r the
 * Sampson angular residuals (thesis eq. 8.15 of the generalized epipolar
 * constraint, eq. 8.16) and W the user weights times the robust loss's IRLS
 * weights at the solution,
 *     d theta / d p = -(J^T W J)^-1 J^T W (dr / dp)
 * for every extrinsic parameter p of a camera: its centre (metres, rig
 * frame) and its orientation (a rotation about its centre, radians). A
 * camera's error moves the origins and turns the bearings of its rays at
 * both times (an intra-camera pair at both ends, a cross-camera pair at one).
 * Each camera k contributes sum_kind sigma_k,kind^2 G G^T to the covariance
 * of theta, G = d theta / d p (6 x 3 per kind); var |tau| = u^T Cov_tau u,
 * u = tau / |tau|.
 *
 * J and the derivatives of a camera's turn are central differences of the
 * residuals (sampson.h, the residual of mcg_gec_residuals): steps of 1e-6
 * rad and 1e-6 |tau|; the residuals are smooth, so the differences are
 * accurate to ~1e-10 relative. A camera's centre enters only through the
 * translation term, so its derivatives come from J's translation columns. One pass over the pairs: each pair's J
 * row and its derivatives for its one or two cameras go straight into
 * J^T W J and the per-camera sums J^T W dr / dp (6 x 3 per camera and
 * kind, in the workspace), so nothing of size N is stored. The numpy
 * implementation this replaces cost 2-4 ms per robust estimate of a rig
 * with a calibration error (issue 19: 3-4x the C search itself).
 */
#include "mcgeom.h"
#include "internal.h"
#include "sampson.h"

#include <math.h>
#include <string.h>

#define MAX_CAL_CAMERAS 4096
#define H_ANG 1e-6 /* angular step of the central differences (radians) */
#define H_REL 1e-6 /* translation step, relative to |tau| */

size_t mcg_calibration_std_work_size(int n_cameras)
{
    if (n_cameras < 1 || n_cameras > MAX_CAL_CAMERAS)
        return 0;
    return 36 * (size_t)n_cameras; /* per camera: J^T W dr/dp, 6 x 3 per kind */
}

/* Rodrigues' rotation by the angle h about axis k (0, 1, 2) */
static void axis_turn(int k, double h, double out[9])
{
    double w[3] = {0.0, 0.0, 0.0};
    w[k] = h;
    mcg_rot_from_angle_axis(w, out);
}

/* the loss's IRLS weight factor at the residual r (scale s, radians), as
 * mcg_refine_motion weighs its normal equations */
static double loss_weight(int loss, double r, double s)
{
    double z = r / s;
    switch (loss) {
    case MCG_LOSS_CAUCHY:
        return 1.0 / (1.0 + z * z);
    case MCG_LOSS_HUBER: {
        double a = fabs(r) > 1e-300 ? fabs(r) : 1e-300;
        return s / a < 1.0 ? s / a : 1.0;
    }
    case MCG_LOSS_SOFT_L1:
        return 1.0 / sqrt(1.0 + z * z);
    default:
        return 1.0;
    }
}

/* d r / d p of one pair for the camera's perturbations of one kind (0: its
 * centre moves along each axis, 1: it turns about each axis), applied at
 * time 1 when at1, at time 2 when at2; dr[3] per axis. A centre enters the
 * residual only through c = tau + R o1 - o2 (sampson.h), so moving o1 by
 * e_k is moving tau by R e_k and moving o2 by e_k is moving tau by -e_k:
 * the position derivatives are the pair's translation row jt of J (no
 * residuals to evaluate). A turn of the bearings is differenced. */
static void camera_derivative(const double *R, const double *tau, const double *o1,
                              const double *d1, const double *o2, const double *d2, int kind,
                              int at1, int at2, const double jt[3], double (*turns)[9],
                              double dr[3])
{
    int k, s;
    if (kind == 0) {
        for (k = 0; k < 3; k++)
            dr[k] = (at1 ? jt[0] * R[k] + jt[1] * R[3 + k] + jt[2] * R[6 + k] : 0.0) -
                    (at2 ? jt[k] : 0.0);
        return;
    }
    for (k = 0; k < 3; k++) {
        double r[2];
        for (s = 0; s < 2; s++) {
            double b1[3], b2[3];
            const double *q = turns[2 * k + s];
            memcpy(b1, d1, sizeof b1);
            memcpy(b2, d2, sizeof b2);
            if (at1)
                mat_vec(q, d1, b1);
            if (at2)
                mat_vec(q, d2, b2);
            r[s] = sampson_residual(R, tau, o1, b1, o2, b2);
        }
        dr[k] = (r[0] - r[1]) / (2.0 * H_ANG);
    }
}

/* B (6 x 3, row-major) += w J dr^T */
static void add_outer(double *b, double w, const double j[6], const double dr[3])
{
    int a, c;
    for (a = 0; a < 6; a++)
        for (c = 0; c < 3; c++)
            b[3 * a + c] += w * j[a] * dr[c];
}

int mcg_calibration_scale_std(int n, const double *o1, const double *d1, const double *o2,
                              const double *d2, const int *cam1, const int *cam2,
                              int n_cameras, const double *extrinsic_std, const double R[9],
                              const double t[3], const double *weights, int loss,
                              double loss_scale, double *rel_std, double cov[36],
                              double *work, size_t lwork)
{
    double c[3] = {0.0, 0.0, 0.0}, tau[3], rc[3], turns[6][9], rturn[6][9], h[36] = {0};
    double hinv[36], scale, h_t, var = 0.0, u[3];
    int i, k, a, b, cam;
    if (!o1 || !d1 || !o2 || !d2 || !cam1 || !cam2 || !extrinsic_std || !R || !t || !rel_std ||
        !cov || (!work && lwork))
        return MCG_EINVAL;
    if (n < 1 || (size_t)n > MAX_ROWS || n_cameras < 1 || n_cameras > MAX_CAL_CAMERAS)
        return MCG_EINVAL;
    if (loss < MCG_LOSS_NONE || loss > MCG_LOSS_SOFT_L1 ||
        (loss != MCG_LOSS_NONE && !(isfinite(loss_scale) && loss_scale > 0.0)))
        return MCG_EINVAL;
    if (!all_finite(R, 9) || !all_finite(t, 3) ||
        !all_finite(extrinsic_std, 2 * (size_t)n_cameras))
        return MCG_EINVAL;
    for (i = 0; i < 2 * n_cameras; i++)
        if (extrinsic_std[i] < 0.0)
            return MCG_EINVAL;
    for (i = 0; i < n; i++) {
        if (cam1[i] < 0 || cam1[i] >= n_cameras || cam2[i] < 0 || cam2[i] >= n_cameras)
            return MCG_EINVAL;
        if (weights && !(isfinite(weights[i]) && weights[i] >= 0.0))
            return MCG_EINVAL;
    }
    if (!all_finite(o1, 3 * (size_t)n) || !all_finite(o2, 3 * (size_t)n) ||
        !all_finite(d1, 3 * (size_t)n) || !all_finite(d2, 3 * (size_t)n))
        return MCG_EINVAL;
    if (lwork < mcg_calibration_std_work_size(n_cameras))
        return MCG_ENOMEM;

    /* the centroid of the origins (both times) and tau = t + R c - c */
    for (i = 0; i < n; i++)
        for (k = 0; k < 3; k++)
            c[k] += o1[3 * i + k];
    for (k = 0; k < 3; k++)
        c[k] /= n;
    {
        double c2[3] = {0.0, 0.0, 0.0};
        for (i = 0; i < n; i++)
            for (k = 0; k < 3; k++)
                c2[k] += o2[3 * i + k];
        for (k = 0; k < 3; k++)
            c[k] = 0.5 * (c[k] + c2[k] / n);
    }
    mat_vec(R, c, rc);
    for (k = 0; k < 3; k++)
        tau[k] = t[k] + rc[k] - c[k];
    scale = sqrt(dot3(tau, tau));
    if (!(scale > 1e-9))
        scale = 1e-9;
    h_t = H_REL * scale;
    for (k = 0; k < 3; k++) {
        axis_turn(k, H_ANG, turns[2 * k]);
        axis_turn(k, -H_ANG, turns[2 * k + 1]);
        mul33(turns[2 * k], R, rturn[2 * k]);
        mul33(turns[2 * k + 1], R, rturn[2 * k + 1]);
    }
    memset(work, 0, 36 * (size_t)n_cameras * sizeof *work);

    /* one pass: J^T W J and, per camera and kind, J^T W dr/dp */
    for (i = 0; i < n; i++) {
        double p1[3], p2[3], q1[3], q2[3], j[6], r0, w, n1, n2;
        for (k = 0; k < 3; k++) {
            p1[k] = o1[3 * i + k] - c[k];
            p2[k] = o2[3 * i + k] - c[k];
        }
        n1 = sqrt(dot3(d1 + 3 * i, d1 + 3 * i));
        n2 = sqrt(dot3(d2 + 3 * i, d2 + 3 * i));
        for (k = 0; k < 3; k++) {
            q1[k] = d1[3 * i + k] / n1;
            q2[k] = d2[3 * i + k] / n2;
        }
        r0 = sampson_residual(R, tau, p1, q1, p2, q2);
        if (!isfinite(r0))
            return MCG_EINVAL; /* a zero direction, or magnitudes that overflow */
        w = (weights ? weights[i] : 1.0) * loss_weight(loss, r0, loss_scale);
        for (k = 0; k < 3; k++) {
            double tp[3], tm[3];
            memcpy(tp, tau, sizeof tp);
            memcpy(tm, tau, sizeof tm);
            tp[k] += h_t;
            tm[k] -= h_t;
            j[k] = (sampson_residual(rturn[2 * k], tau, p1, q1, p2, q2) -
                    sampson_residual(rturn[2 * k + 1], tau, p1, q1, p2, q2)) / (2.0 * H_ANG);
            j[3 + k] = (sampson_residual(R, tp, p1, q1, p2, q2) -
                        sampson_residual(R, tm, p1, q1, p2, q2)) / (2.0 * h_t);
        }
        for (a = 0; a < 6; a++)
            for (b = 0; b < 6; b++)
                h[6 * a + b] += w * j[a] * j[b];
        if (w == 0.0)
            continue;
        for (cam = 0; cam < 2; cam++) {
            int id = cam == 0 ? cam1[i] : cam2[i], kind;
            int at1 = cam1[i] == id, at2 = cam2[i] == id;
            if (cam == 1 && at1)
                break; /* an intra-camera pair: both ends done above */
            for (kind = 0; kind < 2; kind++) {
                double dr[3];
                if (extrinsic_std[2 * id + kind] == 0.0)
                    continue;
                camera_derivative(R, tau, p1, q1, p2, q2, kind, at1, at2, j + 3, turns, dr);
                add_outer(work + 36 * (size_t)id + 18 * kind, w, j, dr);
            }
        }
    }
    if (!all_finite(h, 36))
        return MCG_ENUMERIC;

    /* (J^T W J)^-1, column by column; a singular matrix: the motion is not
     * determined by the rays, the std is infinite */
    for (k = 0; k < 6; k++) {
        double e[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0}, x[6];
        e[k] = 1.0;
        if (mcg_spd_solve(6, h, e, x) != MCG_OK) {
            for (i = 0; i < 36; i++)
                cov[i] = HUGE_VAL;
            *rel_std = HUGE_VAL;
            return MCG_OK;
        }
        for (i = 0; i < 6; i++)
            hinv[6 * i + k] = x[i];
    }
    memset(cov, 0, 36 * sizeof *cov);
    for (cam = 0; cam < n_cameras; cam++) {
        int kind;
        for (kind = 0; kind < 2; kind++) {
            const double *bm = work + 36 * (size_t)cam + 18 * kind;
            double g[18], s2 = extrinsic_std[2 * cam + kind];
            if (s2 == 0.0)
                continue;
            s2 *= s2;
            for (a = 0; a < 6; a++) /* G = -H^-1 B */
                for (k = 0; k < 3; k++) {
                    double acc = 0.0;
                    for (b = 0; b < 6; b++)
                        acc += hinv[6 * a + b] * bm[3 * b + k];
                    g[3 * a + k] = -acc;
                }
            for (a = 0; a < 6; a++)
                for (b = 0; b < 6; b++)
                    cov[6 * a + b] += s2 * (g[3 * a] * g[3 * b] + g[3 * a + 1] * g[3 * b + 1] +
                                            g[3 * a + 2] * g[3 * b + 2]);
        }
    }
    for (k = 0; k < 3; k++)
        u[k] = tau[k] / scale;
    for (a = 0; a < 3; a++)
        for (b = 0; b < 3; b++)
            var += u[a] * cov[6 * (3 + a) + 3 + b] * u[b];
    *rel_std = sqrt(var > 0.0 ? var : 0.0) / scale;
    if (!isfinite(*rel_std) || !all_finite(cov, 36))
        return MCG_ENUMERIC;
    return MCG_OK;
}
