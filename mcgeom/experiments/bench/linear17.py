"""``mcgeom bench linear17``: where the time of a linear17 call goes.

For each N, on one synthetic problem (a 4-camera non-axial rig,
intra-camera correspondences, 0.05 deg angular noise), the best mean time of:

- ``public``: ``mcgeom.estimate(rays, "linear17")``, what a user calls
  (RayPairs in, RigMotion with its scale verdict out: the registry, the
  plugin, the cffi wrapper and the kernel; the estimate and its static-rig
  test share one marshalling of the rays, ``_core.linear17_static_raw``);
- ``plugin``: the estimator without the shared static-rig test
  (``mcgeom.estimators.linear17.linear17_no_static_check``: input checks, the kernel, the
  info dict and the verdict); ``static`` = public - plugin is what the test
  of :mod:`mcgeom.estimators._static` costs (issue 18's, shared by every
  estimator) together with the check that no single correspondence carries
  a metric estimate (``mcg_sampson_leverage``,
  :func:`mcgeom.estimators._outliers.one_pair_rule`: ~4 us at 100 rays);
- ``static C``: that test's kernel ``mcg_static_check`` alone through cffi
  (its pointers, workspace and options made beforehand, the plugin's
  rotation as the estimate's): ``static - static C`` is its Python;
- ``wrapper``: ``mcgeom._core.linear17`` (the cffi wrapper: buffers in, the
  result struct as a dict of numpy views out);
- ``C``: the kernel ``mcg_linear17`` alone through cffi, its pointers made
  beforehand (the C time plus one foreign call);
- ``numpy``: the same algorithm written with numpy (``linear17_numpy``).

``python`` = public - C is what the layers above the kernel cost.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mcgeom import _core, estimate, synth
from mcgeom.estimators._static import KERNEL_OPTIONS, intra_groups
from mcgeom.estimators.linear17 import linear17_no_static_check
from ..common import Progress, no_progress
from .linear17_numpy import linear17_numpy
from .timing import best_of

__all__ = ["Linear17Timing", "bench_linear17"]


@dataclass(frozen=True)
class Linear17Timing:
    """Microseconds per call at ``n`` rays (see the module docstring)."""

    n: int
    public_us: float
    plugin_us: float
    wrapper_us: float
    c_us: float
    static_c_us: float
    numpy_us: float
    iterations: int

    @property
    def python_us(self) -> float:
        """Time spent above the kernel: public call minus C."""
        return self.public_us - self.c_us

    @property
    def static_us(self) -> float:
        """Time of the shared static-rig test: public call minus plugin."""
        return self.public_us - self.plugin_us

    @property
    def ratio(self) -> float:
        """numpy / public."""
        return self.numpy_us / self.public_us


def _timed(fn, budget_s: float) -> float:
    once = best_of(fn, 1, 3)
    number = max(1, int(budget_s / 5 / max(once, 1e-7)))
    return best_of(fn, 5, number)


def bench_linear17(sizes=(17, 100, 1000, 10000), seed: int = 0, budget_s: float = 0.5,
                   progress: Progress = no_progress) -> list[Linear17Timing]:
    """Time linear17 through the public call, the plugin, the wrapper and the bare kernel,
    the static test's bare kernel, and the numpy reference, for each N (microseconds per call, best of
    batches; ``budget_s`` seconds per timing)."""
    rng = np.random.default_rng(seed)
    rig = synth.generic_rig(4, rng)
    out = []
    for n in progress(sizes, total=len(sizes), desc="linear17"):
        R, t = synth.random_motion(rng, max_angle=0.3, t_norm=0.5)
        prob = synth.make_problem(rig, R, t, n, rng, angular_noise=np.deg2rad(0.05),
                                  require_visible=False)
        rays = prob.rays
        m = estimate(rays, "linear17")
        args = (rays.origins1, rays.dirs1, rays.origins2, rays.dirs2)
        ptrs = [_core.ffi.from_buffer("double[]", a) for a in args]
        res = _core.ffi.new("mcg_linear17_result *")
        kernel = _core.lib.mcg_linear17
        # the static test's kernel as check_static calls it on this estimate
        group = intra_groups(rays)
        R_est = np.ascontiguousarray(linear17_no_static_check(rays).R)
        work = np.empty(_core.lib.mcg_static_check_work_size(n))
        s_args = (n, *ptrs, _core.ffi.from_buffer("int[]", group),
                  _core.ffi.from_buffer("double[]", R_est), _core.ffi.NULL, 0.0,
                  KERNEL_OPTIONS, _core.ffi.new("mcg_static_result *"),
                  _core.ffi.from_buffer("double[]", work), work.size)
        static_kernel = _core.lib.mcg_static_check
        public_t = _timed(lambda: estimate(rays, "linear17"), budget_s)
        plugin_t = _timed(lambda: linear17_no_static_check(rays), budget_s)
        wrapper_t = _timed(lambda: _core.linear17(*args), budget_s)
        c_t = _timed(lambda: kernel(n, *ptrs, _core.ffi.NULL, res), budget_s)
        static_c_t = _timed(lambda: static_kernel(*s_args), budget_s)
        np_t = _timed(lambda: linear17_numpy(*args), budget_s)
        out.append(Linear17Timing(n, public_t * 1e6, plugin_t * 1e6, wrapper_t * 1e6, c_t * 1e6,
                                  static_c_t * 1e6, np_t * 1e6, m.info["iterations"]))
    return out
