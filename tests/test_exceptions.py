"""The typed errors of ``pkmkit.exceptions``: the facts they carry and where
their message says the problem is."""

import pytest

from pkmkit.exceptions import OutOfStrokeError, PkmError


def test_out_of_stroke_names_the_batch_row_when_given():
    """Documented: ``pose_index`` is the row when the value came from a batch, and the message
    says where; a single value has no row prefix."""
    msg = "Q1 = 50° is beyond its stroke [-45, 45]°"
    err = OutOfStrokeError(msg, "Q1", 0.87, (-0.785, 0.785), pose_index=3)
    assert str(err) == f"pose 3: {msg}"
    assert err.pose_index == 3 and err.joint == "Q1"
    assert err.stroke == pytest.approx((-0.785, 0.785)) and isinstance(err, PkmError)
    first = OutOfStrokeError(msg, "Q1", 0.87, (-0.785, 0.785), pose_index=0)  # 0 is a row
    assert str(first) == f"pose 0: {msg}"
    single = OutOfStrokeError(msg, "Q1", 0.87, (-0.785, 0.785))
    assert str(single) == msg and single.pose_index is None
