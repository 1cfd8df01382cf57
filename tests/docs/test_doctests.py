"""The ``>>>`` examples in pkmkit's docstrings run as written."""

import doctest
import importlib
import pkgutil

import pytest

import pkmkit

MODULES = sorted(info.name for info in pkgutil.walk_packages(pkmkit.__path__, "pkmkit."))


def _examples(name):
    module = importlib.import_module(name)
    return [t for t in doctest.DocTestFinder().find(module) if t.examples]


WITH_EXAMPLES = [name for name in MODULES if _examples(name)]


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
