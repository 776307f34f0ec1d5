/*
 * sixpt.c -- the generic minimal generalized relative pose from 6
 * correspondences (Stewenius, Nister, Oskarsson, Astrom, OMNIVIS 2005).
 * Body under construction on branch six21.
 */
#include "mcgeom.h"
#include "internal.h"

int mcg_sixpt(const double o1[18], const double d1[18], const double o2[18], const double d2[18],
              double R[576], double t[192], int *n_solutions)
{
    if (!o1 || !d1 || !o2 || !d2 || !R || !t || !n_solutions)
        return MCG_EINVAL;
    *n_solutions = 0;
    return MCG_EDEGENERATE;
}
