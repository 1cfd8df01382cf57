"""Atomic output files: a result appears whole or not at all.

Every file pkmkit writes goes first to a temporary file in the destination's directory, which
replaces the destination (``os.replace``, atomic on POSIX and Windows) only once it is complete;
a failed or interrupted run leaves the previous file, if any, untouched and no partial file.
The file gets the permissions the umask gives any new file.

Temporary files are named ``.<name>.pkmkit-<pid>.<random>.part<suffix>``: an exception or an
interruption (Ctrl-C; SIGTERM, which the command line turns into an exit) removes them, and a
process killed outright (SIGKILL, power loss) leaves one that the next write into the same
directory removes once its process is gone.
"""

from __future__ import annotations

import contextlib
import os
import re
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
    directory = target.parent if str(target.parent) else Path(".")
    sweep_stale_temporaries(directory)
    import tempfile  # at first write: a command that writes no file does not import it

    try:
        handle, temp = tempfile.mkstemp(prefix=f".{target.name}.{TEMP_TAG}{os.getpid()}.",
                                        suffix=f".part{target.suffix}", dir=directory)
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


#: Marks pkmkit's temporary files (followed by the writing process's id).
TEMP_TAG = "pkmkit-"
_TEMP_NAME = re.compile(r"^\..+\." + TEMP_TAG + r"(\d+)\.[^.]+\.part")


def sweep_stale_temporaries(directory: str | Path) -> list[Path]:
    """Remove the temporary files left in ``directory`` by pkmkit processes that no longer run
    (killed while writing); return them. Files of running processes are left alone."""
    removed = []
    with contextlib.suppress(OSError):
        for entry in os.scandir(directory):
            match = _TEMP_NAME.match(entry.name)
            if match and entry.is_file() and not _process_alive(int(match.group(1))):
                with contextlib.suppress(OSError):
                    os.unlink(entry.path)
                    removed.append(Path(entry.path))
    return removed


def _process_alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):
        return True  # exists, owned by someone else
    return True


def write_bytes_atomic(path: str | Path, payload: bytes) -> None:
    """Write ``payload`` to ``path`` atomically: a temporary file in the same directory, flushed
    to disk, then renamed over ``path`` with the permissions the umask gives a new file.

    Raises:
        InputError: the destination cannot be written, or the disk is full (no file is left).
    """
    try:
        with atomic_path(path) as temp, open(temp, "wb") as handle:
            handle.write(payload)
            handle.flush()
            os.fsync(handle.fileno())
    except OSError as exc:
        raise InputError(f"{path}: cannot write file: {exc.strerror or exc}") from None


def write_text_atomic(path: str | Path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically (see :func:`write_bytes_atomic`)."""
    write_bytes_atomic(path, text.encode("utf-8"))


def _umask() -> int:
    current = os.umask(0)
    os.umask(current)
    return current


def write_files_atomic(files: dict[str | Path, bytes | str]) -> list[Path]:
    """Write a set of files that belong together (a report and the machine file it describes)
    so that a failure leaves none of them: every file is first written in full to its
    temporary file (text as UTF-8), and only when all are complete are they renamed into
    place, in the given order. Returns the destinations.

    A failure while staging (full disk, read-only folder, an interruption) removes every
    temporary file and leaves the previous outputs, if any, untouched.

    Raises:
        InputError: a destination cannot be written, or the disk is full.
    """
    staged: list[tuple[Path, Path]] = []
    try:
        for path, payload in files.items():
            target = check_output_file(path)
            directory = target.parent if str(target.parent) else Path(".")
            sweep_stale_temporaries(directory)
            import tempfile  # at first write (see atomic_path)

            handle, temp = tempfile.mkstemp(prefix=f".{target.name}.{TEMP_TAG}{os.getpid()}.",
                                            suffix=f".part{target.suffix}", dir=directory)
            staged.append((Path(temp), target))
            data = payload.encode("utf-8") if isinstance(payload, str) else payload
            with os.fdopen(handle, "wb") as stream:
                stream.write(data)
                stream.flush()
                os.fsync(stream.fileno())
            os.chmod(temp, 0o666 & ~_umask())
    except BaseException as exc:
        for temp, _ in staged:
            with contextlib.suppress(OSError):
                temp.unlink()
        if isinstance(exc, OSError):
            raise InputError(f"{path}: cannot write file: {exc.strerror or exc}; "
                             "none of the output set was written") from None
        raise
    for temp, target in staged:
        os.replace(temp, target)
    return [target for _, target in staged]
