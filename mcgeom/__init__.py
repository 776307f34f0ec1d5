"""mcgeom: relative motion, with metric scale, of calibrated multi-camera rigs.

Conventions (docs/architecture.md §3): rays and camera centres in the rig frame
(metres); a motion is rig2_from_rig1, ``X_rig2 = R @ X_rig1 + t`` as in
``cv2.recoverPose``; angles in radians.
"""

from __future__ import annotations

from . import registry
from .errors import (DegenerateError, InfeasibleError, McgeomError, NumericalError,
                     ScaleNotObservableWarning)
from .types import RayPairs, RigMotion, ScaleVerdict
from . import estimators as _estimators  # noqa: F401  (registers the built-ins)
from . import robust
from .io import load_rig
from .cv import (RIG_5P1_DIRECT, RIG_5P1_RANSAC, RIG_LINEAR17, RIG_LINEAR17_RANSAC,
                 estimateRigMotion)

__version__ = "0.1.0"


def estimate(rays: RayPairs, method: str = "linear17", **options) -> RigMotion:
    """Estimate the rig motion from ray correspondences with a registered method.

    ``method`` is any name of :func:`mcgeom.registry.names`; ``options`` are the
    method's keyword options (see ``mcgeom methods``).
    """
    return registry.get(method)(rays, **options)


__all__ = [
    "RayPairs", "RigMotion", "ScaleVerdict", "estimate", "registry", "robust",
    "estimateRigMotion", "RIG_5P1_RANSAC", "RIG_5P1_DIRECT", "RIG_LINEAR17",
    "RIG_LINEAR17_RANSAC", "load_rig",
    "McgeomError", "NumericalError", "InfeasibleError", "DegenerateError",
    "ScaleNotObservableWarning", "__version__",
]
