"""Error metrics of motion estimates and trajectories.

A motion is rig2_from_rig1 (docs/architecture.md §3): ``X_rig2 = R X_rig1 + t``,
``t`` in metres in the rig2 frame; as a 4x4 matrix ``M = [[R, t], [0, 1]]``.
Poses are world_from_rig 4x4 matrices (metres). Angles are in radians.

These are the yardsticks of the tests, the demo, the benchmarks and the
experiments; they live apart from :mod:`mcgeom.synth` so that library code
can measure errors without depending on the synthetic-data generator.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from .validation import check_int, check_points, check_poses

__all__ = ["rotation_error", "translation_errors", "rotation_angle", "motion_errors",
           "loop_closure_error", "path_length", "polyline_length", "align_se3", "absolute_trajectory_error",
           "relative_pose_error", "scale_drift"]


def rotation_error(R_est: np.ndarray, R_true: np.ndarray) -> float:
    """Angle (radians, in [0, pi]) of the rotation ``R_est R_true^T``.

    Both are 3x3 rotations between the same two frames (e.g. rig2_from_rig1).
    Computed with atan2 of the sine and cosine parts, accurate for tiny angles too
    (arccos of the trace loses half the digits near 0).
    """
    D = np.asarray(R_est, dtype=np.float64) @ np.asarray(R_true, dtype=np.float64).T
    s = 0.5 * np.linalg.norm([D[2, 1] - D[1, 2], D[0, 2] - D[2, 0], D[1, 0] - D[0, 1]])
    c = 0.5 * (np.trace(D) - 1.0)
    return float(np.arctan2(s, c))


def translation_errors(t_est: np.ndarray, t_true: np.ndarray) -> tuple[float, float]:
    """``(direction_error, scale_ratio)`` of a translation estimate.

    ``t_est`` and ``t_true`` are 3-vectors in the same frame (the rig2 frame for a
    rig2_from_rig1 motion), any unit. ``direction_error`` is the angle (radians)
    between them; ``scale_ratio`` is ``|t_est| / |t_true|`` (1 = exact metric
    scale). Both are NaN when ``t_true`` is zero; the angle is NaN when ``t_est``
    is zero.
    """
    a = np.asarray(t_est, dtype=np.float64).reshape(3)
    b = np.asarray(t_true, dtype=np.float64).reshape(3)
    na, nb = np.linalg.norm(a), np.linalg.norm(b)
    if nb == 0:
        return float("nan"), float("nan")
    if na == 0:
        return float("nan"), 0.0
    angle = np.arctan2(np.linalg.norm(np.cross(a, b)), a @ b)
    return float(angle), float(na / nb)


def rotation_angle(R: np.ndarray) -> float:
    """Rotation angle of a 3x3 rotation, radians in [0, pi] (accurate near 0)."""
    return rotation_error(R, np.eye(3))


def motion_errors(M_est: np.ndarray, M_true: np.ndarray) -> dict:
    """Errors of a 4x4 rig2_from_rig1 motion estimate against the truth.

    Returns a dict: ``rot_err`` (radians), ``dir_err`` (radians, angle between
    the translations, rig2 frame), ``scale_ratio`` (``|t_est| / |t_true|``) and
    ``t_err`` (``|t_est - t_true|``, metres).
    """
    dir_err, ratio = translation_errors(M_est[:3, 3], M_true[:3, 3])
    return {
        "rot_err": rotation_error(M_est[:3, :3], M_true[:3, :3]),
        "dir_err": dir_err,
        "scale_ratio": ratio,
        "t_err": float(np.linalg.norm(M_est[:3, 3] - M_true[:3, 3])),
    }


def loop_closure_error(poses: Sequence[np.ndarray]) -> tuple[float, float]:
    """(position gap in metres, rotation gap in radians) between the last and the
    first of a sequence of world_from_rig 4x4 poses (0 for a closed loop)."""
    D = np.linalg.inv(poses[0]) @ poses[-1]
    return float(np.linalg.norm(D[:3, 3])), rotation_angle(D[:3, :3])


# --- trajectory metrics (issue 17) --------------------------------------------
# The definitions are those of the TUM RGB-D benchmark (Sturm et al., "A Benchmark
# for the Evaluation of RGB-D SLAM Systems", IROS 2012, eqs. 1-4) as evo computes
# them (tests/test_metrics.py compares with evo to 1e-9), except that the
# alignment never corrects the scale: the metric scale is what is measured.


def _pose_pair(est_poses: np.ndarray, gt_poses: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Both pose lists checked: (N, 4, 4) rigid world_from_rig, same N."""
    est = check_poses("est_poses", est_poses)
    gt = check_poses("gt_poses", gt_poses)
    if est.shape[0] != gt.shape[0]:
        raise ValueError(f"est_poses has {est.shape[0]} poses and gt_poses {gt.shape[0]}: "
                         "they must be the same frames (select the frames both have)")
    return est, gt


def polyline_length(positions: np.ndarray) -> float:
    """Length of the polyline through ``positions`` (N, 3), in their unit:
    sum of ``|p_{k+1} - p_k|``; 0 for one position."""
    return float(np.sum(np.linalg.norm(np.diff(positions, axis=0), axis=1)))


def path_length(poses: np.ndarray) -> float:
    """Length (metres) of the polyline through the positions of world_from_rig
    ``poses`` (N, 4, 4): sum of ``|t_{k+1} - t_k|``; 0 for one pose."""
    return polyline_length(check_poses("poses", poses)[:, :3, 3])


def align_se3(est_positions: np.ndarray, gt_positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rigid transform ``(R, t)`` minimising ``sum_i |gt_i - (R est_i + t)|^2``.

    ``est_positions``, ``gt_positions``: (N, 3) positions (metres) of the same
    frames in two world frames; ``R`` (3, 3) rotation and ``t`` (3,) metres map
    the estimate's world frame into the truth's (gt_world_from_est_world).

    Umeyama (PAMI 1991, eqs. 38-41) with the scale fixed to 1: ``Sigma = (1/N)
    sum (gt_i - mu_gt)(est_i - mu_est)^T = U D V^T``, ``R = U S V^T`` with ``S =
    diag(1, 1, det(U) det(V))`` (a rotation, never a reflection), ``t = mu_gt -
    R mu_est``. The scale is not aligned: a metric estimate must be right in
    metres. When the points do not fix ``R`` (fewer than 3 non-collinear
    points, or a constant trajectory) every minimiser has the same residuals
    and one of them is returned (evo raises instead).
    """
    x = check_points("est_positions", est_positions)
    y = check_points("gt_positions", gt_positions)
    if x.shape != y.shape or x.shape[0] == 0:
        raise ValueError(f"est_positions {x.shape} and gt_positions {y.shape} must be the "
                         "same non-empty (N, 3) shape (the same frames)")
    mx, my = x.mean(axis=0), y.mean(axis=0)
    cov = (y - my).T @ (x - mx) / x.shape[0]
    U, _, Vt = np.linalg.svd(cov)
    S = np.eye(3)
    if np.linalg.det(U) * np.linalg.det(Vt) < 0:
        S[2, 2] = -1.0
    R = U @ S @ Vt
    return R, my - R @ mx


def _stats(e: np.ndarray) -> dict:
    """RMSE, mean, median, max, std of errors (evo's statistics)."""
    return {"rmse": float(np.sqrt(np.mean(e * e))), "mean": float(np.mean(e)),
            "median": float(np.median(e)), "max": float(np.max(e)), "std": float(np.std(e))}


def absolute_trajectory_error(est_poses: np.ndarray, gt_poses: np.ndarray) -> dict:
    """Absolute trajectory error of world_from_rig ``est_poses`` against
    ``gt_poses`` (both (N, 4, 4), metres, the same N frames).

    The estimate is first aligned by :func:`align_se3` on the positions (rigid,
    no scale), then ``e_i = |t_gt_i - t_aligned_i|`` (Sturm et al. 2012, eq. 3;
    evo's APE on the translation part after ``align(correct_scale=False)``).

    Returns a dict: ``rmse``, ``mean``, ``median``, ``max``, ``std`` (metres),
    ``errors`` (N,) metres, ``aligned`` (N, 4, 4) the aligned estimate, ``R``,
    ``t`` the alignment (gt_world_from_est_world), ``path_length`` of the truth
    (metres) and ``rmse_percent`` = 100 rmse / path length (NaN for a
    trajectory that does not move).
    """
    est, gt = _pose_pair(est_poses, gt_poses)
    R, t = align_se3(est[:, :3, 3], gt[:, :3, 3])
    A = np.eye(4)
    A[:3, :3], A[:3, 3] = R, t
    aligned = A @ est
    errors = np.linalg.norm(gt[:, :3, 3] - aligned[:, :3, 3], axis=1)
    out = _stats(errors)
    length = path_length(gt)
    out.update(errors=errors, aligned=aligned, R=R, t=t, path_length=length,
               rmse_percent=100.0 * out["rmse"] / length if length > 0 else float("nan"))
    return out


def relative_pose_error(est_poses: np.ndarray, gt_poses: np.ndarray, delta: int = 1) -> dict:
    """Relative pose error over every frame pair ``(i, i + delta)``.

    ``est_poses``, ``gt_poses``: world_from_rig (N, 4, 4), metres, the same N
    frames; ``delta`` >= 1 frames (< N). For each pair, the relative motions
    ``Q = gt_i^-1 gt_j`` and ``P = est_i^-1 est_j`` (rig_i_from_rig_j) give the
    error ``E = Q^-1 P`` (Sturm et al. 2012, eq. 1; evo's RPE with
    ``delta_unit=frames``, ``all_pairs=True``, which for ``delta = 1`` is its
    default). No alignment: relative motions do not depend on the world frame.

    Returns a dict: ``pairs`` (M, 2) int frame indices, ``translation`` (M,)
    ``|E_t| = |P_t - Q_t|`` metres, ``rotation_deg`` (M,) angle of ``E_R``
    in degrees, ``length_ratio`` (M,) ``|P_t| / |Q_t|`` (NaN where the truth
    does not move), and ``translation_rmse``, ``translation_mean`` (m),
    ``rotation_rmse_deg``, ``rotation_mean_deg``.
    """
    est, gt = _pose_pair(est_poses, gt_poses)
    d = check_int("delta", delta)
    n = est.shape[0]
    if not 1 <= d < n:
        raise ValueError(f"delta must be in [1, {n - 1}] for {n} poses, got {d}")
    i = np.arange(n - d)
    j = i + d
    P = np.linalg.inv(est[i]) @ est[j]
    Q = np.linalg.inv(gt[i]) @ gt[j]
    E = np.linalg.inv(Q) @ P
    trans = np.linalg.norm(E[:, :3, 3], axis=1)
    rot = np.degrees([rotation_angle(Ek[:3, :3]) for Ek in E])
    qn = np.linalg.norm(Q[:, :3, 3], axis=1)
    pn = np.linalg.norm(P[:, :3, 3], axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(qn > 0, pn / np.where(qn > 0, qn, 1.0), np.nan)
    return {"pairs": np.stack([i, j], axis=1), "translation": trans, "rotation_deg": rot,
            "length_ratio": ratio,
            "translation_rmse": float(np.sqrt(np.mean(trans ** 2))),
            "translation_mean": float(np.mean(trans)),
            "rotation_rmse_deg": float(np.sqrt(np.mean(rot ** 2))),
            "rotation_mean_deg": float(np.mean(rot))}


def scale_drift(est_poses: np.ndarray, gt_poses: np.ndarray) -> float:
    """Scale drift in percent: ``(L_est / L_gt - 1) * 100``.

    ``L`` is :func:`path_length` of world_from_rig (N, 4, 4) poses of the same
    N frames (metres). +2 means the estimate travelled 2 % too far, -2 % too
    short; it measures the metric scale over the whole run, independent of
    rotation errors (which ATE mixes in). The per-step version is
    ``relative_pose_error(...)["length_ratio"]``. ValueError if the truth does
    not move (``L_gt = 0``: no scale to compare with).
    """
    est, gt = _pose_pair(est_poses, gt_poses)
    lg = path_length(gt)
    if not lg > 0:
        raise ValueError("gt_poses do not move (path length 0): the scale drift is undefined")
    return 100.0 * (path_length(est) / lg - 1.0)
