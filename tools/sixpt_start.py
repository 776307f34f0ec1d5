"""Offline generator of the start system of csrc/sixpt.c's parameter homotopy.

The 6-point generalized relative pose (Stewenius, Nister, Oskarsson, Astrom,
OMNIVIS 2005) has 64 complex solutions for generic data. csrc/sixpt.c tracks
them from one generic complex problem P0 (whose 64 solutions are tabulated)
to the given real problem. This script finds P0's solutions by monodromy
(Duff et al., "Solving polynomial systems via homotopy continuation and
monodromy", IMA J. Numer. Anal. 2019): a problem is built around one known
solution, then loops P0 -> Pa -> Pb -> P0 through random complex problems
permute the solutions; tracking every known solution around such loops finds
the others until the count stops growing. Then every solution is checked
(residual, distinctness) and the tables are written as C.

Unknowns x = (s, t): Cayley vector s (R = Rt(s) / (1 + s.s), Rt(s) = (1 - s.s)
I + 2 [s]x + 2 s s^T) and the translation t. Equation of correspondence i
(the generalized epipolar constraint, thesis eq. 8.16, times 1 + s.s):
    F_i = <Rt(s), G_i>,  G_i = (d2 x t) d1^T + d2 m1^T + m2 d1^T,  m = o x d.

    python tools/sixpt_start.py --seed 1 > csrc/sixpt_start.h
"""

from __future__ import annotations

import argparse
import sys

import numpy as np


def rt(s):
    """Rt(s) for s (..., 3) complex, (..., 3, 3)."""
    ss = np.einsum("...i,...i->...", s, s)
    I = np.eye(3)
    K = np.zeros(s.shape[:-1] + (3, 3), dtype=complex)
    K[..., 0, 1], K[..., 0, 2], K[..., 1, 2] = -s[..., 2], s[..., 1], -s[..., 0]
    K[..., 1, 0], K[..., 2, 0], K[..., 2, 1] = s[..., 2], -s[..., 1], s[..., 0]
    return (1 - ss)[..., None, None] * I + 2 * K + 2 * s[..., :, None] * s[..., None, :]


def drt(s):
    """dRt/ds_k, (..., 3, 3, 3) with k first after the batch axes."""
    out = np.zeros(s.shape[:-1] + (3, 3, 3), dtype=complex)
    for k in range(3):
        e = np.zeros(3)
        e[k] = 1
        E = np.zeros((3, 3))
        E[[2, 0, 1][k], [1, 2, 0][k]] = 1
        E[[1, 2, 0][k], [2, 0, 1][k]] = -1
        out[..., k, :, :] = (-2 * s[..., k])[..., None, None] * np.eye(3) + 2 * E \
            + 2 * (e[:, None] * s[..., None, :] + s[..., :, None] * e[None, :])
    return out


def gmat(p, t):
    """G_i (..., 6, 3, 3) for problems p (..., 6, 4, 3) = (o1, d1, o2, d2), t (..., 3)."""
    o1, d1, o2, d2 = p[..., 0, :], p[..., 1, :], p[..., 2, :], p[..., 3, :]
    m1, m2 = np.cross(o1, d1), np.cross(o2, d2)
    tt = np.broadcast_to(t[..., None, :], d2.shape)
    return (np.cross(d2, tt)[..., :, None] * d1[..., None, :] + d2[..., :, None] * m1[..., None, :]
            + m2[..., :, None] * d1[..., None, :])


def F(x, p):
    s, t = x[..., :3], x[..., 3:]
    return np.einsum("...ab,...iab->...i", rt(s), gmat(p, t))


def jac(x, p):
    s, t = x[..., :3], x[..., 3:]
    G = gmat(p, t)
    Js = np.einsum("...kab,...iab->...ik", drt(s), G)
    d1, d2 = p[..., 1, :], p[..., 3, :]
    Rd1 = np.einsum("...ab,...ib->...ia", rt(s), d1)
    Jt = np.cross(Rd1, d2)
    return np.concatenate([Js, Jt], axis=-1)


def track(x, pa, pb, steps_min=40):
    """Track solutions x (n, 6) of problem pa to pb along the straight segment."""
    n = x.shape[0]
    tau = np.zeros(n)
    h = np.full(n, 1.0 / steps_min)
    ok = np.ones(n, bool)
    x = x.copy()
    dp = pb - pa
    for _ in range(20000):
        act = ok & (tau < 1)
        if not act.any():
            break
        idx = np.nonzero(act)[0]
        hh = np.minimum(h[idx], 1 - tau[idx])
        xx = x[idx]

        def vel(xv, tv):
            pv = pa + tv[:, None, None, None] * dp
            J = jac(xv, pv)
            # dF/dtau: F is polynomial in p; use a complex-step-free central difference in tau
            e = 1e-6
            Fp = F(xv, pa + (tv + e)[:, None, None, None] * dp)
            Fm = F(xv, pa + (tv - e)[:, None, None, None] * dp)
            return -np.linalg.solve(J, ((Fp - Fm) / (2 * e))[..., None])[..., 0]

        t0 = tau[idx]
        k1 = vel(xx, t0)
        k2 = vel(xx + hh[:, None] / 2 * k1, t0 + hh / 2)
        k3 = vel(xx + hh[:, None] / 2 * k2, t0 + hh / 2)
        k4 = vel(xx + hh[:, None] * k3, t0 + hh)
        xp = xx + hh[:, None] / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        t1 = t0 + hh
        pv = pa + t1[:, None, None, None] * dp
        good = np.ones(len(idx), bool)
        for it in range(3):
            dx = np.linalg.solve(jac(xp, pv), F(xp, pv)[..., None])[..., 0]
            xp = xp - dx
            nd = np.linalg.norm(dx, axis=1) / (1 + np.linalg.norm(xp, axis=1))
            if it == 0:
                first = nd
        good = (nd < 1e-9) & (first < 1e-3)
        x[idx[good]] = xp[good]
        tau[idx[good]] = t1[good]
        h[idx[good]] = np.minimum(h[idx[good]] * 1.5, 0.1)
        h[idx[~good]] *= 0.5
        big = np.linalg.norm(x, axis=1) > 1e8
        ok &= (h > 1e-12) & ~big
    ok &= tau >= 1
    return x, ok


def rand_c(rng, *shape):
    return rng.normal(size=shape) + 1j * rng.normal(size=shape)


def problem_through(x0, rng):
    """A random complex problem (6, 4, 3) with solution x0."""
    p = rand_c(rng, 6, 4, 3)
    s, t = x0[:3], x0[3:]
    R = rt(s)
    for i in range(6):
        o1, d1, o2 = p[i, 0], p[i, 1], p[i, 2]
        w = np.cross(t, R @ d1) + R @ np.cross(o1, d1) + np.cross(R @ d1, o2)
        d2 = p[i, 3]
        p[i, 3] = d2 - (d2 @ w) / (w @ w) * w
    return p


def dedupe(sols, tol=1e-6):
    out = []
    for x in sols:
        if all(np.linalg.norm(x - y) > tol * (1 + np.linalg.norm(x)) for y in out):
            out.append(x)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--expect", type=int, default=64)
    a = ap.parse_args(argv)
    rng = np.random.default_rng(a.seed)
    x0 = rand_c(rng, 6) * 0.5
    p0 = problem_through(x0, rng)
    sols = [x0]
    stall = 0
    loops = 0
    while stall < 6 and loops < 200:
        loops += 1
        pa, pb = rand_c(rng, 6, 4, 3), rand_c(rng, 6, 4, 3)
        X = np.array(sols)
        X1, ok1 = track(X, p0, pa)
        X2, ok2 = track(X1[ok1], pa, pb)
        X3, ok3 = track(X2[ok2], pb, p0)
        before = len(sols)
        sols = dedupe(sols + list(X3[ok3]))
        stall = stall + 1 if len(sols) == before else 0
        print(f"loop {loops}: {len(sols)} solutions", file=sys.stderr)
    X = np.array(sols)
    P = np.broadcast_to(p0, (len(sols),) + p0.shape)
    for _ in range(3):  # Newton polish of the tabulated solutions
        X = X - np.linalg.solve(jac(X, P), F(X, P)[..., None])[..., 0]
    P = np.broadcast_to(p0, (len(sols),) + p0.shape)
    res = np.abs(F(X, P)).max(axis=1)
    cond = np.linalg.cond(jac(X, P))
    gap = min(np.linalg.norm(X[i] - X[j]) for i in range(len(X)) for j in range(i))
    print(f"{len(sols)} solutions, max residual {res.max():.2e}, max cond(J) {cond.max():.2e}, "
          f"min distance {gap:.2e}", file=sys.stderr)
    if len(sols) != a.expect or res.max() > 1e-8:
        raise SystemExit(f"found {len(sols)} solutions (expected {a.expect}), residual {res.max():.1e}")
    emit(p0, X, a.seed)


def _c(v):
    return ", ".join(f"{z:.17g}" for z in v)


def emit(p0, X, seed):
    """Write the C tables: the start problem (6 x 4 x 3, real and imaginary
    parts) and its solutions (64 x 6)."""
    print("/* Generated by tools/sixpt_start.py --seed %d: do not edit. The start problem of"
          % seed)
    print(" * csrc/sixpt.c's parameter homotopy (o1, d1, o2, d2 per correspondence, complex)")
    print(" * and its %d solutions x = (Cayley s, t), all found by monodromy and checked. */" % len(X))
    print("#ifndef MCGEOM_SIXPT_START_H\n#define MCGEOM_SIXPT_START_H\n")
    print("#define SIXPT_N_START %d\n" % len(X))
    for name, arr in (("re", p0.real), ("im", p0.imag)):
        print(f"static const double sixpt_p0_{name}[72] = {{")
        for row in arr.reshape(-1, 12):
            print(f"    {_c(row)},")
        print("};\n")
    for name, arr in (("re", X.real), ("im", X.imag)):
        print(f"static const double sixpt_x0_{name}[SIXPT_N_START * 6] = {{")
        for row in arr:
            print(f"    {_c(row)},")
        print("};\n")
    print("#endif /* MCGEOM_SIXPT_START_H */")


if __name__ == "__main__":
    main()
