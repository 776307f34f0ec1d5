"""Shared by the atheris harnesses of fuzz/python: the allowed outcomes and
the checks of a returned motion.

A harness calls the API on decoded input; it may return a result or raise one
of the library's documented exceptions (``ValueError``, including
``mcgeom.DegenerateError``, and ``mcgeom.McgeomError`` subclasses) with a
non-empty message. Any other exception, an empty message, a crash, a hang,
or a result that breaks its invariants (non-finite or non-rotation R, ...)
is a finding: it propagates out of the harness, and atheris reports it and
keeps the input.

Imported, it also stops atheris from tracing comparisons that involve a numpy
array (see _untraced_array_compares).
"""
from __future__ import annotations

import operator

import atheris
import numpy as np

import mcgeom

try:  # how COMPARE_OP's argument encodes the operator (shifted from Python 3.12)
    from atheris.version_dependent import CMP_OP_SHIFT_AMOUNT
except ImportError:  # pragma: no cover - an atheris without the module
    CMP_OP_SHIFT_AMOUNT = 0

#: the comparisons in the order of dis.cmp_op
_COMPARE = (operator.lt, operator.le, operator.eq, operator.ne, operator.gt, operator.ge)
_native_trace_cmp = atheris._trace_cmp


def _untraced_array_compares(obj1, obj2, op: int, counter: int, is_const: bool):
    """atheris._trace_cmp, except where an operand is a numpy array.

    The instrumented code calls ``atheris._trace_cmp`` for every comparison.
    atheris 3.0.0 keeps a reference to each result that is not a bool: about
    1 KB per comparison of a 1000-element array. A 1200 s run of
    fuzz_estimate grew by ~400 KB per input and hit libFuzzer's 2 GB limit
    after 4,767 inputs, an "oom" that no single input reproduces (session 27;
    the same inputs replayed without instrumentation stay at 63 MB). An array
    comparison gives libFuzzer's value tracing nothing to use, so it is made
    here directly."""
    if isinstance(obj1, np.ndarray) or isinstance(obj2, np.ndarray):
        return _COMPARE[op >> CMP_OP_SHIFT_AMOUNT](obj1, obj2)
    return _native_trace_cmp(obj1, obj2, op, counter, is_const)


# the instrumented bytecode looks the hook up on the atheris module at each call
atheris._trace_cmp = _untraced_array_compares


class Finding(AssertionError):
    """A violated invariant (not an exception the library raised)."""


ALLOWED = (ValueError, mcgeom.McgeomError)


def allowed(exc: BaseException) -> bool:
    """True if exc is a documented outcome: an allowed type with a message."""
    if not isinstance(exc, ALLOWED):
        return False
    if not str(exc).strip():
        raise Finding(f"{type(exc).__name__} without a message") from exc
    return True


def check_rotation(R, what: str) -> None:
    R = np.asarray(R, dtype=float)
    if R.shape != (3, 3) or not np.all(np.isfinite(R)):
        raise Finding(f"{what}: R is not a finite 3x3 matrix: {R!r}")
    err = np.abs(R @ R.T - np.eye(3)).max()
    if err > 1e-6 or np.linalg.det(R) < 0.5:
        raise Finding(f"{what}: R is not a rotation (|R R^T - I| = {err:.3g})")


def check_motion(m, what: str) -> None:
    """A RigMotion: rotation R, finite t, a verdict, a finite or nan rms."""
    check_rotation(m.R, what)
    t = np.asarray(m.t, dtype=float).reshape(-1)
    if t.shape != (3,) or not np.all(np.isfinite(t)):
        raise Finding(f"{what}: t is not 3 finite values: {m.t!r}")
    if m.scale is None or not isinstance(m.scale.observable, (bool, np.bool_)):
        raise Finding(f"{what}: no scale verdict")
    if m.scale.observable and not np.isfinite(np.linalg.norm(t)):
        raise Finding(f"{what}: observable scale with |t| not finite")


def floats(fdp, n: int, special: bool = True) -> np.ndarray:
    """n doubles: mostly moderate, sometimes NaN, inf, huge, tiny, denormal."""
    out = np.empty(n)
    table = [0.0, -0.0, np.nan, np.inf, -np.inf, 1e308, -1e308, 1e-320, 1e150, 1e-300, 1.0]
    for i in range(n):
        sel = fdp.ConsumeIntInRange(0, 31) if special else 0
        if sel == 31:
            out[i] = fdp.ConsumeRegularFloat()
        elif sel == 30:
            out[i] = table[fdp.ConsumeIntInRange(0, len(table) - 1)]
        else:
            out[i] = fdp.ConsumeFloatInRange(-1.0, 1.0)
    return out


def cross_fraction(fdp, rig) -> float:
    """Mostly none or few cross-camera matches (many make make_problem fail)."""
    if len(rig.cameras) < 2 or fdp.ConsumeBool():
        return 0.0
    return fdp.ConsumeFloatInRange(0.0, 0.3)
