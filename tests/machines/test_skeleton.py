"""The skeleton every family answers (machines/skeleton.py), checked against the closure it
draws: every rod of a rod-leg machine spans its length between its base and platform joints,
and the tool point is the direct model's."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import NoAssemblyError
from pkmkit.machines.registry import machines

ROD_MACHINES = ["orthoglide", "delta", "five-bar-biglide", "linear-delta", "gough-stewart",
                "dietmaier-hexapod", "verne"]


def _moved(m, rng):
    lo, hi = m.home_q - 0.01, m.home_q + 0.01
    return rng.uniform(lo, hi)


@pytest.mark.parametrize("ident", ROD_MACHINES)
def test_each_rod_spans_its_length_at_a_moved_configuration(ident):
    m = pkmkit.machine(ident)
    rng = np.random.default_rng(3)
    q = _moved(m, rng)
    sk = m.skeleton(q)
    rods = [line for line in sk.lines if line.kind == "leg"]
    assert len(rods) == m.model.n_rods
    length = np.array([np.linalg.norm(r.points[1] - r.points[0]) for r in rods])
    expected = np.asarray(m.model.rod_length, dtype=float)
    struts = ~(expected > 0)                       # a strut's length is its actuator's value
    expected = np.where(struts, q[np.asarray(m.model.rod_actuator)], expected)
    np.testing.assert_allclose(length, expected, atol=1e-9)
    pose = np.atleast_1d(m.fk(q))
    np.testing.assert_allclose(sk.tool[:min(3, m.dims)], pose[:min(3, m.dims)], atol=1e-12)


@pytest.mark.parametrize("ident", machines())
def test_every_builtin_draws_at_home_with_its_tool_point(ident):
    m = pkmkit.machine(ident)
    sk = m.skeleton()
    assert all(line.points.shape[1] == 3 and np.isfinite(line.points).all()
               for line in sk.lines)
    assert {line.kind for line in sk.lines} <= {"guide", "leg", "platform", "head", "tool"}
    if m.family == "chain":
        pose = m.fk(m.home_q)
        np.testing.assert_allclose(sk.tool, np.asarray(pose)[:3], atol=1e-12)
        legs = [line for line in sk.lines if line.kind == "leg"]
        assert len(legs) == len(m.model.legs)


def test_no_assembly_is_a_typed_error():
    m = pkmkit.machine("five-bar-biglide")
    with pytest.raises(NoAssemblyError):
        m.skeleton(np.array([-1.0, -0.35]))
