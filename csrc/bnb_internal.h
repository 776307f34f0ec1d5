/*
 * bnb_internal.h -- what the parts of the branch and bound share (csrc/bnb.c,
 * the entry point mcg_bnb_linf, its search and certificate; bnb_feasible.c,
 * the feasibility test; bnb_polish.c, the incumbent's polish): the constants
 * of the method, the state of a call (bnb_ctx) and the functions one part
 * calls in another. Not installed; not part of the public API.
 */
#ifndef MCGEOM_BNB_INTERNAL_H
#define MCGEOM_BNB_INTERNAL_H

#include "mcgeom.h"
#include "internal.h"

#define SQRT3 1.7320508075688772
#define PI 3.14159265358979323846
#define EPS_MAX 1.5         /* a bound beyond this (rad) constrains nothing */
#define SUBSET 32           /* widest-angle correspondences tested first: a
                               subset's infeasibility proves the group's, and
                               most blocks of a search are discarded by one;
                               measured on 300 KITTI raw inliers (two groups
                               of ~150, gap 1e-4): 8 -> 32 took the 2-variable
                               LPs from 190k to 100k and the search from 1.05
                               to 0.84 s CPU (16: 0.96, 64: 0.88 s) */
#define ROWS_PER 4          /* rows of a correspondence: its wedge and its cap */
#define CAP_MAX 1.5         /* caps only of radius below this (rad, ~75 deg) */
#define BLOCK_DOUBLES 5     /* centre (3), half-side, lower bound */
#define WS_CAP 48           /* rows of a working set before a full LP */
#define WS_ADD 4            /* most violated rows added per round */
#define BISECT_MAX 200      /* bisection steps: (0, 1.5] to tol >= 1e-15
                               takes <= 51; the cap only guards the loop */
/* A test the LP backend could not decide (MCG_ENUMERIC: its point failed the
 * verification, seen only at bounds ~1e-10 rad on noise-free data): taken as
 * feasible where a lower bound is at stake (no block is wrongly discarded)
 * and as infeasible where an upper bound is (no error is wrongly claimed). */
#define UNDECIDED 2

typedef struct {
    int n, G;
    double *a1, *a2;        /* origins, centred and scaled (work) */
    double *u1, *u2;        /* unit bearings d1, d2 (work) */
    const int *order;       /* by group, then alpha descending (work) */
    const int *gstart;      /* G + 1 offsets into order (work) */
    double *a1n;            /* |a1_i| */
    double *A3, *b3;        /* <= 4n rows of the 3-variable LP (ROWS_PER) */
    double *A2, *b2;        /* rows of one 2-variable LP (2 n_g) */
    double *zsum;           /* 3 G: sum of unit wedge centres per group */
    int *grows;             /* rows of each group in A3 (count) */
    int *gfirst;            /* first row of each group in A3 */
    double *lpw;
    size_t lplen;
    const mcg_lp_backend *lp;
    int preemptive;
    int working_sets;       /* 0: every LP on all its rows, no hints */
    long lp2, lp3, hints, undecided;
    double floor;           /* certified lower bound of f (for the polish) */
    double apex[3];         /* apex of the group being built */
    double *gapex;          /* 3 G: each group's apex */
    double t_hint[3];       /* the last feasible translation */
    int have_hint;
    /* working sets of the constraint-generation LPs (see lp_working_set) */
    int *rid;               /* 4n: stable id (4 i + k) of each row of A3 */
    int *where;             /* 4n: row of an id in the current view */
    int *ws;                /* (G + 1) x WS_CAP ids: slot 0 the 3-variable
                               LP, slot 1 + g group g's 2-variable LP */
    int *nws;               /* G + 1 sizes */
    double *Asub, *bsub;    /* WS_CAP rows */
} bnb_ctx;

/* bnb_feasible.c: the feasibility test, FindMinError */
int bnb_feasible(bnb_ctx *c, const double R[9], double eps, double s, double t[3]);
int bnb_find_min_error(bnb_ctx *c, const double R[9], double s, double lo,
                       double *hi, double t_hi[3], double tol, int lower);

/* bnb_polish.c: the incumbent's polish */
int bnb_polish_slp(bnb_ctx *c, const mcg_bnb_options *o, mcg_bnb_result *res,
                   long *tests, double deadline);

/* bnb.c: the search */
double bnb_now_seconds(void);

#endif /* MCGEOM_BNB_INTERNAL_H */
