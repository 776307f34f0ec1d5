"""mcgeom.synth_views: the ch. 6.5.1 sequence (tracks along the image sequence,
open or closed loop) and the two scores of the experiment (similarity
alignment, spiral measure)."""

from __future__ import annotations

import numpy as np
import pytest

from mcgeom import synth
from mcgeom.synth_views import circle_sequence, similarity_align, spiral_measure


def _links_last_to_first(seq, m):
    """Number of tracks that observe both view m - 1 and view 0."""
    ends = [set(seq.view[seq.track == t].tolist()) for t in np.unique(seq.track)]
    return sum({0, m - 1} <= e for e in ends)


@pytest.mark.parametrize("closed", [False, True])
def test_tracks_follow_the_sequence_unless_the_loop_is_closed(closed):
    m = 40
    seq = circle_sequence(n_views=m, n_points=800, rng=5, closed_loop=closed)
    n = _links_last_to_first(seq, m)
    assert (n > 0) if closed else (n == 0)
    for t in np.unique(seq.track):      # 2-3 views, consecutive along the (cyclic) sequence
        v = set(seq.view[seq.track == t].tolist())
        assert 2 <= len(v) <= 3
        runs = [{(s + k) % m for k in range(len(v))} for s in range(m)]
        assert v in runs


def test_tracks_are_short_runs_of_consecutive_views_open():
    seq = circle_sequence(n_views=30, n_points=500, rng=6)
    for t in np.unique(seq.track):
        v = np.sort(seq.view[seq.track == t])
        np.testing.assert_array_equal(np.diff(v), 1)


def test_tracks_drawn_from_any_seeing_views():
    seq = circle_sequence(n_views=30, n_points=500, rng=6, track_views="any")
    gaps = []
    for t in np.unique(seq.track):
        v = np.sort(seq.view[seq.track == t])
        assert 2 <= v.size <= 3 and np.unique(v).size == v.size
        gaps.append(np.diff(v).max())
    assert max(gaps) > 1        # not only consecutive views
    with pytest.raises(ValueError, match="track_views"):
        circle_sequence(n_views=10, n_points=50, rng=1, track_views="wide")


def test_similarity_align_undoes_a_similarity():
    rng = np.random.default_rng(0)
    true = rng.normal(size=(30, 3)) * 10.0
    R = synth.random_rotation(rng)
    est = 0.03 * true @ R.T + np.array([1.0, -2.0, 5.0])
    aligned, rms = similarity_align(est, true)
    assert rms < 1e-10
    np.testing.assert_allclose(aligned, true, atol=1e-9)


def test_similarity_align_rms_and_no_reflection():
    rng = np.random.default_rng(1)
    true = rng.normal(size=(40, 3))
    mirrored = true * np.array([1.0, 1.0, -1.0])     # not a similarity of true
    aligned, rms = similarity_align(mirrored, true)
    assert rms == pytest.approx(np.sqrt(np.mean(np.sum((aligned - true) ** 2, axis=1))))
    assert rms > 0.1
    # the fitted map is a proper rotation: the aligned cloud keeps the handedness
    A, T = aligned - aligned.mean(0), mirrored - mirrored.mean(0)
    M = np.linalg.lstsq(T, A, rcond=None)[0]
    assert np.linalg.det(M) > 0


def test_spiral_measure_sees_folds_and_drift():
    ang = np.linspace(0, 2 * np.pi, 50, endpoint=False)
    circle = np.c_[np.cos(ang), np.sin(ang), np.zeros(50)]
    assert spiral_measure(circle, circle) < 1e-12
    folded = circle.copy()
    folded[25:] = 2 * folded[24] - folded[25:]          # the path turns back at view 24
    assert np.degrees(spiral_measure(folded, circle)) > 90
    spiral = circle * np.exp(-np.linspace(0, 1.5, 50))[:, None]
    assert 5 < np.degrees(spiral_measure(spiral, circle)) < 90
