"""The plain-C tests of csrc/tests, built and run by `meson test` from pytest.

The C library is configured without Python (-Dpython=false) in a temporary
build directory, so this checks the C core exactly as an embedding user
builds it.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _meson() -> list[str]:
    exe = shutil.which("meson")
    return [exe] if exe else [sys.executable, "-m", "mesonbuild.mesonmain"]


@pytest.fixture(scope="module")
def builddir(tmp_path_factory):
    if not (ROOT / "meson.build").exists():
        pytest.skip("source tree not available (tests run from an sdist-less install)")
    bd = tmp_path_factory.mktemp("cbuild")
    r = subprocess.run(_meson() + ["setup", str(bd), str(ROOT), "-Dpython=false"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    return bd


def test_meson_c_tests_pass(builddir):
    r = subprocess.run(_meson() + ["test", "-C", str(builddir), "--print-errorlogs"],
                       capture_output=True, text=True, timeout=600)
    print(r.stdout[-4000:])
    assert r.returncode == 0, r.stdout[-4000:] + r.stderr[-2000:]
    assert re.search(r"^Fail:\s+0\s*$", r.stdout, re.M), r.stdout[-2000:]
    assert re.search(r"^Ok:\s+[1-9][0-9]*\s*$", r.stdout, re.M), r.stdout[-2000:]
