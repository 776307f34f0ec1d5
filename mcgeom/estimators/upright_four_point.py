"""``upright_four_point``: generalized relative pose with a known vertical direction.

An IMU gives the vertical (gravity) direction in the rig frame at each time,
``gravity1`` and ``gravity2``; the same physical direction, so the motion
satisfies ``R gravity1 = gravity2`` (up to their lengths) and only the yaw
about the vertical, and ``t``, are unknown: four correspondences determine
them (Sweeney, Flynn, Turk, 3DV 2014; Lee, Fraundorfer, Pollefeys, CVPR 2014).

* :func:`minimal_solutions` -- the minimal solver (``csrc/upright4.c``: the
  yaw from a degree-8 polynomial in the tangent of its half-angle, derivation
  there), the hook :mod:`mcgeom.robust` drives with
  ``solver_options={"gravity1": g1, "gravity2": g2}``;
* :func:`upright_four_point` -- the estimator on all correspondences: the yaw
  minimising the smallest eigenvalue of the 4 x 4 matrix of the linear
  constraints on ``(t, 1)`` (eq. U1 of ``csrc/upright4.c``, a one-dimensional
  version of Kneip and Li's eigensolver; its three lowest local minima, since
  that algebraic cost can rank a wrong one first under noise), then the joint
  refinement of all six
  degrees of freedom (so that an error of the IMU's vertical does not bias
  the result) and the scale verdict.

In the C robust search (``mcgeom.cv.estimate`` with ``gravity1``/``gravity2``,
:func:`mcgeom.robust.ransac` with this method) the samples are 3+1 wherever
some camera has 3 intra-camera correspondences: the central upright 3-point
solver (``mcg_upright3_central`` in ``csrc/upright4.c``; Fraundorfer,
Tanskanen, Pollefeys, ECCV 2010) gives that camera's rotation and direction
of travel, the metric scale comes from the other cameras' correspondences as
in 5+1, and the adaptive stop counts 3-samples; elsewhere 4-samples of this
solver.

Frames and units (docs/architecture.md §3): rays in the rig frame (metres),
gravity vectors in the rig frames at times 1 and 2 (any non-zero length),
``X2 = R X1 + t`` with ``t`` in metres.
"""

from __future__ import annotations

from typing import Any, Optional

import numpy as np

from .. import _core
from ..errors import DegenerateError
from ..geometry import rcross, unit_rows
from ..registry import register
from ..types import RayPairs, RigMotion
from ._finish import refine_and_report
from .essential import bearings_planar

__all__ = ["upright_four_point", "minimal_solutions", "check_gravity", "upright_rotation",
           "GRAVITY_STD", "vertical_misfit", "vertical_contradiction"]

#: default error of each given vertical (radians, one std of its tilt about
#: each horizontal axis): an IMU's gravity at rest is good to 0.1-0.3 deg, a
#: moving vehicle's accelerations tilt it further
GRAVITY_STD = float(np.radians(0.5))

#: 99th percentile of chi-square with 2 degrees of freedom (-2 ln 0.01)
_CHI2_2_99 = 9.21


def check_gravity(name: str, g: Any) -> np.ndarray:
    """``g`` as a unit (3,) float64 vector; ValueError naming ``name`` when it is
    missing, of the wrong shape, not finite or of zero length."""
    if g is None:
        raise ValueError(f"{name} is required: the vertical (gravity) direction in the rig "
                         "frame, a 3-vector")
    try:
        v = np.asarray(g, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a 3-vector of numbers, got {g!r}") from None
    if v.shape != (3,):
        raise ValueError(f"{name} must be a 3-vector, got shape {v.shape}")
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{name} contains NaN or inf")
    n = float(np.linalg.norm(v))
    if not n > 1e-50:
        raise ValueError(f"{name} has zero length")
    return v / n


def upright_rotation(g: np.ndarray) -> np.ndarray:
    """A rotation ``Q`` with ``Q g = e_z`` for the unit ``g`` (rows: ``a``,
    ``g x a``, ``g`` with ``a`` completing an orthonormal basis)."""
    k = int(np.argmin(np.abs(g)))
    a = np.zeros(3)
    a[k] = 1.0
    a -= (a @ g) * g
    a /= np.linalg.norm(a)
    return np.array([a, np.cross(g, a), g])


def minimal_solutions(sample: RayPairs, *, gravity1: Any = None,
                      gravity2: Any = None) -> list[tuple[np.ndarray, np.ndarray]]:
    """Every motion of 4 correspondences with ``R gravity1 = gravity2`` (up to 8).

    ``sample``: exactly 4 correspondences (rig frames, metres); ``gravity1``,
    ``gravity2``: the vertical in rig frame 1 and 2. Degenerate samples (rays
    from one centre, no yaw determined) give ``[]``.
    """
    if len(sample) != 4:
        raise ValueError(f"upright_four_point: a minimal sample has 4 correspondences, "
                         f"got {len(sample)}")
    g1, g2 = check_gravity("gravity1", gravity1), check_gravity("gravity2", gravity2)
    try:
        return _core.upright4(sample.origins1, sample.dirs1, sample.origins2, sample.dirs2,
                              g1, g2)
    except DegenerateError:
        return []


# ------------------------------------------------------- all correspondences

def _yaw_system(rays: RayPairs, Q1: np.ndarray, Q2: np.ndarray, c: np.ndarray, s: float
                ) -> np.ndarray:
    """The 3 x 3 blocks (4 x 4 each) of ``S(yaw) = sum_k v_k v_k^T``, with the
    row of eq. U1 ``v_k = cos(yaw) A_k + sin(yaw) B_k + C_k`` in the upright
    frames (origins centred on ``c`` and divided by ``s``): returns G (3, 3, 4, 4)
    with ``S = sum_ij w_i w_j G[i, j]``, ``w = (cos, sin, 1)``."""
    d1 = unit_rows(rays.dirs1) @ Q1.T
    d2 = unit_rows(rays.dirs2) @ Q2.T
    m1 = rcross(((rays.origins1 - c) / s) @ Q1.T, d1)
    m2 = rcross(((rays.origins2 - c) / s) @ Q2.T, d2)
    # Rz(yaw) = cos Pc + sin Pe + Pz: Pc = diag(1, 1, 0), Pe = [e_z]x, Pz = diag(0, 0, 1)
    pc = np.diag([1.0, 1.0, 0.0])
    pe = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    pz = np.diag([0.0, 0.0, 1.0])
    basis = []
    for P in (pc, pe, pz):
        pd1, pm1 = d1 @ P.T, m1 @ P.T
        v = np.empty((len(rays), 4))
        v[:, :3] = rcross(pd1, d2)
        v[:, 3] = np.einsum("ij,ij->i", d2, pm1) + np.einsum("ij,ij->i", m2, pd1)
        basis.append(v)
    V = np.stack(basis)                      # (3, N, 4)
    return np.einsum("ink,jnl->ijkl", V, V)


def _smallest_eig(G: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    w = np.stack([np.cos(yaw), np.sin(yaw), np.ones_like(yaw)], axis=-1)
    S = np.einsum("ai,aj,ijkl->akl", w, w, G)
    return np.linalg.eigvalsh(S)[:, 0]


def _low_yaws(G: np.ndarray) -> list[float]:
    """The (up to) three lowest local minima of the smallest eigenvalue of
    S(yaw), lowest first: a grid of 1 degree, then golden-section search
    around each."""
    grid = np.linspace(-np.pi, np.pi, 360, endpoint=False)
    f = _smallest_eig(G, grid)
    is_min = (f <= np.roll(f, 1)) & (f <= np.roll(f, -1))
    cands = np.flatnonzero(is_min)
    cands = cands[np.argsort(f[cands], kind="stable")][:3]
    step = grid[1] - grid[0]
    found = []
    ratio = (np.sqrt(5.0) - 1.0) / 2.0
    for k in cands:
        lo, hi = grid[k] - step, grid[k] + step
        x1, x2 = hi - ratio * (hi - lo), lo + ratio * (hi - lo)
        f1, f2 = _smallest_eig(G, np.array([x1, x2]))
        for _ in range(60):          # (0.618)^60 * 2 deg ~ 1e-14 rad
            if f1 <= f2:
                hi, x2, f2 = x2, x1, f1
                x1 = hi - ratio * (hi - lo)
                f1 = _smallest_eig(G, np.array([x1]))[0]
            else:
                lo, x1, f1 = x1, x2, f2
                x2 = lo + ratio * (hi - lo)
                f2 = _smallest_eig(G, np.array([x2]))[0]
        x = 0.5 * (lo + hi)
        found.append((float(_smallest_eig(G, np.array([x]))[0]), float(x)))
    return [x for _, x in sorted(found)]


def _translation(S: np.ndarray) -> tuple[np.ndarray, bool]:
    """``t_u`` from the eigenvector of the smallest eigenvalue of S (``(t_u, 1)``
    up to scale). When the null space is two-dimensional and holds (0, 0, 0, 1)
    -- no rotation and intra-camera rays only, the critical motion of thesis
    ch. 7.3.2 -- the unit direction orthogonal to it (False: no scale). A 3 x 3
    ``S`` (central rays, no moments) gives the unit direction alone."""
    w, V = np.linalg.eigh(S)
    v = V[:, 0]
    if len(S) == 3:                 # central rays: the direction only
        return v, False
    if w[1] <= 1e-10 * max(w[3], 1e-300):
        N = V[:, :2]
        # the combination with no homogeneous part: |t| is free
        u = N @ np.array([N[3, 1], -N[3, 0]])
        if np.linalg.norm(u[:3]) > 0.5:
            return u[:3] / np.linalg.norm(u[:3]), False
    if not abs(v[3]) > 1e-12:
        return v[:3] / np.linalg.norm(v[:3]), False
    return v[:3] / v[3], True


def _sample_solutions(rays: RayPairs, g1: np.ndarray, g2: np.ndarray,
                      samples: int = 6) -> list[tuple[np.ndarray, np.ndarray]]:
    """Minimal solutions of ``samples`` 4-samples spread over the correspondences.

    The correspondences are put in a canonical order (lexicographic in their
    coordinates), so that the samples, hence the result, do not depend on the
    order the caller gave them in; sample j takes the rows j, j + n/4, j + n/2,
    j + 3n/4 of that order.
    """
    n = len(rays)
    order = np.lexsort(np.concatenate([rays.origins1, rays.dirs1, rays.origins2, rays.dirs2],
                                      axis=1).T[::-1])
    out: list = []
    for j in range(min(samples, max(n // 4, 1))):
        idx = order[(j + (n * np.arange(4)) // 4) % n]
        if len(set(idx.tolist())) == 4:
            out += minimal_solutions(rays.take(idx), gravity1=g1, gravity2=g2)
    return out


@register(
    "upright_four_point",
    min_sample=4,
    camera_kinds=("most-general", "locally-central", "axial", "locally-central-and-axial"),
    family="minimal",
    needs_rotation=False,
    recovers_scale=True,
    description="generalized relative pose with a known vertical (IMU gravity): yaw and metric "
                "t from 4 correspondences (Sweeney et al. 2014, Lee et al. 2014), joint "
                "refinement",
    options={"gravity1": "vertical (gravity) direction in the rig frame at time 1, required",
             "gravity2": "vertical (gravity) direction in the rig frame at time 2, required",
             "gravity_std": "error of each vertical, radians (one std per horizontal axis; "
                            "0.5 deg): a refined rotation that turns gravity1 further from "
                            "gravity2 than this allows is not reported with a metric scale",
             "max_scale_rel_std": "relative std of |t| above which the scale is reported "
                                  "unobservable (0.1)"},
    minimal_solver=minimal_solutions,
)
def upright_four_point(rays: RayPairs, *, gravity1: Any = None, gravity2: Any = None,
                       max_scale_rel_std: float = 0.1,
                       gravity_std: float = GRAVITY_STD) -> RigMotion:
    """Rig motion rig2_from_rig1 (R, t in metres) from >= 4 correspondences and the vertical.

    ``rays`` in the rig frame (origins at the camera centres, metres);
    ``gravity1``/``gravity2``: the vertical direction (e.g. an IMU's gravity) in
    the rig frame at time 1 / time 2 (3-vectors, any non-zero length). The yaw
    about the vertical minimises the smallest eigenvalue of the linear
    constraints on ``(t, 1)`` (eq. U1 of ``csrc/upright4.c``) over all
    correspondences; ``t`` is its eigenvector; from each of the three lowest
    local minima all six degrees of freedom are refined jointly (Sampson
    angular error) and the least cost wins, so the vertical only guides the
    start. ``gravity_std``: the error of each vertical (radians, one std of
    its tilt per horizontal axis, default :data:`GRAVITY_STD`, 0.5 deg); a
    refined rotation that contradicts the verticals beyond it
    (:func:`vertical_contradiction`) gets no metric scale.
    ``info["gravity_misfit"]``: the angle (radians) between
    ``R gravity1`` and ``gravity2`` after the refinement. Raises ValueError
    for bad input or a missing/invalid gravity. Rays from one centre (a
    central camera) give the yaw and the unit direction of that centre's
    travel, the scale reported unobservable.
    """
    if not isinstance(rays, RayPairs):
        raise TypeError(f"rays must be a RayPairs, got {type(rays).__name__}")
    g1, g2 = check_gravity("gravity1", gravity1), check_gravity("gravity2", gravity2)
    if len(rays) < 4:
        raise ValueError(f"too few correspondences: upright_four_point needs at least 4, "
                         f"got {len(rays)}")
    if not (np.isfinite(max_scale_rel_std) and max_scale_rel_std > 0):
        raise ValueError(f"max_scale_rel_std must be a positive number, got {max_scale_rel_std}")
    if isinstance(gravity_std, bool) or not (
            isinstance(gravity_std, (int, float, np.floating)) and np.isfinite(gravity_std)
            and gravity_std > 0):
        raise ValueError(f"gravity_std must be a positive number of radians, got {gravity_std!r}")
    rays.check_finite()
    Q1, Q2 = upright_rotation(g1), upright_rotation(g2)
    allo = np.concatenate([rays.origins1, rays.origins2])
    c = allo.mean(axis=0)
    # centred and scaled by the RMS distance (invariant to the rig frame, unlike
    # a maximum over coordinates): the algebraic start then is too
    s = float(np.sqrt(np.mean(np.sum((allo - c) ** 2, axis=1))))
    # every ray from one centre (one camera, or cameras sharing their centre):
    # the moments vanish about it, (U1) reads t . (R d1 x d2) = 0 -- the
    # essential matrix of that centre: the yaw and the direction of its travel,
    # no scale (the verdict says so)
    central = not s > 1e-12 * (1.0 + np.abs(c).max())
    G = _yaw_system(rays, Q1, Q2, c, 1.0 if central else s)
    if central:
        if bearings_planar(rays.dirs1, rays.dirs2, 1e-9):
            # points on a line: the bearings of each time span a plane, and
            # several yaws map one plane onto the other (seen: the truth and
            # one 179 deg away fit equally)
            raise DegenerateError("upright_four_point: the motion is not determined: every "
                                  "ray starts at one centre and the bearings lie in one plane "
                                  "through it (scene points on a line)")
        G, s = G[:, :, :3, :3], 1.0
    cands = []
    for yaw in _low_yaws(G):
        w = np.array([np.cos(yaw), np.sin(yaw), 1.0])
        tu, _ = _translation(np.einsum("i,j,ijkl->kl", w, w, G))
        Rz = np.array([[w[0], -w[1], 0.0], [w[1], w[0], 0.0], [0.0, 0.0, 1.0]])
        R = Q2.T @ Rz @ Q1
        # t = s t_u + c - R c (origins centred on c and divided by s); without
        # scale t_u is a unit direction and the length a guess the verdict flags
        cands.append((R, s * (Q2.T @ tu) + c - R @ c))
    # The algebraic cost has a wide valley near "no translation" (t ~ 0: every
    # row small) in which the true yaw can be a narrow notch that a grid
    # misses (seen on 4-camera rigs with 1 m of travel). The minimal solver on
    # a few samples spread over the correspondences proposes yaws near the
    # truth; every candidate is ranked by the Sampson cost, the two best refined.
    cands += _sample_solutions(rays, g1, g2)
    cost = [float(np.sum(_core.gec_residuals(rays.origins1, rays.dirs1, rays.origins2,
                                             rays.dirs2, R, t) ** 2)) for R, t in cands]
    starts = [cands[k] for k in np.argsort(cost, kind="stable")[:2]]
    info: dict = {"candidates": len(cands)}
    m = refine_and_report(rays, starts, "upright_four_point", max_scale_rel_std, info,
                          prior_check=lambda R: vertical_contradiction(R, g1, g2, gravity_std))
    m.info["gravity_misfit"] = vertical_misfit(m.R, g1, g2)
    return m


def vertical_misfit(R: np.ndarray, g1: np.ndarray, g2: np.ndarray) -> float:
    """The angle (radians) between ``R g1`` and ``g2``: how far the rotation
    ``R`` (rig2_from_rig1) turns the vertical of frame 1 from that of frame 2
    (unit ``g1``, ``g2``)."""
    Rg = R @ g1
    return float(np.arctan2(np.linalg.norm(np.cross(Rg, g2)), Rg @ g2))


def vertical_contradiction(R: np.ndarray, g1: np.ndarray, g2: np.ndarray,
                           gravity_std: float) -> Optional[str]:
    """Why the rotation ``R`` (rig2_from_rig1) contradicts the given verticals
    ``g1``, ``g2`` (unit, rig frames 1 and 2), each with a tilt error of
    ``gravity_std`` radians per horizontal axis; None when it does not.

    ``R g1`` and ``g2`` differ by the two verticals' errors (and the far
    smaller error of ``R``): their angle ``a`` has ``a^2 / (2 gravity_std^2)``
    ~ chi-square with 2 degrees of freedom, so beyond its 99th percentile the
    refinement left the vertical it was given. That happens when it ends in a
    wrong basin: a ring with 1 % random time-2 bearings (``tests/
    test_gross_outliers.py``) gave one estimate of 20 with the rotation
    5.7 deg and |t| 96 % off at a reported std of 3 %, which neither its
    profile nor the robust refit of :mod:`._outliers` saw, and ``R g1`` 5.0
    deg from ``g2`` (correct estimates there: 0.05 deg with exact verticals,
    at most 1.0 deg with each tilted by 0.5 deg). The rig motion then
    rests on something the data and the vertical do not both say, and its
    scale is not called metric."""
    a = vertical_misfit(R, g1, g2)
    limit = gravity_std * np.sqrt(2.0 * _CHI2_2_99)
    if not a > limit:
        return None
    return (f"the rotation contradicts the given vertical: it turns gravity1 "
            f"{np.degrees(a):.3g} deg away from gravity2, beyond the {np.degrees(limit):.3g} "
            f"deg that their errors allow at 99 % (gravity_std {np.degrees(gravity_std):.3g} "
            f"deg each) -- a fit in a wrong basin (upright_four_point takes every "
            f"correspondence as an inlier, gross outliers included: use mcgeom.robust.ransac) "
            f"or a wrong vertical; scale not reported as metric")
