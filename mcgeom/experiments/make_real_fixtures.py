"""Small ``.npz`` fixtures of matched pixels from the real recordings, for the tests.

``tests/test_real_data_estimators.py`` runs every registered estimator on these fixtures
(no images, no data folder needed at test time). This experiment writes them::

    mcgeom experiment make_real_fixtures --out tests/data/real

For each fixture below, a frame pair of one recording of ``../shared/data`` is matched as
:mod:`mcgeom.experiments.real_data` does it (:func:`~mcgeom.experiments.real_data.correspondences`:
SIFT, Lowe ratio, mutual check; intra-camera and, between overlapping views, cross-camera
matches; tracked stereo correspondences for KITTI-00), the default robust pipeline
(:func:`mcgeom.cv.estimate`, 5+1 in LO-RANSAC, threshold
:data:`~mcgeom.experiments.real_data.THRESHOLD_PX` pixels) keeps its inliers, and at most
``--max-corr`` of them are kept (seeded; cross-camera inliers first, up to half), so that
each file stays a few tens of KB. A fixture holds:

* ``pixels1``, ``pixels2`` (N, 2) float64 pixels, ``cam1``, ``cam2`` (N,) int16 camera ids;
* ``rig_json``: the rig as mcgeom JSON text (:func:`mcgeom.io.rig_to_dict`), cam_from_rig
  in the recording's rig frame (its ``Rig.frame`` is recorded);
* ``R_gt``, ``t_gt``: the ground-truth motion rig2_from_rig1 (``X2 = R X1 + t``, metres);
* ``kind``: ``"static"`` (the rig did not move: the answer is ``t = 0``),
  ``"straight_intra"`` (straight driving, intra-camera matches only: the scale is not
  observable), ``"cross"`` (cross-camera matches fix the metric scale);
* ``meta``: JSON text: recording, frame pair, mode, counts, what 5+1 returned at
  extraction, the command.

Straight-driving pairs are chosen as the pair of smallest ground-truth rotation among the
first ``--candidates`` pairs (KITTI raw 0023 turns by 0.10-0.19 deg per frame).
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path
from typing import Any, Optional

import numpy as np

from . import real_data as rd
from .common import Progress, no_progress, positive_int, write_line

__all__ = ["FIXTURES", "FixtureSpec", "extract_fixture", "make_fixtures", "load_fixture",
           "add_arguments", "run_cli"]


class FixtureSpec:
    """One fixture: a recording (a key of :data:`mcgeom.experiments.real_data.SET_KEYS`),
    its kind, the matching mode and the candidate frame pairs (None: the set's pairs)."""

    def __init__(self, name: str, key: str, kind: str, mode: str,
                 pairs: Optional[list] = None, note: str = ""):
        self.name, self.key, self.kind, self.mode = name, key, kind, mode
        self.pairs, self.note = pairs, note


#: the fixtures of tests/data/real, in the order they are written
FIXTURES: tuple[FixtureSpec, ...] = (
    FixtureSpec("euroc_static", "euroc", "static", "intra+cross", [(0, 1)],
                "EuRoC V1_01 clip, MAV standing still (GT |t| ~1 mm), stereo"),
    FixtureSpec("ddad01_static", "dgp_scene_01", "static", "intra+cross", [(0, 1)],
                "DDAD scene_01, parked car, 6-camera surround rig, cross-camera matches"),
    FixtureSpec("kitti_raw_straight_intra", "kitti_raw", "straight_intra", "intra", None,
                "KITTI raw 0023 straight driving, intra-camera matches only"),
    FixtureSpec("kitti00_straight_intra", "kitti00_tracks", "straight_intra", "intra", None,
                "KITTI-00 GTSAM stereo tracks, straight driving, intra-camera only"),
    FixtureSpec("kitti_raw_cross", "kitti_raw", "cross", "intra+cross", [(0, 1)],
                "KITTI raw 0023, stereo cross-camera matches (metric)"),
    FixtureSpec("ddad02_cross", "dgp_scene_02", "cross", "intra+cross", [(0, 1)],
                "DDAD scene_02, moving surround rig, cross-camera matches (metric)"),
)


def _straightest(seq: rd.Sequence, candidates: int) -> tuple[int, int]:
    """The pair of smallest ground-truth rotation among the first ``candidates``."""
    pairs = seq.pairs[:candidates]
    if not pairs:
        raise ValueError(f"{seq.name}: no frame pairs with ground truth")
    return min(pairs, key=lambda p: rd.rot_angle_deg(seq.gt_motion(*p)[0]))


def _subsample(corr: rd.Corr, max_corr: int, rng: np.random.Generator) -> np.ndarray:
    """Indices of at most ``max_corr`` correspondences: cross-camera first (up to half),
    then intra-camera; sorted, so the fixture keeps the matcher's order."""
    cross = np.flatnonzero(~corr.intra)
    intra = np.flatnonzero(corr.intra)
    n_cross = min(cross.size, max_corr // 2)
    keep_cross = rng.choice(cross, n_cross, replace=False) if n_cross < cross.size else cross
    n_intra = min(intra.size, max_corr - keep_cross.size)
    keep_intra = rng.choice(intra, n_intra, replace=False) if n_intra < intra.size else intra
    return np.sort(np.concatenate([keep_cross, keep_intra]).astype(np.int64))


def extract_fixture(spec: FixtureSpec, root: Path, max_corr: int = 200, candidates: int = 6,
                    seed: int = 0) -> dict[str, Any]:
    """The arrays of one fixture (see the module docstring), from the recording."""
    from mcgeom.cv import estimate
    from mcgeom.io import rig_to_dict

    seq = rd.load_sequences((spec.key,), root)[0]
    k1, k2 = spec.pairs[0] if spec.pairs else _straightest(seq, candidates)
    corr = rd.correspondences(seq, k1, k2, rd.Features(seq.nfeatures) if seq.kind == "images"
                              else None)
    use = corr if spec.mode == "intra+cross" else corr.subset(corr.intra)
    m = estimate(use.p1, use.p2, use.c1, use.c2, seq.rig, threshold=rd.THRESHOLD_PX)
    inl = use.subset(np.asarray(m.inliers, bool))
    keep = _subsample(inl, max_corr, np.random.default_rng(seed))
    fix = inl.subset(keep)
    R_gt, t_gt = seq.gt_motion(k1, k2)
    meta = {
        "fixture": spec.name, "recording": seq.name, "set": spec.key, "pair": [k1, k2],
        "mode": spec.mode, "kind": spec.kind, "note": spec.note,
        "matches": int(len(use.p1)), "inliers_5p1": int(len(inl.p1)),
        "kept": int(len(fix.p1)), "kept_cross": int(np.count_nonzero(~fix.intra)),
        "threshold_px": rd.THRESHOLD_PX, "seed": seed,
        "five_plus_one_at_extraction": {
            "rot_err_deg": rd.rot_angle_deg(np.asarray(m.R) @ R_gt.T),
            "observable": bool(m.scale.observable), "reason": m.scale.reason,
            "t_norm": float(np.linalg.norm(rd.metric_t(m))),
            "rel_std": float(m.scale.rel_std)},
        "gt_rotation_deg": rd.rot_angle_deg(R_gt), "gt_t_norm": float(np.linalg.norm(t_gt)),
        "command": "mcgeom experiment make_real_fixtures",
    }
    return {
        "pixels1": np.ascontiguousarray(fix.p1, np.float64),
        "pixels2": np.ascontiguousarray(fix.p2, np.float64),
        "cam1": fix.c1.astype(np.int16), "cam2": fix.c2.astype(np.int16),
        "rig_json": np.array(json.dumps(rig_to_dict(seq.rig))),
        "R_gt": R_gt, "t_gt": t_gt, "kind": np.array(spec.kind),
        "meta": np.array(json.dumps(meta)),
    }


def load_fixture(path: Any) -> dict[str, Any]:
    """A fixture written by :func:`make_fixtures`: the arrays, ``rig`` (a
    :class:`mcgeom.rig.Rig`), ``kind`` (str) and ``meta`` (dict)."""
    from mcgeom.io import rig_from_dict
    with np.load(path, allow_pickle=False) as z:
        out = {k: z[k] for k in z.files}
    out["rig"] = rig_from_dict(json.loads(str(out.pop("rig_json"))))
    out["kind"] = str(out["kind"])
    out["meta"] = json.loads(str(out["meta"]))
    return out


def make_fixtures(out_dir: Any, root: Path, names: Optional[list] = None, max_corr: int = 200,
                  candidates: int = 6, out=print, progress: Progress = no_progress) -> list[Path]:
    """Write the fixtures ``names`` (default all of :data:`FIXTURES`) to ``out_dir``."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    specs = [s for s in FIXTURES if names is None or s.name in names]
    written = []
    for spec in progress(specs, total=len(specs), desc="fixtures"):
        t0 = time.perf_counter()
        arrays = extract_fixture(spec, root, max_corr=max_corr, candidates=candidates)
        path = out_dir / f"{spec.name}.npz"
        tmp = out_dir / f".{spec.name}.tmp.npz"
        np.savez_compressed(tmp, **arrays)
        os.replace(tmp, path)
        meta = json.loads(str(arrays["meta"]))
        f = meta["five_plus_one_at_extraction"]
        out("%-26s %-40s pair %s: %4d kept (%3d cross) of %4d 5+1 inliers; GT rot %.3f deg "
            "|t| %.3f m; 5+1 rot err %.3f deg, %s; %.1f KB, %.1f s" % (
                spec.name, meta["recording"][:40], tuple(meta["pair"]), meta["kept"],
                meta["kept_cross"], meta["inliers_5p1"], meta["gt_rotation_deg"],
                meta["gt_t_norm"], f["rot_err_deg"],
                "observable" if f["observable"] else "not observable",
                path.stat().st_size / 1024, time.perf_counter() - t0))
        written.append(path)
    return written


def add_arguments(ap: argparse.ArgumentParser) -> None:
    """The options of ``mcgeom experiment make_real_fixtures``."""
    ap.add_argument("--out", type=Path, default=Path("tests/data/real"),
                    help="output folder of the .npz fixtures")
    ap.add_argument("--only", nargs="*", default=None, choices=[s.name for s in FIXTURES],
                    metavar="NAME", help="write only these fixtures (default: all of "
                                         + ", ".join(s.name for s in FIXTURES) + ")")
    ap.add_argument("--max-corr", type=positive_int, default=200,
                    help="correspondences kept per fixture")
    ap.add_argument("--candidates", type=positive_int, default=6,
                    help="frame pairs searched for the straightest one")
    rd.add_data_argument(ap)


def run_cli(args: argparse.Namespace, progress: Progress = no_progress) -> int:
    """Write the fixtures; 2 if the recordings are missing."""
    root = rd.data_root_or_none(args, "make_real_fixtures")
    if root is None:
        return 2
    if rd.cv2 is not None:
        rd.cv2.setNumThreads(2)
    write_line(f"data {root}; writing to {args.out}")
    make_fixtures(args.out, root, args.only, args.max_corr, args.candidates, out=write_line,
                  progress=progress)
    return 0

