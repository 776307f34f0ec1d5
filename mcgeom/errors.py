"""Exceptions raised by mcgeom.

Bad input is always a ``ValueError`` (or a subclass) whose message names what is
wrong; numerical trouble and degenerate data have their own classes so that a
caller can tell "you passed garbage" from "this geometry cannot be solved".
"""

from __future__ import annotations

__all__ = ["McgeomError", "NumericalError", "InfeasibleError", "DegenerateError",
           "ScaleNotObservableWarning"]


class McgeomError(Exception):
    """Base class of every error mcgeom raises on purpose."""


class NumericalError(McgeomError, ArithmeticError):
    """A kernel failed numerically (no convergence, singular system)."""


class InfeasibleError(McgeomError):
    """An optimisation problem has no feasible point."""


class DegenerateError(McgeomError, ValueError):
    """The data or the motion is degenerate for the chosen method.

    Examples: too few independent correspondences for the detected generalized
    camera case, or a motion without translation for which the generalized
    essential matrix E = [t]x R vanishes.
    """


class ScaleNotObservableWarning(UserWarning):
    """The metric scale of the returned translation is not trustworthy.

    Emitted by the OpenCV-style :func:`mcgeom.estimateRigMotion`, whose
    ``(retval, R, t, mask)`` carries no verdict: either the data do not
    determine the scale at all (exactly critical motion, one camera: ``t`` has
    unit norm, only its direction is meaningful) or they determine it too
    loosely (``t`` is the maximum-likelihood metric estimate but its relative
    standard deviation exceeds the limit). The message says which;
    :func:`mcgeom.cv.estimate` returns the full verdict instead.
    """
