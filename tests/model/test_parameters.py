import math

import numpy as np
import pytest

from pkmkit.exceptions import ParameterError, UnknownParameterError
from pkmkit.model.parameters import ParameterSpec, length_scale, resolve_parameters

LENGTH = ParameterSpec("L", "length", 1.0, "rod", positive=True)
ANGLES = ParameterSpec("angles", "angle", (0.0, 1.0, 2.0), "slides", size=3)
POINT = ParameterSpec("A", "length", (0.0, 0.0), "origin", size=2)


def test_boundary_conversions():
    assert LENGTH.from_boundary(1300, "mm", "m") == pytest.approx(1.3)
    assert ANGLES.from_boundary([0, 120, 240], "mm", "m") == pytest.approx(
        (0.0, 2 * math.pi / 3, 4 * math.pi / 3)
    )
    assert LENGTH.to_boundary(1.3, "mm") == pytest.approx(1300)
    assert ANGLES.to_boundary((0.0, math.pi / 2, math.pi), "m") == pytest.approx([0, 90, 180])
    assert POINT.parse_text("700, -700", "mm", "m") == pytest.approx((0.7, -0.7))
    assert LENGTH.boundary_unit("mm") == "mm" and ANGLES.boundary_unit() == "deg"


@pytest.mark.parametrize(
    "spec, value, message",
    [
        (LENGTH, -1.0, "must be > 0"),
        (LENGTH, (1.0, 2.0), "scalar"),
        (POINT, (1.0, 2.0, 3.0), "vector of 2"),
        (LENGTH, float("nan"), "finite"),
        (LENGTH, "abc", "numeric"),
        (ANGLES, (0.0, 120.0, 240.0), "radians"),
    ],
)
def test_validation_errors_name_the_parameter(spec, value, message):
    with pytest.raises(ParameterError, match=message) as info:
        spec.validate(value, "some-machine")
    assert info.value.parameter == spec.name


def test_degrees_out_of_range_at_the_boundary():
    with pytest.raises(ParameterError, match=r"of 'x' is an angle in degrees within \[-360"):
        ANGLES.from_boundary([0, 120, 400], "m", "x")
    with pytest.raises(ParameterError, match="of 'x' must be > 0"):  # the machine is named
        LENGTH.from_boundary(-3.0, "mm", "x")


@pytest.mark.parametrize("value", [7.0, -7.0, 9.0])
def test_radians_beyond_a_turn_are_refused(value):
    """Between 2π and 3π: an angle in degrees passed to the Python API by mistake."""
    with pytest.raises(ParameterError, match="2π"):
        ANGLES.validate((0.0, 1.0, value), "m")
    assert ANGLES.validate((0.0, 1.0, 6.28), "m") == pytest.approx((0.0, 1.0, 6.28))


def test_parse_text_rejects_words():
    with pytest.raises(ParameterError, match="comma-separated"):
        POINT.parse_text("1,b", "m", "x")


def test_resolve_unknown_lists_valid_names():
    with pytest.raises(UnknownParameterError, match="valid parameters: A, L, angles"):
        resolve_parameters((LENGTH, ANGLES, POINT), {"bogus": 1.0}, "m")
    values = resolve_parameters((LENGTH, POINT), {"L": np.float64(2.0)}, "m")
    assert values == {"L": 2.0, "A": (0.0, 0.0)}


def test_unknown_unit():
    with pytest.raises(ParameterError, match="unknown length unit"):
        length_scale("inch")


def test_inch_units_for_machine_tool_users():
    """Inches are a length unit of the field (G20 programs, US machine tools)."""
    from click.testing import CliRunner

    from pkmkit.cli.main import cli
    from pkmkit.model.parameters import length_scale

    assert length_scale("in") == 0.0254
    runner = CliRunner()
    inch = runner.invoke(cli, ["ik", "linear-delta", "--pose", "1,2,8", "--units", "in",
                               "--json"])
    metre = runner.invoke(cli, ["ik", "linear-delta", "--pose", "0.0254,0.0508,0.2032",
                                "--json"])
    import json

    q_in = json.loads(inch.stdout)["q"]
    q_m = json.loads(metre.stdout)["q"]
    assert q_in == pytest.approx([v / 0.0254 for v in q_m], rel=1e-12)
