/* test_fuzz_regressions.c -- one check per finding of the libFuzzer harnesses
 * of fuzz/c/ (fuzz/README.md lists them), on the input that triggered it
 * (reduced to its meaning), so a fixed bug stays fixed. */
#include "mcgeom.h"
#include "../internal.h"
#include "testutil.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* fuzz_linalg: an angle-axis vector with finite components whose norm
 * overflows (-DBL_MAX, ...) gave a NaN matrix with MCG_OK. */
static void test_angle_axis_overflow(void)
{
    double w[3] = {-DBL_MAX, -1.3e232, DBL_MAX}, r[9];
    check_status(mcg_rot_from_angle_axis(w, r), MCG_EINVAL,
                 "rot_from_angle_axis: |w| > DBL_MAX rejected");
    w[0] = 1e300;
    w[2] = -1e300;
    check_status(mcg_rot_from_angle_axis(w, r), MCG_OK,
                 "rot_from_angle_axis: |w| = 1.4e300 still a rotation");
    check(isfinite(r[0] + r[1] + r[2] + r[3] + r[4] + r[5] + r[6] + r[7] + r[8]),
          "rot_from_angle_axis: |w| = 1.4e300 finite", 0.0, 0.0);
}

/* fuzz_linalg: a 9 x 3 matrix with a column of size 1e-8 next to one of
 * 1e150 (a graded matrix): the reflector of the small column was computed
 * from squares in the denormal range, Q lost its orthonormality (2.7e-9). */
static void test_qr_graded_columns(void)
{
    double a[27], q[27], r[9], w[64], e;
    int i;
    for (i = 0; i < 9; ++i) {
        a[3 * i] = (i % 2) ? 1e-8 * (i + 1) : 0.0;
        a[3 * i + 1] = 2.5 * (i + 1) - 0.3 * i * i;
        a[3 * i + 2] = (i % 2) ? 1e150 * (i + 1) : -1.27e126 * (i + 1);
    }
    check_status(mcg_qr(9, 3, a, q, r, w, 64), MCG_OK, "qr of a graded 9 x 3 matrix");
    e = orthonormality_error(q, 9, 3);
    check(e <= 1e-14, "qr of a graded matrix: |Q^T Q - I|", e, 1e-14);
}

/* fuzz_linalg (session 24): a 9 x 4 matrix whose entries span 5e-324 to
 * 3e304 (the smallest subnormal in most places). Scaled to max |a| < 1, the
 * last column's remaining part was subnormal, and the factor 2^s of the
 * tiny-column scaling (s > 1023) overflowed to inf: Q held NaN with MCG_OK. */
static void test_qr_subnormal_column(void)
{
    double a[36], q[36], r[16], w[128], e;
    int i;
    for (i = 0; i < 36; ++i)
        a[i] = 4.9406564584124654e-324;
    a[0] = 1e150;
    a[31] = -0.000244140625;
    a[32] = -7.269300888741212e+182;
    a[35] = -3.0173682326313768e+304;
    check_status(mcg_qr(9, 4, a, q, r, w, 128), MCG_OK, "qr with a subnormal column");
    e = orthonormality_error(q, 9, 4);
    check(e <= 1e-14, "qr with a subnormal column: |Q^T Q - I|", e, 1e-14);
}

/* fuzz_linear17: 15 rays of one central camera (centre (-1, -1, -1) at both
 * times) of which one has a component of 1e150 in both directions: the
 * Sampson terms of the refinement overflowed, cost_final was NaN with MCG_OK
 * (and a NaN cost lost the comparison with the other camera kind's
 * solution). The kernel must answer an error or a finite cost. */
static void test_linear17_overflowing_direction(void)
{
    static const double dd[15][6] = {
        {-4.0999999999999996, -4.0666666666666664, 1.9666666666666666, 0.2535726228569315, 4.297991319002084, -3.2310096112774858},
        {-4, -3.9666666666666668, 2.0666666666666669, 0.2535726228569315, 4.297991319002084, -3.2310096112774858},
        {-3.8999999999999999, -4.0999999999999996, 1.9333333333333333, 0.2535726228569315, 4.297991319002084, -3.2310096112774858},
        {-4.0333333333333332, -4, 2.0333333333333332, 0.2535726228569315, 4.297991319002084, -3.2310096112774858},
        {-3.9333333333333331, -3.8999999999999999, 1.8999999999999999, 0.2535726228569315, 4.297991319002084, -3.2310096112774858},
        {-4.0666666666666664, -4.0333333333333332, 19.360784313725489, -15.90208535980647, 10.584769117971284, -4.1626597823660081},
        {-1.5482642862592508, 5.2039215686274503, 19.46078431372549, -17.492563030809123, 7.8159283449408843, 4.7335191034598054},
        {5.0372549019607842, 5.0705882352941174, 19.327450980392154, -19.893523455561599, 1.5647157720538107, 4.1851491428173206},
        {5.1372549019607838, 5.170588235294117, 19.427450980392155, -19.893523455561599, 1.5647157720538107, 4.1851491428173206},
        {5.2372549019607835, 5.0372549019607842, 19.294117647058822, -19.893523455561599, 1.5647157720538107, 4.1851491428173206},
        {5.1039215686274506, 1e150, 19.394117647058824, -19.893523455561599, 1e150, 4.1851491428173206},
        {5.2039215686274503, 6.0966430151827264, 20.899999999999999, -21.487258347891995, 2.1095258792951332, 4.9524607061942181},
        {5.9333333333333336, -4.0311970702677957, 2, -3.3200651417843545, -5.0061183372946143, -4.0450496559657374},
        {6.0333333333333332, 6.0666666666666664, 21.100000000000001, -21.795824372837167, 1.3066382525994662, 4.8853873084400057},
        {5.9000000000000004, 5.9333333333333336, 20.966666666666665, -21.795824372837167, 1.3066382525994662, 4.8853873084400057},
    };
    double o1[45], d1[45], o2[45], d2[45];
    mcg_linear17_result res;
    int i, k, st;
    for (i = 0; i < 15; ++i)
        for (k = 0; k < 3; ++k) {
            o1[3 * i + k] = o2[3 * i + k] = -1.0;
            d1[3 * i + k] = dd[i][k];
            d2[3 * i + k] = dd[i][3 + k];
        }
    st = mcg_linear17(15, o1, d1, o2, d2, NULL, &res);
    check(st != MCG_OK || (isfinite(res.cost_final) && isfinite(res.cost_linear)),
          "linear17: a direction of 1e150 gives an error or a finite cost",
          st == MCG_OK ? res.cost_final : (double)st, 0.0);
}

/* fuzz_linear17: a central camera (all rays through one centre, gc_case
 * CENTRAL) with exact correspondences: the algebraic cost x^T M x rounds to
 * slightly below 0 and cost_final = sqrt(cost / n) was NaN with MCG_OK. */
static void test_linear17_central_exact_cost(void)
{
    double o1[3 * 55], d1[3 * 55], o2[3 * 55], d2[3 * 55], w[3], R[9], t[3];
    int trial, i, k, bad = 0, ok = 0;
    mcg_linear17_result res;
    for (trial = 0; trial < 200; ++trial) {
        double c[3] = {2 * urand() - 1, 2 * urand() - 1, 2 * urand() - 1};
        for (k = 0; k < 3; ++k) {
            w[k] = 0.3 * (2 * urand() - 1);
            t[k] = 2 * (2 * urand() - 1);
        }
        mcg_rot_from_angle_axis(w, R);
        for (i = 0; i < 55; ++i) {
            double X[3] = {10 * urand() - 5, 10 * urand() - 5, 1 + 19 * urand()};
            for (k = 0; k < 3; ++k) {
                o1[3 * i + k] = o2[3 * i + k] = c[k];
                d1[3 * i + k] = X[k] - c[k];
                d2[3 * i + k] = R[3 * k] * X[0] + R[3 * k + 1] * X[1] + R[3 * k + 2] * X[2] +
                                t[k] - c[k];
            }
        }
        if (mcg_linear17(55, o1, d1, o2, d2, NULL, &res) != MCG_OK)
            continue;
        ++ok;
        if (!isfinite(res.cost_final) || !isfinite(res.cost_linear) || isnan(res.scale_rel_std))
            ++bad;
    }
    check(ok > 0 && bad == 0, "linear17: central exact data, costs never NaN (of MCG_OK)",
          (double)bad, 0.0);
}

/* fuzz_linf_local: n < 0 computed the work layout (work + 8 n) before
 * rejecting n: a pointer overflow (undefined behaviour; UBSan reports it,
 * the plain build passed by luck). Now MCG_EINVAL before any arithmetic. */
static void test_linf_local_negative_n(void)
{
    double u[3] = {0, 0, 1}, R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, t[3] = {0, 0, 0}, w[9], f;
    int steps;
    check_status(mcg_linf_local(-1, u, u, u, u, R, t, 1.0, 0.1, 5, w, &f, &steps), MCG_EINVAL,
                 "linf_local: n = -1 rejected");
    check_status(mcg_linf_local(-2147483647 - 1, u, u, u, u, R, t, 1.0, 0.1, 5, w, &f, &steps),
                 MCG_EINVAL, "linf_local: n = INT_MIN rejected");
}

/* fuzz_bnb: one camera, 5 near-exact pairs, tol 5.4e-5, polish on: the
 * polish bisected f from a floor of (lower bound - 2 tol) < 0, the relaxed
 * tests passed at negative bounds and linf = lower_bound = -7.7e-5 came
 * back with MCG_OK (the decoded input, exact hexadecimal values). */
static void test_bnb_polish_nonnegative(void)
{
    static const double d1[15] = {
        -0x1.ff81ff81ff82p+1, 0x1.6d17ed17ed17fp+2, 0x1.89e289e289e28p+3,
        -0x1.fb8ffb8ffb9p+1, 0x1.5064506450645p+2, 0x1.2600e600e600ep+3,
        -0x1.48a148a148a2p-4, -0x1.3421342134216p-2, 0x1.26ee66ee66ee6p+3,
        -0x1.48a148a148a2p-4, -0x1.3421342134216p-2, 0x1.c3ffc3ffc3ffcp+0,
        -0x1.bb98bb98bb98cp+1, 0x1.26ca26ca26ca2p+1, 0x1.9eb67eb67eb68p+3,
    };
    static const double a1[15] = {
        0x1.28fp+1, -0x1.8e178e178e179p-1, -0x1.072p+0,
        0x1.919p+2, -0x1.8e178e178e179p-1, -0x1.87ff87ff87ff8p-1,
        -0x1.ff13ff13ff14p-1, -0x1.8e178e178e179p-1, -0x1.87ff87ff87ff8p-1,
        -0x1.ff13ff13ff14p-1, -0x1.8e178e178e179p-1, -0x1.87ff87ff87ff8p-1,
        -0x1.ff13ff13ff14p-1, -0x1.8e178e178e179p-1, -0x1.87ff87ff87ff8p-1,
    };
    static const double d2[15] = {
        0x1.d124d2992d6acp-3, -0x1.0e80ce833035ep-2, 0x1.dce9c1542673ap+3,
        -0x1.ddc38d78f6efp-2, 0x1.a2031d386e84dp-1, 0x1.80bf00774f19ap+3,
        0x1.17b44b41e90c6p+0, -0x1.368d4c5295adep+2, 0x1.14a8957fffb88p+3,
        -0x1.f59f1d52d737p-3, -0x1.58b89179f274p+0, 0x1.1aac6d9b506ep+1,
        -0x1.959689818c49p-2, -0x1.caeb34effdbc4p+1, 0x1.bf48edfe5e6p+3,
    };
    static const double a2[15] = {
        -0x1.ff13ff13ff14p-1, -0x1.8e178e178e179p-1, -0x1.87ff87ff87ff8p-1,
        -0x1.ff13ff13ff14p-1, -0x1.8e178e178e179p-1, -0x1.87ff87ff87ff8p-1,
        -0x1.ff13ff13ff14p-1, -0x1.8e178e178e179p-1, -0x1.87ff87ff87ff8p-1,
        -0x1.ff13ff13ff14p-1, -0x1.8e178e178e179p-1, -0x1.87ff87ff87ff8p-1,
        -0x1.ff13ff13ff14p-1, -0x1.8e178e178e179p-1, -0x1.87ff87ff87ff8p-1,
    };
    static const double R0[9] = {0x1.919p+2, 0x1.919p+2, 0x1.9p-6, 0x1.b74p-1, -0x1.62c8p+1, 0x1.9258p+2, 0x0p+0, 0x0p+0, 0x0p+0};
    int group[5] = {0, 0, 0, 0, 0};
    mcg_bnb_options opt;
    mcg_bnb_result res;
    static double work[1 << 16];
    size_t ws;
    int st;
    mcg_bnb_default_options(&opt);
    opt.resolution = 0x1.47ae147ae147bp-7;
    opt.tol = 0x1.c1ce8a96b25aap-15;
    opt.max_blocks = 115;
    opt.max_queue = 1701;
    opt.grid = 1;
    opt.preemptive = 1;
    opt.working_sets = 1;
    opt.polish_tol = 0x1.ed7373a856892p-15;
    opt.bound_steps = 0;
    ws = mcg_bnb_work_size(5, 1, &opt);
    check(ws > 0 && ws <= sizeof work / sizeof work[0], "bnb polish case: work size", (double)ws,
          0.0);
    st = mcg_bnb_linf(5, d1, a1, d2, a2, group, 1, R0, &opt, &res, work, ws);
    check_status(st, MCG_OK, "bnb polish case: status");
    check(res.linf >= 0.0 && res.lower_bound >= 0.0 && res.lower_bound <= res.linf,
          "bnb polish case: 0 <= lower_bound <= linf", res.linf, 0.0);
}

/* fuzz_linalg (long run): a 2 x 5 matrix with an entry of 1.8e308 gave
 * MCG_OK with a non-finite V; now MCG_ENUMERIC or finite output. */
static void test_svd_near_dbl_max(void)
{
    double a[10] = {0.0022, 1.04, 1.0, 1.0, 1.7976931348623157e308, 1.0, 0.0, 0.0, 0.0, 0.0};
    double s[5], v[25], w[512];
    int st = mcg_svd(2, 5, a, NULL, s, v, w, 512), ok = 1, i;
    if (st == MCG_OK)
        for (i = 0; i < 25; ++i)
            ok = ok && isfinite(v[i]) && (i >= 5 || isfinite(s[i]));
    check(st == MCG_ENUMERIC || (st == MCG_OK && ok), "svd near DBL_MAX: finite or MCG_ENUMERIC",
          (double)st, 0.0);
}

/* fuzz_cone (long run): with a small max_iterations, the budget was spent by
 * the first active-set rounds and a later round still ran its pi/2
 * feasibility test, so res.iterations came out above max_iterations (12 >
 * 11). The decoded input of the finding (11 cones, options as decoded). */
static void test_cone_iteration_budget(void)
{
    static const double apex[33] = {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, -0.92971694514381631, -1, -0.99218738078889146, -1, 0.84313725490196068, 1, 1, 0.33333333333333326};
    static const double axis[33] = {-0.041147478446631573, 0.066666666666666666, 0.066666666666666666, 0.066666666666666666, 0.066666666666666666, 0.066666666666666666, -4.06103515625, 0.066666666666666666, 0.066666666666666666, 0.066666666666666666, 0.066666666666666666, 0.066666666666666666, 0.066666666666666666, 0.066666666666666666, 0.066666666666666666, 0.066666666666666666, 0.066666666666666666, 0.066666666666666666, 0.066666666666666666, 0.066666666666666666, 0.066666666666666666, 0.066666666666666666, 0.066666666666666666, 0.066666666666666666, 0.066666666666666666, 1.8630502784771497, 1.9333333333333333, 2.0088553190407161, 1.9552859795020472, 0.22352941176470598, 0.066666666666666666, -5.33349609375, 0.68888888888888899};
    mcg_cone_options o;
    mcg_cone_result res;
    int st;
    mcg_cone_default_options(&o);
    o.tolerance = 0.0066666666670000003;
    o.abs_tolerance = 9.9999999999999998e-13;
    o.max_iterations = 11;
    o.max_newton = 91;
    o.max_radius = 1000000;
    o.active_tolerance = 1e-08;
    st = mcg_cone_linf(11, apex, axis, &o, &res);
    check(st == MCG_OK || st == MCG_EINFEASIBLE, "cone: the finding's input solved", (double)st,
          0.0);
    check(res.iterations <= o.max_iterations, "cone: iterations <= max_iterations (11)",
          (double)res.iterations, (double)o.max_iterations);
}

/* fuzz_rays (long run): bearings nearly parallel or anti-parallel (up to
 * 1.7e-4 rad) and wide error bounds: |y|^2 came from [1 c; c 1] [p; q] =
 * [sa; sb] in the basis (a, b), which cancels there, and the normals had
 * |n|^2 = 0.99999 (planes off by 1e-5) with MCG_OK. Three of the finding's
 * decoded inputs. */
static void test_wedge_near_parallel(void)
{
    static const double in[3][8] = {
        {0, 0, -0.0625, -0.000244140625, 1.9305930352295117e-197, 1.443115234375,
         1.443115234375, 1.443115234375},
        {0, 4.249755859375, 0, -0.000244140625, -6.375, -0.000244140625, 0.313720703125,
         0.313720703125},
        {0, 0.690185546875, 0.690185546875, 0.002685546875, -7.309814453125, -7.309814453125,
         0.690185546875, 0.690185546875}};
    double n1[3], n2[3], worst = 0.0;
    int k, ok = 0;
    for (k = 0; k < 3; ++k) {
        if (mcg_wedge_normals(in[k], in[k] + 3, in[k][6], in[k][7], n1, n2) != MCG_OK)
            continue;
        ++ok;
        worst = fmax(worst, fabs(n1[0] * n1[0] + n1[1] * n1[1] + n1[2] * n1[2] - 1.0));
        worst = fmax(worst, fabs(n2[0] * n2[0] + n2[1] * n2[1] + n2[2] * n2[2] - 1.0));
    }
    check(ok == 3, "wedge: the finding's inputs give wedges", (double)ok, 3.0);
    check(worst <= 1e-12, "wedge: unit normals there", worst, 1e-12);
}

/* fuzz_rays (CI, session 11): axes 1.4e-8 rad from parallel (v = -0.33 x,
 * vp = (1, 1e-8, 1e-8), eps 1e-8, epsp 0) gave MCG_OK with normals whose
 * rounding (~1e-16 / sin alpha) put a t of the cones 1.3e-8 |t| on the wrong
 * side of both planes. Within 1e-6 rad of parallel there is now no wedge;
 * just above it the planes still hold every t of the cones. */
static void test_wedge_tiny_angle(void)
{
    const double v[3] = {-0.325927734375, 0.0, 0.0}, vp[3] = {1.0, 1e-8, 1e-8};
    const double vq[3] = {-0.325927734375, 0.0, 0.0}, vpq[3] = {1.0, 3e-6, 0.0};
    const double nv = 0.325927734375, nvp = sqrt(1.0 + 9e-12), l = 9.06;
    double n1[3], n2[3], worst = INFINITY;
    int k;
    check(mcg_wedge_normals(v, vp, 1e-8, 0.0, n1, n2) == MCG_EDEGENERATE,
          "wedge: axes 1.4e-8 rad apart give no wedge", 0.0, 0.0);
    check(mcg_wedge_normals(vq, vpq, 1e-7, 0.0, n1, n2) == MCG_OK,
          "wedge: axes 3e-6 rad apart, half-angle 1e-7: a wedge", 0.0, 0.0);
    /* t = lp vp / |vp| - l v / |v| (the cones' axes), lp = 1 .. 10, l = 9.06:
     * the harness's bound is -1e-9 (l + lp) */
    for (k = 1; k <= 10; ++k) {
        double t[3], lp = (double)k;
        int i;
        for (i = 0; i < 3; ++i)
            t[i] = lp * vpq[i] / nvp - l * vq[i] / nv;
        worst = fmin(worst, fmin(n1[0] * t[0] + n1[1] * t[1] + n1[2] * t[2],
                                 n2[0] * t[0] + n2[1] * t[1] + n2[2] * t[2]) / (l + lp));
    }
    check(worst >= -1e-9, "wedge: the axes' t on the inner side of both planes (/ (l + lp))",
          worst, -1e-9);
}

/* fuzz_linear17: exact data that hardly move a cross-camera rig (R = I,
 * |t| ~ 1e-4 of the rig) or repeat rays (a decoder out of bytes: the tail of
 * the points identical) gave MCG_OK, an "observable" scale and residuals up to
 * 0.1 rad: (0, I) was nearly annihilated by every row and taken for the
 * structural null vector of a locally-central rig, or A had two null vectors
 * while the reduced system looked well ranked. Scenes built like the
 * harness's fz_scene: MCG_OK with an observable scale must fit exact data. */
static double lcg_uniform(unsigned long *s, double lo, double hi)
{
    *s = *s * 6364136223846793005UL + 1442695040888963407UL;
    return lo + (hi - lo) * (double)((*s >> 11) & 0xFFFFFUL) / (double)0xFFFFFUL;
}

static void test_linear17_near_static_and_repeated(void)
{
    enum { N = 96, SCENES = 1500 };
    static double o1[3 * N], d1[3 * N], o2[3 * N], d2[3 * N], r[N];
    unsigned long s = 12345UL;
    int sc, observable = 0, wrong = 0, degenerate = 0;
    double worst_wrong = 0.0;
    for (sc = 0; sc < SCENES; ++sc) {
        double c[8 * 3], t[3], R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, tn;
        int n = 20 + (int)lcg_uniform(&s, 0.0, 75.99), ncams = 2 + (int)lcg_uniform(&s, 0, 6.99);
        int ndist = 1 + (int)lcg_uniform(&s, 0.0, n - 1.01), i, k, st;
        int cross = lcg_uniform(&s, 0, 1) < 0.8;
        mcg_linear17_result res;
        tn = pow(10.0, -lcg_uniform(&s, 1.0, 4.5));
        for (k = 0; k < 3; ++k)
            t[k] = tn * lcg_uniform(&s, -1.0, 1.0);
        for (k = 0; k < 3 * ncams; ++k)
            c[k] = lcg_uniform(&s, -1.0, 1.0);
        if (lcg_uniform(&s, 0, 1) < 0.7) /* two cameras nearly coincide */
            for (k = 0; k < 3; ++k)
                c[3 + k] = c[k] + 3e-5 * (double)((int)lcg_uniform(&s, 0, 4.99) - 2);
        for (i = 0; i < n; ++i) {
            static double X[3];
            int g = i % ncams, h = (cross && i % 4 == 3) ? (g + 1) % ncams : g;
            if (i <= ndist) {
                X[0] = lcg_uniform(&s, -5.0, 5.0);
                X[1] = lcg_uniform(&s, -5.0, 5.0);
                X[2] = lcg_uniform(&s, 1.0, 20.0);
            }
            for (k = 0; k < 3; ++k) {
                o1[3 * i + k] = c[3 * g + k];
                d1[3 * i + k] = X[k] - c[3 * g + k];
                o2[3 * i + k] = c[3 * h + k];
                d2[3 * i + k] = X[k] + t[k] - c[3 * h + k];
            }
        }
        (void)R;
        st = mcg_linear17(n, o1, d1, o2, d2, NULL, &res);
        if (st == MCG_EDEGENERATE)
            ++degenerate;
        if (st != MCG_OK || !res.scale_observable)
            continue;
        ++observable;
        if (mcg_gec_residuals(n, o1, d1, o2, d2, res.R, res.t, r) == MCG_OK) {
            double w = 0.0;
            for (i = 0; i < n; ++i)
                w = fmax(w, fabs(r[i]));
            if (w > 1e-5) {
                ++wrong;
                worst_wrong = fmax(worst_wrong, w);
            }
        }
    }
    printf("linear17 near-static/repeated scenes: %d observable, %d degenerate, %d wrong "
           "(worst %.3g rad)\n", observable, degenerate, wrong, worst_wrong);
    check(observable > SCENES / 3, "linear17: most near-static scenes still solved",
          (double)observable, SCENES / 3.0);
    check(wrong == 0, "linear17: an observable scale fits exact data", (double)wrong, 0.0);
}

/* fuzz_linear17 (300 s run, finding 19): exact data of three cameras
 * whose centres are 1.2e-4 apart in two of them, 18 distinct intra-camera
 * rays (95 with repeats): A_R's next eigenvalues 1.8e-10 and 9.6e-10 of
 * the largest were inverted as non-structural, the reduced system's E was
 * a mix, and the motion came out 1.6 deg off (residuals up to 3.3e-3 rad)
 * with its scale "observable". Now the kind read with those eliminated
 * (locally central and axial) is solved too and the lower cost kept: the
 * exact motion. The rays as the harness decoded them (o1, d1, o2, d2). */
static const double F19_RAYS[18][12] = {
    {0.2078431372549019, 0.2078431372549019, 0.2078431372549019, -5.207843137254902, -5.207843137254902, 0.7921568627450981, 0.2078431372549019, 0.2078431372549019, 0.2078431372549019, -3.326591519171399, -0.3499668567734545, -5.972498250566226},
    {0.2078431372549019, 0.2078431372549019, 0.2078431372549019, -4.16046387426566, -5.203265430685893, 18.63566033417258, 0.2078431372549019, 0.2078431372549019, 0.2078431372549019, -19.610178411242433, -1.0409777213495275, 1.3660944158918393},
    {0.2078431372549019, 0.2078431372549019, 0.2078431372549019, -2.864057373922331, -5.176104371709774, 0.7921568627450981, 0.2078431372549019, 0.2078431372549019, 0.2078431372549019, -2.6588689369399585, -1.8474346796472514, -4.297363710812909},
    {0.2078431372549019, 0.2078431372549019, 0.2078431372549019, 0.8313725490196078, 0.8313725490196078, 12.266666666666667, 0.2078431372549019, 0.2078431372549019, 0.2078431372549019, -10.841630440637203, 0.31345721517396785, 6.180389717344739},
    {0.2078431372549019, 0.2078431372549019, 0.2078431372549019, 3.537254901960785, 3.537254901960785, 12.286671244373236, 0.2078431372549019, 0.2078431372549019, 0.2078431372549019, -9.450311033342157, 0.6148740812594684, 9.73248444845335},
    {0.2078431372549019, 0.2078431372549019, 0.2078431372549019, 3.537254901960785, 3.537254901960785, 17.407843137254904, 0.2078431372549019, 0.2078431372549019, 0.2078431372549019, -14.208758269086168, 0.6107056629945666, 11.625514845824332},
    {0.2078431372549019, 0.20796520943007546, 0.2078431372549019, -5.207843137254902, -5.207965209430076, 0.7921568627450981, 0.2078431372549019, 0.20796520943007546, 0.2078431372549019, -3.326591519171399, -0.3500889289486281, -5.972498250566226},
    {0.2078431372549019, 0.20796520943007546, 0.2078431372549019, -1.4237582970931564, 3.5371328297856115, 17.407843137254904, 0.2078431372549019, 0.20796520943007546, 0.2078431372549019, -15.606021152939654, 3.8313218213009472, 8.12035384448539},
    {0.2078431372549019, 0.20796520943007546, 0.2078431372549019, -0.6763714045929656, -4.865094987411307, 8.773693446250096, 0.2078431372549019, 0.20796520943007546, 0.2078431372549019, -9.384440684673136, -3.0376711097669213, 0.38643938053756366},
    {0.2078431372549019, 0.20796520943007546, 0.2078431372549019, 0.8313725490196078, 0.8312504768444342, 12.266666666666667, 0.2078431372549019, 0.20796520943007546, 0.2078431372549019, -10.841630440637203, 0.3133351429987943, 6.180389717344739},
    {0.2078431372549019, 0.20796520943007546, 0.2078431372549019, 0.8313725490196078, 3.526604104676891, 17.407843137254904, 0.2078431372549019, 0.20796520943007546, 0.2078431372549019, -14.973387115559213, 2.359260603938983, 9.707343426753724},
    {0.2078431372549019, 0.20796520943007546, 0.2078431372549019, 2.51108567940795, -5.207965209430076, 5.294926375219348, 0.2078431372549019, 0.20796520943007546, 0.2078431372549019, -5.336410642183705, -5.364957983848233, 1.1456834564541962},
    {0.2078431372549019, 0.9931334401464866, -0.9926756694895857, -5.207843137254902, -5.993133440146487, 1.9926756694895857, 0.2078431372549019, 0.9931334401464866, -0.9926756694895857, -3.326591519171399, -1.1352571596650392, -4.771979443821738},
    {0.2078431372549019, 0.9931334401464866, -0.9926756694895857, -0.2077668421454184, -5.989013504234379, 20.298313878080414, 0.2078431372549019, 0.9931334401464866, -0.9926756694895857, -18.926418501069026, -4.393121892098895, 5.529908037345516},
    {0.2078431372549019, 0.9931334401464866, -0.9926756694895857, 0.8313725490196078, -4.055542839703975, 13.424567025253682, 0.2078431372549019, 0.9931334401464866, -0.9926756694895857, -11.78397574696613, -3.5915312534482378, 4.8900023927333045},
    {0.2078431372549019, 0.9931334401464866, -0.9926756694895857, 0.8313725490196078, 0.04608224612802303, 13.430075532158389, 0.2078431372549019, 0.9931334401464866, -0.9926756694895857, -10.807148938928913, -0.471802881788161, 7.367190912514076},
    {0.2078431372549019, 0.9931334401464866, -0.9926756694895857, 0.8313725490196078, 0.04608224612802303, 13.467185473411154, 0.2078431372549019, 0.9931334401464866, -0.9926756694895857, -10.841630440637203, -0.4718330877176169, 7.380908524089227},
    {0.2078431372549019, 0.9931334401464866, -0.9926756694895857, 2.091920347905699, 2.7519645990692005, 18.60836194399939, 0.2078431372549019, 0.9931334401464866, -0.9926756694895857, -14.615834857295452, 0.76374067134564, 11.804845014383456}
};
static const int F19_FIRST[18] = {15, 9, 3, 16, 10, 5, 17, 7, 4, 14, 11, 1, 13, 8, 2, 12, 6, 0};

static void test_linear17_nearly_axial_locally_central(void)
{
    enum { N = 95 };
    static double o1[3 * N], d1[3 * N], o2[3 * N], d2[3 * N], r[N];
    const double R[9] = {0.28164869307744289, 0.23940392780873987, -0.92917155199538681,
                         -0.64920976849965739, 0.76060897572745978, -0.00081395788934479629,
                         0.70654135772252535, 0.60345649834314652, 0.36964789250723223};
    const double t[3] = {0.41568627450980378, 0.41568627450980378, 0.41568627450980378};
    mcg_linear17_result res;
    double worst = 0.0, truth = 0.0;
    int i, k, st;
    for (i = 0; i < N; ++i) {
        static const int tail[3] = {12, 6, 0};
        const double *row = F19_RAYS[i < 18 ? F19_FIRST[i] : tail[(i - 18) % 3]];
        for (k = 0; k < 3; ++k) {
            o1[3 * i + k] = row[k];
            d1[3 * i + k] = row[3 + k];
            o2[3 * i + k] = row[6 + k];
            d2[3 * i + k] = row[9 + k];
        }
    }
    if (mcg_gec_residuals(N, o1, d1, o2, d2, R, t, r) == MCG_OK)
        for (i = 0; i < N; ++i)
            truth = fmax(truth, fabs(r[i]));
    check(truth < 1e-12, "finding 19: the rays are exact for the true motion", truth, 1e-12);
    st = mcg_linear17(N, o1, d1, o2, d2, NULL, &res);
    if (st == MCG_OK && mcg_gec_residuals(N, o1, d1, o2, d2, res.R, res.t, r) == MCG_OK)
        for (i = 0; i < N; ++i)
            worst = fmax(worst, fabs(r[i]));
    check(st == MCG_OK && worst < 1e-9,
          "finding 19: nearly axial locally-central rig solved exactly", worst, 1e-9);
}

/* fuzz_linear17 (240 s run, against the first form of finding 19's fix,
 * which took the near kind's motion also where the kind read at rank_rtol
 * gave none): exact data of 29 rays, four distinct centres of which three
 * lie within 3e-4 of each other. At rank_rtol the data determine no E
 * (MCG_EDEGENERATE); the near kind's elimination only approximates them,
 * and its motion (0.07 deg off, residuals 3e-4 rad) came back
 * "observable". The harness's invariant: no motion, or one that is not
 * called observable, or one that fits the exact data. */
static const double F19B_RAYS[29][12] = {
    {0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 0.47843137254901946, 0.47843137254901946, 11.913725490196079, 0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 11.522424913514937, -1.5264419574717267, 6.327868081732083},
    {0.5607843137254902, -0.15797665369649805, 0.5607843137254902, 0.47843137254901946, 1.1971923399710076, 12.062165255207143, 0.5607843137254902, -0.15797665369649805, 0.5607843137254902, 11.65129758428329, -0.8483693701625902, 6.3892737352939815},
    {0.5610284580758373, 0.5607843137254902, 0.5607843137254902, 0.4781872281986723, 0.47843137254901946, 11.913725490196079, 0.5610284580758373, 0.5607843137254902, 0.5607843137254902, 11.52218076916459, -1.5264419574717267, 6.327868081732083},
    {0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 0.47843137254901946, 0.47843137254901946, 11.913725490196079, 0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 11.522424913514937, -1.5264419574717267, 6.327868081732083},
    {0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 0.47843137254901946, 0.47843137254901946, 11.913725490196079, 0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 11.522424913514937, -1.5264419574717267, 6.327868081732083},
    {0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 0.47843137254901946, 0.47843137254901946, 11.913725490196079, 0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 11.522424913514937, -1.5264419574717267, 6.327868081732083},
    {0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 0.47843137254901946, 0.47843137254901946, 0.4838635843442436, 0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 1.5992292643519386, 1.6065633112178526, 1.599632757465873},
    {0.5607232776379034, 0.5607843137254902, 0.5607843137254902, -3.02558937972076, 3.6191958495460437, 15.033569848172734, 0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 11.9145719864944, -4.124540225573284, 11.325119882462584},
    {0.5607843137254902, 0.5607843137254902, 0.5607843137254902, -2.626474402990768, -1.029312581063554, 1.09066910811017, 0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 1.2829498468880074, -1.8791026518108256, 1.4206222198417517},
    {0.5607843137254902, -0.15797665369649805, 0.5607843137254902, -1.3599755855649651, 5.119066147859923, 19.43921568627451, 0.5607843137254902, -0.15797665369649805, 0.5607843137254902, 16.199585178654388, -2.844164919417355, 13.354299755031672},
    {0.5610284580758373, 0.5607843137254902, 0.5607843137254902, 4.438971541924163, -5.486625467307546, 12.537056534676127, 0.5610284580758373, 0.5607843137254902, 0.5607843137254902, 15.362423798991848, -0.7262095630110663, 0.30537535360820134},
    {0.5607843137254902, 0.5607843137254902, 0.5607843137254902, -4.35898374914168, 0.46637674525062933, 17.523704890516516, 0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 14.420618149637193, -7.268918057573119, 10.001700338583278},
    {0.5607843137254902, 0.5607843137254902, 0.5607843137254902, -5.560631723506523, -2.801495384145876, 11.913725490196079, 0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 9.9805077553624, -8.126265368565507, 5.190755498389379},
    {0.5607843137254902, 0.5607843137254902, 0.5607843137254902, -0.3028305485618372, 0.47843137254901946, 11.913725490196079, 0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 11.203343785779477, -2.204719172041993, 6.5480894328670125},
    {0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 0.47843137254901946, 4.43921568627451, 19.43921568627451, 0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 16.93945490178279, -1.95075855637535, 12.869775800526968},
    {0.5607232776379034, 0.5607843137254902, 0.5607843137254902, 4.439276722362097, 4.43921568627451, 19.43921568627451, 0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 18.557108970655708, 1.4879214550700424, 11.753313767048574},
    {0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 4.43921568627451, 4.43921568627451, 19.43921568627451, 0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 18.557108970655708, 1.4879214550700424, 11.753313767048574},
    {0.5607843137254902, -0.15797665369649805, 0.5607843137254902, 4.43921568627451, 5.157976653696498, 19.43921568627451, 0.5607843137254902, -0.15797665369649805, 0.5607843137254902, 18.557108970655708, 2.2066824224920305, 11.753313767048574},
    {0.5610284580758373, 0.5607843137254902, 0.5607843137254902, 4.438971541924163, 4.43921568627451, 19.43921568627451, 0.5610284580758373, 0.5607843137254902, 0.5607843137254902, 18.55686482630536, 1.4879214550700424, 11.753313767048574},
    {0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 4.43921568627451, 4.43921568627451, 19.43921568627451, 0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 18.557108970655708, 1.4879214550700424, 11.753313767048574},
    {0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 4.43921568627451, 4.43921568627451, 11.913725490196079, 0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 12.023616948909464, 3.550711069502251, 8.640215037544264},
    {0.5607843137254902, 0.5607843137254902, 0.5607843137254902, -5.146654459449149, -5.56078431372549, 15.242603189135577, 0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 13.81743936663999, -9.820772400258795, 4.062446570624235},
    {0.5607843137254902, 0.5607843137254902, 0.5607843137254902, -0.1688563363088431, -5.544457160296025, 15.894346532387276, 0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 16.411689074313287, -5.671033027727702, 2.9430531141249334},
    {0.5607232776379034, 0.5607843137254902, 0.5607843137254902, -5.560723277637903, -5.56078431372549, 0.4392156862745098, 0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 0.7962729848052474, -6.1226000320403635, -1.9445936562752448},
    {0.5607843137254902, 0.5607843137254902, 0.5607843137254902, -5.56078431372549, -5.56078431372549, 0.4392156862745098, 0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 0.7962729848052474, -6.1226000320403635, -1.9445936562752448},
    {0.5607843137254902, -0.15797665369649805, 0.5607843137254902, -5.56078431372549, -4.842023346303502, 0.4392156862745098, 0.5607843137254902, -0.15797665369649805, 0.5607843137254902, 0.7962729848052474, -5.403839064618375, -1.9445936562752448},
    {0.5610284580758373, 0.5607843137254902, 0.5607843137254902, -5.561028458075837, -5.56078431372549, 0.4392156862745098, 0.5610284580758373, 0.5607843137254902, 0.5607843137254902, 0.7960288404549003, -6.1226000320403635, -1.9445936562752448},
    {0.5607843137254902, 0.5607843137254902, 0.5607843137254902, -5.56078431372549, -5.56078431372549, 0.4392156862745098, 0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 0.7962729848052474, -6.1226000320403635, -1.9445936562752448},
    {0.5607843137254902, 0.5607843137254902, 0.5607843137254902, -5.56078431372549, -5.56078431372549, 0.4392156862745098, 0.5607843137254902, 0.5607843137254902, 0.5607843137254902, 0.7962729848052474, -6.1226000320403635, -1.9445936562752448}
};

static void test_linear17_near_kind_not_alone(void)
{
    enum { N = 29 };
    static double o1[3 * N], d1[3 * N], o2[3 * N], d2[3 * N], r[N];
    mcg_linear17_result res;
    double worst = 0.0;
    int i, k, st;
    for (i = 0; i < N; ++i)
        for (k = 0; k < 3; ++k) {
            o1[3 * i + k] = F19B_RAYS[i][k];
            d1[3 * i + k] = F19B_RAYS[i][3 + k];
            o2[3 * i + k] = F19B_RAYS[i][6 + k];
            d2[3 * i + k] = F19B_RAYS[i][9 + k];
        }
    st = mcg_linear17(N, o1, d1, o2, d2, NULL, &res);
    if (st == MCG_OK && res.scale_observable &&
        mcg_gec_residuals(N, o1, d1, o2, d2, res.R, res.t, r) == MCG_OK)
        for (i = 0; i < N; ++i)
            worst = fmax(worst, fabs(r[i]));
    check(st == MCG_OK || st == MCG_EDEGENERATE, "finding 19b: status", (double)st, 0);
    check(worst <= 1e-5, "finding 19b: no observable motion that misfits exact data", worst, 1e-5);
}

/* fuzz_lp (CI run): a homogeneous cone {a_k . x >= 0} whose points within
 * the box hug the face x + y + z = 0 (rows nearly parallel to each other):
 * the native solver declared it empty (a row with projected norm 1e-13 was
 * taken as parallel to the line although it crossed it inside the box) while
 * GLPK returned a point with margin 1 S. */
static void test_lp_native_nearly_parallel_rows(void)
{
    const double A[] = {6.0234375, 6.0234375, 6.0234375,  3.5859375, 6.0234375, 6.0234375,
                        6.0234375, 6.0234375, 6.0234375,  6.0234375, 6.0234375, -6.0234375,
                        6.037353515625, 6.0234375, 6.0234375,  6.0234375, 6.0234375, 0.0};
    const double b[6] = {0, 0, 0, 0, 0, 0}, p[3] = {2.5774101875722408, 1e6, -1e6};
    double x[3], work[128], worst = HUGE_VAL;
    int k;
    for (k = 0; k < 6; ++k) /* GLPK's point: inside every row by >= 1 S |a_k| */
        worst = fmin(worst, (A[3 * k] * p[0] + A[3 * k + 1] * p[1] + A[3 * k + 2] * p[2]) /
                                sqrt(A[3 * k] * A[3 * k] + A[3 * k + 1] * A[3 * k + 1] +
                                     A[3 * k + 2] * A[3 * k + 2]));
    check(worst >= 0.99, "lp: the finding's cone has an interior point", worst, 0.99);
    check(mcg_lp_native_work_size(3, 6) <= 128, "lp: work size", 0.0, 0.0);
    check_status(mcg_lp_native_feasible(3, 6, A, b, x, work, 128), MCG_OK,
                 "lp native: nearly parallel rows, feasible cone");
}

/* fuzz_lp, against the first fix of the finding above (a row parallel only
 * when it changes by less than tol over the box): rows duplicated exactly
 * have projected norms at rounding level (5e-17) whose offsets rh / g are
 * noise; taken as crossing rows they cut a feasible slab (planted point with
 * margin 0.059 S) to nothing. */
static void test_lp_native_duplicated_rows(void)
{
    const double A[] = {0.78789959563591982, 0.78823529411764715, 0.78823529411764715,
                        0.78823529411764715, 0.78823529411764715, 0.78823529411764715,
                        0.78823529411764715, 0.78823529411764715, 0.78823529411764715,
                        0.78823529411764715, 0.78823529411764715, 0.78823529411764715,
                        0.78823529411764715, 0.78823529411764715, 0.78823529411764715,
                        0.78823529411764715, 0.78823529411764715, -0.28990615701533529,
                        -0.29411764705882348, -0.29411764705882348, -0.29411764705882348};
    const double b[7] = {6.0768915759372408, 5.9305201237647847, 5.9305201237647847,
                         5.9305201237647847, 5.9305201237647847, 2.516852942427116,
                         -3.291666613307918};
    double x[3], work[128];
    check(mcg_lp_native_work_size(3, 7) <= 128, "lp: work size (7 rows)", 0.0, 0.0);
    check_status(mcg_lp_native_feasible(3, 7, A, b, x, work, 128), MCG_OK,
                 "lp native: duplicated rows, feasible slab");
}

/* fuzz_scale_line (10-minute run): a proposal lam = -a_k / b_k that
 * underflows to 0 (a_k denormal) was scored, and with no other proposal
 * lam = 0 came back with MCG_OK. Here e(t) = t_y: a = t0_y = -5e-324,
 * b = w_y = 10. */
static void test_scale_ransac_underflowing_proposal(void)
{
    const double o[3] = {0, 0, 0}, d1[3] = {0, 0, 1}, d2[3] = {1, 0, 1};
    const double R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, t0[3] = {0, -4.9406564584124654e-324, 0};
    const double w[3] = {0, 10, 0};
    int order[1] = {0}, m = -1, st;
    double lam = -1.0, score = -1.0, work[64];
    check(mcg_scale_ransac_work_size(1) <= 64, "scale_ransac: work size", 0.0, 0.0);
    st = mcg_scale_ransac(1, o, d1, o, d2, R, t0, w, 1, order, 10, 1e-3, 0.99, &lam, &score, &m,
                          work, 64);
    check(st == MCG_EDEGENERATE || (st == MCG_OK && lam > 0.0),
          "scale_ransac: no lam = 0 with MCG_OK (underflowing proposal)", lam, 0.0);
}

/* fuzz_refine (CI run, 10 s): a frequency weight of DBL_MAX on one pair of
 * a valid scene kept every cost finite, but the information matrix J^T W J
 * at the solution overflowed to inf and came back with MCG_OK (NaN
 * covariance downstream). Scenes like the harness's fz_scene, started near
 * the truth: MCG_OK must come with finite statistics, else MCG_ENUMERIC
 * with t untouched. */
static void test_refine_overflowing_information(void)
{
    enum { N = 17, SCENES = 200 };
    double o1[3 * N], d1[3 * N], o2[3 * N], d2[3 * N], w[N];
    unsigned long s = 99UL;
    int sc, bad = 0, enumeric = 0;
    for (sc = 0; sc < SCENES; ++sc) {
        double R[9], t[3], t0[3], tt[3], c[8 * 3], dw[3], Rt[9], Rd[9];
        mcg_refine_result res;
        int i, k, st, ncams = 1 + (int)lcg_uniform(&s, 0.0, 7.99);
        for (k = 0; k < 3; ++k) {
            tt[k] = lcg_uniform(&s, -2.0, 2.0);
            dw[k] = lcg_uniform(&s, -1.0, 1.0);
        }
        mcg_rot_from_angle_axis(dw, Rt);
        for (k = 0; k < 3 * ncams; ++k)
            c[k] = lcg_uniform(&s, -1.0, 1.0);
        for (i = 0; i < N; ++i) {
            double X[3], X2[3];
            int g = i % ncams;
            X[0] = lcg_uniform(&s, -5.0, 5.0);
            X[1] = lcg_uniform(&s, -5.0, 5.0);
            X[2] = lcg_uniform(&s, 1.0, 20.0);
            for (k = 0; k < 3; ++k)
                X2[k] = Rt[3 * k] * X[0] + Rt[3 * k + 1] * X[1] + Rt[3 * k + 2] * X[2] + tt[k];
            for (k = 0; k < 3; ++k) {
                o1[3 * i + k] = c[3 * g + k];
                d1[3 * i + k] = X[k] - c[3 * g + k];
                o2[3 * i + k] = c[3 * g + k];
                d2[3 * i + k] = X2[k] - c[3 * g + k];
            }
            w[i] = i == 1 ? DBL_MAX : lcg_uniform(&s, 0.5, 5.0);
        }
        for (k = 0; k < 3; ++k)
            dw[k] = lcg_uniform(&s, -0.2, 0.2);
        mcg_rot_from_angle_axis(dw, Rd);
        for (i = 0; i < 3; ++i)
            for (k = 0; k < 3; ++k)
                R[3 * i + k] = Rd[3 * i] * Rt[k] + Rd[3 * i + 1] * Rt[3 + k] +
                               Rd[3 * i + 2] * Rt[6 + k];
        for (k = 0; k < 3; ++k)
            t0[k] = t[k] = tt[k] + lcg_uniform(&s, -0.3, 0.3);
        st = mcg_refine_motion(N, o1, d1, o2, d2, w, NULL, R, t, &res);
        if (st == MCG_OK) {
            int finite = !isnan(res.sigma2) && !isnan(res.scale_rel_std);
            for (i = 0; i < 36; ++i)
                finite &= isfinite(res.info[i]) != 0;
            bad += !finite;
        } else if (st == MCG_ENUMERIC) {
            ++enumeric;
            bad += memcmp(t, t0, sizeof t) != 0;
        } else {
            ++bad;
        }
    }
    printf("refine with a DBL_MAX weight: %d of %d scenes MCG_ENUMERIC\n", enumeric, SCENES);
    check(bad == 0, "refine: MCG_OK only with finite statistics, else MCG_ENUMERIC (a weight "
          "DBL_MAX)", (double)bad, 0.0);
}

/* fuzz_linalg (10 s run): a quaternion of denormal components was divided
 * by its norm, itself rounded to a denormal of few significant bits: the
 * matrix was orthogonal only to 3e-8. */
static void test_rot_from_quat_denormal(void)
{
    const double qs[4][4] = {{3e-310, 1e-310, -2e-310, 7e-311},
                             {4.9406564584124654e-324, 1.5e-323, 0.0, -2.5e-323},
                             {1e-320, -3.3e-321, 7.7e-322, 2e-320},
                             {2.2250738585072009e-308, 1e-309, -1e-310, 3e-311}};
    int c, i, j, k;
    double worst = 0.0;
    for (c = 0; c < 4; ++c) {
        double r[9];
        if (mcg_rot_from_quat(qs[c], r) != MCG_OK) {
            worst = 1.0;
            continue;
        }
        for (i = 0; i < 3; ++i)
            for (j = 0; j < 3; ++j) {
                double acc = 0.0;
                for (k = 0; k < 3; ++k)
                    acc += r[3 * i + k] * r[3 * j + k];
                worst = fmax(worst, fabs(acc - (i == j ? 1.0 : 0.0)));
            }
    }
    check(worst < 1e-14, "rot_from_quat of denormal quaternions is a rotation", worst, 1e-14);
}

/* fuzz_cone (300 s runs): (a) two nearly opposite rays whose optimum lies
 * 1e-9 from an apex at |C| = 6.9: gamma 6e-12 at the optimum, 2.8e-7 at the
 * returned X after rounding -- within the header's bound eps |X| / min|X -
 * C_i|; (b) coincident apexes at 1e150, where the rounded X is on the apexes'
 * grid: gamma must stay the optimum (a first fix that evaluated gamma at the
 * rounded X returned 2.19 rad with "converged"). */
static double cone_angle_at(const double *X, const double *c, const double *a, double *dist)
{
    double u[3], v[3], mu = 0.0, mv = 0.0, cr[3];
    int j;
    for (j = 0; j < 3; ++j) {
        u[j] = X[j] - c[j];
        mu = fmax(mu, fabs(u[j]));
        mv = fmax(mv, fabs(a[j]));
    }
    *dist = mu == 0.0 ? 0.0 : mu * sqrt((u[0] / mu) * (u[0] / mu) + (u[1] / mu) * (u[1] / mu) +
                                        (u[2] / mu) * (u[2] / mu));
    if (mu == 0.0)
        return 0.0;
    for (j = 0; j < 3; ++j) {
        u[j] /= mu;
        v[j] = a[j] / mv;
    }
    cr[0] = u[1] * v[2] - u[2] * v[1];
    cr[1] = u[2] * v[0] - u[0] * v[2];
    cr[2] = u[0] * v[1] - u[1] * v[0];
    return atan2(sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]),
                 u[0] * v[0] + u[1] * v[1] + u[2] * v[2]);
}

static void test_cone_gamma_and_rounded_point(void)
{
    static const double apex_a[6] = {6.90185546875, 6.90185546875, 6.90185546875,
                                     6.90185546875, 6.9013671875, 6.90185546875};
    static const double axis_a[6] = {6.90185546875, -9.9999999999999998e+149, -4.78564453125,
                                     0.0, 1000000.0, 3.0625};
    static const double apex_b[6] = {1e150, 1.0, 1e150, 1e150, -1.426025390625, 1e150};
    static const double axis_b[6] = {1e150, 1e150, 1e150, 1e150, 1e150, 1e150};
    mcg_cone_options o;
    mcg_cone_result res;
    double worst = 0.0, dmin = HUGE_VAL, xmax = 0.0, d;
    int st, i;
    mcg_cone_default_options(&o);
    o.tolerance = 0.0043137254901960784;
    o.max_iterations = 16;
    o.max_newton = 126;
    st = mcg_cone_linf(2, apex_a, axis_a, &o, &res);
    check(st == MCG_OK, "cone near an apex: solved", (double)st, 0.0);
    for (i = 0; i < 2; ++i) {
        worst = fmax(worst, cone_angle_at(res.X, apex_a + 3 * i, axis_a + 3 * i, &d));
        dmin = fmin(dmin, d);
    }
    for (i = 0; i < 3; ++i)
        xmax = fmax(xmax, fabs(res.X[i]));
    check(res.gamma < 1e-9, "cone near an apex: gamma is the optimum", res.gamma, 1e-9);
    check(fabs(worst - res.gamma) <= 1e-7 + 4.0 * DBL_EPSILON * xmax / dmin,
          "cone near an apex: the angle at the rounded X within eps |X| / dist",
          fabs(worst - res.gamma), 4.0 * DBL_EPSILON * xmax / dmin);
    st = mcg_cone_linf(2, apex_b, axis_b, NULL, &res);
    check(st == MCG_OK && res.gamma <= 1.5707963267948966 && res.gamma_lower <= res.gamma,
          "cone with apexes at 1e150: gamma stays the optimum (<= pi/2)", res.gamma,
          1.5707963267948966);
}

/* fuzz_cone (300 s run): 25 cones, 13 of them identical; the first
 * bisection step at pi / 4 was undecided with the bracket [0, pi / 2] open,
 * and "undecided" was taken as the floating-point limit: converged, with
 * gamma 1.576 > pi / 2. An undecided test now closes only a narrow bracket. */
static void test_cone_undecided_wide_bracket(void)
{
    static const double apex[75] = {
        -0.0039215686274509665, -1, -1, 0.38194857709620811, -0.0024261844815747224,
        -0.0039215686274509665, -0.0039215686274509665, -0.0039215686274509665,
        -0.0039215686274509665, -0.99218738078889146, 0.76571297779812308,
        -0.99954222934309911, -0.99389639124132145, 0.68059815365835052,
        -0.96780346379797055, 0.90154879072251459, 0.91409170672159923,
        -0.0039215686274509665, -0.0039215686274509665, -0.66018158236057067,
        -0.0039215686274509665, 0.38820477607385362, 0.38039215686274508,
        0.37648584725719081, -0.0039215686274509665, -0.0039215686274509665,
        -0.0039215686274509665, -0.0039215686274509665, 0.60546272983901739,
        -0.99310292210269324, -0.65624475471122301, 0.065873197528038441,
        -0.79687190051117729, 0.91284046692607013, 0.50014496070801862,
        -0.9941100175478752, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1,
        -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1,
        -1, -1, -1};
    static const double axis[75] = {
        -0.0574540292045711, 0.93843137254901965, 1.0069173694044644, -0.3749628113700656,
        -0.0095338308971257349, -0.0080384467512494909, -0.0080384467512494909,
        -0.0080384467512494909, 0.022311281054727562, 0.93061875333791111,
        -0.81016124597393691, 0.99105826702390731, 0.94244433972566677,
        -0.72973384974650579, 0.90691575972725247, -0.96296694626580304,
        -0.92605172210029973, -0.0081752393946057569, -0.0081585202937511023,
        0.64822156698187017, 0.011027407896095066, -0.38102446081049335,
        -0.37313432576814959, -0.3883713866411751, -0.0080384467512494909,
        -0.0080384467512494909, -0.0080384467512494909, -0.0080384467512494909,
        -0.60088451463594517, 1.0197473105973909, 0.59469892603413532,
        -0.12713784132711597, 0.75441320533706735, -0.96229990560350187,
        -0.56171206824073949, 0.93254139009689485, 0.93843137254901965,
        0.93843137254901965, 0.93843137254901965, 0.93843137254901965, 0.93843137254901965,
        0.93843137254901965, 0.93843137254901965, 0.93843137254901965, 0.93843137254901965,
        0.93843137254901965, 0.93843137254901965, 0.93843137254901965, 0.93843137254901965,
        0.93843137254901965, 0.93843137254901965, 0.93843137254901965, 0.93843137254901965,
        0.93843137254901965, 0.93843137254901965, 0.93843137254901965, 0.93843137254901965,
        0.93843137254901965, 0.93843137254901965, 0.93843137254901965, 0.93843137254901965,
        0.93843137254901965, 0.93843137254901965, 0.93843137254901965, 0.93843137254901965,
        0.93843137254901965, 0.93843137254901965, 0.93843137254901965, 0.93843137254901965,
        0.93843137254901965, 0.93843137254901965, 0.93843137254901965, 0.93843137254901965,
        0.93843137254901965, 0.93843137254901965};
    mcg_cone_options o;
    mcg_cone_result res;
    int st;
    mcg_cone_default_options(&o);
    o.tolerance = 0.0049803921568627452;
    o.max_iterations = 15;
    o.max_newton = 158;
    st = mcg_cone_linf(25, apex, axis, &o, &res);
    check(st == MCG_OK || st == MCG_EINFEASIBLE, "cone, undecided step: solved or infeasible",
          (double)st, 0.0);
    if (st == MCG_OK)
        check(!res.converged || res.gamma <= 1.5707963267948966,
              "cone, undecided step: converged only with gamma <= pi/2", res.gamma,
              1.5707963267948966);
}

/* fuzz_cls (CI run, 10 s): a harness finding, not a kernel bug. With
 * rcond = 0.032, mcg_cls_range drops G's second singular direction
 * (s2 / s1 = 0.0097), as documented; the harness compared x with a y = G z
 * lying almost wholly along that dropped direction. The kernel's answer is
 * pinned here: x = +-u1 (G's leading left singular vector), resid = |A u1|. */
static void test_cls_range_dropped_direction(void)
{
    const double a[2] = {0.99859922178988325, 1.0};
    const double g[4] = {1.0, 1.0, 0.0038910505836575876, 0.023906614785992219};
    double x[2], resid = -1.0, w[256], ggt[3], lam, u[2], nu, dot;
    size_t ws = mcg_cls_range_work_size(1, 2, 2);
    check(ws > 0 && ws <= 256, "cls_range 1x2, r = 2: work size", (double)ws, 256.0);
    check_status(mcg_cls_range(1, 2, 2, a, g, 0.0319824, x, &resid, w, 256), MCG_OK,
                 "cls_range with one direction of G below rcond");
    /* u1: leading eigenvector of G G^T (2 x 2, closed form) */
    ggt[0] = g[0] * g[0] + g[1] * g[1];
    ggt[1] = g[0] * g[2] + g[1] * g[3];
    ggt[2] = g[2] * g[2] + g[3] * g[3];
    lam = 0.5 * (ggt[0] + ggt[2]) + sqrt(0.25 * (ggt[0] - ggt[2]) * (ggt[0] - ggt[2]) +
                                         ggt[1] * ggt[1]);
    u[0] = ggt[1];
    u[1] = lam - ggt[0];
    nu = sqrt(u[0] * u[0] + u[1] * u[1]);
    u[0] /= nu;
    u[1] /= nu;
    dot = fabs(x[0] * u[0] + x[1] * u[1]);
    check(fabs(dot - 1.0) < 1e-12, "cls_range: x = +-u1 of G", dot - 1.0, 1e-12);
    check(fabs(resid - fabs(a[0] * u[0] + a[1] * u[1])) < 1e-12, "cls_range: resid = |A u1|",
          resid - fabs(a[0] * u[0] + a[1] * u[1]), 1e-12);
}

/* fuzz_robust (session 29): the local 6-point sampler's best motion, left
 * unrefined (refine = 0), had |t| 1.6e150 on these 23 pairs of 3 cameras,
 * and the verdict's evidence (mcg_verdict_stats takes entries up to 1e150)
 * was refused: have_verdict 0 although verdict_still_factor > 0 asked for
 * it. The evidence is now gathered at t shortened to 1e149 (robust.c). */
static const double F21_RAYS[23][12] = {
    {0.4140840772106509, -0.9985961699855039, 0.6753795681696804, -0.4336919203479057, 0.9789883268482491, 9.787365529869536, 0.4140840772106509, -0.9985961699855039, 0.6753795681696804, 0.9212455885981286, 8.869673218549817, -1.682015167871225},
    {0.3206683451590753, -0.9621881437399863, 0.23567559319447628, -0.3402761882963301, 0.9425803006027315, 10.227069504844739, 0.3206683451590753, -0.9621881437399863, 0.23567559319447628, 1.0146613206497042, 8.8332651923043, -1.2423111928960209},
    {0.2031433585107194, -0.9988708323796445, -0.005172808422980069, -0.22275120164797424, 0.9792629892423896, 10.467917906462196, 0.2031433585107194, -0.9988708323796445, -0.005172808422980069, 1.13218630729806, 8.869947880943958, -1.0014627912785645},
    {0.4140840772106509, -0.9985961699855039, 0.6753795681696804, -0.4336919203479057, 0.9789883268482491, 9.787365529869536, 0.3206683451590753, -0.9621881437399863, 0.23567559319447628, 1.0146613206497042, 8.8332651923043, -1.2423111928960209},
    {0.3206683451590753, -0.9621881437399863, 0.23567559319447628, -0.3402761882963301, 0.9425803006027315, 10.227069504844739, 0.3206683451590753, -0.9621881437399863, 0.23567559319447628, 1.0146613206497042, 8.8332651923043, -1.2423111928960209},
    {0.2031433585107194, -0.9988708323796445, -0.005172808422980069, -0.22275120164797424, 0.9792629892423896, 10.467917906462196, 0.2031433585107194, -0.9988708323796445, -0.005172808422980069, 1.13218630729806, 8.869947880943958, -1.0014627912785645},
    {0.4140840772106509, -0.9985961699855039, 0.6753795681696804, -0.4336919203479057, 0.9789883268482491, 9.787365529869536, 0.4140840772106509, -0.9985961699855039, 0.6753795681696804, 0.9212455885981286, 8.869673218549817, -1.682015167871225},
    {0.3206683451590753, -0.9621881437399863, 0.23567559319447628, -0.3402761882963301, 0.9425803006027315, 10.227069504844739, 0.2031433585107194, -0.9988708323796445, -0.005172808422980069, 1.13218630729806, 8.869947880943958, -1.0014627912785645},
    {0.2031433585107194, -0.9988708323796445, -0.005172808422980069, -0.22275120164797424, 0.9792629892423896, 10.467917906462196, 0.2031433585107194, -0.9988708323796445, -0.005172808422980069, 1.13218630729806, 8.869947880943958, -1.0014627912785645},
    {0.4140840772106509, -0.9985961699855039, 0.6753795681696804, -0.4336919203479057, 0.9789883268482491, 9.787365529869536, 0.4140840772106509, -0.9985961699855039, 0.6753795681696804, 0.9212455885981286, 8.869673218549817, -1.682015167871225},
    {0.3206683451590753, -0.9621881437399863, 0.23567559319447628, -0.3402761882963301, 0.9425803006027315, 10.227069504844739, 0.3206683451590753, -0.9621881437399863, 0.23567559319447628, 1.0146613206497042, 8.8332651923043, -1.2423111928960209},
    {0.2031433585107194, -0.9988708323796445, -0.005172808422980069, -0.22275120164797424, 0.9792629892423896, 10.467917906462196, 0.4140840772106509, -0.9985961699855039, 0.6753795681696804, 0.9212455885981286, 8.869673218549817, -1.682015167871225},
    {0.4140840772106509, -0.9985961699855039, 0.6753795681696804, -0.4336919203479057, 0.9789883268482491, 15.451850156404975, 0.4140840772106509, -0.9985961699855039, 0.6753795681696804, 2.7341965595352917, 14.065183087562684, -3.0259913812858175},
    {0.3206683451590753, -0.9621881437399863, 0.23567559319447628, -3.0159456778820477, -4.0046997787441825, 15.550896467536433, -1e+150, -0.9621881437399863, 0.23567559319447628, -1.1842623040332068, 14.03376737678806, -6.543012358937809},
    {0.2031433585107194, -0.9988708323796445, -0.005172808422980069, -0.7107347219043259, -2.828931105516136, 7.090913252460517, 0.2031433585107194, -0.9988708323796445, -0.005172808422980069, -3.325768350520141, 6.5198966754667325, -1.866639196999694},
    {0.4140840772106509, -0.9985961699855039, 0.6753795681696804, 3.72683299000534, 5.175066758220797, 17.759914549477376, 0.3206683451590753, -0.9621881437399863, 0.23567559319447628, 6.4278564997512815, 16.4817730519693, 2.0251381296710385},
    {0.3206683451590753, -0.9621881437399863, 0.23567559319447628, 3.8558022430762184, 5.13865873197528, 18.199618524452582, 0.3206683451590753, -0.9621881437399863, 0.23567559319447628, 6.419420942113921, 16.49315216140323, 2.057748098893767},
    {0.2031433585107194, -0.9988708323796445, -0.005172808422980069, 3.973327229724574, 5.175341420614938, 18.440466926070037, 0.2031433585107194, -0.9988708323796445, -0.005172808422980069, 6.536945928762276, 16.52983485004289, 2.2985965005112234},
    {0.4140840772106509, -0.9985961699855039, 0.6753795681696804, 3.7359884031433577, 5.175066758220797, 17.759914549477376, 0.4140840772106509, -0.9985961699855039, 0.6753795681696804, 6.332268521097809, 16.5211113209875, 1.5938315716630609},
    {0.3206683451590753, -0.9621881437399863, 0.23567559319447628, 3.8558022430762184, 5.13865873197528, 18.199618524452582, 0.2031433585107194, -0.9988708323796445, -0.005172808422980069, 6.536945928762276, 16.52983485004289, 2.2985965005112234},
    {0.2031433585107194, -0.9988708323796445, -0.005172808422980069, 3.973327229724574, 5.175341420614938, 18.440466926070037, 0.2031433585107194, -0.9988708323796445, -0.005172808422980069, 6.536945928762276, 16.52983485004289, 2.2985965005112234},
    {0.4140840772106509, -0.9985961699855039, 0.6753795681696804, 3.7623865110246424, 5.175066758220797, 0.3924620431830319, 0.4140840772106509, -0.9985961699855039, 0.6753795681696804, 0.7674518799866037, 0.5999960974989493, 5.73870903784976},
    {0.3206683451590753, -0.9621881437399863, 0.23567559319447628, -5.320668345159075, 5.104020752269779, 18.199618524452582, 0.3206683451590753, -0.9621881437399863, 0.23567559319447628, 8.564893483667515, 13.564388163316533, -6.370069012513921}};
static const int F21_CAM1[23] = {0, 1, 2, 0, 1, 2, 0, 1, 2, 0, 1, 2, 0, 1, 2, 0, 1, 2, 0, 1, 2, 0, 1};
static const int F21_CAM2[23] = {0, 1, 2, 1, 1, 2, 0, 2, 2, 0, 1, 0, 0, 1, 2, 1, 1, 2, 0, 2, 2, 0, 1};

static void test_robust_verdict_of_a_far_translation(void)
{
    double o1[69], d1[69], o2[69], d2[69], *work, big = 0.0;
    unsigned char mask[23];
    mcg_robust_options opt;
    mcg_robust_result res;
    size_t lw = mcg_robust_work_size(23, 3);
    int i, k, st;
    for (k = 0; k < 23; k++)
        for (i = 0; i < 3; i++) {
            o1[3 * k + i] = F21_RAYS[k][i];
            d1[3 * k + i] = F21_RAYS[k][3 + i];
            o2[3 * k + i] = F21_RAYS[k][6 + i];
            d2[3 * k + i] = F21_RAYS[k][9 + i];
        }
    mcg_robust_default_options(&opt);
    opt.threshold = 0.00019461570153353171;
    opt.prob = 0.7534779430838483;
    opt.max_iterations = 20;
    opt.min_iterations = 15;
    opt.seed = 4439423446346108949ULL;
    opt.lo_rounds = 3;
    opt.refine = 0;
    opt.loss = 3;
    opt.sampler = MCG_SAMPLER_6PT_LOCAL;
    opt.verdict_still_factor = 0.031891355764095519;
    work = malloc(lw * sizeof *work);
    st = mcg_robust_rig_motion(23, o1, d1, o2, d2, F21_CAM1, F21_CAM2, 3, NULL, NULL, NULL, &opt,
                               &res, mask, NULL, work, lw);
    free(work);
    check_status(st, MCG_OK, "robust: far-translation case estimated");
    for (i = 0; i < 3; i++)
        big = fabs(res.t[i]) > big ? fabs(res.t[i]) : big;
    check(big > 1e150, "robust: the case's |t_i| beyond 1e150", big, 1e150);
    check(res.have_verdict == 1, "robust: verdict evidence with |t_i| beyond 1e150",
          (double)res.have_verdict, 1.0);
    check(res.verdict.n_inliers == res.n_inliers, "robust: the evidence counts the inliers",
          (double)res.verdict.n_inliers, (double)res.n_inliers);
}

/* fuzz_leverage (session 38): t alone fitted (R held, here 9 arbitrary
 * doubles as fuzz input gives them), 7 pairs whose time-2 origins are 0,
 * one time-1 origin at -2.4e77 m: an exact fit (sum w r^2 = 0) with a
 * travel gradient beyond the doubles, and the travel's std came out NaN
 * (0 x inf) with MCG_OK. Now HUGE_VAL: a std nothing determines. */
static void test_leverage_nan_std(void)
{
    static const double o1[21] = {-2.7109375, 3.053466796875, -0.526611328125,
                                  0.133056640625, 0.54345703125, 3.38818359375,
                                  3.38818359375, 3.199951171875, 3.199951171875,
                                  -0.686279296875, -0.00048828125, 5.949462890625,
                                  6.76708984375, -2.1875, 0.375,
                                  2.9375, 6.5625, -2.375,
                                  2.3125, 7.62158203125, -2.4413519756306118e+77};
    static const double d1[21] = {0.746826171875, 2.29931640625, 3.529296875,
                                  -1.462646484375, 0, 0.05029296875,
                                  2.240478515625, 6.89794921875, 10.587890625,
                                  -5.8505859375, 0, 0.201171875,
                                  3.734130859375, 11.49658203125, 17.646484375,
                                  -8.77587890625, 0, 0.3017578125,
                                  5.227783203125, 16.09521484375, 24.705078125};
    static const double o2[21] = {-1.1875e-160, -0.0, 4.8828124999999999e-164,
                                  9.5214843749999998e-123, 0, 0};
    static const double d2[21] = {0.99999999999999989, -0.021728515625, 0,
                                  2.25, 0.004638671875, 0.054443359375,
                                  -6.5625, -6.525634765625, -6.525634765625,
                                  -6.525634765625, -6.525634765625, -6.525634765625,
                                  -6.525634765625, -6.525634765625, -6.525634765625,
                                  -6.525634765625, -6.525634765625, -6.525634765625,
                                  -6.525634765625, -6.525634765625, -6.525634765625};
    const double R[9] = {-6.525634765625, -6.525634765625, -6.525634765625, 0, 0, 0, 0, 0, 0};
    const double t[3] = {0, 0, 0};
    mcg_leverage_result lr;
    int st = mcg_sampson_leverage(7, o1, d1, o2, d2, NULL, R, t, 1, NULL, &lr);
    check(st != MCG_OK || (lr.travel_std >= 0.0 && lr.travel_std_hc >= 0.0),
          "sampson_leverage: an exact fit with an overflowing gradient, std not NaN",
          lr.travel_std, 0.0);
}

int main(void)
{
    test_robust_verdict_of_a_far_translation();
    test_cls_range_dropped_direction();
    test_cone_undecided_wide_bracket();
    test_cone_gamma_and_rounded_point();
    test_rot_from_quat_denormal();
    test_refine_overflowing_information();
    test_scale_ransac_underflowing_proposal();
    test_lp_native_nearly_parallel_rows();
    test_lp_native_duplicated_rows();
    test_linear17_near_static_and_repeated();
    test_linear17_nearly_axial_locally_central();
    test_linear17_near_kind_not_alone();
    test_wedge_near_parallel();
    test_wedge_tiny_angle();
    test_cone_iteration_budget();
    test_svd_near_dbl_max();
    test_bnb_polish_nonnegative();
    test_linf_local_negative_n();
    test_linear17_central_exact_cost();
    test_linear17_overflowing_direction();
    test_angle_axis_overflow();
    test_qr_graded_columns();
    test_qr_subnormal_column();
    test_leverage_nan_std();
    printf("%d checks, %d failed\n", n_checks, n_failed);
    return n_failed != 0;
}
