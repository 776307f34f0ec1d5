/*
 * linear17_internal.h -- what the parts of linear17 share (csrc/linear17.c,
 * the entry point mcg_linear17, and linear17_gram.c, linear17_alternation.c,
 * linear17_sampson.c): the sizes of the unknowns, the rays in the normalised
 * frame, the quadratic in t, small helpers, and the functions one part calls
 * in another. Not installed; not part of the public API.
 */
#ifndef MCGEOM_LINEAR17_INTERNAL_H
#define MCGEOM_LINEAR17_INTERNAL_H

#include "mcgeom.h"
#include "internal.h"

#include <math.h>
#include <string.h>

/* The loops over the rays (the accumulation of M, the Sampson passes) are
 * written in lanes of 4 doubles for the vectoriser and carry MCG_AVX2_CLONE
 * (internal.h: AVX2's 4-double registers hold a whole lane block, the same
 * bits on every CPU; issue 22: 8 % of the instructions of the public call
 * at 100 rays). */
#define NX 18
#define NXP 20 /* NX rounded up to a multiple of 4 */
#define DIR2_MIN 1e-100 /* smallest squared length of a direction (|d| >= 1e-50) */

typedef struct {
    double t[3];        /* minimiser (metric mode) or unit direction */
    double cost;        /* x^T M x at (R, t) */
    double cond;        /* lambda_min(H) / lambda_max(H) */
    double h[3], hv[9]; /* eigen-decomposition of H */
    double hm[9], g[3], c0; /* the quadratic t^T H t + 2 g^T t + c0 */
} tsolve;

/* The rays and their normalisation (Algorithm 2 step 1), for the passes over
 * the rays after the linear step. */
typedef struct {
    int n;
    const double *o1, *d1, *o2, *d2, *origin;
    double scale;
} raydata;

/* y = m x (n x n, row-major), and x^T m x for the 18 x 18 M */
static inline void matvec(int n, const double *m, const double *x, double *y)
{
    int i, j;
    for (i = 0; i < n; i++) {
        double acc = 0.0;
        for (j = 0; j < n; j++)
            acc += m[i * n + j] * x[j];
        y[i] = acc;
    }
}

static inline double quad18(const double *m, const double *x)
{
    double y[NX], acc = 0.0;
    int i;
    matvec(NX, m, x, y);
    for (i = 0; i < NX; i++)
        acc += x[i] * y[i];
    return acc;
}

/* x = (vec([t]x R), vec(R)): the unknown vector of eq. 8.18 for a motion. */
static inline void motion_vector(const double r[9], const double t[3], double x[NX])
{
    skew_times(t, r, x);
    memcpy(x + 9, r, 9 * sizeof(double));
}

/* the 9 x 9 block of M at row r0, column c0 (M_EE, M_ER, M_RR) */
static inline void block(const double *m, int r0, int c0, double *out)
{
    int i, j;
    for (i = 0; i < 9; i++)
        for (j = 0; j < 9; j++)
            out[9 * i + j] = m[(r0 + i) * NX + c0 + j];
}

/* linear17_gram.c: M, the camera kind, the linear step, the candidates */
int linear17_accumulate(int n, const double *o1, const double *d1,
                        const double *o2, const double *d2,
                        double *m, double origin[3], double *scale);
int linear17_classify(const double *wr, const double *vr, double rtol,
                      double tr_m, int *nullity);
int linear17_linear_step(const double *m, int gc_case,
                         const double *wr, const double *vr, double pinv_rtol,
                         double rtol, double tr_m, double e[9], double r[9],
                         mcg_linear17_result *res);
int linear17_rotation_candidates(const double e[9], const double r[9], int use_r,
                                 double cand[4][9], int *ncand);

/* linear17_alternation.c: t given R (eq. 8.15), R given t */
int linear17_solve_t(const double *m, const double r[9], int unit_mode,
                     const double tprev[3], int want_eig, tsolve *out);
int linear17_step_r(const double *m, double r[9], const double t[3], double *cost);

/* linear17_sampson.c: the geometric refinement */
double linear17_sampson_pass(const raydata *rd, const double r[9], const double t[3],
                             double h[36], double g[6]);
int linear17_geometric_refine(const raydata *rd, const mcg_linear17_options *o,
                              double r[9], double t[3], double *cost, double h[36],
                              int *converged, double *cost0);
double linear17_geometric_rel_std(const double h[36], double cost, int n, const double t[3]);

#endif /* MCGEOM_LINEAR17_INTERNAL_H */
