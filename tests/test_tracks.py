"""mcgeom.sequence.Tracks: validation and the two-frame correspondences."""

from __future__ import annotations

import numpy as np
import pytest

from mcgeom.sequence import Tracks


def _tracks() -> Tracks:
    # track 0: cameras 0 and 1 in frames 0 and 1; track 1: camera 1 in frames 0, 1, 2;
    # track 2: camera 0 in frame 1 only
    rows = [(0, 0, 0), (0, 0, 1), (0, 1, 0), (0, 1, 1), (1, 0, 1), (1, 1, 1), (1, 2, 1),
            (2, 1, 0)]
    t, f, c = np.array(rows).T
    px = np.column_stack([np.arange(len(rows)), 10.0 * np.arange(len(rows))])
    return Tracks(t, f, c, px, 3)


def test_correspondences_pair_every_camera_combination():
    tr = _tracks()
    p1, p2, c1, c2, track = tr.correspondences(0, 1)
    got = sorted(zip(track.tolist(), c1.tolist(), c2.tolist(), p1[:, 0].tolist(),
                     p2[:, 0].tolist()))
    # track 0: (0,0) (0,1) (1,0) (1,1); track 1: (1,1)
    assert got == [(0, 0, 0, 0.0, 2.0), (0, 0, 1, 0.0, 3.0), (0, 1, 0, 1.0, 2.0),
                   (0, 1, 1, 1.0, 3.0), (1, 1, 1, 4.0, 5.0)]
    p1, p2, c1, c2, track = tr.correspondences(1, 2)
    assert track.tolist() == [1] and p1[0, 0] == 5.0 and p2[0, 0] == 6.0
    assert len(tr.correspondences(0, 2)[0]) == 1          # only track 1 spans frames 0..2


def test_n_tracks_counts_distinct_tracks():
    assert _tracks().n_tracks == 3


def test_in_frames_renumbers():
    sub = _tracks().in_frames(1, 2)
    assert sub.n_frames == 2 and len(sub) == 5 and sub.frame.min() == 0


@pytest.mark.parametrize("change, message", [
    (dict(pixels=np.full((8, 2), np.nan)), "NaN"),
    (dict(frame=np.full(8, 3)), "n_frames"),
    (dict(camera=np.zeros(8, int)), "same frame and camera"),
    (dict(track=np.zeros(7, int)), "shape"),
    (dict(n_frames=-1), "non-negative"),
])
def test_bad_tracks_are_value_errors(change, message):
    tr = _tracks()
    args = dict(track=tr.track, frame=tr.frame, camera=tr.camera, pixels=tr.pixels,
                n_frames=tr.n_frames)
    args.update(change)
    with pytest.raises(ValueError, match=message):
        Tracks(**args)
