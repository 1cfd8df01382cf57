"""Atomic output files: a result appears whole or not at all.

Every file pkmkit writes goes first to a temporary file in the destination's directory, which
replaces the destination (``os.replace``, atomic on POSIX and Windows) only once it is complete;
a failed or interrupted run leaves the previous file, if any, untouched and no partial file.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

from pkmkit.exceptions import InputError


def check_output_file(path: str | Path) -> Path:
    """The destination as a :class:`Path`, after checking that a file can be created there.

    Raises:
        InputError: the path is a directory, its directory does not exist or is not a
            directory, or it is not writable.
    """
    p = Path(path)
    if p.is_dir():
        raise InputError(f"{path}: is a directory; give a file name")
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.exists():
        raise InputError(f"{path}: cannot write file: directory {str(parent)!r} does not exist")
    if not parent.is_dir():
        raise InputError(f"{path}: cannot write file: {str(parent)!r} is not a directory")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InputError(f"{path}: cannot write file: directory {str(parent)!r} is not writable")
    if p.exists() and not os.access(p, os.W_OK):
        raise InputError(f"{path}: cannot write file: it exists and is read-only")
    return p


def check_output_dir(path: str | Path) -> Path:
    """Create the output directory ``path`` (and its parents) if needed.

    Raises:
        InputError: ``path`` is an existing file, or cannot be created or written.
    """
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise InputError(f"{path}: exists and is not a directory; give a directory for --out")
    try:
        p.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"cannot create {path}: {exc.strerror or exc}") from None
    if not os.access(p, os.W_OK | os.X_OK):
        raise InputError(f"{path}: directory is not writable")
    return p


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """A temporary path to write instead of ``path``; it replaces ``path`` when the block ends
    without an exception and is removed otherwise. It keeps ``path``'s suffix (writers that
    infer the format from it, such as matplotlib, still do).

    Raises:
        InputError: the destination cannot be written (see :func:`check_output_file`).
    """
    target = check_output_file(path)
    try:
        handle, temp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=f".part{target.suffix}",
                                        dir=target.parent if str(target.parent) else ".")
    except OSError as exc:
        raise InputError(f"{path}: cannot write file: {exc.strerror or exc}") from None
    os.close(handle)
    temp_path = Path(temp)
    try:
        yield temp_path
        mode = 0o666 & ~_umask()
        os.chmod(temp_path, mode)
        os.replace(temp_path, target)
    except BaseException:
        with contextlib.suppress(OSError):
            temp_path.unlink()
        raise


def write_text_atomic(path: str | Path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    try:
        with atomic_path(path) as temp:
            temp.write_text(text, encoding="utf-8")
    except OSError as exc:
        raise InputError(f"{path}: cannot write file: {exc.strerror or exc}") from None


def _umask() -> int:
    current = os.umask(0)
    os.umask(current)
    return current
