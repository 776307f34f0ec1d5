/*
 * sampson.h -- the Sampson angular residual of one ray pair (thesis eq. 8.15
 * applied to the generalized epipolar constraint, eq. 8.16), shared by the
 * kernels that evaluate it pair by pair: refine.c (mcg_gec_residuals, the
 * refinement's rows) and calibration_std.c (the derivatives of the
 * calibration error's propagation). Not installed.
 */
#ifndef MCGEOM_SAMPSON_H
#define MCGEOM_SAMPSON_H

#include <float.h>
#include <math.h>

#define SAMPSON_HALF_PI 1.5707963267948966
#define SAMPSON_INV_HALF_PI2 0.40528473456935109 /* (2 / pi)^2 */
/* smallest accepted squared length of a direction (|d| >= 1e-50): shorter
 * ones count as zero-length; keeps the products of the residual far from
 * underflow (overflow is detected) */
#define SAMPSON_DIR2_MIN 1e-100

/* The terms of one pair's Sampson angular residual, in the raw form of the
 * header comment of mcg_gec_residuals (thesis eq. 8.15 applied to the
 * generalized epipolar constraint, eq. 8.16): A = R d1, B = d2 (both
 * unnormalised), p = R o1, c = t + p - o2, Q = c x A, H = B x c,
 * E = B.Q, den = |B|^2 |Q|^2 + |A|^2 |H|^2 - 2 E^2 (|A|^2 = |d1|^2), and
 * the residual r = E / sqrt(m) with m = max(den, (2/pi)^2 E^2, DBL_MIN)
 * (the pi/2 cap). One definition for the residual pass and for the
 * residual + Jacobian rows of the refinement, so the two cannot drift
 * apart. Static inline and branch-free (selects only): the callers' loops
 * over the pairs vectorise. */
typedef struct {
    double a0, a1, a2;    /* A = R d1 */
    double p0, p1, p2;    /* p = R o1 */
    double c0, c1, c2;    /* c = t + p - o2 */
    double b0, b1, b2;    /* B = d2 */
    double q0, q1, q2;    /* Q = c x A */
    double h0, h1, h2;    /* H = B x c */
    double n1, n2;        /* |d1|^2, |d2|^2 */
    double e, dd;         /* E and den */
    double lo, m;         /* max((2/pi)^2 E^2, DBL_MIN) and max(den, lo) */
    double marker;        /* 0, or NaN for an invalid pair (see below) */
} sampson_terms;

static inline void sampson_pair(const double *rm, const double *tv, const double *o1,
                                const double *d1, const double *o2, const double *d2,
                                sampson_terms *s)
{
    double ee, cap, x, mm;
    s->b0 = d2[0];
    s->b1 = d2[1];
    s->b2 = d2[2];
    s->n1 = d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2];
    s->n2 = s->b0 * s->b0 + s->b1 * s->b1 + s->b2 * s->b2;
    s->a0 = rm[0] * d1[0] + rm[1] * d1[1] + rm[2] * d1[2];
    s->a1 = rm[3] * d1[0] + rm[4] * d1[1] + rm[5] * d1[2];
    s->a2 = rm[6] * d1[0] + rm[7] * d1[1] + rm[8] * d1[2];
    s->p0 = rm[0] * o1[0] + rm[1] * o1[1] + rm[2] * o1[2];
    s->p1 = rm[3] * o1[0] + rm[4] * o1[1] + rm[5] * o1[2];
    s->p2 = rm[6] * o1[0] + rm[7] * o1[1] + rm[8] * o1[2];
    s->c0 = tv[0] + s->p0 - o2[0];
    s->c1 = tv[1] + s->p1 - o2[1];
    s->c2 = tv[2] + s->p2 - o2[2];
    s->q0 = s->c1 * s->a2 - s->c2 * s->a1;
    s->q1 = s->c2 * s->a0 - s->c0 * s->a2;
    s->q2 = s->c0 * s->a1 - s->c1 * s->a0;
    s->h0 = s->b1 * s->c2 - s->b2 * s->c1;
    s->h1 = s->b2 * s->c0 - s->b0 * s->c2;
    s->h2 = s->b0 * s->c1 - s->b1 * s->c0;
    s->e = s->b0 * s->q0 + s->b1 * s->q1 + s->b2 * s->q2;
    ee = s->e * s->e;
    s->dd = s->n2 * (s->q0 * s->q0 + s->q1 * s->q1 + s->q2 * s->q2) +
            s->n1 * (s->h0 * s->h0 + s->h1 * s->h1 + s->h2 * s->h2) - 2.0 * ee;
    cap = ee * SAMPSON_INV_HALF_PI2;
    s->lo = cap > DBL_MIN ? cap : DBL_MIN;
    s->m = s->dd > s->lo ? s->dd : s->lo;
    /* validation folded in as a NaN marker, which keeps the loops
     * branch-free and vectorisable: n1, n2 >= SAMPSON_DIR2_MIN rules out zero
     * directions, and 0 * x is NaN iff x is not finite, where a NaN/inf
     * in any input or an overflow makes x = n1 + n2 + dd NaN or inf.
     * (Vectorised only with -fno-math-errno, see meson.build.) */
    x = s->n1 + s->n2 + s->dd;
    mm = s->n1 < s->n2 ? s->n1 : s->n2;
    s->marker = 0.0 * x + (mm >= SAMPSON_DIR2_MIN ? 0.0 : NAN);
}

/* The residual of one pair (radians), as mcg_gec_residuals: NaN for an
 * invalid pair (zero direction, NaN/inf input, overflow). */
static inline double sampson_residual(const double *rm, const double *tv, const double *o1,
                                      const double *d1, const double *o2, const double *d2)
{
    sampson_terms s;
    sampson_pair(rm, tv, o1, d1, o2, d2, &s);
    return s.e / sqrt(s.m) + s.marker;
}

#endif
