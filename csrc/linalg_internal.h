/*
 * linalg_internal.h -- what linalg.c (QR, SVD, pseudo-inverse, Cholesky) and
 * linalg_eig.c (the symmetric eigen-solvers) share: the caps of their loops
 * and the exact power-of-two scaling of their inputs. Not installed.
 */
#ifndef MCGEOM_LINALG_INTERNAL_H
#define MCGEOM_LINALG_INTERNAL_H

#include <float.h>
#include <math.h>
#include <stddef.h>

/* Jacobi converges quadratically: a handful of sweeps in practice. The cap
 * only turns a pathological input into MCG_ENUMERIC instead of a hang. */
#define MAX_SWEEPS 60
#define SPD_MAX 64

/* Exponent e with max_abs * 2^-e in [0.5, 1) (0 for a zero array). Scaling
 * by a power of two is exact, and it keeps every sum of squares below away
 * from overflow and harmful underflow whatever the magnitude of the input. */
static inline int scale_exponent(double amax)
{
    int e = 0;
    if (amax > 0.0)
        (void)frexp(amax, &e);
    return e;
}

/* 2^e where it is a normal double, else 0 (then mul_pow2 calls ldexp). */
static inline double pow2_or_zero(int e)
{
    return (e >= DBL_MIN_EXP - 1 && e <= DBL_MAX_EXP - 1) ? ldexp(1.0, e) : 0.0;
}

/* x 2^e, f = pow2_or_zero(e): where 2^e is a normal double one
 * multiplication by it, whose result is the exact x 2^e rounded once --
 * ldexp's result, so the same bits (subnormal, overflowing, inf and NaN
 * values included) -- instead of a libm call per value (issue 22: ldexp was
 * ~1.2k instructions of a public linear17 call at 100 rays). */
static inline double mul_pow2(double x, int e, double f)
{
    return f != 0.0 ? x * f : ldexp(x, e);
}

/* Exchange two rows of n doubles. */
static inline void swap_rows(double *x, double *y, size_t n)
{
    size_t i;
    for (i = 0; i < n; ++i) {
        double t = x[i];
        x[i] = y[i];
        y[i] = t;
    }
}

/* Selection sort of the nn keys, ascending (descending = 0) or descending,
 * the rows (nn doubles each) of a and, unless NULL, of b moved with them:
 * O(nn^2) comparisons, at most nn - 1 swaps, no index array. The SVD
 * (descending singular values, rows of w and vt) and the eigen-solvers
 * (ascending eigenvalues, rows of v) both finish with it. */
static inline void sort_with_rows(size_t nn, double *key, int descending, double *a, double *b)
{
    size_t i, j;
    for (i = 0; i + 1 < nn; ++i) {
        size_t best = i;
        for (j = i + 1; j < nn; ++j)
            if (descending ? key[j] > key[best] : key[j] < key[best])
                best = j;
        if (best != i) {
            double t = key[i];
            key[i] = key[best];
            key[best] = t;
            swap_rows(a + i * nn, a + best * nn, nn);
            if (b)
                swap_rows(b + i * nn, b + best * nn, nn);
        }
    }
}

#endif /* MCGEOM_LINALG_INTERNAL_H */
