"""mcgeom.io.images: the image-folder layouts of a rig's sequence and their errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

cv2 = pytest.importorskip("cv2")

from mcgeom.io.images import ImageSequence, find_image_sequence, read_image  # noqa: E402
from mcgeom.rig import Camera, Rig  # noqa: E402

W, H = 16, 12


def _rig(names=("left", "right")) -> Rig:
    K = np.array([[20.0, 0, W / 2], [0, 20.0, H / 2], [0, 0, 1]])
    return Rig(tuple(Camera(name=n, K=K, dist=[], model="pinhole", R=np.eye(3),
                            t=[-0.1 * i, 0, 0], width=W, height=H)
                     for i, n in enumerate(names)))


def _png(path: Path, value: int = 0) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    assert cv2.imwrite(str(path), np.full((H, W), value, np.uint8))


def _folders(root: Path, names, n_frames: int, ext: str = ".png") -> None:
    for c in names:
        for k in range(n_frames):
            _png(root / c / f"{k:04d}{ext}", 10 * k)


# ------------------------------------------------------------------ each layout

@pytest.mark.parametrize("names", [("left", "right"), ("cam0", "cam1")])
def test_camera_folders_by_rig_name_or_index(tmp_path, names):
    _folders(tmp_path, names, 4)
    seq = find_image_sequence(tmp_path, _rig())
    assert isinstance(seq, ImageSequence) and seq.layout == "folders"
    assert seq.folders == names and len(seq) == seq.n_frames == 4 and seq.n_cameras == 2
    assert seq.timestamps is None and seq.indices.tolist() == [0, 1, 2, 3]
    # rig order, sorted file names give the frame order
    assert seq.paths[2] == tuple(str(tmp_path / c / "0002.png") for c in names)
    assert seq.read(3, 1).shape == (H, W) and int(seq.read(3, 1)[0, 0]) == 30


def test_rig_order_not_alphabetical(tmp_path):
    _folders(tmp_path, ("b", "a"), 2)
    seq = find_image_sequence(tmp_path, _rig(("b", "a")))
    assert seq.folders == ("b", "a")
    assert seq.paths[0][0].endswith("b/0000.png")


@pytest.mark.parametrize("under_mav0", [False, True])
def test_euroc_layout(tmp_path, under_mav0):
    base = tmp_path / "mav0" if under_mav0 else tmp_path
    stamps = [1403715274312143104 + 50_000_000 * k for k in range(5)]
    for c in ("cam0", "cam1"):
        lines = ["#timestamp [ns],filename"]
        for s in stamps:
            _png(base / c / "data" / f"{s}.png")
            lines.append(f"{s},{s}.png")
        (base / c / "data.csv").write_text("\n".join(lines) + "\n")
        (base / c / "sensor.yaml").write_text("sensor_type: camera\n")
    seq = find_image_sequence(tmp_path, _rig(("cam0", "cam1")), start=1, step=2)
    assert seq.layout == "euroc" and seq.folders == ("cam0", "cam1")
    assert seq.indices.tolist() == [1, 3]
    np.testing.assert_allclose(seq.timestamps, np.array(stamps)[[1, 3]] * 1e-9, rtol=0, atol=1e-6)
    assert seq.paths[0][1] == str(base / "cam1" / "data" / f"{stamps[1]}.png")


def test_euroc_unsynchronised_cameras(tmp_path):
    for c, off in (("cam0", 0), ("cam1", 10_000_000)):
        rows = []
        for k in range(3):
            s = 1_000_000_000 * (k + 1) + off
            _png(tmp_path / c / "data" / f"{s}.png")
            rows.append(f"{s},{s}.png")
        (tmp_path / c / "data.csv").write_text("#timestamp [ns],filename\n" + "\n".join(rows))
    with pytest.raises(ValueError, match="cam1 is not synchronised with cam0"):
        find_image_sequence(tmp_path, _rig(("cam0", "cam1")))


def _kitti(root: Path, folders=("image_02", "image_03"), frames=range(3), stamps: bool = True):
    for f in folders:
        for k in frames:
            _png(root / f / "data" / f"{k:010d}.png")
        if stamps:
            (root / f / "timestamps.txt").write_text("".join(
                f"2011-09-26 13:17:59.{100000000 * k + 87203584:09d}\n"
                for k in range(10)))


def test_kitti_raw_layout_colour_pair_with_timestamps(tmp_path):
    _kitti(tmp_path, ("image_00", "image_01", "image_02", "image_03"), frames=range(2, 6))
    seq = find_image_sequence(tmp_path, _rig(("left", "right")), end=3)
    assert seq.layout == "kitti" and seq.folders == ("image_02", "image_03")
    assert seq.paths[0][0].endswith("image_02/data/0000000002.png")
    # image k is line k of timestamps.txt: frames 2, 3, 4 (a part of the drive)
    t0 = 1317043079.0
    np.testing.assert_allclose(seq.timestamps - t0, [0.087203584 + 0.1 * k for k in (2, 3, 4)],
                               atol=1e-6)


def test_kitti_raw_grey_pair_and_rig_names(tmp_path):
    _kitti(tmp_path, ("image_00", "image_01"), stamps=False)
    seq = find_image_sequence(tmp_path, _rig(("a", "b")))
    assert seq.folders == ("image_00", "image_01") and seq.timestamps is None
    _kitti(tmp_path, ("image_02", "image_03"), stamps=False)
    seq = find_image_sequence(tmp_path, _rig(("image_03", "image_00")))
    assert seq.folders == ("image_03", "image_00")


def test_kitti_rig_with_three_cameras(tmp_path):
    _kitti(tmp_path)
    with pytest.raises(ValueError, match="KITTI raw layout.*rig has 3 cameras"):
        find_image_sequence(tmp_path, _rig(("a", "b", "c")))


# ------------------------------------------------------------------ bad cases

def test_missing_camera_folder_names_expected_and_found(tmp_path):
    _folders(tmp_path, ("left",), 3)
    with pytest.raises(ValueError) as e:
        find_image_sequence(tmp_path, _rig())
    msg = str(e.value)
    assert str(tmp_path) in msg and "expected left, right" in msg and "cam0, cam1" in msg
    assert "found left" in msg and "missing right" in msg


def test_mismatched_camera_folders(tmp_path):
    _folders(tmp_path, ("front", "back"), 3)
    with pytest.raises(ValueError, match="expected left, right .* found back, front"):
        find_image_sequence(tmp_path, _rig())


def test_rig_with_fewer_cameras_than_folders(tmp_path):
    _folders(tmp_path, ("cam0", "cam1", "cam2"), 3)
    with pytest.raises(ValueError, match="rig has 2 cameras .* holds 3 .*extra: cam2"):
        find_image_sequence(tmp_path, _rig())


def test_different_numbers_of_images(tmp_path):
    _folders(tmp_path, ("left",), 3)
    _folders(tmp_path, ("right",), 5)
    with pytest.raises(ValueError, match=r"different numbers of images \(left: 3, right: 5\)"):
        find_image_sequence(tmp_path, _rig())


def test_non_image_file(tmp_path):
    _folders(tmp_path, ("left", "right"), 3)
    (tmp_path / "right" / "notes.txt").write_text("hello")
    (tmp_path / "right" / ".hidden").write_text("skipped")
    with pytest.raises(ValueError, match=r"notes\.txt is not an image file"):
        find_image_sequence(tmp_path, _rig())


def test_fewer_than_two_frames(tmp_path):
    _folders(tmp_path, ("left", "right"), 1)
    with pytest.raises(ValueError, match="1 frame.*at least 2 frames"):
        find_image_sequence(tmp_path, _rig())
    _folders(tmp_path, ("left", "right"), 5)
    with pytest.raises(ValueError, match="at least 2 frames"):
        find_image_sequence(tmp_path, _rig(), start=1, step=3, end=4)


@pytest.mark.parametrize("kw, match", [
    (dict(step=0), "step must be >= 1"),
    (dict(start=-1), "start -1 out of range"),
    (dict(start=5), "start 5 out of range"),
    (dict(end=6), "end 6 out of range"),
    (dict(start=3, end=3), "end 3 out of range"),
    (dict(step=1.5), "step must be an integer"),
])
def test_bad_slicing(tmp_path, kw, match):
    _folders(tmp_path, ("left", "right"), 5)
    with pytest.raises(ValueError, match=match):
        find_image_sequence(tmp_path, _rig(), **kw)


def test_slicing(tmp_path):
    _folders(tmp_path, ("left", "right"), 7)
    seq = find_image_sequence(tmp_path, _rig(), start=1, end=6, step=2)
    assert seq.indices.tolist() == [1, 3, 5]
    assert seq.paths[1][0].endswith("0003.png")


def test_not_a_folder_and_no_rig(tmp_path):
    with pytest.raises(ValueError, match="not a folder"):
        find_image_sequence(tmp_path / "nope", _rig())
    with pytest.raises(ValueError, match="rig must be a mcgeom.rig.Rig"):
        find_image_sequence(tmp_path, ["left", "right"])


def test_unreadable_image_names_the_file(tmp_path):
    _folders(tmp_path, ("left", "right"), 2)
    bad = tmp_path / "right" / "0001.png"
    bad.write_bytes(b"\x89PNG\r\n\x1a\n not really a png")
    seq = find_image_sequence(tmp_path, _rig())   # found: the layout does not decode
    with pytest.raises(ValueError, match=r"0001\.png: cannot read the image"):
        seq.read(1, 1)
    with pytest.raises(ValueError, match="image file not found"):
        read_image(tmp_path / "missing.png")
    with pytest.raises(ValueError, match="frame 2 out of range"):
        seq.read(2, 0)
