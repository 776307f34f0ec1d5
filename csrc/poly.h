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

#endif /* MCGEOM_POLY_H */
