"""Descriptor matching of the front end (mcgeom.sequence.features.match_descriptors):
mutual nearest neighbours passing Lowe's ratio test both ways, against a brute-force
reference that computes every distance directly."""

from __future__ import annotations

import numpy as np
import pytest

cv2 = pytest.importorskip("cv2")

from mcgeom.sequence import features  # noqa: E402
from mcgeom.sequence.features import match_descriptors  # noqa: E402


def _reference(desc1: np.ndarray, desc2: np.ndarray, hamming: bool, ratio: float):
    """Every distance by its definition, then the ratio test both ways and
    the mutual check, as match_descriptors documents them."""
    if hamming:
        x = np.unpackbits(desc1[:, None, :] ^ desc2[None, :, :], axis=2)
        dist = x.sum(axis=2).astype(float)
    else:
        diff = desc1[:, None, :].astype(float) - desc2[None, :, :].astype(float)
        dist = np.sqrt((diff * diff).sum(axis=2))

    def one_way(d):
        order = np.argsort(d, axis=1, kind="stable")
        near, second = d[np.arange(len(d)), order[:, 0]], d[np.arange(len(d)), order[:, 1]]
        return order[:, 0], near < ratio * second, near, second

    j12, ok12, near, second = one_way(dist)
    j21, ok21, _, _ = one_way(dist.T)
    i1 = np.flatnonzero(ok12 & ok21[j12] & (j21[j12] == np.arange(len(desc1))))
    return i1, j12[i1], near[i1] / second[i1]


def _sift_like(rng, n: int, base=None) -> np.ndarray:
    """Integer-valued float32 descriptors in [0, 255], as cv2.SIFT gives; with
    ``base``, noisy copies of its rows (true matches) in shuffled order."""
    if base is None:
        return rng.integers(0, 256, size=(n, 128)).astype(np.float32)
    d = base[rng.permutation(len(base))[:n]] + rng.integers(-20, 21, size=(n, 128))
    return np.clip(d, 0, 255).astype(np.float32)


@pytest.mark.parametrize("block_floats", [1 << 22, 5 * 300])   # one block; 5-row blocks
def test_sift_matches_equal_brute_force(monkeypatch, block_floats):
    monkeypatch.setattr(features, "_BLOCK_FLOATS", block_floats)
    rng = np.random.default_rng(4)
    d1 = _sift_like(rng, 250)
    d2 = np.vstack([_sift_like(rng, 200, d1), _sift_like(rng, 100)])
    i1, i2, score = match_descriptors(d1, d2, cv2.NORM_L2)
    r1, r2, rscore = _reference(d1, d2, False, 0.8)
    assert len(i1) > 150                       # most true matches found
    np.testing.assert_array_equal(i1, r1)
    np.testing.assert_array_equal(i2, r2)
    np.testing.assert_allclose(score, rscore, rtol=1e-12)


@pytest.mark.parametrize("block_floats", [1 << 22, 7 * 90, 90])   # 1, 7 and 1 rows a block
def test_two_nearest_both_ways_equal_the_distance_matrix(monkeypatch, block_floats):
    """The blocked search's nearest index and its two distances, per row and
    per column (merged across blocks), against the full matrix."""
    monkeypatch.setattr(features, "_BLOCK_FLOATS", block_floats)
    rng = np.random.default_rng(6)
    d1, d2 = _sift_like(rng, 60), _sift_like(rng, 90)
    diff = d1[:, None, :].astype(float) - d2[None, :, :].astype(float)
    dist = np.sqrt((diff * diff).sum(axis=2))
    i12, n12, s12, i21, n21, s21 = features._nearest_two_l2(d1, d2)
    for d, i, near, second in ((dist, i12, n12, s12), (dist.T, i21, n21, s21)):
        srt = np.sort(d, axis=1)
        np.testing.assert_array_equal(i, d.argmin(axis=1))
        np.testing.assert_allclose(near, srt[:, 0], rtol=1e-12)
        np.testing.assert_allclose(second, srt[:, 1], rtol=1e-12)


def test_orb_matches_equal_brute_force():
    rng = np.random.default_rng(5)
    d1 = rng.integers(0, 256, size=(150, 32), dtype=np.uint8)
    flips = rng.random((120, 32 * 8)) < 0.08
    d2 = np.vstack([np.packbits(np.unpackbits(d1[:120], axis=1) ^ flips, axis=1),
                    rng.integers(0, 256, size=(60, 32), dtype=np.uint8)])
    i1, i2, score = match_descriptors(d1, d2, cv2.NORM_HAMMING)
    r1, r2, rscore = _reference(d1, d2, True, 0.8)
    assert len(i1) > 100
    np.testing.assert_array_equal(i1, r1)
    np.testing.assert_array_equal(i2, r2)
    np.testing.assert_allclose(score, rscore, rtol=1e-6)


def test_ratio_and_degenerate_inputs():
    d = np.eye(4, 128, dtype=np.float32) * 100
    # identical descriptors on the other side: nearest 0, second 100 -> kept
    i1, i2, s = match_descriptors(d, d.copy(), cv2.NORM_L2)
    assert list(i1) == [0, 1, 2, 3] and list(i2) == [0, 1, 2, 3] and np.all(s == 0)
    # a ratio of 0 is refused, fewer than two descriptors give no matches
    with pytest.raises(ValueError, match="ratio"):
        match_descriptors(d, d, cv2.NORM_L2, ratio=0.0)
    assert len(match_descriptors(d[:1], d, cv2.NORM_L2)[0]) == 0
