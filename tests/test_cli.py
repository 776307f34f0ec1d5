"""The mcgeom command line: version, help, argparse errors for invalid values
(usage + message, exit code 2, never a traceback), the experiment registry, the
real-data root, and the progress bar on stderr."""

from __future__ import annotations

import argparse
import io
import re
import subprocess
import sys

import numpy as np
import pytest

import mcgeom
from mcgeom import cli
from mcgeom.experiments import EXPERIMENTS, common, load
from mcgeom.experiments import real_data


def _exit_code(argv: list[str]) -> int:
    with pytest.raises(SystemExit) as exc:
        cli.main(argv)
    return exc.value.code


def test_version(capsys):
    assert _exit_code(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"mcgeom {mcgeom.__version__}"


def test_python_dash_m_runs_the_command(tmp_path):
    # run outside the checkout: its source tree (no compiled extension) must not shadow
    # the installed package
    r = subprocess.run([sys.executable, "-m", "mcgeom", "--version"], capture_output=True,
                       text=True, check=True, cwd=tmp_path)
    assert r.stdout.strip() == f"mcgeom {mcgeom.__version__}"


def test_experiment_help_lists_every_name(capsys):
    assert _exit_code(["experiment", "--help"]) == 0
    out = capsys.readouterr().out
    listing = out.split("experiments:", 1)[1]
    for name, (_, desc) in EXPERIMENTS.items():
        assert f"  {name} " in listing, name
        assert " ".join(desc.split()[:3]) in " ".join(listing.split()), name


@pytest.mark.parametrize("name", list(EXPERIMENTS))
def test_every_experiment_has_a_parser_and_a_run(name, capsys):
    mod = load(name)
    assert callable(mod.run_cli)
    assert _exit_code(["experiment", name, "--help"]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"usage: mcgeom experiment {name}")
    assert "``" not in out and ":func:" not in out


def test_unknown_experiment_is_an_argparse_error(capsys):
    assert _exit_code(["experiment", "no_such_experiment"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("usage: mcgeom experiment")
    assert "invalid choice: 'no_such_experiment'" in err


def test_a_value_error_while_an_experiment_runs_is_a_usage_error(monkeypatch, capsys):
    # a bad value an experiment only finds while running (named by mcgeom's
    # ValueError) is reported like an argparse error: usage, message, exit 2
    mod = load("ch8")

    def run_cli(args, progress):
        raise ValueError("threshold: must be positive, got -1")

    monkeypatch.setattr(mod, "run_cli", run_cli)
    assert _exit_code(["experiment", "ch8"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("usage: mcgeom experiment ch8")
    assert "mcgeom experiment ch8: error: threshold: must be positive, got -1" in err
    assert "Traceback" not in err


@pytest.mark.parametrize("argv, message", [
    (["demo", "--frames", "1"], "argument --frames: expected at least 2 frames"),
    (["demo", "--frames", "-4"], "argument --frames: expected a positive integer"),
    (["demo", "--seed", "-3"], "argument --seed: expected a non-negative integer"),
    (["demo", "--seed", "1.5"], "argument --seed: expected a non-negative integer"),
    (["demo", "--features", "surf"], "argument --features: invalid choice"),
    (["odometry", "--rig", "r.json", "--images", "d", "--step", "0"],
     "argument --step: expected a positive integer"),
    (["odometry", "--images", "d"], "the following arguments are required: --rig"),
    (["odometry", "--rig", "r.json", "--images", "d", "--rig-frame", "imu"],
     "argument --rig-frame: expected body, camera:NAME, camera:INDEX or a file"),
    (["bench", "linear17", "--budget", "0"], "argument --budget: expected a positive number"),
    (["bench", "bnb", "--problems", "0"], "argument --problems: expected a positive integer"),
    (["bench", "linear17", "--sizes", "5,abc"], "argument --sizes: expected a comma-separated"),
    (["bench", "cone", "--sizes", "5,0"], "argument --sizes: expected a comma-separated"),
    (["bench", "nope"], "argument NAME: invalid choice: 'nope'"),
    (["experiment", "ch7", "--trials", "0"], "argument --trials: expected a positive integer"),
    (["experiment", "ch6", "--range", "-5"], "argument --range: expected a positive number"),
])
def test_invalid_values_are_argparse_errors(argv, message, capsys):
    assert _exit_code(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("usage: mcgeom")
    assert message in err
    assert "Traceback" not in err


def test_validators():
    assert common.positive_int("3") == 3
    assert common.non_negative_int("0") == 0
    assert common.positive_float("0.25") == 0.25
    assert common.non_negative_float("0") == 0.0
    assert common.positive_int_list("17, 100,1000") == (17, 100, 1000)
    for fn, bad in ((common.positive_int, "0"), (common.positive_int, "x"),
                    (common.non_negative_int, "-1"), (common.positive_float, "0"),
                    (common.positive_float, "inf"), (common.non_negative_float, "-0.1"),
                    (common.positive_int_list, ""), (common.positive_int_list, "3,,4"),
                    (common.positive_int_list, "-2")):
        with pytest.raises(argparse.ArgumentTypeError):
            fn(bad)


@pytest.mark.parametrize("argv", [["demo"], ["odometry"], ["bench"], ["experiment"]] +
                         [["experiment", name] for name in EXPERIMENTS])
def test_every_option_shows_its_default(argv, capsys):
    assert _exit_code(argv + ["--help"]) == 0
    out = capsys.readouterr().out
    assert "``" not in out
    section = out.split("\noptions:\n", 1)[1].split("\n\n", 1)[0]
    entries = re.split(r"\n(?=  -)", section)
    for entry in entries:
        if not entry.startswith("  -h, --help"):
            text = " ".join(entry.split())
            assert "default" in text or text.endswith("; required"), (argv, entry)
    assert all(len(line) <= 100 for line in out.splitlines()), argv   # wrapped, not cut


@pytest.mark.parametrize("name", ["real_data", "ch6_kitti"])
def test_missing_data_root_is_a_one_line_error(name, tmp_path, capsys):
    missing = tmp_path / "no_data_here"
    assert cli.main(["experiment", name, "--data", str(missing)]) == 2
    captured = capsys.readouterr()
    err = captured.err.strip()
    assert len(err.splitlines()) == 1, err
    assert str(missing) in err and "--data" in err and real_data.DATA_ENV in err
    assert "Traceback" not in err and captured.out == ""


def test_data_root_from_the_environment(tmp_path, monkeypatch):
    monkeypatch.setenv(real_data.DATA_ENV, str(tmp_path))
    assert real_data.default_data_root() == tmp_path
    monkeypatch.delenv(real_data.DATA_ENV)
    monkeypatch.chdir(tmp_path)
    # nothing beside this directory: the guess beside the working directory is named
    if not real_data.data_available(real_data.default_data_root()):
        assert real_data.default_data_root() == tmp_path.parent / "shared" / "data"


def test_missing_peer_is_a_clear_error(monkeypatch, capsys):
    # poselib made unimportable: the comparison says what it needs, exit code 2
    monkeypatch.setitem(sys.modules, "poselib", None)
    assert cli.main(["experiment", "robust_vs_poselib", "--problems", "1"]) == 2
    err = capsys.readouterr().err
    assert "robust_vs_poselib needs poselib: pip install poselib" in err


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_progress_bar_on_stderr_in_a_terminal(monkeypatch, capsys):
    fake = _Terminal()
    monkeypatch.setattr(sys, "stderr", fake)
    assert cli.main(["bench", "linear17", "--sizes", "17,30", "--budget", "0.001"]) == 0
    out = capsys.readouterr().out
    assert "linear17:" in out and "\r" not in out       # the table is untouched
    assert "linear17:" in fake.getvalue() and "/2 [" in fake.getvalue()   # N of 2 sizes


def test_no_progress_bar_when_stderr_is_not_a_terminal(monkeypatch):
    fake = io.StringIO()
    monkeypatch.setattr(sys, "stderr", fake)
    assert list(common.progress_bar(range(3), total=3, desc="x")) == [0, 1, 2]
    assert fake.getvalue() == ""


def test_methods_lists_the_lp_backends_and_how_to_get_glpk(tmp_path):
    """Without libglpk (a library path that does not exist) ``mcgeom methods``
    still lists the native backend and says how to install GLPK."""
    import os
    env = dict(os.environ, MCG_GLPK_LIBRARY=str(tmp_path / "no-libglpk.so"))
    r = subprocess.run([sys.executable, "-m", "mcgeom", "methods"], capture_output=True,
                       text=True, check=True, cwd=tmp_path, env=env)
    backends = r.stdout[r.stdout.index("LP backends"):]
    assert "native:" in backends
    assert "glpk: unavailable" in backends and "pip install 'mcgeom[glpk]'" in backends


def test_methods_fits_the_terminal_and_keeps_commands_whole(capsys):
    """``mcgeom methods`` is filled to 100 columns, as ``--help`` is, and the
    commands it quotes stay on one line (a reader copies them)."""
    assert cli.main(["methods"]) == 0
    out = capsys.readouterr().out
    assert all(len(line) <= 100 for line in out.splitlines())
    assert "mcgeom experiment peer_solvers --part ransac --outliers 0 0.3 0.5 0.6" in out
    assert "upright_four_point  when a vertical prior is passed" in out
    assert "\0" not in out


def test_rig_frame_argument(tmp_path):
    """--rig-frame: names pass through, a file gives its checked 4x4 transform."""
    assert cli.rig_frame_arg("body") == "body"
    assert cli.rig_frame_arg("camera:2") == "camera:2"
    T = np.eye(4)
    T[:3, 3] = (0.1, -0.2, 1.5)
    np.savetxt(tmp_path / "T.txt", T)
    np.testing.assert_array_equal(cli.rig_frame_arg(str(tmp_path / "T.txt")), T)
    np.savetxt(tmp_path / "bad.txt", 2 * T)
    with pytest.raises(argparse.ArgumentTypeError, match="bad.txt: frame: the 4x4 transform "
                                                         "is not rigid"):
        cli.rig_frame_arg(str(tmp_path / "bad.txt"))
    (tmp_path / "text.txt").write_text("not numbers\n")
    with pytest.raises(argparse.ArgumentTypeError, match="text.txt"):
        cli.rig_frame_arg(str(tmp_path / "text.txt"))
