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
    empty = (np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0))
    if len(desc1) < 2 or len(desc2) < 2:
        return empty
    bf = cv2.BFMatcher(norm, crossCheck=False)

    def best(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        nn = bf.knnMatch(a, b, k=2)
        idx = np.full(len(a), -1, np.int64)
        score = np.ones(len(a))
        for q, m in enumerate(nn):
            if len(m) == 2 and m[0].distance < ratio * m[1].distance:
                idx[q] = m[0].trainIdx
                score[q] = m[0].distance / m[1].distance if m[1].distance > 0 else 0.0
        return idx, score

    f, sf = best(desc1, desc2)
    b, _ = best(desc2, desc1)
    i1 = np.flatnonzero(f >= 0)
    i2 = f[i1]
    keep = b[i2] == i1
    return i1[keep], i2[keep], sf[i1[keep]]
