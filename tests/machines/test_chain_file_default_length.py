"""A joint-chain machine file without ``characteristic_length`` gets the documented default,
0.5 m (docs/joint-chains.md), whatever the file's unit (issue 18 §9, plausible bugs: the
default read as 0.5 in the file's unit gave 0.5 mm to a file in mm and passed every test)."""

import re
from pathlib import Path

import pytest

import pkmkit
from pkmkit.machines.chain_file import machine_file_text

CRANK_SLIDER = Path(__file__).resolve().parents[2] / "docs" / "examples" / "crank-slider.toml"


def test_crank_slider_in_mm_without_a_characteristic_length(tmp_path):
    text = CRANK_SLIDER.read_text()
    assert 'units = "mm"' in text
    path = tmp_path / "cs.toml"
    path.write_text(re.sub(r"characteristic_length = 300.*\n", "", text))
    assert "characteristic_length" not in path.read_text()
    assert pkmkit.load(CRANK_SLIDER).model.characteristic_length == pytest.approx(0.3)
    assert pkmkit.load(path).model.characteristic_length == pytest.approx(0.5, rel=1e-12)


@pytest.mark.parametrize("units", ["m", "mm", "in"])
def test_tripteor_file_without_a_characteristic_length_in_every_unit(tmp_path, units):
    text = machine_file_text(pkmkit.machine("tripteor-x7"), units=units)
    path = tmp_path / f"t-{units}.toml"
    path.write_text(re.sub(r"characteristic_length\s*=.*\n", "", text))
    assert pkmkit.load(path).model.characteristic_length == pytest.approx(0.5, rel=1e-12)
