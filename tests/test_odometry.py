"""``mcgeom odometry`` end to end on a short rendered sequence (seconds), its
outputs read back by evo, and bad input: a clear error naming what is wrong,
exit code 2, and nothing written."""

from __future__ import annotations

import csv
import shutil

import numpy as np
import pytest

from mcgeom import cli
from mcgeom.experiments.render import render_sequence, surround_rig
from mcgeom.io.trajectory import read_tum
from mcgeom.sequence.run import run_odometry


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    """Six frames of the demo's rig and courtyard, 0.9 m apart, at a small size."""
    root = tmp_path_factory.mktemp("rendered")
    return render_sequence(root, n_frames=6, step=0.9, rig=surround_rig(320, 240))


def test_pipeline_on_rendered_images_is_metric_and_accurate(rendered, tmp_path):
    run = run_odometry(rendered.rig_path, rendered.out_dir / "images", tmp_path / "out",
                       gt=rendered.groundtruth_path)
    traj = run.trajectory
    assert traj.n_frames == 6 and traj.known.all()
    assert set(traj.status) <= {"metric", "carried"}
    # 4.5 m of path: centimetres, not a scale off by a factor
    assert run.errors.ate["rmse"] < 0.05
    assert abs(run.errors.scale_drift_percent) < 3.0
    for name in ("trajectory_tum.txt", "trajectory_kitti.txt", "steps.csv", "trajectory.png",
                 "errors.txt", "errors.csv", "rpe.csv", "trajectory_frames.txt"):
        assert (tmp_path / "out" / name).stat().st_size > 0, name
    ts, poses = read_tum(tmp_path / "out" / "trajectory_tum.txt")
    assert np.allclose(poses, traj.poses) and np.array_equal(ts, np.arange(6))
    with open(tmp_path / "out" / "steps.csv") as f:
        rows = list(csv.DictReader(f))
    assert [r["scale"] for r in rows] == list(traj.status)
    assert all(float(r["translation_m"]) > 0.8 for r in rows)
    with open(tmp_path / "out" / "rpe.csv") as f:
        rpe = list(csv.DictReader(f))
    assert len(rpe) == 5 and all(float(r["translation_error_m"]) < 0.05 for r in rpe)


def test_evo_reads_the_trajectory(rendered, tmp_path):
    file_interface = pytest.importorskip("evo.tools.file_interface")
    run_odometry(rendered.rig_path, rendered.out_dir / "images", tmp_path / "out")
    traj = file_interface.read_tum_trajectory_file(str(tmp_path / "out" / "trajectory_tum.txt"))
    _, ours = read_tum(tmp_path / "out" / "trajectory_tum.txt")
    assert np.allclose(traj.poses_se3, ours, atol=1e-12)


def _odometry(capsys, *args: str) -> tuple[int, str]:
    code = cli.main(["odometry", *args])
    return code, capsys.readouterr().err


def test_missing_camera_folder(rendered, tmp_path, capsys):
    images = tmp_path / "images"
    shutil.copytree(rendered.out_dir / "images", images)
    shutil.rmtree(images / "rear_left")
    code, err = _odometry(capsys, "--rig", str(rendered.rig_path), "--images", str(images),
                          "--out", str(tmp_path / "out"))
    assert code == 2 and "rear_left" in err and "error" in err
    assert not (tmp_path / "out").exists()


def test_mismatched_image_counts(rendered, tmp_path, capsys):
    images = tmp_path / "images"
    shutil.copytree(rendered.out_dir / "images", images)
    (images / "front" / "000005.png").unlink()
    code, err = _odometry(capsys, "--rig", str(rendered.rig_path), "--images", str(images),
                          "--out", str(tmp_path / "out"))
    assert code == 2 and "front" in err
    assert not (tmp_path / "out").exists()


def test_unreadable_image(rendered, tmp_path, capsys):
    images = tmp_path / "images"
    shutil.copytree(rendered.out_dir / "images", images)
    (images / "front" / "000003.png").write_bytes(b"not a png")
    code, err = _odometry(capsys, "--rig", str(rendered.rig_path), "--images", str(images),
                          "--out", str(tmp_path / "out"))
    assert code == 2 and "000003.png" in err
    assert not (tmp_path / "out").exists()


def test_rig_whose_cameras_do_not_match_the_folders(rendered, tmp_path, capsys):
    from mcgeom.io import save_mcgeom_json
    from mcgeom.rig import Rig
    rig = Rig(list(rendered.rig.cameras[:3]))
    save_mcgeom_json(rig, tmp_path / "rig3.json")
    code, err = _odometry(capsys, "--rig", str(tmp_path / "rig3.json"), "--images",
                          str(rendered.out_dir / "images"), "--out", str(tmp_path / "out"))
    assert code == 2 and "error" in err
    assert not (tmp_path / "out").exists()


def test_fewer_than_two_frames(rendered, tmp_path, capsys):
    code, err = _odometry(capsys, "--rig", str(rendered.rig_path), "--images",
                          str(rendered.out_dir / "images"), "--start", "5",
                          "--out", str(tmp_path / "out"))
    assert code == 2 and "2 frames" in err
    assert not (tmp_path / "out").exists()


def test_a_failed_run_keeps_the_previous_outputs(rendered, tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    (out / "trajectory_tum.txt").write_text("# an earlier run\n")
    code, _ = _odometry(capsys, "--rig", str(rendered.rig_path), "--images",
                        str(tmp_path / "no_such_folder"), "--out", str(out))
    assert code == 2
    assert (out / "trajectory_tum.txt").read_text() == "# an earlier run\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]   # no partial folder


def test_rig_frame_names_the_frame_of_the_trajectory(rendered, tmp_path, capsys):
    """--rig-frame camera:NAME: the same physical motion, expressed in that camera's
    frame (each step conjugated by cam_from_body); a frame the rig lacks is a clear
    error naming frame, and nothing is written."""
    images = rendered.out_dir / "images"
    body = run_odometry(rendered.rig_path, images, tmp_path / "body", end=3)
    name = body.rig.names[0]
    cam = run_odometry(rendered.rig_path, images, tmp_path / "cam", end=3,
                       rig_frame=f"camera:{name}")
    assert cam.rig.frame == f"camera:{name}" and body.rig.frame != cam.rig.frame
    F = np.eye(4)
    F[:3, :3], F[:3, 3] = body.rig.cameras[0].R, body.rig.cameras[0].t
    for Pb, Pc in zip(body.trajectory.poses, cam.trajectory.poses):
        # world_from_cam = (world_from_body F^-1) re-anchored at the first frame
        expect = F @ Pb @ np.linalg.inv(F)
        np.testing.assert_allclose(Pc, expect, atol=1e-4)
    code, err = _odometry(capsys, "--rig", str(rendered.rig_path), "--images", str(images),
                          "--rig-frame", "camera:nosuch", "--out", str(tmp_path / "bad"))
    assert code == 2 and "frame='camera:nosuch'" in err and name in err
    assert not (tmp_path / "bad").exists()
