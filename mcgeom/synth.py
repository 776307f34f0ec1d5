"""Seeded synthetic rigs, scenes, motions, noise and outliers.

Shared by the tests, the benchmarks and the demo, so that all of them speak about the
same rigs. Every random function takes ``rng``: a ``numpy.random.Generator``, an int
seed, or None (fresh entropy); the same seed always gives the same output.

Frames: rigs follow docs/architecture.md §3 (cam_from_rig extrinsics, metres). The rig
frame of the vehicle, Ladybug and stereo rigs is **x forward, y left, z up**; camera
frames are OpenCV's (x right, y down, z forward). A motion ``(R, t)`` is rig2_from_rig1:
``X_rig2 = R X_rig1 + t``.

Rigs (thesis figures in brackets):

* :func:`stereo_head` -- two cameras looking opposite ways, sideways [Fig. 8.4c];
* :func:`axial_rig` -- centres on a line, different viewing directions [Fig. 8.4b];
* :func:`generic_rig` -- random non-collinear centres and orientations [Fig. 8.4a];
* :func:`ladybug2` -- 5 ring cameras + 1 up, a Ladybug2-like head [ch. 8.5.2];
* :func:`vehicle8` -- 4 cameras on each side of a car [ch. 7.5.2, Fig. 7.10].
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional, Sequence, Union

import numpy as np

from mcgeom.metrics import rotation_error
from mcgeom.rig import Camera, Rig
from mcgeom.types import RayPairs

__all__ = [
    "RngLike", "as_rng", "look_at_camera",
    "stereo_head", "axial_rig", "ladybug2", "vehicle8", "generic_rig",
    "rotation_about", "random_rotation", "random_motion", "figure_eight_path",
    "relative_motion", "SyntheticProblem", "make_problem", "perturb_directions",
    "GRAVITY", "tilted",
]

RngLike = Union[np.random.Generator, int, None]

# In raw (require_visible=False) mode a camera "sees" any point within this angle of its
# optical axis: the whole front hemisphere in spirit, but bounded so that the virtual
# pixel of the ray stays finite (tan(85 deg) ~ 11.4 focal lengths from the centre).
RAW_HALF_ANGLE = np.deg2rad(85.0)
_MAX_BATCHES = 200  # bound on candidate batches per camera in make_problem



#: the rigs built here are known exactly (the synthetic data come from them):
#: no extrinsic calibration error (the default of an unstated calibration is
#: mcgeom.rig.DEFAULT_EXTRINSIC_STD)
_EXACT = (0.0, 0.0)

def as_rng(rng: RngLike) -> np.random.Generator:
    """A Generator from a Generator (returned as is), an int seed, or None."""
    if isinstance(rng, (bool, np.bool_)):
        raise ValueError(f"rng must be a numpy Generator, an int seed or None, got {rng!r}")
    if rng is None or isinstance(rng, (int, np.integer, np.random.Generator)):
        return np.random.default_rng(rng)
    raise ValueError(f"rng must be a numpy Generator, an int seed or None, got {type(rng).__name__}")


# --------------------------------------------------------------------------- rotations

def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def rotation_about(axis: Sequence[float], angle: float) -> np.ndarray:
    """3x3 rotation by ``angle`` (radians, right-handed) about ``axis`` (Rodrigues)."""
    a = np.asarray(axis, dtype=np.float64)
    n = np.linalg.norm(a)
    if not np.isfinite(n) or n == 0:
        raise ValueError(f"rotation axis must be a finite non-zero 3-vector, got {axis!r}")
    S = _skew(a / n)
    return np.eye(3) + np.sin(angle) * S + (1.0 - np.cos(angle)) * (S @ S)


#: the direction of gravity in the frame of the synthetic rigs (their z is up)
GRAVITY = np.array([0.0, 0.0, -1.0])


def tilted(g: np.ndarray, deg: float, rng: RngLike = None) -> np.ndarray:
    """``g`` (a 3-vector) turned by ``deg`` degrees about a random axis
    perpendicular to it: a vertical known to that error (an IMU's gravity)."""
    gen = as_rng(rng)
    return rotation_about(np.cross(g, gen.normal(size=3)), np.radians(deg)) @ g


def _random_unit(gen: np.random.Generator, n: Optional[int] = None) -> np.ndarray:
    """Uniform unit vector(s) on the sphere: (3,) or (n, 3)."""
    v = gen.standard_normal(3 if n is None else (n, 3))
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def random_rotation(rng: RngLike = None, max_angle: float = np.pi) -> np.ndarray:
    """Rotation about a uniform random axis by an angle uniform in [0, max_angle] (rad).

    Note: with ``max_angle = pi`` this is *not* the uniform (Haar) distribution on SO(3)
    (small angles are over-represented); it is the usual "random motion" of a benchmark.
    """
    gen = as_rng(rng)
    if not (np.isfinite(max_angle) and 0 <= max_angle <= np.pi):
        raise ValueError(f"max_angle must be in [0, pi] radians, got {max_angle!r}")
    axis = _random_unit(gen)
    return rotation_about(axis, gen.uniform(0.0, max_angle))


def _uniform_rotation(gen: np.random.Generator) -> np.ndarray:
    """Haar-uniform rotation (a random unit quaternion)."""
    q = gen.standard_normal(4)
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def random_motion(rng: RngLike = None, max_angle: float = 0.3,
                  t_norm: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """A random rig motion rig2_from_rig1 ``(R, t)``: ``X_rig2 = R X_rig1 + t``.

    ``R`` from :func:`random_rotation` (angle in [0, max_angle] radians), ``t`` a uniform
    random direction of length ``t_norm`` metres.
    """
    gen = as_rng(rng)
    R = random_rotation(gen, max_angle)
    return R, t_norm * _random_unit(gen)


def random_motion_between(rng: RngLike, min_angle: float, max_angle: float,
                          t_min: float, t_max: float) -> tuple[np.ndarray, np.ndarray]:
    """A random motion ``(R, t)`` with a rotation angle in [min_angle, max_angle]
    radians (drawn up to max_angle, redrawn below min_angle, so that the scale
    is observable) and ``|t|`` uniform in [t_min, t_max] metres (the set-up of
    thesis ch. 10.5.1)."""
    gen = as_rng(rng)
    R = random_rotation(gen, max_angle)
    while rotation_error(R, np.eye(3)) < min_angle:
        R = random_rotation(gen, max_angle)
    t = gen.normal(size=3)
    t *= gen.uniform(t_min, t_max) / np.linalg.norm(t)
    return R, t


# --------------------------------------------------------------------------- rigs

def look_at_camera(name: str, centre: Sequence[float], forward: Sequence[float],
                   up: Sequence[float] = (0.0, 0.0, 1.0), f: float = 600.0,
                   width: int = 1000, height: int = 1000,
                   dist: Sequence[float] = (), model: str = "pinhole") -> Camera:
    """A camera at ``centre`` (rig frame, metres) whose optical axis points along ``forward``.

    The image "up" is as close to ``up`` (rig frame) as possible, i.e. the OpenCV camera
    y axis (down) is ``-up`` projected orthogonally to ``forward``. Square pixels, no skew,
    principal point at the image centre, focal length ``f`` pixels.
    """
    z = np.asarray(forward, dtype=np.float64)
    z = z / np.linalg.norm(z)
    u = np.asarray(up, dtype=np.float64)
    y = -(u - (u @ z) * z)  # image down = -up, made orthogonal to the axis
    if np.linalg.norm(y) < 1e-9:
        raise ValueError(f"camera {name!r}: 'up' is parallel to the viewing direction")
    y = y / np.linalg.norm(y)
    x = np.cross(y, z)
    R = np.vstack([x, y, z])  # rows: camera axes in the rig frame -> cam_from_rig
    c = np.asarray(centre, dtype=np.float64)
    K = np.array([[f, 0.0, (width - 1) / 2.0], [0.0, f, (height - 1) / 2.0], [0.0, 0.0, 1.0]])
    return Camera(name=name, K=K, dist=np.asarray(dist, dtype=np.float64), model=model,  # type: ignore[arg-type]
                  R=R, t=-R @ c, width=width, height=height)


def _heading(yaw_deg: float, pitch_deg: float = 0.0) -> np.ndarray:
    """Unit direction in the rig frame (x fwd, y left, z up) from yaw/pitch in degrees."""
    yaw, pitch = np.deg2rad(yaw_deg), np.deg2rad(pitch_deg)
    return np.array([np.cos(pitch) * np.cos(yaw), np.cos(pitch) * np.sin(yaw), np.sin(pitch)])


def ring_rig(n_cameras: int, radius: float = 0.5, f: float = 800.0,
             name: str = "cam") -> Rig:
    """``n_cameras`` cameras on a horizontal ring of ``radius`` metres, looking
    outward at equal yaw steps (1024 x 768 px, focal ``f`` px); named
    ``name0``, ``name1``..."""
    cams = []
    for k in range(n_cameras):
        yaw = 2 * np.pi * k / n_cameras
        h = np.array([np.cos(yaw), np.sin(yaw), 0.0])
        cams.append(look_at_camera(f"{name}{k}", radius * h, h, f=f, width=1024, height=768))
    return Rig(tuple(cams), calibration_std=_EXACT)


def stereo_head(baseline: float = 0.5, f: float = 600.0) -> Rig:
    """Non-overlapping stereo head (thesis Fig. 8.4c): 2 cameras looking opposite ways.

    Rig frame x forward, y left, z up, origin midway between the centres; camera 0
    ("left") at ``y = +baseline/2`` looks left (+y), camera 1 ("right") at
    ``y = -baseline/2`` looks right (-y). 1000x1000 px, focal ``f`` px (80 deg field of
    view at the default), so the views do not overlap.
    """
    if not baseline > 0:
        raise ValueError(f"baseline must be positive (metres), got {baseline!r}")
    h = baseline / 2.0
    return Rig((look_at_camera("left", (0.0, h, 0.0), (0, 1, 0), f=f),
                look_at_camera("right", (0.0, -h, 0.0), (0, -1, 0), f=f)),
               calibration_std=_EXACT)


def axial_rig(n_cameras: int = 3, spacing: float = 0.3, f: float = 600.0) -> Rig:
    """Axial rig (thesis Fig. 8.4b): centres on the rig y axis, ``spacing`` metres apart.

    Camera k looks horizontally at yaw ``90 + 360 k / n`` degrees (rig frame x forward,
    y left, z up), so the cameras look in different directions; 1000x1000 px.
    """
    if n_cameras < 1:
        raise ValueError(f"n_cameras must be at least 1, got {n_cameras}")
    if not spacing > 0:
        raise ValueError(f"spacing must be positive (metres), got {spacing!r}")
    offset = spacing * (n_cameras - 1) / 2.0
    return Rig(tuple(
        look_at_camera(f"cam{k}", (0.0, k * spacing - offset, 0.0),
                       _heading(90.0 + 360.0 * k / n_cameras), f=f)
        for k in range(n_cameras)), calibration_std=_EXACT)


def ladybug2(radius: float = 0.04, f: float = 400.0) -> Rig:
    """A Ladybug2-like spherical head (thesis ch. 8.5.2, Fig. 8.11).

    Rig frame x forward, y left, z up, origin at the centre of the ring. Cameras 0..4
    ("ring0".."ring4") sit on a horizontal ring of ``radius`` metres and look outward at
    yaw 0, 72, ..., 288 degrees; camera 5 ("top") sits 0.06 m above the centre looking
    up (image top towards +x). 1024x768 px, focal ``f`` px (104 x 88 deg fields of view,
    so neighbouring ring cameras overlap a little).
    """
    cams = [look_at_camera(f"ring{k}", radius * _heading(72.0 * k), _heading(72.0 * k),
                           f=f, width=1024, height=768) for k in range(5)]
    cams.append(look_at_camera("top", (0.0, 0.0, 0.06), (0, 0, 1), up=(1, 0, 0),
                               f=f, width=1024, height=768))
    return Rig(tuple(cams), calibration_std=_EXACT)


def vehicle8(half_width: float = 0.95, f: float = 800.0) -> Rig:
    """The 8-camera vehicle rig of thesis ch. 7.5.2 (Fig. 7.10).

    Rig frame x forward, y left, z up, origin midway between the two camera clusters.
    Each side (y = +/- ``half_width``; the sides are ~1.9 m apart) carries 4 cameras on a
    short bar: backward, turned 30 deg outward (yaw +/-150 deg, at x = -0.25); sideways
    (yaw +/-90 deg, x = 0); forward, turned 30 deg outward (yaw +/-30 deg, x = +0.25);
    and up (pitched 75 deg up, leaning outward, 0.1 m higher). 1024x768 px, focal ``f`` px (65 deg horizontal field
    of view): neighbouring cameras overlap by a few degrees only.
    Ids 0..3 left (back, side, front, up), 4..7 right in the same order.
    """
    cams = []
    for side, sign in (("left", 1.0), ("right", -1.0)):
        y = sign * half_width
        specs = (("back", (-0.25, y, 0.0), _heading(sign * 150.0)),
                 ("side", (0.0, y, 0.0), _heading(sign * 90.0)),
                 ("front", (0.25, y, 0.0), _heading(sign * 30.0)),
                 ("up", (0.0, y, 0.1), _heading(sign * 90.0, 75.0)))
        for what, centre, forward in specs:
            cams.append(look_at_camera(f"{side}_{what}", centre, forward,
                                       f=f, width=1024, height=768))
    return Rig(tuple(cams), calibration_std=_EXACT)


def generic_rig(n_cameras: int = 4, rng: RngLike = None) -> Rig:
    """A random non-axial rig (thesis Fig. 8.4a): the "locally-central" generalized camera.

    Centres uniform in a 1 m cube around the origin, re-drawn until their RMS distance to
    the best-fitting line exceeds 5 cm (so for ``n_cameras >= 3`` the rig is truly
    non-axial; 1 camera is central and 2 are axial by nature); orientations uniform on SO(3); focal lengths
    uniform in 500..700 px; 1000x1000 px.
    """
    gen = as_rng(rng)
    if n_cameras < 1:
        raise ValueError(f"n_cameras must be at least 1, got {n_cameras}")
    while True:
        centres = gen.uniform(-0.5, 0.5, size=(n_cameras, 3))
        spread = np.linalg.svd(centres - centres.mean(axis=0), compute_uv=False)
        if n_cameras < 3 or spread[1] > 0.05 * np.sqrt(n_cameras):
            break
    cams = []
    for k in range(n_cameras):
        R = _uniform_rotation(gen)
        fk = gen.uniform(500.0, 700.0)
        K = np.array([[fk, 0.0, 499.5], [0.0, fk, 499.5], [0.0, 0.0, 1.0]])
        cams.append(Camera(f"cam{k}", K, np.zeros(0), "pinhole", R, -R @ centres[k], 1000, 1000))
    return Rig(tuple(cams), calibration_std=_EXACT)


# --------------------------------------------------------------------------- paths

def _lemniscate(s: np.ndarray, a: float) -> tuple[np.ndarray, np.ndarray]:
    """Bernoulli lemniscate points and tangents at parameters ``s`` (half-width ``a``)."""
    den = 1.0 + np.sin(s) ** 2
    x = a * np.cos(s) / den
    y = a * np.sin(s) * np.cos(s) / den
    # derivatives of x(s), y(s): heading of the rig
    dden = 2.0 * np.sin(s) * np.cos(s)
    dx = a * (-np.sin(s) * den - np.cos(s) * dden) / den**2
    dy = a * (np.cos(2 * s) * den - np.sin(s) * np.cos(s) * dden) / den**2
    return np.stack([x, y], axis=1), np.stack([dx, dy], axis=1)


def figure_eight_path(n_positions: int = 108, size: float = 2.5,
                      height: float = 0.0) -> list[np.ndarray]:
    """A closed figure-eight (Bernoulli lemniscate) path of rig poses (thesis Fig. 8.12).

    The thesis moved a Ladybug2 over 108 marked positions of an ∞-shaped path printed on
    an A2 sheet; this path is that shape scaled up: ``size`` metres end to end (default
    2.5 m, ~6.6 m long, so consecutive positions are ~6 cm apart, equally spaced by arc
    length). The path lies in the world plane z = ``height`` (world z up); the rig's x
    axis (forward) is tangent to the path and its z axis is world up, so the rig turns
    about its up axis between frames (and barely at the crossing, where the motion is
    nearly a pure translation: a critical motion for the scale). The last pose connects
    to the first with the same step.

    Returns:
        ``n_positions`` 4x4 world_from_rig poses (``X_world = T @ [X_rig, 1]``).
    """
    if n_positions < 2:
        raise ValueError(f"n_positions must be at least 2, got {n_positions}")
    if not size > 0:
        raise ValueError(f"size must be positive (metres), got {size!r}")
    a = size / 2.0
    # reparametrise by arc length so that every frame-to-frame baseline is the same
    dense = np.linspace(0.0, 2 * np.pi, 20001)
    _, d = _lemniscate(dense, a)
    speed = np.linalg.norm(d, axis=1)
    arc = np.concatenate([[0.0], np.cumsum(0.5 * (speed[1:] + speed[:-1]) * np.diff(dense))])
    s = np.interp(np.arange(n_positions) * arc[-1] / n_positions, arc, dense)
    xy, dxy = _lemniscate(s, a)
    poses = []
    for (x, y), (dx, dy) in zip(xy, dxy):
        T = np.eye(4)
        T[:3, :3] = rotation_about((0, 0, 1), np.arctan2(dy, dx))
        T[:3, 3] = (x, y, height)
        poses.append(T)
    return poses


def relative_motion(T_world_from_rig1: np.ndarray,
                    T_world_from_rig2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """rig2_from_rig1 ``(R, t)`` between two 4x4 world_from_rig poses."""
    T = np.linalg.inv(T_world_from_rig2) @ T_world_from_rig1
    return np.ascontiguousarray(T[:3, :3]), np.ascontiguousarray(T[:3, 3])


# --------------------------------------------------------------------------- problems

@dataclass(frozen=True, eq=False)
class SyntheticProblem:
    """A synthetic two-frame problem with its ground truth.

    Attributes:
        rig: the rig (same at both times).
        R, t: true motion rig2_from_rig1 (``X_rig2 = R X_rig1 + t``, metres).
        points: (N, 3) scene points in the rig1 frame, metres.
        cam1, cam2: (N,) camera ids observing point k at time 1 / time 2.
        pixels1, pixels2: (N, 2) observed pixels (with pixel noise; time 2 replaced by a
            random pixel for outliers). In raw mode they may lie outside the image.
        rays: :class:`RayPairs` from the observed pixels via ``rig.ray_pairs`` (plus the
            angular noise, which perturbs the ray directions only).
        inlier: (N,) bool, False for the outliers.
    """

    rig: Rig
    R: np.ndarray
    t: np.ndarray
    points: np.ndarray
    cam1: np.ndarray
    cam2: np.ndarray
    pixels1: np.ndarray
    pixels2: np.ndarray
    rays: RayPairs
    inlier: np.ndarray

    def __len__(self) -> int:
        return self.points.shape[0]

    @property
    def T(self) -> np.ndarray:
        """4x4 homogeneous true motion rig2_from_rig1."""
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = self.R, self.t
        return T


def _check_fraction(name: str, value: float) -> float:
    if not (np.isfinite(value) and 0.0 <= value <= 1.0):
        raise ValueError(f"{name} must be in [0, 1], got {value!r}")
    return float(value)


def _check_sigma(name: str, value: float) -> float:
    if not (np.isfinite(value) and value >= 0.0):
        raise ValueError(f"{name} must be a finite non-negative number, got {value!r}")
    return float(value)


def _random_pixels(gen: np.random.Generator, cam: Camera, n: int) -> np.ndarray:
    """Uniform pixels over the image area [-0.5, w - 0.5) x [-0.5, h - 0.5)."""
    return np.column_stack([gen.uniform(-0.5, cam.width - 0.5, n),
                            gen.uniform(-0.5, cam.height - 0.5, n)])


def _random_cone_dirs(gen: np.random.Generator, cam: Camera, n: int) -> np.ndarray:
    """Uniform rig-frame directions within RAW_HALF_ANGLE of the camera's optical axis."""
    cos_t = gen.uniform(np.cos(RAW_HALF_ANGLE), 1.0, n)  # uniform on the spherical cap
    phi = gen.uniform(0.0, 2 * np.pi, n)
    sin_t = np.sqrt(1.0 - cos_t**2)
    d_cam = np.column_stack([sin_t * np.cos(phi), sin_t * np.sin(phi), cos_t])
    return d_cam @ cam.R  # R^T d, row-wise


def _observe(cam: Camera, points: np.ndarray, raw: bool) -> tuple[np.ndarray, np.ndarray]:
    """Pixels of rig-frame ``points`` in ``cam`` and whether the camera sees them.

    Visible mode: OpenCV projection inside the image (Camera.project). Raw mode: within
    RAW_HALF_ANGLE of the axis, and the (virtual, possibly off-image) pixel maps back to
    the point's direction -- so rays computed from the pixel are the true rays.
    """
    pixels, visible = cam.project(points)
    if not raw:
        return pixels, visible
    X_cam = points @ cam.R.T + cam.t
    ok = X_cam[:, 2] > np.cos(RAW_HALF_ANGLE) * np.linalg.norm(X_cam, axis=1)
    ok[ok] = cam.round_trip_ok(pixels[ok], X_cam[ok])  # never raises
    return pixels, ok


def _candidates(gen: np.random.Generator, rig: Rig, i: int, n: int, R: np.ndarray,
                t: np.ndarray, depth_range: tuple[float, float], raw: bool):
    """``n`` random points seen by camera ``i`` at time 1 and who sees them at time 2.

    Returns (points_rig1, pixels1, ok1 (n,), pixels2 (M, n, 2), seen2 (M, n)).
    """
    cam = rig.cameras[i]
    if raw:
        dirs = _random_cone_dirs(gen, cam, n)
    else:
        dirs = cam.pixels_to_bearings(_random_pixels(gen, cam, n))
    depth = gen.uniform(depth_range[0], depth_range[1], n)  # distance from the centre
    points = cam.centre + depth[:, None] * dirs
    pixels1, ok1 = _observe(cam, points, raw)
    points2 = points @ R.T + t
    obs2 = [_observe(c, points2, raw) for c in rig.cameras]
    pixels2 = np.stack([p for p, _ in obs2])
    seen2 = np.stack([s for _, s in obs2])
    return points, pixels1, ok1, pixels2, seen2


def _quota(n: int, m: int) -> np.ndarray:
    """Split ``n`` items round robin over ``m`` cameras."""
    return np.array([n // m + (1 if k < n % m else 0) for k in range(m)])


class _Collector:
    """Accepted correspondences: point, camera ids and noise-free pixels."""

    def __init__(self) -> None:
        self.parts: list[tuple[np.ndarray, ...]] = []

    def add(self, points, cam1, cam2, px1, px2) -> None:
        self.parts.append((points, cam1, cam2, px1, px2))

    def arrays(self) -> tuple[np.ndarray, ...]:
        if not self.parts:
            return (np.zeros((0, 3)), np.zeros(0, np.int64), np.zeros(0, np.int64),
                    np.zeros((0, 2)), np.zeros((0, 2)))
        return tuple(np.concatenate(col) for col in zip(*self.parts))


def _sample_camera(gen, rig, i, n_intra, n_cross, R, t, depth_range, raw):
    """Correspondences whose time-1 camera is ``i``: ``n_intra`` seen again by ``i``,
    up to ``n_cross`` seen at time 2 by another camera. Returns (collector, n_cross_found,
    n_intra_found)."""
    got = _Collector()
    need_intra, need_cross = n_intra, n_cross
    batch = max(64, 2 * (n_intra + n_cross))
    for _ in range(_MAX_BATCHES):
        if need_intra == 0 and need_cross == 0:
            break
        P, px1, ok1, px2, seen2 = _candidates(gen, rig, i, batch, R, t, depth_range, raw)
        intra = np.flatnonzero(ok1 & seen2[i])[:need_intra]
        got.add(P[intra], np.full(intra.size, i), np.full(intra.size, i), px1[intra], px2[i, intra])
        need_intra -= intra.size
        others = seen2.copy()
        others[i] = False
        cross = np.flatnonzero(ok1 & others.any(axis=0) & ~np.isin(np.arange(batch), intra))
        cross = cross[:need_cross]
        # the time-2 camera is drawn among all the other cameras that see the point
        j = np.array([gen.choice(np.flatnonzero(others[:, k])) for k in cross], dtype=np.int64)
        got.add(P[cross], np.full(cross.size, i), j, px1[cross], px2[j, cross])
        need_cross -= cross.size
    return got, n_cross - need_cross, n_intra - need_intra


def perturb_directions(dirs: np.ndarray, sigma: float, rng: RngLike = None) -> np.ndarray:
    """Rotate each unit direction by a N(0, sigma) angle (radians) about a random axis
    perpendicular to it (the angular noise of thesis ch. 8.5.1). Returns unit vectors."""
    gen = as_rng(rng)
    d = dirs / np.linalg.norm(dirs, axis=1, keepdims=True)
    axis = np.cross(d, gen.standard_normal(d.shape))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    angle = gen.normal(0.0, sigma, d.shape[0])[:, None]
    # Rodrigues with axis ⟂ d: d' = cos(a) d + sin(a) (axis x d)
    out = np.cos(angle) * d + np.sin(angle) * np.cross(axis, d)
    return out / np.linalg.norm(out, axis=1, keepdims=True)


def make_problem(rig: Rig, R: np.ndarray, t: np.ndarray, n_points: int, rng: RngLike = None,
                 cross_fraction: float = 0.0, pixel_noise: float = 0.0,
                 angular_noise: float = 0.0, outlier_fraction: float = 0.0,
                 depth_range: tuple[float, float] = (2.0, 20.0),
                 require_visible: bool = True) -> SyntheticProblem:
    """A synthetic correspondence problem for ``rig`` moving by rig2_from_rig1 ``(R, t)``.

    Each point is drawn for a time-1 camera ``i`` (round robin over the cameras): a random
    pixel of ``i`` (raw mode: a random direction within 85 deg of its axis) at a random
    distance in ``depth_range`` metres from its centre. It is kept if, at time 2, it is
    seen by the same camera ``i`` (intra-camera) or -- for ``round(cross_fraction *
    n_points)`` of the points -- by another camera ``j`` (cross-camera, drawn among those
    that see it; these make the "most-general" generalized camera of thesis ch. 8.3).

    "Seen" means visible in the image (``require_visible=True``), or, in raw mode
    (``require_visible=False``, the raw generalized-camera rays of thesis ch. 8.5.1),
    within 85 deg of the camera's optical axis, with a virtual pixel that may lie off
    the image.

    Noise, in this order: Gaussian pixel noise of ``pixel_noise`` px on both pixels;
    ``outlier_fraction`` of the correspondences get their time-2 pixel replaced by a
    random pixel (raw mode: direction) of the same camera ``cam2``; rays come from the
    pixels via ``rig.ray_pairs`` (origins = camera centres); then each ray direction is
    rotated by a N(0, ``angular_noise``) angle (radians) about a random perpendicular
    axis. Correspondences are returned in random order.

    Raises:
        ValueError: bad arguments, or not enough correspondences found within a bounded
            number of attempts (the message says for which camera and what to change).
    """
    gen = as_rng(rng)
    Rm, tv = _check_motion(R, t)
    n_points = _check_count(n_points)
    cross_fraction = _check_fraction("cross_fraction", cross_fraction)
    outlier_fraction = _check_fraction("outlier_fraction", outlier_fraction)
    pixel_noise = _check_sigma("pixel_noise", pixel_noise)
    angular_noise = _check_sigma("angular_noise", angular_noise)
    depth_range = _check_depth_range(depth_range)
    m = len(rig.cameras)
    n_cross = int(round(cross_fraction * n_points))
    if n_cross and m < 2:
        raise ValueError("cross_fraction > 0 needs a rig with at least 2 cameras")
    raw = not require_visible

    pts, c1, c2, px1, px2 = _sample_all(gen, rig, n_points - n_cross, n_cross, Rm, tv,
                                        depth_range, raw)
    order = gen.permutation(n_points)
    pts, c1, c2, px1, px2 = pts[order], c1[order], c2[order], px1[order], px2[order]

    px1 = px1 + gen.normal(0.0, pixel_noise, px1.shape) if pixel_noise else px1
    px2 = px2 + gen.normal(0.0, pixel_noise, px2.shape) if pixel_noise else px2
    inlier = np.ones(n_points, dtype=bool)
    n_out = int(round(outlier_fraction * n_points))
    if n_out:
        out = gen.choice(n_points, n_out, replace=False)
        inlier[out] = False
        px2[out] = _outlier_pixels(gen, rig, c2[out], raw)

    rays = rig.ray_pairs(px1, px2, c1, c2)
    if angular_noise:
        rays = RayPairs(rays.origins1, perturb_directions(rays.dirs1, angular_noise, gen),
                        rays.origins2, perturb_directions(rays.dirs2, angular_noise, gen),
                        rays.cam1, rays.cam2)
    return SyntheticProblem(rig=rig, R=Rm, t=tv, points=pts, cam1=c1, cam2=c2,
                            pixels1=px1, pixels2=px2, rays=rays, inlier=inlier)


def _sample_all(gen, rig, n_intra, n_cross, R, t, depth_range, raw):
    """Intra-camera correspondences round robin over the cameras, then cross-camera ones
    (round robin too, falling back on the cameras that can produce them)."""
    m = len(rig.cameras)
    got = _Collector()
    for i, q in enumerate(_quota(n_intra, m)):
        part, _, found = _sample_camera(gen, rig, i, int(q), 0, R, t, depth_range, raw)
        if found < q:
            raise ValueError(_shortfall(rig, i, found, int(q), "intra-camera", raw))
        got.parts += part.parts
    need = n_cross
    active = list(range(m))
    while need > 0 and active:
        # Share what is missing among the cameras still able to deliver. A camera whose
        # points no other camera sees after the motion falls short and drops out; each
        # round either completes or drops one camera, so this terminates.
        still = []
        for i, q in zip(active, _quota(need, len(active))):
            if q == 0:
                still.append(i)
                continue
            part, found, _ = _sample_camera(gen, rig, i, 0, int(q), R, t, depth_range, raw)
            got.parts += part.parts
            need -= found
            if found == q:
                still.append(i)
        active = still
    if need > 0:
        raise ValueError(
            f"make_problem: found only {n_cross - need} of {n_cross} cross-camera "
            f"correspondences (points seen by one camera at time 1 and another at time 2) "
            f"after {_MAX_BATCHES} batches per camera; the views do not overlap enough after "
            f"this motion. Use a larger rotation or a lower cross_fraction"
            + ("" if raw else ", or require_visible=False"))
    return got.arrays()


def _shortfall(rig: Rig, i: int, found: int, wanted: int, kind: str, raw: bool) -> str:
    mode = "raw rays" if raw else "visible in the image"
    return (f"make_problem: camera {i} ({rig.cameras[i].name!r}) yielded only {found} of "
            f"{wanted} {kind} correspondences ({mode} at both times) after {_MAX_BATCHES} "
            f"batches of random points; the motion moves its view away. Use a smaller "
            f"motion or another depth_range" + ("" if raw else ", or require_visible=False"))


def _outlier_pixels(gen: np.random.Generator, rig: Rig, cams: np.ndarray, raw: bool) -> np.ndarray:
    """A random time-2 observation in each given camera (pixel, or raw-mode direction)."""
    out = np.empty((cams.size, 2))
    for j in np.unique(cams):
        sel = cams == j
        cam = rig.cameras[j]
        if raw:
            pts = cam.centre + _random_cone_dirs(gen, cam, int(sel.sum()))
            out[sel] = cam.project(pts)[0]
        else:
            out[sel] = _random_pixels(gen, cam, int(sel.sum()))
    return out


def _check_motion(R, t) -> tuple[np.ndarray, np.ndarray]:
    Rm = np.asarray(R, dtype=np.float64)
    tv = np.asarray(t, dtype=np.float64).reshape(-1)
    if Rm.shape != (3, 3) or not np.all(np.isfinite(Rm)):
        raise ValueError(f"R must be a finite 3x3 rotation, got shape {Rm.shape}")
    if np.max(np.abs(Rm.T @ Rm - np.eye(3))) > 1e-6 or np.linalg.det(Rm) <= 0:
        raise ValueError("R is not a rotation (R^T R != I or det(R) <= 0)")
    if tv.shape != (3,) or not np.all(np.isfinite(tv)):
        raise ValueError(f"t must be a finite 3-vector, got shape {np.shape(t)}")
    return np.ascontiguousarray(Rm), tv.copy()


def _check_count(n_points) -> int:
    if isinstance(n_points, (bool, np.bool_)) or not isinstance(n_points, (int, np.integer)):
        raise ValueError(f"n_points must be an integer, got {n_points!r}")
    if n_points < 1:
        raise ValueError(f"n_points must be at least 1, got {n_points}")
    return int(n_points)


def _check_depth_range(depth_range) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in depth_range)
    except (TypeError, ValueError):
        raise ValueError(f"depth_range must be a pair (near, far) in metres, got {depth_range!r}") from None
    if not (np.isfinite(lo) and np.isfinite(hi) and 0.0 < lo <= hi):
        raise ValueError(f"depth_range must satisfy 0 < near <= far (metres), got {depth_range!r}")
    return lo, hi
