"""A fork server for the documentation runs: one pre-warmed Python process per test process
forks a child per ``pkmkit ...`` command or Python block, so each block still starts from a
fresh process state (its own ``__main__``, arguments, folder, environment and output files)
without paying a new interpreter and ``import pkmkit`` each time (≈ 0.4 s of CPU per block).

The server imports NumPy, SciPy's common modules, click and pkmkit with every command-line
module — never Numba: pkmkit chooses its compiled kernels when ``numba`` is already imported
(``pkmkit.numerics.jit``), so a warm Numba would change the code path a block runs; the server
refuses to start if anything pulls it in. Compiled kernels are therefore loaded (from Numba's
on-disk cache) by the child that needs them, as by a fresh process.

The child runs a command as the ``pkmkit`` console script does (``sys.exit(main())`` with
``sys.argv`` set) and a program as ``python -c`` does (in a new ``__main__`` module, tracebacks
on standard error and exit status 1, ``SystemExit`` as the interpreter treats it), then runs
the exit handlers, flushes its output and exits. What a block can still tell from a fresh
process (compared with a fingerprint of the interpreter's state, 2026-11-26): the warm modules
are imported, with the warning filters NumPy and SciPy add at import (a fresh block that
imports them gets the same filters), and the warm heap is frozen for the garbage collector
(``gc.freeze``, so that the children do not copy it). Anything the fork server cannot reproduce (a
shell pipeline, redirection, variable, glob, another program, a ``fresh`` block) runs in a new
process as before: ``docs_blocks``/``test_docs_run`` decide which; ``PKMKIT_DOCS_FRESH=1`` sends
every block there.

This file is run as the server's program (``python -c``, so that ``sys.path[0]`` is the block's
folder as for ``python -c``) and imported by the tests for the client: standard library only.
"""

from __future__ import annotations

import contextlib
import json
import os
import select
import shutil
import signal
import subprocess
import sys
import tempfile
from pathlib import Path

#: Modules imported before the first fork (besides every ``pkmkit.cli`` module).
WARM = ("numpy", "scipy.linalg", "scipy.optimize", "scipy.spatial", "click", "pkmkit",
        "pkmkit.cli.main")
#: Metacharacters that need a shell when unquoted (``#`` starts a comment at a word's start).
_SHELL = set("|&;<>()$`*?[]{}~\\\"'")


def shell_words(text: str) -> list[str] | None:
    """The words of a shell command line that needs no shell feature but quoting (words split
    on blanks, single and double quotes, a ``#`` comment at a word's start), else None: a
    redirection, pipe, variable, glob, brace, tilde, backslash or command substitution, which
    only a real shell reproduces."""
    words: list[str] = []
    word: str | None = None
    k = 0
    while k < len(text):
        char = text[k]
        if char in " \t":
            if word is not None:
                words.append(word)
            word = None
        elif char == "#" and word is None:
            break
        elif char == "'":
            end = text.find("'", k + 1)
            if end < 0:
                return None
            word = (word or "") + text[k + 1:end]
            k = end
        elif char == '"':
            end = text.find('"', k + 1)
            inside = text[k + 1:end]
            if end < 0 or any(c in inside for c in "$`\\!"):
                return None
            word = (word or "") + inside
            k = end
        elif char in _SHELL:
            return None
        else:
            word = (word or "") + char
        k += 1
    if word is not None:
        words.append(word)
    return words


class ForkServer:
    """The client: start the server (lazily), send it one block at a time."""

    def __init__(self, env: dict[str, str]):
        self._env = dict(env)
        self._process: subprocess.Popen | None = None
        self.cpu = 0.0  # user + system CPU time of the children so far (s)
        self._folder = Path(tempfile.mkdtemp(prefix="docs-fork-"))

    def _start(self) -> subprocess.Popen:
        self._folder.mkdir(exist_ok=True)
        log = open(self._folder / "server.log", "wb")  # the server's stderr
        process = subprocess.Popen(
            [sys.executable, "-c", Path(__file__).read_text(encoding="utf-8")],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=log, cwd=self._folder,
            env=self._env, start_new_session=True)
        log.close()
        reply = self._reply(process, 600)
        if not reply.get("ready"):
            _kill(process)
            raise RuntimeError(f"the documentation fork server did not start: {reply} "
                               "(PKMKIT_DOCS_FRESH=1 runs every block in a new process)")
        return process

    def _reply(self, process: subprocess.Popen, timeout: float) -> dict:
        ready, _, _ = select.select([process.stdout], [], [], timeout)
        line = process.stdout.readline() if ready else b""
        if not line:
            _kill(process)
            self._process = None
            if not ready:
                raise subprocess.TimeoutExpired("fork server", timeout)
            log = (self._folder / "server.log").read_text(errors="replace")
            raise RuntimeError(f"the documentation fork server died:\n{log}")
        return json.loads(line)

    def run(self, request: dict, *, merge: bool, timeout: float) -> tuple[int, str, str]:
        """Run one request (``{"cli": [arguments]}`` or ``{"program": source}`` with ``cwd``,
        ``env``); ``(exit status, stdout, stderr)``, stderr merged into stdout with
        ``merge``, decoded as ``subprocess.run(..., text=True)`` does."""
        if self._process is None or self._process.poll() is not None:
            self._process = self._start()
        out, err = self._folder / "stdout", self._folder / "stderr"
        request = {**request, "stdout": str(out), "stderr": None if merge else str(err)}
        self._process.stdin.write(json.dumps(request).encode() + b"\n")
        self._process.stdin.flush()
        reply = self._reply(self._process, timeout)
        self.cpu += reply["cpu"]
        status = reply["returncode"]
        stdout = out.read_text()
        stderr = "" if merge else err.read_text()
        return status, stdout, stderr

    def close(self) -> None:
        """Stop the server (it ends at the end of its input) and remove its files."""
        process, self._process = self._process, None
        if process is not None:
            process.stdin.close()
            process.wait()
            process.stdout.close()
        shutil.rmtree(self._folder, ignore_errors=True)


def _kill(process: subprocess.Popen) -> None:
    """Kill the server and the child it runs (its own process group)."""
    with contextlib.suppress(ProcessLookupError):
        os.killpg(process.pid, signal.SIGKILL)
    process.wait()
    for pipe in (process.stdin, process.stdout):
        with contextlib.suppress(OSError):
            pipe.close()


def serve() -> None:
    """The server's loop: warm up, then one forked child per request line on standard input,
    its exit status as a reply line on standard output."""
    import gc
    import importlib
    import pkgutil
    import warnings

    requests = os.fdopen(os.dup(0), "rb")
    replies = os.fdopen(os.dup(1), "wb", buffering=0)
    null = os.open(os.devnull, os.O_RDWR)
    os.dup2(null, 0)
    os.dup2(null, 1)  # sys.stdout keeps the configuration of a pipe, as in a fresh process
    caught: list[str] = []  # warnings shown during the warm-up (the filters stay as the
    show = warnings.showwarning  # imports left them, as in a fresh process)
    warnings.showwarning = lambda message, *_, **__: caught.append(str(message))
    for name in WARM:
        importlib.import_module(name)
    import pkmkit.cli

    for info in pkgutil.iter_modules(pkmkit.cli.__path__, "pkmkit.cli."):
        importlib.import_module(info.name)
    warnings.showwarning = show
    problem = ("the warm-up imported numba" if "numba" in sys.modules else
               f"the warm-up warned (a fresh process would show it): {caught[0]}"
               if caught else None)
    if problem:  # the children would not run what a fresh process runs
        replies.write(json.dumps({"error": problem}).encode() + b"\n")
        return
    replies.write(b'{"ready": true}\n')
    gc.freeze()  # the children do not copy the warm heap by collecting it
    for line in requests:
        request = json.loads(line)
        pid = os.fork()
        if pid == 0:
            requests.close()
            replies.close()
            _child(request, null)
        _, status, usage = os.wait4(pid, 0)
        reply = {"returncode": os.waitstatus_to_exitcode(status),
                 "cpu": usage.ru_utime + usage.ru_stime}
        replies.write(json.dumps(reply).encode() + b"\n")


def _child(request: dict, null: int) -> None:
    """Run one request in the forked child and exit with its status (never returns)."""
    status = 1
    try:
        os.chdir(request["cwd"])
        os.environ.clear()
        os.environ.update(request["env"])
        flags = os.O_WRONLY | os.O_CREAT | os.O_TRUNC
        out = os.open(request["stdout"], flags)
        err = out if request["stderr"] is None else os.open(request["stderr"], flags)
        os.dup2(out, 1)
        os.dup2(err, 2)
        os.dup2(null, 0)
        status = _run(request)
        _finish()
    except BaseException:
        sys.excepthook(*sys.exc_info())
    finally:
        os._exit(status)


def _run(request: dict) -> int:
    """The block's exit status, as the interpreter would give it."""
    import builtins
    import types

    if "cli" in request:
        script = request["script"]
        sys.argv = [script, *request["cli"]]
        sys.path[0] = os.path.dirname(script)  # a console script's first path entry

        def target():
            from pkmkit.cli.main import main

            sys.exit(main())
    else:
        sys.argv = ["-c"]
        main_module = types.ModuleType("__main__")  # as python -c's (the server's is one)
        main_module.__dict__.update(__builtins__=builtins, __annotations__={},
                                    __loader__=sys.modules["__main__"].__loader__)
        sys.modules["__main__"] = main_module
        # dont_inherit: not this file's ``from __future__ import annotations``
        code = compile(request["program"], "<string>", "exec", dont_inherit=True)

        def target():
            exec(code, main_module.__dict__)
    try:
        target()
    except SystemExit as exc:
        if exc.code is None:
            return 0
        if isinstance(exc.code, int):
            return exc.code
        print(exc.code, file=sys.stderr)
        return 1
    except BaseException:
        sys.excepthook(*sys.exc_info())
        return 1
    return 0


def _finish() -> None:
    """What the interpreter does at exit that a block can see: wait for its threads, run the
    exit handlers, flush the standard streams."""
    import atexit
    import threading

    threading._shutdown()
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass


if __name__ == "__main__":
    serve()
