"""The typed errors of ``pkmkit.exceptions``: the facts they carry and where
their message says the problem is."""

import pytest

import pkmkit
from pkmkit.exceptions import OutOfStrokeError, PkmError, UnknownMachineError


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


def test_unknown_machine_message_is_the_plain_text():
    """``str()`` of an unknown machine id is its message, not the quoted repr a KeyError would
    print, and it is what ``pkmkit.machine`` raises for a wrong id."""
    err = UnknownMachineError("delta", ["orthoglide", "linear-delta"])
    assert str(err) == "unknown machine 'delta'; valid ids: linear-delta, orthoglide"
    assert isinstance(err, KeyError) and err.valid == ["linear-delta", "orthoglide"]
    with pytest.raises(UnknownMachineError, match=r"^unknown machine 'no-such-machine'; valid"):
        pkmkit.machine("no-such-machine")
