"""``pose_orientation`` and ``position_controlled`` (machines.protocol.MachineFace): what a pose
row holds, said by every machine so that callers need not test its family (issue 19)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pkmkit

EXAMPLES = Path(__file__).resolve().parents[2] / "docs" / "examples"
FILES = ("my-machine.toml", "hexapod-6-6.toml", "planar-3rpr.toml")


def _machines():
    for name in pkmkit.machines():
        yield pytest.param(lambda name=name: pkmkit.machine(name), id=name)
    for file in FILES:
        yield pytest.param(lambda file=file: pkmkit.load(str(EXAMPLES / file)), id=file)


@pytest.fixture(params=list(_machines()))
def machine(request):
    return request.param()


def test_the_orientation_form_matches_the_home_pose(machine):
    home = np.asarray(machine.home_pose, dtype=float)
    form = machine.pose_orientation
    assert form in (None, "rotvec", "axis")
    if form is None:  # position only: the pose row is the position
        assert home.shape == (machine.dims,) and machine.dims <= 3
        return
    assert home.shape == (6,)
    if form == "axis":  # a unit tool axis after the tool point
        assert np.linalg.norm(home[3:]) == pytest.approx(1.0, abs=1e-12)


def test_a_position_alone_is_a_pose_only_of_position_controlled_machines(machine):
    if machine.pose_orientation is None:
        assert not machine.position_controlled
        return
    position = np.asarray(machine.home_pose, dtype=float)[:3]
    if machine.position_controlled:
        q = machine.ik(position, strokes="ignore")
        assert np.allclose(q, machine.home_q, atol=1e-7)
    else:
        with pytest.raises(pkmkit.exceptions.PkmError):
            machine.ik(position, strokes="ignore")


def test_the_families_and_forms_agree():
    seen = {pkmkit.machine(name).family: pkmkit.machine(name).pose_orientation
            for name in pkmkit.machines()}
    assert seen == {"translational": None, "full-pose": "rotvec", "chain": "axis"}
