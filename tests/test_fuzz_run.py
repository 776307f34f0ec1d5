"""fuzz/run's time bound (run_bounded): a libFuzzer process that is still
replaying its corpus when the time is up gets SIGINT and its exit code 72 is
the time bound, not a finding; one that does not stop is killed. The
processes here are small Python programs standing in for libFuzzer."""

from __future__ import annotations

import importlib.machinery
import importlib.util
import sys
import time
from pathlib import Path

import pytest

RUN = Path(__file__).resolve().parents[1] / "fuzz" / "run"


@pytest.fixture(scope="module")
def fuzz_run():
    if not RUN.exists():
        pytest.skip("fuzz/run is not in this checkout")
    loader = importlib.machinery.SourceFileLoader("fuzz_run_script", str(RUN))
    spec = importlib.util.spec_from_loader("fuzz_run_script", loader)
    mod = importlib.util.module_from_spec(spec)
    loader.exec_module(mod)
    return mod


def _program(body: str) -> list[str]:
    return [sys.executable, "-c", "import signal, sys, time\n" + body]


# exits like libFuzzer on SIGINT: its statistics, then the code 72
_LIKE_LIBFUZZER = ("def stop(*_):\n    print('run interrupted'); sys.exit(72)\n"
                   "signal.signal(signal.SIGINT, stop)\ntime.sleep(60)\n")


def _run(fuzz_run, tmp_path, cmd, soft, hard):
    with open(tmp_path / "log", "w") as fh:
        t0 = time.monotonic()
        out = fuzz_run.run_bounded(cmd, fh, None, soft, hard)
    return out, time.monotonic() - t0, (tmp_path / "log").read_text()


def test_a_process_that_ends_in_time_keeps_its_exit_code(fuzz_run, tmp_path):
    assert _run(fuzz_run, tmp_path, _program("sys.exit(0)"), 20, 30)[0] == (0, False)
    # a finding (libFuzzer exits 1 on a crash) is not taken for the bound
    assert _run(fuzz_run, tmp_path, _program("sys.exit(1)"), 20, 30)[0] == (1, False)


def test_soft_bound_interrupts_and_is_not_a_finding(fuzz_run, tmp_path):
    (rc, cut), seconds, log = _run(fuzz_run, tmp_path, _program(_LIKE_LIBFUZZER), 0.5, 60)
    assert (rc, cut) == (0, True)
    assert seconds < 20
    assert "run interrupted" in log


def test_an_other_exit_code_after_sigint_stays_a_failure(fuzz_run, tmp_path):
    body = ("signal.signal(signal.SIGINT, lambda *_: sys.exit(3))\ntime.sleep(60)\n")
    assert _run(fuzz_run, tmp_path, _program(body), 0.5, 60)[0] == (3, False)


def test_a_process_deaf_to_sigint_is_killed(fuzz_run, tmp_path, monkeypatch):
    monkeypatch.setattr(fuzz_run, "INT_GRACE", 0.5)
    body = "signal.signal(signal.SIGINT, signal.SIG_IGN)\ntime.sleep(60)\n"
    (rc, cut), seconds, _ = _run(fuzz_run, tmp_path, _program(body), 0.5, 60)
    assert (rc, cut) == (-9, False)
    assert seconds < 20


def test_without_a_soft_bound_the_hard_one_kills(fuzz_run, tmp_path):
    (rc, cut), seconds, _ = _run(fuzz_run, tmp_path, _program(_LIKE_LIBFUZZER), None, 0.5)
    assert (rc, cut) == (-9, False)
    assert seconds < 20
