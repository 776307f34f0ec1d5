"""Feature tracks of a rig's image sequence: the data the front end hands to
the back end of the sequence pipeline.

One observation per row: track ``track[k]`` was seen at pixel ``pixels[k]``
(OpenCV convention, the raw -- distorted -- image of the camera; the rig
undistorts) by camera ``camera[k]`` of the rig in frame ``frame[k]``. A track
is one scene point: it may be seen by several cameras in one frame (matches
across cameras whose views overlap) and over several frames (matches between
consecutive frames of a camera). A track has at most one observation per
(frame, camera).

Two frames' correspondences for the two-frame estimators are the pairs of
observations of a track in both frames: every combination of the cameras
that saw it, so a track seen by cameras i and j in both frames gives the
intra-camera pairs (i, i), (j, j) and the cross-camera pairs (i, j), (j, i)
(cross-camera pairs fix the metric scale, thesis ch. 7.3.2).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["Tracks"]


def _int_column(name: str, a: Any, n: int) -> np.ndarray:
    arr = np.asarray(a)
    if arr.ndim != 1 or arr.shape[0] != n:
        raise ValueError(f"Tracks: {name} must have shape ({n},), got {arr.shape}")
    if arr.size and arr.dtype.kind not in "iu":
        raise ValueError(f"Tracks: {name} must hold integers, got dtype {arr.dtype}")
    if arr.size and arr.min() < 0:
        raise ValueError(f"Tracks: {name} holds a negative value ({int(arr.min())})")
    return np.ascontiguousarray(arr, dtype=np.int64)


@dataclass(frozen=True)
class Tracks:
    """Observations of feature tracks over ``n_frames`` frames of a rig.

    ``track``, ``frame``, ``camera``: (N,) int64; ``pixels``: (N, 2) float64
    pixels of the raw image of that camera. Frames are 0 .. n_frames - 1.
    """

    track: np.ndarray
    frame: np.ndarray
    camera: np.ndarray
    pixels: np.ndarray
    n_frames: int

    def __post_init__(self) -> None:
        px = np.asarray(self.pixels, dtype=np.float64) if np.size(self.pixels) else \
            np.zeros((0, 2))
        if px.ndim != 2 or px.shape[1] != 2:
            raise ValueError(f"Tracks: pixels must have shape (N, 2), got {px.shape}")
        if not np.all(np.isfinite(px)):
            raise ValueError("Tracks: pixels contain NaN or inf")
        n = px.shape[0]
        object.__setattr__(self, "pixels", np.ascontiguousarray(px))
        for name in ("track", "frame", "camera"):
            object.__setattr__(self, name, _int_column(name, getattr(self, name), n))
        if isinstance(self.n_frames, bool) or int(self.n_frames) != self.n_frames \
                or self.n_frames < 0:
            raise ValueError(f"Tracks: n_frames must be a non-negative integer, "
                             f"got {self.n_frames!r}")
        object.__setattr__(self, "n_frames", int(self.n_frames))
        if n and self.frame.max() >= self.n_frames:
            raise ValueError(f"Tracks: frame index {int(self.frame.max())} >= n_frames "
                             f"{self.n_frames}")
        if n:
            key = (self.track * (self.n_frames + 1) + self.frame) * (int(self.camera.max()) + 1) \
                + self.camera
            if np.unique(key).size != n:
                raise ValueError("Tracks: a track has two observations in the same frame "
                                 "and camera")

    def __len__(self) -> int:
        return int(self.pixels.shape[0])

    @property
    def n_tracks(self) -> int:
        """Number of distinct tracks (scene points)."""
        return int(np.unique(self.track).size)

    def in_frames(self, first: int, last: int) -> "Tracks":
        """The observations of frames ``first .. last`` (inclusive), renumbered
        from 0 (tracks keep their ids)."""
        if not 0 <= first <= last < self.n_frames:
            raise ValueError(f"Tracks.in_frames: need 0 <= first <= last < {self.n_frames}, "
                             f"got {first}, {last}")
        keep = (self.frame >= first) & (self.frame <= last)
        return Tracks(self.track[keep], self.frame[keep] - first, self.camera[keep],
                      self.pixels[keep], last - first + 1)

    def correspondences(self, frame1: int, frame2: int
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Pixel correspondences between two frames: ``(pixels1, pixels2, cam1,
        cam2, track)``, one row per pair of observations of a track in
        ``frame1`` and ``frame2`` (every combination of the cameras that saw
        it in each frame), as ``mcgeom.cv.estimate`` takes them."""
        a = np.flatnonzero(self.frame == frame1)
        b = np.flatnonzero(self.frame == frame2)
        # join on the track id: sort both sides, pair every observation of a
        # track in frame1 with every one in frame2
        a = a[np.argsort(self.track[a], kind="stable")]
        b = b[np.argsort(self.track[b], kind="stable")]
        ta, tb = self.track[a], self.track[b]
        lo = np.searchsorted(tb, ta, side="left")
        hi = np.searchsorted(tb, ta, side="right")
        counts = hi - lo
        ia = np.repeat(a, counts)
        starts = np.repeat(lo, counts)
        offs = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
        ib = b[starts + offs]
        return (self.pixels[ia], self.pixels[ib], self.camera[ia], self.camera[ib],
                self.track[ia])
