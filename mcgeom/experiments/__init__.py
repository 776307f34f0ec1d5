"""The application layer: the experiments of the thesis chapters, the
evaluations on real recordings, the benchmarks (:mod:`mcgeom.experiments.bench`)
and the demo (:mod:`mcgeom.experiments.demo`).

Each experiment runs as ``mcgeom experiment NAME [options]``. Its module
exposes ``add_arguments(parser)`` (its command-line options) and
``run_cli(args) -> int`` (the exit code), next to importable functions that
the tests call with small sizes. The modules are imported only when their
experiment runs, so that ``mcgeom --help`` does not pay for them.

Unlike the library, these modules may use :mod:`mcgeom.synth` (synthetic
data) and peer libraries (poselib, clarabel), the latter imported lazily.
"""

from __future__ import annotations

import importlib
from types import ModuleType

__all__ = ["EXPERIMENTS", "load"]

#: name -> (module under mcgeom.experiments, one-line description)
EXPERIMENTS: dict[str, tuple[str, str]] = {
    "ch6": ("ch6", "thesis ch. 6.5.1: known-rotation translations of 101 views on a "
                   "circle, bilinear/trilinear x plain/constrained"),
    "ch6_rig_scale": ("ch6_rig_scale", "thesis ch. 6 with a rig's offsets: is the metric scale "
                                       "of the algebraic solution and of its bundle adjustment "
                                       "within its std? (4-camera ring, no overlap)"),
    "ch7": ("ch7", "thesis ch. 7.5.2: scale observability of the 8-camera vehicle rig"),
    "ch8": ("ch8", "thesis ch. 8.5.1: linear17 next to PoseLib on three rigs (needs poselib)"),
    "ch9": ("ch9", "thesis ch. 10.5.1 set-up: E+SOCP next to linear17 and five_plus_one"),
    "ch10": ("ch10", "thesis ch. 10.5.1: B&B+LP against E+SOCP, and the preemptive test"),
    "linear17_accuracy": ("linear17_accuracy", "issue 22: the steps of linear17 varied one "
                                               "at a time against OpenGV's reported approach "
                                               "and the previous version, paired"),
    "linear17_peers": ("linear17_peers", "issue 22: linear17 next to OpenGV's seventeenpt on "
                                         "identical rays of the issue's five cases (needs a "
                                         "user-built OpenGV module, else mcgeom alone)"),
    "minimal_5p1": ("minimal_5p1", "noise-free minimal 5+1 samples: how often the true "
                                   "motion is among the solutions"),
    "calibration_coverage": ("calibration_coverage", "synthetic rigs with perturbed "
                                                     "extrinsics: does the 3-sigma interval "
                                                     "of |t| contain the truth?"),
    "calibration_real": ("calibration_real", "a real near-critical DDAD step: the first-order "
                                             "calibration part of the std of |t| next to the "
                                             "sampled one"),
    "robust_vs_poselib": ("robust_vs_poselib", "robust rig motion from pixels: mcgeom "
                                               "against PoseLib (needs poselib)"),
    "real_data": ("real_data", "the robust pipeline on the real recordings (KITTI, DDAD, "
                               "EuRoC), against their ground truth"),
    "bnb_real": ("bnb_real", "bnb_lp (ch. 10) on the 5+1 inliers of KITTI raw and DDAD: "
                             "rotation, |t|, verdict, time, blocks, certified gap"),
    "direct_outliers": ("direct_outliers", "the direct estimators given 2 % gross outliers on "
                                           "the property suite's rig kinds: is a wrong "
                                           "estimate ever called metric?"),
    "honesty": ("honesty", "every estimator on the inliers of the real recordings: rotation "
                           "error, |t| against the truth, verdict, rel_std, time"),
    "ch6_kitti": ("ch6_kitti", "thesis ch. 6 on real data: the KITTI-00 stereo trajectory "
                               "from tracks with known rotations"),
    "odometry_kitti00": ("odometry_kitti00", "the sequence back end on the KITTI-00 stereo "
                                             "tracks: ATE and scale drift, next to naive "
                                             "chaining and PoseLib"),
    "odometry_real": ("odometry_real", "the whole sequence pipeline on the real image "
                                       "recordings (KITTI raw, DDAD, EuRoC) against their "
                                       "ground truth"),
    "make_real_fixtures": ("make_real_fixtures", "the small .npz fixtures of matched pixels "
                                                 "from the real recordings that "
                                                 "tests/test_real_data_estimators.py runs "
                                                 "every estimator on"),
    "peer_solvers": ("peer_solvers", "the upright 4-point solver next to PoseLib's: noise-free "
                                     "minimal configurations, then RANSAC from pixels with a "
                                     "known vertical (needs poselib)"),
    "batch_scaling": ("batch_scaling", "mcgeom batch on Dask: sequences per minute with 1 "
                                       "and 2 workers, scheduler overhead per task, and the "
                                       "extrapolation to 10,000 sequences (needs dask)"),
}


def load(name: str) -> ModuleType:
    """The module of experiment ``name`` (a key of :data:`EXPERIMENTS`)."""
    return importlib.import_module(f"{__name__}.{EXPERIMENTS[name][0]}")
