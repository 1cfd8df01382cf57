"""The demos live in ``pkmkit.demos`` and the command-line coordinates in ``pkmkit.boundary``
(issue 19 §4): the old ``pkmkit.cli`` paths still import the same module objects, with a
DeprecationWarning, and nothing inside pkmkit uses them; the demos never import the command
line."""

from __future__ import annotations

import importlib
import re
import sys
import warnings
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[2] / "src" / "pkmkit"

MOVED = [
    ("pkmkit.cli.demo", "pkmkit.demos.run"),
    ("pkmkit.cli.demo_analysis", "pkmkit.demos.analysis"),
    ("pkmkit.cli.demo_calibration", "pkmkit.demos.calibration"),
    ("pkmkit.cli.demo_design", "pkmkit.demos.design"),
    ("pkmkit.cli.demo_errors", "pkmkit.demos.errors"),
    ("pkmkit.cli.demo_machines", "pkmkit.demos.machines"),
    ("pkmkit.cli.demo_machining", "pkmkit.demos.machining"),
    ("pkmkit.cli.demo_motion", "pkmkit.demos.motion"),
    ("pkmkit.cli.demo_stiffness", "pkmkit.demos.stiffness"),
    ("pkmkit.cli.coordinates", "pkmkit.boundary.coordinates"),
]


@pytest.mark.parametrize(("old", "new"), MOVED)
def test_old_path_imports_the_new_module_and_warns(old, new):
    sys.modules.pop(old, None)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        module = importlib.import_module(old)
    assert module is importlib.import_module(new)
    assert module.__spec__.name == new
    assert any(issubclass(w.category, DeprecationWarning) and new in str(w.message)
               for w in caught)


def test_from_import_of_an_old_name():
    sys.modules.pop("pkmkit.cli.demo_errors", None)
    with pytest.warns(DeprecationWarning, match="pkmkit.demos.errors"):
        from pkmkit.cli.demo_errors import error_summary
    from pkmkit.demos.errors import error_summary as new

    assert error_summary is new


def test_a_name_that_never_existed_still_fails():
    with pytest.raises(ModuleNotFoundError):
        importlib.import_module("pkmkit.cli.demo_nothing")


def test_nothing_inside_pkmkit_uses_the_old_paths():
    old = "|".join(re.escape(o) for o, _ in MOVED)
    offenders = [str(p.relative_to(PACKAGE)) for p in PACKAGE.rglob("*.py")
                 if p.name != "__init__.py"
                 and re.search(rf"^\s*(from|import) ({old})\b", p.read_text(), re.M)]
    assert offenders == []


def test_the_demos_do_not_import_the_command_line():
    offenders = [p.name for p in (PACKAGE / "demos").glob("*.py")
                 if re.search(r"^\s*from (pkmkit\.cli|\.\.cli)\b|^\s*import pkmkit\.cli\b",
                              p.read_text(), re.M)]
    assert offenders == []
    assert not any(p.name.startswith("demo") for p in (PACKAGE / "cli").glob("*.py"))
