/*
 * internal.h -- helpers shared by the kernels of libmcgeom (not installed,
 * not part of the public API): the size limits every entry point enforces,
 * overflow-checked size arithmetic for workspace sizes, and the finiteness
 * test of the inputs.
 */
#ifndef MCGEOM_INTERNAL_H
#define MCGEOM_INTERNAL_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

/* Size limits. They keep every work-size computation far from overflow and
 * reject absurd sizes (usually a mix-up of arguments) up front. */
#define MAX_ROWS ((size_t)1 << 20)
#define MAX_COLS ((size_t)4096)

/* a * b, clearing *ok on overflow */
static inline size_t mul_sz(size_t a, size_t b, int *ok)
{
    if (a != 0 && b > SIZE_MAX / a) {
        *ok = 0;
        return 0;
    }
    return a * b;
}

/* a + b, clearing *ok on overflow */
static inline size_t add_sz(size_t a, size_t b, int *ok)
{
    if (b > SIZE_MAX - a) {
        *ok = 0;
        return 0;
    }
    return a + b;
}

static inline size_t max_sz(size_t a, size_t b) { return a > b ? a : b; }
static inline size_t min_sz(size_t a, size_t b) { return a < b ? a : b; }

/* 1 if none of the n values is NaN or +-inf */
static inline int all_finite(const double *x, size_t n)
{
    size_t i;
    for (i = 0; i < n; ++i)
        if (!isfinite(x[i]))
            return 0;
    return 1;
}

#endif /* MCGEOM_INTERNAL_H */
