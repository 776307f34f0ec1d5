"""The textured world of the rendered demo: planar façades and a ground plane.

A :class:`Scene` is a set of textured rectangles (:class:`Plane`), each with its
own 8-bit grayscale texture, a texel size in metres and a mip pyramid for the
renderer (:mod:`mcgeom.experiments.render`). :func:`courtyard` builds the
default world: a ring road around a central block inside a walled courtyard,
the ground and every wall covered with a seeded procedural texture made for
feature detectors (multi-octave value noise for blobs at every scale, random
rectangles and windows for corners, random discs and ellipses), without the
periodic patterns that confuse matching. :func:`loop_path` is the closed path
of the car around the block.

Frames and units:

* World frame: metres, z up. A rig pose is **world_from_rig**, a 4x4 matrix
  with ``X_world = T @ [X_rig, 1]``.
* Rig frame of the car (as :func:`mcgeom.synth.vehicle8`): x forward, y left,
  z up, the origin at the height of the cameras; the ground is the plane
  ``z = -height`` of the world.
* :func:`courtyard` and :func:`loop_path` share one world frame, chosen so that
  the start of the loop (arc length 0, the middle of the first straight) is the
  world origin with the car heading along +x: the first pose is the identity.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Sequence

import cv2
import numpy as np

from mcgeom.validation import check_int, check_vector3

__all__ = ["Plane", "Scene", "CourtyardLayout", "courtyard", "loop_path", "procedural_texture",
           "check_n_frames", "layout_or_default"]

# below this size (texels) a mip level carries no useful detail
_MIN_MIP_SIZE = 4


def _finite_positive(what: str, value: Any) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{what} must be a number, got {value!r}") from None
    if not (math.isfinite(x) and x > 0):
        raise ValueError(f"{what} must be positive and finite, got {value!r}")
    return x


@dataclass(frozen=True, eq=False)
class Plane:
    """A textured rectangle of the world.

    Texel ``(row i, column j)`` of ``texture`` covers the square of side
    ``texel`` metres whose centre is ``origin + (j + 0.5) texel u + (i + 0.5)
    texel v`` (world frame). The rectangle spans ``width_m = W texel`` along
    ``u`` and ``height_m = H texel`` along ``v``; its normal is ``u x v``.

    Attributes:
        name: for messages.
        origin: (3,) corner of the rectangle in the world frame, metres.
        u, v: (3,) orthonormal directions of the texture's columns and rows.
        texture: (H, W) uint8 grayscale texture.
        texel: side of a texel, metres.
        gain: brightness factor of the plane (a fixed Lambertian shading, so
            that walls facing different ways differ), in (0, 1].
        mips: the mip pyramid (level 0 = ``texture``, each level a
            ``cv2.pyrDown`` of the previous), float32; computed here.
    """

    name: str
    origin: np.ndarray
    u: np.ndarray
    v: np.ndarray
    texture: np.ndarray
    texel: float
    gain: float = 1.0
    mips: tuple[np.ndarray, ...] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        who = f"plane {self.name!r}"
        set_ = lambda k, x: object.__setattr__(self, k, x)  # noqa: E731
        set_("origin", check_vector3(f"{who}: origin", self.origin))
        u = check_vector3(f"{who}: u", self.u)
        v = check_vector3(f"{who}: v", self.v)
        if abs(np.linalg.norm(u) - 1) > 1e-9 or abs(np.linalg.norm(v) - 1) > 1e-9 \
                or abs(u @ v) > 1e-9:
            raise ValueError(f"{who}: u and v must be orthonormal, got u={u}, v={v}")
        set_("u", u)
        set_("v", v)
        tex = np.asarray(self.texture)
        if tex.ndim != 2 or tex.dtype != np.uint8 or min(tex.shape) < 1:
            raise ValueError(f"{who}: texture must be a non-empty 2-D uint8 array, "
                             f"got {tex.dtype} of shape {tex.shape}")
        set_("texture", tex)
        set_("texel", _finite_positive(f"{who}: texel", self.texel))
        gain = float(self.gain)
        if not 0 < gain <= 1:
            raise ValueError(f"{who}: gain must be in (0, 1], got {self.gain!r}")
        set_("gain", gain)
        levels = [tex.astype(np.float32)]
        while min(levels[-1].shape) >= 2 * _MIN_MIP_SIZE:
            levels.append(cv2.pyrDown(levels[-1]))
        set_("mips", tuple(levels))

    @property
    def normal(self) -> np.ndarray:
        """(3,) unit normal ``u x v`` (world frame)."""
        return np.cross(self.u, self.v)

    @property
    def size(self) -> tuple[float, float]:
        """``(width_m, height_m)``: extent along ``u`` and ``v``, metres."""
        return self.texture.shape[1] * self.texel, self.texture.shape[0] * self.texel

    def point(self, column: float, row: float) -> np.ndarray:
        """World point (metres) of texture coordinates ``(column, row)``, in
        OpenCV's convention (the centre of texel (0, 0) is (0, 0))."""
        return self.origin + self.texel * ((column + 0.5) * self.u + (row + 0.5) * self.v)


@dataclass(frozen=True)
class Scene:
    """The planes of a world, and the brightness of the (featureless) sky.

    ``sky``: gray level of a horizontal ray that hits nothing; it brightens
    smoothly upwards (a gradient, so that the sky has no features).
    """

    planes: tuple[Plane, ...]
    sky: int = 170

    def __post_init__(self) -> None:
        planes = self.planes
        if isinstance(planes, Plane) or not isinstance(planes, Sequence) or not planes:
            raise ValueError("a scene needs a non-empty sequence of Plane")
        for i, p in enumerate(planes):
            if not isinstance(p, Plane):
                raise ValueError(f"planes[{i}] is a {type(p).__name__}, not a Plane")
        object.__setattr__(self, "planes", tuple(planes))
        sky = check_int("sky", self.sky)
        if not 0 <= sky <= 255:
            raise ValueError(f"sky must be a gray level in 0..255, got {sky}")


# --------------------------------------------------------------------------- textures

def _value_noise(gen: np.random.Generator, shape: tuple[int, int], cells: float) -> np.ndarray:
    """Smooth noise in [0, 1] with about ``cells`` texels per random value: a grid of
    uniform values upsampled by bicubic interpolation (value noise)."""
    h, w = shape
    gh, gw = max(2, int(h / cells) + 2), max(2, int(w / cells) + 2)
    grid = gen.random((gh, gw), dtype=np.float32)
    return cv2.resize(grid, (w, h), interpolation=cv2.INTER_CUBIC)


def procedural_texture(shape: tuple[int, int], texel: float, rng: np.random.Generator,
                       windows: bool = False) -> np.ndarray:
    """A seeded grayscale texture rich in corners and blobs at every scale.

    Args:
        shape: ``(rows, columns)`` in texels.
        texel: texel size in metres (sets the physical size of the patterns:
            blobs 5 cm .. 1 m, rectangles 10 cm .. 2 m, noise 6 cm .. 4 m).
        rng: the random generator (the only source of randomness).
        windows: add framed window-like rectangles (for façades), at random
            positions and sizes, so they do not repeat.

    Returns:
        (rows, columns) uint8 texture, contrast stretched to 15..240.
    """
    h, w = (int(s) for s in shape)
    if h < 1 or w < 1:
        raise ValueError(f"texture shape must be positive, got {shape!r}")
    texel = _finite_positive("texel", texel)
    img = np.zeros((h, w), np.float32)
    # fractal value noise: amplitude grows with the wavelength (about 1/f^0.7),
    # so blobs of every size have contrast (SIFT detects across its octaves)
    for wavelength in (4.0, 2.0, 1.0, 0.5, 0.25, 0.12, 0.06):
        cells = max(2.0, wavelength / texel)
        img += (wavelength ** 0.7) * (_value_noise(rng, (h, w), cells) - 0.5)
    img = (img - img.min()) / max(float(np.ptp(img)), 1e-6)   # 0 .. 1
    area = h * w * texel * texel                               # square metres
    m = lambda x: max(1, int(round(x / texel)))               # noqa: E731  metres -> texels

    def rect(x0: float, y0: float, rw: float, rh: float, value: float) -> None:
        cv2.rectangle(img, (m(x0), m(y0)), (m(x0 + rw), m(y0 + rh)), float(value), -1)

    for _ in range(int(0.5 * area)):            # patches: corners at every scale
        rw, rh = rng.uniform(0.1, 2.0, 2)
        rect(rng.uniform(0, w * texel), rng.uniform(0, h * texel), rw, rh, rng.random())
    for _ in range(int(1.5 * area)):            # discs and ellipses: blobs
        r = rng.uniform(0.05, 0.5)
        cv2.ellipse(img, (m(rng.uniform(0, w * texel)), m(rng.uniform(0, h * texel))),
                    (m(r), m(r * rng.uniform(0.4, 1.0))), float(rng.uniform(0, 180)),
                    0, 360, float(rng.random()), -1)
    if windows:                                   # framed panes of random size and place
        for _ in range(int(0.08 * area)):
            ww, wh = rng.uniform(0.5, 1.6), rng.uniform(0.7, 2.0)
            x0, y0 = rng.uniform(0, w * texel), rng.uniform(0, h * texel)
            frame = rng.uniform(0.06, 0.15)
            rect(x0 - frame, y0 - frame, ww + 2 * frame, wh + 2 * frame, rng.uniform(0.7, 1.0))
            rect(x0, y0, ww, wh, rng.uniform(0.0, 0.35))
            if rng.random() < 0.5:               # a mullion at a random place
                rect(x0 + rng.uniform(0.3, 0.7) * ww, y0, frame, wh, rng.uniform(0.7, 1.0))
    # a light blur anti-aliases the drawn edges (they are drawn without AA)
    img = cv2.GaussianBlur(img, (0, 0), 0.7)
    return np.clip(15 + 225 * img, 0, 255).round().astype(np.uint8)


# --------------------------------------------------------------------------- layout

@dataclass(frozen=True)
class CourtyardLayout:
    """Dimensions of the default world and its path, metres.

    The car drives a rounded rectangle: straights of ``straight_x`` and
    ``straight_y`` joined by quarter circles of radius ``turn_radius``. The
    central block's walls stand ``inner_offset`` inside the path, the courtyard's
    walls ``outer_offset`` outside it (so the façades are 6 .. 40 m from the
    cameras). The cameras are ``camera_height`` above the ground.
    """

    straight_x: float = 18.0
    straight_y: float = 8.0
    turn_radius: float = 5.0
    inner_offset: float = 6.0
    outer_offset: float = 7.0
    inner_height: float = 9.0
    outer_height: float = 12.0
    camera_height: float = 1.5
    wall_texel: float = 0.02
    ground_texel: float = 0.025

    def __post_init__(self) -> None:
        for k in ("straight_x", "straight_y", "turn_radius", "inner_offset", "outer_offset",
                  "inner_height", "outer_height", "camera_height", "wall_texel",
                  "ground_texel"):
            _finite_positive(k, getattr(self, k))
        if self.inner_offset >= self.turn_radius + min(self.straight_x, self.straight_y) / 2:
            raise ValueError("inner_offset leaves no central block inside the path")

    @property
    def length(self) -> float:
        """Length of the closed path, metres."""
        return 2 * (self.straight_x + self.straight_y) + 2 * math.pi * self.turn_radius

    @property
    def block_centre(self) -> np.ndarray:
        """(2,) world x, y of the centre of the central block: the start of the
        path is the middle of the lower straight, at the world origin."""
        return np.array([0.0, self.straight_y / 2 + self.turn_radius])


def check_n_frames(n_frames: Any) -> int:
    """``n_frames`` as an int of at least 2 (a sequence needs two frames), else ValueError."""
    n = check_int("n_frames", n_frames)
    if n < 2:
        raise ValueError(f"n_frames must be at least 2, got {n}")
    return n


def layout_or_default(layout: Any) -> "CourtyardLayout":
    """``layout`` if it is a :class:`CourtyardLayout`, the default one for None,
    else ValueError."""
    lay = CourtyardLayout() if layout is None else layout
    if not isinstance(lay, CourtyardLayout):
        raise ValueError(f"layout must be a CourtyardLayout, got {type(lay).__name__}")
    return lay


def _wall(name: str, a: np.ndarray, b: np.ndarray, bottom: float, top: float,
          texel: float, gen: np.random.Generator, gain: float) -> Plane:
    """Vertical wall from ``a`` to ``b`` (world x, y) between heights ``bottom`` and
    ``top``: texture columns along ``b - a``, rows downwards, so its normal
    ``u x v`` points to the left of ``a -> b``."""
    along = np.append(b - a, 0.0)
    length = float(np.linalg.norm(along))
    cols, rows = max(1, round(length / texel)), max(1, round((top - bottom) / texel))
    tex = procedural_texture((rows, cols), texel, gen, windows=True)
    return Plane(name, np.array([a[0], a[1], top]), along / length, np.array([0.0, 0.0, -1.0]),
                 tex, texel, gain)


def courtyard(seed: int = 0, layout: CourtyardLayout | None = None) -> Scene:
    """The default world: a walled courtyard with a central block and textured ground.

    Nine planes: the ground (``z = -camera_height``), the four façades of the
    central block facing out, and the four courtyard walls facing in; each
    with its own texture drawn from ``numpy.random.default_rng(seed)`` (same
    seed, same world, bit for bit).
    """
    seed = check_int("seed", seed)
    if seed < 0:
        raise ValueError(f"seed must be non-negative, got {seed}")
    lay = layout_or_default(layout)
    gen = np.random.default_rng(seed)
    cx, cy = lay.block_centre
    hx = lay.straight_x / 2 + lay.turn_radius        # half extents of the path
    hy = lay.straight_y / 2 + lay.turn_radius
    ground_z = -lay.camera_height
    sun = np.array([0.5, -0.3, 0.8]) / np.linalg.norm([0.5, -0.3, 0.8])

    def corners(half_x: float, half_y: float) -> list[np.ndarray]:
        # counter-clockwise seen from above
        return [np.array([cx + sx * half_x, cy + sy * half_y])
                for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]

    planes = []
    ox, oy = hx + lay.outer_offset, hy + lay.outer_offset
    g_cols, g_rows = round(2 * ox / lay.ground_texel), round(2 * oy / lay.ground_texel)
    planes.append(Plane("ground", np.array([cx - ox, cy + oy, ground_z]), np.array([1.0, 0, 0]),
                        np.array([0.0, -1, 0]),
                        procedural_texture((g_rows, g_cols), lay.ground_texel, gen),
                        lay.ground_texel, 0.85))
    inner = corners(hx - lay.inner_offset, hy - lay.inner_offset)
    outer = corners(ox, oy)
    for k in range(4):
        # the block's façades face outwards: walk its corners clockwise
        a, b = inner[(k + 1) % 4], inner[k]
        n = np.cross(np.append(b - a, 0.0) / np.linalg.norm(b - a), [0.0, 0.0, -1.0])
        planes.append(_wall(f"block{k}", a, b, ground_z, ground_z + lay.inner_height,
                            lay.wall_texel, gen, 0.55 + 0.45 * max(0.0, float(n @ sun))))
        # the courtyard's walls face inwards: counter-clockwise
        a, b = outer[k], outer[(k + 1) % 4]
        n = np.cross(np.append(b - a, 0.0) / np.linalg.norm(b - a), [0.0, 0.0, -1.0])
        planes.append(_wall(f"court{k}", a, b, ground_z, ground_z + lay.outer_height,
                            lay.wall_texel, gen, 0.55 + 0.45 * max(0.0, float(n @ sun))))
    return Scene(tuple(planes))


def loop_path(n_frames: int, step: float | None = None, start: float = 0.0,
              layout: CourtyardLayout | None = None) -> np.ndarray:
    """Poses of the car along the closed loop around the block, counter-clockwise.

    Frame ``k`` is at arc length ``start + k step`` (metres, modulo the loop
    length); the default ``step`` is ``length / n_frames``, so the last frame
    joins the first with the same step. The rig's x axis is the tangent of the
    path, its z axis world up (rig frame x forward, y left, z up), and its
    origin at the cameras' height (world z = 0). Arc length 0 is the middle of
    the first straight, the world origin, heading +x: with ``start = 0`` the
    first pose is the identity.

    Returns:
        (n_frames, 4, 4) world_from_rig poses.
    """
    n = check_n_frames(n_frames)
    lay = layout_or_default(layout)
    L = lay.length
    step = L / n if step is None else _finite_positive("step", step)
    try:
        start = float(start)
    except (TypeError, ValueError):
        raise ValueError(f"start must be a number (metres), got {start!r}") from None
    if not math.isfinite(start):
        raise ValueError(f"start must be finite, got {start!r}")
    s = np.mod(start + step * np.arange(n), L)
    # the loop as 8 pieces from the start: half straight, turn, straight, turn,
    # straight, turn, straight, turn, half straight (block-centred coordinates)
    sx, sy, r = lay.straight_x, lay.straight_y, lay.turn_radius
    q = math.pi * r / 2
    pieces = [("line", sx / 2, (0.0, -sy / 2 - r), 0.0),
              ("arc", q, (sx / 2, -sy / 2), -math.pi / 2),
              ("line", sy, (sx / 2 + r, -sy / 2), math.pi / 2),
              ("arc", q, (sx / 2, sy / 2), 0.0),
              ("line", sx, (sx / 2, sy / 2 + r), math.pi),
              ("arc", q, (-sx / 2, sy / 2), math.pi / 2),
              ("line", sy, (-sx / 2 - r, sy / 2), -math.pi / 2),
              ("arc", q, (-sx / 2, -sy / 2), math.pi),
              ("line", sx / 2, (-sx / 2, -sy / 2 - r), 0.0)]
    ends = np.cumsum([p[1] for p in pieces])
    poses = np.tile(np.eye(4), (n, 1, 1))
    centre = lay.block_centre
    for k, sk in enumerate(s):
        i = int(np.searchsorted(ends, sk, side="right"))
        i = min(i, len(pieces) - 1)
        kind, length, (px, py), ang = pieces[i]
        d = sk - (ends[i] - length)                   # arc length within the piece
        if kind == "line":                            # from (px, py) along heading ang
            x, y, yaw = px + d * math.cos(ang), py + d * math.sin(ang), ang
        else:                                         # around centre (px, py), from angle ang
            phi = ang + d / r
            x, y, yaw = px + r * math.cos(phi), py + r * math.sin(phi), phi + math.pi / 2
        c, sn = math.cos(yaw), math.sin(yaw)
        poses[k, :3, :3] = [[c, -sn, 0.0], [sn, c, 0.0], [0.0, 0.0, 1.0]]
        poses[k, :3, 3] = (x + centre[0], y + centre[1], 0.0)
    return poses
