"""``gcc -O2 -Werror`` builds of the generated LinuxCNC modules, each paid once per machine state.

A build is a pure function of its inputs: the compiler (its path and ``--version``), the flags,
the texts of the sources and of every file of the stand-in headers (``linuxcnc_stub/``). The
library of a build is kept under ``tests/export/__pycache__/c-builds/`` (git-ignored, like the
bytecode and Numba's caches beside it) named by the SHA-256 of those inputs, so the next test,
test process or pytest-xdist worker that asks for the same module copies it instead of
compiling it again (≈ 0.25 s of CPU per build, 20 builds in the ordinary run:
docs/testing.md, "Sixth round (session 34, suite3b)"). A changed generator, header, flag or
compiler is a new key, hence a new ``-Werror`` build; a failing build is never kept. Each caller
gets its own copy of the library (its own file, so its own ``dlopen`` handle and static state).
At most :data:`MAX_KEPT` libraries are kept. ``PKMKIT_TEST_C_CACHE=0`` compiles every time.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

STUB = Path(__file__).parent / "linuxcnc_stub"
CACHE = Path(__file__).parent / "__pycache__" / "c-builds"
#: Libraries kept at most (≈ 25 kB each; the oldest written go first).
MAX_KEPT = 200
_VERSIONS: dict[str, str] = {}


def _compiler_identity(cc: str) -> str:
    """The compiler's path and ``--version`` text (asked once per process)."""
    if cc not in _VERSIONS:
        done = subprocess.run([cc, "--version"], capture_output=True, text=True, check=True)
        _VERSIONS[cc] = f"{os.path.realpath(cc)}\n{done.stdout}"
    return _VERSIONS[cc]


def build_key(cc: str, args: list[str], sources: list[Path]) -> str:
    """SHA-256 of everything a build reads: compiler, arguments, sources, stub headers."""
    digest = hashlib.sha256()
    for part in [_compiler_identity(cc), *args]:
        digest.update(part.encode() + b"\0")
    for path in [*sources, *sorted(STUB.iterdir())]:
        if path.is_file():
            digest.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()


def build_shared(cc: str, flags: list[str], sources: list[Path], lib: Path) -> bool:
    """Build ``sources`` into the shared library ``lib`` (``cc -shared FLAGS SOURCES -lm``), or
    copy the kept library of the same inputs; True when it compiled."""
    key = build_key(cc, flags, sources)
    kept = CACHE / f"{key}.so"
    use_cache = os.environ.get("PKMKIT_TEST_C_CACHE") != "0"
    if use_cache and kept.is_file():
        shutil.copyfile(kept, lib)
        return False
    subprocess.run([cc, "-shared", *flags, *map(str, sources), "-o", str(lib), "-lm"],
                   check=True, capture_output=True)
    if use_cache:
        try:
            CACHE.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(dir=CACHE, suffix=".tmp")  # another worker may write it
            os.close(fd)
            shutil.copyfile(lib, tmp)
            os.replace(tmp, kept)
            _prune()
        except OSError:  # a read-only checkout: compiled every time, as before
            pass
    return True


def _prune() -> None:
    """Drop the oldest libraries beyond :data:`MAX_KEPT` (those of generators since changed)."""
    kept = sorted(CACHE.glob("*.so"), key=lambda p: p.stat().st_mtime)
    for path in kept[:max(0, len(kept) - MAX_KEPT)]:
        path.unlink(missing_ok=True)
