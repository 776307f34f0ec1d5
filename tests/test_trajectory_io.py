"""mcgeom.io.trajectory: TUM and KITTI trajectory files (round trips, evo's
readers, malformed files, atomic writes)."""

from __future__ import annotations

import os

import numpy as np
import pytest

from mcgeom import _core
from mcgeom.io import trajectory as tio


def random_poses(n: int, seed: int = 0) -> np.ndarray:
    """n world_from_rig poses with rotations spread over SO(3) (including w < 0
    quaternions before the sign convention) and positions of tens of metres."""
    rng = np.random.default_rng(seed)
    T = np.tile(np.eye(4), (n, 1, 1))
    for k in range(n):
        q = rng.normal(size=4)
        T[k, :3, :3] = _core.rot_from_quat(q)
        T[k, :3, 3] = rng.uniform(-30, 30, 3)
    return T


def test_tum_round_trip_is_exact(tmp_path):
    T = random_poses(20)
    ts = 1403636580.0 + 0.05 * np.arange(20)
    path = tmp_path / "est.txt"
    tio.write_tum(path, T, ts, comment="estimate\nsecond line")
    text = path.read_text()
    assert text.startswith("# estimate\n# second line\n# timestamp tx ty tz qx qy qz qw")
    ts2, T2 = tio.read_tum(path)
    np.testing.assert_array_equal(ts2, ts)
    np.testing.assert_array_equal(T2[:, :3, 3], T[:, :3, 3])
    np.testing.assert_allclose(T2, T, atol=1e-15)


def test_tum_quaternion_is_hamilton_w_last_with_w_positive(tmp_path):
    # a rotation of 90 deg about +z: Hamilton q = (w, x, y, z) = (c, 0, 0, s), c = s = 1/sqrt2
    T = np.eye(4)[None].copy()
    T[0, :3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
    T[0, :3, 3] = [1, 2, 3]
    # a rotation of 270 deg about +z, whose quaternion with w >= 0 is about -z
    T = np.concatenate([T, T])
    T[1, :3, :3] = T[0, :3, :3].T
    tio.write_tum(tmp_path / "q.txt", T)
    rows = np.loadtxt(tmp_path / "q.txt")
    h = np.sqrt(0.5)
    np.testing.assert_allclose(rows[0], [0, 1, 2, 3, 0, 0, h, h], atol=1e-15)
    np.testing.assert_allclose(rows[1], [1, 1, 2, 3, 0, 0, -h, h], atol=1e-15)


def test_default_timestamps_are_frame_indices(tmp_path):
    tio.write_tum(tmp_path / "t.txt", random_poses(3))
    ts, _ = tio.read_tum(tmp_path / "t.txt")
    np.testing.assert_array_equal(ts, [0.0, 1.0, 2.0])


def test_kitti_round_trip_is_exact(tmp_path):
    T = random_poses(15, seed=1)
    tio.write_kitti(tmp_path / "k.txt", T)
    lines = (tmp_path / "k.txt").read_text().splitlines()
    assert len(lines) == 15 and all(len(line.split()) == 12 for line in lines)
    np.testing.assert_array_equal(tio.read_kitti(tmp_path / "k.txt"), T)


def test_evo_reads_what_we_write(tmp_path):
    file_interface = pytest.importorskip("evo.tools.file_interface")
    T = random_poses(12, seed=2)
    ts = np.arange(12) * 0.1
    tio.write_tum(tmp_path / "e.tum", T, ts)
    tio.write_kitti(tmp_path / "e.kitti", T)
    traj = file_interface.read_tum_trajectory_file(str(tmp_path / "e.tum"))
    np.testing.assert_array_equal(traj.timestamps, ts)
    np.testing.assert_allclose(np.asarray(traj.poses_se3), T, atol=1e-14)
    path = file_interface.read_kitti_poses_file(str(tmp_path / "e.kitti"))
    np.testing.assert_array_equal(np.asarray(path.poses_se3), T)


def test_we_read_what_evo_writes(tmp_path):
    file_interface = pytest.importorskip("evo.tools.file_interface")
    from evo.core.trajectory import PosePath3D, PoseTrajectory3D
    T = random_poses(10, seed=3)
    ts = 100.0 + np.arange(10) * 0.5
    file_interface.write_tum_trajectory_file(str(tmp_path / "w.tum"),
                                             PoseTrajectory3D(poses_se3=list(T), timestamps=ts))
    file_interface.write_kitti_poses_file(str(tmp_path / "w.kitti"), PosePath3D(poses_se3=list(T)))
    ts2, T2 = tio.read_tum(tmp_path / "w.tum")
    np.testing.assert_allclose(ts2, ts, rtol=1e-12)
    np.testing.assert_allclose(T2, T, atol=1e-6)   # evo prints fewer digits
    np.testing.assert_allclose(tio.read_kitti(tmp_path / "w.kitti"), T, atol=1e-6)


def test_comments_and_blank_lines_are_skipped(tmp_path):
    p = tmp_path / "c.txt"
    p.write_text("# header\n\n0 1 2 3 0 0 0 1\n   \n# mid\n1.5 4 5 6 0 0 0 -1\n")
    ts, T = tio.read_tum(p)
    np.testing.assert_array_equal(ts, [0.0, 1.5])
    np.testing.assert_array_equal(T[1, :3, 3], [4, 5, 6])
    np.testing.assert_allclose(T[1, :3, :3], np.eye(3))   # q and -q: the same rotation


@pytest.mark.parametrize("name, text, message", [
    ("t.txt", "0 1 2 3 0 0 0 1\n1 1 2 3 0 0 1\n", r"t\.txt:2: a TUM line has 8 numbers .* got 7"),
    ("t.txt", "0 1 2 3 0 0 0 1\n1 1 2 x 0 0 0 1\n", r"t\.txt:2: 'x' is not a number"),
    ("t.txt", "# c\n0 1 2 3 0 0 0 2\n", r"t\.txt:2: the quaternion .* has norm 2, not 1"),
    ("t.txt", "0 1 2 3 0 0 0 0\n", r"t\.txt:1: the quaternion .* has norm 0"),
    ("t.txt", "0 1 2 nan 0 0 0 1\n", r"t\.txt:1: non-finite number"),
    ("t.txt", "1 1 2 3 0 0 0 1\n1 1 2 3 0 0 0 1\n", r"t\.txt:2: timestamp 1\.0 does not follow"),
    ("t.txt", "# only a comment\n", r"t\.txt: no poses"),
    ("k.kitti", "1 0 0 0 0 1 0 0 0 0 1\n", r"k\.kitti:1: a KITTI line has 12 numbers .* got 11"),
    ("k.kitti", "0 1 0 0 0 0 0 1 0 0 0 0 1\n", r"k\.kitti:1: .* got 13 \(a leading timestamp"),
    ("k.kitti", "1 0 0 0 0 1 0 0 0 0 1 0\n2 0 0 0 0 1 0 0 0 0 1 0\n",
     r"k\.kitti:2: its 3x3 part is not a rotation"),
    ("k.kitti", "1 0 0 0 0 1 0 0 0 0 -1 0\n", r"k\.kitti:1: .*not a rotation .*det = -1"),
])
def test_malformed_files_name_file_and_line(tmp_path, name, text, message):
    p = tmp_path / name
    p.write_text(text)
    reader = tio.read_kitti if name.endswith(".kitti") else tio.read_tum
    with pytest.raises(ValueError, match=message):
        reader(p)


def test_kitti_benchmark_precision_is_accepted(tmp_path):
    # the first lines of KITTI odometry's poses/00.txt: 7 significant digits
    p = tmp_path / "00.txt"
    p.write_text("1.000000e+00 9.043680e-12 2.326809e-11 5.551115e-17 9.043683e-12 "
                 "1.000000e+00 2.392370e-10 3.330669e-16 2.326810e-11 2.392370e-10 "
                 "9.999999e-01 -4.440892e-16\n"
                 "9.999978e-01 5.272628e-04 -2.066935e-03 -4.690294e-02 -5.296506e-04 "
                 "9.999992e-01 -1.154865e-03 -2.839928e-02 2.066324e-03 1.155958e-03 "
                 "9.999971e-01 8.586941e-01\n")
    T = tio.read_kitti(p)
    assert T.shape == (2, 4, 4) and T[1, 2, 3] == pytest.approx(0.8586941)


@pytest.mark.parametrize("poses, ts, message", [
    (np.eye(4), None, r"got one \(4, 4\) matrix"),
    (np.zeros((0, 4, 4)), None, r"N >= 1"),
    (np.full((2, 4, 4), np.nan), None, r"non-finite"),
    (np.tile(np.diag([1.0, 1.0, 2.0, 1.0]), (2, 1, 1)), None, r"pose 0 is not rigid"),
    (np.tile(np.eye(4), (2, 1, 1)), [0.0, 0.0], r"timestamps must increase strictly"),
    (np.tile(np.eye(4), (2, 1, 1)), [0.0], r"timestamps must have shape \(2,\)"),
])
def test_bad_poses_are_refused_and_nothing_is_written(tmp_path, poses, ts, message):
    p = tmp_path / "out.txt"
    with pytest.raises(ValueError, match=message):
        tio.write_tum(p, poses, ts)
    assert not p.exists()
    assert os.listdir(tmp_path) == []


def test_a_failed_write_keeps_the_old_file(tmp_path, monkeypatch):
    p = tmp_path / "traj.txt"
    tio.write_kitti(p, random_poses(2))
    before = p.read_bytes()

    def broken_replace(src, dst):
        raise OSError("disk full (simulated)")

    monkeypatch.setattr(tio.os, "replace", broken_replace)
    with pytest.raises(OSError, match="simulated"):
        tio.write_kitti(p, random_poses(5))
    assert p.read_bytes() == before
    assert os.listdir(tmp_path) == ["traj.txt"]     # no temporary file left behind
