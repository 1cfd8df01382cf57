"""The shared plan of the full-pose inverse (``native/inverse_shared.c``) under
ThreadSanitizer: a C harness (tests/native/tsan/inverse_shared_harness.c) runs three threads
on one plan 300 times, slices of 1–7 rows in blocks of 1–5, and compares every row and status
with the single-thread kernel's bits; ThreadSanitizer reports any data race (a planted write
without the compare-and-swap claim gives ten). Built with the system's C compiler against
libpython (the file's Python face is linked, not run); skipped where either is missing.
Marked ``ci``: a compilation and 300 runs under the sanitizer take seconds."""

from __future__ import annotations

import shutil
import subprocess
import sysconfig
from pathlib import Path

import pytest

pytestmark = pytest.mark.ci

HERE = Path(__file__).parent
NATIVE = HERE.parents[1] / "src" / "pkmkit" / "native"


def test_no_data_race_and_every_row_its_bits(tmp_path):
    compiler = shutil.which("gcc")
    libdir = sysconfig.get_config_var("LIBDIR")
    version = sysconfig.get_config_var("LDVERSION")
    if compiler is None or not libdir or not (Path(libdir) / f"libpython{version}.so").exists():
        pytest.skip("needs gcc and a shared libpython")
    binary = tmp_path / "harness"
    build = subprocess.run(
        [compiler, "-O1", "-g", "-fsanitize=thread", "-std=c11", "-D_GNU_SOURCE",
         "-ffp-contract=off", f"-I{NATIVE}", f"-I{sysconfig.get_paths()['include']}",
         str(HERE / "tsan" / "inverse_shared_harness.c"), str(NATIVE / "inverse_shared.c"),
         str(NATIVE / "inverse.c"), str(NATIVE / "inverse_simd.c"), "-o", str(binary), "-lm",
         "-lpthread", f"-L{libdir}", f"-lpython{version}", f"-Wl,-rpath,{libdir}"],
        capture_output=True, text=True)
    if build.returncode != 0:
        pytest.skip(f"ThreadSanitizer build failed: {build.stderr[-300:]}")
    run = subprocess.run([str(binary)], capture_output=True, text=True, timeout=600)
    assert "ThreadSanitizer" not in run.stderr, run.stderr[-2000:]
    assert run.returncode == 0 and "rows differing in 0" in run.stdout, run.stdout
