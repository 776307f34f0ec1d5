/*
 * internal.h -- helpers shared by the kernels of libmcgeom (not installed,
 * not part of the public API): the size limits every entry point enforces,
 * overflow-checked size arithmetic for workspace sizes, and the finiteness
 * test of the inputs. The 3-vector / 3 x 3 / SO(3) helpers are in so3.h,
 * included here.
 */
#ifndef MCGEOM_INTERNAL_H
#define MCGEOM_INTERNAL_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "so3.h" /* dot3, cross3, mat_vec, mul33, det33, skew3, is_rotation, ... */

/* MCG_AVX2_CLONE before a hot loop's function: on x86-64 Linux with GCC and
 * glibc it is also compiled for AVX2 (4 doubles a register) and an ifunc
 * picks the clone at load time; elsewhere (clang, musl -- no ifunc --,
 * other CPUs) the plain function alone. Only "avx2", never "fma": without
 * fused multiply-adds every product and sum rounds as in the default clone,
 * so the results are the same to the bit on every CPU (issue 22).
 * Only on static functions: a global target_clones function exports its
 * ifunc and resolver symbols whatever -fvisibility says, and libmcgeom.so
 * exports mcgeom.h's functions alone (.ci/c_checks); a clone that another
 * file calls sits behind a plain wrapper. */
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && \
    defined(__linux__) && defined(__GLIBC__)
#define MCG_AVX2_CLONE __attribute__((target_clones("avx2", "default")))
#else
#define MCG_AVX2_CLONE
#endif

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

/* the largest |x_i| (0 for n = 0) */
static inline double max_abs(const double *x, size_t n)
{
    double mx = 0.0;
    size_t i;
    for (i = 0; i < n; ++i) {
        double ax = fabs(x[i]);
        if (ax > mx)
            mx = ax;
    }
    return mx;
}

/* 1 if none of the n values is NaN or +-inf */
static inline int all_finite(const double *x, size_t n)
{
    size_t i;
    for (i = 0; i < n; ++i)
        if (!isfinite(x[i]))
            return 0;
    return 1;
}

/* |y| without overflow or harmful underflow: the entries are divided by
 * the largest magnitude first (returned as is when 0 or not finite). Shared
 * by the least-squares residuals of cls.c and the rotation conversions of
 * linalg.c. */
static inline double norm_scaled(const double *y, size_t n)
{
    double mx = 0.0, acc = 0.0;
    size_t i;
    for (i = 0; i < n; ++i)
        if (fabs(y[i]) > mx)
            mx = fabs(y[i]);
    if (mx == 0.0 || !isfinite(mx))
        return mx;
    for (i = 0; i < n; ++i) {
        double t = y[i] / mx;
        acc += t * t;
    }
    return mx * sqrt(acc);
}

/* Two independent parts of a relative std of |t| (the noise's and the
 * calibration's) in quadrature, HUGE_VAL if either is not finite
 * (mcgeom.observability.combine_rel_std); shared by the robust verdict and
 * the checks of its consensus. */
static inline double combine_rel_std(double a, double b)
{
    if (!(isfinite(a) && isfinite(b)))
        return HUGE_VAL;
    return hypot(a, b);
}

/* Centroid c of the 2n ray origins o1, o2 (n x 3 each, n >= 1) and the RMS
 * distance of the origins from it: the position and size of a rig, both
 * independent of the rig frame's origin and orientation. */
static inline double origin_spread(int n, const double *o1, const double *o2, double c[3])
{
    double ss = 0.0;
    int k, i;
    c[0] = c[1] = c[2] = 0.0;
    for (k = 0; k < n; k++)
        for (i = 0; i < 3; i++)
            c[i] += o1[3 * k + i] + o2[3 * k + i];
    for (i = 0; i < 3; i++)
        c[i] /= 2.0 * n;
    for (k = 0; k < n; k++)
        for (i = 0; i < 3; i++) {
            double a = o1[3 * k + i] - c[i], b = o2[3 * k + i] - c[i];
            ss += a * a + b * b;
        }
    return sqrt(ss / (2.0 * n));
}

/* wedge.c: the bitangent normals from unit axes a = v'/|v'|, b = -v/|v| and
 * the sines of the enlarged half-angles (no checks; see mcg_wedge_normals). */
int mcg_wedge_unit(const double a[3], const double b[3], double sa, double sb,
                   double n1[3], double n2[3]);

/* linf_local.c: local minimisation of the L-infinity error over (R, t)
 * from (R, t) (in/out; unit bearings u1, u2, origins a1, a2, n x 3) by
 * trust-region sequential LP, at most max_steps steps, trust radius from
 * delta0 until it falls below delta_min; work: 9 n doubles. *f_out: the final max of sin(e_i) of the
 * closed-form per-correspondence errors; *steps_out: steps taken. The
 * caller verifies the result (the model may be invalid near a wedge's
 * front). */
int mcg_linf_local(int n, const double *u1, const double *a1, const double *u2,
                   const double *a2, double R[9], double t[3], double delta0,
                   double delta_min, int max_steps, double *work, double *f_out,
                   int *steps_out);

/* mcg_scale_ransac (scale_line.c) on the pairs idx[0..n) of the n_all x 3
 * arrays o1, d1, o2, d2 (idx NULL: the first n), the arguments already
 * checked by the caller; work: mcg_scale_ransac_work_size(n) doubles. For
 * robust.c's 1-point scale search, which then needs no copy of the pairs. */
int mcg_scale_ransac_indexed(int n, const int *idx, const double *o1, const double *d1,
                             const double *o2, const double *d2, const double R[9],
                             const double t0[3], const double w[3], int n_order,
                             const int *order, int max_proposals, double threshold,
                             double prob, double *lam, double *score, int *n_inliers,
                             double *work);

/* upright4.c: the central upright 3-point solver (rays of one camera, the
 * vertical g1, g2 known at both times, any lengths): up to 6 rotations R
 * (rig frames, 6 x 9) and unit directions u (6 x 3, sign arbitrary) of the
 * camera centre's travel with d2^T [u]x R d1 = 0 for the 3 bearing pairs
 * d1 -> d2 (any non-zero lengths). MCG_OK (possibly 0 solutions),
 * MCG_EINVAL for a zero or non-finite bearing or vertical, MCG_EDEGENERATE
 * where every yaw fits (e.g. repeated pairs). No allocation. */
#define MCG_UPRIGHT3_MAX_SOLUTIONS 6
int mcg_upright3_central(const double d1[9], const double d2[9], const double g1[3],
                         const double g2[3], double R[54], double u[18], int *n_solutions);

/* mcg_refine_motion (refine.c) that also stops, converged with reason
 * MCG_REFINE_STOP_COST, once its cost is at most cost_target, or evidently
 * above it (more than 100 times the last accepted step's decrease above)
 * (-HUGE_VAL: never; mcg_refine_motion itself). */
int mcg_refine_motion_until(int n, const double *o1, const double *d1, const double *o2,
                            const double *d2, const double *weights,
                            const mcg_refine_options *opt, double cost_target, double R[9],
                            double t[3], mcg_refine_result *res);

/* The k-th smallest of x[0..m) (x is reordered; Hoare's selection), and the
 * median as numpy.median (the mean of the two middle values for even m,
 * m >= 1; x is reordered). For the robust statistics of the kernels
 * (static_test.c, robust.c). */
static inline double select_kth_inplace(double *x, int m, int k)
{
    int lo = 0, hi = m - 1;
    while (lo < hi) {
        double pivot = x[lo + (hi - lo) / 2];
        int i = lo, j = hi;
        while (i <= j) {
            while (x[i] < pivot)
                i++;
            while (x[j] > pivot)
                j--;
            if (i <= j) {
                double s = x[i];
                x[i] = x[j];
                x[j] = s;
                i++;
                j--;
            }
        }
        if (k <= j)
            hi = j;
        else if (k >= i)
            lo = i;
        else
            break;
    }
    return x[k];
}

static inline double median_inplace(double *x, int m)
{
    double hi = select_kth_inplace(x, m, m / 2), lo;
    int i;
    if (m % 2)
        return hi;
    /* the largest of the lower half (all <= hi after the selection) */
    lo = x[0];
    for (i = 1; i < m / 2; i++)
        if (x[i] > lo)
            lo = x[i];
    return 0.5 * (lo + hi);
}

#endif /* MCGEOM_INTERNAL_H */
