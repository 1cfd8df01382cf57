"""Error messages in the unit the command asked for (issue 18 §5): with ``--units mm`` no
line mixes metres and millimetres."""

import re

import pytest

import pkmkit
from pkmkit.cli.unit_text import MACHINE_KEY, UNITS_KEY, in_units


def _metres(text: str) -> list[str]:
    """Lengths a text marks with ``m`` (a number or a list followed by `` m``)."""
    return re.findall(r"[\d\]] m\b(?![/²³])", text)


@pytest.mark.parametrize("args, expected", [
    (["fk", "gough-stewart", "--q", "100,100,100,100,100,3000"],
     "q = [100, 100, 100, 100, 100, 3000] mm: no assembly found from the guess (closure "
     "residual 1670 mm)"),
    (["fk", "linear-delta", "--q", "100,100,5000"], "q = [100, 100, 5000] mm admits no real"),
    (["ik", "linear-delta", "--pose", "5000,0,0"], "is too short by 3996.46 mm to reach it"),
    (["path", "delta", "--line", "0,0,-0.8,0.05,0,-0.8", "--feed", "0.05", "--accel", "1"],
     "(leg 1 too short by 294.998 mm): first at t = 0 s, pose [0, 0, -0.8] mm"),
])
def test_command_errors_are_in_the_units_asked(run, args, expected):
    result = run(*args, "--units", "mm")
    assert result.exit_code == 1
    assert expected in result.output
    assert _metres(result.output) == [], result.output


def test_in_metres_the_message_is_the_library_s(run):
    result = run("ik", "linear-delta", "--pose", "5,0,0")
    assert "is too short by 3.99646 m to reach it" in result.output


def test_in_units_converts_lengths_vectors_and_keeps_other_units():
    m = pkmkit.machine("gough-stewart")
    meta = {UNITS_KEY: "mm", MACHINE_KEY: m}
    assert in_units("stroke [0.65, 1.1] m, 2.5 m beyond; 3 mm; 4 m/s", meta) == (
        "stroke [650, 1100] mm, 2500 mm beyond; 3 mm; 4 m/s")
    assert in_units("pose [0.0, 0.0, 1.0, 0.1, 0.0, 0.0] is far", meta) == (
        "pose [0, 0, 1000, 0.1, 0, 0] (mm, rotation vector in rad) is far")
    assert in_units("q = [1, 2] mm stays", meta) == "q = [1, 2] mm stays"
    delta = pkmkit.machine("delta")
    assert in_units("q = [0.5, 0.5, 0.5] fails", {UNITS_KEY: "mm", MACHINE_KEY: delta}) == (
        "q = [28.6479, 28.6479, 28.6479] deg fails")
    assert in_units("1.5 m", {UNITS_KEY: "m", MACHINE_KEY: m}) == "1.5 m"
    assert in_units("1.5 m", {}) == "1.5 m"
