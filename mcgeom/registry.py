"""Plugin registry: estimators and LP backends swapped at runtime by name.

An estimator is a callable ``fn(rays: RayPairs, **options) -> RigMotion``
registered with metadata that tests, the robust layer and the CLI rely on:
the minimal sample size, the generalized-camera kinds it supports (thesis
ch. 8.3), its family (linear / minimal / globally optimal / refinement),
whether it needs a known rotation and whether it recovers the metric scale.

The contract a plugin fulfils is written once, below, as :class:`EstimatorPlugin`
(a ``typing.Protocol`` that :class:`EstimatorInfo` satisfies) and the
protocols of its callables: :class:`Estimator` (required), and the optional
hooks through which :mod:`mcgeom.robust` drives it -- :class:`MinimalSolver`
with :class:`Sampler` (classic RANSAC: draw ``min_sample`` correspondences,
solve, score), :class:`Proposer` (a method-specific robust search whose
motions RANSAC scores and refines) -- and :class:`Objective` (set-valued
global optima). :func:`register` and :class:`EstimatorInfo` are annotated with
them; ``tests/test_registry_contract.py`` checks the built-ins against them.

Third-party packages register through the entry-point group
``mcgeom.estimators``: each entry point names a module (or a callable) whose
import registers its estimators with :func:`register`. Entry points are
loaded lazily, the first time the registry is queried.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from importlib import metadata
from typing import Any, Callable, Iterable, Optional, Protocol, Union

import numpy as np

from .errors import DegenerateError
from .types import RayPairs, RigMotion

__all__ = [
    "CAMERA_KINDS", "FAMILIES", "EstimatorInfo", "register", "get", "names",
    "Estimator", "MinimalSolver", "Sampler", "Proposer", "Objective", "EstimatorPlugin",
    "check_distinct",
    "list_estimators", "unregister", "load_plugins", "ENTRY_POINT_GROUP",
    "lp_backends", "set_default_lp_backend", "default_lp_backend", "resolve_lp_backend",
    "glpk_status",
]

ENTRY_POINT_GROUP = "mcgeom.estimators"

#: generalized-camera kinds of thesis ch. 8.3 (plus the plain central camera)
CAMERA_KINDS = ("most-general", "locally-central", "axial", "locally-central-and-axial",
                "central")
#: estimator families
FAMILIES = ("linear", "minimal", "globally-optimal", "refinement")


# ------------------------------------------------------------ the contract
# Frames and units for every callable below (docs/architecture.md §3): rays in the
# rig frame (origins at the camera centres, metres; unit directions), camera
# ids in ``rays.cam1``/``rays.cam2`` when known; a motion ``(R, t)`` is
# rig2_from_rig1, ``X2 = R X1 + t``, ``R`` a (3, 3) rotation, ``t`` (3,) in
# metres; residuals and thresholds in radians (Sampson angular error of the
# generalized epipolar constraint, thesis eq. 8.15). The hooks' parameters are
# positional: the robust layer calls them so.

class Estimator(Protocol):
    """The estimator: ``fn(rays, **options) -> RigMotion`` (required).

    Must: accept the :class:`RayPairs` positionally and its documented options
    (``register(options=...)``) as keywords; return a :class:`RigMotion` with
    ``R``, ``t`` (metric when ``verdict.observable``, else unit length or zero),
    the scale verdict and ``method``; raise ValueError for bad or too few
    correspondences and :class:`mcgeom.errors.DegenerateError` when the data do
    not determine the motion -- never return a motion the data do not support.
    Equivalent inputs (ray order, rig frame) must give equivalent results.
    """

    def __call__(self, rays: RayPairs, /, **options: Any) -> RigMotion: ...


class MinimalSolver(Protocol):
    """``solver(sample) -> [(R, t), ...]``: every motion consistent with a minimal sample.

    ``sample`` holds exactly ``min_sample`` correspondences (as the plugin's
    :class:`Sampler`, or the default sampler, drew them). Returns all
    solutions (possibly none); each ``(R, t)`` must satisfy the sample's
    epipolar constraints to rounding. A degenerate sample returns ``[]`` or
    raises :class:`mcgeom.errors.DegenerateError` (the robust layer skips it).
    The robust layer scores each solution on all correspondences (cf. PoseLib's
    ``generate_models``). Keyword options (e.g. the gravity directions of
    ``upright_four_point``) come from ``mcgeom.robust.ransac(solver_options=...)``.
    """

    def __call__(self, sample: RayPairs, /, **options: Any
                 ) -> list[tuple[np.ndarray, np.ndarray]]: ...


class Sampler(Protocol):
    """``sampler(rays, rng) -> index array``: one minimal sample.

    Returns ``min_sample`` distinct indices into ``rays`` (an int array),
    drawn with ``rng`` only (the run is then reproducible from the seed), in
    the layout the :class:`MinimalSolver` expects. ValueError when ``rays``
    cannot yield such a sample. Optional: the default spreads the sample across
    camera pairs (:func:`mcgeom.robust.sample_across_cameras`).
    """

    def __call__(self, rays: RayPairs, rng: np.random.Generator, /) -> np.ndarray: ...


class Proposer(Protocol):
    """``proposer(rays, threshold, prob, rng)``: hypotheses from a method-specific search.

    ``threshold`` is the inlier threshold in radians, ``prob`` the RANSAC
    confidence, ``rng`` the only source of randomness. Yields ``(R, t)`` or
    ``(R, t, expected_inlier_ratio)`` (the fraction of the correspondences the
    search expects the motion to explain); the robust layer scores and refines
    each on all correspondences and stops asking once one explains about the
    expected ratio (e.g. the two-stage RANSAC of thesis ch. 7.4). Yielding
    nothing makes the robust layer fall back to the minimal solver.
    """

    def __call__(self, rays: RayPairs, threshold: float, prob: float,
                 rng: np.random.Generator, /
                 ) -> Iterable[Union[tuple[np.ndarray, np.ndarray],
                                     tuple[np.ndarray, np.ndarray, float]]]: ...


class Objective(Protocol):
    """``objective(rays, R) -> float``: the value a set-valued global optimum minimises.

    For a globally optimal estimator whose optimum may be a set of rotations
    (an L-infinity minimum, radians): the value at rotation ``R``; the
    estimator's results then carry ``info["linf"]`` and the certified
    ``info["gap"]``, and equivalent inputs must give values within the gaps.
    """

    def __call__(self, rays: RayPairs, R: np.ndarray, /) -> float: ...


class EstimatorPlugin(Protocol):
    """What a registered estimator provides (:class:`EstimatorInfo` is one).

    ``func`` (:class:`Estimator`) and ``min_sample`` (the fewest
    correspondences that determine the motion: the size of a minimal sample)
    are required; ``camera_kinds`` (of :data:`CAMERA_KINDS`), ``family`` (of
    :data:`FAMILIES`), ``needs_rotation`` and ``recovers_scale`` describe it.
    RANSAC (:mod:`mcgeom.robust`) can drive the estimator when it has a
    ``minimal_solver`` (optionally with its ``sampler``) or a ``proposer``:
    sample size ``min_sample``, generate models with the minimal solver or
    the proposer, score them (MSAC on the Sampson residual), refine the best
    on its inliers (the centred refinement, not a hook) -- the split of
    PoseLib's ``robust/ransac_impl.h`` (sample_sz, generate_models,
    score_model, refine_model).
    """

    name: str
    func: Estimator
    min_sample: int
    camera_kinds: tuple[str, ...]
    family: str
    needs_rotation: bool
    recovers_scale: bool
    minimal_solver: Optional[MinimalSolver]
    sampler: Optional[Sampler]
    proposer: Optional[Proposer]
    objective: Optional[Objective]


@dataclass(frozen=True)
class EstimatorInfo:
    """A registered estimator and its metadata (fulfils :class:`EstimatorPlugin`)."""

    name: str
    func: Estimator
    min_sample: int
    camera_kinds: tuple[str, ...]
    family: str
    needs_rotation: bool = False
    recovers_scale: bool = True
    description: str = ""
    options: dict = field(default_factory=dict)
    # the hooks of the contract (see the protocols above); None = not provided
    minimal_solver: Optional[MinimalSolver] = None
    #: None = the robust layer's default (spread across cameras)
    sampler: Optional[Sampler] = None
    proposer: Optional[Proposer] = None
    objective: Optional[Objective] = None
    #: True when the estimator itself raises DegenerateError for fewer than
    #: ``min_sample`` distinct correspondences (e.g. in its C kernel, in the
    #: same pass as its other checks): the registry then skips
    #: :func:`check_distinct`, whose sort costs more than a fast estimator
    checks_distinct: bool = False

    def __call__(self, rays: RayPairs, **options: Any) -> RigMotion:
        if not self.checks_distinct:
            check_distinct(rays, self.min_sample, self.name)
        return self.func(rays, **options)


def _first_rows_distinct(rays: RayPairs, need: int) -> bool:
    """Are the first ``need`` correspondences pairwise different (some entry
    of the six arrays differs, as ``!=`` compares: what
    :meth:`RayPairs.n_distinct` counts)? Then there are at least ``need``
    distinct ones: the common case answered by one (need, need) comparison
    instead of a sort (issue 19: the robust façade asks this of every
    problem)."""
    # first one column: rows whose first time-1 direction components already
    # differ pairwise are distinct (one slice and a set of ``need`` floats;
    # the whole rows only when two of those components are equal)
    if len(set(rays.dirs1[:need, 0].tolist())) == need:
        return True
    cols = [a[:need] for a in (rays.origins1, rays.dirs1, rays.origins2, rays.dirs2)]
    cols += [ids[:need, None] for ids in (rays.cam1, rays.cam2) if ids is not None]
    r = np.concatenate(cols, axis=1, dtype=np.float64)
    # a set of the rows as tuples of Python floats: equal as ``==`` compares
    # (0.0 and -0.0 alike, hash included; NaN objects never equal), the
    # numpy (need, need, 14) comparison's answer without its ~10 array ops
    return len(set(map(tuple, r.tolist()))) == need


def check_distinct(rays: RayPairs, need: int, name: str) -> None:
    """DegenerateError when repeated correspondences leave fewer distinct ones
    than ``need`` (the minimal sample): copies of one correspondence constrain
    no more than it does, and estimators would otherwise return a motion the
    data do not determine (or search for one at length)."""
    if not isinstance(rays, RayPairs) or len(rays) < need:
        return  # the estimator's own checks name the problem
    if _first_rows_distinct(rays, need):
        return
    k = rays.n_distinct(at_least=need)
    if k < need:
        raise DegenerateError(f"{name}: only {k} distinct correspondence(s) among {len(rays)} "
                              f"(the others repeat them); {name} needs at least {need}")


_REGISTRY: dict[str, EstimatorInfo] = {}
_plugins_loaded = False


def register(name: str, *, min_sample: int, camera_kinds: Iterable[str], family: str,
             needs_rotation: bool = False, recovers_scale: bool = True,
             description: str = "", options: Optional[dict] = None,
             minimal_solver: Optional[MinimalSolver] = None, sampler: Optional[Sampler] = None,
             proposer: Optional[Proposer] = None, objective: Optional[Objective] = None,
             checks_distinct: bool = False,
             replace: bool = False) -> Callable[[Estimator], Estimator]:
    """Decorator registering ``fn(rays, **options) -> RigMotion`` under ``name``.

    ``options`` documents the keyword options (name -> short description).
    ``minimal_solver``, ``sampler`` and ``proposer`` (see :class:`EstimatorInfo`) let
    :mod:`mcgeom.robust` drive the estimator with minimal samples; ``objective``
    declares the value a set-valued global optimum minimises.
    ``checks_distinct=True`` promises that the estimator raises DegenerateError
    by itself when repeated correspondences leave fewer than ``min_sample``
    distinct ones (the registry then does not check it again).
    Registering an existing name raises ValueError unless ``replace=True``.
    """
    kinds = tuple(camera_kinds)
    bad = [k for k in kinds if k not in CAMERA_KINDS]
    if bad:
        raise ValueError(f"unknown camera kind(s) {bad}; valid: {CAMERA_KINDS}")
    if family not in FAMILIES:
        raise ValueError(f"unknown family {family!r}; valid: {FAMILIES}")
    if int(min_sample) < 1:
        raise ValueError(f"min_sample must be >= 1, got {min_sample}")
    if not name or not isinstance(name, str):
        raise ValueError("estimator name must be a non-empty string")

    def deco(fn: Estimator) -> Estimator:
        if name in _REGISTRY and not replace:
            raise ValueError(f"estimator {name!r} is already registered")
        _REGISTRY[name] = EstimatorInfo(name, fn, int(min_sample), kinds, family,
                                        bool(needs_rotation), bool(recovers_scale),
                                        description or (fn.__doc__ or "").strip().split("\n")[0],
                                        dict(options or {}), minimal_solver, sampler,
                                        proposer, objective, bool(checks_distinct))
        return fn

    return deco


def unregister(name: str) -> None:
    """Remove an estimator (mainly for tests of third-party registration)."""
    _REGISTRY.pop(name, None)


def load_plugins() -> None:
    """Import the modules advertised in the ``mcgeom.estimators`` entry points."""
    global _plugins_loaded
    if _plugins_loaded:
        return
    _plugins_loaded = True
    for ep in metadata.entry_points(group=ENTRY_POINT_GROUP):
        obj = ep.load()  # importing a module registers its estimators
        if callable(obj):
            obj()  # "pkg.mod:setup" style: a function that registers


def get(name: str) -> EstimatorInfo:
    """The estimator registered as ``name``; ValueError listing the known names."""
    load_plugins()
    try:
        return _REGISTRY[name]
    except KeyError:
        raise ValueError(f"unknown estimator {name!r}; registered: {sorted(_REGISTRY)}") from None


def names() -> list[str]:
    """Names of the registered estimators, sorted."""
    load_plugins()
    return sorted(_REGISTRY)


def list_estimators() -> list[EstimatorInfo]:
    """All registered estimators with their metadata, sorted by name."""
    load_plugins()
    return [_REGISTRY[k] for k in sorted(_REGISTRY)]


# ------------------------------------------------------------- LP backends
# The LP feasibility backends of the branch and bound (thesis ch. 10.3) live
# in the C core (``native`` always, ``glpk`` when libglpk could be loaded);
# the registry names them and holds the process-wide default, so a caller
# swaps the solver at runtime by name, like an estimator.

_lp_default = "native"


def lp_backends() -> dict[str, str]:
    """Available LP backends: name -> short description (the GLPK entry says
    why it is missing when it is)."""
    from . import _core
    out = {"native": "Seidel's randomized incremental LP (csrc/lp_native.c), MIT"}
    status = _core.glpk_load_status()
    if "glpk" in _core.LP_BACKENDS:
        out["glpk"] = "GLPK primal simplex (csrc/lp_glpk.c, GPL-3.0), " + status
    return out


def glpk_status() -> str:
    """Why the GLPK backend is or is not available."""
    from . import _core
    return _core.glpk_load_status()


def set_default_lp_backend(name: str) -> None:
    """Make ``name`` the LP backend used when an estimator is not told one."""
    global _lp_default
    _lp_default = resolve_lp_backend(name)


def default_lp_backend() -> str:
    """The LP backend used when an estimator is not told one."""
    return _lp_default


def resolve_lp_backend(name: Optional[str]) -> str:
    """``name`` checked against the available backends (None: the default)."""
    if name is None:
        return _lp_default
    avail = lp_backends()
    if name not in avail:
        hint = f" (glpk: {glpk_status()})" if name == "glpk" else ""
        raise ValueError(f"unknown or unavailable LP backend {name!r}; available: "
                         f"{sorted(avail)}{hint}")
    return name
