/* Input checks, scaling and the final verification shared by the LP
 * feasibility backends (lp_native.c, lp_glpk.c): both decide the same
 * question, {x : a_k . x >= b_k}, with the same conventions (row norms, the
 * scale S, zero rows), so these live in one place. */
#ifndef MCGEOM_LP_INTERNAL_H
#define MCGEOM_LP_INTERNAL_H

#include "mcgeom.h"
#include "internal.h"

#include <math.h>

#define LP_MAX_ROWS ((int)1 << 20)
#define ZERO_ROW 1e-100   /* row norm at or below: the constraint 0 >= b_k */
#define VALUE_MAX 1e150

/* |a_k| of row k of the m x dim matrix A */
static inline double lp_row_norm(int dim, const double *A, int k)
{
    double n2 = 0.0;
    int i;
    for (i = 0; i < dim; ++i)
        n2 += A[k * dim + i] * A[k * dim + i];
    return sqrt(n2);
}

/* Validates A (m x dim) and b (finite, below VALUE_MAX), decides zero rows
 * and returns the scale S = max(1, max_k |b_k| / |a_k|) in *S. MCG_EINVAL for
 * bad values, MCG_EINFEASIBLE for a zero row with b_k > 0, else MCG_OK. */
static inline int lp_check_rows(int dim, int m, const double *A, const double *b,
                                double *S)
{
    int k;
    *S = 1.0;
    for (k = 0; k < m * dim; ++k)
        if (!isfinite(A[k]) || fabs(A[k]) > VALUE_MAX)
            return MCG_EINVAL;
    for (k = 0; k < m; ++k)
        if (!isfinite(b[k]) || fabs(b[k]) > VALUE_MAX)
            return MCG_EINVAL;
    for (k = 0; k < m; ++k) {
        double n = lp_row_norm(dim, A, k);
        if (!(n > ZERO_ROW)) {
            if (b[k] > 0.0)
                return MCG_EINFEASIBLE;
            continue;
        }
        if (fabs(b[k]) / n > *S)
            *S = fabs(b[k]) / n;
    }
    return MCG_OK;
}

/* A feasible answer checked against the original rows: every
 * a_k . x >= b_k - 2 tol |a_k|. MCG_ENUMERIC if not. */
static inline int lp_verify_point(int dim, int m, const double *A, const double *b,
                                  const double *x, double tol)
{
    int k, i;
    for (k = 0; k < m; ++k) {
        double s = 0.0;
        for (i = 0; i < dim; ++i)
            s += A[k * dim + i] * x[i];
        if (s < b[k] - 2.0 * tol * lp_row_norm(dim, A, k) || !isfinite(s))
            return MCG_ENUMERIC;
    }
    return MCG_OK;
}

#endif /* MCGEOM_LP_INTERNAL_H */
