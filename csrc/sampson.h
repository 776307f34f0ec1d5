/*
 * sampson.h -- the Sampson angular residual of one ray pair (thesis eq. 8.15
 * applied to the generalized epipolar constraint, eq. 8.16), shared by the
 * kernels that evaluate it pair by pair: refine.c (mcg_gec_residuals, the
 * refinement's rows, sampson_jacobian) and calibration_std.c (the derivatives
 * of the calibration error's propagation). Not installed.
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

/* The residual of one pair and its row of the Jacobian, derived on the raw
 * form above (left perturbation R <- exp([dw]x) R, t <- t + dt): with
 * s = m^-1/2, r = E s, f1 = s (1 + 2 r^2) and f2 = r s^2 (both 0 on the
 * pi/2 cap, where r is constant),
 *     dr/dt = f1 A x B - f2 (2 |A|^2 |B|^2 c - |B|^2 (A.c) A - |A|^2 (B.c) B),
 *     dr/dw = p x dr/dt + f1 A x H - f3 Q,  f3 = f2 |B|^2 (A.c),
 * the last two terms being A x dr/dA. One definition for the refinement's
 * rows (refine.c) and the calibration error's derivatives
 * (calibration_std.c, which also uses f1, f2 and B.c). Branch-free. */
typedef struct {
    double r;          /* E s, without the invalid-pair marker */
    double on;         /* 1 on the Sampson branch, 0 on the cap */
    double f1, f2, bc; /* the factors above and B.c */
    double j[6];       /* dr/dw, dr/dt */
} sampson_row;

static inline void sampson_jacobian(const sampson_terms *p, sampson_row *w)
{
    double s, rr, f1, f2, f3, ac, bc, k0, k1, k2, v0, v1, v2, jt0, jt1, jt2, on;
    /* 1 on the Sampson branch (a select, not a branch: vectorisable) */
    on = p->dd > p->lo ? 1.0 : 0.0;
    s = 1.0 / sqrt(p->m);
    rr = p->e * s;
    f1 = on * s * (1.0 + 2.0 * rr * rr);
    f2 = on * rr * s * s;
    ac = p->a0 * p->c0 + p->a1 * p->c1 + p->a2 * p->c2;
    bc = p->b0 * p->c0 + p->b1 * p->c1 + p->b2 * p->c2;
    k0 = p->a1 * p->b2 - p->a2 * p->b1;
    k1 = p->a2 * p->b0 - p->a0 * p->b2;
    k2 = p->a0 * p->b1 - p->a1 * p->b0;
    v0 = 2.0 * p->n1 * p->n2 * p->c0 - p->n2 * ac * p->a0 - p->n1 * bc * p->b0;
    v1 = 2.0 * p->n1 * p->n2 * p->c1 - p->n2 * ac * p->a1 - p->n1 * bc * p->b1;
    v2 = 2.0 * p->n1 * p->n2 * p->c2 - p->n2 * ac * p->a2 - p->n1 * bc * p->b2;
    jt0 = f1 * k0 - f2 * v0;
    jt1 = f1 * k1 - f2 * v1;
    jt2 = f1 * k2 - f2 * v2;
    f3 = f2 * p->n2 * ac;
    w->r = rr;
    w->on = on;
    w->f1 = f1;
    w->f2 = f2;
    w->bc = bc;
    w->j[0] = p->p1 * jt2 - p->p2 * jt1 + f1 * (p->a1 * p->h2 - p->a2 * p->h1) - f3 * p->q0;
    w->j[1] = p->p2 * jt0 - p->p0 * jt2 + f1 * (p->a2 * p->h0 - p->a0 * p->h2) - f3 * p->q1;
    w->j[2] = p->p0 * jt1 - p->p1 * jt0 + f1 * (p->a0 * p->h1 - p->a1 * p->h0) - f3 * p->q2;
    w->j[3] = jt0;
    w->j[4] = jt1;
    w->j[5] = jt2;
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
