"""The main job on an embedded default: rendered images of a surround car rig
driving a closed loop through a courtyard, turned into a metric trajectory by
the sequence pipeline (``mcgeom odometry``), and compared with the path the
images were rendered from.

The images are rendered by :mod:`mcgeom.experiments.render` (a textured
courtyard ray-cast into five distorted pinhole cameras; deterministic), then
the pipeline runs on the files exactly as on a user's recording: the rig file,
the folder of images, the ground truth as a TUM file. Success means: ATE RMSE
after an SE(3) alignment (no scale: the metric scale is the point) at most
:data:`ATE_TARGET_PERCENT` % of the path length, and no step chained with an
invented scale (every step is metric, carried from a metric step along the
tracks, or reported unknown and left out of the metric trajectory).
"""

from __future__ import annotations

import shutil
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Optional

from mcgeom.sequence.run import OdometryRun, run_odometry

from .common import Progress, no_progress
from .render import RenderedSequence, render_sequence

__all__ = ["ATE_TARGET_PERCENT", "DemoRun", "run_demo"]

#: the demo's success criterion on the ATE RMSE, percent of the path length
ATE_TARGET_PERCENT = 1.0


@dataclass(frozen=True)
class DemoRun:
    """The rendered sequence, the odometry run on it, the render time (s)."""

    rendered: RenderedSequence
    run: OdometryRun
    render_seconds: float

    @property
    def success(self) -> bool:
        """ATE within the target, and every step's scale accounted for (no
        step chained without a metric or carried length: unknown steps are
        never in the metric trajectory)."""
        e = self.run.errors
        return bool(e is not None and e.ate["rmse_percent"] <= ATE_TARGET_PERCENT
                    and self.run.trajectory.known.all())


def run_demo(out: Any = "mcgeom_demo", n_frames: int = 90, seed: int = 0,
             features: str = "sift", progress: Progress = no_progress) -> DemoRun:
    """Render the default sequence and run the sequence pipeline on it.

    ``out``: the output folder; it receives the pipeline's files
    (:mod:`mcgeom.sequence.outputs`) plus ``groundtruth_tum.txt``, ``rig.json``
    and the rendered ``images/`` (so that ``mcgeom odometry`` can be re-run on
    them). ``n_frames``: frames around the loop; ``seed``: the textures;
    ``features``: ``"sift"`` or ``"orb"``; ``progress``: wraps the loops over
    frames and steps.
    """
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    scratch = Path(tempfile.mkdtemp(prefix=f".{out.name}.render-", dir=out.parent))
    try:
        t0 = time.perf_counter()
        rendered = render_sequence(scratch, n_frames=n_frames, seed=seed, progress=progress)
        seconds = time.perf_counter() - t0
        # the rendered files join the outputs, moved in when they are written
        extra = {name: (lambda dst, src=scratch / name: shutil.move(src, dst))
                 for name in ("images", "rig.json", "groundtruth_tum.txt")}
        run = run_odometry(rendered.rig_path, scratch / "images", out, features=features,
                           gt=rendered.groundtruth_path, extra_outputs=extra,
                           title="mcgeom demo (rendered surround rig)", progress=progress)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    return DemoRun(rendered, run, seconds)


def describe(demo: DemoRun) -> list[str]:
    """The lines ``mcgeom demo`` prints (the CLI adds nothing but them)."""
    r, run = demo.rendered, demo.run
    rig = r.rig
    c = run.trajectory.status_counts
    lines = [f"rendered {r.n_frames} frames of a {len(rig)}-camera surround rig "
             f"({', '.join(rig.names)}; {rig.cameras[0].width}x{rig.cameras[0].height} px) "
             f"around a {r.path_length:.1f} m loop with 4 turns in {demo.render_seconds:.1f} s",
             f"tracks: {run.tracks.n_tracks} ({len(run.tracks)} observations)",
             f"steps: {c['metric']} metric, {c['carried']} carried, {c['unknown']} unknown"]
    e: Optional[Any] = run.errors
    if e is not None:
        lines.append("against the rendered path: " + e.summary())
    secs = ", ".join(f"{k} {v:.1f} s" for k, v in run.seconds.items())
    lines.append(f"timings: render {demo.render_seconds:.1f} s, {secs}")
    if demo.success:
        lines.append(f"SUCCESS: ATE RMSE {e.ate['rmse']:.3f} m = {e.ate['rmse_percent']:.2f} % "
                     f"of the path (target <= {ATE_TARGET_PERCENT:g} %), every frame located "
                     f"in metres without an invented scale")
    else:
        why = ("no metric frames to score" if e is None else
               f"ATE {e.ate['rmse_percent']:.2f} % of the path (target <= "
               f"{ATE_TARGET_PERCENT:g} %), {int((~run.trajectory.known).sum())} frame(s) "
               f"without a metric position")
        lines.append(f"FAILED: {why}")
    lines.append(f"wrote {run.out}/: trajectory_tum.txt, groundtruth_tum.txt, "
                 f"trajectory_kitti.txt, steps.csv, errors.txt, rpe.csv, trajectory.png, "
                 f"rig.json, images/")
    lines.append(f"re-run the pipeline on these images: mcgeom odometry --rig {run.out}/rig.json "
                 f"--images {run.out}/images --gt {run.out}/groundtruth_tum.txt "
                 f"--out {run.out}_odometry")
    return lines
