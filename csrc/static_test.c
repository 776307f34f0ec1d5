/*
 * static_test.c -- the noise level of the shared static-rig test
 * (mcgeom/estimators/_static.py, issue 18): per camera, the Sampson angular
 * residuals of its intra-camera correspondences when the camera translates
 * in its own best direction under a given rotation R.
 *
 * For camera i the generalized epipolar constraint (thesis eq. 8.16) of an
 * intra-camera pair reduces to the essential matrix about the camera centre
 * (thesis ch. 2.3): with a = (R d1) x d2 (unit bearings) it reads u . a = 0,
 * u the translation of the camera centre. u is the null vector of the rows
 * a, found robustly: least median of squares (Rousseeuw 1984) over the
 * directions that two rows fix (their cross product), scored by the median
 * of |ahat . v| (the sine of the angle between v and each row's plane), then
 * least squares on the rows within 2.5 robust standard deviations. The
 * samples come from a fixed stream (splitmix64 seeded by the camera's row
 * count), so the result is a function of the data. The residuals are those
 * of mcg_gec_residuals with t = u + c - R c (c the camera centre): the
 * camera's centre moves by u. Outliers handed to a direct estimator then do
 * not swing the direction and inflate the noise level.
 */
#include "mcgeom.h"
#include "internal.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#define MAX_SAMPLES 65536
#define MAD_TO_STD 1.4826 /* 1 / the median of |N(0, 1)| */
#define KEEP_SIGMAS 2.5   /* rows kept for the least-squares step */
#define MIN_SINE 1e-12    /* two rows closer than this fix no direction */

/* doubles holding n ints (the index arrays live in the double workspace) */
static size_t ints_as_doubles(size_t n)
{
    return (n * sizeof(int) + sizeof(double) - 1) / sizeof(double);
}

size_t mcg_static_noise_work_size(int n)
{
    int ok = 1;
    size_t w;
    if (n < 0 || (size_t)n > MAX_ROWS)
        return 0;
    /* two index arrays, the unit rows (3 n), their absolute products (n) */
    w = add_sz(mul_sz(2, ints_as_doubles((size_t)n), &ok), mul_sz(4, (size_t)n, &ok), &ok);
    w = add_sz(w, 1, &ok);
    return ok ? w : 0;
}

static uint64_t splitmix64(uint64_t *state)
{
    uint64_t z = (*state += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

/* the k-th smallest of x[0..m) (x is reordered; Hoare's selection) */
static double select_kth(double *x, int m, int k)
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

/* median of x[0..m), m >= 1, as numpy.median (the mean of the two middle
 * values when m is even); x is reordered */
static double median_inplace(double *x, int m)
{
    double hi = select_kth(x, m, m / 2);
    double lo;
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

/* stable merge sort of idx[0..m) by group[idx] (tmp: m ints) */
static void sort_by_group(int *idx, int *tmp, int m, const int *group)
{
    int width, i;
    for (width = 1; width < m; width *= 2) {
        for (i = 0; i < m; i += 2 * width) {
            int a = i, mid = i + width < m ? i + width : m;
            int end = i + 2 * width < m ? i + 2 * width : m, b = mid, k = i;
            while (a < mid && b < end)
                tmp[k++] = group[idx[b]] < group[idx[a]] ? idx[b++] : idx[a++];
            while (a < mid)
                tmp[k++] = idx[a++];
            while (b < end)
                tmp[k++] = idx[b++];
        }
        for (i = 0; i < m; i++)
            idx[i] = tmp[i];
    }
}

/* eigenvector of the smallest eigenvalue of the 3 x 3 scatter s (row-major) */
static int smallest_eigvec(const double s[9], double u[3])
{
    double a[9], w[3], v[9];
    int i, st;
    for (i = 0; i < 9; i++)
        a[i] = s[i];
    st = mcg_sym_eig(3, a, w, v);
    if (st != MCG_OK)
        return st;
    for (i = 0; i < 3; i++)
        u[i] = v[3 * i];
    return MCG_OK;
}

/* median of |ahat . v| over the m rows, scratch prod (m doubles) */
static double median_abs_dot(const double *ahat, int m, const double v[3], double *prod)
{
    int i;
    for (i = 0; i < m; i++)
        prod[i] = fabs(dot3(ahat + 3 * i, v));
    return median_inplace(prod, m);
}

/* the robust null vector u of camera rows rows[0..m) (see the file comment) */
static int camera_direction(const double *d1, const double *d2, const double R[9],
                            const int *rows, int m, int samples, double *ahat, double *prod,
                            int *okrow, double u[3])
{
    double s[9] = {0}, best;
    int i, k, n_ok = 0, st;
    uint64_t state = (uint64_t)m;
    for (i = 0; i < m; i++) {
        const double *p = d1 + 3 * rows[i], *q = d2 + 3 * rows[i];
        double rd[3], b[3], a[3], nr, nb, na;
        int r, c;
        mat_vec(R, p, rd);
        nr = sqrt(dot3(rd, rd));
        nb = sqrt(dot3(q, q));
        /* R maps a bearing to zero or beyond the doubles: not a rotation */
        if (!(nr > 0.0 && isfinite(nr)))
            return MCG_EINVAL;
        for (r = 0; r < 3; r++) {
            rd[r] /= nr;
            b[r] = q[r] / nb;
        }
        cross3(rd, b, a);
        for (r = 0; r < 3; r++)
            for (c = 0; c < 3; c++)
                s[3 * r + c] += a[r] * a[c];
        na = sqrt(dot3(a, a));
        if (na > 0.0) {
            for (r = 0; r < 3; r++)
                ahat[3 * n_ok + r] = a[r] / na;
            okrow[n_ok++] = i;
        }
    }
    st = smallest_eigvec(s, u);
    if (st != MCG_OK || n_ok < 3)
        return st;
    best = median_abs_dot(ahat, n_ok, u, prod);
    for (k = 0; k < samples; k++) {
        int a = (int)(splitmix64(&state) % (uint64_t)n_ok);
        int b = (int)(splitmix64(&state) % (uint64_t)(n_ok - 1));
        double v[3], nv, med;
        if (b >= a)
            b++;
        cross3(ahat + 3 * a, ahat + 3 * b, v);
        nv = sqrt(dot3(v, v));
        if (!(nv > MIN_SINE))
            continue;
        med = median_abs_dot(ahat, n_ok, v, prod) / nv;
        if (med < best) {
            best = med;
            for (i = 0; i < 3; i++)
                u[i] = v[i] / nv;
        }
    }
    {
        /* least squares on the rows within KEEP_SIGMAS robust stds (the
         * scatter of the unnormalised rows, as the first estimate) */
        double lim = KEEP_SIGMAS * MAD_TO_STD * best, s2[9] = {0};
        int kept = 0, r, c;
        for (i = 0; i < n_ok; i++) {
            if (fabs(dot3(ahat + 3 * i, u)) <= lim) {
                const double *p = d1 + 3 * rows[okrow[i]], *q = d2 + 3 * rows[okrow[i]];
                double rd[3], b[3], a[3], nr, nb;
                mat_vec(R, p, rd);
                nr = sqrt(dot3(rd, rd));
                nb = sqrt(dot3(q, q));
                for (r = 0; r < 3; r++) {
                    rd[r] /= nr;
                    b[r] = q[r] / nb;
                }
                cross3(rd, b, a);
                for (r = 0; r < 3; r++)
                    for (c = 0; c < 3; c++)
                        s2[3 * r + c] += a[r] * a[c];
                kept++;
            }
        }
        if (kept >= 2)
            st = smallest_eigvec(s2, u);
    }
    return st;
}

int mcg_static_noise(int n, const double *o1, const double *d1, const double *o2,
                     const double *d2, const int *group, const double R[9], int min_rows,
                     int samples, double *res, double *median, int *n_used, double *work,
                     size_t lwork)
{
    size_t need;
    int *idx, *tmp, i, m = 0, used = 0;
    double *ahat, *prod;
    if (!o1 || !d1 || !o2 || !d2 || !group || !R || !res || !median || !n_used ||
        (!work && lwork))
        return MCG_EINVAL;
    need = mcg_static_noise_work_size(n);
    if (need == 0 || min_rows < 1 || samples < 0 || samples > MAX_SAMPLES)
        return MCG_EINVAL;
    if (!all_finite(R, 9) || !all_finite(o1, 3 * (size_t)n) || !all_finite(d1, 3 * (size_t)n) ||
        !all_finite(o2, 3 * (size_t)n) || !all_finite(d2, 3 * (size_t)n))
        return MCG_EINVAL;
    for (i = 0; i < n; i++) {
        if (group[i] < -1)
            return MCG_EINVAL;
        /* a zero direction has no bearing (as mcg_gec_residuals) */
        if (group[i] >= 0 && !(dot3(d1 + 3 * i, d1 + 3 * i) > 0.0 &&
                               dot3(d2 + 3 * i, d2 + 3 * i) > 0.0))
            return MCG_EINVAL;
        /* mat_vec(R, .) of a direction must not overflow */
        if (group[i] >= 0 && !(isfinite(dot3(d1 + 3 * i, d1 + 3 * i)) &&
                               isfinite(dot3(d2 + 3 * i, d2 + 3 * i))))
            return MCG_EINVAL;
    }
    if (lwork < need)
        return MCG_ENOMEM;
    idx = (int *)work;
    tmp = idx + n;
    ahat = work + 2 * ints_as_doubles((size_t)n);
    prod = ahat + 3 * (size_t)n;
    for (i = 0; i < n; i++) {
        res[i] = -1.0;
        if (group[i] >= 0)
            idx[m++] = i;
    }
    sort_by_group(idx, tmp, m, group);
    for (i = 0; i < m;) {
        int j = i, k, st;
        double u[3], c[3], rc[3], t[3];
        while (j < m && group[idx[j]] == group[idx[i]])
            j++;
        if (j - i >= min_rows) {
            /* tmp serves as the row list of the camera's usable rows */
            st = camera_direction(d1, d2, R, idx + i, j - i, samples, ahat, prod, tmp, u);
            if (st != MCG_OK)
                return st;
            for (k = 0; k < 3; k++)
                c[k] = o1[3 * idx[i] + k];
            mat_vec(R, c, rc);
            for (k = 0; k < 3; k++)
                t[k] = u[k] + c[k] - rc[k];
            for (k = i; k < j; k++) {
                int r = idx[k];
                double e;
                st = mcg_gec_residuals(1, o1 + 3 * r, d1 + 3 * r, o2 + 3 * r, d2 + 3 * r, R, t,
                                       &e);
                if (st != MCG_OK)
                    return st;
                res[r] = fabs(e);
            }
        }
        i = j;
    }
    for (i = 0; i < n; i++)
        if (res[i] >= 0.0)
            prod[used++] = res[i];
    *n_used = used;
    *median = used ? median_inplace(prod, used) : 0.0;
    return MCG_OK;
}
