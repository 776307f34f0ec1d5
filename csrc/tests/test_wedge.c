/*
 * test_wedge.c -- plain-C checks of csrc/wedge.c (bitangent-plane normals,
 * thesis eqs. 10.9-10.12): conservativeness by sampling directions inside
 * both error cones and the translations they imply, tangency of each plane
 * to both cones, the closed form of eq. 10.10 for |y| = sin beta, exclusion
 * of negative-depth directions, the degenerate cases and invalid arguments.
 * Exit status 0 iff every check passes.
 */
#include "mcgeom.h"

#define TEST_SEED 0x3ed9e5eedULL
#include "testutil.h"

#include <math.h>
#include <stdio.h>

static double dot(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void unit(double *a)
{
    double n = sqrt(dot(a, a));
    a[0] /= n;
    a[1] /= n;
    a[2] /= n;
}

static void cross(const double *a, const double *b, double *c)
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

/* a unit vector at angle <= e from the unit axis ax (on the boundary if
 * boundary != 0) */
static void in_cone(const double *ax, double e, int boundary, double *u)
{
    double p[3], q[3], r[3], th, ph;
    int i;
    randn(r, 3);
    cross(ax, r, p);
    unit(p);
    cross(ax, p, q);
    th = boundary ? e : e * sqrt(urand());
    ph = 6.283185307179586 * urand();
    for (i = 0; i < 3; ++i)
        u[i] = cos(th) * ax[i] + sin(th) * (cos(ph) * p[i] + sin(ph) * q[i]);
}

static double angle(const double *a, const double *b)
{
    double c[3];
    cross(a, b, c);
    return atan2(sqrt(dot(c, c)), dot(a, b));
}

int main(void)
{
    double v[3], vp[3], n1[3], n2[3], u[3], up[3], t[3];
    double worst = 0.0, worst_tan = 0.0, worst_beta = 0.0;
    int trial, k, i, st, n_ok = 0, n_degen = 0, bad_status = 0, wrong = 0;
    int neg_ok = 1, trials = scaled(3000);

    for (trial = 0; trial < trials; ++trial) {
        double eps = 0.3 * urand() * urand(), epsp = 0.3 * urand() * urand();
        double al, sb2, y2, m1, m2;
        randn(v, 3);
        randn(vp, 3);
        unit(v);
        unit(vp);
        st = mcg_wedge_normals(v, vp, eps, epsp, n1, n2);
        al = angle(v, vp);
        if (st == MCG_EDEGENERATE) {
            ++n_degen;
            if (al > eps + epsp + 1e-9 && al < 3.141592653589793 - fabs(eps - epsp) - 1e-9)
                ++wrong; /* a wedge exists but was refused */
            continue;
        }
        if (st != MCG_OK) {
            ++bad_status;
            continue;
        }
        ++n_ok;
        if (al <= eps + epsp)
            ++wrong; /* cones overlap: no valid wedge */
        /* eq. 10.10: the in-plane part of n has length sin beta */
        sb2 = (sin(eps) * sin(eps) + 2 * sin(eps) * sin(epsp) * cos(al) +
               sin(epsp) * sin(epsp)) / (sin(al) * sin(al));
        y2 = 0.25 * ((n1[0] + n2[0]) * (n1[0] + n2[0]) +
                     (n1[1] + n2[1]) * (n1[1] + n2[1]) +
                     (n1[2] + n2[2]) * (n1[2] + n2[2]));
        if (fabs(y2 - sb2) > worst_beta)
            worst_beta = fabs(y2 - sb2);
        /* tangency: min over each cone boundary of n.u is 0 */
        m1 = 1.0;
        m2 = 1.0;
        for (k = 0; k < scaled(2000); ++k) {
            double mv, a1, a2, nv[3] = {-v[0], -v[1], -v[2]};
            in_cone(vp, epsp, 1, up);
            in_cone(nv, eps, 1, u);
            a1 = dot(n1, up) < dot(n1, u) ? dot(n1, up) : dot(n1, u);
            a2 = dot(n2, up) < dot(n2, u) ? dot(n2, up) : dot(n2, u);
            mv = a1 < a2 ? a1 : a2;
            if (mv < m1)
                m1 = mv;
            (void)m2;
        }
        if (fabs(m1) > worst_tan && m1 > 0)
            worst_tan = m1;
        /* conservativeness: translations implied by rays in the cones */
        for (k = 0; k < 200; ++k) {
            double l = exp(8.0 * (urand() - 0.5)), lp = 1.0, e1, e2;
            in_cone(v, eps, k % 2, u);
            in_cone(vp, epsp, k % 3 == 0, up);
            if (k % 10 == 0) {
                l = 0.0; /* the limits of the sector */
            } else if (k % 10 == 1) {
                lp = 0.0;
            }
            for (i = 0; i < 3; ++i)
                t[i] = lp * up[i] - l * u[i];
            unit(t);
            e1 = dot(n1, t);
            e2 = dot(n2, t);
            if (-e1 > worst)
                worst = -e1;
            if (-e2 > worst)
                worst = -e2;
        }
        /* a point behind a camera: t = +v (lambda < 0), well inside the cone
         * around v, is excluded */
        in_cone(v, 0.5 * eps, 0, u);
        if (!(dot(n1, u) < 0 || dot(n2, u) < 0))
            neg_ok = 0;
    }
    printf("wedge: %d ok, %d degenerate\n", n_ok, n_degen);
    check(bad_status == 0 && n_ok > trials / 3, "random cones: status OK or DEGENERATE",
          (double)bad_status, 0);
    check(wrong == 0, "DEGENERATE exactly when the cones overlap/nest",
          (double)wrong, 0);
    check(worst <= 1e-12, "conservative: max violation by implied directions",
          worst, 1e-12);
    check(worst_tan <= 1e-3, "tight: each plane touches the cones (min n.u)",
          worst_tan, 1e-3);
    check(worst_beta <= 1e-9, "|y|^2 = sin^2 beta of eq. 10.10", worst_beta,
          1e-9);
    check(neg_ok, "negative depth (t along +v) excluded", 0, 0);

    /* degenerate cases */
    {
        double a[3] = {0, 0, 1}, b[3] = {0, 0, 2}, c[3] = {0, 0, -1};
        double d[3] = {0, 0.05, 1}, e[3] = {0, 0.5, 1}, z[3] = {0, 0, 0};
        double nan3[3] = {NAN, 0, 1};
        check_status(mcg_wedge_normals(a, b, 0.01, 0.01, n1, n2),
                     MCG_EDEGENERATE, "v parallel to v'");
        check_status(mcg_wedge_normals(a, c, 0.01, 0.01, n1, n2),
                     MCG_EDEGENERATE, "v anti-parallel to v'");
        check_status(mcg_wedge_normals(a, b, 0.0, 0.0, n1, n2),
                     MCG_EDEGENERATE, "v parallel to v', eps = 0");
        check_status(mcg_wedge_normals(a, d, 0.03, 0.03, n1, n2),
                     MCG_EDEGENERATE, "overlapping cones");
        check_status(mcg_wedge_normals(a, e, 0.03, 0.03, n1, n2), MCG_OK,
                     "separate cones");
        check_status(mcg_wedge_normals(a, e, 0.0, 0.0, n1, n2), MCG_OK,
                     "eps = 0: the epipolar plane");
        check(fabs(dot(n1, n2) + 1.0) < 1e-9, "eps = 0: n1 = -n2",
              fabs(dot(n1, n2) + 1.0), 1e-9);
        check_status(mcg_wedge_normals(NULL, e, 0.1, 0.1, n1, n2), MCG_EINVAL,
                     "NULL v");
        check_status(mcg_wedge_normals(a, e, 0.1, 0.1, NULL, n2), MCG_EINVAL,
                     "NULL n1");
        check_status(mcg_wedge_normals(z, e, 0.1, 0.1, n1, n2), MCG_EINVAL,
                     "zero v");
        check_status(mcg_wedge_normals(nan3, e, 0.1, 0.1, n1, n2), MCG_EINVAL,
                     "NaN in v");
        check_status(mcg_wedge_normals(a, e, -0.1, 0.1, n1, n2), MCG_EINVAL,
                     "negative eps");
        check_status(mcg_wedge_normals(a, e, 0.1, 1.6, n1, n2), MCG_EINVAL,
                     "eps' >= pi/2");
        check_status(mcg_wedge_normals(a, e, NAN, 0.1, n1, n2), MCG_EINVAL,
                     "NaN eps");
    }
    printf("%d checks, %d failed\n", n_checks, n_failed);
    return n_failed != 0;
}
