"""The front end of the sequence pipeline: a rig's images to feature tracks.

Per frame, every camera's image is detected and described once
(:class:`mcgeom.sequence.features.FeatureDetector`, SIFT by default). Matches are
made

* within each camera between consecutive frames (ratio test + mutual check), then
  checked against an essential matrix fitted by OpenCV's RANSAC
  (``cv2.findEssentialMat``, Nister's five-point solver) on the undistorted,
  normalised points of that camera (``geometric_check=True``); and
* across cameras whose views overlap, within one frame (:func:`overlapping_pairs`
  chooses the pairs from the calibration), checked against the epipolar geometry
  that the calibration fixes: the two rays must be coplanar with the baseline
  (thesis eq. 8.16 with R = I, t = 0: ``d_j . ((c_j - c_i) x d_i) = 0``) and the
  point in front of both cameras.

The matches are linked into tracks with a union-find (:class:`TrackLinker`) that
refuses any union which would give a track two observations in one (frame, camera):
the matches of a frame are linked best first (lowest ratio-test score), so a
conflicting, weaker match splits the track instead of corrupting it. Tracks with at
least 2 observations are kept.

The returned :class:`mcgeom.sequence.Tracks` hold the **raw (distorted) pixels** of
the keypoints: the rig's camera models undistort them later (``Rig.ray_pairs``,
``mcgeom.cv.estimate``). Only the previous frame's features are held while the
sequence runs, so memory grows with the tracks, not with the images.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable, Optional, Sequence

import numpy as np

from mcgeom.geometry import find_essential_mat
from mcgeom.io.images import ImageSequence, read_image
from mcgeom.rig import Rig
from mcgeom.sequence.features import FeatureDetector, Keypoints, match_descriptors
from mcgeom.sequence.tracks import Tracks

__all__ = ["MIN_OVERLAP", "overlapping_pairs", "essential_inliers", "calibrated_inliers",
           "TrackLinker", "FrontEndStats", "FrontEnd", "tracks_from_images", "build_tracks"]

#: camera pairs whose views overlap by at least this fraction get cross-camera matches
MIN_OVERLAP = 0.05
#: default epipolar threshold of the geometric checks, pixels
EPIPOLAR_PX = 1.5
#: fewer matches than this in a camera between two frames: too few for a RANSAC
#: essential matrix to tell inliers from outliers, so none is rejected there
_MIN_FOR_RANSAC = 12
#: a bearing this close to the image plane (z of the unit bearing, camera frame) has
#: no finite normalised point for cv2.findEssentialMat
_MIN_Z = 1e-3
#: below this parallax (radians) a cross-camera match's depth sign is noise
_MIN_PARALLAX = 1e-3


# ----------------------------------------------------------------------------- overlap

def overlapping_pairs(rig: Rig, min_frac: float = MIN_OVERLAP,
                      depths: tuple = (5.0, 15.0, 40.0)) -> list[tuple[int, int, float]]:
    """Camera pairs whose fields of view overlap, from the calibration only.

    A 24 x 16 grid of pixels of camera i is back-projected to points at each of
    ``depths`` (metres along camera i's optical axis) and projected into camera j;
    the overlap of (i, j) is the larger of the two mean visible fractions (i's grid
    seen by j, j's grid seen by i).

    Returns:
        ``[(i, j, overlap), ...]`` for ``i < j`` with ``overlap >= min_frac``.
    """
    def frac(i: int, j: int) -> float:
        ci = rig.cameras[i]
        u, v = np.meshgrid(np.linspace(0, ci.width - 1, 24), np.linspace(0, ci.height - 1, 16))
        px = np.c_[u.ravel(), v.ravel()]
        o, dirs = rig.rays(np.full(len(px), i), px)
        vis = []
        for z in depths:
            # depth along the optical axis of camera i: scale the bearing accordingly
            cos = dirs @ ci.R[2]
            _, ok = rig.project(j, o + dirs * (z / cos)[:, None])
            vis.append(ok.mean())
        return float(np.mean(vis))

    out = []
    n = len(rig.cameras)
    for i in range(n):
        for j in range(i + 1, n):
            f = max(frac(i, j), frac(j, i))
            if f >= min_frac:
                out.append((i, j, f))
    return out


# ----------------------------------------------------------------------------- checks

def _focal(cam: Any) -> float:
    return 0.5 * float(cam.K[0, 0] + cam.K[1, 1])


def essential_inliers(rig: Rig, camera: int, pixels1: np.ndarray, pixels2: np.ndarray,
                      threshold_px: float = EPIPOLAR_PX, prob: float = 0.999) -> np.ndarray:
    """Matches of one camera between two frames consistent with an essential matrix.

    The raw pixels are undistorted through the camera model
    (:meth:`mcgeom.rig.Camera.pixels_to_bearings`, then back to the camera frame)
    and normalised (``x/z, y/z``); ``cv2.findEssentialMat`` (five-point RANSAC,
    Nister 2004) fits E with the Sampson threshold ``threshold_px / f``.

    Args:
        rig, camera: the rig and the camera id of both images.
        pixels1, pixels2: (N, 2) raw pixels in the two frames.
        threshold_px: Sampson threshold, pixels.
        prob: RANSAC confidence.

    Returns:
        (N,) bool mask. With fewer than 12 matches nothing is rejected (too few for
        RANSAC to tell inliers from outliers; the two-frame robust estimator still
        judges them). A static camera passes: every correct match fits E = [t]x for
        any t when R = I and the points do not move.
    """
    n = len(pixels1)
    if n < _MIN_FOR_RANSAC:
        return np.ones(n, dtype=bool)
    import cv2

    cam = rig.camera(camera)
    # bearings come in the rig frame (d = R^T d_cam): rotate back to the camera
    b1 = cam.pixels_to_bearings(pixels1) @ cam.R.T
    b2 = cam.pixels_to_bearings(pixels2) @ cam.R.T
    ok = (b1[:, 2] > _MIN_Z) & (b2[:, 2] > _MIN_Z)
    out = np.zeros(n, dtype=bool)
    if ok.sum() < _MIN_FOR_RANSAC:
        out[ok] = True
        return out
    x1 = np.ascontiguousarray(b1[ok, :2] / b1[ok, 2:])
    x2 = np.ascontiguousarray(b2[ok, :2] / b2[ok, 2:])
    E, mask = find_essential_mat(x1, x2, np.eye(3), method=cv2.RANSAC, prob=prob,
                                   threshold=threshold_px / _focal(cam))
    if E is None or mask is None:
        # RANSAC found no model (degenerate configuration): keep them all, the
        # robust two-frame estimator decides
        out[ok] = True
        return out
    out[np.flatnonzero(ok)] = mask.ravel().astype(bool)
    return out


def calibrated_inliers(rig: Rig, cam1: int, cam2: int, pixels1: np.ndarray,
                       pixels2: np.ndarray, threshold_px: float = EPIPOLAR_PX) -> np.ndarray:
    """Matches between two cameras of the rig at the same instant that the calibration
    allows.

    The rays ``(c_1, d_1)`` and ``(c_2, d_2)`` (rig frame) of a true match meet, so
    they are coplanar with the baseline ``b = c_2 - c_1``: ``e = d_2 . (b x d_1) = 0``
    (the generalized epipolar constraint, thesis eq. 8.16, with no motion). The
    error is the first-order angular (Sampson) distance ``|e| / |grad e|`` over
    tangent perturbations of the unit bearings, times the mean focal length of the
    two cameras; the midpoint triangulation must also put the point in front of both
    cameras where the parallax exceeds 1e-3 rad.

    Returns:
        (N,) bool mask.
    """
    n = len(pixels1)
    if n == 0:
        return np.zeros(0, dtype=bool)
    c1, d1 = rig.rays(np.full(n, cam1), pixels1)
    c2, d2 = rig.rays(np.full(n, cam2), pixels2)
    b = c2 - c1
    e = np.einsum("ij,ij->i", d2, np.cross(b, d1))
    # e = d1 . (d2 x b) = d2 . (b x d1): the gradients in d1 and d2
    g1 = np.cross(d2, b)
    g2 = np.cross(b, d1)
    g1 -= np.einsum("ij,ij->i", g1, d1)[:, None] * d1
    g2 -= np.einsum("ij,ij->i", g2, d2)[:, None] * d2
    den = np.sqrt(np.einsum("ij,ij->i", g1, g1) + np.einsum("ij,ij->i", g2, g2))
    f = 0.5 * (_focal(rig.camera(cam1)) + _focal(rig.camera(cam2)))
    ok = np.abs(e) * f <= threshold_px * np.maximum(den, 1e-300)
    # cheirality: c1 + a d1 = c2 + s d2 (least squares), a, s > 0
    cos = np.einsum("ij,ij->i", d1, d2)
    det = 1.0 - cos * cos
    par = det > _MIN_PARALLAX ** 2
    p = np.einsum("ij,ij->i", d1, b)
    q = np.einsum("ij,ij->i", d2, b)
    with np.errstate(divide="ignore", invalid="ignore"):
        a = (p - cos * q) / det
        s = (cos * p - q) / det
    ok &= ~par | ((a > 0) & (s > 0))
    return ok


# ----------------------------------------------------------------------------- tracks

class TrackLinker:
    """Union-find over observations (frame, camera, pixel) that keeps every track
    free of conflicts: a union that would give a track two observations in one
    (frame, camera) is refused (the track is split there instead).

    Each root holds the set of (frame, camera) slots of its track; a union merges
    the smaller set into the larger (union by size) after checking they are
    disjoint; ``find`` halves paths.
    """

    def __init__(self) -> None:
        self._parent: list[int] = []
        self._slots: list[Optional[set]] = []
        self._frame: list[int] = []
        self._camera: list[int] = []
        self._pixels: list[tuple[float, float]] = []
        #: number of unions refused because of a conflict
        self.conflicts = 0

    def __len__(self) -> int:
        return len(self._parent)

    def add(self, frame: int, camera: int, pixel: Sequence[float]) -> int:
        """A new observation (its own track); returns its node id."""
        node = len(self._parent)
        self._parent.append(node)
        self._slots.append({(int(frame), int(camera))})
        self._frame.append(int(frame))
        self._camera.append(int(camera))
        self._pixels.append((float(pixel[0]), float(pixel[1])))
        return node

    def find(self, node: int) -> int:
        """The root of ``node``'s track."""
        parent = self._parent
        while parent[node] != node:
            parent[node] = parent[parent[node]]
            node = parent[node]
        return node

    def union(self, a: int, b: int) -> bool:
        """Join the tracks of nodes ``a`` and ``b``; False (and nothing changes) if
        they share a (frame, camera) slot."""
        ra, rb = self.find(a), self.find(b)
        if ra == rb:
            return True
        sa, sb = self._slots[ra], self._slots[rb]
        assert sa is not None and sb is not None
        if len(sa) < len(sb):
            ra, rb, sa, sb = rb, ra, sb, sa
        if not sa.isdisjoint(sb):
            self.conflicts += 1
            return False
        sa |= sb
        self._parent[rb] = ra
        self._slots[rb] = None
        return True

    def tracks(self, n_frames: int, min_observations: int = 2) -> Tracks:
        """The tracks with at least ``min_observations`` observations, numbered
        0, 1, ... in order of their first observation."""
        n = len(self._parent)
        if n == 0:
            return Tracks(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0, np.int64),
                          np.zeros((0, 2)), n_frames)
        roots = np.array([self.find(i) for i in range(n)], dtype=np.int64)
        _, first, inverse, counts = np.unique(roots, return_index=True, return_inverse=True,
                                              return_counts=True)
        keep = counts[inverse] >= min_observations
        # renumber the kept tracks by first appearance
        order = np.argsort(first, kind="stable")
        rank = np.empty_like(order)
        rank[order] = np.arange(order.size)
        kept_ids = np.unique(rank[inverse[keep]])
        new_id = np.full(order.size, -1, np.int64)
        new_id[kept_ids] = np.arange(kept_ids.size)
        track = new_id[rank[inverse[keep]]]
        frame = np.asarray(self._frame, np.int64)[keep]
        camera = np.asarray(self._camera, np.int64)[keep]
        pixels = np.asarray(self._pixels, np.float64).reshape(-1, 2)[keep]
        srt = np.lexsort((camera, frame, track))
        return Tracks(track[srt], frame[srt], camera[srt], pixels[srt], n_frames)


# ----------------------------------------------------------------------------- front end

@dataclass
class FrontEndStats:
    """What the last :meth:`FrontEnd.run` did, per step k -> k+1 and per frame.

    ``keypoints[k][i]``: keypoints of camera i in frame k; ``intra_matches[k][i]`` /
    ``intra_kept[k][i]``: matches of camera i between frames k and k+1 before / after
    the essential-matrix check; ``cross_matches[k][(i, j)]`` / ``cross_kept``: matches
    between overlapping cameras i and j in frame k before / after the calibrated
    check; ``conflicts``: unions refused by the track linker.
    """

    cross_pairs: list = field(default_factory=list)
    keypoints: list = field(default_factory=list)
    intra_matches: list = field(default_factory=list)
    intra_kept: list = field(default_factory=list)
    cross_matches: list = field(default_factory=list)
    cross_kept: list = field(default_factory=list)
    conflicts: int = 0


class FrontEnd:
    """Images of a rig's frames to :class:`mcgeom.sequence.Tracks`.

    Args:
        rig: the calibrated rig (camera i of every frame is ``rig.cameras[i]``).
        features: ``"sift"`` (default) or ``"orb"``.
        n_features: keypoints per image, at most.
        ratio: Lowe's ratio test threshold, in (0, 1].
        cross_camera: match across the overlapping cameras (:func:`overlapping_pairs`).
        geometric_check: reject temporal matches inconsistent with a RANSAC essential
            matrix of their camera (:func:`essential_inliers`). On by default because
            it measurably helps the two-frame estimator downstream (SIFT, 4000 per
            image): on DDAD scene_02 the share of step correspondences within 1 px of
            the ground-truth epipolar geometry rises from 92 / 90 % to 96 / 95 % and
            the |t| error of ``mcgeom.cv.estimate`` drops from 2.3 / 8.9 % to 1.3 /
            5.1 %; on KITTI raw 0023 the share rises by about 1 point (94-97 %).
        threshold_px: the epipolar threshold of both checks, pixels.
        min_overlap: the overlap fraction from which a camera pair is matched.
    """

    def __init__(self, rig: Rig, *, features: str = "sift", n_features: int = 4000,
                 ratio: float = 0.8, cross_camera: bool = True, geometric_check: bool = True,
                 threshold_px: float = EPIPOLAR_PX, min_overlap: float = MIN_OVERLAP) -> None:
        if not isinstance(rig, Rig):
            raise ValueError(f"rig must be a mcgeom.rig.Rig, got {type(rig).__name__}")
        if not (isinstance(ratio, (int, float)) and 0 < ratio <= 1):
            raise ValueError(f"ratio must be in (0, 1], got {ratio!r}")
        if not (isinstance(threshold_px, (int, float)) and np.isfinite(threshold_px)
                and threshold_px > 0):
            raise ValueError(f"threshold_px must be a positive number, got {threshold_px!r}")
        self.rig = rig
        #: one detector per camera: the cameras of a frame are detected in
        #: parallel threads (OpenCV releases the GIL), none shared between two
        self.detectors = [FeatureDetector(features, n_features) for _ in rig.cameras]
        #: the descriptors' distance (cv2.NORM_L2 for SIFT, NORM_HAMMING for ORB)
        self.norm = self.detectors[0].norm
        self.ratio = float(ratio)
        self.geometric_check = bool(geometric_check)
        self.threshold_px = float(threshold_px)
        #: the overlapping camera pairs matched within each frame, ``[(i, j, overlap)]``
        self.cross_pairs = overlapping_pairs(rig, min_overlap) if cross_camera else []
        self.stats = FrontEndStats()

    def _detect(self, k: int, images: Sequence[Any], pool: ThreadPoolExecutor
                ) -> list[Keypoints]:
        """Frame k's features, its cameras in ``pool``'s threads (SIFT is most of
        the front end's time: 1.6x faster on 2 cores than one camera after the
        other, the demo's images). An error names the first bad camera."""
        n = len(self.rig)
        if isinstance(images, np.ndarray) or len(images) != n:
            got = "an array" if isinstance(images, np.ndarray) else f"{len(images)} images"
            raise ValueError(f"frame {k}: expected a list of {n} images (one per rig camera, "
                             f"in rig order), got {got}")

        def one(i: int) -> Keypoints:
            c = self.rig.cameras[i]
            return self.detectors[i].detect(images[i], (c.width, c.height),
                                             f"frame {k}, camera {i} ({c.name!r})")

        return list(pool.map(one, range(n)))

    def run(self, frames: Iterable[Sequence[Any]],
            progress: Optional[Callable[[int], Any]] = None) -> Tracks:
        """Build the tracks of a sequence.

        Args:
            frames: an iterable over the frames; each frame a sequence of one image
                per rig camera, in rig order ((H, W) grey or (H, W, 3) BGR uint8, of
                the calibrated size). It is consumed once: a generator that reads
                the images lazily keeps memory flat.
            progress: optional ``progress(n_done_frames)``, called after each frame.

        Returns:
            :class:`mcgeom.sequence.Tracks` with raw (distorted) pixels.

        Raises:
            ValueError: fewer than 2 frames, a frame with the wrong number of images,
                an image of the wrong type or size.
        """
        st = self.stats = FrontEndStats(cross_pairs=list(self.cross_pairs))
        linker = TrackLinker()
        prev: Optional[list[Keypoints]] = None
        prev_nodes: list[dict] = []
        k = -1
        pool = ThreadPoolExecutor(max_workers=max(1, min(len(self.rig), os.cpu_count() or 1)))
        with pool:
            for k, images in enumerate(frames):
                prev, prev_nodes = self._add_frame(k, images, pool, linker, prev, prev_nodes)
                if progress is not None:
                    progress(k + 1)
        n_frames = k + 1
        if n_frames < 2:
            raise ValueError(f"a sequence needs at least 2 frames, got {n_frames}")
        st.conflicts = linker.conflicts
        return linker.tracks(n_frames)

    def _add_frame(self, k: int, images: Sequence[Any], pool: ThreadPoolExecutor,
                   linker: "TrackLinker", prev: Optional[list[Keypoints]],
                   prev_nodes: list[dict]) -> tuple[list[Keypoints], list[dict]]:
        """Frame k's features, matched within the frame and to the previous
        one and linked into the tracks; returns its features and node maps
        (the next frame's previous)."""
        st = self.stats
        feats = self._detect(k, images, pool)
        st.keypoints.append([len(f) for f in feats])
        nodes: list[dict] = [{} for _ in feats]
        # candidate links (score, (frame, cam, kp), (frame, cam, kp)); the
        # previous frame's are "p"-tagged so their node maps can be found
        edges: list[tuple[float, tuple, tuple]] = []
        cross_m, cross_k = {}, {}
        for i, j, _ in self.cross_pairs:
            a, b, s = match_descriptors(feats[i].descriptors, feats[j].descriptors,
                                        self.norm, self.ratio)
            ok = calibrated_inliers(self.rig, i, j, feats[i].pixels[a], feats[j].pixels[b],
                                    self.threshold_px)
            cross_m[(i, j)], cross_k[(i, j)] = len(a), int(ok.sum())
            edges += [(sc, ("c", i, ia), ("c", j, ib))
                      for ia, ib, sc in zip(a[ok].tolist(), b[ok].tolist(), s[ok].tolist())]
        st.cross_matches.append(cross_m)
        st.cross_kept.append(cross_k)
        if prev is not None:
            im, ik = [], []
            for i in range(len(feats)):
                a, b, s = match_descriptors(prev[i].descriptors, feats[i].descriptors,
                                            self.norm, self.ratio)
                ok = (essential_inliers(self.rig, i, prev[i].pixels[a], feats[i].pixels[b],
                                        self.threshold_px)
                      if self.geometric_check else np.ones(len(a), bool))
                im.append(len(a))
                ik.append(int(ok.sum()))
                edges += [(sc, ("p", i, ia), ("c", i, ib))
                          for ia, ib, sc in zip(a[ok].tolist(), b[ok].tolist(),
                                                s[ok].tolist())]
            st.intra_matches.append(im)
            st.intra_kept.append(ik)
        # best matches first: a weaker match that conflicts with them is refused
        edges.sort(key=lambda e: e[0])

        def node(ref: tuple) -> int:
            tag, cam, kp = ref
            table, f, fr = ((prev_nodes, prev, k - 1) if tag == "p" else (nodes, feats, k))
            got = table[cam].get(kp)
            if got is None:
                got = table[cam][kp] = linker.add(fr, cam, f[cam].pixels[kp])
            return got

        for _, r1, r2 in edges:
            linker.union(node(r1), node(r2))
        return feats, nodes


def tracks_from_images(rig: Rig, frames: Iterable[Sequence[Any]], *, features: str = "sift",
                       n_features: int = 4000, ratio: float = 0.8, cross_camera: bool = True,
                       geometric_check: bool = True, threshold_px: float = EPIPOLAR_PX,
                       progress: Optional[Callable[[int], Any]] = None) -> Tracks:
    """Feature tracks of a sequence given as image arrays (see :class:`FrontEnd`).

    ``frames[k][i]`` is the image of ``rig.cameras[i]`` in frame k ((H, W) grey or
    (H, W, 3) BGR uint8). The tracks hold raw (distorted) pixels.
    """
    fe = FrontEnd(rig, features=features, n_features=n_features, ratio=ratio,
                  cross_camera=cross_camera, geometric_check=geometric_check,
                  threshold_px=threshold_px)
    return fe.run(frames, progress)


def build_tracks(rig: Rig, sequence: ImageSequence, *, features: str = "sift",
                 n_features: int = 4000, ratio: float = 0.8, cross_camera: bool = True,
                 geometric_check: bool = True, threshold_px: float = EPIPOLAR_PX,
                 progress: Optional[Callable[..., Iterable]] = None) -> Tracks:
    """Feature tracks of an image sequence on disk
    (:func:`mcgeom.io.images.find_image_sequence`).

    Each image is read once, when its frame is processed (grey, ``cv2.imread``);
    only the previous frame's features are kept. Frame k of the tracks is frame k
    of ``sequence`` (after its slicing). Options: see :class:`FrontEnd`.
    ``progress``: wraps the loop over the frames (``progress(iterable, total=,
    desc=)``, e.g. a tqdm bar), as the back end's does.

    Raises:
        ValueError: the sequence's camera count differs from the rig's; an image
            cannot be read (the message names the file) or has the wrong size.
    """
    if not isinstance(sequence, ImageSequence):
        raise ValueError(f"sequence must be a mcgeom.io.images.ImageSequence, got "
                         f"{type(sequence).__name__}")
    if sequence.n_cameras != len(rig):
        raise ValueError(f"{sequence.root}: the sequence has {sequence.n_cameras} cameras "
                         f"({', '.join(sequence.folders)}) but the rig has {len(rig)} "
                         f"({', '.join(rig.names)})")
    frames: Iterable = ([read_image(p) for p in paths] for paths in sequence.paths)
    if progress is not None:
        frames = progress(frames, total=sequence.n_frames, desc="frames")
    return tracks_from_images(rig, frames, features=features, n_features=n_features,
                              ratio=ratio, cross_camera=cross_camera,
                              geometric_check=geometric_check, threshold_px=threshold_px)
