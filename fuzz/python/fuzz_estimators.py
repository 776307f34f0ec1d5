#!/usr/bin/env python3
"""atheris harness of every registered estimator (``mcgeom.registry.names()``)
on fuzzed ``RayPairs``.

Rays come from a synthetic problem (a synth rig, a decoded motion, noise,
outliers, cross-camera matches, ``rig.ray_pairs``) and are then damaged as
real data can be: NaN/inf/huge/denormal entries, zero directions, all
origins collapsed onto one point (a central rig), duplicated or truncated
pairs, all pairs in one camera, rays replaced by arbitrary vectors, no
camera ids; or the arrays are arbitrary floats altogether. Byte-decoded
choice of the estimator and of a few of its options (bnb_lp always with a
small budget: max_blocks <= 400, resolution >= 0.02). Outcomes: a RigMotion
with R a rotation and t finite (fuzz/python/_common.py: check_motion), or
ValueError / McgeomError with a message.
"""
from __future__ import annotations

import os
import sys

import atheris

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
with atheris.instrument_imports(include=["mcgeom"]):
    import numpy as np

    import mcgeom
    from mcgeom import registry, synth
    from mcgeom.types import RayPairs

import _common  # noqa: E402

NAMES = registry.names()
RIGS = [synth.ladybug2(), synth.stereo_head(), synth.ring_rig(3), synth.axial_rig(3),
        synth.ring_rig(1)]


def synthetic_rays(fdp):
    rig = RIGS[fdp.ConsumeIntInRange(0, len(RIGS) - 1)]
    n = fdp.ConsumeIntInRange(0, 60)
    seed = fdp.ConsumeIntInRange(0, 2**16)
    R, t = synth.random_motion(np.random.default_rng(seed),
                               max_angle=fdp.ConsumeFloatInRange(0.0, 3.2),
                               t_norm=fdp.ConsumeFloatInRange(0.0, 2.0))
    prob = synth.make_problem(rig, R, t, n, rng=seed,
                              cross_fraction=_common.cross_fraction(fdp, rig),
                              pixel_noise=fdp.ConsumeFloatInRange(0.0, 2.0),
                              outlier_fraction=fdp.ConsumeFloatInRange(0.0, 0.5))
    return rig.ray_pairs(prob.pixels1, prob.pixels2, prob.cam1, prob.cam2)


def damage(fdp, r: RayPairs) -> RayPairs:
    arrs = [r.origins1.copy(), r.dirs1.copy(), r.origins2.copy(), r.dirs2.copy()]
    cam1, cam2 = r.cam1, r.cam2
    n = len(r)
    for _ in range(fdp.ConsumeIntInRange(0, 3)):
        kind = fdp.ConsumeIntInRange(0, 8)
        a = arrs[fdp.ConsumeIntInRange(0, 3)]
        if kind == 0 and n:
            a.reshape(-1)[fdp.ConsumeIntInRange(0, a.size - 1)] = _common.floats(fdp, 1)[0]
        elif kind == 1 and n:
            a[fdp.ConsumeIntInRange(0, n - 1)] = 0.0              # zero direction/origin
        elif kind == 2:
            arrs[0][:] = arrs[0][:1] if n else arrs[0]            # collapsed origins
            arrs[2][:] = arrs[0][:1] if n else arrs[2]
        elif kind == 3 and n:
            k = fdp.ConsumeIntInRange(1, 3)                       # duplicated pairs
            arrs = [np.repeat(x, k, axis=0) for x in arrs]
            cam1 = None if cam1 is None else np.repeat(cam1, k)
            cam2 = None if cam2 is None else np.repeat(cam2, k)
            n *= k
        elif kind == 4:
            m = fdp.ConsumeIntInRange(0, n)                       # truncated
            arrs = [x[:m] for x in arrs]
            cam1 = None if cam1 is None else cam1[:m]
            cam2 = None if cam2 is None else cam2[:m]
            n = m
        elif kind == 5 and cam1 is not None:
            cam1 = np.zeros_like(cam1)                            # all in one camera
            cam2 = np.zeros_like(cam2)
        elif kind == 6:
            cam1 = cam2 = None
        elif kind == 7 and n:
            a *= 10.0 ** fdp.ConsumeIntInRange(-200, 200)         # huge/tiny scale
        elif kind == 8 and n:
            a[:] = _common.floats(fdp, a.size, special=False).reshape(a.shape)
    return RayPairs(*arrs, cam1=cam1, cam2=cam2)


def arbitrary_rays(fdp) -> RayPairs:
    n = fdp.ConsumeIntInRange(0, 40)
    special = fdp.ConsumeIntInRange(0, 3) == 0
    arrs = [_common.floats(fdp, 3 * n, special).reshape(n, 3) * 5.0 for _ in range(4)]
    cams = np.array([fdp.ConsumeIntInRange(0, 3) for _ in range(n)], dtype=np.int64)
    return RayPairs(*arrs, cam1=cams if fdp.ConsumeBool() else None,
                    cam2=cams if fdp.ConsumeBool() else None)


def options_for(fdp, name: str) -> dict:
    opts: dict = {}
    if name == "bnb_lp":
        opts = {"max_blocks": fdp.ConsumeIntInRange(0, 400),
                "resolution": fdp.ConsumeFloatInRange(0.02, 0.5),
                "polish": fdp.ConsumeBool()}
        if fdp.ConsumeBool() and "glpk" in registry.lp_backends():
            opts["lp_backend"] = "glpk"
    elif name == "refine" and fdp.ConsumeBool():
        opts = {"loss": ["cauchy", "huber", "soft_l1", "none", "bogus"][fdp.ConsumeIntInRange(0, 4)],
                "max_iterations": fdp.ConsumeIntInRange(-1, 60)}
    elif name == "linear17" and fdp.ConsumeBool():
        opts = {"refine": fdp.ConsumeBool(), "max_iterations": fdp.ConsumeIntInRange(-1, 200)}
    elif name in ("five_plus_one", "eigensolver") and fdp.ConsumeBool():
        # (unrefined, their std comes from the Sampson cost at the estimate
        # and one step towards its optimum: _finish.unrefined_scale_std)
        opts = {"refine": fdp.ConsumeBool()}
    return opts


def TestOneInput(data: bytes) -> None:
    fdp = atheris.FuzzedDataProvider(data)
    name = NAMES[fdp.ConsumeIntInRange(0, len(NAMES) - 1)]
    try:
        rays = damage(fdp, synthetic_rays(fdp)) if fdp.ConsumeIntInRange(0, 3) else \
            arbitrary_rays(fdp)
    except Exception as exc:  # noqa: BLE001 -- bad rays must be refused with ValueError
        if _common.allowed(exc):
            return
        raise
    opts = options_for(fdp, name)
    try:
        m = registry.get(name)(rays, **opts)
    except Exception as exc:  # noqa: BLE001 -- the harness classifies every exception
        if _common.allowed(exc):
            return
        raise
    _common.check_motion(m, f"{name}({len(rays)} rays, {opts})")


def main() -> None:
    atheris.Setup(sys.argv, TestOneInput)
    atheris.Fuzz()


if __name__ == "__main__":
    main()
