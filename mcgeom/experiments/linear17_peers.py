"""mcgeom's ``linear17`` next to OpenGV's ``relative_pose::seventeenpt``
(issue 22), both run here on IDENTICAL rays from our own generator.

The cases are those of :data:`mcgeom.experiments.linear17_accuracy.CASES` (the
five of the issue: general 6-camera rig, axial 4-camera rig and 2-camera
non-overlapping head with 100 rays and 0.05 deg angular noise; 4 cameras x 50
points with 0.5 px; the 8-camera car rig driving forward, 320 rays). Every
trial draws one problem; both methods receive the same unit bearings and the
same camera centres:

- mcgeom: ``mcgeom.estimate(rays, "linear17")``, the public call with the
  registry's checks and the scale verdict; its metric ``t`` is
  ``info["t_metric"]`` whatever the verdict (the share of trials it judges
  scale-observable is printed next to it, so that no unobservable scale is
  read as metric);
- OpenGV: ``seventeenpt`` on a ``NoncentralRelativeAdapter`` whose cameras are
  the distinct ray origins (rotation identity, bearings in the rig frame).
  OpenGV returns the pose of viewpoint 2 in viewpoint 1, ``X1 = R_o X2 + t_o``;
  our rig2_from_rig1 is ``R = R_o^T``, ``t = -R_o^T t_o``.
- PoseLib (2.0.5) has no linear 17-point solver in its Python API (only the
  minimal 6-point / upright 4-point and the robust estimate): it is skipped,
  as the issue's table has no PoseLib column either.

OpenGV is not a dependency and is never vendored. The experiment calls a
Python extension module named ``opengv17`` that the user builds themselves
against OpenGV (from its public source, Release mode with ``-faligned-new``,
as issue 22 says; the build used for the issue's figures is written down in
the issue's report, not here). The module exposes
``seventeenpt(bearings1, bearings2, cam1, cam2, offsets, rotations)
-> 3x4 [R_o | t_o]`` and ``seventeenpt_timed(..., repeats) -> ([R_o | t_o],
ns per call measured in C++)``, with bearings (N, 3) in their camera frames,
camera indices (N,) into offsets (C, 3) and rotations (C, 3, 3) (camera to
viewpoint, OpenGV's ``camOffsets`` / ``camRotations``). ``--opengv PATH``
points at that module file or at the folder holding it; without it the
module is imported from ``sys.path``. When it cannot be loaded the experiment
says so and prints mcgeom's rows alone.

Before the trials a noise-free problem of each case (exact rays from the
generator's scene points) checks the conventions: both errors must be ~1e-10.

Printed per case and method: median rotation error (deg), median scale error
|(|t| / |t_true|) - 1|, median time per call (Python ``perf_counter`` around
the call; for OpenGV also the C++-side time of ``seventeenpt_timed``), the
fraction of trials where OpenGV is more accurate, and the paired per-trial
comparison (median difference with a bootstrap 95 % interval).
``--variants`` also runs the numpy variants of ``linear17_accuracy`` (among
them ``opengv``, the approach reported for OpenGV, written from the paper) on
the same rays, to tell which step makes a difference; each is then also
compared with the real OpenGV (paired), and the largest per-trial difference
between ``numpy:opengv`` and OpenGV is printed (it shows whether the numpy
transcription of the published approach computes what OpenGV computes).

``mcgeom experiment linear17_peers [--trials 100] [--seed 0] [--opengv PATH]
[--variants]``
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import os
import time
from types import ModuleType
from typing import Callable, Optional

import numpy as np

import mcgeom
from mcgeom import metrics
from mcgeom.types import RayPairs

from . import linear17_accuracy
from .common import Progress, add_count_and_seed, no_progress, positive_int

__all__ = ["OPENGV_MODULE", "load_opengv", "opengv_inputs", "opengv_linear17", "noise_free_rays",
           "noise_free_check", "run", "table", "agreement", "add_arguments", "run_cli"]

#: the name of the user-built extension module around OpenGV's seventeenpt
OPENGV_MODULE = "opengv17"


def load_opengv(path: Optional[str] = None) -> tuple[Optional[ModuleType], str]:
    """``(module or None, a sentence saying what was loaded or why not)``.

    ``path``: the ``opengv17`` extension file, or a folder holding it; None
    imports ``opengv17`` from ``sys.path``. A path that does not exist is a
    ValueError naming ``--opengv``; a module that fails to load is reported,
    not raised, so that mcgeom's rows are still printed.
    """
    if path is None:
        try:
            mod = importlib.import_module(OPENGV_MODULE)
        except ImportError as exc:
            return None, (f"OpenGV not available ({OPENGV_MODULE} not importable: {exc}); "
                          "pass --opengv PATH to the module built against OpenGV")
        return mod, f"OpenGV: {mod.__file__}"
    if not os.path.exists(path):
        raise ValueError(f"--opengv: {path!r} does not exist (give the {OPENGV_MODULE} "
                         "extension module or the folder that holds it)")
    file = path
    if os.path.isdir(path):
        found = sorted(f for f in os.listdir(path)
                       if f.startswith(OPENGV_MODULE + ".") and f.endswith((".so", ".pyd")))
        if not found:
            return None, f"OpenGV not available: no {OPENGV_MODULE}*.so in {path!r}"
        file = os.path.join(path, found[0])
    try:
        spec = importlib.util.spec_from_file_location(OPENGV_MODULE, file)
        if spec is None or spec.loader is None:
            return None, f"OpenGV not available: {file!r} is not an extension module"
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
    except ImportError as exc:
        return None, f"OpenGV not available: loading {file!r} failed: {exc}"
    if not (hasattr(mod, "seventeenpt") and hasattr(mod, "seventeenpt_timed")):
        return None, f"OpenGV not available: {file!r} lacks seventeenpt / seventeenpt_timed"
    return mod, f"OpenGV: {file}"


def _opengv_path(text: str) -> str:
    """argparse type of ``--opengv``: an existing file or folder (a usage
    error, exit code 2, otherwise)."""
    if not os.path.exists(text):
        raise argparse.ArgumentTypeError(f"{text!r} does not exist (give the {OPENGV_MODULE} "
                                         "extension module or the folder that holds it)")
    return text


def _unit(d: np.ndarray) -> np.ndarray:
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def opengv_inputs(rays: RayPairs) -> tuple[np.ndarray, ...]:
    """OpenGV's non-central adapter arrays for ``rays`` (rig frame, metres):
    unit bearings (N, 3) at both times, camera indices (N,) of each time into
    the distinct ray origins ``offsets`` (C, 3), and identity ``rotations``
    (C, 3, 3) (the bearings are already in the rig frame)."""
    n = len(rays)
    offsets, inv = np.unique(np.vstack([rays.origins1, rays.origins2]), axis=0,
                             return_inverse=True)
    inv = inv.reshape(-1).astype(np.int32)
    rotations = np.broadcast_to(np.eye(3), (len(offsets), 3, 3)).copy()
    return (_unit(rays.dirs1), _unit(rays.dirs2), inv[:n].copy(), inv[n:].copy(),
            offsets, rotations)


def _from_opengv(T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """OpenGV's [R_o | t_o] (viewpoint 2 in viewpoint 1: X1 = R_o X2 + t_o) as
    our rig2_from_rig1 (R, t): X2 = R_o^T X1 - R_o^T t_o."""
    Ro, to = T[:, :3], T[:, 3]
    return Ro.T.copy(), -Ro.T @ to


def opengv_linear17(opengv: ModuleType, rays: RayPairs) -> tuple[np.ndarray, np.ndarray]:
    """OpenGV's seventeenpt on ``rays`` as rig2_from_rig1 ``(R, t)`` (t metric,
    metres: the unit of the ray origins)."""
    return _from_opengv(np.asarray(opengv.seventeenpt(*opengv_inputs(rays))))


def _with_unit_dirs(rays: RayPairs) -> RayPairs:
    return RayPairs(rays.origins1, _unit(rays.dirs1), rays.origins2, _unit(rays.dirs2),
                    rays.cam1, rays.cam2)


def noise_free_rays(prob) -> RayPairs:
    """The rays of synthetic problem ``prob`` without noise: from each camera
    centre (the rays' origins, which carry no noise) to the scene point, at
    time 1 in the rig1 frame and at time 2 in the rig2 frame."""
    r = prob.rays
    X2 = prob.points @ prob.R.T + prob.t
    return RayPairs(r.origins1, prob.points - r.origins1, r.origins2, X2 - r.origins2,
                    r.cam1, r.cam2)


def _errors(R: np.ndarray, t: np.ndarray, R_true: np.ndarray, t_true: np.ndarray):
    """(rotation error in degrees, |(|t| / |t_true|) - 1|)"""
    return (float(np.degrees(metrics.rotation_error(R, R_true))),
            abs(float(np.linalg.norm(t) / np.linalg.norm(t_true)) - 1.0))


def _mcgeom(rays: RayPairs) -> tuple[np.ndarray, np.ndarray, bool]:
    m = mcgeom.estimate(rays, "linear17")
    return m.R, m.info["t_metric"], bool(m.scale.observable)


def noise_free_check(opengv: Optional[ModuleType], seed: int = 0,
                     cases: Optional[dict] = None) -> dict:
    """{case: {method: (rotation error deg, scale error)}} on one noise-free
    problem per case: the conventions are right when both are ~1e-10."""
    out = {}
    for name, make in (cases or linear17_accuracy.CASES).items():
        prob = make(np.random.default_rng(seed))
        rays = _with_unit_dirs(noise_free_rays(prob))
        out[name] = {"mcgeom": _errors(*_mcgeom(rays)[:2], prob.R, prob.t)}
        if opengv is not None:
            out[name]["opengv"] = _errors(*opengv_linear17(opengv, rays), prob.R, prob.t)
    return out


def run(trials: int = 100, seed: int = 0, opengv: Optional[ModuleType] = None,
        cases: Optional[dict] = None, variants: tuple[str, ...] = (), repeats: int = 10,
        progress: Progress = no_progress) -> dict:
    """Per case, per method, a (trials x 4) array: rotation error (deg), scale
    error, Python-side seconds per call, and the scale verdict for mcgeom (1/0)
    or the C++-side seconds per call (mean of ``repeats``) for OpenGV (NaN for
    the numpy variants of :mod:`linear17_accuracy`, named ``numpy:<variant>``).
    Every method sees the same rays in every trial (paired)."""
    out = {}
    for name, make in (cases or linear17_accuracy.CASES).items():
        rng = np.random.default_rng(seed)
        rows: dict[str, list] = {"mcgeom": []}
        if opengv is not None:
            rows["opengv"] = []
        for v in variants:
            rows[f"numpy:{v}"] = []
        for _ in progress(range(trials), total=trials, desc=name):
            prob = make(rng)
            rays = _with_unit_dirs(prob.rays)        # prepared outside the timing
            t0 = time.perf_counter()
            R, t, obs = _mcgeom(rays)
            dt = time.perf_counter() - t0
            rows["mcgeom"].append((*_errors(R, t, prob.R, prob.t), dt, float(obs)))
            if opengv is not None:
                args = opengv_inputs(rays)
                t0 = time.perf_counter()
                T = opengv.seventeenpt(*args)
                dt = time.perf_counter() - t0
                _, ns = opengv.seventeenpt_timed(*args, repeats)
                rows["opengv"].append((*_errors(*_from_opengv(np.asarray(T)), prob.R, prob.t),
                                       dt, ns * 1e-9))
            for v in variants:
                t0 = time.perf_counter()
                R, t, _ = linear17_accuracy.VARIANTS[v](rays)
                dt = time.perf_counter() - t0
                rows[f"numpy:{v}"].append((*_errors(R, t, prob.R, prob.t), dt, np.nan))
        out[name] = {k: np.array(v) for k, v in rows.items()}
    return out


def table(res: dict) -> str:
    """Medians per case and method, and the fraction of trials where OpenGV
    (and each other method) is more accurate than mcgeom."""
    lines = [f"{'case':<27} {'method':<20} {'rot med [deg]':>13} {'scale med':>10} "
             f"{'other better: rot / scale':>26} {'us/call (py)':>12} {'us/call (C++)':>13} "
             f"{'observable':>10}"]
    for case, methods in res.items():
        ref = methods["mcgeom"]
        for meth, e in methods.items():
            med = np.median(e, axis=0)
            better = "" if meth == "mcgeom" else (
                f"{np.mean(e[:, 0] < ref[:, 0]):.2f} / {np.mean(e[:, 1] < ref[:, 1]):.2f}")
            cpp = f"{1e6 * med[3]:13.1f}" if meth == "opengv" else f"{'':13}"
            obs = f"{np.mean(e[:, 3]):10.2f}" if meth == "mcgeom" else ""
            lines.append(f"{case:<27} {meth:<20} {med[0]:13.4f} {med[1]:10.4f} {better:>26} "
                         f"{1e6 * med[2]:12.1f} {cpp} {obs}")
    return "\n".join(lines)


def agreement(res: dict, a: str = "opengv", b: str = "numpy:opengv") -> str:
    """The largest per-trial difference of the rotation and the scale errors of
    methods ``a`` and ``b`` per case: ~1e-12 when ``b`` computes what ``a`` does."""
    lines = [f"{b} against {a}: largest per-trial |difference| of the errors"]
    for case, m in res.items():
        d = np.max(np.abs(m[a][:, :2] - m[b][:, :2]), axis=0)
        lines.append(f"  {case:<27} rotation {d[0]:.1e} deg  scale {d[1]:.1e}")
    return "\n".join(lines)


def add_arguments(ap: argparse.ArgumentParser) -> None:
    """The options of ``mcgeom experiment linear17_peers``."""
    add_count_and_seed(ap, "--trials", 100, "problems per case")
    ap.add_argument("--opengv", default=None, metavar="PATH", type=_opengv_path,
                    help=f"the {OPENGV_MODULE} extension module built against OpenGV, or its "
                         "folder (default: import it from sys.path; absent: mcgeom alone)")
    ap.add_argument("--variants", nargs="*", default=[], metavar="NAME",
                    choices=list(linear17_accuracy.VARIANTS),
                    help="numpy variants of linear17_accuracy to run on the same rays")
    ap.add_argument("--repeats", type=positive_int, default=10,
                    help="calls per trial for OpenGV's C++-side timing")


def run_cli(args: argparse.Namespace, progress: Progress = no_progress) -> int:
    """Print the noise-free convention check, the table and the paired
    comparisons."""
    opengv, note = load_opengv(args.opengv)
    print(note)
    print("PoseLib: no linear 17-point solver in its API; skipped")
    print("\nnoise-free problem per case (rotation error deg, scale error):")
    for case, methods in noise_free_check(opengv, args.seed).items():
        print(f"  {case:<27} " + "  ".join(f"{m} {r:.1e} {s:.1e}" for m, (r, s) in methods.items()))
    variants = tuple(v for v in args.variants if v != "kernel")
    res = run(args.trials, args.seed, opengv, variants=variants, repeats=args.repeats,
              progress=progress)
    print()
    print(table(res))
    methods = list(next(iter(res.values())))
    pairs = [("mcgeom", m) for m in methods if m != "mcgeom"]
    if "opengv" in methods:      # the numpy variants against the real OpenGV
        pairs += [("opengv", m) for m in methods if m.startswith("numpy:")]
    for ref, other in pairs:
        print()
        print(linear17_accuracy.paired(res, other, ref=ref))
    if "opengv" in methods and "numpy:opengv" in methods:
        print()
        print(agreement(res))
    return 0
