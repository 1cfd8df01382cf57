"""Inside :mod:`pkmkit.calibration`, no module reads another's private names (issue 18 §1):
neither ``from pkmkit.calibration.x import _name`` nor ``x._name`` on an imported calibration
module. (``tools/house.py`` checks this across sub-packages only.)"""

from __future__ import annotations

import ast
from pathlib import Path

import pkmkit.calibration

PACKAGE = Path(pkmkit.calibration.__file__).resolve().parent


def _private_reads(path: Path) -> list[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    modules: set[str] = set()  # local names bound to calibration modules
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and (node.module or "").startswith(
                "pkmkit.calibration"):
            for alias in node.names:
                if alias.name.startswith("_"):
                    found.append(f"{path.name}:{node.lineno} imports {alias.name} from "
                                 f"{node.module}")
                if node.module == "pkmkit.calibration":  # from pkmkit.calibration import x
                    modules.add(alias.asname or alias.name)
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.startswith("pkmkit.calibration.") and alias.asname:
                    modules.add(alias.asname)
    for node in ast.walk(tree):
        if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name)
                and node.value.id in modules and node.attr.startswith("_")
                and not node.attr.startswith("__")):
            found.append(f"{path.name}:{node.lineno} reads {node.value.id}.{node.attr}")
    return found


def test_no_private_cross_module_reads_inside_calibration():
    found = [f for path in sorted(PACKAGE.glob("*.py")) for f in _private_reads(path)]
    assert not found, found
