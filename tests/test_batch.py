"""``mcgeom batch`` on a LocalCluster of 2 worker processes: three short
rendered sequences and a broken entry; a worker killed mid-run; a re-run that
skips the finished work; each result equal to the serial run; the manifest's
checks; the command line (and its message when Dask is missing)."""

from __future__ import annotations

import csv
import os
import signal
import sys
import threading
import time

import numpy as np
import pytest

distributed = pytest.importorskip("distributed")
import dask  # noqa: E402

from mcgeom import cli  # noqa: E402
from mcgeom.batch import read_manifest, run  # noqa: E402
from mcgeom.batch.runner import WORKER_DEATHS  # noqa: E402
from mcgeom.experiments.render import render_sequence, surround_rig  # noqa: E402
from mcgeom.io.trajectory import read_tum  # noqa: E402
from mcgeom.sequence.run import run_odometry  # noqa: E402

#: (name, seed, start along the loop in metres, frames)
SEQUENCES = (("alpha", 0, 0.0, 5), ("beta", 1, 3.0, 5), ("gamma", 2, 30.0, 4))


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    """The three sequences and a manifest of them plus a broken entry (an
    images folder that does not exist)."""
    root = tmp_path_factory.mktemp("batch_data")
    rig = surround_rig(320, 240)
    for name, seed, start, n in SEQUENCES:
        render_sequence(root / name, n_frames=n, seed=seed, start=start, step=0.9, rig=rig)
    lines = ["name,rig,images,gt"]
    lines += [f"{name},{name}/rig.json,{name}/images,{name}/groundtruth_tum.txt"
              for name, *_ in SEQUENCES]
    lines.append("broken,alpha/rig.json,no_such_images,")
    (root / "manifest.csv").write_text("\n".join(lines) + "\n")
    return root


def _local_cluster():
    """A LocalCluster of 2 single-threaded worker processes and its client."""
    with dask.config.set({"distributed.scheduler.allowed-failures": WORKER_DEATHS}):
        cluster = distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1,
                                           dashboard_address=":0")
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


@pytest.fixture(scope="module")
def client():
    yield from _local_cluster()


@pytest.fixture
def own_client():
    """A cluster for one test that kills its workers again and again: a nanny
    whose new worker is killed while it starts closes for good (CI at 337d0ef:
    "Only 1/2 workers arrived after 240"), so no other test may share it."""
    yield from _local_cluster()


def _kill_a_busy_worker(client, killed: list) -> None:
    """Wait until a worker runs a sequence, let it work a moment, SIGKILL it."""
    pids = client.run(os.getpid)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        busy = [a for a, keys in client.processing().items()
                if any("run_sequence" in str(k) for k in keys)]
        if busy:
            time.sleep(0.5)       # mid-task: the front end is reading images
            os.kill(pids[busy[0]], signal.SIGKILL)
            killed.append(pids[busy[0]])
            return
        time.sleep(0.05)


@pytest.fixture(scope="module")
def first_run(rendered, client, tmp_path_factory):
    """The batch, with one worker killed while it runs a sequence."""
    out = tmp_path_factory.mktemp("batch_out")
    killed: list = []
    killer = threading.Thread(target=_kill_a_busy_worker, args=(client, killed))
    killer.start()
    rows = run(rendered / "manifest.csv", out, client=client)
    killer.join()
    return out, rows, killed


def test_summary_after_a_worker_was_killed(first_run, client):
    out, rows, killed = first_run
    assert len(killed) == 1
    assert killed[0] not in client.run(os.getpid).values()    # the nanny started another
    by_name = {r["name"]: r for r in rows}
    assert [r["name"] for r in rows] == ["alpha", "beta", "gamma", "broken"]
    for name, _, _, n in SEQUENCES:
        r = by_name[name]
        assert r["status"] == "ok" and r["frames"] == n and r["error"] is None
        assert r["ate_rmse_m"] < 0.05 and abs(r["path_length_m"] - 0.9 * (n - 1)) < 0.1
        assert r["unknown_share"] == 0 and r["metric_share"] + r["carried_share"] == 1
        assert (out / name / "trajectory_tum.txt").is_file()
    bad = by_name["broken"]
    assert bad["status"] == "failed" and "no_such_images" in bad["error"]
    with open(out / "summary.csv") as f:
        table = list(csv.DictReader(f))
    assert [t["status"] for t in table] == ["ok", "ok", "ok", "failed"]
    assert float(table[0]["ate_rmse_m"]) == pytest.approx(by_name["alpha"]["ate_rmse_m"],
                                                          rel=1e-5)
    assert "no_such_images" in table[3]["error"] and table[3]["frames"] == ""
    if (out / "summary.parquet").exists():
        pq = pytest.importorskip("pyarrow.parquet")
        assert pq.read_table(out / "summary.parquet").column("status").to_pylist() == \
            ["ok", "ok", "ok", "failed"]
    assert not [p for p in out.iterdir() if p.name.startswith(".summary")]


def test_each_result_equals_the_serial_run(first_run, rendered, tmp_path):
    out = first_run[0]
    for name, *_ in SEQUENCES:
        run_odometry(rendered / name / "rig.json", rendered / name / "images", tmp_path / name,
                     gt=rendered / name / "groundtruth_tum.txt")
        ts_b, poses_b = read_tum(out / name / "trajectory_tum.txt")
        ts_s, poses_s = read_tum(tmp_path / name / "trajectory_tum.txt")
        assert np.array_equal(ts_b, ts_s)
        assert np.max(np.abs(poses_b - poses_s)) <= 1e-12, name
        assert (out / name / "steps.csv").read_text() == (tmp_path / name / "steps.csv").read_text()


def test_a_rerun_skips_finished_work(first_run, rendered, client):
    out, rows, _ = first_run
    files = [out / n / f for n, *_ in SEQUENCES for f in ("result.json", "trajectory_tum.txt")]
    before = {p: p.stat().st_mtime_ns for p in files}
    broken = (out / "broken" / "result.json").stat().st_mtime_ns
    # what a worker killed while writing leaves: removed when the task runs again
    stale = out / ".broken.partial-killed"
    stale.mkdir()
    (stale / "steps.csv").write_text("half a file")
    again = run(rendered / "manifest.csv", out, client=client)
    assert not stale.exists()
    assert [r["reused"] for r in rows] == [False] * 4
    assert [r["reused"] for r in again] == [True, True, True, False]
    assert [{**r, "reused": 0} for r in again[:3]] == [{**r, "reused": 0} for r in rows[:3]]
    assert {**again[3], "seconds": 0, "reused": 0} == {**rows[3], "seconds": 0, "reused": 0}
    assert {p: p.stat().st_mtime_ns for p in files} == before      # not rewritten
    # a failed sequence is tried again (its input may have been fixed)
    assert (out / "broken" / "result.json").stat().st_mtime_ns > broken


def test_a_changed_entry_is_run_again(first_run, rendered, client, tmp_path):
    out = first_run[0]
    manifest = tmp_path / "m.csv"
    manifest.write_text(f"name,rig,images,gt,end\nalpha,{rendered}/alpha/rig.json,"
                        f"{rendered}/alpha/images,,3\n")
    (rows,) = run(manifest, tmp_path / "out", client=client)
    assert rows["status"] == "ok" and rows["frames"] == 3 and rows["ate_rmse_m"] is None
    before = (out / "alpha" / "result.json").stat().st_mtime_ns
    # same output folder, other options: not the finished run of this entry
    (rows,) = run(manifest, out, client=client)
    assert rows["frames"] == 3
    assert (out / "alpha" / "result.json").stat().st_mtime_ns > before


# ------------------------------------------------------------------ manifest

def _manifest(tmp_path, text: str):
    p = tmp_path / "manifest.csv"
    p.write_text(text)
    return p


@pytest.mark.parametrize("text, words", [
    ("name,rig,imgs,gt\na,r.json,i,\n", ["line 1", "name,rig,images,gt"]),
    ("name,rig,images,gt\na,r.json,,\n", ["line 2", "'images'", "empty"]),
    ("name,rig,images,gt\na,r.json,i,\nb,r.json,j,\na,r.json,k,\n",
     ["line 4", "duplicate", "'a'", "line 2"]),
    ("name,rig,images,gt\na,r.json,i\n", ["line 2", "3 columns"]),
    ("name,rig,images,gt,speed\na,r.json,i,,1\n", ["line 1", "'speed'"]),
    ("name,rig,images,gt,step\na,r.json,i,,0\n", ["line 2", "'step'", "'0'"]),
    ("name,rig,images,gt,features\na,r.json,i,,surf\n", ["line 2", "'features'", "sift"]),
    ("name,rig,images,gt\n../a,r.json,i,\n", ["line 2", "'name'", "folder"]),
    ("name,rig,images,gt\n", ["no sequence"]),
    ("name,rig,images,gt,rig_frame\na,r.json,i,,imu\n", ["line 2", "'rig_frame'", "camera:NAME"]),
    ("name,rig,images,gt,calibration_check\na,r.json,i,,none\n",
     ["line 2", "'calibration_check'", "first_order"]),
])
def test_manifest_errors_name_line_and_column(tmp_path, text, words):
    with pytest.raises(ValueError) as e:
        read_manifest(_manifest(tmp_path, text))
    for w in words:
        assert w in str(e.value), (w, str(e.value))


def test_manifest_paths_are_relative_to_its_folder(tmp_path):
    (tmp_path / "sub").mkdir()
    p = tmp_path / "sub" / "m.csv"
    p.write_text("name,rig,images,gt,start,threshold,cross_camera,rig_frame,calibration_check\n"
                 f"a,r.json,imgs,gt.txt,2,1.5,false,camera:front,first-order\n"
                 f"b,{tmp_path}/r.json,i,,,,,,\n")
    a, b = read_manifest(p)
    assert a.rig == tmp_path / "sub" / "r.json" and a.gt == tmp_path / "sub" / "gt.txt"
    assert a.options == {"start": 2, "threshold": 1.5, "cross_camera": False,
                         "rig_frame": "camera:front", "calibration_check": "first_order"}
    assert b.rig == tmp_path / "r.json" and b.gt is None and b.options == {}
    with pytest.raises(ValueError, match="not a file"):
        read_manifest(tmp_path / "missing.csv")


# ------------------------------------------------------------------ command line

def test_cli_batch_on_one_sequence(rendered, tmp_path, capsys):
    manifest = _manifest(tmp_path, f"name,rig,images,gt,end\none,{rendered}/gamma/rig.json,"
                                   f"{rendered}/gamma/images,"
                                   f"{rendered}/gamma/groundtruth_tum.txt,3\n")
    code = cli.main(["batch", str(manifest), "--out", str(tmp_path / "out"), "--workers", "1"])
    text = capsys.readouterr().out
    assert code == 0, text
    assert "1 ok, 0 failed of 1 sequences" in text and "summary.csv" in text
    assert "(0 already done" in text
    assert (tmp_path / "out" / "one" / "trajectory_tum.txt").is_file()
    code = cli.main(["batch", str(manifest), "--out", str(tmp_path / "out"), "--workers", "1"])
    assert code == 0 and "(1 already done" in capsys.readouterr().out


def test_cli_batch_on_an_existing_cluster(rendered, client, tmp_path, capsys):
    """--scheduler ADDRESS: the workers of a cluster that was already running."""
    manifest = _manifest(tmp_path, f"name,rig,images,gt,end,features\ntwo,"
                                   f"{rendered}/beta/rig.json,{rendered}/beta/images,,3,orb\n")
    code = cli.main(["batch", str(manifest), "--out", str(tmp_path / "out"), "--scheduler",
                     client.scheduler.address])
    text = capsys.readouterr().out
    assert code == 0 and "1 ok, 0 failed of 1 sequences" in text, text
    assert client.status == "running"          # the batch closed its own client only
    with open(tmp_path / "out" / "summary.csv") as f:
        (row,) = list(csv.DictReader(f))
    assert row["frames"] == "3" and row["ate_rmse_m"] == ""


def test_cli_batch_errors(tmp_path, capsys, monkeypatch):
    manifest = _manifest(tmp_path, "name,rig,images\n")
    assert cli.main(["batch", str(manifest), "--out", str(tmp_path / "o")]) == 2
    assert "line 1" in capsys.readouterr().err and not (tmp_path / "o").exists()
    with pytest.raises(SystemExit) as e:
        cli.main(["batch", str(manifest), "--out", "o", "--workers", "2",
                  "--scheduler", "tcp://127.0.0.1:1"])
    assert e.value.code == 2 and "not allowed with" in capsys.readouterr().err
    monkeypatch.setitem(sys.modules, "distributed", None)     # as if not installed
    assert cli.main(["batch", str(manifest), "--out", str(tmp_path / "o")]) == 2
    assert "mcgeom batch needs Dask: pip install 'mcgeom[batch]'" in capsys.readouterr().err


def _kill_every_runner(client, stop: threading.Event, killed: list) -> None:
    """SIGKILL whichever worker runs a sequence, again and again, until stopped."""
    while not stop.is_set():
        busy = [a for a, keys in client.processing().items()
                if any("run_sequence" in str(k) for k in keys)]
        if busy:
            try:
                pid = client.run(os.getpid, workers=busy[:1])[busy[0]]
            except Exception:         # the worker went away meanwhile: look again
                continue
            time.sleep(0.3)
            os.kill(pid, signal.SIGKILL)
            killed.append(pid)
            while not stop.is_set() and busy[0] in client.processing():
                time.sleep(0.05)      # until the scheduler has seen it die
        time.sleep(0.05)


def test_a_sequence_whose_worker_always_dies_fails_after_the_bound(rendered, own_client,
                                                                   tmp_path):
    """Retries of a killed task are bounded: after WORKER_DEATHS + 1 deaths the
    sequence is recorded as failed (Dask's KilledWorker), the batch ends."""
    manifest = _manifest(tmp_path, f"name,rig,images,gt,end\ndoomed,"
                                   f"{rendered}/gamma/rig.json,{rendered}/gamma/images,,3\n")
    stop, killed = threading.Event(), []
    killer = threading.Thread(target=_kill_every_runner, args=(own_client, stop, killed))
    killer.start()
    try:
        (row,) = run(manifest, tmp_path / "out", client=own_client)
    finally:
        stop.set()
        killer.join()
    assert row["status"] == "failed" and "KilledWorker" in row["error"], row
    assert len(killed) == WORKER_DEATHS + 1
    with open(tmp_path / "out" / "summary.csv") as f:
        assert "KilledWorker" in next(iter(csv.DictReader(f)))["error"]
