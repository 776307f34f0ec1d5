"""Feature detection, description and descriptor matching with OpenCV (the front end's
image-level half; :mod:`mcgeom.sequence.frontend` adds the geometry and the tracks).

SIFT (Lowe 2004, ``cv2.SIFT_create``, L2 descriptor distance) by default; ORB (Rublee
et al. 2011, ``cv2.ORB_create``, Hamming distance) as a faster option. Matching is
brute force (exact, deterministic), with Lowe's ratio test applied both ways and a
mutual-nearest-neighbour check.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Optional

import numpy as np

from mcgeom.validation import check_int

__all__ = ["FEATURE_KINDS", "Keypoints", "FeatureDetector", "match_descriptors"]

#: the detector / descriptor kinds of :class:`FeatureDetector`
FEATURE_KINDS = ("sift", "orb")


@dataclass(frozen=True)
class Keypoints:
    """The features of one image.

    Attributes:
        pixels: (N, 2) float64 keypoint positions, pixels of the raw (distorted)
            image, OpenCV convention (centre of the top-left pixel at (0, 0)).
        descriptors: (N, D) descriptors (float32 for SIFT, uint8 for ORB).
    """

    pixels: np.ndarray
    descriptors: np.ndarray

    def __len__(self) -> int:
        return int(self.pixels.shape[0])


def _grey(image: Any, what: str) -> np.ndarray:
    """An (H, W) uint8 view of a grey, BGR or BGRA uint8 image; ValueError otherwise."""
    import cv2

    img = np.asarray(image)
    if img.dtype != np.uint8:
        raise ValueError(f"{what}: images must be uint8 (grey or BGR), got dtype {img.dtype}")
    if img.ndim == 3 and img.shape[2] in (3, 4):
        img = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY if img.shape[2] == 3 else cv2.COLOR_BGRA2GRAY)
    elif img.ndim == 3 and img.shape[2] == 1:
        img = img[:, :, 0]
    if img.ndim != 2 or min(img.shape) < 1:
        raise ValueError(f"{what}: expected an (H, W) or (H, W, 3) image, got shape "
                         f"{np.shape(image)}")
    return np.ascontiguousarray(img)


class FeatureDetector:
    """Detect keypoints and compute descriptors in images.

    Args:
        kind: ``"sift"`` (default) or ``"orb"``.
        n_features: at most this many keypoints per image (the strongest).
    """

    def __init__(self, kind: str = "sift", n_features: int = 4000) -> None:
        import cv2

        if kind not in FEATURE_KINDS:
            raise ValueError(f"features must be one of {', '.join(FEATURE_KINDS)}, got {kind!r}")
        n = check_int("n_features", n_features)
        if n < 1:
            raise ValueError(f"n_features must be >= 1, got {n}")
        if kind == "sift" and not hasattr(cv2, "SIFT_create"):
            raise ValueError("features='sift' needs OpenCV >= 4.4 (cv2.SIFT_create); "
                             "use features='orb'")
        self.kind = kind
        self.n_features = n
        self._det = cv2.SIFT_create(nfeatures=n) if kind == "sift" else cv2.ORB_create(nfeatures=n)
        #: the descriptor distance of the kind (cv2.NORM_L2 or cv2.NORM_HAMMING)
        self.norm = cv2.NORM_L2 if kind == "sift" else cv2.NORM_HAMMING

    def detect(self, image: Any, size: Optional[tuple[int, int]] = None,
               what: str = "image") -> Keypoints:
        """Keypoints and descriptors of one image.

        Args:
            image: (H, W) grey or (H, W, 3) BGR uint8 array.
            size: the expected ``(width, height)`` in pixels (the calibrated
                camera's), checked when given.
            what: how messages name the image.

        Raises:
            ValueError: not a uint8 grey/BGR image, or not of the expected size.
        """
        img = _grey(image, what)
        if size is not None and (img.shape[1], img.shape[0]) != tuple(size):
            raise ValueError(f"{what}: the image is {img.shape[1]}x{img.shape[0]} pixels but "
                             f"the camera is calibrated for {size[0]}x{size[1]}")
        kps, desc = self._det.detectAndCompute(img, None)
        pts = np.array([k.pt for k in kps], dtype=np.float64).reshape(-1, 2)
        if desc is None:
            width = 128 if self.kind == "sift" else 32
            desc = np.zeros((0, width), np.float32 if self.kind == "sift" else np.uint8)
        return Keypoints(np.ascontiguousarray(pts), desc)


#: floats of one block of the L2 distance matrix (16 MB): rows of desc1 at a time
_BLOCK_FLOATS = 1 << 22


def _nearest_two_l2(desc1: np.ndarray, desc2: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                               np.ndarray, np.ndarray, np.ndarray]:
    """The two nearest neighbours by L2 distance, both ways, from one distance matrix.

    ``|a - b|^2 = |a|^2 + |b|^2 - 2 a.b`` by one BLAS product per block of rows
    (cv2.BFMatcher's knnMatch computes the whole matrix once per direction and
    hands back one Python object per match: 3x slower on the demo's
    SIFT features). OpenCV's SIFT
    descriptors are integers in [0, 255], so these float32 sums (at most
    128 * 255^2 < 2^24) are exact.

    Returns:
        ``(i12, d12, e12, i21, d21, e21)``: per row of desc1 the index of its
        nearest row of desc2, the distances to it and to the second nearest;
        the same per row of desc2 against desc1.
    """
    a = np.ascontiguousarray(desc1, dtype=np.float32)
    b = np.ascontiguousarray(desc2, dtype=np.float32)
    n1, n2 = len(a), len(b)
    na = np.einsum("ij,ij->i", a, a)
    nb = np.einsum("ij,ij->i", b, b)
    i12, d12, e12 = np.empty(n1, np.int64), np.empty(n1), np.empty(n1)
    i21, d21, e21 = np.zeros(n2, np.int64), np.full(n2, np.inf), np.full(n2, np.inf)
    cols = np.arange(n2)
    step = max(1, _BLOCK_FLOATS // n2)
    for s in range(0, n1, step):
        e = min(n1, s + step)
        d = (a[s:e] @ b.T) * np.float32(-2.0)
        d += na[s:e, None]
        d += nb[None, :]
        np.maximum(d, 0.0, out=d)
        rows = np.arange(e - s)
        # per row: nearest, then the second with the nearest masked
        j = d.argmin(axis=1)
        best = d[rows, j]
        d[rows, j] = np.inf
        i12[s:e], d12[s:e], e12[s:e] = j, best, d.min(axis=1)
        d[rows, j] = best
        # per column, this block's two nearest merged with the running two
        k = d.argmin(axis=0)
        c0 = d[k, cols].astype(np.float64)
        d[k, cols] = np.inf
        c1 = d.min(axis=0).astype(np.float64)
        e21[:] = np.minimum(np.maximum(d21, c0), np.minimum(e21, c1))
        better = c0 < d21
        i21[better] = k[better] + s
        d21[better] = c0[better]
    return i12, np.sqrt(d12), np.sqrt(e12), i21, np.sqrt(d21), np.sqrt(e21)


def _nearest_two_cv(desc1: np.ndarray, desc2: np.ndarray, norm: int
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                               np.ndarray, np.ndarray, np.ndarray]:
    """As :func:`_nearest_two_l2` by cv2.BFMatcher's knnMatch (any norm, e.g.
    Hamming for ORB)."""
    import cv2

    bf = cv2.BFMatcher(norm, crossCheck=False)

    def one_way(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        two = bf.knnMatch(x, y, k=2)
        # a query with fewer than two neighbours fails the ratio test (inf < inf)
        idx = np.array([m[0].trainIdx if m else 0 for m in two], np.int64)
        d = np.array([(m[0].distance, m[1].distance) if len(m) == 2 else (np.inf, np.inf)
                      for m in two], np.float64).reshape(-1, 2)
        return idx, d[:, 0], d[:, 1]

    return (*one_way(desc1, desc2), *one_way(desc2, desc1))


def match_descriptors(desc1: np.ndarray, desc2: np.ndarray, norm: int, ratio: float = 0.8
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mutual nearest neighbours that pass Lowe's ratio test both ways.

    Args:
        desc1, desc2: (N1, D), (N2, D) descriptors of the two images.
        norm: ``cv2.NORM_L2`` (SIFT) or ``cv2.NORM_HAMMING`` (ORB).
        ratio: Lowe's ratio (Lowe 2004, sec. 7.1): the nearest neighbour must be
            closer than ``ratio`` times the second nearest, in (0, 1].

    Returns:
        ``(i1, i2, score)``: int64 indices of the matched descriptors and, per
        match, the forward distance ratio (nearest / second nearest, lower is more
        distinctive).
    """
    import cv2

    if not 0 < ratio <= 1:
        raise ValueError(f"ratio must be in (0, 1], got {ratio}")
    if len(desc1) < 2 or len(desc2) < 2:
        return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0)
    if norm == cv2.NORM_L2:
        i12, d12, e12, i21, d21, e21 = _nearest_two_l2(desc1, desc2)
    else:
        i12, d12, e12, i21, d21, e21 = _nearest_two_cv(desc1, desc2, norm)
    # the ratio test both ways, then the mutual check
    fwd = d12 < ratio * e12
    back = d21 < ratio * e21
    i1 = np.flatnonzero(fwd)
    i2 = i12[i1]
    keep = back[i2] & (i21[i2] == i1)
    i1, i2 = i1[keep], i2[keep]
    score = np.divide(d12[i1], e12[i1], out=np.zeros(len(i1)), where=e12[i1] > 0)
    return i1, i2, score
