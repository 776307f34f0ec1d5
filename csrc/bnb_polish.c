/*
 * bnb_polish.c -- the polish of the branch and bound's incumbent (csrc/bnb.c):
 * random local moves of the rotation that lower f(R), the L-infinity error of
 * the feasibility test, then sequential LP steps; an upper bound only (the
 * certificate is the search's lower bound).
 */
#include "bnb_internal.h"

#include <math.h>
#include <string.h>

/* The polish (after the search): the local L-infinity minimum over (R, t)
 * by sequential LP (linf_local.c) from the incumbent and from POLISH_STARTS
 * - 1 rotations around it at 3, 10, 30 and 100 x the resolution (fixed
 * pseudo-random directions). The bound of the search cannot tell apart
 * basins whose minima differ by less than the certified gap (about half the
 * resolution): f has shallow valleys whose separate minima can lie some
 * resolutions apart (measured: two minima 6e-4 rad apart, 6.6e-7 rad
 * different, over a ridge 8e-7 high); local minimisations started across
 * that neighbourhood find the lower one. A start costs about 1 ms for 200
 * correspondences. */
#define POLISH_STARTS 13
#define POLISH_MAX_STEPS 200 /* sequential-LP steps per start */

static double lcg_uniform(unsigned long long *state)
{
    *state = *state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*state >> 11) * (1.0 / 9007199254740992.0);
}

/* a pseudo-random unit direction */
static void random_direction(unsigned long long *state, double dir[3])
{
    double n = 0.0;
    int tries;
    /* rejection sampling in the unit ball: a draw is accepted with
     * probability ~0.52, so 1000 tries never all fail in practice; the last
     * draw is kept regardless (any non-zero direction would do) */
    for (tries = 0; tries < 1000; ++tries) {
        dir[0] = 2.0 * lcg_uniform(state) - 1.0;
        dir[1] = 2.0 * lcg_uniform(state) - 1.0;
        dir[2] = 2.0 * lcg_uniform(state) - 1.0;
        n = dot3(dir, dir);
        if (n <= 1.0 && n >= 1e-4)
            break;
    }
    if (n < 1e-4) {
        dir[0] = 1.0;
        dir[1] = dir[2] = 0.0;
        n = 1.0;
    }
    n = sqrt(n);
    dir[0] /= n;
    dir[1] /= n;
    dir[2] /= n;
}

/* f at angle-axis w if it is below level (then 1, *f and t set), else 0
 * (f >= level up to the tolerance): one exact test decides, a bisection
 * above the certified lower bound, to tol, follows only when it passes. */
static int f_below(bnb_ctx *c, const mcg_bnb_options *o, const double w[3], double level,
                   double tol, double *f, double t[3], long *tests)
{
    double Rn[9], hi = level - 2.0 * o->tol;
    int st, r;
    if (hi <= 0.0)
        return 0;
    st = mcg_rot_from_angle_axis(w, Rn);
    if (st != MCG_OK)
        return -st;
    ++*tests;
    r = bnb_feasible(c, Rn, hi, 0.0, t);
    if (r < 0)
        return r;
    if (r != 1)
        return 0;
    st = bnb_find_min_error(c, Rn, 0.0, c->floor, &hi, t, tol, 0);
    if (st != MCG_OK)
        return -st;
    *f = hi;
    return 1;
}

/* f just below the incumbent at angle-axis w? If so, the incumbent moves
 * there: 1; not: 0; < 0 status. */
static int try_move(bnb_ctx *c, const mcg_bnb_options *o, mcg_bnb_result *res,
                    const double w[3], long *tests)
{
    double f = 0.0, tt[3];
    int r = f_below(c, o, w, res->linf, o->tol, &f, tt, tests);
    if (r != 1)
        return r;
    r = mcg_rot_from_angle_axis(w, res->R);
    if (r != MCG_OK)
        return -r;
    res->linf = f;
    memcpy(res->t, tt, sizeof tt);
    return 1;
}

/* The polish: each start's local minimum verified by the exact test (the
 * incumbent moves only where f is lower; never increases f). Its workspace
 * is the 3- and 2-variable rows' space (9 of their 6 ROWS_PER n doubles). */
int bnb_polish_slp(bnb_ctx *c, const mcg_bnb_options *o, mcg_bnb_result *res,
                   long *tests, double deadline)
{
    unsigned long long state = 0x2545f4914f6cdd1dULL;
    double w0[3];
    int st, k, start;
    st = mcg_angle_axis_from_rot(res->R, w0);
    if (st != MCG_OK)
        return st;
    for (start = 0; start < POLISH_STARTS; ++start) {
        double R[9], t[3], w[3], fs, dir[3];
        int steps;
        if (start > 0 && bnb_now_seconds() > deadline) {
            res->stop = MCG_BNB_TIME_LIMIT;
            break; /* the incumbent so far stands: never worse */
        }
        memcpy(w, w0, sizeof w);
        if (start > 0) {
            static const double scales[4] = {100.0, 3.0, 10.0, 30.0};
            double scale = o->resolution * scales[start % 4];
            random_direction(&state, dir);
            for (k = 0; k < 3; ++k)
                w[k] += scale * dir[k];
        }
        st = mcg_rot_from_angle_axis(w, R);
        if (st != MCG_OK)
            return st;
        memcpy(t, res->t, sizeof t);
        st = mcg_linf_local(c->n, c->u1, c->a1, c->u2, c->a2, R, t, 10.0 * o->resolution,
                            o->polish_tol, POLISH_MAX_STEPS, c->A3, &fs, &steps);
        if (st != MCG_OK)
            return st;
        *tests += steps;
        if (!(asin(fs < 1.0 ? fs : 1.0) < res->linf - o->tol))
            continue;
        st = mcg_angle_axis_from_rot(R, w);
        if (st != MCG_OK)
            return st;
        st = try_move(c, o, res, w, tests);
        if (st < 0)
            return -st;
        if (start == 0)
            memcpy(w0, w, sizeof w);
    }
    return MCG_OK;
}
