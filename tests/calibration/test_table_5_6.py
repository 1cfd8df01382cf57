"""Seed 002's identified geometry (Table 5.6) on pkmkit's Tripteor (calibration/table_5_6.py):
the table's entries land on the right defects, and what the evaluation says holds when
checked by the direct model itself."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.calibration.table_5_6 import (
    TABLE_5_6,
    evaluate_table_5_6,
    table_5_6_defects,
    table_5_6_machine_text,
)


@pytest.fixture(scope="module")
def tripteor():
    return pkmkit.machine("tripteor-x7")


@pytest.fixture(scope="module")
def study(tripteor):
    return evaluate_table_5_6(tripteor, n_configurations=20)


def test_absolute_entries_become_differences_from_the_nominal_points(tripteor):
    defects, gauges = table_5_6_defects(tripteor)
    # C62 = -195.0289 mm against pkmkit's -l/2 = -194.93 mm; A63 = 389.8632 against l = 389.86
    assert defects["dc62"] == pytest.approx(-0.0989e-3, abs=1e-12)
    assert defects["da63"] == pytest.approx(0.0032e-3, abs=1e-12)
    assert defects["db12"] == pytest.approx(0.0, abs=1e-12)      # B12 = -L/2 exactly
    assert defects["dJ41"] == 0.1827 and defects["da13"] == -0.7288e-3
    # positions along a joint's own axis: no defect of a minimal parametrisation
    assert sorted(gauges) == ["A12", "A21", "A22", "A23", "A32", "B51", "B52", "B53", "B7"]
    assert len(defects) + len(gauges) == sum(len(row) for row in TABLE_5_6.values())


def test_the_identified_geometry_cannot_assemble_and_its_projection_can(tripteor, study):
    """The least-squares closures of Table 5.6's machine miss by ~0.18 mm everywhere; the
    same defects projected on the compatible subspace close to second order (nm)."""
    assert 1e-4 < study.closure["mean"] <= study.closure["max"] < 3e-4
    assert study.compatible_closure["max"] < 1e-8
    # the largest incompatible defect: A13 = -0.7288 mm, forced to zero with D_ICS^L11 held
    assert study.incompatible_largest[0][0] == "da13"
    assert study.incompatible_largest[0][1] == pytest.approx(-0.7288e-3, rel=1e-6)
    # checked by the direct model itself: A13 alone breaks the closure by its own size
    alone = tripteor.with_defects({"da13": -0.7288e-3})
    res = alone.fk(tripteor.home_q, full_output=True, strokes="ignore")
    assert float(res.closure_residual) > 1e-4


def test_defects_without_effect_on_the_tool_are_the_fourteen_zero_columns(tripteor, study):
    """Each defect alone on the nominal machine: the 14 that move the tool tips at second
    order only are the zero columns of the identification Jacobian (seed-errata Ch. 5 #2,
    found there analytically); J41's 10.5° moves the tool by nothing."""
    assert sorted(study.no_effect_on_tool) == sorted(
        ["dJ21", "dJ41", "dJ12", "dK12", "dJ22", "dK22", "dJ32", "dK32", "dJ23", "dJ43",
         "da51", "da52", "da53", "dI52"])
    assert "dI7" not in study.no_effect_on_tool            # a head tilt: seen once it turns
    q = tripteor.home_q
    moved = tripteor.with_defects({"dJ41": 0.1827}).fk(q, strokes="ignore")
    np.testing.assert_allclose(np.asarray(moved), np.asarray(tripteor.fk(q)), atol=1e-12)


def test_the_machine_file_loads_to_the_same_machine(tripteor, tmp_path):
    path = tmp_path / "tripteor-table-5-6.toml"
    path.write_text(table_5_6_machine_text(tripteor))
    loaded = pkmkit.load(path)
    defects, _ = table_5_6_defects(tripteor)
    direct = tripteor.with_defects(defects)
    np.testing.assert_allclose(loaded.defects(), direct.defects(), atol=1e-15)
    q = tripteor.home_q
    np.testing.assert_allclose(np.asarray(loaded.fk(q, strokes="ignore")),
                               np.asarray(direct.fk(q, strokes="ignore")), atol=1e-12)


def test_the_documented_machine_file_is_the_code_s(tripteor):
    from pathlib import Path

    shipped = Path(__file__).parents[2] / "docs" / "examples" / "tripteor-table-5-6.toml"
    assert shipped.read_text() == table_5_6_machine_text(tripteor)
