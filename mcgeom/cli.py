"""The mcgeom command: demo (the main job on rendered images), odometry (an
image sequence to a metric trajectory), batch (many sequences on Dask),
methods (the registered estimators), bench (timings against references) and
experiment (the thesis experiments and the real-data evaluations).

Printing, files and the progress bar only; the work is done by
mcgeom.sequence and the modules of mcgeom.experiments, imported when their
command runs so that mcgeom --help stays fast.
"""

from __future__ import annotations

import argparse
import sys
import textwrap
from pathlib import Path
from typing import Optional, Sequence

from . import __version__, registry
from .experiments import EXPERIMENTS
from .experiments.common import (HelpFormatter, MissingPeerError,
                                 non_negative_int, plain_text, positive_float, positive_int,
                                 positive_int_list, progress_bar)

__all__ = ["main"]

#: name -> one-line description of ``mcgeom bench NAME``
BENCHES = {
    "linear17": "linear 17-point estimator (C) against a numpy implementation, N = 17..10000",
    "cone": "L-infinity cone bisection (C) against clarabel SOCP steps (needs clarabel)",
    "bnb": "branch and bound over rotations, 4 cameras x 50 points, and its growth",
    "known_rotation": "multi-view translations with known rotations against dense numpy",
    "essential5": "5-point essential-matrix solver (C) against OpenCV and PoseLib: success, "
                  "solutions, time",
    "robust": "robust 5+1 façade (one C call) against PoseLib on three rigs, and its "
              "scaling to 1e6 correspondences (needs poselib)",
}
#: the default N of ``--sizes`` per benchmark
BENCH_SIZES = {"linear17": (17, 100, 1000, 10000), "cone": (3, 6, 20, 100, 1000),
               "robust": (1000, 10000, 100000, 1000000)}
#: the default ``--problems`` per benchmark
BENCH_PROBLEMS = {"bnb": 10, "robust": 300, "essential5": 10000}


#: the samplers the façade chooses from (``mcgeom methods``), in its order of preference
_SAMPLERS = (
    ("upright_four_point",
     "when a vertical prior is passed (gravity1=, gravity2=: the gravity direction in the "
     "rig frame at each time, e.g. from an IMU): 3 intra-camera correspondences of one "
     "camera solved with the vertical (Fraundorfer et al. 2010) + 1 for the scale, as "
     "5+1, when some camera has 3; else 4-samples of any cameras (Sweeney et al. 2014, "
     "Lee et al. 2014); its smaller samples pay off where outliers are many: measured "
     "2.4-6.1x faster than 5+1 at 50-60 % outliers, 1.3-1.4x at 30 %, 0.99-1.06x without "
     "outliers (mcgeom experiment peer_solvers --part ransac --outliers 0 0.3 0.5 0.6)"),
    ("five_plus_one",
     "else, when some camera has >= 5 intra-camera correspondences: 5 of one camera + 1 "
     "of another (thesis ch. 7)"),
    ("six_point",
     "else: 6-samples of any cameras (the generic minimal problem of Stewenius et al. "
     "2005), for rigs with many cameras and few or mostly cross-camera matches each; "
     "solved by a local search (~1 ms a sample) whose rate of finding a sample's motion "
     "the search measures on its consensus and allows for (info['found_rate']), every "
     "256th sample by the complete homotopy solver (64 paths, 14-30 ms a sample); "
     "7.2x faster than 17-point RANSAC on the 12-camera case of peer_solvers (a vertical "
     "prior is faster still: the upright sampler draws 3+1, or 4 of any cameras)"),
)


#: commands quoted in ``mcgeom methods``: never split over two lines (a reader copies them)
_COMMANDS = ("mcgeom experiment peer_solvers --part ransac --outliers 0 0.3 0.5 0.6",
             "pip install 'mcgeom[glpk]'")


def _wrapped(text: str, indent: str, first: str = "") -> str:
    """``text`` filled to the width of ``--help`` (100 columns), ``first`` then
    ``indent`` at the start of its lines; the commands of :data:`_COMMANDS`
    stay whole."""
    for cmd in _COMMANDS:
        text = text.replace(cmd, cmd.replace(" ", "\0"))
    return textwrap.fill(text, width=100, initial_indent=first or indent,
                         subsequent_indent=indent, break_on_hyphens=False).replace("\0", " ")


def _cmd_methods(args: argparse.Namespace) -> int:
    for e in registry.list_estimators():
        print(f"{e.name}")
        print(_wrapped(e.description, "    "))
        print(f"    family={e.family}  min_sample={e.min_sample}  "
              f"recovers_scale={e.recovers_scale}  needs_rotation={e.needs_rotation}")
        print(_wrapped(f"camera kinds: {', '.join(e.camera_kinds)}", "    "))
        for k, v in e.options.items():
            print(_wrapped(f"option {k}: {v}", "        ", "    "))
    print()
    print(_wrapped("The facade (mcgeom.cv.estimate, estimateRigMotion) chooses the minimal "
                   "solver of its LO-RANSAC from the data (info['sampler'] says which ran; all "
                   "three run in the C entry point mcg_robust_rig_motion):", ""))
    for name, text in _SAMPLERS:
        print(_wrapped(text, " " * 24, f"    {name:<20}"))
    print(_wrapped("Any registered name, 'ransac:NAME' or 'direct:NAME' may be passed as "
                   "method instead ('ransac:five_plus_one' forces 5+1; 'ransac:eigensolver' "
                   "runs the eigensolver's 17-correspondence samples in the same C entry "
                   "point; 'ransac:linear17' is 17-point RANSAC there too: linear17's motion "
                   "from 17 correspondences, ~55 us a sample, whose samples are all "
                   "inliers once in ~6,000 draws at 40 % outliers: see mcgeom experiment "
                   "peer_solvers).",
                   ""))
    # the LP backends of bnb_lp: the available ones, and why GLPK is not (with
    # the command that brings it) when it is not
    print(f"\nLP backends (bnb_lp, default {registry.default_lp_backend()}):")
    backends = registry.lp_backends()
    for name, what in backends.items():
        print(_wrapped(f"{name}: {what}", "        ", "    "))
    if "glpk" not in backends:
        print(_wrapped(f"glpk: {registry.glpk_status()}", "        ", "    "))
    return 0


def frame_count(text: str) -> int:
    """argparse type: a number of frames >= 2 (a sequence needs two)."""
    n = positive_int(text)
    if n < 2:
        raise argparse.ArgumentTypeError(f"expected at least 2 frames, got {text!r}")
    return n


def rig_frame_arg(text: str):
    """argparse type of ``--rig-frame``: ``body``, ``camera:NAME``, ``camera:INDEX``, or
    a text file holding the 4x4 rigid transform rig_from_default (``numpy.loadtxt``)."""
    if text == "body" or (text.startswith("camera:") and len(text) > len("camera:")):
        return text
    if not Path(text).is_file():
        raise argparse.ArgumentTypeError(
            f"expected body, camera:NAME, camera:INDEX or a file holding a 4x4 transform, "
            f"got {text!r}")
    import numpy as np
    from .io.frame import check_frame_spec
    try:
        return check_frame_spec(np.loadtxt(text, ndmin=2))
    except ValueError as exc:   # unreadable numbers, wrong shape, not rigid
        raise argparse.ArgumentTypeError(f"{text}: {exc}") from None


def _cmd_demo(args: argparse.Namespace) -> int:
    from .experiments.demo import describe, run_demo

    demo = run_demo(args.out, n_frames=args.frames, seed=args.seed, features=args.features,
                    progress=progress_bar)
    for line in describe(demo):
        print(line)
    return 0 if demo.success else 1


def _print_run(run) -> None:
    """The summary of a sequence run: steps by scale status, segments, errors."""
    traj = run.trajectory
    counts = traj.status_counts
    seq = run.sequence
    print(f"{seq.n_frames} frames of {seq.n_cameras} cameras ({seq.layout} layout, "
          f"{seq.root}); {len(run.tracks)} observations in "
          f"{run.tracks.n_tracks} tracks")
    print(f"steps: {counts['metric']} metric, {counts['carried']} carried, "
          f"{counts['unknown']} unknown (scale not observable, never chained as metric); "
          f"{len(traj.segments)} segment(s), "
          f"{sum(not sg.metric for sg in traj.segments)} direction-only")
    known = traj.known
    if known.sum() > 1:
        print(f"metric trajectory: {int(known.sum())} frames, path "
              f"{traj.metric_path_length:.3f} m")
    else:
        print("metric trajectory: none (no step with an observable scale)")
    if run.errors is not None:
        print("against the ground truth: " + run.errors.summary())
    secs = ", ".join(f"{k} {v:.1f} s" for k, v in run.seconds.items())
    gt_files = ", errors.txt, errors.csv, rpe.csv" if run.errors is not None else ""
    print(f"wrote {run.out}/ (trajectory_tum.txt, trajectory_kitti.txt, steps.csv, "
          f"trajectory.png{gt_files}); {secs}")


def _cmd_odometry(args: argparse.Namespace) -> int:
    from .sequence.run import run_odometry

    try:
        run = run_odometry(args.rig, args.images, args.out, start=args.start, end=args.end,
                           step=args.step, features=args.features,
                           n_features=args.n_features, cross_camera=not args.no_cross_camera,
                           threshold=args.threshold, gt=args.gt, progress=progress_bar,
                           title=Path(args.images).name, rig_frame=args.rig_frame,
                           calibration_check=args.calibration_check.replace("-", "_"))
    except (ValueError, OSError) as exc:
        # bad input (rig file, image layout, unreadable image, ground truth):
        # the message names it; nothing was written
        print(f"mcgeom odometry: error: {exc}", file=sys.stderr)
        return 2
    _print_run(run)
    return 0


#: what ``mcgeom batch`` says when Dask is not installed (exit code 2)
NEEDS_DASK = "mcgeom batch needs Dask: pip install 'mcgeom[batch]'"


def _batch_bar(counts: dict):
    """A progress callable for :func:`mcgeom.batch.run`: a tqdm bar on stderr
    whose postfix counts the sequences done and failed as rows arrive."""
    from tqdm import tqdm

    def progress(rows, total=None, desc=None):
        stream = sys.stderr
        with tqdm(total=total, desc=desc, file=stream, leave=False,
                  disable=not (hasattr(stream, "isatty") and stream.isatty())) as bar:
            for row in rows:
                counts["ok" if row["status"] == "ok" else "failed"] += 1
                bar.set_postfix(done=counts["ok"], failed=counts["failed"])
                bar.update()
                yield row
    return progress


def _fmt(value, spec: str) -> str:
    return "-" if value is None else format(value, spec)


def _cmd_batch(args: argparse.Namespace) -> int:
    try:
        import dask  # noqa: F401  (the optional extra: checked before any work)
        import distributed  # noqa: F401
    except ImportError:
        print(f"mcgeom: error: {NEEDS_DASK}", file=sys.stderr)
        return 2
    import time

    from .batch import connect, read_manifest, run

    try:
        entries = read_manifest(args.manifest)
    except ValueError as exc:
        print(f"mcgeom batch: error: {exc}", file=sys.stderr)
        return 2
    counts = {"ok": 0, "failed": 0}
    t0 = time.perf_counter()
    try:
        with connect(workers=args.workers, scheduler=args.scheduler) as client:
            # the link only when the scheduler serves a dashboard (it needs bokeh)
            if "dashboard" in client.scheduler_info().get("services", {}):
                print(f"Dask dashboard: {client.dashboard_link}", flush=True)
            rows = run(entries, args.out, client=client, progress=_batch_bar(counts))
    except (ValueError, OSError) as exc:
        print(f"mcgeom batch: error: {exc}", file=sys.stderr)
        return 2
    wall = time.perf_counter() - t0
    width = max(len(r["name"]) for r in rows)
    print(f"{'name':<{width}} {'status':>6} {'frames':>6} {'path m':>8} {'metric':>6} "
          f"{'ATE m':>7} {'drift %':>8} {'s':>6}  error")
    for r in rows:
        print(f"{r['name']:<{width}} {r['status']:>6} {_fmt(r['frames'], 'd'):>6} "
              f"{_fmt(r['path_length_m'], '.3f'):>8} {_fmt(r['metric_share'], '.0%'):>6} "
              f"{_fmt(r['ate_rmse_m'], '.3f'):>7} {_fmt(r['scale_drift_percent'], '+.2f'):>8} "
              f"{_fmt(r['seconds'], '.1f'):>6}  {r['error'] or ''}")
    ok = sum(r["status"] == "ok" for r in rows)
    print(f"{ok} ok, {len(rows) - ok} failed of {len(rows)} sequences in {wall:.1f} s "
          f"({sum(r['reused'] for r in rows)} already done, not run again); wrote "
          f"{Path(args.out)}/summary.csv")
    return 0 if ok == len(rows) else 1


def _cmd_bench(args: argparse.Namespace) -> int:
    return {"linear17": _bench_linear17, "cone": _bench_cone, "bnb": _bench_bnb,
            "known_rotation": _bench_known_rotation, "robust": _bench_robust,
            "essential5": _bench_essential5}[args.what](args)


def _problems(args: argparse.Namespace) -> int:
    return BENCH_PROBLEMS.get(args.what, 10) if args.problems is None else args.problems


def _bench_robust(args: argparse.Namespace) -> int:
    from .experiments.bench.robust import TUNED_PEER, WARM_BLOCK, bench_speed
    from .experiments.bench.robust_scaling import (allowed_at_smallest, bench_scaling,
                                                   fit_worst_error, fixed_and_marginal,
                                                   spread_ratios)

    rows = bench_speed(_problems(args), progress=progress_bar)
    print(f"robust: mcgeom.cv.estimate (pixels in: 5+1 and its scale verdict in one C call) vs "
          f"PoseLib estimate_generalized_relative_pose, {_problems(args)} problems per case, "
          f"1 px threshold; medians")
    print(f"{'case':<22} {'method':<19} {'rot deg':>8} {'scale err':>9} {'ms cold':>7} "
          f"{'mcgeom/this':>11} {'ms warm':>7} {'mcgeom/this':>11} {'outside C':>9} "
          f"{'mcgeom better rot/scale (paired)':>32}")
    own = {r.case: r for r in rows if r.method == "mcgeom"}   # (the ratios' numerators)
    for r in rows:
        out = "" if r.method != "mcgeom" else f"{100 * r.outside_c:8.0f}%"
        paired = "" if r.method == "mcgeom" else \
            f"{100 * r.mcgeom_rot_better:3.0f}% / {100 * r.mcgeom_scale_better:3.0f}%"
        m = own[r.case]
        print(f"{r.case:<22} {r.method:<19} {r.rot_deg:8.4f} {r.scale_err:9.4f} {r.ms:7.3f} "
              f"{m.ms / r.ms:10.2f}x {r.ms_warm:7.3f} {m.ms_warm / r.ms_warm:10.2f}x {out:>9} "
              f"{paired:>32}")
    print(f"cold: the methods alternate on every problem (errors and 'outside C' from this "
          f"pass); warm: the same problems in blocks of {WARM_BLOCK}, each method on a block "
          f"in turn")
    print("mcgeom's C call by stage (cold medians, ms; info['c_stage_seconds']): the "
          "pixels' rays, the search (sampling, scoring, local optimisation), the final "
          "refinement and scale profiles, the verdict; and the time outside C")
    for r in rows:
        if r.method == "mcgeom" and r.stages_ms:
            print(f"  {r.case:<22} " + ", ".join(f"{k} {v:.3f}" for k, v in r.stages_ms.items()))
    print(f"mcgeom / {TUNED_PEER}, medians' ratio with its 95 % bootstrap interval "
          f"(problems resampled):")
    for r in rows:
        if r.method == TUNED_PEER:
            m = own[r.case]
            print(f"  {r.case:<22} " + "; ".join(
                f"{what} {ratio:.2f} [{ci[0]:.2f}, {ci[1]:.2f}]" for what, ratio, ci in (
                    ("time cold", m.ms / r.ms, r.time_ratio_ci),
                    ("rotation error", m.rot_deg / r.rot_deg, r.rot_ratio_ci),
                    ("scale error", m.scale_err / r.scale_err, r.scale_ratio_ci))))
    print("Cramer-Rao bound on the same problems (pixel noise, the inliers known): the "
          "median errors of an efficient estimator, and each method's medians over them "
          "(below 1: the draw of the problems, a bias, or heavy tails)")
    for r in rows:
        b = own[r.case]
        if r.method == "mcgeom":
            print(f"  {r.case:<22} bound: rotation {b.bound_rot_deg:.4f} deg, scale "
                  f"{b.bound_scale_err:.4f}")
        print(f"  {'':<22} {r.method:<19} rotation {r.rot_deg / b.bound_rot_deg:5.2f}x, "
              f"scale {r.scale_err / b.bound_scale_err:5.2f}x")
    print("\nscaling: 4-camera ring, 20 % outliers; mcgeom rays in (mcgeom.robust.ransac), "
          "PoseLib (min_iterations=100) the same pixels; medians over the problems of each "
          "size, each drawn and solved with its own seed; 'search alone': mcgeom without "
          "local optimisation and final refinement")
    print(f"{'N':>8} {'problems':>8} {'seconds':>8} {'us/corr':>8} {'min-max us/corr':>15} "
          f"{'peak MB':>8} {'input MB':>8} {'peak/input':>10} {'rot deg':>8} {'inliers':>7} "
          f"{'C ms':>9} {'outside C':>9} {'search ms':>9} {'PoseLib s':>9} {'us/corr':>8} "
          f"{'rot deg':>8} {'mcgeom/PoseLib':>14} {'facade us/corr':>14} "
          f"{'facade peak/px in':>17}")
    scaling = bench_scaling(_sizes(args), progress=progress_bar)
    for r in scaling:
        spread = f"{r.us_per_corr_min:.3f}-{r.us_per_corr_max:.3f}"
        print(f"{r.n:8d} {r.problems:8d} {r.seconds:8.3f} {r.us_per_corr:8.3f} {spread:>15} "
              f"{r.peak_mb:8.1f} {r.input_mb:8.1f} {r.peak_mb / r.input_mb:10.2f} "
              f"{r.rot_deg:8.4f} {r.inlier_ratio:7.3f} {1e3 * r.c_seconds:9.3f} "
              f"{100 * (1 - r.c_seconds / r.seconds):8.0f}% {1e3 * r.search_seconds:9.3f} "
              f"{r.peer_seconds:9.3f} {1e6 * r.peer_seconds / r.n:8.3f} {r.peer_rot_deg:8.4f} "
              f"{r.seconds / r.peer_seconds:13.3f}x {1e6 * r.facade_seconds / r.n:14.3f} "
              f"{r.facade_peak_mb / r.facade_input_mb:17.2f}")
    if len(scaling) > 1:
        ours, theirs, facade = spread_ratios(scaling)
        print(f"cost per correspondence, largest / smallest median: mcgeom "
              f"{ours:.2f}x (issue 19's target: within 2x), PoseLib {theirs:.2f}x; the "
              f"facade (mcgeom.cv.estimate, pixels and ids in) {facade:.2f}x, its peak "
              f"memory over ITS input (pixels and ids, half the rays' bytes) in the last "
              f"column")
        fixed, marginal = fixed_and_marginal(scaling)
        small, big = min(scaling, key=lambda r: r.n), max(scaling, key=lambda r: r.n)
        off = fit_worst_error(scaling, fixed, marginal)
        print(f"fit of the medians, seconds = fixed + marginal x N: {1e3 * fixed:.2f} ms + "
              f"{1e6 * marginal:.3f} us x N, within {100 * off:.0f} % of every median; the "
              f"fixed part is {100 * fixed / small.seconds:.0f} % of the time at N = {small.n}")
        print(f"within 2x of the cost per correspondence at N = {big.n} allows "
              f"{1e3 * allowed_at_smallest(scaling):.3f} ms at N = {small.n}; the search alone "
              f"takes {1e3 * small.search_seconds:.3f} ms there, the whole estimate "
              f"{1e3 * small.seconds:.3f} ms")
    return 0


def _sizes(args: argparse.Namespace) -> tuple[int, ...]:
    return BENCH_SIZES[args.what] if args.sizes is None else args.sizes


def _bench_linear17(args: argparse.Namespace) -> int:
    from .experiments.bench.linear17 import bench_linear17

    rows = bench_linear17(_sizes(args), budget_s=args.budget, progress=progress_bar)
    print("linear17: the public call mcgeom.estimate (RayPairs in, RigMotion with its verdict "
          "out), the plugin without the shared static-rig test (static = public - plugin: "
          "that test and the one-pair check of a metric estimate; "
          "staticC: its bare kernel mcg_static_check), the cffi wrapper, the bare C kernel, and "
          "a numpy implementation of the same algorithm; python = public - C")
    print(f"{'N':>7} {'public[us]':>10} {'static[us]':>10} {'staticC[us]':>11} {'plugin[us]':>10} "
          f"{'wrapper[us]':>11} {'C[us]':>8} {'python[us]':>10} "
          f"{'C share':>7} {'numpy[us]':>10} {'ratio':>6} {'us/ray':>7} {'iters':>5}")
    for r in rows:
        print(f"{r.n:7d} {r.public_us:10.1f} {r.static_us:10.1f} {r.static_c_us:11.1f} "
              f"{r.plugin_us:10.1f} "
              f"{r.wrapper_us:11.1f} {r.c_us:8.1f} "
              f"{r.python_us:10.1f} {r.c_us / r.public_us:7.0%} {r.numpy_us:10.1f} "
              f"{r.ratio:6.1f} {r.public_us / r.n:7.3f} {r.iterations:5d}")
    print("reference (issue 22): OpenGV seventeenpt 79-108 us at 100 rays, 167 us at 200, "
          "707 us at 320 (Release, C++)")
    return 0


def _bench_cone(args: argparse.Namespace) -> int:
    from .experiments.bench.cone import bench_cone

    rows = bench_cone(_sizes(args), budget_s=args.budget, progress=progress_bar)
    print("cone: mcgeom L-inf cone bisection (C kernel via the Python API) vs "
          "bisection with clarabel solving each SOCP feasibility step")
    print(f"{'N':>6} {'mcgeom[us]':>11} {'clarabel[us]':>13} {'ratio':>7} "
          f"{'steps':>5} {'ref steps':>9} {'rel dgamma':>10}")
    for r in rows:
        print(f"{r.n:6d} {r.mcgeom_us:11.1f} {r.clarabel_us:13.1f} {r.ratio:7.1f} "
              f"{r.steps_mcgeom:5d} {r.steps_clarabel:9d} {r.gamma_rel_diff:10.1e}")
    return 0


def _bench_known_rotation(args: argparse.Namespace) -> int:
    from .experiments.bench.known_rotation import bench_known_rotation

    print("known_rotation: centres of a circle sequence (thesis ch. 6.5.1 scaled up, noise "
          "1e-4 rad), constrained solver; mcgeom (C rows + skyline) vs dense numpy, seconds")
    print(f"{'views':>6} {'tracks':>7} {'relation':>10} {'relations':>9} {'mcgeom s':>9} "
          f"{'numpy s':>9} {'ratio':>7} {'max diff':>9}")
    for r in bench_known_rotation(progress=progress_bar):
        dense = ("" if r.numpy_s is None else
                 f"{r.numpy_s:9.3f} {r.ratio:7.1f} {r.max_diff:9.1e}")
        print(f"{r.views:6d} {r.tracks:7d} {r.relation:>10} {r.relations:9d} "
              f"{r.mcgeom_s:9.4f} {dense}")
    return 0


def _bench_essential5(args: argparse.Namespace) -> int:
    from .experiments.bench.essential5 import bench_essential5

    n = _problems(args)
    rows, c_us, note = bench_essential5(problems=n, budget_s=args.budget,
                                        progress=progress_bar)
    print(f"essential5: {n} random noise-free minimal problems; found = true E among the "
          "solutions (to 1e-6); CPU time per call through Python")
    print(f"{'solver':>8} {'found':>8} {'solutions':>9} {'us/call':>8} {'vs mcgeom':>9}")
    for r in rows:
        print(f"{r.name:>8} {r.found:8.4f} {r.mean_solutions:9.3f} {r.us_per_call:8.2f} "
              f"{r.us_per_call / rows[0].us_per_call:9.2f}")
    print(f"C kernel alone (mcg_essential5 through cffi, preallocated buffers): {c_us:.2f} us "
          "per call")
    if note:
        print(f"poselib not compared: {note}")
    return 0


def _bench_bnb(args: argparse.Namespace) -> int:
    from .experiments.bench.bnb import bench_bnb, growth

    def row(r) -> str:
        g = "" if r.glpk_s is None else f" {r.glpk_s:9.3f} {r.glpk_ratio:7.1f}"
        return (f"{r.cams:4d} {r.pts:4d} {r.search_s:9.3f} {r.total_s:9.3f} "
                f"{r.estimator_cpu_s:9.3f} {r.blocks:8.0f} {r.lps:8.0f} {r.us_per_lp:7.2f}{g}")

    head = (f"{'cams':>4} {'pts':>4} {'search s':>9} {'+polish s':>9} {'est cpu s':>9} "
            f"{'blocks':>8} {'LPs':>8} {'us/LP':>7}")
    print("bnb: branch and bound over rotations to 1e-4 rad (4 cameras x 50 points, "
          "0.5 px; medians)")
    print(head + f" {'glpk s':>9} {'glpk/nat':>7}")
    print(row(bench_bnb(problems=_problems(args), progress=progress_bar)))
    print("published: thesis ch. 10.5.1 about 3.5 s (C++ with GLPK)")
    print("\ngrowth with points (4 cameras) and cameras (50 points each)")
    print(head)
    for r in growth(problems=max(3, _problems(args) // 2), progress=progress_bar):
        print(row(r))
    return 0


def _experiment_parser(name: str, module) -> argparse.ArgumentParser:
    """The parser of ``mcgeom experiment NAME``: the module's options, its
    docstring as the description."""
    ep = argparse.ArgumentParser(prog=f"mcgeom experiment {name}",
                                 description=plain_text(module.__doc__),
                                 formatter_class=HelpFormatter)
    module.add_arguments(ep)
    return ep


def _cmd_experiment(args: argparse.Namespace) -> int:
    from .experiments import load

    module = load(args.name)
    ep = _experiment_parser(args.name, module)
    eargs = ep.parse_args(args.options)
    try:
        return module.run_cli(eargs, progress=progress_bar)
    except ValueError as exc:
        # mcgeom's ValueErrors name the argument or option at fault: a usage
        # message (exit 2), not a traceback, for options whose bad values an
        # experiment only finds while running (e.g. a case name, a data set)
        ep.error(str(exc))


def _name_list(title: str, items: dict) -> str:
    """``title:`` and one entry per name, its description wrapped beside it
    (the epilog is printed as written, so it is wrapped here)."""
    width = max(len(n) for n in items)
    lines = [f"{title}:"]
    for name, desc in items.items():
        lines += textwrap.wrap(desc, 78, initial_indent=f"  {name:<{width}}  ",
                               subsequent_indent=" " * (width + 4))
    return "\n".join(lines)


def _command(sub, name: str, help: str, description: str,
             epilog: Optional[str] = None) -> argparse.ArgumentParser:
    """A sub-command whose description (and epilog) are paragraphs wrapped to
    79 columns."""
    return sub.add_parser(name, formatter_class=HelpFormatter, help=help,
                          description=textwrap.fill(description, 79),
                          epilog=None if epilog is None else textwrap.fill(epilog, 79))


def build_parser() -> argparse.ArgumentParser:
    """The parser of the ``mcgeom`` command (without the experiments' own options,
    which are parsed once the experiment is known)."""
    p = argparse.ArgumentParser(prog="mcgeom", description=plain_text(__doc__),
                                formatter_class=HelpFormatter)
    p.add_argument("--version", action="version", version=f"%(prog)s {__version__}",
                   help="print the version and exit")
    sub = p.add_subparsers(dest="cmd", required=True, metavar="COMMAND")

    d = _command(sub, "demo",
                 help="the main job: rendered images of a surround rig to a metric "
                      "trajectory",
                 description=(
                     "Render a 5-camera surround car rig driving a closed 83 m loop "
                     "through a textured courtyard (deterministic), run mcgeom odometry "
                     "on the images and compare the trajectory with the rendered path "
                     "(ATE after an SE(3) alignment, no scale). Writes the trajectories "
                     "(TUM, KITTI), the ground truth, steps.csv, the plot, the rig file "
                     "and the images to OUT."))
    d.add_argument("--frames", type=frame_count, default=90, help="frames around the loop")
    d.add_argument("--seed", type=non_negative_int, default=0, help="seed of the textures")
    d.add_argument("--features", choices=("sift", "orb"), default="sift",
                   help="feature detector and descriptor")
    d.add_argument("--out", default="mcgeom_demo", help="output directory")
    d.set_defaults(func=_cmd_demo)

    o = _command(sub, "odometry",
                 help="a rig's image sequence to a metric trajectory",
                 description=(
                     "Feature tracks (OpenCV) of a rig's image sequence, every step's "
                     "motion with its scale verdict, and the metric trajectory: scale "
                     "observed on a step (metric), carried along the tracks "
                     "(carried), or not known (unknown: such a stretch is reported "
                     "as direction-only, never chained with a guessed length). "
                     "Writes OUT/trajectory_tum.txt, trajectory_kitti.txt, steps.csv "
                     "and trajectory.png; with --gt also errors.txt (ATE after an "
                     "SE(3) alignment, no scale; RPE; scale drift)."),
                 epilog=(
                     "Image layouts: IMAGES/<camera name or camN>/ with the same "
                     "number of images each (sorted names give the frame order); "
                     "EuRoC/ASL (camN/data.csv + camN/data/); KITTI raw "
                     "(image_02/data, image_03/data)."))
    o.add_argument("--rig", required=True, help="rig calibration file (mcgeom JSON, OpenCV "
                   "FileStorage, Kalibr camchain, COLMAP rig config); required")
    o.add_argument("--rig-frame", default=None, metavar="FRAME", type=rig_frame_arg,
                   help="rig frame of the estimated motions: 'body' (the body/IMU frame, "
                        "when the file has one), 'camera:NAME' / 'camera:INDEX', or a text "
                        "file holding the 4x4 transform from the default frame (default: "
                        "the file's own: Kalibr IMU if every camera has T_cam_imu, else "
                        "cam0; COLMAP the reference camera; mcgeom JSON the file's frame)")
    o.add_argument("--images", required=True, help="folder of the images; required")
    o.add_argument("--out", default="mcgeom_odometry", help="output folder")
    o.add_argument("--start", type=non_negative_int, default=0, help="first frame")
    o.add_argument("--end", type=positive_int, default=None,
                   help="frame to stop before (default: all)")
    o.add_argument("--step", type=positive_int, default=1, help="use every STEP-th frame")
    o.add_argument("--features", choices=("sift", "orb"), default="sift",
                   help="feature detector and descriptor")
    o.add_argument("--n-features", type=positive_int, default=4000,
                   help="features per image")
    o.add_argument("--threshold", type=positive_float, default=1.0,
                   help="inlier threshold of the two-frame estimates (pixels)")
    o.add_argument("--no-cross-camera", action="store_true",
                   help="do not match across cameras whose views overlap")
    o.add_argument("--calibration-check", choices=("sampled", "first-order"),
                   default="sampled",
                   help="check a metric step's calibration part of the std of |t| by "
                        "refitting it on 128 rigs drawn with the rig's stated extrinsic "
                        "error (sampled), or keep the two-frame verdict's first-order "
                        "figure (first-order)")
    o.add_argument("--gt", default=None, help="ground truth, TUM file of world_from_rig "
                   "(time stamps as the images', or frame numbers) (default: none, no "
                   "errors computed)")
    o.set_defaults(func=_cmd_odometry)

    bt = _command(sub, "batch",
                  help="odometry of many sequences on Dask (local or a cluster)",
                  description=(
                      "Run mcgeom odometry on every sequence of MANIFEST, one Dask "
                      "task per sequence, on a local cluster of worker processes or "
                      "on an existing Dask cluster. Writes OUT/<name>/ (the odometry "
                      "outputs) and OUT/summary.csv (and summary.parquet with "
                      "pyarrow): status, frames, path length, shares of metric / "
                      "carried / unknown steps, run time, ATE / RPE / scale drift "
                      "with ground truth, the error of a failed sequence. A re-run "
                      "with the same OUT skips the sequences already done. Exit "
                      "code 1 when a sequence failed. Needs pip install "
                      "'mcgeom[batch]'."),
                  epilog=(
                      "MANIFEST: a CSV file with the header name,rig,images,gt "
                      "(gt may be empty) and optional columns start, end, step, "
                      "features, n_features, threshold, cross_camera, rig_frame; paths "
                      "relative to the manifest's folder."))
    bt.add_argument("manifest", help="the CSV file of sequences")
    bt.add_argument("--out", required=True, help="output folder; required")
    where = bt.add_mutually_exclusive_group()
    where.add_argument("--workers", type=positive_int, default=None,
                       help="worker processes of a local cluster (default: the CPU count)")
    where.add_argument("--scheduler", default=None, metavar="ADDRESS",
                       help="address of an existing Dask scheduler, e.g. tcp://host:8786")
    bt.set_defaults(func=_cmd_batch)

    m = sub.add_parser("methods", formatter_class=HelpFormatter,
                       help="list the registered estimators",
                       description="List the registered estimators with their options.")
    m.set_defaults(func=_cmd_methods)

    b = sub.add_parser("bench", formatter_class=HelpFormatter,
                       help="benchmarks with ratios against references",
                       description=textwrap.fill("Time an mcgeom kernel against a "
                                                 "reference implementation and print the "
                                                 "ratios.", 79),
                       epilog=_name_list("benchmarks", BENCHES))
    b.add_argument("what", choices=list(BENCHES), metavar="NAME",
                   help="benchmark: " + ", ".join(BENCHES))
    b.add_argument("--problems", type=positive_int, default=None,
                   help="problems per row (bnb: default 10; essential5: default 10000; "
                        "robust: per case, default 300)")
    b.add_argument("--sizes", type=positive_int_list, default=None,
                   help="comma-separated N (linear17, cone, robust; default: linear17 "
                        "17,100,1000,10000, cone 3,6,20,100,1000, robust "
                        "1000,10000,100000,1000000)")
    b.add_argument("--budget", type=positive_float, default=0.5,
                   help="seconds per timing (linear17, cone, essential5)")
    b.set_defaults(func=_cmd_bench)

    e = sub.add_parser("experiment", formatter_class=HelpFormatter,
                       help="thesis experiments and real-data evaluations",
                       description="Run an experiment: mcgeom experiment NAME [its options].\n"
                                   "mcgeom experiment NAME --help lists its options.",
                       epilog=_name_list("experiments", {n: desc for n, (_, desc)
                                                         in EXPERIMENTS.items()}))
    e.add_argument("name", choices=list(EXPERIMENTS), metavar="NAME",
                   help="experiment: " + ", ".join(EXPERIMENTS))
    e.add_argument("options", nargs=argparse.REMAINDER,
                   help="the experiment's options (see mcgeom experiment NAME --help)")
    e.set_defaults(func=_cmd_experiment)
    return p


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Entry point of the ``mcgeom`` command; returns the exit code."""
    args = build_parser().parse_args(argv)
    try:
        return int(args.func(args))
    except MissingPeerError as exc:
        # a peer library of a comparison is not installed: say which, no traceback
        print(f"mcgeom: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
