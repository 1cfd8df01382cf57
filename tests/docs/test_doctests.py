"""The ``>>>`` examples in pkmkit's docstrings run as written.

The modules with examples are found by their source text (a ``>>>`` in the file), not by
importing every module at collection: each pytest-xdist worker collects the whole suite, and
importing pkmkit's ~300 modules there (Numba among them) cost each worker ≈ 0.6 s of CPU
(docs/testing.md, "Seventh round"). One test imports them all and checks that the scan finds
exactly the modules whose docstrings hold examples."""

import doctest
import importlib
import pkgutil
from pathlib import Path

import pytest

import pkmkit

ROOT = Path(pkmkit.__file__).parent


def _source_modules() -> dict[str, Path]:
    """Every pkmkit module written in Python, by name, from the files under the package."""
    modules = {}
    for path in sorted(ROOT.rglob("*.py")):
        parts = path.relative_to(ROOT).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        if any(not p.isidentifier() for p in parts):
            continue
        modules[".".join(("pkmkit", *parts))] = path
    return modules


SOURCES = _source_modules()
WITH_EXAMPLES = sorted(name for name, path in SOURCES.items()
                       if name != "pkmkit" and ">>>" in path.read_text(encoding="utf-8"))


def _examples(name):
    module = importlib.import_module(name)
    return [t for t in doctest.DocTestFinder().find(module) if t.examples]


def test_the_scan_finds_every_module_with_examples():
    """The oracle of the source scan: every module the package walk finds, imported, and its
    docstrings searched by doctest; the Python modules are the files scanned."""
    walked = sorted(info.name for info in pkgutil.walk_packages(pkmkit.__path__, "pkmkit."))
    found = {name for name in ["pkmkit", *walked] if _examples(name)}
    compiled = {name for name in walked if name not in SOURCES}
    assert all(importlib.import_module(name).__file__.endswith((".so", ".pyd"))
               for name in compiled), compiled
    assert set(SOURCES) == {"pkmkit", *walked} - compiled
    assert found == set(WITH_EXAMPLES) | ({"pkmkit"} & found)


def test_the_public_api_has_examples():
    expected = {"pkmkit", "pkmkit.motion.timelaw", "pkmkit.motion.joints",
                "pkmkit.dynamics.trajectory", "pkmkit.analysis.region_check",
                "pkmkit.io.table", "pkmkit.motion.extrema", "pkmkit.analysis.inscribed"}
    names = set(WITH_EXAMPLES) | ({"pkmkit"} if _examples("pkmkit") else set())
    assert expected <= names, expected - names


@pytest.mark.parametrize("name", ["pkmkit", *WITH_EXAMPLES])
def test_docstring_examples(name):
    runner = doctest.DocTestRunner(optionflags=doctest.NORMALIZE_WHITESPACE | doctest.ELLIPSIS)
    for test in _examples(name):
        runner.run(test)
    result = runner.summarize(verbose=False)
    assert result.failed == 0 and result.attempted > 0
