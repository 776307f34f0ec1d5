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
 *
 * mcg_static_check runs the whole test of one estimate in one call (issue
 * 22: it runs on every estimator call): the best pure rotation of the
 * intra-camera bearings (Wahba's problem, the rotation nearest to
 * sum d2 d1^T), the noise level (the smaller of those at the estimate's and
 * at the pure rotation), then the no-parallax statistic of
 * mcgeom.observability.no_parallax (a fraction of the rotation-only angles
 * within a factor of the level) at the pure rotation and, failing that, at
 * the estimate's own rotation; and at least min_distinct distinct
 * intra-camera pairs (repeats of one pair explain any rotation). A moving
 * rig is recognised at an upper bound of the level, from the cameras that
 * hold just over half of the residuals, without fitting the others (see
 * mcg_static_check); its reported noise_level is then that bound.
 */
#include "mcgeom.h"
#include "internal.h"

#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>

/* The passes over a camera's rows (making them, and the candidates'
 * counting passes and medians of the least median of squares) and over
 * the bearings (making them unit, and the rotation-only statistic) are
 * written without branches so that they vectorise, and carry
 * MCG_AVX2_CLONE (internal.h: the same bits on every CPU; issue 22). A
 * function the clones call carries it too: GCC does not inline it into
 * them, and the default build of it would not vectorise for AVX2. */

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
    /* two index arrays, the unit rows (3 n), their absolute products (n),
     * one camera's rays gathered contiguously (12 n), its residuals (n) and
     * its rows before normalisation (3 n) */
    w = add_sz(mul_sz(2, ints_as_doubles((size_t)n), &ok), mul_sz(20, (size_t)n, &ok), &ok);
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

/* the m pairs with group >= 0 into idx, stably sorted by group: a counting
 * sort when every id is below n (camera ids; tmp holds the counts), else a
 * merge sort (tmp: its scratch). Both give the one stable order. */
static void merge_sort_by_group(int *idx, int *tmp, int m, const int *group);

static int pairs_by_group(int n, const int *group, int *idx, int *tmp)
{
    int i, m = 0, top = -1;
    for (i = 0; i < n; i++)
        if (group[i] > top)
            top = group[i];
    if (top < n) {
        int sum = 0;
        for (i = 0; i <= top; i++)
            tmp[i] = 0;
        for (i = 0; i < n; i++)
            if (group[i] >= 0)
                tmp[group[i]]++;
        for (i = 0; i <= top; i++) { /* counts -> first positions */
            int c = tmp[i];
            tmp[i] = sum;
            sum += c;
        }
        for (i = 0; i < n; i++)
            if (group[i] >= 0)
                idx[tmp[group[i]]++] = i;
        return sum;
    }
    for (i = 0; i < n; i++)
        if (group[i] >= 0)
            idx[m++] = i;
    merge_sort_by_group(idx, tmp, m, group);
    return m;
}

/* stable merge sort of idx[0..m) by group[idx] (tmp: m ints) */
static void merge_sort_by_group(int *idx, int *tmp, int m, const int *group)
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

/* eigenvector of the smallest eigenvalue of the 3 x 3 scatter s (row-major,
 * symmetric positive semi-definite, finite: sums of products of unit
 * vectors). Cyclic Jacobi rotations on the three off-diagonal entries
 * (Golub & Van Loan, Matrix Computations, alg. 8.5.3, the rotation angle
 * of Rutishauser's formulation), accumulated into v. Why not mcg_sym_eig:
 * its input checks, power-of-two scaling and general n cost about 5000
 * instructions per 3 x 3 call, and the test makes 8 calls per estimate
 * (two per camera at each of two rotations; issue 22: a quarter of the
 * test). Jacobi keeps the small eigenvalue accurate to rounding of the
 * largest, as the general routine does. */
static int smallest_eigvec(const double s[9], double u[3])
{
    static const int P[3] = {0, 0, 1}, Q[3] = {1, 2, 2};
    double a[9], v[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    int sweep, k, i, best;
    for (i = 0; i < 9; i++)
        a[i] = s[i];
    for (sweep = 0; sweep < 50; sweep++) {
        double off = fabs(a[1]) + fabs(a[2]) + fabs(a[5]);
        if (!(off > 0.0))
            break;
        for (k = 0; k < 3; k++) {
            int p = P[k], q = Q[k], r = 3 - p - q;
            double apq = a[3 * p + q], app = a[4 * p], aqq = a[4 * q], g = 100.0 * fabs(apq);
            double theta, t, c, sn, arp, arq;
            if (apq == 0.0)
                continue;
            /* negligible next to both diagonal entries: zero it (after the
             * first sweeps, when the quadratic convergence has set in) */
            if (sweep > 3 && fabs(app) + g == fabs(app) && fabs(aqq) + g == fabs(aqq)) {
                a[3 * p + q] = a[3 * q + p] = 0.0;
                continue;
            }
            theta = (aqq - app) / (2.0 * apq);
            t = fabs(theta) > 1e150 ? 0.5 / theta
                                    : (theta >= 0.0 ? 1.0 : -1.0) /
                                          (fabs(theta) + sqrt(theta * theta + 1.0));
            c = 1.0 / sqrt(t * t + 1.0);
            sn = t * c;
            a[4 * p] = app - t * apq;
            a[4 * q] = aqq + t * apq;
            a[3 * p + q] = a[3 * q + p] = 0.0;
            arp = a[3 * r + p];
            arq = a[3 * r + q];
            a[3 * r + p] = a[3 * p + r] = c * arp - sn * arq;
            a[3 * r + q] = a[3 * q + r] = sn * arp + c * arq;
            for (i = 0; i < 3; i++) {
                double vp = v[3 * i + p], vq = v[3 * i + q];
                v[3 * i + p] = c * vp - sn * vq;
                v[3 * i + q] = sn * vp + c * vq;
            }
        }
    }
    if (!(isfinite(a[0]) && isfinite(a[4]) && isfinite(a[8])))
        return MCG_ENUMERIC;
    best = a[0] <= a[4] ? 0 : 1;
    if (a[8] < a[4 * best])
        best = 2;
    for (i = 0; i < 3; i++)
        u[i] = v[3 * i + best];
    return MCG_OK;
}

/* The unit rows of a camera are stored by coordinate (ax, ay, az: stride
 * m), so that the passes over them below vectorise; p . v is summed in the
 * order of dot3. */

/* median of |ahat . v| over the k rows, scratch prod (k doubles) */
MCG_AVX2_CLONE
static double median_abs_dot(const double *ax, const double *ay, const double *az, int k,
                             const double v[3], double *prod)
{
    int i;
    for (i = 0; i < k; i++)
        prod[i] = fabs(ax[i] * v[0] + ay[i] * v[1] + az[i] * v[2]);
    return median_inplace(prod, k);
}

/* whether at least need of the k rows have |ahat . v| < x: counted in
 * blocks, stopping once the rows left cannot make up the count. The count
 * is kept in 4 lanes (whole numbers in doubles: their sum is exact in any
 * order), since one running sum is a chain the compiler may not reorder and
 * so does not vectorise (issue 22: this pass is most of the test's time) */
#define COUNT_BLOCK 64
#define COUNT_LANES 4
MCG_AVX2_CLONE
static int enough_below(const double *ax, const double *ay, const double *az, int k,
                        const double v[3], double x, int need)
{
    int i0;
    double c = 0.0;
    for (i0 = 0; i0 < k; i0 += COUNT_BLOCK) {
        int i, l, end = k - i0 < COUNT_BLOCK ? k : i0 + COUNT_BLOCK;
        double cl[COUNT_LANES] = {0.0, 0.0, 0.0, 0.0};
        for (i = i0; i + COUNT_LANES <= end; i += COUNT_LANES)
            for (l = 0; l < COUNT_LANES; l++)
                cl[l] += fabs(ax[i + l] * v[0] + ay[i + l] * v[1] + az[i + l] * v[2]) < x
                             ? 1.0 : 0.0;
        for (; i < end; i++)
            cl[0] += fabs(ax[i] * v[0] + ay[i] * v[1] + az[i] * v[2]) < x ? 1.0 : 0.0;
        c += (cl[0] + cl[1]) + (cl[2] + cl[3]);
        if (c >= need)
            return 1;
        if (c + (k - end) < need)
            return 0;
    }
    return c >= need;
}

/* The rows a = (R d1 / |R d1|) x (d2 / |d2|) of a camera's m pairs (its
 * bearings gathered contiguously in d1, d2): into raw by row (3 m) and
 * their units into ax, ay, az by coordinate (NaN where a = 0, whose
 * bearings are parallel). One pass without branches, so that it
 * vectorises: its square roots and divisions, one row at a time, were half
 * of camera_direction's time (issue 22); the same operations in the same
 * order as before, so the same bits. 0 when R maps a bearing to zero or
 * beyond the doubles (not a rotation). */
MCG_AVX2_CLONE
static int unit_rows(const double *restrict d1, const double *restrict d2, const double R[9],
                     int m, double *restrict raw, double *restrict ax, double *restrict ay,
                     double *restrict az)
{
    double Rl[9]; /* (a local copy: no store can change it, so R is loaded once) */
    int i, bad = 0;
    for (i = 0; i < 9; i++)
        Rl[i] = R[i];
    for (i = 0; i < m; i++) {
        const double *p = d1 + 3 * i, *q = d2 + 3 * i;
        double rd[3], b[3], a[3], nr, nb, na;
        int r;
        mat_vec(Rl, p, rd);
        nr = sqrt(dot3(rd, rd));
        nb = sqrt(dot3(q, q));
        bad |= !((nr > 0.0) & (nr <= DBL_MAX));
        for (r = 0; r < 3; r++) {
            rd[r] /= nr;
            b[r] = q[r] / nb;
        }
        cross3(rd, b, a);
        na = sqrt(dot3(a, a));
        for (r = 0; r < 3; r++)
            raw[3 * i + r] = a[r];
        ax[i] = a[0] / na;
        ay[i] = a[1] / na;
        az[i] = a[2] / na;
    }
    return !bad;
}

/* the robust null vector u of the m rows of one camera, its bearings
 * gathered contiguously in d1, d2 (see the file comment); ahat and raw: 3 m
 * doubles (the unit rows and the rows), prod: m doubles */
MCG_AVX2_CLONE
static int camera_direction(const double *d1, const double *d2, const double R[9], int m,
                            int samples, double *ahat, double *raw, double *prod, double u[3])
{
    double s[9] = {0}, best, *ax = ahat, *ay = ahat + m, *az = ahat + 2 * (size_t)m;
    int i, k, n_ok = 0, st, need;
    uint64_t state = (uint64_t)m;
    if (!unit_rows(d1, d2, R, m, raw, ax, ay, az))
        return MCG_EINVAL;
    /* the rows with a direction (a != 0: ahat not NaN), kept in order, and
     * their scatter s = sum a a^T (the zero rows add nothing to it) */
    for (i = 0; i < m; i++) {
        const double *a;
        int r, c;
        if (!(ax[i] == ax[i]))
            continue;
        if (n_ok != i) {
            for (r = 0; r < 3; r++)
                raw[3 * n_ok + r] = raw[3 * i + r];
            ax[n_ok] = ax[i];
            ay[n_ok] = ay[i];
            az[n_ok] = az[i];
        }
        a = raw + 3 * n_ok;
        for (r = 0; r < 3; r++)
            for (c = 0; c < 3; c++)
                s[3 * r + c] += a[r] * a[c];
        n_ok++;
    }
    st = smallest_eigvec(s, u);
    if (st != MCG_OK || n_ok < 3)
        return st;
    best = median_abs_dot(ax, ay, az, n_ok, u, prod);
    /* a candidate v replaces u only when median|ahat . v| / |v| < best; the
     * median is at least x when fewer than ceil(n_ok / 2) rows are below x
     * (the middle order statistic -- or, for an even count, both middle
     * ones -- is then >= x). So one counting pass with x a hair above
     * best |v| rejects a candidate exactly as the median would (issue 22:
     * the selection ran for all 32 samples and was most of the test's
     * time); the median is computed only for candidates that may win. */
    need = (n_ok + 1) / 2;
    for (k = 0; k < samples; k++) {
        int a = (int)(splitmix64(&state) % (uint64_t)n_ok);
        int b = (int)(splitmix64(&state) % (uint64_t)(n_ok - 1));
        double v[3], p[3], q[3], nv, med, x;
        if (b >= a)
            b++;
        p[0] = ax[a];
        p[1] = ay[a];
        p[2] = az[a];
        q[0] = ax[b];
        q[1] = ay[b];
        q[2] = az[b];
        cross3(p, q, v);
        nv = sqrt(dot3(v, v));
        if (!(nv > MIN_SINE))
            continue;
        /* x far from underflow: the relative margin 1e-9 then covers the
         * rounding of med / nv against best */
        x = best * nv * (1.0 + 1e-9);
        if (x > 1e-200 && !enough_below(ax, ay, az, n_ok, v, x, need))
            continue;
        med = median_abs_dot(ax, ay, az, n_ok, v, prod) / nv;
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
        int kept = 0;
        for (i = 0; i < n_ok; i++) {
            if (fabs(ax[i] * u[0] + ay[i] * u[1] + az[i] * u[2]) <= lim) {
                const double *a = raw + 3 * i; /* as unit_rows made it */
                int r, c;
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

/* 1 if none of the n values is NaN or +-inf: 0 x is NaN exactly for those,
 * and a sum of signed zeros is zero (one branch-free pass, where all_finite
 * tests and branches on every value: with the row checks below, 88
 * against 119 instructions per correspondence measured). Four partial sums
 * (any order gives zero, or NaN), so that the loop vectorises: one running
 * sum is a chain the compiler may not reorder (issue 22). */
static int all_finite_fast(const double *x, size_t n)
{
    size_t i, l;
    double acc[4] = {0.0, 0.0, 0.0, 0.0};
    for (i = 0; i + 4 <= n; i += 4)
        for (l = 0; l < 4; l++)
            acc[l] += 0.0 * x[i + l];
    for (; i < n; i++)
        acc[0] += 0.0 * x[i];
    return (acc[0] + acc[1]) + (acc[2] + acc[3]) == 0.0;
}

/* the checks shared by both entry points (sizes and workspace aside) */
static int check_rays(int n, const double *o1, const double *d1, const double *o2,
                      const double *d2, const int *group, int min_rows, int samples)
{
    int i, bad = 0;
    if (min_rows < 1 || samples < 0 || samples > MAX_SAMPLES)
        return MCG_EINVAL;
    if (!all_finite_fast(o1, 3 * (size_t)n) || !all_finite_fast(d1, 3 * (size_t)n) ||
        !all_finite_fast(o2, 3 * (size_t)n) || !all_finite_fast(d2, 3 * (size_t)n))
        return MCG_EINVAL;
    for (i = 0; i < n; i++) {
        /* a zero direction has no bearing (as mcg_gec_residuals); mat_vec(R,
         * .) of a direction must not overflow (the inputs are finite here) */
        double a = dot3(d1 + 3 * i, d1 + 3 * i), b = dot3(d2 + 3 * i, d2 + 3 * i);
        int ok = a > 0.0 && b > 0.0 && a <= DBL_MAX && b <= DBL_MAX;
        bad |= (group[i] < -1) | ((group[i] >= 0) & !ok);
    }
    return bad ? MCG_EINVAL : MCG_OK;
}

/* The residuals of the cameras of pairs idx[*pos..m) (sorted by group by
 * pairs_by_group) into res, a camera at a time; stops after the camera
 * that brings the rows done to at least stop (0: never) and leaves *pos at
 * the next camera, so that a later call resumes there. *done counts the
 * rows whose residual was computed. work: as static_noise's. */
MCG_AVX2_CLONE
static int noise_cameras(const double *o1, const double *d1, const double *o2,
                         const double *d2, const int *group, const double R[9], int min_rows,
                         int samples, double *res, int n, double *work, int m, int *pos,
                         int stop, int *done)
{
    int *idx = (int *)work, i;
    double *ahat, *prod, *buf, *cres, *raw;
    ahat = work + 2 * ints_as_doubles((size_t)n);
    prod = ahat + 3 * (size_t)n;
    buf = prod + (size_t)n;
    cres = buf + 12 * (size_t)n;
    raw = cres + (size_t)n;
    for (i = *pos; i < m;) {
        int j = i, k, c, st, mc;
        double u[3], cc[3], rc[3], t[3], *bo1, *bd1, *bo2, *bd2;
        while (j < m && group[idx[j]] == group[idx[i]])
            j++;
        mc = j - i;
        if (mc >= min_rows) {
            /* the camera's rays gathered contiguously: its passes run over
             * consecutive memory and its residuals are one call */
            bo1 = buf;
            bd1 = buf + 3 * (size_t)mc;
            bo2 = buf + 6 * (size_t)mc;
            bd2 = buf + 9 * (size_t)mc;
            for (k = 0; k < mc; k++)
                for (c = 0; c < 3; c++) {
                    int r = 3 * idx[i + k] + c;
                    bo1[3 * k + c] = o1[r];
                    bd1[3 * k + c] = d1[r];
                    bo2[3 * k + c] = o2[r];
                    bd2[3 * k + c] = d2[r];
                }
            st = camera_direction(bd1, bd2, R, mc, samples, ahat, raw, prod, u);
            if (st != MCG_OK)
                return st;
            for (k = 0; k < 3; k++)
                cc[k] = bo1[k];
            mat_vec(R, cc, rc);
            for (k = 0; k < 3; k++)
                t[k] = u[k] + cc[k] - rc[k];
            st = mcg_gec_residuals(mc, bo1, bd1, bo2, bd2, R, t, cres);
            if (st != MCG_OK)
                return st;
            for (k = 0; k < mc; k++)
                res[idx[i + k]] = fabs(cres[k]);
            *done += mc;
        }
        i = j;
        if (stop > 0 && *done >= stop)
            break;
    }
    *pos = i;
    return MCG_OK;
}

/* the residuals res >= 0 (the cameras done; NaN and -1 left out) into out;
 * returns their number */
static int gather_used(int n, const double *res, double *out)
{
    int i, used = 0;
    for (i = 0; i < n; i++)
        if (res[i] >= 0.0)
            out[used++] = res[i];
    return used;
}

/* mcg_static_noise on checked arguments */
static int static_noise(int n, const double *o1, const double *d1, const double *o2,
                        const double *d2, const int *group, const double R[9], int min_rows,
                        int samples, double *res, double *median, int *n_used, double *work)
{
    int *idx = (int *)work, i, m, used, pos = 0, done = 0, st;
    double *prod = work + 2 * ints_as_doubles((size_t)n) + 3 * (size_t)n;
    for (i = 0; i < n; i++)
        res[i] = -1.0;
    m = pairs_by_group(n, group, idx, idx + n);
    st = noise_cameras(o1, d1, o2, d2, group, R, min_rows, samples, res, n, work, m, &pos,
                       0, &done);
    if (st != MCG_OK)
        return st;
    used = gather_used(n, res, prod);
    *n_used = used;
    *median = used ? median_inplace(prod, used) : 0.0;
    return MCG_OK;
}

int mcg_static_noise(int n, const double *o1, const double *d1, const double *o2,
                     const double *d2, const int *group, const double R[9], int min_rows,
                     int samples, double *res, double *median, int *n_used, double *work,
                     size_t lwork)
{
    size_t need;
    int st;
    if (!o1 || !d1 || !o2 || !d2 || !group || !R || !res || !median || !n_used ||
        (!work && lwork))
        return MCG_EINVAL;
    need = mcg_static_noise_work_size(n);
    if (need == 0 || !all_finite(R, 9))
        return MCG_EINVAL;
    st = check_rays(n, o1, d1, o2, d2, group, min_rows, samples);
    if (st != MCG_OK)
        return st;
    if (lwork < need)
        return MCG_ENOMEM;
    return static_noise(n, o1, d1, o2, d2, group, R, min_rows, samples, res, median, n_used,
                        work);
}

void mcg_static_default_options(mcg_static_options *opt)
{
    if (!opt)
        return;
    opt->noise_factor = 10.0;
    opt->noise_floor = 1e-9;
    opt->default_level = 1e-3;
    opt->parallax_factor = 1.5;
    opt->fraction = 0.9;
    opt->min_pairs = 5;
    opt->min_distinct = 5;
    opt->min_rows = 12;
    opt->samples = 32;
}

size_t mcg_static_check_work_size(int n)
{
    int ok = 1;
    size_t w = mcg_static_noise_work_size(n);
    if (w == 0)
        return 0;
    /* residuals, angles, the unit bearings at both times (6 n) */
    w = add_sz(w, mul_sz(8, (size_t)n, &ok), &ok);
    return ok ? w : 0;
}

/* the unit bearings u1 = d1 / |d1|, u2 = d2 / |d2| of every pair, in one
 * pass without branches so that it vectorises (issue 22); a pair outside
 * the intra-camera ones may have a zero direction, whose NaN here is never
 * read (the passes below skip group < 0). The products as v * (1 / |v|),
 * as before. */
MCG_AVX2_CLONE
static void unit_bearings(int n, const double *restrict d1, const double *restrict d2,
                          double *restrict u1, double *restrict u2)
{
    int i, r;
    for (i = 0; i < 3 * n; i += 3) {
        double s1 = 1.0 / sqrt(dot3(d1 + i, d1 + i)), s2 = 1.0 / sqrt(dot3(d2 + i, d2 + i));
        for (r = 0; r < 3; r++) {
            u1[i + r] = d1[i + r] * s1;
            u2[i + r] = d2[i + r] * s2;
        }
    }
}

/* the sine and cosine of the angle between the unit bearings b and R a (as
 * numpy's arctan2(|R d1 x d2|, R d1 . d2) of geometry.rotation_fit) */
static inline void rotation_angle_terms(const double a[3], const double b[3], const double R[9],
                                 double *s, double *c)
{
    double ra[3], x[3];
    mat_vec(R, a, ra);
    cross3(ra, b, x);
    *s = sqrt(dot3(x, x));
    *c = dot3(ra, b);
}

/* the rotation-only statistic at R: the fraction of the n_intra
 * intra-camera pairs whose angle between d2 and R d1 is below lim. The
 * angle atan2(s, c) is needed only near the bound: for lim < 1.5 (< pi/2)
 * s < c tan(lim) (1 - 1e-9) puts it surely below and s > c tan(lim)
 * (1 + 1e-9) or c <= 0 surely above (atan2 and tan are accurate to a few
 * ulps, far inside the margin), so the count is that of atan2(s, c) < lim
 * exactly, without an atan2 per pair (issue 22) */
MCG_AVX2_CLONE
static void rotation_statistic(int n, const double *u1, const double *u2, const int *group,
                               const double R[9], double lim, int *n_intra, double *explained)
{
    int i, m = 0, inside = 0, fast = lim > 1e-100 && lim < 1.5;
    double tl = fast ? tan(lim) : 0.0, below = tl * (1.0 - 1e-9), above = tl * (1.0 + 1e-9);
    if (!fast) {
        for (i = 0; i < n; i++) {
            double s, c;
            if (group[i] < 0)
                continue;
            rotation_angle_terms(u1 + 3 * i, u2 + 3 * i, R, &s, &c);
            inside += atan2(s, c) < lim;
            m++;
        }
    } else {
        /* counted without branches, so that the pass vectorises (the
         * counts are integers: any order gives the same sums); the pairs
         * within the margin, if any, get their atan2 in a second pass */
        double Rl[9];
        long long cm = 0, cin = 0, unsure = 0;
        for (i = 0; i < 9; i++)
            Rl[i] = R[i];
        for (i = 0; i < n; i++) {
            double s, c;
            long long g = group[i] >= 0, below_ok, above_ok;
            rotation_angle_terms(u1 + 3 * i, u2 + 3 * i, Rl, &s, &c);
            below_ok = (c > 0.0) & (s < c * below);
            above_ok = (c > 0.0) & !(s > c * above);
            cm += g;
            cin += g & below_ok;
            unsure += g & !below_ok & above_ok;
        }
        m = (int)cm;
        inside = (int)cin;
        for (i = 0; unsure > 0 && i < n; i++) {
            double s, c;
            if (group[i] < 0)
                continue;
            rotation_angle_terms(u1 + 3 * i, u2 + 3 * i, Rl, &s, &c);
            if (c > 0.0 && !(s < c * below) && !(s > c * above))
                inside += atan2(s, c) < lim;
        }
    }
    *n_intra = m;
    *explained = m ? (double)inside / m : 0.0;
}

/* the median rotation-only angle at R of the intra-camera pairs (radians,
 * nan without any; ang: scratch of n doubles) */
static double median_angle_at(int n, const double *u1, const double *u2, const int *group,
                              const double R[9], double *ang)
{
    int i, m = 0;
    for (i = 0; i < n; i++) {
        double s, c;
        if (group[i] < 0)
            continue;
        rotation_angle_terms(u1 + 3 * i, u2 + 3 * i, R, &s, &c);
        ang[m++] = atan2(s, c);
    }
    return m ? median_inplace(ang, m) : NAN;
}

/* at least k distinct intra-camera pairs (all four rows and the camera
 * compared exactly)? O(k n) */
static int distinct_at_least(int n, const double *o1, const double *d1, const double *o2,
                             const double *d2, const int *group, int k, int *seen)
{
    int i, j, found = 0;
    if (k <= 0)
        return 1;
    for (i = 0; i < n && found < k; i++) {
        int same = 0;
        if (group[i] < 0)
            continue;
        for (j = 0; j < found && !same; j++) {
            int p = seen[j], c;
            same = group[p] == group[i];
            for (c = 0; c < 3 && same; c++)
                same = o1[3 * p + c] == o1[3 * i + c] && d1[3 * p + c] == d1[3 * i + c] &&
                       o2[3 * p + c] == o2[3 * i + c] && d2[3 * p + c] == d2[3 * i + c];
        }
        if (!same)
            seen[found++] = i;
    }
    return found >= k;
}

/* the noise level of the median residual med: noise_factor robust stds,
 * at least noise_floor */
static double level_of(double med, const mcg_static_options *o)
{
    double level = o->noise_factor * MAD_TO_STD * med;
    return level < o->noise_floor ? o->noise_floor : level;
}

/* the pairs of the cameras with at least min_rows of them (idx[0..m)
 * sorted by group): the residuals the noise level can have */
static int rows_of_fitted_cameras(const int *group, const int *idx, int m, int min_rows)
{
    int i = 0, rows = 0;
    while (i < m) {
        int j = i;
        while (j < m && group[idx[j]] == group[idx[i]])
            j++;
        if (j - i >= min_rows)
            rows += j - i;
        i = j;
    }
    return rows;
}

/* the noise level at R (noise_factor robust stds of the per-camera
 * residuals, at least noise_floor), 0 when no camera has min_rows pairs */
static int level_at(int n, const double *o1, const double *d1, const double *o2,
                    const double *d2, const int *group, const double R[9],
                    const mcg_static_options *o, double *res, double *work, double *level)
{
    double med;
    int used, st = static_noise(n, o1, d1, o2, d2, group, R, o->min_rows, o->samples, res,
                                &med, &used, work);
    *level = 0.0;
    if (st == MCG_OK && used) {
        *level = o->noise_factor * MAD_TO_STD * med;
        if (*level < o->noise_floor)
            *level = o->noise_floor;
    }
    return st;
}

/* the rotation tried i-th by the statistic: R_given (else R_fit), then --
 * without R_given -- R_est; NULL when there is no i-th */
static const double *rotation_tried(int i, const double *R_est, const double *R_given,
                                    const double *R_fit)
{
    if (i == 0)
        return R_given ? R_given : R_fit;
    return i == 1 && R_est && !R_given ? R_est : NULL;
}

/* the rotation-only statistic at R_test and out->noise_level into out (its
 * figures, R and decided_at = i); 1 if enough angles are explained (the
 * necessary condition of a static answer) */
static int explained_at(int n, const double *u1, const double *u2, const int *group,
                        const double *R_test, int i, const mcg_static_options *o,
                        mcg_static_result *out)
{
    int r;
    rotation_statistic(n, u1, u2, group, R_test, o->parallax_factor * out->noise_level,
                       &out->n_intra, &out->explained);
    out->decided_at = i;
    for (r = 0; r < 9; r++)
        out->R[r] = R_test[r];
    return out->n_intra >= o->min_pairs && out->n_intra > 0 && out->explained >= o->fraction;
}

/* the statistic at out->noise_level at each rotation tried, until one gives
 * a static answer (also min_distinct distinct intra-camera pairs);
 * out->is_static and the figures of the last rotation tried (u1, u2: the
 * unit bearings of the intra-camera pairs) */
static void explained_anywhere(int n, const double *o1, const double *d1, const double *o2,
                               const double *d2, const double *u1, const double *u2,
                               const int *group, const double *R_est,
                               const double *R_given, const mcg_static_options *o,
                               mcg_static_result *out, double *ang)
{
    const double *R_test;
    int i, distinct = -1, seen[64];
    out->is_static = 0;
    for (i = 0; !out->is_static && (R_test = rotation_tried(i, R_est, R_given, out->R_fit));
         i++) {
        if (!explained_at(n, u1, u2, group, R_test, i, o, out))
            continue;
        if (distinct < 0)
            distinct = distinct_at_least(n, o1, d1, o2, d2, group, o->min_distinct, seen);
        out->is_static = distinct;
    }
    /* the median angle only for the answer that reports it (a static rig) */
    out->median_angle =
        out->is_static ? median_angle_at(n, u1, u2, group, out->R, ang) : NAN;
}

/* explained_anywhere's statistic without its distinct-pairs condition and
 * median angle (a necessary condition of a static answer, for the bound of
 * mcg_static_check): 1 if enough angles are explained at some rotation
 * tried; out gets the figures of the last rotation tried, as
 * explained_anywhere reports a moving rig */
static int explained_somewhere(int n, const double *u1, const double *u2, const int *group,
                               const double *R_est, const double *R_given,
                               const mcg_static_options *o, mcg_static_result *out)
{
    const double *R_test;
    int i;
    out->is_static = 0;
    out->median_angle = NAN;
    for (i = 0; (R_test = rotation_tried(i, R_est, R_given, out->R_fit)); i++)
        if (explained_at(n, u1, u2, group, R_test, i, o, out))
            return 1;
    return 0;
}

int mcg_static_check(int n, const double *o1, const double *d1, const double *o2,
                     const double *d2, const int *group, const double *R_est,
                     const double *R_given, double noise_level, const mcg_static_options *opt,
                     mcg_static_result *out, double *work, size_t lwork)
{
    mcg_static_options o;
    size_t need;
    double B[9] = {0}, *res, *ang, *u1, *u2, levels[2];
    int i, r, c, st, n_intra = 0;
    if (!o1 || !d1 || !o2 || !d2 || !group || !out || (!work && lwork))
        return MCG_EINVAL;
    if (opt)
        o = *opt;
    else
        mcg_static_default_options(&o);
    need = mcg_static_check_work_size(n);
    if (need == 0 || !(isfinite(o.noise_factor) && o.noise_factor > 0.0) ||
        !(isfinite(o.noise_floor) && o.noise_floor >= 0.0) ||
        !(isfinite(o.default_level) && o.default_level > 0.0) ||
        !(isfinite(o.parallax_factor) && o.parallax_factor > 0.0) ||
        !(o.fraction >= 0.0 && o.fraction <= 1.0) || o.min_pairs < 0 || o.min_distinct < 0 ||
        o.min_distinct > 64)
        return MCG_EINVAL;
    /* noise_level: > 0 given (radians), 0 = estimate it */
    if (!(isfinite(noise_level) && noise_level >= 0.0))
        return MCG_EINVAL;
    if ((R_est && !all_finite(R_est, 9)) || (R_given && !all_finite(R_given, 9)))
        return MCG_EINVAL;
    st = check_rays(n, o1, d1, o2, d2, group, o.min_rows, o.samples);
    if (st != MCG_OK)
        return st;
    if (lwork < need)
        return MCG_ENOMEM;
    res = work + mcg_static_noise_work_size(n);
    ang = res + n;
    u1 = ang + n;
    u2 = u1 + 3 * (size_t)n;
    /* the best pure rotation: nearest rotation to sum d2 d1^T (identity
     * with fewer than two intra-camera pairs) */
    unit_bearings(n, d1, d2, u1, u2);
    for (i = 0; i < n; i++) {
        const double *a = u1 + 3 * i, *b = u2 + 3 * i;
        if (group[i] < 0)
            continue;
        for (r = 0; r < 3; r++)
            for (c = 0; c < 3; c++)
                B[3 * r + c] += b[r] * a[c];
        n_intra++;
    }
    /* rank < 2 (one bearing repeated): no rotation is determined, the
     * identity stands in and the distinct-pairs condition decides */
    if (n_intra < 2 || mcg_project_so3(B, out->R_fit) != MCG_OK) {
        for (i = 0; i < 9; i++)
            out->R_fit[i] = (i % 4 == 0) ? 1.0 : 0.0;
    }
    /* the noise level: the smaller of those at the first rotation (the
     * estimate's, else the given one) and at the pure rotation. The pure
     * rotation's comes first: it bounds the level from above, and a smaller
     * level only explains fewer angles, so when no rotation explains enough
     * of them at that bound the rig moved whatever the other level is (the
     * exact early exit of a moving rig: one noise computation, not two) */
    out->noise_from_default = 0;
    if (noise_level > 0.0) {
        out->noise_level = noise_level;
    } else {
        /* the level at the pure rotation, with an exact early exit for a
         * moving rig (issue 22: the per-camera fits are most of the test).
         * Once the cameras done hold more than half of the residuals any
         * camera could add (U_max: the rows of the cameras with min_rows
         * pairs), the median of all of them is at most the stop-th smallest
         * done, stop = floor(U_max / 2) + 1: both middle values of the
         * sorted residuals are then at most that value. The level at that
         * bound is an upper bound of the level, and the statistic only
         * explains fewer angles at a smaller level, so a rig that is
         * moving at the bound (at both rotations) is moving at the level:
         * the remaining cameras are not fitted. Otherwise they are, and the
         * test goes on as without the bound. */
        int *idx = (int *)work, m, pos = 0, done = 0, used, stop = 0;
        double *prod = work + 2 * ints_as_doubles((size_t)n) + 3 * (size_t)n;
        for (i = 0; i < n; i++)
            res[i] = -1.0;
        m = pairs_by_group(n, group, idx, idx + n);
        if (R_est || R_given)
            stop = rows_of_fitted_cameras(group, idx, m, o.min_rows) / 2 + 1;
        st = noise_cameras(o1, d1, o2, d2, group, out->R_fit, o.min_rows, o.samples, res, n,
                           work, m, &pos, stop, &done);
        if (st != MCG_OK)
            return st;
        if (pos < m) {
            used = gather_used(n, res, prod);
            if (used >= stop) {
                out->noise_level = level_of(select_kth_inplace(prod, used, stop - 1), &o);
                if (!explained_somewhere(n, u1, u2, group, R_est, R_given, &o, out))
                    return MCG_OK; /* moving at an upper bound of the level */
            }
            st = noise_cameras(o1, d1, o2, d2, group, out->R_fit, o.min_rows, o.samples, res,
                               n, work, m, &pos, 0, &done);
            if (st != MCG_OK)
                return st;
        }
        used = gather_used(n, res, prod);
        levels[1] = used ? level_of(median_inplace(prod, used), &o) : 0.0;
        if (levels[1] == 0.0) { /* no camera with min_rows pairs */
            out->noise_level = o.default_level;
            out->noise_from_default = 1;
        } else {
            out->noise_level = levels[1];
            if (R_est || R_given) {
                explained_anywhere(n, o1, d1, o2, d2, u1, u2, group, R_est, R_given, &o, out, ang);
                if (!out->is_static)
                    return MCG_OK; /* moving at the upper bound of the level */
                st = level_at(n, o1, d1, o2, d2, group, R_est ? R_est : R_given, &o, res, work,
                              &levels[0]);
                if (st != MCG_OK)
                    return st;
                if (levels[0] < out->noise_level)
                    out->noise_level = levels[0];
            }
        }
    }
    explained_anywhere(n, o1, d1, o2, d2, u1, u2, group, R_est, R_given, &o, out, ang);
    return MCG_OK;
}
