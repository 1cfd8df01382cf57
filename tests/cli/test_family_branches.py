"""The command line tests no machine family (issue 19 §1, docs/architecture.md "Family branches
in cli"): a family that needs its own output or options is looked up in a dispatch table; the
rest reads the machine protocol."""

from __future__ import annotations

import re
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[2] / "src" / "pkmkit"

#: A test of the family or of the class: ``m.family == …``, ``kind != "chain"``, ``hasattr(m,
#: …)``, ``getattr(m, "…", default)``, ``isinstance(m, …Machine)``.
FAMILY_TEST = re.compile(
    r"\.family\s*(==|!=|\bin\b|\bnot in\b)|\bkind\s*(==|!=)\s*\"(chain|full-pose|translational)\""
    r"|isinstance\(.*Machine\)|hasattr\(m(achine)?, |getattr\(m(achine)?, \"")


def _tests_in(folder: str) -> list[str]:
    found = []
    for path in sorted((PACKAGE / folder).glob("*.py")):
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            if FAMILY_TEST.search(line):
                found.append(f"{folder}/{path.name}:{number}: {line.strip()}")
    return found


def test_the_command_line_tests_no_family():
    assert _tests_in("cli") + _tests_in("boundary") == []


def test_the_pattern_finds_what_it_counts():
    for line in ('if m.family != "translational":', 'kind == "chain"',
                 'if hasattr(m, "characteristic_length")', 'getattr(m, "position_controlled", 0)',
                 "isinstance(m, JointChainMachine)"):
        assert FAMILY_TEST.search(line), line
    for line in ("face = FACES[m.family]", "_FACES.get(m.family, _RODS)",
                 'f"{m.id!r} is a {m.family} machine"'):
        assert not FAMILY_TEST.search(line), line
