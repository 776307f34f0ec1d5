"""The main job on the embedded default: a Ladybug2-like head on the closed
∞-shaped path of thesis ch. 8.5.2 (108 positions), every frame-to-frame motion
estimated with a registered estimator (``linear17`` by default) from noisy
pixels, the motions chained, and the errors reported.

Scene: points on the walls of a room around the path (the thesis put books
around the camera), seen by the head's cameras with Gaussian pixel noise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mcgeom import estimate, synth
from mcgeom.metrics import loop_closure_error, motion_errors
from mcgeom.odometry import chain, to_matrix

from .common import Progress, no_progress

__all__ = ["DemoFrame", "DemoResult", "run_demo"]


@dataclass(frozen=True)
class DemoFrame:
    """Errors of one frame-to-frame motion: angles in degrees, ``t_err_m`` in
    metres, ``scale_ratio`` = |t_est| / |t_true|."""

    index: int
    n_rays: int
    rot_err_deg: float
    dir_err_deg: float
    scale_ratio: float
    t_err_m: float
    scale_observable: bool
    camera_kind: str
    iterations: int


@dataclass(frozen=True)
class DemoResult:
    """Per-frame errors, the true and the chained world_from_rig 4x4 poses
    (metres), the loop-closure gap (metres, radians) and the path length (metres)."""

    frames: list
    true_poses: list
    est_poses: list
    loop_gap_m: float
    loop_gap_rad: float
    path_length_m: float

    def summary(self) -> dict:
        """Medians over the frames: rotation and direction errors (deg), |1 - scale|,
        and the number of frames whose scale was reported observable."""
        return {
            "rot_deg": float(np.median([f.rot_err_deg for f in self.frames])),
            "dir_deg": float(np.median([f.dir_err_deg for f in self.frames])),
            "scale_err": float(np.median([abs(1 - f.scale_ratio) for f in self.frames])),
            "n_observable": sum(f.scale_observable for f in self.frames),
        }


def run_demo(method: str = "linear17", pixel_noise: float = 0.3, points_per_camera: int = 60,
             n_positions: int = 108, seed: int = 0,
             progress: Progress = no_progress) -> DemoResult:
    """Simulate the ∞ path and estimate every frame-to-frame motion with ``method``.

    ``pixel_noise``: Gaussian std in pixels. When an estimate reports its scale
    unobservable, the chain uses the method's metric least-squares estimate if
    it has one (``info['t_metric']``) and the frame is flagged; errors are
    computed on what was chained. ``progress`` wraps the loop over the frames.
    """
    rng = np.random.default_rng(seed)
    rig = synth.ladybug2()
    poses = synth.figure_eight_path(n_positions)
    frames, motions = [], []
    for k in progress(range(len(poses)), total=len(poses), desc=f"demo {method}"):
        T1, T2 = poses[k], poses[(k + 1) % len(poses)]
        R_true, t_true = synth.relative_motion(T1, T2)
        M_true = to_matrix(R_true, t_true)
        prob = synth.make_problem(rig, R_true, t_true,
                                  points_per_camera * len(rig.cameras), rng,
                                  pixel_noise=pixel_noise, depth_range=(0.6, 3.0))
        m = estimate(prob.rays, method)
        t = m.t
        if not m.scale.observable and "t_metric" in m.info and np.any(m.info["t_metric"]):
            t = m.info["t_metric"]
        M = to_matrix(m.R, t)
        motions.append(M)
        e = motion_errors(M, M_true)
        frames.append(DemoFrame(k, len(prob.rays), np.degrees(e["rot_err"]),
                                np.degrees(e["dir_err"]), e["scale_ratio"], e["t_err"],
                                m.scale.observable, m.info.get("camera_kind", ""),
                                int(m.info.get("iterations", 0))))
    est = chain(motions, poses[0])
    true = list(poses) + [poses[0]]
    gap_m, gap_r = loop_closure_error(est)
    length = float(sum(np.linalg.norm(true[i + 1][:3, 3] - true[i][:3, 3])
                       for i in range(len(true) - 1)))
    return DemoResult(frames, true, est, gap_m, gap_r, length)
