"""Trajectory plots with matplotlib: a top view coloured by scale status, and the
per-step errors against a ground truth.

Presentation only: the poses come in world_from_rig (metres), the errors from
:mod:`mcgeom.metrics`. The figure is drawn on matplotlib's Agg canvas directly
(``matplotlib.figure.Figure`` + ``FigureCanvasAgg``): pyplot is never imported,
so neither its global figure manager nor the backend of a user's interactive
session is touched, and no display is needed.

Scale status of a step (issue 17): ``metric`` (observed on the step), ``carried``
(propagated along tracks from an observed step), ``unknown`` (no metric length).
A *direction-only* segment (no metric scale at all) is drawn dashed, in its own
colour and with its own legend entry: it never looks like the metric track.
"""

from __future__ import annotations

import io
import os
from dataclasses import dataclass
from typing import Any, Mapping, Optional, Sequence, Union

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from .io.trajectory import write_atomically
from .metrics import path_length, relative_pose_error
from .validation import check_int, check_poses

__all__ = ["STATUS_COLOURS", "DIRECTION_ONLY_COLOUR", "PlotSegment", "plot_trajectory"]

#: line colour of each scale status (colour-blind safe pairs: green/blue/orange)
STATUS_COLOURS = {"metric": "#1a9641", "carried": "#2b6cb0", "unknown": "#e66101"}
#: colour of a direction-only segment (dashed): its steps are the ``unknown`` ones
DIRECTION_ONLY_COLOUR = STATUS_COLOURS["unknown"]
_ESTIMATE_COLOUR = "#2b6cb0"     # an estimate drawn without scale statuses
_AXES = "xyz"
_DPI = 100


@dataclass(frozen=True)
class PlotSegment:
    """One drawn piece of an estimated trajectory.

    ``frames`` (n,): increasing frame indices (indices into ``gt_poses`` and into
    the per-step arrays, step ``k`` being frame ``k`` -> ``k + 1``); ``poses``
    (n, 4, 4): world_from_rig of those frames, metres when ``metric``, otherwise a
    direction-only shape with no unit. Any object with these three attributes
    (e.g. ``mcgeom.sequence`` segments) is accepted by :func:`plot_trajectory`.
    """

    frames: np.ndarray
    poses: np.ndarray
    metric: bool = True


def _as_segments(segments: Any) -> list[PlotSegment]:
    """The segments checked: a single (N, 4, 4) metric estimate (frames 0..N-1)
    or a sequence of objects with ``frames``, ``poses``, ``metric``."""
    if isinstance(segments, np.ndarray):
        T = check_poses("segments", segments)
        return [PlotSegment(np.arange(T.shape[0]), T, True)]
    if not isinstance(segments, Sequence) or isinstance(segments, (str, bytes)) \
            or len(segments) == 0:
        raise ValueError("segments must be an (N, 4, 4) array of world_from_rig poses or a "
                         "non-empty sequence of segments (frames, poses, metric)")
    out = []
    for i, s in enumerate(segments):
        try:
            frames, poses, metric = s.frames, s.poses, s.metric
        except AttributeError:
            raise ValueError(f"segments[{i}] has no frames/poses/metric attributes "
                             f"(got {type(s).__name__})") from None
        T = check_poses(f"segments[{i}].poses", poses)
        f = np.asarray(frames)
        if f.dtype.kind not in "iu" or f.shape != (T.shape[0],):
            raise ValueError(f"segments[{i}].frames must be {T.shape[0]} integer frame "
                             f"indices (one per pose), got {f.dtype} {f.shape}")
        if f.size > 1 and not np.all(np.diff(f) > 0):
            raise ValueError(f"segments[{i}].frames must increase, got {f.tolist()}")
        if f.size and f[0] < 0:
            raise ValueError(f"segments[{i}].frames has a negative frame ({int(f[0])})")
        out.append(PlotSegment(f.astype(np.int64), T, bool(metric)))
    return out


def _placed(segments: list[PlotSegment]) -> list[np.ndarray]:
    """(n, 3) drawn positions of each segment.

    A segment that starts where an earlier one ended (a shared boundary frame)
    or right after it is translated so that it continues from that drawn point:
    segments after an ``unknown`` stretch are not located in metres from frame 0,
    so no position is invented for them, they are only drawn in sequence. A
    direction-only segment (no unit) is drawn at the median step length of the
    metric segments (1 if there is none); its legend entry says so.
    """
    steps = [np.linalg.norm(np.diff(s.poses[:, :3, 3], axis=0), axis=1)
             for s in segments if s.metric and s.poses.shape[0] > 1]
    steps = np.concatenate(steps) if steps else np.array([])
    typical = float(np.median(steps[steps > 0])) if np.any(steps > 0) else 1.0
    placed: list[np.ndarray] = []
    for s in segments:
        p = s.poses[:, :3, 3].copy()
        if not s.metric:
            n_steps = max(p.shape[0] - 1, 1)
            length = float(np.sum(np.linalg.norm(np.diff(p, axis=0), axis=1)))
            if length > 0:
                p = p * (typical * n_steps / length)
        if placed:
            p = p - p[0] + placed[-1][-1]
        placed.append(p)
    return placed


def _plane(plane: Any, points: np.ndarray) -> tuple[int, int]:
    """Axis indices (horizontal, vertical) of the top view."""
    if plane is None:
        extent = np.ptp(points, axis=0)
        a, b = sorted(np.argsort(-extent, kind="stable")[:2])
        return int(a), int(b)
    if isinstance(plane, str) and len(plane) == 2 and set(plane) <= set(_AXES) \
            and plane[0] != plane[1]:
        return _AXES.index(plane[0]), _AXES.index(plane[1])
    raise ValueError(f"plane must be None (the two axes of largest extent) or two of "
                     f"'x', 'y', 'z' such as 'xz', got {plane!r}")


def _statuses(step_status: Any, n_steps: int) -> Optional[list[str]]:
    if step_status is None:
        return None
    st = [str(s) for s in step_status]
    if len(st) != n_steps:
        raise ValueError(f"step_status must have one entry per step ({n_steps}: frame k -> "
                         f"k + 1), got {len(st)}")
    bad = sorted(set(st) - set(STATUS_COLOURS))
    if bad:
        raise ValueError(f"step_status has unknown value(s) {bad}; expected "
                         f"{sorted(STATUS_COLOURS)}")
    return st


def _step_errors_from_gt(segments: list[PlotSegment], gt: np.ndarray,
                         n_steps: int) -> np.ndarray:
    """Per-step translation error (m) of the metric segments' consecutive frames
    (:func:`mcgeom.metrics.relative_pose_error`, delta 1); NaN elsewhere."""
    err = np.full(n_steps, np.nan)
    for s in segments:
        if not s.metric or s.frames.size < 2:
            continue
        consecutive = np.flatnonzero(np.diff(s.frames) == 1)
        rpe = relative_pose_error(s.poses, gt[s.frames])
        err[s.frames[consecutive]] = rpe["translation"][consecutive]
    return err


def plot_trajectory(path: Union[str, os.PathLike], segments: Any,
                    gt_poses: Optional[np.ndarray] = None,
                    step_status: Optional[Sequence[str]] = None,
                    step_errors: Optional[np.ndarray] = None, title: str = "", *,
                    plane: Optional[str] = None, ate: Optional[Mapping[str, Any]] = None,
                    frame_offset: int = 0) -> None:
    """Write a PNG: the estimated trajectory from above, with its scale status.

    ``path``: the PNG (written atomically; its folder must exist).
    ``segments``: the estimate, world_from_rig in metres: an (N, 4, 4) array
    (one metric segment, frames 0..N-1) or a sequence of :class:`PlotSegment`-like
    objects (``frames``, ``poses``, ``metric``); direction-only segments are dashed.
    ``gt_poses`` (F, 4, 4): the ground truth, world_from_rig in the estimate's
    world frame (e.g. both with frame 0 the identity), metres, drawn black dashed.
    ``step_status`` (F - 1,): ``metric`` / ``carried`` / ``unknown`` of each step
    k -> k + 1, colouring the segments (legend with counts); None draws the
    estimate in one colour. ``step_errors`` (F - 1,): per-step translation error
    (m; NaN where undefined) for the second panel; with ``gt_poses`` and no
    ``step_errors`` it is the relative pose error of the metric segments.
    ``title``: the headline (large); with ``ate`` (the dict of
    :func:`mcgeom.metrics.absolute_trajectory_error`) "ATE RMSE x m (y % of L m)"
    is added, and its per-frame errors (``ate["frames"]`` if present, else 0..)
    are drawn in the second panel. ``plane``: the top-view axes, e.g. ``"xz"`` for
    camera-like frames (y down); default: the two of largest extent.
    ``frame_offset``: added to the frame numbers shown on the error panel's axis
    (e.g. the ``--start`` frame of the images, so that the axis names the files' frames).

    F is the number of frames: ``len(gt_poses)`` if given, else one past the
    last segment frame. Size: 1500 x 700 px with the error panel, 900 x 800 without.
    """
    segs = _as_segments(segments)
    offset = check_int("frame_offset", frame_offset)
    n_frames = int(max(s.frames[-1] for s in segs)) + 1
    gt = None
    if gt_poses is not None:
        gt = check_poses("gt_poses", gt_poses)
        if gt.shape[0] < n_frames:
            raise ValueError(f"gt_poses has {gt.shape[0]} poses but the segments reach frame "
                             f"{n_frames - 1}")
        n_frames = gt.shape[0]
    n_steps = max(n_frames - 1, 0)
    status = _statuses(step_status, n_steps)
    errors = None
    if step_errors is not None:
        errors = np.asarray(step_errors, dtype=np.float64)
        if errors.shape != (n_steps,):
            raise ValueError(f"step_errors must have shape ({n_steps},) (one per step k -> "
                             f"k + 1), got {errors.shape}")
    elif gt is not None:
        errors = _step_errors_from_gt(segs, gt, n_steps)
    folder = os.path.dirname(os.path.abspath(os.fspath(path)))
    if not os.path.isdir(folder):
        raise ValueError(f"cannot write {os.fspath(path)}: folder {folder} does not exist")

    placed = _placed(segs)
    every = np.vstack(placed + ([gt[:, :3, 3]] if gt is not None else []))
    a, b = _plane(plane, every)

    second = errors is not None or ate is not None
    fig = Figure(figsize=(15, 7) if second else (9, 8), dpi=_DPI, layout="constrained")
    FigureCanvasAgg(fig)
    if second:
        ax, ax_err = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1.25, 1]})
    else:
        ax, ax_err = fig.subplots(1, 1), None

    handles = _draw_top_view(ax, segs, placed, gt, status, a, b)
    ax.set_xlabel(f"{_AXES[a]} (m)", fontsize=12)
    ax.set_ylabel(f"{_AXES[b]} (m)", fontsize=12)
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, color="#dddddd")
    ax.set_title("top view", fontsize=12)
    # the legend sits under the map, never on the data
    ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.09), ncol=2,
              fontsize=10, frameon=False)
    if ax_err is not None:
        _draw_errors(ax_err, errors, status, ate, offset)

    headline = title
    if ate is not None:
        figure = f"ATE RMSE {ate['rmse']:.3g} m"
        length = ate.get("path_length")
        if length:
            figure += f" ({100.0 * ate['rmse'] / length:.2g} % of {length:.3g} m path)"
        headline = f"{title}: {figure}" if title else figure
    if headline:
        fig.suptitle(headline, fontsize=17, fontweight="bold")
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=_DPI)
    write_atomically(path, buf.getvalue())


def _draw_top_view(ax: Any, segs: list[PlotSegment], placed: list[np.ndarray],
                   gt: Optional[np.ndarray], status: Optional[list[str]], a: int,
                   b: int) -> list:
    """Ground truth, segments, start/end markers; returns the legend handles."""
    handles = []
    if gt is not None:
        g = gt[:, :3, 3]
        ax.plot(g[:, a], g[:, b], color="black", linestyle=(0, (5, 3)), linewidth=1.4,
                zorder=2)
        handles.append(Line2D([], [], color="black", linestyle=(0, (5, 3)),
                              label=f"ground truth ({path_length(gt):.3g} m)"))
    counts = {k: 0 for k in STATUS_COLOURS}
    n_direction_only = 0
    any_direction_only = False
    for s, p in zip(segs, placed):
        xy = p[:, [a, b]]
        if xy.shape[0] < 2:
            continue
        lines = np.stack([xy[:-1], xy[1:]], axis=1)
        if not s.metric:
            any_direction_only = True
            n_direction_only += len(lines)
            ax.add_collection(LineCollection(lines, colors=DIRECTION_ONLY_COLOUR,
                                             linestyles=(0, (2, 2)), linewidths=2.5, zorder=3))
            continue
        if status is None:
            colours = [_ESTIMATE_COLOUR] * len(lines)
        else:
            colours = []
            for k, step in zip(s.frames[:-1], np.diff(s.frames)):
                st = status[k] if step == 1 else "unknown"
                counts[st] += 1
                colours.append(STATUS_COLOURS[st])
        ax.add_collection(LineCollection(lines, colors=colours, linewidths=2.5, zorder=3))
    if status is None:
        handles.append(Line2D([], [], color=_ESTIMATE_COLOUR, linewidth=2.5, label="estimate"))
    else:
        names = {"metric": "metric (scale observed)", "carried": "carried (scale via tracks)",
                 "unknown": "unknown scale"}
        for k, colour in STATUS_COLOURS.items():
            if counts[k]:
                handles.append(Line2D([], [], color=colour, linewidth=2.5,
                                      label=f"{names[k]}: {counts[k]} steps"))
    if any_direction_only:
        handles.append(Line2D([], [], color=DIRECTION_ONLY_COLOUR, linestyle=(0, (2, 2)),
                              linewidth=2.5,
                              label=f"direction only, no metric scale: {n_direction_only} "
                                    "steps (drawn at the typical step length)"))
    first = placed[0][0]
    last = placed[-1][-1]
    ax.plot(first[a], first[b], "o", color="white", markeredgecolor="black", markersize=11,
            markeredgewidth=2, zorder=5)
    ax.plot(last[a], last[b], "s", color="black", markersize=9, zorder=5)
    handles += [Line2D([], [], marker="o", color="white", markeredgecolor="black",
                       markeredgewidth=2, markersize=10, linestyle="", label="start"),
                Line2D([], [], marker="s", color="black", markersize=8, linestyle="",
                       label="end of estimate")]
    if gt is not None:
        ax.plot(gt[-1, a, 3], gt[-1, b, 3], "X", color="black", markersize=10, zorder=5)
        handles.append(Line2D([], [], marker="X", color="black", markersize=9, linestyle="",
                              label="end of ground truth"))
    ax.autoscale_view()
    return handles


def _draw_errors(ax: Any, errors: Optional[np.ndarray], status: Optional[list[str]],
                 ate: Optional[Mapping[str, Any]], offset: int) -> None:
    """Per-step translation error (bars, coloured by status) and ATE per frame;
    frame numbers shifted by ``offset``."""
    handles = []
    if errors is not None and errors.size:
        k = np.arange(errors.size) + offset
        ok = np.isfinite(errors)
        colours = ([STATUS_COLOURS[s] for s in status] if status is not None
                   else [_ESTIMATE_COLOUR] * errors.size)
        ax.bar(k[ok] + 0.5, errors[ok], width=0.85, color=np.asarray(colours)[ok])
        label = "translation error of step k -> k+1" + (
            " (bar colour: its scale status)" if status is not None else "")
        handles.append(Patch(color=colours[int(np.flatnonzero(ok)[0])] if ok.any()
                             else _ESTIMATE_COLOUR, label=label))
        for j in k[~ok]:
            ax.axvspan(j, j + 1, facecolor="none", edgecolor=DIRECTION_ONLY_COLOUR,
                       hatch="///", linewidth=0, alpha=0.5, zorder=0)
        if not ok.all():
            handles.append(Patch(facecolor="none", edgecolor=DIRECTION_ONLY_COLOUR,
                                 hatch="///", label=f"no metric length: {int((~ok).sum())} "
                                                    "steps (no error in metres)"))
    if ate is not None:
        e = np.asarray(ate["errors"], dtype=np.float64)
        frames = np.asarray(ate.get("frames", np.arange(e.size))) + offset
        ax.plot(frames, e, color="black", linewidth=1.8, marker=".", label="ATE per frame")
        handles.append(Line2D([], [], color="black", marker=".", label="ATE per frame "
                              "(after SE(3) alignment)"))
    ax.set_xlabel("frame", fontsize=12)
    ax.set_ylabel("error (m)", fontsize=12)
    ax.set_ylim(bottom=0)
    ax.margins(y=0.08)
    ax.grid(True, axis="y", color="#dddddd")
    ax.set_title("errors against the ground truth", fontsize=12)
    ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.09), ncol=1,
              fontsize=10, frameon=False)
