/*
 * refine_internal.h -- what the parts of the refinement share (csrc/refine.c,
 * the Levenberg-Marquardt driver of mcg_refine_motion; refine_eval.c, the
 * residuals and one evaluation of the robust cost and its normal equations):
 * the sums of an evaluation, the robust loss, and the functions one part calls
 * in the other. Not installed; not part of the public API.
 */
#ifndef MCGEOM_REFINE_INTERNAL_H
#define MCGEOM_REFINE_INTERNAL_H

#include "mcgeom.h"
#include "internal.h"


#define MAX_RAYS (1 << 26)


/* ------------------------------------------------------ one evaluation */

typedef struct {
    double cost;   /* sum w rho(r^2) */
    double h[36];  /* J^T W J, W = w rho'(r^2) */
    double g[6];   /* J^T W r */
    double sw;     /* sum of the user weights */
    double swr2;   /* sum w r^2 */
    double som;    /* sum of the IRLS weights omega = w rho'(r^2) */
    double somr2;  /* sum omega r^2 */
    int n_used;    /* w > 0 and a non-zero Jacobian row */
    int bad;       /* some input non-finite, zero direction or overflow */
} accum;

typedef struct {
    int loss;
    double s, s2, inv_s2; /* loss scale, its square and inverse square */
} lossfn;

/* refine_eval.c */
void refine_evaluate(int n, const double *o1, const double *d1, const double *o2,
                     const double *d2, const double *wts, const lossfn *l,
                     const double r[9], const double t[3], accum *acc);

#endif /* MCGEOM_REFINE_INTERNAL_H */
