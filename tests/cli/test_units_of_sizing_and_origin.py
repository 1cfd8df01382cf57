"""Lengths in the command's unit, on cheap inputs (the ``ci`` tests check the same on full
runs: ``test_design_cli.py::test_design_linear_delta``,
``test_outputs_in_mm_and_m.py::test_machined_part_origin_in_mm_and_m``):

- ``design linear-delta --json`` prints every length of the sizing (R, r, L, d, the stroke,
  the slider positions q_min, q_max, the centre) in --units: in mm, 1000 times the figures in
  m of the library's result for the same cube (the sizing run on 3 points per edge here);
- ``machined-part simulate --origin`` reads the work offset in the command's unit: 10 mm (the
  default unit) and 0.01 m both reach the machining as 0.01 m."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pkmkit.cli import design_cmds
from pkmkit.design import linear_delta

EXAMPLES = Path(__file__).resolve().parents[2] / "docs" / "examples"
LENGTHS = ("R", "r", "L", "d", "stroke", "q_min", "q_max", "center")


@pytest.fixture
def sizings(monkeypatch):
    """The results the command sized (the library's, on a 3³ grid: about 0.2 s each)."""
    found = []

    def coarse(*args, **kwargs):
        res = linear_delta.size_linear_delta(*args, **kwargs, samples=3, search_samples=3)
        found.append(res)
        return res

    monkeypatch.setattr(design_cmds, "size_linear_delta", coarse)
    return found


def test_design_linear_delta_lengths_in_mm_and_m(run, as_json, sizings):
    args = ("design", "linear-delta", "--bounds", "0.4,1.2", "--objective", "compactness",
            "--json")
    in_mm = as_json(run(*args, "--cube", "200", "--max-leg", "600", "--units", "mm"))
    in_m = as_json(run(*args, "--cube", "0.2", "--max-leg", "0.6", "--units", "m"))
    mm, m = sizings
    assert mm.cube_side == m.cube_side == 0.2 and mm.L == pytest.approx(m.L, rel=1e-12)
    for key in LENGTHS:
        want = np.asarray(getattr(m, key), dtype=float)
        np.testing.assert_allclose(in_m[key], want, rtol=1e-12, err_msg=key)
        np.testing.assert_allclose(in_mm[key], 1000.0 * want, rtol=1e-9, err_msg=key)
    assert in_mm["compactness"] == pytest.approx(in_m["compactness"], rel=1e-9)


class _Stop(Exception):
    """Raised by the spy once it has seen the origin (nothing is machined)."""


def test_machined_part_origin_in_the_commands_unit(run, tmp_path, monkeypatch):
    from pkmkit.machining import study

    seen = []

    def spy(*args, origin, **kwargs):
        seen.append(np.asarray(origin, dtype=float))
        raise _Stop

    monkeypatch.setattr(study, "simulate_cmm", spy)
    monkeypatch.chdir(tmp_path)
    gcode = EXAMPLES / "pocket.nc"
    for args in (["--origin", "10,-20,5"], ["--origin", "0.01,-0.02,0.005", "--units", "m"],
                 ["--origin", "10,-20,5", "--units", "mm"]):
        with pytest.raises(_Stop):
            run("machined-part", "simulate", "verne", "--gcode", gcode, "--out", "cmm.csv",
                *args)
    assert len(seen) == 3
    for origin in seen:
        np.testing.assert_allclose(origin, [0.01, -0.02, 0.005], rtol=1e-12)
