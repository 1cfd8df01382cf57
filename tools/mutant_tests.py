"""Which test files exercise which function of a package: the map that lets a mutant run only
the tests that reach the code it changes (``tools/mutation.py --plausible``).

The map is derived, not declared: one run of the package's tests (``pytest -p mutant_tests``,
this module as a plugin) records, for each test file, the Python functions of
``src/pkmkit/<package>`` it calls (a profile hook on ``call`` events, all threads).
:meth:`TestMap.tests_for` then answers, for a line of a source file:

1. the test files that called the innermost function (``def``) holding the line;
2. where no test called that function (a module-level line, a class attribute, one only the
   ``ci``/``slow`` tests reach): the test files that called any function of the module;
3. ``None`` (the caller runs the package's whole test directory) where no test called
   anything of the module, or where the line is in a function Numba compiles (its Python
   code never runs: no call is seen).

A module's own code (run once, when its first importer imports it) is not counted as a call.
The map is written to ``mutants/test_map_<package>.json`` (git-ignored) with a hash of the
package's sources (a changed source derives it again: one run of the package's tests, the cost
of one mutant on the whole directory) and of each test file: a test file added or changed
since is run for every mutant (so a new killer is tried on the survivors at once). Line
numbers are those of the sources the map was derived from: derive it from the tree the
mutants are planted from.
"""

from __future__ import annotations

import ast
import hashlib
import json
import os
import subprocess
import sys
import threading
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
#: Set by the plugin's process: the package's source directory (absolute, resolved).
_SOURCE = os.environ.get("PKMKIT_TEST_MAP_SOURCE")
_OUT = os.environ.get("PKMKIT_TEST_MAP_OUT")

_calls: dict[str, set[tuple[str, int]]] = {}
_current: list[str] = [""]


def _profile(frame, event, arg):
    if event == "call":
        code = frame.f_code  # a module's own code runs once, for its first importer: left out
        if code.co_filename.startswith(_SOURCE) and code.co_name != "<module>":
            _calls.setdefault(_current[0], set()).add(
                (Path(code.co_filename).name, code.co_firstlineno))


def _test_file(node) -> str:
    return node.path.relative_to(node.config.rootpath).as_posix()


def pytest_collectstart(collector):
    """A test file's module-level code (run when it is collected) counts as its own."""
    if getattr(collector, "path", None) is not None and collector.path.suffix == ".py":
        _current[0] = _test_file(collector)


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_setup(item):
    _current[0] = _test_file(item)


def pytest_sessionstart(session):
    if _SOURCE:
        sys.setprofile(_profile)
        threading.setprofile(_profile)


def pytest_sessionfinish(session, exitstatus):
    if not (_SOURCE and _OUT):
        return
    sys.setprofile(None)
    threading.setprofile(None)
    by_function: dict[str, dict[str, set[str]]] = {}
    for test, calls in _calls.items():
        for module, line in calls:
            if test:
                by_function.setdefault(module, {}).setdefault(str(line), set()).add(test)
    Path(_OUT).write_text(json.dumps(
        {m: {k: sorted(v) for k, v in f.items()} for m, f in by_function.items()}, indent=0))


# ------------------------------------------------------------------ deriving and reading


def _sources(package: str) -> Path:
    return ROOT / "src" / "pkmkit" / package


def _digest(files: list[Path]) -> str:
    digest = hashlib.sha256()
    for f in files:
        digest.update(str(f.relative_to(ROOT)).encode())
        digest.update(f.read_bytes())
    return digest.hexdigest()


def _test_files(tests: list[str]) -> list[Path]:
    files = []
    for t in tests:
        p = ROOT / t
        files += sorted(p.rglob("*.py")) if p.is_dir() else [p]
    return files


class TestMap:
    """The derived map: ``functions`` (source file name → first line of a function → test
    files that called it) and ``extra``, the test files added or changed since it was derived
    (run for every mutant: a new killer is tried on the survivors without deriving again)."""

    __test__ = False  # not a pytest class

    def __init__(self, functions: dict, extra: list[str]):
        self.functions, self.extra = functions, extra

    def tests_for(self, name: str, source: str, line: int) -> list[str] | None:
        """The test files that exercise ``line`` of the source file ``name`` (``machine.py``)
        whose text is ``source`` (module doc), or None where the map cannot tell: no test
        called the module, or the line is in a function compiled by Numba (``@njit``: its
        Python code never runs, so no call of it is seen)."""
        module = self.functions.get(name)
        first, compiled = _enclosing_def(source, line)
        if not module or compiled:
            return None
        found = module.get(str(first)) if first is not None else None
        if found is None:
            found = sorted({t for tests in module.values() for t in tests})
        return sorted(set(found) | set(self.extra))


def derive(package: str, tests: list[str], *, markers: str, pythonpath: Path,
           timeout: float) -> TestMap:
    """The map of ``package`` (``machines``), from one run of ``tests`` with ``markers``,
    importing the sources under ``pythonpath``; read from ``mutants/`` while the package's
    sources are those it was derived from (a changed or new test file is run for every
    mutant instead: :class:`TestMap`)."""
    out = ROOT / "mutants" / f"test_map_{package}.json"
    stamp = _digest(sorted(_sources(package).rglob("*.py"))) + markers
    files = _test_files(tests)
    now = {str(f.relative_to(ROOT)): _digest([f]) for f in files}
    if out.exists():
        saved = json.loads(out.read_text())
        if saved.get("stamp") == stamp:
            extra = [f for f, h in now.items() if saved["tests"].get(f) != h]
            return TestMap(saved["functions"], extra)
    out.parent.mkdir(parents=True, exist_ok=True)
    raw = out.with_suffix(".raw.json")
    env = {**os.environ, "PYTHONPATH": f"{ROOT / 'tools'}{os.pathsep}{pythonpath}",
           "PKMKIT_TEST_MAP_SOURCE": str((pythonpath / "pkmkit" / package).resolve()),
           "PKMKIT_TEST_MAP_OUT": str(raw), "HYPOTHESIS_PROFILE": "mutation"}
    subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p",
                    "mutant_tests", "-m", markers, *tests], cwd=ROOT, env=env,
                   stdout=subprocess.DEVNULL, timeout=timeout, check=False)
    functions = json.loads(raw.read_text())
    raw.unlink()
    out.write_text(json.dumps({"stamp": stamp, "tests": now, "functions": functions}))
    return TestMap(functions, [])


def _enclosing_def(source: str, line: int) -> tuple[int | None, bool]:
    """The first line of the innermost function holding ``line`` (its first decorator's line,
    as ``co_firstlineno``; None at module or class level), and whether it or a function
    around it is compiled by Numba (a decorator naming ``jit``)."""
    best, compiled = None, False
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) \
                and node.lineno <= line <= node.end_lineno:
            first = min([node.lineno, *(d.lineno for d in node.decorator_list)])
            compiled |= any("jit" in ast.unparse(d) for d in node.decorator_list)
            if best is None or first > best:
                best = first
    return best, compiled
