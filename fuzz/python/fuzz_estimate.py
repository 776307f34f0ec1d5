#!/usr/bin/env python3
"""atheris harness of ``mcgeom.estimateRigMotion`` (the OpenCV-style façade).

A synthetic problem (a rig from mcgeom.synth, a decoded motion, noise,
outliers, cross-camera matches) gives pixels and camera ids, which are then
mutated the way a user's matcher output can be wrong: NaN/inf/huge pixels,
ids out of range or negative, other dtypes and shapes (N x 1 x 2, float32,
integers, transposed), truncated arrays, masks, duplicated matches, all
matches in one camera; with any method flag (including unknown names),
prob, threshold and maxIters. Outcomes: ``retval, R, t, mask`` with R a
rotation, t finite 3 x 1, mask N x 1 uint8 with retval = mask.sum(), or a
ValueError / McgeomError with a message (fuzz/python/_common.py).
"""
from __future__ import annotations

import os
import sys

import atheris

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
with atheris.instrument_imports(include=["mcgeom"]):
    import numpy as np

    import mcgeom
    from mcgeom import synth

import _common  # noqa: E402

RIGS = [lambda: synth.ladybug2(), lambda: synth.stereo_head(), lambda: synth.ring_rig(3),
        lambda: synth.axial_rig(3), lambda: synth.vehicle8(), lambda: synth.ring_rig(1)]
METHODS = [mcgeom.RIG_5P1_RANSAC, mcgeom.RIG_5P1_DIRECT, mcgeom.RIG_LINEAR17,
           mcgeom.RIG_LINEAR17_RANSAC, "refine", "e_socp", "bnb_lp", "nonexistent", ""]
_RIG_CACHE: dict[int, object] = {}


def rig_for(k: int):
    if k not in _RIG_CACHE:
        _RIG_CACHE[k] = RIGS[k]()
    return _RIG_CACHE[k]


def mutate_points(fdp, p: np.ndarray):
    kind = fdp.ConsumeIntInRange(0, 9)
    if kind == 1 and p.size:
        p = p.copy()
        k = fdp.ConsumeIntInRange(0, p.size - 1)
        p.reshape(-1)[k] = _common.floats(fdp, 1)[0] * (1e3 if fdp.ConsumeBool() else 1.0)
        return p
    if kind == 2:
        return p.astype(np.float32).reshape(-1, 1, 2)    # OpenCV's N x 1 x 2
    if kind == 3:
        return p.T                                       # 2 x N
    if kind == 4:
        return p[: fdp.ConsumeIntInRange(0, len(p))]     # truncated
    if kind == 5:
        return np.round(p).astype(np.int32)
    if kind == 6:
        return p.tolist()
    if kind == 7 and p.size:
        return p * _common.floats(fdp, 1)[0] * 1e6
    return p


def mutate_ids(fdp, ids: np.ndarray, ncams: int):
    kind = fdp.ConsumeIntInRange(0, 7)
    ids = np.array(ids)
    if kind == 1 and ids.size:
        ids[fdp.ConsumeIntInRange(0, ids.size - 1)] = fdp.ConsumeIntInRange(-3, ncams + 3)
    elif kind == 2:
        ids = ids.astype(np.float64) + (0.5 if fdp.ConsumeBool() else 0.0)
    elif kind == 3:
        ids = np.zeros_like(ids)                         # all in one camera
    elif kind == 4:
        ids = ids.reshape(-1, 1)
    elif kind == 5:
        return None
    return ids


def TestOneInput(data: bytes) -> None:
    fdp = atheris.FuzzedDataProvider(data)
    rig = rig_for(fdp.ConsumeIntInRange(0, len(RIGS) - 1))
    n = fdp.ConsumeIntInRange(0, 80)
    seed = fdp.ConsumeIntInRange(0, 2**16)
    angle = fdp.ConsumeFloatInRange(0.0, 3.2)
    tn = fdp.ConsumeFloatInRange(0.0, 2.0)
    try:
        R, t = synth.random_motion(np.random.default_rng(seed), max_angle=angle, t_norm=tn)
        prob = synth.make_problem(rig, R, t, n, rng=seed,
                                  cross_fraction=_common.cross_fraction(fdp, rig),
                                  pixel_noise=fdp.ConsumeFloatInRange(0.0, 3.0),
                                  outlier_fraction=fdp.ConsumeFloatInRange(0.0, 0.6))
    except _common.ALLOWED as exc:
        _common.allowed(exc)
        return
    p1, p2, c1, c2 = prob.pixels1, prob.pixels2, prob.cam1, prob.cam2
    if fdp.ConsumeIntInRange(0, 7) == 0 and len(p1):     # duplicated correspondences
        k = fdp.ConsumeIntInRange(1, 4)
        p1, p2 = np.repeat(p1, k, axis=0), np.repeat(p2, k, axis=0)
        c1, c2 = np.repeat(c1, k), np.repeat(c2, k)
    p1, p2 = mutate_points(fdp, p1), mutate_points(fdp, p2)
    ncams = len(rig.cameras)
    c1, c2 = mutate_ids(fdp, c1, ncams), mutate_ids(fdp, c2, ncams)
    if c1 is None:
        c1 = np.asarray(prob.cam1)
    method = METHODS[fdp.ConsumeIntInRange(0, len(METHODS) - 1)]
    kwargs = {}
    if fdp.ConsumeBool():
        kwargs["prob"] = _common.floats(fdp, 1)[0] * 2.0
    if fdp.ConsumeBool():
        kwargs["threshold"] = _common.floats(fdp, 1)[0] * 10.0
    kwargs["maxIters"] = fdp.ConsumeIntInRange(-2, 200)
    if fdp.ConsumeIntInRange(0, 5) == 0:
        m = fdp.ConsumeIntInRange(0, 2)
        size = len(prob.pixels1) + fdp.ConsumeIntInRange(-1, 1)
        kwargs["mask"] = [np.ones(max(size, 0), np.uint8), np.zeros(max(size, 0), np.uint8),
                          np.arange(max(size, 0)) % 2][m]
    if method == "bnb_lp":
        return  # the global search has no budget in the façade: fuzz_estimators covers it
    try:
        retval, R_est, t_est, mask = mcgeom.estimateRigMotion(p1, p2, c1, c2, rig, method=method,
                                                              **kwargs)
    except Exception as exc:  # noqa: BLE001 -- the harness classifies every exception
        if _common.allowed(exc):
            return
        raise
    _common.check_rotation(R_est, f"estimateRigMotion({method})")
    t_est = np.asarray(t_est)
    if t_est.shape != (3, 1) or not np.all(np.isfinite(t_est)):
        raise _common.Finding(f"estimateRigMotion({method}): t {t_est!r}")
    mask = np.asarray(mask)
    if mask.dtype != np.uint8 or mask.ndim != 2 or mask.shape[1] != 1:
        raise _common.Finding(f"estimateRigMotion({method}): mask {mask.dtype} {mask.shape}")
    if retval != int(mask.sum()):
        raise _common.Finding(f"estimateRigMotion({method}): retval {retval} != mask sum")


def main() -> None:
    atheris.Setup(sys.argv, TestOneInput)
    atheris.Fuzz()


if __name__ == "__main__":
    main()
