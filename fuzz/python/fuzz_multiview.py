#!/usr/bin/env python3
"""atheris harness of ``mcgeom.multiview.translations_from_tracks`` (thesis
ch. 6) with and without rig offsets, and so of the bundle adjustment of
``mcgeom.multiview_refine`` behind a rig's metric centres.

Input: 2-6 views with decoded rotations and centres, 1-3 rig cameras at
decoded offsets (or central views), 1-40 points each seen by a decoded run
of views through one camera; the exact bearings, then damaged as real data
can be (NaN/inf/huge/denormal entries, zero bearings, a bearing replaced by
an arbitrary vector, a repeated observation, all points at one place), or
arbitrary floats altogether; the relation, solver, pairs, window, refine,
max_rel_std and rotation_std decoded. Outcomes: a TranslationResult whose centres are finite
for the solved views and NaN for the others, a metric verdict only with
origins, a finite relative std at most max_rel_std and a finite refinement
summary; or ValueError / McgeomError with a message.
"""
from __future__ import annotations

import os
import sys

import atheris

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
with atheris.instrument_imports(include=["mcgeom"]):
    import numpy as np

    from mcgeom import multiview, synth

import _common  # noqa: E402


def rotation(fdp) -> np.ndarray:
    w = np.array([fdp.ConsumeFloatInRange(-3.2, 3.2) for _ in range(3)])
    a = float(np.linalg.norm(w))
    return synth.rotation_about(w / a, a) if a > 0 else np.eye(3)


def problem(fdp):
    m = fdp.ConsumeIntInRange(2, 6)
    rot = np.array([rotation(fdp) for _ in range(m)])
    centres = np.array([[fdp.ConsumeFloatInRange(-3.0, 3.0) for _ in range(3)]
                        for _ in range(m)])
    rig = fdp.ConsumeBool()
    cams = np.array([[fdp.ConsumeFloatInRange(-0.5, 0.5) for _ in range(3)]
                     for _ in range(fdp.ConsumeIntInRange(1, 3))])
    track, view, bear, org = [], [], [], []
    for p in range(fdp.ConsumeIntInRange(1, 40)):
        X = np.array([fdp.ConsumeFloatInRange(-10.0, 10.0) for _ in range(3)])
        X[2] += 12.0
        first = fdp.ConsumeIntInRange(0, m - 1)
        for v in range(first, min(m, first + fdp.ConsumeIntInRange(1, m))):
            o = cams[fdp.ConsumeIntInRange(0, len(cams) - 1)] if rig else np.zeros(3)
            track.append(p)
            view.append(v)
            bear.append(rot[v] @ (X - centres[v]) - o)
            org.append(o)
    track, view = np.array(track), np.array(view)
    bear, org = np.array(bear), np.array(org)
    noise = fdp.ConsumeFloatInRange(0.0, 0.01)
    if noise and len(bear):
        bear = synth.perturb_directions(bear / np.maximum(np.linalg.norm(
            bear, axis=1, keepdims=True), 1e-300), noise, np.random.default_rng(0))
    return track, view, bear, rot, org if rig else None


def damage(fdp, track, view, bear, org):
    n = len(track)
    for _ in range(fdp.ConsumeIntInRange(0, 2)):
        kind = fdp.ConsumeIntInRange(0, 5)
        if n == 0:
            break
        k = fdp.ConsumeIntInRange(0, n - 1)
        if kind == 0:
            bear[k, fdp.ConsumeIntInRange(0, 2)] = _common.floats(fdp, 1)[0]
        elif kind == 1:
            bear[k] = 0.0
        elif kind == 2:
            bear[k] = _common.floats(fdp, 3)
        elif kind == 3:   # a repeated observation
            track, view = np.r_[track, track[k]], np.r_[view, view[k]]
            bear = np.vstack([bear, bear[k]])
            org = None if org is None else np.vstack([org, org[k]])
        elif kind == 4 and org is not None:
            org[k, fdp.ConsumeIntInRange(0, 2)] = _common.floats(fdp, 1)[0]
        elif kind == 5:   # every point at one place
            bear[:] = bear[k]
    return track, view, bear, org


def TestOneInput(data: bytes) -> None:
    fdp = atheris.FuzzedDataProvider(data)
    track, view, bear, rot, org = problem(fdp)
    track, view, bear, org = damage(fdp, track, view, bear, org)
    relation = multiview.RELATIONS[fdp.ConsumeIntInRange(0, 1)]
    kw = dict(relation=relation, solver=multiview.SOLVERS[fdp.ConsumeIntInRange(0, 1)],
              pairs=multiview.PAIRS[fdp.ConsumeIntInRange(0, 1)],
              window=fdp.ConsumeIntInRange(1, 4), refine=fdp.ConsumeBool(),
              max_rel_std=fdp.ConsumeFloatInRange(0.0, 1.0))
    kw["rotation_std"] = fdp.ConsumeFloatInRange(0.0, 0.01) if kw["refine"] else 0.0
    try:
        r = multiview.translations_from_tracks(track, view, bear, rot, origins=org, **kw)
    except _common.ALLOWED as exc:
        _common.allowed(exc)
        return
    what = f"translations_from_tracks({kw})"
    c = r.centres
    if c.shape != (len(rot), 3):
        raise _common.Finding(f"{what}: centres of shape {c.shape}")
    if not np.all(np.isfinite(c[r.connected])) or not np.all(np.isnan(c[~r.connected])):
        raise _common.Finding(f"{what}: centres not finite exactly for the solved views")
    if r.scale.observable:
        if org is None:
            raise _common.Finding(f"{what}: central views called metric")
        if not 0.0 <= r.scale.rel_std <= kw["max_rel_std"]:
            raise _common.Finding(f"{what}: metric at rel_std {r.scale.rel_std}")
    if r.refinement is not None:
        if org is None or not kw["refine"]:
            raise _common.Finding(f"{what}: a refinement without being asked")
        rot = r.refinement.get("rotation_rel_std", 0.0)
        if not (np.isfinite(r.refinement["rms"]) and r.refinement["iterations"] >= 0
                and rot >= 0.0):
            raise _common.Finding(f"{what}: refinement summary {r.refinement}")


def main() -> None:
    atheris.Setup(sys.argv, TestOneInput)
    atheris.Fuzz()


if __name__ == "__main__":
    main()
