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
 * J and the derivatives of a camera's turn are analytic. The residual is a
 * function r(A, B, c) of A = R d1, B = d2 and c = tau + R o1 - o2 (sampson.h),
 * so every derivative needed is one of three (left increments: a rotation
 * by the small vector phi moves a vector v by phi x v):
 *   dr/dc            the translation row of J;
 *   A x dr/dA        the bearings' turn at time 1 seen in the rig2 frame, and
 *                    with R (o1) x dr/dc the rotation row of J;
 *   B x dr/dB        the bearings' turn at time 2.
 * dr/dc and dr/dw are the refinement's row (sampson.h, sampson_jacobian),
 * and A x dr/dA = dr/dw - (R o1) x dr/dc; B x dr/dB follows the same way:
 * with E = B.Q, Q = c x A, H = B x c and den = |B|^2|Q|^2 + |A|^2|H|^2 - 2E^2,
 * dr/dB = f1 Q - f2 (|Q|^2 B + |A|^2 c x H), f1 = s (1 + 2 r^2), f2 = r s^2,
 * s = den^-1/2, so B x dr/dB = f1 B x Q + f2 |A|^2 (B.c) H (B.H = 0). On the
 * pi/2 cap r is constant and every derivative 0. A camera turned by phi about
 * its centre turns its bearings d1 by phi in the rig1 frame, which is R phi
 * in the rig2 frame of A: dr/dphi = R^T (A x dr/dA); at time 2, B x dr/dB.
 * A camera's centre enters only through the translation term, so its
 * derivatives come from J's translation columns. (Until session 27 these
 * were central differences, 13-25 residuals per pair: 4.4 ms of a 20 ms
 * KITTI estimate.) One pass over the pairs: each pair's J
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

size_t mcg_calibration_std_work_size(int n_cameras)
{
    if (n_cameras < 1 || n_cameras > MAX_CAL_CAMERAS)
        return 0;
    return 36 * (size_t)n_cameras; /* per camera: J^T W dr/dp, 6 x 3 per kind */
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

/* One pair's residual r (radians; NaN for an invalid pair) and its
 * derivatives (see the header): j the row of J (dr/dw, dr/dtau), turn1 and
 * turn2 dr/dphi for a turn of the bearings by phi (rig frame) at time 1 and
 * at time 2. o1, o2: origins relative to the centroid; d1, d2 unit. */
static double pair_derivatives(const double R[9], const double tau[3], const double o1[3],
                               const double d1[3], const double o2[3], const double d2[3],
                               double j[6], double turn1[3], double turn2[3])
{
    sampson_terms p;
    sampson_row w;
    double pv[3], pj[3], ja[3];
    int k;
    sampson_pair(R, tau, o1, d1, o2, d2, &p);
    sampson_jacobian(&p, &w);
    memcpy(j, w.j, sizeof w.j);
    /* A x dr/dA = dr/dw - (R o1) x dr/dt */
    pv[0] = p.p0;
    pv[1] = p.p1;
    pv[2] = p.p2;
    cross3(pv, j + 3, pj);
    for (k = 0; k < 3; k++)
        ja[k] = j[k] - pj[k];
    /* a turn at time 1: R^T (A x dr/dA); at time 2: B x dr/dB */
    for (k = 0; k < 3; k++)
        turn1[k] = R[k] * ja[0] + R[3 + k] * ja[1] + R[6 + k] * ja[2];
    turn2[0] = w.f1 * (p.b1 * p.q2 - p.b2 * p.q1) + w.f2 * p.n1 * w.bc * p.h0;
    turn2[1] = w.f1 * (p.b2 * p.q0 - p.b0 * p.q2) + w.f2 * p.n1 * w.bc * p.h1;
    turn2[2] = w.f1 * (p.b0 * p.q1 - p.b1 * p.q0) + w.f2 * p.n1 * w.bc * p.h2;
    return w.r + p.marker;
}

/* d r / d p of one pair for the camera's perturbations of one kind (0: its
 * centre moves along each axis, 1: it turns about each axis), applied at
 * time 1 when at1, at time 2 when at2; dr[3] per axis. A centre enters the
 * residual only through c = tau + R o1 - o2 (sampson.h), so moving o1 by
 * e_k is moving tau by R e_k and moving o2 by e_k is moving tau by -e_k:
 * the position derivatives are the pair's translation row jt of J. */
static void camera_derivative(const double *R, int kind, int at1, int at2, const double jt[3],
                              const double turn1[3], const double turn2[3], double dr[3])
{
    int k;
    for (k = 0; k < 3; k++)
        dr[k] = kind == 0 ? (at1 ? jt[0] * R[k] + jt[1] * R[3 + k] + jt[2] * R[6 + k] : 0.0) -
                                (at2 ? jt[k] : 0.0)
                          : (at1 ? turn1[k] : 0.0) + (at2 ? turn2[k] : 0.0);
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
    double c[3] = {0.0, 0.0, 0.0}, tau[3], rc[3], h[36] = {0};
    double hinv[36], scale, var = 0.0, u[3];
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
    memset(work, 0, 36 * (size_t)n_cameras * sizeof *work);

    /* one pass: J^T W J and, per camera and kind, J^T W dr/dp */
    for (i = 0; i < n; i++) {
        double p1[3], p2[3], q1[3], q2[3], j[6], turn1[3], turn2[3], r0, w, n1, n2;
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
        r0 = pair_derivatives(R, tau, p1, q1, p2, q2, j, turn1, turn2);
        if (!isfinite(r0) || !all_finite(j, 6) || !all_finite(turn1, 3) || !all_finite(turn2, 3))
            return MCG_EINVAL; /* a zero direction, or magnitudes that overflow */
        w = (weights ? weights[i] : 1.0) * loss_weight(loss, r0, loss_scale);
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
                camera_derivative(R, kind, at1, at2, j + 3, turn1, turn2, dr);
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
