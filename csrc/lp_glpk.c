/*
 * lp_glpk.c -- the GLPK backend of the LP feasibility interface of mcgeom.h
 * (thesis ch. 10.3: the thesis solved its LPs with GLPK).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 * This file calls GLPK (GNU GPL v3 or later). It needs only glpk.h at build
 * time and loads libglpk at run time with dlopen (mcg_lp_glpk_load), so
 * libmcgeom, its Python extension and the native backend build, link and
 * work on machines without GLPK; a process that loads GLPK through this
 * backend forms a combined work covered by the GPL-3.0. Without glpk.h at
 * build time, lp_native.c provides stubs and the library stays MIT.
 *
 * Formulation: the same scaling as the native backend, so that the two
 * answer the same question: rows normalised, the box
 * |x_i| <= 1e6 S, S = max(1, max_k |b_k| / |A_k|). GLPK maximises the
 * margin d (A_k . x / |A_k| - d >= b_k / |A_k|, d <= S, primal simplex,
 * messages off), which is always feasible and so never asks GLPK's
 * tolerances to decide infeasibility; the set is feasible iff d* >= -1e-8 S
 * (floating-point simplex margins at highly degenerate vertices were seen
 * off by 3e-9 S, too close to the native backend's 1e-9 S), and then
 * A_k . x >= b_k - 2e-8 S |A_k| (verified). Answers therefore agree with the
 * native backend except for sets within ~1e-8 S of the feasibility
 * boundary. (glp_exact, the rational simplex, was tried for borderline
 * cases: GLPK 5.0 aborts on an internal assertion in some of them.) GLPK
 * allocates its problem object internally (malloc inside GLPK, freed before
 * returning); the caller's workspace is used for the index and value arrays
 * of the matrix. glp_term_out() sets GLPK's own per-thread environment flag.
 */
#define _POSIX_C_SOURCE 200809L /* dlopen / dlsym under -std=c99 */

#include "lp_internal.h"

#include <dlfcn.h>
#include <glpk.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The GLPK entry points we use, resolved from the loaded library; their
 * types are those of glpk.h (GLPK 4.x and 5.x share them). */
static struct {
    void (*term_out)(int);
    glp_prob *(*create_prob)(void);
    void (*set_obj_dir)(glp_prob *, int);
    int (*add_rows)(glp_prob *, int);
    int (*add_cols)(glp_prob *, int);
    void (*set_row_bnds)(glp_prob *, int, int, double, double);
    void (*set_col_bnds)(glp_prob *, int, int, double, double);
    void (*set_obj_coef)(glp_prob *, int, double);
    void (*load_matrix)(glp_prob *, int, const int[], const int[], const double[]);
    void (*init_smcp)(glp_smcp *);
    int (*simplex)(glp_prob *, const glp_smcp *);
    int (*get_status)(glp_prob *);
    double (*get_col_prim)(glp_prob *, int);
    void (*delete_prob)(glp_prob *);
} G;
static void *glpk_handle = NULL;

/* dlsym returns an object pointer; ISO C has no conversion to a function
 * pointer, so the bytes are copied (the POSIX-sanctioned idiom). */
static int resolve(void *h, const char *name, void *fp, size_t size)
{
    void *sym = dlsym(h, name);
    if (!sym)
        return 0;
    memcpy(fp, &sym, size);
    return 1;
}

int mcg_lp_glpk_load(const char *path)
{
    static const char *const defaults[] = {"libglpk.so.40", "libglpk.so"};
    void *h = NULL;
    size_t i;
    int ok;

    if (glpk_handle)
        return MCG_OK;
    if (!path)
        path = getenv("MCG_GLPK_LIBRARY");
    if (path && path[0])
        h = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    for (i = 0; !h && !(path && path[0]) && i < sizeof defaults / sizeof defaults[0]; ++i)
        h = dlopen(defaults[i], RTLD_NOW | RTLD_LOCAL);
    if (!h)
        return MCG_EUNAVAILABLE;
#define GET(field, name) resolve(h, name, &G.field, sizeof G.field)
    ok = GET(term_out, "glp_term_out") && GET(create_prob, "glp_create_prob") &&
         GET(set_obj_dir, "glp_set_obj_dir") && GET(add_rows, "glp_add_rows") &&
         GET(add_cols, "glp_add_cols") && GET(set_row_bnds, "glp_set_row_bnds") &&
         GET(set_col_bnds, "glp_set_col_bnds") &&
         GET(set_obj_coef, "glp_set_obj_coef") &&
         GET(load_matrix, "glp_load_matrix") && GET(init_smcp, "glp_init_smcp") &&
         GET(simplex, "glp_simplex") && GET(get_status, "glp_get_status") &&
         GET(get_col_prim, "glp_get_col_prim") && GET(delete_prob, "glp_delete_prob");
#undef GET
    if (!ok) {
        dlclose(h);
        memset(&G, 0, sizeof G);
        return MCG_EUNAVAILABLE;
    }
    glpk_handle = h;
    return MCG_OK;
}

int mcg_lp_glpk_available(void) { return glpk_handle != NULL; }

/* ia, ja (ints) and ar (doubles), each 1 + m * dim entries, in doubles */
size_t mcg_lp_glpk_work_size(int dim, int m)
{
    size_t n;
    if ((dim != 2 && dim != 3) || m < 0 || m > LP_MAX_ROWS)
        return 0;
    if (!glpk_handle)
        return 0;
    n = 1 + (size_t)m * (size_t)(dim + 1);
    /* two int arrays stored in doubles (sizeof(int) <= sizeof(double)) */
    return 3 * n;
}

int mcg_lp_glpk_feasible(int dim, int m, const double *A, const double *b,
                         double *x, double *work, size_t lwork)
{
    glp_prob *lp;
    glp_smcp parm;
    int *ia, *ja, k, i, ne = 0, st, status, ret;
    double *ar, S, big, tol;
    size_t n;

    if (!glpk_handle)
        return MCG_EUNAVAILABLE;
    if ((dim != 2 && dim != 3) || m < 0 || m > LP_MAX_ROWS || !x)
        return MCG_EINVAL;
    if (m > 0 && (!A || !b))
        return MCG_EINVAL;
    if (!work || lwork < mcg_lp_glpk_work_size(dim, m))
        return work ? MCG_ENOMEM : MCG_EINVAL;
    st = lp_check_rows(dim, m, A, b, &S); /* zero rows are decided here */
    if (st != MCG_OK)
        return st;
    big = 1e6 * S;
    tol = 1e-8 * S; /* GLPK's threshold, see the file comment */
    n = 1 + (size_t)m * (size_t)(dim + 1);
    ar = work;
    ia = (int *)(work + n);
    ja = (int *)(work + 2 * n);

    G.term_out(GLP_OFF);
    lp = G.create_prob();
    /* maximise the margin d: A_k x / |A_k| - d >= b_k / |A_k|, d <= S */
    G.set_obj_dir(lp, GLP_MAX);
    G.add_cols(lp, dim + 1);
    for (i = 0; i < dim; ++i) {
        G.set_col_bnds(lp, i + 1, GLP_DB, -big, big);
        G.set_obj_coef(lp, i + 1, 0.0);
    }
    G.set_col_bnds(lp, dim + 1, GLP_UP, 0.0, S);
    G.set_obj_coef(lp, dim + 1, 1.0);
    {
        int nr = 0;
        for (k = 0; k < m; ++k)
            if (lp_row_norm(dim, A, k) > ZERO_ROW)
                ++nr;
        if (nr > 0)
            G.add_rows(lp, nr);
        nr = 0;
        for (k = 0; k < m; ++k) {
            double nn = lp_row_norm(dim, A, k);
            if (!(nn > ZERO_ROW))
                continue;
            ++nr;
            G.set_row_bnds(lp, nr, GLP_LO, b[k] / nn, 0.0);
            for (i = 0; i < dim; ++i) {
                ++ne;
                ia[ne] = nr;
                ja[ne] = i + 1;
                ar[ne] = A[k * dim + i] / nn;
            }
            ++ne;
            ia[ne] = nr;
            ja[ne] = dim + 1;
            ar[ne] = -1.0;
        }
    }
    if (ne > 0)
        G.load_matrix(lp, ne, ia, ja, ar);
    G.init_smcp(&parm);
    parm.msg_lev = GLP_MSG_OFF;
    parm.presolve = GLP_OFF;
    /* primal tolerance below the decision threshold (default 1e-7; 1e-10
     * made GLPK stall), and a bounded number of simplex iterations */
    parm.tol_bnd = 1e-9;
    parm.it_lim = 10000 + 20 * m;
    st = G.simplex(lp, &parm);
    status = G.get_status(lp);
    if (st == 0 && status == GLP_OPT) {
        /* feasible iff the relaxed rows (margin -tol) can be met */
        if (G.get_col_prim(lp, dim + 1) >= -tol) {
            for (i = 0; i < dim; ++i)
                x[i] = G.get_col_prim(lp, i + 1);
            ret = MCG_OK;
        } else {
            ret = MCG_EINFEASIBLE;
        }
    } else {
        ret = MCG_ENUMERIC;
    }
    G.delete_prob(lp);
    if (ret == MCG_OK)
        return lp_verify_point(dim, m, A, b, x, tol);
    return ret;
}

static size_t glpk_work_size(void *ctx, int dim, int m)
{
    (void)ctx;
    return mcg_lp_glpk_work_size(dim, m);
}

static int glpk_feasible(void *ctx, int dim, int m, const double *A,
                         const double *b, double *x, double *work,
                         size_t lwork)
{
    (void)ctx;
    return mcg_lp_glpk_feasible(dim, m, A, b, x, work, lwork);
}

int mcg_lp_glpk_backend(mcg_lp_backend *be)
{
    if (!be)
        return MCG_EINVAL;
    if (!glpk_handle)
        return MCG_EUNAVAILABLE;
    be->name = "glpk";
    be->ctx = NULL;
    be->work_size = glpk_work_size;
    be->feasible = glpk_feasible;
    return MCG_OK;
}
