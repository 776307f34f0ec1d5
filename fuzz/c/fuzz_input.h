/*
 * fuzz_input.h -- decoding libFuzzer's byte string into the arguments of the
 * libmcgeom entry points (sizes, doubles, layouts), and the invariant checks
 * shared by the harnesses of fuzz/c/.
 *
 * The bytes are consumed front to back; once they run out every read returns
 * zero, so each input decodes to one well-defined call. Doubles come in
 * three flavours chosen by a selector byte, so that the fuzzer reaches both
 * the argument checks and the numerical code behind them:
 *   - "nice" values (most selectors): a 16-bit integer scaled to [-8, 8),
 *     which makes well-posed problems likely;
 *   - special values: 0, -0, +-1, NaN, +-inf, DBL_MIN, the smallest
 *     denormal, DBL_MAX, 1e150 and its neighbours, 1e-300, pi, ...;
 *   - raw IEEE-754 bit patterns (8 bytes), i.e. any double at all.
 * A finding is a crash, a sanitizer report, a timeout or a violated
 * invariant: FZ_CHECK prints what was violated and calls abort().
 */
#ifndef MCGEOM_FUZZ_INPUT_H
#define MCGEOM_FUZZ_INPUT_H

#include "mcgeom.h" /* mcg_rot_from_angle_axis (fz_scene_near) */

#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    const uint8_t *p;
    size_t n;
} fz_in;

static inline fz_in fz_make(const uint8_t *data, size_t size)
{
    fz_in in;
    in.p = data;
    in.n = size;
    return in;
}

static inline uint8_t fz_u8(fz_in *in)
{
    uint8_t v;
    if (in->n == 0)
        return 0;
    v = in->p[0];
    in->p++;
    in->n--;
    return v;
}

static inline uint16_t fz_u16(fz_in *in)
{
    uint16_t lo = fz_u8(in);
    return (uint16_t)(lo | ((uint16_t)fz_u8(in) << 8));
}

static inline uint64_t fz_u64(fz_in *in)
{
    uint64_t v = 0;
    int i;
    for (i = 0; i < 8; ++i)
        v |= (uint64_t)fz_u8(in) << (8 * i);
    return v;
}

/* An integer in [lo, hi] (hi - lo < 65536). */
static inline int fz_int(fz_in *in, int lo, int hi)
{
    unsigned span = (unsigned)(hi - lo) + 1u;
    return lo + (int)(fz_u16(in) % span);
}

/* A size: usually in [lo, hi], sometimes (1 in 16) one that every entry
 * point must reject, from {-1, 0, 2^21, INT32_MAX, INT32_MIN} (2^21 is above
 * the documented limits of rows, columns and rays, 2^20, except for
 * mcg_linear17's 2^26: not used there). *valid (may be NULL) tells whether
 * the size is in [lo, hi]. */
static inline int fz_size(fz_in *in, int lo, int hi, int *valid)
{
    uint8_t sel = fz_u8(in);
    int v;
    if ((sel & 15) == 15) {
        static const int bad[5] = {-1, 0, 1 << 21, 2147483647, -2147483647 - 1};
        v = bad[(sel >> 4) % 5];
    } else {
        v = fz_int(in, lo, hi);
    }
    if (valid)
        *valid = (v >= lo && v <= hi);
    return v;
}

static inline double fz_special(uint8_t k)
{
    static const double table[] = {
        0.0, -0.0, 1.0, -1.0, 0.5, 2.0, 3.141592653589793, 1.5707963267948966,
        1e-300, -1e-300, DBL_MIN, -DBL_MIN, 4.9406564584124654e-324, 1e-160,
        1e-8, 1e-16, 1e150, -1e150, 1.0000000000000002e150, 1e100, 1e200, DBL_MAX,
        -DBL_MAX, 1.0 + DBL_EPSILON, 1.0 - DBL_EPSILON / 2, 1e6, 1e-6, 0.0,
    };
    size_t nt = sizeof table / sizeof table[0];
    if (k % (nt + 3) == nt)
        return NAN;
    if (k % (nt + 3) == nt + 1)
        return INFINITY;
    if (k % (nt + 3) == nt + 2)
        return -INFINITY;
    return table[k % (nt + 3)];
}

/* One double: nice (selector < 224), special (< 248) or raw bits. */
static inline double fz_double(fz_in *in)
{
    uint8_t sel = fz_u8(in);
    if (sel < 224)
        return (double)(int16_t)fz_u16(in) / 4096.0;
    if (sel < 248)
        return fz_special(fz_u8(in));
    {
        uint64_t bits = fz_u64(in);
        double d;
        memcpy(&d, &bits, sizeof d);
        return d;
    }
}

/* A double that is always finite and moderate, for parameters that must be
 * valid for the call to go deeper (e.g. a tolerance): lo + u (hi - lo). */
static inline double fz_range(fz_in *in, double lo, double hi)
{
    return lo + (hi - lo) * ((double)fz_u16(in) / 65535.0);
}

static inline void fz_doubles(fz_in *in, double *x, size_t n)
{
    size_t i;
    for (i = 0; i < n; ++i)
        x[i] = fz_double(in);
}

/* The layout of an array: filled entry by entry (each a fz_double), or with
 * structure that random bytes rarely produce: rank-deficient (a copy of an
 * earlier row, up to a factor), nearly so (the same plus 1e-9 .. 1e-15 of
 * the row's own entries: singular values just above the rank cuts, where
 * fuzz_cls found Algorithm 3 losing its minimum), a constant, or rows
 * scaled by a huge or tiny factor (a graded matrix). rows x cols
 * row-major. */
static inline void fz_matrix(fz_in *in, double *a, size_t rows, size_t cols)
{
    uint8_t layout = fz_u8(in);
    size_t i, j;
    fz_doubles(in, a, rows * cols);
    switch (layout & 7) {
    case 1: /* rank deficient: row i = factor x row (i mod 2) */
        for (i = 2; i < rows; ++i)
            for (j = 0; j < cols; ++j)
                a[i * cols + j] = a[(i % 2) * cols + j] * (double)(i + 1);
        break;
    case 4: /* nearly rank deficient: the upper layout bits pick the size */
        {
            double rel = pow(10.0, -9.0 - (double)((layout >> 3) % 7));
            for (i = 2; i < rows; ++i)
                for (j = 0; j < cols; ++j)
                    a[i * cols + j] = a[(i % 2) * cols + j] * (double)(i + 1) +
                                      rel * a[i * cols + j];
        }
        break;
    case 2: /* constant */
        for (i = 0; i < rows * cols; ++i)
            a[i] = a[0];
        break;
    case 3: /* graded rows */
        for (i = 0; i < rows; ++i) {
            double f = pow(10.0, (double)((int)(i % 9) * 40 - 160));
            for (j = 0; j < cols; ++j)
                a[i * cols + j] *= f;
        }
        break;
    default:
        break;
    }
}

/* Work buffers: heap allocations of exactly the requested size, so ASan sees
 * any out-of-bounds access. fz_alloc(0) returns a valid 1-double buffer. */
static inline double *fz_alloc(size_t n)
{
    double *p;
    if (n > ((size_t)1 << 26))
        return NULL;
    p = (double *)malloc((n ? n : 1) * sizeof(double));
    if (p) {
        size_t i;
        for (i = 0; i < (n ? n : 1); ++i)
            p[i] = NAN; /* outputs must not depend on the buffers' contents */
    }
    return p;
}

#define FZ_CHECK(cond, ...)                                                    \
    do {                                                                       \
        if (!(cond)) {                                                         \
            fprintf(stderr, "INVARIANT VIOLATED %s:%d: %s: ", __FILE__,         \
                    __LINE__, #cond);                                          \
            fprintf(stderr, __VA_ARGS__);                                      \
            fputc('\n', stderr);                                               \
            abort();                                                           \
        }                                                                      \
    } while (0)

/* Small 3-vector / 3x3 helpers shared by the harnesses (the library keeps
 * its own static). */
static inline double fz_dot3(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static inline void fz_cross3(const double *a, const double *b, double *c)
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

/* c = a b for row-major 3x3 matrices (c must not alias a or b) */
static inline void fz_matmul3(const double a[9], const double b[9], double c[9])
{
    int i, j, k;
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) {
            double s = 0.0;
            for (k = 0; k < 3; ++k)
                s += a[3 * i + k] * b[3 * k + j];
            c[3 * i + j] = s;
        }
}

static inline int fz_all_finite(const double *x, size_t n)
{
    size_t i;
    for (i = 0; i < n; ++i)
        if (!isfinite(x[i]))
            return 0;
    return 1;
}

static inline int fz_status_known(int st)
{
    return st >= 0 && st <= 6;
}

/* max |x_i| and a Frobenius norm that does not overflow for finite x */
static inline double fz_maxabs(const double *x, size_t n)
{
    double m = 0.0;
    size_t i;
    for (i = 0; i < n; ++i)
        if (fabs(x[i]) > m)
            m = fabs(x[i]);
    return m;
}

/* |R R^T - I|_max and det R of a 3 x 3 row-major matrix */
static inline double fz_orth_err3(const double r[9])
{
    double e = 0.0;
    int i, j, k;
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) {
            double s = 0.0;
            for (k = 0; k < 3; ++k)
                s += r[3 * i + k] * r[3 * j + k];
            s -= (i == j) ? 1.0 : 0.0;
            if (fabs(s) > e || isnan(s))
                e = isnan(s) ? INFINITY : fabs(s);
        }
    return e;
}

static inline double fz_det3(const double r[9])
{
    return r[0] * (r[4] * r[8] - r[5] * r[7]) - r[1] * (r[3] * r[8] - r[5] * r[6]) +
           r[2] * (r[3] * r[7] - r[4] * r[6]);
}

static inline int fz_is_rotation(const double r[9], double tol)
{
    return fz_all_finite(r, 9) && fz_orth_err3(r) <= tol && fz_det3(r) > 0.5;
}

/* A random rotation from three decoded angles (in radians, nice range),
 * for harnesses that need a valid motion to go deep. */
static inline void fz_rotation(fz_in *in, double r[9])
{
    double w[3], th, k[3], c, s, v;
    int i, j;
    for (i = 0; i < 3; ++i)
        w[i] = fz_range(in, -1.5, 1.5);
    th = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    if (th < 1e-12) {
        for (i = 0; i < 9; ++i)
            r[i] = (i % 4 == 0) ? 1.0 : 0.0;
        return;
    }
    for (i = 0; i < 3; ++i)
        k[i] = w[i] / th;
    c = cos(th);
    s = sin(th);
    v = 1.0 - c;
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j)
            r[3 * i + j] = k[i] * k[j] * v + ((i == j) ? c : 0.0);
    r[1] -= k[2] * s;
    r[2] += k[1] * s;
    r[3] += k[2] * s;
    r[5] -= k[0] * s;
    r[6] -= k[1] * s;
    r[7] += k[0] * s;
}

/* Rays of n pairs (origins and directions at both times, each n x 3), each
 * array decoded as an arbitrary layout (fz_matrix). */
static inline void fz_rays(fz_in *in, size_t n, double *o1, double *d1, double *o2, double *d2)
{
    fz_matrix(in, o1, n, 3);
    fz_matrix(in, d1, n, 3);
    fz_matrix(in, o2, n, 3);
    fz_matrix(in, d2, n, 3);
}

/* A 3 x 3 matrix: nine arbitrary doubles or a rotation, as a byte says. */
static inline void fz_rotation_or_any(fz_in *in, double r[9])
{
    if (fz_u8(in) & 1)
        fz_doubles(in, r, 9);
    else
        fz_rotation(in, r);
}


/* A synthetic rig problem that is consistent most of the time, so that the
 * estimators get past their input checks into the numerics: ncams camera
 * centres c_k (in [-1, 1]^3), n scene points X (in front, depth 1..20), the
 * motion (R, t) with X2 = R X + t; pair i is seen from camera g = i % ncams
 * at time 1 and from camera g or (cross-camera, 1 in 4 pairs when
 * cross != 0) g + 1 at time 2: o1 = c_g, d1 = X - c_g, o2 = c_h, d2 = X2 - c_h.
 * group[i] (may be NULL) receives g. Then up to 3 entries of the rays are
 * replaced by arbitrary decoded doubles (NaN, inf, huge, ...) and some
 * bearings get noise, as a user's matcher would produce. Returns 1 if the
 * pairs are exact (no noise, nothing replaced), else 0. */
static inline int fz_scene(fz_in *in, int n, int ncams, int cross, const double R[9],
                            const double t[3], double *o1, double *d1, double *o2,
                            double *d2, int *group)
{
    double c[8 * 3];
    int i, k, nbad;
    double noise;
    if (ncams < 1)
        ncams = 1;
    if (ncams > 8)
        ncams = 8;
    for (k = 0; k < 3 * ncams; ++k)
        c[k] = fz_range(in, -1.0, 1.0);
    for (i = 0; i < n; ++i) {
        double X[3], X2[3];
        int g = i % ncams, h = g;
        if (cross && i % 4 == 3)
            h = (g + 1) % ncams;
        X[0] = fz_range(in, -5.0, 5.0);
        X[1] = fz_range(in, -5.0, 5.0);
        X[2] = fz_range(in, 1.0, 20.0);
        for (k = 0; k < 3; ++k)
            X2[k] = R[3 * k] * X[0] + R[3 * k + 1] * X[1] + R[3 * k + 2] * X[2] + t[k];
        for (k = 0; k < 3; ++k) {
            o1[3 * i + k] = c[3 * g + k];
            d1[3 * i + k] = X[k] - c[3 * g + k];
            o2[3 * i + k] = c[3 * h + k];
            d2[3 * i + k] = X2[k] - c[3 * h + k];
        }
        if (group)
            group[i] = g;
    }
    noise = (fz_u8(in) & 1) ? fz_range(in, 0.0, 1.0) : 0.0;
    noise = noise * noise * noise * 0.1; /* mostly tiny */
    for (i = 0; i < 3 * n; ++i) {
        d1[i] += noise * ((double)(i % 7) - 3.0) / 3.0;
    }
    nbad = fz_u8(in) % 4;
    for (k = 0; k < nbad && n > 0; ++k) {
        int which = fz_u8(in) % 4, at = fz_int(in, 0, 3 * n - 1);
        double v = fz_double(in);
        double *arr = which == 0 ? o1 : which == 1 ? d1 : which == 2 ? o2 : d2;
        arr[at] = v;
    }
    return noise == 0.0 && nbad == 0;
}

/* fz_scene at a decoded true motion (Rt: fz_rotation; tt in [-2, 2]^3; 1-8
 * cameras, cross-camera pairs or not) and a start (R, t) near it: Rt turned
 * by a decoded angle-axis of up to max_turn rad per component, tt shifted by
 * up to max_shift metres per axis -- the start of a refinement, the fit of a
 * leverage. Returns 0 when the turn is not a rotation (skip the input). */
static inline int fz_scene_near(fz_in *in, int n, double max_turn, double max_shift,
                                double *o1, double *d1, double *o2, double *d2,
                                double Rt[9], double tt[3], double R[9], double t[3])
{
    double dw[3], Rd[9];
    int i;
    fz_rotation(in, Rt);
    for (i = 0; i < 3; ++i)
        tt[i] = fz_range(in, -2.0, 2.0);
    {   /* decoded in this order (not as arguments of one call) */
        const int ncams = fz_int(in, 1, 8), cross = fz_u8(in) & 1;
        fz_scene(in, n, ncams, cross, Rt, tt, o1, d1, o2, d2, NULL);
    }
    for (i = 0; i < 3; ++i)
        dw[i] = fz_range(in, -max_turn, max_turn);
    if (mcg_rot_from_angle_axis(dw, Rd) != MCG_OK)
        return 0;
    fz_matmul3(Rd, Rt, R);
    for (i = 0; i < 3; ++i)
        t[i] = tt[i] + fz_range(in, -max_shift, max_shift);
    return 1;
}

/* The rays and the motion of a fit: mode 0 fz_scene_near's scene and start
 * (the true motion in Rt, tt when not NULL), mode 1 arbitrary rays, a
 * rotation or any 9 doubles, and any t. Returns 0 to skip the input. */
static inline int fz_fit_input(fz_in *in, int mode, int n, double max_turn, double max_shift,
                               double *o1, double *d1, double *o2, double *d2, double R[9],
                               double t[3])
{
    double Rt[9], tt[3];
    if (mode == 0)
        return fz_scene_near(in, n, max_turn, max_shift, o1, d1, o2, d2, Rt, tt, R, t);
    fz_rays(in, (size_t)n, o1, d1, o2, d2);
    fz_rotation_or_any(in, R);
    fz_doubles(in, t, 3);
    return 1;
}

/* Per-pair weights: none (returns 0, w all 1), in [0, 3] (1) or any doubles
 * (2), as a weighted fit's. */
static inline int fz_weights(fz_in *in, int n, double *w)
{
    int use_w = fz_u8(in) % 3, i;
    for (i = 0; i < n; ++i)
        w[i] = use_w == 1 ? fz_range(in, 0.0, 3.0) : use_w == 2 ? fz_double(in) : 1.0;
    return use_w;
}

#endif /* MCGEOM_FUZZ_INPUT_H */
