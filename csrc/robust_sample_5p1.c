/*
 * robust_sample_5p1.c -- the central samples of the robust estimate
 * (csrc/robust.c): 5 intra-camera pairs of one camera and a sixth pair
 * (thesis ch. 7, the 5+1 method): mcg_essential5 -> both rotations of each
 * essential matrix with the sign of the translation that puts the five in
 * front -> the metric scale from the sixth pair (eq. 7.4); or, with the
 * vertical known, 3 pairs of one camera (mcg_upright3_central) and a
 * sixth.
 */
#include "robust_internal.h"

#include <math.h>
#include <string.h>

/* Unit null vector of the 3 x 3 matrix's rows (transpose: 1) from the
 * largest cross product of two of them (E has rank 2). */
static int null_vector(const double *e, int transpose, double v[3])
{
    double r[3][3], x[3][3], best = 0.0;
    int i, j, k = -1;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++)
            r[i][j] = transpose ? e[3 * j + i] : e[3 * i + j];
    cross3(r[0], r[1], x[0]);
    cross3(r[1], r[2], x[1]);
    cross3(r[2], r[0], x[2]);
    for (i = 0; i < 3; i++) {
        double s = dot3(x[i], x[i]);
        if (s > best) {
            best = s;
            k = i;
        }
    }
    return k >= 0 && unit3(x[k], v);
}

/* Re-orthonormalise a near-rotation (Gram-Schmidt on its rows): the
 * closed-form decomposition leaves rounding of the 5-point solution that
 * mcg_refine_motion's rotation check (1e-6) could reject. */
int robust_orthonormalise(double r[9])
{
    double a[3], b[3], c3[3], x;
    if (!unit3(r, a))
        return 0;
    x = dot3(a, r + 3);
    b[0] = r[3] - x * a[0];
    b[1] = r[4] - x * a[1];
    b[2] = r[5] - x * a[2];
    if (!unit3(b, b))
        return 0;
    cross3(a, b, c3);
    memcpy(r, a, sizeof a);
    memcpy(r + 3, b, sizeof b);
    memcpy(r + 6, c3, sizeof c3);
    return 1;
}

/* The two rotations of an essential matrix E = [u]x R (|u| = 1 after
 * scaling |E|_F = sqrt 2): [u]x E = (u u^T - I) R and R^T u = v, the right
 * null vector, give R = u v^T - [u]x E for the sign of v with det R = +1
 * (the other sign gives det -1); the twisted pair is (2 u u^T - I) R
 * (Hartley & Zisserman 9.6.2). u is returned unit, of arbitrary sign. */
static int decompose(const double E[9], double R1[9], double R2[9], double u[3])
{
    double e[9], v[3], ue[9], s = 0.0;
    int i, j;
    for (i = 0; i < 9; i++)
        s += E[i] * E[i];
    if (!(s > 0.0) || !isfinite(s))
        return 0;
    s = sqrt(2.0 / s);
    for (i = 0; i < 9; i++)
        e[i] = E[i] * s;
    if (!null_vector(e, 1, u) || !null_vector(e, 0, v))
        return 0;
    skew_times(u, e, ue); /* [u]x E */
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++)
            R1[3 * i + j] = u[i] * v[j] - ue[3 * i + j];
    if (det33(R1) < 0.0)
        for (i = 0; i < 3; i++)
            for (j = 0; j < 3; j++)
                R1[3 * i + j] -= 2.0 * u[i] * v[j];
    if (!robust_orthonormalise(R1))
        return 0;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) {
            double h[3] = {2.0 * u[i] * u[0] - (i == 0), 2.0 * u[i] * u[1] - (i == 1),
                           2.0 * u[i] * u[2] - (i == 2)};
            R2[3 * i + j] = h[0] * R1[j] + h[1] * R1[3 + j] + h[2] * R1[6 + j];
        }
    return robust_orthonormalise(R2);
}

/* The motion of one rotation candidate of a 5+1 (or upright 3+1) sample:
 * the sign of the camera's translation direction u from the cheirality of
 * its m = 5 (3) points (all in front), the scale lam > 0 from the sixth
 * correspondence (eq. 7.4: a + lam b = 0 with a = d2.((t0 + R o1 - o2) x R d1), b = d2.((u) x R d1),
 * unit bearings), then the sixth point in front of both its rays.
 * `six` < 0: a rig with one camera, lam = 1 (direction only). Returns 1
 * with (t0, u, lam), 2 with (t0, u) and lam = 1 when the sixth pair gives
 * no scale (no offer: the two-stage's robust_record() may still search it), 0
 * when the m are not in front. */
static int candidate(const ctx *c, const double R[9], const double u_in[3],
                     const double b1[15], const double b2[15], int m, const double ca[3],
                     int six, double t0[3], double u[3], double *lam_out)
{
    double rca[3], A[3], t_out[3];
    int k, plus = 0, minus = 0, usable = 0, i;
    for (k = 0; k < m; k++) {
        double s1, s2;
        mat_vec(R, b1 + 3 * k, A);
        if (!depths(A, b2 + 3 * k, u_in, &s1, &s2))
            continue;
        usable++;
        plus += s1 > 0.0 && s2 > 0.0;
        minus += s1 < 0.0 && s2 < 0.0;
    }
    if (usable < 3 || (plus < usable && minus < usable))
        return 0;
    for (i = 0; i < 3; i++)
        u[i] = plus == usable ? u_in[i] : -u_in[i];
    mat_vec(R, ca, rca);
    for (i = 0; i < 3; i++)
        t0[i] = ca[i] - rca[i];
    *lam_out = 1.0;
    if (six < 0)
        return 1;
    {
        const double *o1 = c->o1 + 3 * (size_t)six, *o2 = c->o2 + 3 * (size_t)six;
        double e1[3], e2[3], ro1[3], s0[3], x[3], a, b, lam, g[3], s1, s2;
        if (!unit3(c->d1 + 3 * (size_t)six, e1) || !unit3(c->d2 + 3 * (size_t)six, e2))
            return 2;
        mat_vec(R, e1, A);
        mat_vec(R, o1, ro1);
        for (i = 0; i < 3; i++)
            s0[i] = t0[i] + ro1[i] - o2[i];
        if (dot3(s0, s0) <= 1e-24 * (1.0 + dot3(o1, o1) + dot3(ca, ca))) {
            /* the sixth pair's cameras sit at camera a's centre (a central
             * rig): a = 0 for every lam, no scale; direction only */
            return 1;
        }
        cross3(s0, A, x);
        a = dot3(e2, x);
        cross3(u, A, x);
        b = dot3(e2, x);
        if (!(fabs(b) > 1e-12 * (1.0 + fabs(a))))
            return 2; /* critical for this pair: no scale */
        lam = -a / b;
        if (!(lam > 0.0) || !isfinite(lam))
            return 2;
        for (i = 0; i < 3; i++) {
            t_out[i] = t0[i] + lam * u[i];
            g[i] = ro1[i] + t_out[i] - o2[i];
        }
        /* s1 R d1 + (R o1 + t - o2) = s2 d2: both depths positive */
        if (depths(A, e2, g, &s1, &s2) && !(s1 > 0.0 && s2 > 0.0))
            return 2;
        *lam_out = lam;
    }
    return 1;
}

/* One central sample: m = c->central_m intra-camera pairs of one camera a
 * and a sixth pair. 5+1 (thesis ch. 7): 5 pairs -> mcg_essential5 -> both
 * rotations of each E; upright 3+1 (the vertical known, opt.g1/g2): 3
 * pairs -> mcg_upright3_central (Fraundorfer et al. 2010), the rotation
 * and the direction of camera a's travel -- the two-stage search of
 * REC_PAIRS then as for 5+1 (the sixth pair's scale, the 1-point scale
 * search of a new best, the records), with 3-samples in the adaptive stop
 * (w^3: half the samples of w^5 at 30 % outliers). Returns the number of
 * hypotheses offered, -1 when no camera has m usable pairs. */
#define CENTRAL_CANDIDATES 20 /* 10 essential matrices x 2 rotations */

int robust_sample(ctx *c, const double *w)
{
    const int mm = c->central_m;
    int total = 0, a, k, m, cnt, start, six = -1, n_e = 0, j, offered = 0, nc = 0;
    double b1[15], b2[15], E[90], ca[3], Rc[9 * CENTRAL_CANDIDATES], uc[3 * CENTRAL_CANDIDATES];
    const int *off = c->off;
    for (k = 0; k < c->ncam; k++) {
        cnt = off[k + 1] - off[k];
        total += cnt >= mm && c->usable[k] ? cnt : 0;
    }
    if (total == 0)
        return -1;
    /* camera a with probability proportional to its intra-camera count */
    m = rng_below(&c->rng, total);
    for (a = 0; a < c->ncam; a++) {
        cnt = off[a + 1] - off[a];
        if (cnt < mm || !c->usable[a])
            continue;
        if (m < cnt)
            break;
        m -= cnt;
    }
    start = off[a];
    cnt = off[a + 1] - start;
    /* mm distinct ones: a partial Fisher-Yates shuffle of camera a's group */
    for (j = 0; j < mm; j++) {
        int r = j + rng_below(&c->rng, cnt - j), tmp = c->perm[start + j], idx;
        c->perm[start + j] = c->perm[start + r];
        c->perm[start + r] = tmp;
        idx = c->perm[start + j];
        if (!unit3(c->d1 + 3 * (size_t)idx, b1 + 3 * j) ||
            !unit3(c->d2 + 3 * (size_t)idx, b2 + 3 * j))
            return 0;
    }
    memcpy(ca, c->o1 + 3 * (size_t)c->perm[start], sizeof ca);
    /* the sixth: a cross-camera one when there are enough, else any one not
     * of camera a (the grouped order skips a's group) */
    {
        int ncross = off[c->ncam + 1] - off[c->ncam], nother = c->n - cnt;
        if (ncross >= MIN_CROSS) {
            six = c->perm[off[c->ncam] + rng_below(&c->rng, ncross)];
        } else if (nother > 0) {
            int r = rng_below(&c->rng, nother);
            six = c->perm[r < start ? r : r + cnt];
        }
    }
    /* the candidates (R, u) of camera a's motion */
    if (mm == 5) {
        if (mcg_essential5(b1, b2, E, &n_e) != MCG_OK)
            return 0;
        for (j = 0; j < n_e; j++) {
            double R1[9], R2[9], u[3];
            if (!decompose(E + 9 * j, R1, R2, u))
                continue;
            memcpy(Rc + 9 * nc, R1, sizeof R1);
            memcpy(uc + 3 * nc++, u, sizeof u);
            memcpy(Rc + 9 * nc, R2, sizeof R2);
            memcpy(uc + 3 * nc++, u, sizeof u);
        }
    } else if (mcg_upright3_central(b1, b2, c->opt.g1, c->opt.g2, Rc, uc, &nc) != MCG_OK) {
        return 0;
    }
    for (j = 0; j < nc; j++) {
        double t0[3], us[3], lam;
        int got = candidate(c, Rc + 9 * j, uc + 3 * j, b1, b2, mm, ca, six, t0, us, &lam);
        int best = 0;
        if (got == 0)
            continue; /* not in front of camera a */
        if (got == 1) {
            best = robust_offer(c, Rc + 9 * j, t0, us, lam, w, six >= 0 ? a : -1);
            offered++;
        }
        if (!best && c->records)
            robust_record(c, Rc + 9 * j, t0, us, w, a);
    }
    return offered;
}
