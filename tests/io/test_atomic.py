"""One atomic writer for every output (issue 18 §6): umask, interrupted runs, stale temporaries."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import pytest

from pkmkit.exceptions import InputError
from pkmkit.io.atomic import (
    TEMP_TAG,
    atomic_path,
    sweep_stale_temporaries,
    write_bytes_atomic,
)


def _dead_pid() -> int:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def test_a_killed_writers_temporary_is_swept_by_the_next_write(tmp_path):
    stale = tmp_path / f".out.csv.{TEMP_TAG}{_dead_pid()}.abc123.part.csv"
    stale.write_bytes(b"x" * 1000)
    alive = tmp_path / f".out.csv.{TEMP_TAG}{os.getpid()}.def456.part.csv"
    alive.write_bytes(b"y")
    foreign = tmp_path / ".notes.swp"
    foreign.write_bytes(b"z")
    write_bytes_atomic(tmp_path / "out.csv", b"a,b\n")
    names = sorted(p.name for p in tmp_path.iterdir())
    assert stale.name not in names                 # its process is gone
    assert alive.name in names and foreign.name in names  # a live writer's file, not ours
    assert (tmp_path / "out.csv").read_bytes() == b"a,b\n"


def test_sweep_reports_what_it_removed(tmp_path):
    stale = tmp_path / f".q.parquet.{TEMP_TAG}{_dead_pid()}.zz.part.parquet"
    stale.write_bytes(b"")
    assert sweep_stale_temporaries(tmp_path) == [stale]


def test_an_exception_inside_the_block_leaves_no_file(tmp_path):
    with pytest.raises(RuntimeError), atomic_path(tmp_path / "x.png") as temp:
        temp.write_bytes(b"partial")
        raise RuntimeError("boom")
    assert list(tmp_path.iterdir()) == []


def test_full_disk_is_a_typed_error(tmp_path, monkeypatch):
    def full(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "fsync", full)
    with pytest.raises(InputError, match="No space left"):
        write_bytes_atomic(tmp_path / "x.csv", b"data")
    assert list(tmp_path.iterdir()) == []


def test_sigterm_during_a_write_leaves_no_temporary(tmp_path):
    """The command line turns SIGTERM into an ordinary exit: the writer's cleanup runs."""
    script = textwrap.dedent(f"""
        import os, signal
        from pkmkit.cli.main import exit_on_sigterm
        from pkmkit.io.atomic import atomic_path
        exit_on_sigterm()
        with atomic_path({str(tmp_path / "big.csv")!r}) as temp:
            temp.write_bytes(b"x" * 100000)
            os.kill(os.getpid(), signal.SIGTERM)
            raise AssertionError("not reached")
    """)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, timeout=120)
    assert proc.returncode == 143, proc.stderr.decode()
    assert list(tmp_path.iterdir()) == []


def test_an_output_set_is_written_whole_or_not_at_all(tmp_path, monkeypatch):
    """A failure while staging the third file leaves neither the first two nor a temporary,
    and the previous outputs stay as they were (issue 18 §6: no machine file without its report)."""
    from pkmkit.io import atomic

    (tmp_path / "machine.toml").write_text("old machine")
    real_fsync = os.fsync
    calls = {"n": 0}

    def failing_fsync(fd):
        calls["n"] += 1
        if calls["n"] == 3:
            raise OSError(28, "No space left on device")
        real_fsync(fd)

    monkeypatch.setattr(atomic.os, "fsync", failing_fsync)
    files = {tmp_path / "machine.toml": "new machine", tmp_path / "fig.png": b"\x89PNG",
             tmp_path / "report.html": "<html>"}
    with pytest.raises(InputError, match="none of the output set was written"):
        atomic.write_files_atomic(files)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["machine.toml"]
    assert (tmp_path / "machine.toml").read_text() == "old machine"
    monkeypatch.setattr(atomic.os, "fsync", real_fsync)
    written = atomic.write_files_atomic(files)
    assert [p.name for p in written] == ["machine.toml", "fig.png", "report.html"]
    assert (tmp_path / "machine.toml").read_text() == "new machine"
    assert (tmp_path / "report.html").read_text() == "<html>"
    mode = (tmp_path / "report.html").stat().st_mode & 0o777
    assert mode == 0o666 & ~atomic._umask()
