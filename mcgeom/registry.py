"""Plugin registry: estimators and LP backends swapped at runtime by name.

An estimator is a callable ``fn(rays: RayPairs, **options) -> RigMotion``
registered with metadata that tests, the robust layer and the CLI rely on:
the minimal sample size, the generalized-camera kinds it supports (thesis
ch. 8.3), its family (linear / minimal / globally optimal / refinement),
whether it needs a known rotation and whether it recovers the metric scale.

Third-party packages register through the entry-point group
``mcgeom.estimators``: each entry point names a module (or a callable) whose
import registers its estimators with :func:`register`. Entry points are
loaded lazily, the first time the registry is queried.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from importlib import metadata
from typing import Callable, Iterable, Optional

__all__ = [
    "CAMERA_KINDS", "FAMILIES", "EstimatorInfo", "register", "get", "names",
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


@dataclass(frozen=True)
class EstimatorInfo:
    """A registered estimator and its metadata."""

    name: str
    func: Callable
    min_sample: int
    camera_kinds: tuple[str, ...]
    family: str
    needs_rotation: bool = False
    recovers_scale: bool = True
    description: str = ""
    options: dict = field(default_factory=dict)
    #: ``solver(sample: RayPairs) -> list[(R, t)]``: every motion consistent with a
    #: minimal sample (``min_sample`` rays), for the robust layer; None if the
    #: estimator cannot be driven by minimal samples
    minimal_solver: Optional[Callable] = None
    #: ``sampler(rays: RayPairs, rng) -> index array`` drawing one minimal sample;
    #: None = the robust layer's default (spread across cameras)
    sampler: Optional[Callable] = None
    #: ``proposer(rays, threshold, prob, rng)``: an iterable of ``(R, t)`` or
    #: ``(R, t, expected_inlier_ratio)`` from a method-specific robust search
    #: (e.g. the two-stage RANSAC of thesis ch. 7.4); the robust layer scores and
    #: refines them and stops once one explains the expected inlier ratio
    proposer: Optional[Callable] = None
    #: ``objective(rays, R) -> float``: for a globally optimal estimator whose
    #: optimum may be a set of rotations (an L-infinity minimum), the value it
    #: minimises; its results carry ``info["linf"]`` and the certified
    #: ``info["gap"]``. Equivalent inputs must then give equally good results
    #: (values within the gaps), not necessarily the same rotation.
    objective: Optional[Callable] = None

    def __call__(self, rays, **options):
        check_distinct(rays, self.min_sample, self.name)
        return self.func(rays, **options)


def check_distinct(rays, need: int, name: str) -> None:
    """DegenerateError when repeated correspondences leave fewer distinct ones
    than ``need`` (the minimal sample): copies of one correspondence constrain
    no more than it does, and estimators would otherwise return a motion the
    data do not determine (or search for one at length)."""
    from .errors import DegenerateError
    from .types import RayPairs
    if not isinstance(rays, RayPairs) or len(rays) < need:
        return  # the estimator's own checks name the problem
    k = rays.n_distinct(at_least=need)
    if k < need:
        raise DegenerateError(f"{name}: only {k} distinct correspondence(s) among {len(rays)} "
                              f"(the others repeat them); {name} needs at least {need}")


_REGISTRY: dict[str, EstimatorInfo] = {}
_plugins_loaded = False


def register(name: str, *, min_sample: int, camera_kinds: Iterable[str], family: str,
             needs_rotation: bool = False, recovers_scale: bool = True,
             description: str = "", options: Optional[dict] = None,
             minimal_solver: Optional[Callable] = None, sampler: Optional[Callable] = None,
             proposer: Optional[Callable] = None, objective: Optional[Callable] = None,
             replace: bool = False) -> Callable[[Callable], Callable]:
    """Decorator registering ``fn(rays, **options) -> RigMotion`` under ``name``.

    ``options`` documents the keyword options (name -> short description).
    ``minimal_solver``, ``sampler`` and ``proposer`` (see :class:`EstimatorInfo`) let
    :mod:`mcgeom.robust` drive the estimator with minimal samples; ``objective``
    declares the value a set-valued global optimum minimises.
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

    def deco(fn: Callable) -> Callable:
        if name in _REGISTRY and not replace:
            raise ValueError(f"estimator {name!r} is already registered")
        _REGISTRY[name] = EstimatorInfo(name, fn, int(min_sample), kinds, family,
                                        bool(needs_rotation), bool(recovers_scale),
                                        description or (fn.__doc__ or "").strip().split("\n")[0],
                                        dict(options or {}), minimal_solver, sampler,
                                        proposer, objective)
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
