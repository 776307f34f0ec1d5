"""Plugin registry: estimators (and later backends) swapped at runtime by name.

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

    def __call__(self, rays, **options):
        return self.func(rays, **options)


_REGISTRY: dict[str, EstimatorInfo] = {}
_plugins_loaded = False


def register(name: str, *, min_sample: int, camera_kinds: Iterable[str], family: str,
             needs_rotation: bool = False, recovers_scale: bool = True,
             description: str = "", options: Optional[dict] = None,
             minimal_solver: Optional[Callable] = None, sampler: Optional[Callable] = None,
             proposer: Optional[Callable] = None, replace: bool = False) -> Callable[[Callable], Callable]:
    """Decorator registering ``fn(rays, **options) -> RigMotion`` under ``name``.

    ``options`` documents the keyword options (name -> short description).
    ``minimal_solver``, ``sampler`` and ``proposer`` (see :class:`EstimatorInfo`) let
    :mod:`mcgeom.robust` drive the estimator with minimal samples.
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
                                        proposer)
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
