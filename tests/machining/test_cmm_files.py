"""The CMM file format: round trip, and each malformed file a typed error naming its line and
column."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import InputError
from pkmkit.machining.cmm import format_cmm, probe, read_cmm
from pkmkit.machining.part import Cutters, Placement, part_passes
from pkmkit.machining.reconstruct import reconstruct, reconstructed_measurements
from pkmkit.machining.sweep import machine_part
from pkmkit.motion.gcode import read_gcode

PROGRAM = "G21 G90\nG0 X-60 Y-20 Z-50\nG1 X60 F1000\nG0 X-20 Y-60\nG1 Y50\nM30\n"
GOOD = """# units: mm
# points: surface
section,label,x,y,z,path,direction
1,Q,0,-20,-58,3,x
1,M,0,-10,-47,3,x
1,N,0,-10,-43,3,x
2,Q,20,-20,-58,3,x
2,M,20,-10,-47,3,x
2,N,20,-10,-43,3,x
"""


@pytest.fixture(scope="module")
def part():
    m = pkmkit.machine("verne")
    passes = part_passes(read_gcode(PROGRAM))
    return machine_part(m, m, passes, placement=Placement(0.001, -0.002, 0.0, 0.01),
                        sections=12), passes


def _write(tmp_path, text, name="cmm.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.mark.parametrize("points", ["surface", "tip"])
def test_file_round_trip(tmp_path, part, points):
    machined, passes = part
    cmm = probe(machined, np.random.default_rng(1), sigma=1e-6, points=points)
    path = _write(tmp_path, format_cmm(cmm, units="mm"))
    back = read_cmm(path)
    np.testing.assert_allclose(back.points, cmm.points, atol=1e-13)
    assert back.points_kind == points and back.probe_radius == pytest.approx(cmm.probe_radius)
    a, b = reconstruct(cmm), reconstruct(back)
    np.testing.assert_allclose(a.centre, b.centre, atol=1e-12)
    data = reconstructed_measurements(b, passes, program="part.nc")
    assert data.labels[0] == f"{path}:{4 + (points == 'tip')}"  # + the probe_radius line


def test_hand_written_file(tmp_path):
    rec = reconstruct(read_cmm(_write(tmp_path, GOOD)))
    np.testing.assert_allclose(rec.centre, [[0.0, -0.020, -0.050], [0.020, -0.020, -0.050]],
                               atol=1e-15)


@pytest.mark.parametrize("edit, match", [
    (("2,M,", "2,P,"), r"cmm.csv:8: column 'label': 'P' is not Q or M or N"),
    (("2,N,20,-10,-43,3,x", "2,N,20,-10,-43,3,z"),
     r"cmm.csv:9: column 'direction': 'z' is not x or y"),
    (("1,N,0,-10,-43,3,x\n", ""), r"cmm.csv:4: column 'label': section 1 has no N point"),
    (("1,N,0,-10,-43,3,x", "1,Q,0,-20,-57,3,x"),
     r"cmm.csv:6: column 'label': section 1 has a second Q point \(first at .*cmm.csv:4\)"),
    (("2,M,20,-10,-47,3,x", "2,M,20,-10,-47,5,x"),
     r"cmm.csv:8: column 'path': section 2 is path '3' at .*cmm.csv:7, '5' here"),
    (("2,M,20,", "2,M,20.5,"), r"cmm.csv:8: column 'x': section 2's points are not in one "
                               r"section plane"),
    (("1,N,0,-10,", "1,N,0,-30,"), r"cmm.csv:6: column 'y': section 1: M and N lie on "
                                   r"opposite sides"),
    (("1,M,0,-10,", "1,M,0,-17,"), r"cmm.csv:5: column 'y': section 1: the wall point M is 3 mm"
                                   r" from the slot bottom"),
    (("2,Q,20,", "2,Q,0,"), r"section plane"),
    (("1,Q,0,-20,-58", "1,Q,0,-20,deep"), r"cmm.csv:4: column 'z': 'deep' is not a number"),
    (("# points: surface", "# points: tip"), r"cmm.csv: '# points: tip' needs "
                                             r"'# probe_radius: R'"),
    (("# points: surface", "# points: probe"), r"cmm.csv:2: '# points:' must be surface or tip"),
    (("section,label", "sec,label"), r"cmm.csv:3: missing column\(s\) section"),
])
def test_bad_files_name_line_and_column(tmp_path, edit, match):
    path = _write(tmp_path, GOOD.replace(*edit))
    with pytest.raises(InputError, match=match):
        reconstruct(read_cmm(path))


def test_one_section_per_pass_is_refused(tmp_path):
    text = "\n".join(GOOD.splitlines()[:6]) + "\n"
    with pytest.raises(InputError, match=r"cmm.csv:4: column 'path': pass 3 has 1 section"):
        reconstruct(read_cmm(_write(tmp_path, text)))


def test_sections_must_name_a_pass_of_the_program(tmp_path):
    passes = part_passes(read_gcode(PROGRAM))
    rec = reconstruct(read_cmm(_write(tmp_path, GOOD.replace(",3,x", ",4,x"))))
    with pytest.raises(InputError, match=r"cmm.csv:4: column 'path': part.nc has no straight "
                                         r"pass along x or y at line '4' \(its passes are at "
                                         r"lines 3, 5\)"):
        reconstructed_measurements(rec, passes, program="part.nc")
    rec = reconstruct(read_cmm(_write(tmp_path, GOOD.replace(",3,x", ",5,x"))))
    with pytest.raises(InputError, match=r"cmm.csv:4: column 'direction': the pass at line 5 "
                                         r"of part.nc runs along y"):
        reconstructed_measurements(rec, passes, program="part.nc")


def test_wrong_cutter_is_caught(tmp_path):
    with pytest.raises(InputError, match="should be about 5 mm"):
        reconstruct(read_cmm(_write(tmp_path, GOOD)), Cutters(end_mill=0.005))


def test_wall_lean_is_measured(tmp_path):
    """M at 3 mm and N at 7 mm above the floor: N 0.1 mm farther from the slot than M is a wall
    leaning outwards by atan(0.1 / 4)."""
    rec = reconstruct(read_cmm(_write(tmp_path, GOOD.replace("1,N,0,-10,", "1,N,0,-9.9,"))))
    np.testing.assert_allclose(rec.lean, [np.arctan(0.1 / 4), 0.0], atol=1e-12)
    assert list(rec.leaning()) == [0]
