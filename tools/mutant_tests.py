"""Which test files exercise which function of a package: the map that lets a mutant run only
the tests that reach the code it changes (``tools/mutation.py --plausible``).

The map is derived, not declared: one run of the package's tests (``pytest -p mutant_tests``,
this module as a plugin) records, for each test file, the Python functions of
``src/pkmkit/<package>`` it calls (a profile hook on ``call`` events, all threads).
:func:`tests_for` then answers, for a line of a source file:

1. the test files that called the innermost function (``def``) holding the line;
2. where no test called that function (a module-level line, a class attribute, a function only
   compiled by Numba, one only the ``ci``/``slow`` tests reach): the test files that called any
   function of the module;
3. where no test called anything of the module: ``None`` (the caller falls back to the
   package's whole test directory).

The map is written to ``mutants/test_map_<package>.json`` (git-ignored) with a hash of the
package's sources and test files; a changed source or test makes it stale and it is derived
again (one run of the package's tests, about as long as the run of one mutant on the whole
directory). Line numbers are those of the sources the map was derived from: derive it from
the same tree the mutants are planted from.
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
        code = frame.f_code
        if code.co_filename.startswith(_SOURCE):
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


def _fingerprint(package: str, tests: list[str]) -> str:
    digest = hashlib.sha256()
    files = sorted(_sources(package).rglob("*.py"))
    for t in tests:
        p = ROOT / t
        files += sorted(p.rglob("*.py")) if p.is_dir() else [p]
    for f in files:
        digest.update(str(f.relative_to(ROOT)).encode())
        digest.update(f.read_bytes())
    return digest.hexdigest()


def derive(package: str, tests: list[str], *, markers: str, pythonpath: Path,
           timeout: float) -> dict:
    """The map of ``package`` (``machines``), from one run of ``tests`` with ``markers``,
    importing the sources under ``pythonpath``; read from ``mutants/`` when still fresh."""
    out = ROOT / "mutants" / f"test_map_{package}.json"
    stamp = _fingerprint(package, tests) + markers
    if out.exists():
        saved = json.loads(out.read_text())
        if saved.get("stamp") == stamp:
            return saved["functions"]
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
    out.write_text(json.dumps({"stamp": stamp, "functions": functions}))
    return functions


def _enclosing_def(source: str, line: int) -> int | None:
    """The first line of the innermost function holding ``line`` (its first decorator's line,
    as ``co_firstlineno``), or None at module or class level."""
    best = None
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) \
                and node.lineno <= line <= node.end_lineno:
            first = min([node.lineno, *(d.lineno for d in node.decorator_list)])
            if best is None or first > best:
                best = first
    return best


def tests_for(functions: dict, name: str, source: str, line: int) -> list[str] | None:
    """The test files that exercise ``line`` of the source file ``name`` (``machine.py``)
    whose text is ``source`` (module doc), or None where the map knows no test of it."""
    module = functions.get(name)
    if not module:
        return None
    first = _enclosing_def(source, line)
    if first is not None and str(first) in module:
        return module[str(first)]
    return sorted({t for tests in module.values() for t in tests})
