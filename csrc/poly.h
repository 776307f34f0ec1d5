/*
 * poly.h -- univariate polynomial helpers of libmcgeom (not installed, not
 * part of the public API), shared by the minimal solvers (essential5.c,
 * upright4.c), which each carried a copy. Coefficients by rising powers.
 * static inline: no exported symbol, and the same arithmetic, in the same
 * order, as the copies they replace.
 */
#ifndef MCGEOM_POLY_H
#define MCGEOM_POLY_H

/* c = a * b, a of degree na, b of degree nb; c has na + nb + 1 coefficients */
static inline void poly_mul(const double *a, int na, const double *b, int nb, double *c)
{
    int i, j;
    for (i = 0; i <= na + nb; ++i)
        c[i] = 0.0;
    for (i = 0; i <= na; ++i)
        for (j = 0; j <= nb; ++j)
            c[i + j] += a[i] * b[j];
}

/* p(x), p of degree n (Horner) */
static inline double poly_eval(const double *p, int n, double x)
{
    double v = p[n];
    int i;
    for (i = n - 1; i >= 0; --i)
        v = v * x + p[i];
    return v;
}

/* p(x) and q(x) for p of degree n >= 1 and q of degree n - 1 (p and its
 * derivative in a Newton step): the two Horner chains of poly_eval in one
 * loop, so that their latencies overlap; each value is rounded exactly as
 * poly_eval rounds it */
static inline void poly_eval2(const double *p, const double *q, int n, double x, double *pv,
                              double *qv)
{
    double v = p[n], w = q[n - 1];
    int i;
    for (i = n - 1; i >= 1; --i) {
        v = v * x + p[i];
        w = w * x + q[i - 1];
    }
    *pv = v * x + p[0];
    *qv = w;
}

#endif /* MCGEOM_POLY_H */
