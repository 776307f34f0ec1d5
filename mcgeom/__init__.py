"""mcgeom: relative motion, with metric scale, of calibrated multi-camera rigs.

Conventions (docs/architecture.md §3): rays and camera centres in the rig frame
(metres); a motion is rig2_from_rig1, ``X_rig2 = R @ X_rig1 + t`` as in
``cv2.recoverPose``; angles in radians.
"""

from __future__ import annotations

from . import registry
from .errors import (DegenerateError, InfeasibleError, McgeomError, NumericalError,
                     ScaleNotObservableWarning)
from .observability import with_calibration
from .types import RayPairs, RigMotion, ScaleVerdict
from . import estimators as _estimators  # noqa: F401  (registers the built-ins)
from . import robust
from .io import load_rig
from .cv import (RIG_5P1_DIRECT, RIG_5P1_RANSAC, RIG_LINEAR17, RIG_LINEAR17_RANSAC,
                 estimateRigMotion)

__version__ = "0.1.0"


def estimate(rays: RayPairs, method: str = "linear17", *, calibration_std=None,
             **options) -> RigMotion:
    """Estimate the rig motion from ray correspondences with a registered method.

    ``method`` is any name of :func:`mcgeom.registry.names`; ``options`` are the
    method's keyword options (see ``mcgeom methods``). ``calibration_std``: the
    rig's extrinsic calibration error (``rig.extrinsic_std``: (M, 2) metres and
    radians per camera id, or one pair); when given, ``scale.rel_std`` of every
    estimator includes it and the verdict is decided on that total
    (:func:`mcgeom.observability.with_calibration`); None = the rays are exact.
    """
    est = registry.get(method)
    if calibration_std is not None and "calibration_std" in est.options:
        return est(rays, calibration_std=calibration_std, **options)   # propagates it itself
    motion = est(rays, **options)
    if calibration_std is None:
        return motion
    return with_calibration(motion, rays, calibration_std,
                            float(options.get("max_scale_rel_std", 0.1)))


__all__ = [
    "RayPairs", "RigMotion", "ScaleVerdict", "estimate", "registry", "robust",
    "estimateRigMotion", "RIG_5P1_RANSAC", "RIG_5P1_DIRECT", "RIG_LINEAR17",
    "RIG_LINEAR17_RANSAC", "load_rig",
    "McgeomError", "NumericalError", "InfeasibleError", "DegenerateError",
    "ScaleNotObservableWarning", "__version__",
]
