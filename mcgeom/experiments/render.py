"""A small deterministic renderer: a rig's cameras, with their lens distortion,
looking at a textured world of planes (the images of the demo's main job, issue 17).

Each pixel of each camera is unprojected once, through the camera's lens model, to
its bearing in the rig frame (:meth:`mcgeom.rig.Camera.pixels_to_bearings`,
``d = R_i^T normalize([x, y, 1])`` of docs/architecture.md §3, ``(x, y)`` undistorted
by ``cv2.undistortPoints``). For a pose world_from_rig ``(R, t)`` the ray of a pixel
leaves the camera centre ``R c_i + t`` along ``R d`` (the Plücker ray of the pixel,
thesis ch. 4.2, moved rigidly with the rig); the nearest plane it hits in front gives
the texture point, read bilinearly from a mip level chosen from the pixel's footprint
on the plane (trilinear mip-mapping, so that far and grazing texture does not alias).
A ray that hits nothing sees a featureless sky gradient. The output is 8-bit grayscale.

Because the rays come from the camera model itself, a world point ``X`` appears at
``Camera.project(X)`` (the forward model, ``cv2.projectPoints``) up to the sampling:
the rendered images follow the calibration exactly, distortion included.

:func:`render_sequence` writes the demo's input:

* ``out_dir/images/<camera name>/<frame:06d>.png``, one folder per camera;
* ``out_dir/rig.json`` (:func:`mcgeom.io.save_mcgeom_json`);
* ``out_dir/groundtruth_tum.txt``: ``timestamp tx ty tz qx qy qz qw`` of
  world_from_rig, the world being the rig frame of the first frame (so its first
  line is the identity), the timestamp the frame index.

Frames: the rig frame of :func:`surround_rig` is car-like (x forward, y left, z up,
origin at the cameras' height); the world of :mod:`mcgeom.experiments.world` has z up.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Any, Optional, Union

import cv2
import numpy as np

from mcgeom.io import save_mcgeom_json
from mcgeom.io.trajectory import write_tum
from mcgeom.rig import Camera, Rig
from mcgeom.synth import look_at_camera
from mcgeom.validation import check_int

from .common import Progress, no_progress
from .world import CourtyardLayout, Scene, check_n_frames, courtyard, layout_or_default, loop_path

__all__ = ["surround_rig", "Renderer", "render_frame", "RenderedSequence",
           "render_sequence", "MatchStats", "match_statistics"]

# rays hitting a plane closer than this (metres) are ignored: a camera mounted on a
# plane must not see the plane at its own centre
_MIN_DEPTH = 1e-3
_FRAME_FILE = re.compile(r"^\d{6}\.png$")


# --------------------------------------------------------------------------- rig

def surround_rig(width: int = 480, height: int = 360) -> Rig:
    """A surround-view car rig: 5 pinhole cameras with mild barrel distortion.

    Rig frame car-like: x forward, y left, z up, origin at the centre of the car at
    the cameras' height (metres). The cameras look outwards at yaw 0 ("front"),
    +72 ("front_left"), +144 ("rear_left"), -144 ("rear_right") and -72 degrees
    ("front_right"), pitched 5 degrees down, from the car's body (front bumper,
    mirrors, rear corners: 0.85 .. 1.9 m from the origin). Focal length
    ``0.42 width`` pixels: about 100 degrees horizontal field of view, so
    neighbouring cameras overlap by ~28 degrees (their matches fix the metric
    scale, thesis ch. 7.3.2; measured: 0.52 width, 16 degrees of overlap, gave
    about half as many correct SIFT matches across cameras). Distortion ``k1`` -0.05 .. -0.07, ``k2`` 0.01
    (OpenCV's radial model), a little different for each camera.

    Args:
        width, height: image size in pixels (default 480 x 360).
    """
    w, h = check_int("width", width), check_int("height", height)
    if w < 16 or h < 16:
        raise ValueError(f"image size must be at least 16 x 16 pixels, got {w} x {h}")
    f = 0.42 * w
    specs = (("front", (1.9, 0.0), 0.0, -0.05),
             ("front_left", (1.0, 0.9), 72.0, -0.06),
             ("rear_left", (-1.5, 0.85), 144.0, -0.07),
             ("rear_right", (-1.5, -0.85), -144.0, -0.06),
             ("front_right", (1.0, -0.9), -72.0, -0.05))
    cams = []
    pitch = math.radians(-5.0)
    for name, (x, y), yaw_deg, k1 in specs:
        yaw = math.radians(yaw_deg)
        forward = (math.cos(pitch) * math.cos(yaw), math.cos(pitch) * math.sin(yaw),
                   math.sin(pitch))
        cams.append(look_at_camera(name, (x, y, 0.0), forward, f=f, width=w, height=h,
                                   dist=(k1, 0.01, 0.0, 0.0, 0.0)))
    return Rig(tuple(cams))


# --------------------------------------------------------------------------- renderer

@dataclass(frozen=True)
class _CameraRays:
    """What does not change with the pose: each pixel's bearing (rig frame) and the
    angle it subtends (radians), row-major over the image."""

    bearings: np.ndarray   # (3, H W) float32: one row per axis
    angle: np.ndarray      # (H W,) float32
    centre: np.ndarray     # (3,) rig frame
    shape: tuple[int, int]


def _camera_rays(cam: Camera) -> _CameraRays:
    u, v = np.meshgrid(np.arange(cam.width, dtype=np.float64),
                       np.arange(cam.height, dtype=np.float64))
    b = cam.pixels_to_bearings(np.column_stack([u.ravel(), v.ravel()]))
    grid = b.reshape(cam.height, cam.width, 3)
    # angle between neighbouring pixels' bearings (chord ~ angle at these sizes);
    # the last column/row repeats its neighbour's
    du = np.linalg.norm(np.diff(grid, axis=1), axis=2)
    dv = np.linalg.norm(np.diff(grid, axis=0), axis=2)
    du = np.concatenate([du, du[:, -1:]], axis=1) if cam.width > 1 else np.ones_like(grid[..., 0])
    dv = np.concatenate([dv, dv[-1:]], axis=0) if cam.height > 1 else np.ones_like(grid[..., 0])
    angle = np.sqrt(du * dv).ravel()
    return _CameraRays(np.ascontiguousarray(b.T, dtype=np.float32), angle.astype(np.float32),
                       cam.centre, (cam.height, cam.width))


def _check_pose(T: Any) -> np.ndarray:
    M = np.asarray(T, dtype=np.float64) if not isinstance(T, np.ndarray) else T.astype(np.float64)
    if M.shape != (4, 4):
        raise ValueError(f"pose must be a 4x4 world_from_rig matrix, got shape {M.shape}")
    if not np.all(np.isfinite(M)):
        raise ValueError("pose has non-finite entries")
    R = M[:3, :3]
    if (np.abs(R.T @ R - np.eye(3)).max() > 1e-6 or np.linalg.det(R) < 0
            or np.abs(M[3] - [0, 0, 0, 1]).max() > 0):
        raise ValueError("pose must be a rigid transform [[R, t], [0, 0, 0, 1]] with R a "
                         "rotation")
    return M


class Renderer:
    """Renders a :class:`~mcgeom.experiments.world.Scene` into the cameras of a rig.

    The bearings of every pixel of every camera are computed once, here; each
    rendering then costs a few matrix products and texture look-ups. Rendering is
    deterministic (same scene, rig and pose: same bytes).
    """

    def __init__(self, scene: Scene, rig: Rig) -> None:
        if not isinstance(scene, Scene):
            raise ValueError(f"scene must be a mcgeom.experiments.world.Scene, got "
                             f"{type(scene).__name__}")
        if not isinstance(rig, Rig):
            raise ValueError(f"rig must be a mcgeom.rig.Rig, got {type(rig).__name__}")
        self.scene = scene
        self.rig = rig
        planes = scene.planes
        self._origin = np.array([p.origin for p in planes])                  # (P, 3)
        self._axes = np.stack([np.array([p.normal for p in planes]),
                               np.array([p.u for p in planes]),
                               np.array([p.v for p in planes])])             # (3, P, 3)
        self._size = np.array([p.size for p in planes])                      # (P, 2)
        self._rays = [_camera_rays(c) for c in rig.cameras]

    def render(self, T_world_from_rig: Any, camera: Union[int, str]) -> np.ndarray:
        """One camera's image at one rig pose.

        Args:
            T_world_from_rig: 4x4 pose, ``X_world = T @ [X_rig, 1]`` (metres).
            camera: camera id (0-based) or name.

        Returns:
            (height, width) uint8 grayscale image.
        """
        T = _check_pose(T_world_from_rig)
        names = self.rig.names
        if isinstance(camera, str):
            if camera not in names:
                raise ValueError(f"no camera named {camera!r} in the rig ({', '.join(names)})")
            cam_id = names.index(camera)
        else:
            cam_id = names.index(self.rig.camera(camera).name)   # ValueError if unknown id
        return self._render(T, self._rays[cam_id])

    def render_frame(self, T_world_from_rig: Any) -> tuple[np.ndarray, ...]:
        """Every camera's image at one rig pose, in camera id order (uint8)."""
        T = _check_pose(T_world_from_rig)
        return tuple(self._render(T, r) for r in self._rays)

    def _render(self, T: np.ndarray, rays: _CameraRays) -> np.ndarray:
        R = T[:3, :3]
        centre = R @ rays.centre + T[:3, 3]                       # world, metres
        # the planes' axes in the rig frame: n.(R d) = (R^T n).d for a rig bearing d
        axes = (self._axes @ R).astype(np.float32)                 # (3, P, 3)
        B = rays.bearings                                          # (3, N)
        P = self._origin.shape[0]
        rel = centre - self._origin                                # (P, 3)
        n0, u0, v0 = (np.einsum("pk,pk->p", ax, rel) for ax in self._axes)
        n = B.shape[1]
        depth = np.full(n, np.inf, np.float32)
        which = np.full(n, -1, np.int8)
        a_hit = np.zeros(n, np.float32)
        b_hit = np.zeros(n, np.float32)
        cos_hit = np.ones(n, np.float32)

        def dot(v: np.ndarray) -> np.ndarray:
            # (3,) . (3, N) by hand: BLAS threads for a 3-long inner dimension cost
            # more than they save on a busy machine
            return v[0] * B[0] + v[1] * B[1] + v[2] * B[2]

        # plane k: n.(C + s D - O) = 0  ->  s = -n.(C - O) / n.D; in-plane coordinates
        # (a, b) = (u, v).(C - O) + s (u, v).D; keep the nearest hit in front
        with np.errstate(divide="ignore", invalid="ignore"):
            for k in range(P):
                nd = dot(axes[0, k])
                s = np.float32(-n0[k]) / nd
                ok = (s > _MIN_DEPTH) & (s < depth)
                if not ok.any():
                    continue
                a = np.float32(u0[k]) + s * dot(axes[1, k])
                b = np.float32(v0[k]) + s * dot(axes[2, k])
                w, h = self._size[k]
                ok &= (a >= 0) & (a < w) & (b >= 0) & (b < h)
                np.copyto(depth, s, where=ok)
                np.copyto(which, np.int8(k), where=ok)
                np.copyto(a_hit, a, where=ok)
                np.copyto(b_hit, b, where=ok)
                np.copyto(cos_hit, np.abs(nd), where=ok)
        out = np.empty(n, np.float32)
        sky = which < 0
        # smooth sky: brighter upwards (no features)
        out[sky] = self.scene.sky + 60.0 * dot(R[2].astype(np.float32))[sky]
        # footprint of a pixel on its plane (metres): depth x angle, stretched by
        # 1/cos(incidence) along one axis; the geometric mean of both axes picks the
        # mip level (a compromise between blur and aliasing at grazing angles)
        foot = depth * rays.angle / np.sqrt(np.maximum(cos_hit, 1e-3))
        order = np.argsort(which, kind="stable")
        bounds = np.searchsorted(which[order], np.arange(P + 1))
        for k, plane in enumerate(self.scene.planes):
            sel = order[bounds[k]:bounds[k + 1]]
            if sel.size == 0:
                continue
            ak, bk = a_hit[sel], b_hit[sel]
            last = len(plane.mips) - 1
            level = np.clip(np.log2(np.maximum(foot[sel] / plane.texel, 1e-6)), 0.0,
                            float(last))
            base = np.minimum(level.astype(np.int64), max(last - 1, 0))
            frac = (level - base).astype(np.float32)
            vals = np.empty(sel.size, np.float32)
            for lv in range(int(base.min()), int(base.max()) + 1):
                g = np.flatnonzero(base == lv)
                if g.size == 0:
                    continue
                lo = self._sample(plane.mips[lv], ak[g], bk[g], plane.texel, lv)
                if lv + 1 <= last:
                    hi = self._sample(plane.mips[lv + 1], ak[g], bk[g], plane.texel, lv + 1)
                    lo = lo + frac[g] * (hi - lo)
                vals[g] = lo
            out[sel] = plane.gain * vals
        return np.clip(np.rint(out), 0, 255).astype(np.uint8).reshape(rays.shape)

    @staticmethod
    def _sample(tex: np.ndarray, a: np.ndarray, b: np.ndarray, texel: float,
                level: int) -> np.ndarray:
        """Bilinear values of mip ``level`` at plane coordinates ``(a, b)`` (metres) of a
        texture of ``texel`` metres (level 0: texel centres at (k + 0.5) texel)."""
        # cv2.pyrDown centres pixel k of a level on pixel 2k of the level below, so
        # level-l coordinates are the level-0 ones divided by 2^l
        scale = 1.0 / 2.0 ** level
        # cv2.remap wants maps of fewer than 32767 rows and columns: lay the points
        # out as rows of 1024 (the padding is sampled and dropped)
        n = a.shape[0]
        rows = -(-n // 1024)
        maps = np.zeros((2, rows * 1024), np.float32)
        maps[0, :n] = (a / texel - 0.5) * scale
        maps[1, :n] = (b / texel - 0.5) * scale
        return cv2.remap(tex, maps[0].reshape(rows, 1024), maps[1].reshape(rows, 1024),
                         cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE).reshape(-1)[:n]


def render_frame(T_world_from_rig: Any, rig: Optional[Rig] = None,
                 scene: Optional[Scene] = None, seed: int = 0) -> tuple[np.ndarray, ...]:
    """Every camera's uint8 image of one rig pose (world_from_rig, 4x4, metres).

    Defaults: :func:`surround_rig` in :func:`~mcgeom.experiments.world.courtyard`
    of ``seed``. For many poses build a :class:`Renderer` once instead.
    """
    scene = courtyard(seed) if scene is None else scene
    return Renderer(scene, surround_rig() if rig is None else rig).render_frame(T_world_from_rig)


# --------------------------------------------------------------------------- sequence

@dataclass(frozen=True)
class RenderedSequence:
    """What :func:`render_sequence` wrote.

    Attributes:
        out_dir: the output folder.
        rig: the rig (also in ``rig_path``).
        poses: (n_frames, 4, 4) world_from_rig, the world being the rig frame of
            frame 0 (``poses[0]`` is the identity), metres; as in ``groundtruth_path``.
        images: per camera name, the n_frames image paths in frame order.
        rig_path: ``out_dir/rig.json``.
        groundtruth_path: ``out_dir/groundtruth_tum.txt``.
        step: path length between consecutive frames, metres.
        path_length: length of the whole loop, metres.
    """

    out_dir: Path
    rig: Rig
    poses: np.ndarray
    images: dict[str, tuple[Path, ...]]
    rig_path: Path
    groundtruth_path: Path
    step: float
    path_length: float

    @property
    def n_frames(self) -> int:
        """Number of frames."""
        return int(self.poses.shape[0])


def _prepare_out_dir(out_dir: Any, rig: Rig, n_frames: int) -> tuple[Path, dict[str, Path]]:
    """Create the folders; refuse a folder holding what is not ours; remove frames
    of an earlier, longer run (they would be read as frames of this one)."""
    try:
        root = Path(out_dir)
    except TypeError:
        raise ValueError(f"out_dir must be a path, got {out_dir!r}") from None
    if root.exists() and not root.is_dir():
        raise ValueError(f"out_dir {str(root)!r} exists and is not a folder")
    images = root / "images"
    if images.exists():
        if not images.is_dir():
            raise ValueError(f"{str(images)!r} exists and is not a folder")
        foreign = sorted(p.name for p in images.iterdir() if p.name not in rig.names)
        if foreign:
            raise ValueError(f"{str(images)!r} holds entries that are not cameras of the rig "
                             f"({', '.join(foreign[:5])}); use an empty or new out_dir")
    dirs = {}
    for name in rig.names:
        d = images / name
        if d.exists():
            if not d.is_dir():
                raise ValueError(f"{str(d)!r} exists and is not a folder")
            other = sorted(p.name for p in d.iterdir() if not _FRAME_FILE.match(p.name))
            if other:
                raise ValueError(f"{str(d)!r} holds files that are not rendered frames "
                                 f"({', '.join(other[:5])}); use an empty or new out_dir")
            for p in d.iterdir():
                if int(p.name[:6]) >= n_frames:
                    p.unlink()
        d.mkdir(parents=True, exist_ok=True)
        dirs[name] = d
    return root, dirs


def render_sequence(out_dir: Union[str, PathLike], n_frames: int = 90, seed: int = 0, *,
                    step: Optional[float] = None, start: float = 0.0,
                    rig: Optional[Rig] = None, layout: Optional[CourtyardLayout] = None,
                    progress: Optional[Progress] = None) -> RenderedSequence:
    """Render the car's loop around the courtyard's block and write it to ``out_dir``.

    The car (:func:`surround_rig`, or ``rig``) drives the closed loop of
    :func:`~mcgeom.experiments.world.loop_path` (two long and two short straights
    joined by 90-degree turns of 5 m radius, 83.4 m in all with the default layout)
    through :func:`~mcgeom.experiments.world.courtyard` of ``seed``. With the
    defaults (90 frames, step = loop / 90 = 0.93 m) the last frame joins the first.

    Args:
        out_dir: output folder (created). An existing one may only hold an earlier
            rendering of the same cameras; stale frames beyond ``n_frames`` are removed.
        n_frames: number of frames, at least 2.
        seed: seed of the world's textures (non-negative int).
        step: metres between frames (default: the loop length / ``n_frames``).
        start: arc length of the first frame along the loop, metres (0: the middle
            of the first long straight; 9 + 7.85 / 2: the middle of the first turn).
        rig: the rig (default :func:`surround_rig`); its frame must be car-like
            (x forward, y left, z up, origin at the cameras' height).
        layout: the world's dimensions (default :class:`CourtyardLayout`).
        progress: ``progress(iterable, total=, desc=)`` wrapping the loop over the
            frames (:func:`mcgeom.experiments.common.progress_bar`), or None.

    Returns:
        The :class:`RenderedSequence` (poses world_from_rig with world = frame 0).

    Raises:
        ValueError: a bad argument, or an ``out_dir`` holding other files.
        OSError: a file cannot be written.
    """
    n = check_n_frames(n_frames)
    rig = surround_rig() if rig is None else rig
    if not isinstance(rig, Rig):
        raise ValueError(f"rig must be a mcgeom.rig.Rig, got {type(rig).__name__}")
    if progress is not None and not callable(progress):
        raise ValueError(f"progress must be callable or None, got {type(progress).__name__}")
    lay = layout_or_default(layout)
    scene_poses = loop_path(n, step=step, start=start, layout=lay)   # validates step, start
    scene = courtyard(seed, lay)                                       # validates seed
    root, dirs = _prepare_out_dir(out_dir, rig, n)
    renderer = Renderer(scene, rig)
    wrap = no_progress if progress is None else progress
    paths: dict[str, list[Path]] = {name: [] for name in rig.names}
    png = [cv2.IMWRITE_PNG_COMPRESSION, 1]    # fast; PNG is lossless at any level
    for k in wrap(range(n), total=n, desc="render"):
        for name, img in zip(rig.names, renderer.render_frame(scene_poses[k])):
            p = dirs[name] / f"{k:06d}.png"
            if not cv2.imwrite(str(p), img, png):
                raise OSError(f"cannot write {str(p)!r}")
            paths[name].append(p)
    # the world of the written poses is the rig frame of frame 0
    poses = np.linalg.inv(scene_poses[0]) @ scene_poses
    poses[0] = np.eye(4)
    rig_path = root / "rig.json"
    save_mcgeom_json(rig, rig_path)
    gt_path = root / "groundtruth_tum.txt"
    write_tum(gt_path, poses)   # timestamps: the frame indices
    used_step = lay.length / n if step is None else float(step)
    return RenderedSequence(root, rig, poses, {k: tuple(v) for k, v in paths.items()},
                            rig_path, gt_path, used_step, lay.length)


# --------------------------------------------------------------------------- usefulness

@dataclass(frozen=True)
class MatchStats:
    """SIFT matches between two images of a rendered sequence.

    ``matches``: ratio-test matches; ``consistent``: those within 1 px (Sampson
    distance, undistorted through the cameras) of the true epipolar geometry.
    """

    camera1: str
    frame1: int
    camera2: str
    frame2: int
    matches: int
    consistent: int


def _sampson_px(cam1: Camera, cam2: Camera, T1: np.ndarray, T2: np.ndarray,
                px1: np.ndarray, px2: np.ndarray) -> np.ndarray:
    """Sampson distance (pixels, via the mean focal length) of matches to the true
    essential matrix ``E = [t]x R`` of cam2_from_cam1 (Hartley & Zisserman eq. 11.9)."""
    def cam_from_world(cam: Camera, T: np.ndarray) -> np.ndarray:
        C = np.eye(4)
        C[:3, :3], C[:3, 3] = cam.R, cam.t
        return C @ np.linalg.inv(T)
    M = cam_from_world(cam2, T2) @ np.linalg.inv(cam_from_world(cam1, T1))
    R, t = M[:3, :3], M[:3, 3]
    E = np.array([[0, -t[2], t[1]], [t[2], 0, -t[0]], [-t[1], t[0], 0]]) @ R
    x1 = cam1.pixels_to_bearings(px1) @ cam1.R.T       # camera-frame rays
    x2 = cam2.pixels_to_bearings(px2) @ cam2.R.T
    x1, x2 = x1 / x1[:, 2:], x2 / x2[:, 2:]
    Ex1, Etx2 = x1 @ E.T, x2 @ E
    num = np.sum(x2 * Ex1, axis=1) ** 2
    den = Ex1[:, 0] ** 2 + Ex1[:, 1] ** 2 + Etx2[:, 0] ** 2 + Etx2[:, 1] ** 2
    f = 0.25 * (cam1.K[0, 0] + cam1.K[1, 1] + cam2.K[0, 0] + cam2.K[1, 1])
    return f * np.sqrt(num / np.maximum(den, 1e-300))


def match_statistics(seq: RenderedSequence, pairs: list[tuple[str, int, str, int]],
                     ratio: float = 0.8, n_features: int = 2000,
                     progress: Optional[Progress] = None) -> list[MatchStats]:
    """SIFT (OpenCV) matches between pairs of rendered images, checked against the
    true geometry: how useful the rendering is to a feature-based front end.

    Args:
        seq: a rendered sequence.
        pairs: ``(camera1, frame1, camera2, frame2)`` per pair (camera names).
        ratio: Lowe's ratio test threshold.
        n_features: SIFT's feature budget per image.
        progress: as in :func:`render_sequence`.

    Returns:
        One :class:`MatchStats` per pair.
    """
    names = seq.rig.names
    sift = cv2.SIFT_create(nfeatures=check_int("n_features", n_features))
    matcher = cv2.BFMatcher(cv2.NORM_L2)
    cache: dict[tuple[str, int], tuple[np.ndarray, Any]] = {}

    def features(name: str, k: int) -> tuple[np.ndarray, Any]:
        if name not in names:
            raise ValueError(f"no camera named {name!r} in the rig ({', '.join(names)})")
        if not 0 <= k < seq.n_frames:
            raise ValueError(f"frame {k} is outside 0..{seq.n_frames - 1}")
        if (name, k) not in cache:
            img = cv2.imread(str(seq.images[name][k]), cv2.IMREAD_GRAYSCALE)
            kp, des = sift.detectAndCompute(img, None)
            cache[(name, k)] = (np.array([p.pt for p in kp], np.float64).reshape(-1, 2), des)
        return cache[(name, k)]

    out = []
    wrap = no_progress if progress is None else progress
    for c1, f1, c2, f2 in wrap(pairs, total=len(pairs), desc="SIFT"):
        (p1, d1), (p2, d2) = features(c1, f1), features(c2, f2)
        good = []
        if d1 is not None and d2 is not None and len(d1) >= 2 and len(d2) >= 2:
            good = [m for m, m2 in matcher.knnMatch(d1, d2, k=2)
                    if m.distance < ratio * m2.distance]
        n_ok = 0
        if good:
            i1 = np.array([m.queryIdx for m in good])
            i2 = np.array([m.trainIdx for m in good])
            err = _sampson_px(seq.rig.camera(names.index(c1)), seq.rig.camera(names.index(c2)),
                              seq.poses[f1], seq.poses[f2], p1[i1], p2[i2])
            n_ok = int(np.sum(err < 1.0))
        out.append(MatchStats(c1, f1, c2, f2, len(good), n_ok))
    return out
