"""The documentation runs: every console and Python block of README.md and docs/*.md is
executed in a temporary folder (one per file, with ``docs/examples``, ``bench``, ``tests`` and
``pyproject.toml`` beside it) and what it prints is compared with what the documentation shows
(see ``docs_blocks``). Blocks marked ``ci`` (long examples) carry the pytest marker ``ci``: the
ordinary run leaves them out, ``.ci/run`` runs them (``python -m pytest -m "slow or ci"``). The
blocks of one file share its folder and run in order, so under pytest-xdist they go to one
worker (``xdist_group``, with ``--dist loadgroup``). A plain ``pkmkit ...`` command and a Python
block run in a child forked from a pre-warmed process (``fork_server``: a fresh process state
without the start-up of a new interpreter); other commands run through bash, and every block
does with ``PKMKIT_DOCS_FRESH=1``."""

import atexit
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from .docs_blocks import blocks, compare
from .fork_server import ForkServer, shell_words

ROOT = Path(__file__).resolve().parents[2]
FILES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
ALL_BLOCKS = [b for path in FILES for b in blocks(path)]
TIMEOUT = 900


class PageFolders:
    """One working folder per documentation file, shared by its blocks in order. A block whose
    page has earlier ordinary blocks that did not run in this session (a ``-m ci`` run, or a
    ``-k`` selection, leaves them out) gets them run first, unchecked, for the files they
    write; blocks marked ``ci`` or ``skip`` are never run that way."""

    def __init__(self, tmp_path_factory):
        self._factory = tmp_path_factory
        self._made: dict[Path, Path] = {}
        self._ran: set[tuple[Path, int]] = set()

    def __call__(self, block) -> Path:
        path = block.path
        if path not in self._made:
            work = self._factory.mktemp(path.stem)
            shutil.copytree(ROOT / "docs" / "examples", work / "docs" / "examples")
            (work / "bench").symlink_to(ROOT / "bench")
            # the documentation's test commands run the repository's tests and configuration
            (work / "tests").symlink_to(ROOT / "tests")
            (work / "pyproject.toml").symlink_to(ROOT / "pyproject.toml")
            self._made[path] = work
        work = self._made[path]
        for earlier in blocks(path):
            if earlier.line >= block.line:
                break
            if ((path, earlier.line) not in self._ran and "skip" not in earlier.options
                    and "ci" not in earlier.options):
                _run(earlier, work, check=False)
                self._ran.add((path, earlier.line))
        self._ran.add((path, block.line))
        return work


@pytest.fixture(scope="module")
def folders(tmp_path_factory):
    return PageFolders(tmp_path_factory)


def _environment() -> dict[str, str]:
    env = dict(os.environ)
    env["PATH"] = str(Path(sys.executable).parent) + os.pathsep + env.get("PATH", "")
    env["COLUMNS"] = "100"
    env.pop("PYTHONPATH", None)
    return env


def _params():
    params = []
    for block in ALL_BLOCKS:
        marks = [pytest.mark.xdist_group(block.path.name)]
        if "skip" in block.options:
            marks.append(pytest.mark.skip(reason=block.options["skip"]))
        elif "ci" in block.options:
            marks.append(pytest.mark.ci)
        params.append(pytest.param(block, id=block.name, marks=marks))
    return params


@pytest.mark.parametrize("block", _params())
def test_block_runs_as_shown(block, folders):
    _run(block, folders(block), check=True)


def _run(block, work: Path, check: bool) -> None:
    """Run one block in ``work``; with ``check``, compare its exit statuses and output with
    what the page shows."""
    env = _environment()
    fresh = "fresh" in block.options or os.environ.get("PKMKIT_DOCS_FRESH") == "1"
    if block.lang == "python":
        program, expected = block.program()
        returncode, stdout, stderr = _python(program, work, env, fresh)
        if not check:
            return
        assert returncode == 0, f"{block.name}: {stderr}"
        if expected:
            problem = compare(expected, stdout, numbers="any-numbers" not in block.options)
            assert problem is None, f"{block.name}\n{problem}"
        return
    for command in block.commands():
        returncode, output = _command(command.text, work, env, fresh)
        if not check:
            continue
        where = f"{block.path.name}:{command.line}: $ {command.text}"
        shows_error = bool(command.expected) and command.expected[0].startswith("Error:")
        if shows_error:
            assert returncode == 1, f"{where}\nexpected a failure, got:\n{output}"
        else:
            assert returncode in (0, 3), f"{where}\nexit {returncode}:\n{output}"
        if command.expected:
            problem = compare(command.expected, output,
                              numbers="any-numbers" not in block.options)
            assert problem is None, f"{where}\n{problem}"


_SERVER: list[ForkServer] = []


def _server(env: dict[str, str]) -> ForkServer:
    """This test process's fork server (started on first use, stopped at exit)."""
    if not _SERVER:
        _SERVER.append(ForkServer(env))
        atexit.register(_SERVER[0].close)
    return _SERVER[0]


def _python(program: str, work: Path, env: dict[str, str], fresh: bool) -> tuple[int, str, str]:
    """``python -c PROGRAM`` in ``work``: a child of the fork server, or with ``fresh`` a new
    interpreter; (exit status, stdout, stderr)."""
    if not fresh:
        return _server(env).run({"program": program, "cwd": str(work), "env": env},
                                merge=False, timeout=TIMEOUT)
    done = subprocess.run([sys.executable, "-c", program], cwd=work, env=env,
                          capture_output=True, text=True, timeout=TIMEOUT)
    return done.returncode, done.stdout, done.stderr


def _command(text: str, work: Path, env: dict[str, str], fresh: bool) -> tuple[int, str]:
    """One console command in ``work``, stderr merged into stdout: a plain ``pkmkit ...``
    (no shell feature but quoting) in a child of the fork server, anything else (or with
    ``fresh``) through bash; (exit status, output)."""
    words = None if fresh else shell_words(text)
    script = shutil.which("pkmkit", path=env["PATH"])
    if words and words[0] == "pkmkit" and script:
        returncode, output, _ = _server(env).run(
            {"cli": words[1:], "script": script, "cwd": str(work), "env": env},
            merge=True, timeout=TIMEOUT)
        return returncode, output
    done = subprocess.run(["bash", "-c", text], cwd=work, env=env, stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True, timeout=TIMEOUT)
    return done.returncode, done.stdout


def test_every_file_an_example_reads_ships_with_the_docs():
    """Paths in the commands that are not written by an earlier command of the same file (as
    ``--out``/``--output``, a redirection, or a file its shown output reports as ``→ FILE``)
    exist under docs/examples (or are the repository's own scripts)."""
    import re
    import shlex

    for path in FILES:
        written: set[str] = set()
        for block in blocks(path):
            if block.lang == "python" or "skip" in block.options:
                continue
            for command in block.commands():
                words = shlex.split(command.text.split("  #")[0], comments=True)
                for k, word in enumerate(words):
                    if word in (">", ">>") and k + 1 < len(words):
                        written.add(words[k + 1])
                    if words[max(k - 1, 0)] in ("--out", "--output"):
                        written.add(word)
                for shown in command.expected:  # a file the (checked) output says it wrote
                    written.update(re.findall(r"→ ([\w./-]+\.[A-Za-z]\w*)\b", shown))
                for word in words:
                    if re.fullmatch(r"[\w./-]+\.(toml|yaml|yml|nc|csv|parquet|feather|py)",
                                    word) and word not in written:
                        assert (ROOT / word).exists() or any(
                            word.startswith(w.rstrip("/") + "/") for w in written), (
                            f"{path.name}:{command.line}: {word} is not shipped")


def test_the_comparison_catches_a_wrong_number_and_a_dropped_line():
    from .docs_blocks import compare

    shown = ["result 1.235 m", "  next [0.5, 2]"]
    assert compare(shown, "result 1.2351 m\n  next [0.5, 2]\n") is None
    assert compare(shown, "result 1.2371 m\n  next [0.5, 2]\n") is not None
    assert compare(shown, "result 1.235 m\n  extra\n  next [0.5, 2]\n") is not None
    assert compare(["result 1.235 m", "...", "  next [0.5, 2]"],
                   "result 1.235 m\n  extra\n  more\n  next [0.5, 2]\n") is None
    assert compare(["a ... z 3"], "a b c z 3\n") is None
    assert compare(["q = 1.5 m      # table: 1.50"], "q = 1.5 m\n") is None


def test_a_python_session_and_a_program_output_are_compared(tmp_path):
    """``>>>`` sessions show what the interpreter shows; an ``output`` block is a program's."""
    page = tmp_path / "page.md"
    page.write_text("""```python
>>> x = [1.25,
...      2]
>>> x
[1.25, 2]
>>> for k in x:
...     print(k * 2)
2.5
4
```

```python
print(3.14159)
```

<!-- docs-test: output -->
```text
3.1416
```
""")
    session, program = blocks(page)
    source, shown = session.program()
    done = subprocess.run([sys.executable, "-c", source], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert shown == ["[1.25, 2]", "2.5", "4"]
    assert compare(shown, done.stdout) is None
    assert compare(["[1.25, 5]", "2.5", "4"], done.stdout) is not None
    source, shown = program.program()
    assert shown == ["3.1416"]
    done = subprocess.run([sys.executable, "-c", source], capture_output=True, text=True)
    assert compare(shown, done.stdout) is None
    assert compare(["3.1426"], done.stdout) is not None


def test_a_mismatch_in_a_long_output_is_found_quickly():
    """A long output that does not have the shown form, with many ``...`` lines, is rejected in
    time linear in (shown lines × output lines): one regex over the whole text backtracked
    exponentially there, and a changed demo output hung the suite."""
    import time

    shown = []
    for k in range(40):
        shown += ["...", f"== section {k}", "   value 1.5 m"]
    actual = "\n".join(f"== section {k}\n   value 1.5 m\n   note" for k in range(40))
    start = time.perf_counter()
    assert compare([*shown, "== missing"], actual) is not None
    assert compare([*shown, "..."], actual) is None
    assert time.perf_counter() - start < 30  # a hang guard, not a benchmark


def test_a_block_run_alone_first_gets_the_files_of_the_earlier_blocks(tmp_path_factory):
    """A ``ci`` block whose page's ordinary blocks ran in another session (``.ci/run``'s
    ``-m "slow or ci"``) finds the files they write; an earlier ``ci`` block is not replayed."""
    page = tmp_path_factory.mktemp("page") / "page.md"
    page.write_text("""```console
$ echo 1.5 > value.txt
```

<!-- docs-test: ci -->
```console
$ echo 2.5 > other.txt
```

<!-- docs-test: ci -->
```console
$ cat value.txt
1.5
$ test -e other.txt || echo absent
absent
```
""")
    first, _, last = blocks(page)
    folders = PageFolders(tmp_path_factory)
    _run(last, folders(last), check=True)
    assert (folders(first) / "value.txt").read_text() == "1.5\n"
