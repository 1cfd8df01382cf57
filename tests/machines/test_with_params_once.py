"""``with_params`` builds the new machine once (it built it, then again through
``dataclasses.replace`` to add the kept poses), with the same result.

The oracle is the former two-step path, written out here: the kind's machine with its reference
poses, then ``replace`` adding this machine's other poses (and, for a full-pose machine, its
characteristic length when given, else None so that the new geometry's default is taken and
stays "not given": the former path passed the old default through ``replace``, which then
counted as given and stuck through a second ``with_params`` — fixed in session 33).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from pkmkit.machines.registry import machine
from pkmkit.model.parameters import resolve_parameters


def _two_step(m, **overrides):
    params = resolve_parameters(m.kind.parameters, {**m.params, **overrides}, m.id)
    model = m.kind.build(params)
    rebuilt = type(m)(id=m.id, name=m.name, kind=m.kind, params=dict(params), model=model,
                      description=m.description, source=m.source,
                      extra_poses=m.kind.reference_poses(params, model))
    extra = {k: v for k, v in m.extra_poses.items() if k not in rebuilt.extra_poses}
    kept = ({"characteristic_length": m.characteristic_length
             if m.length_given else None} if hasattr(m, "length_given") else {})
    return replace(rebuilt, extra_poses={**rebuilt.extra_poses, **extra}, **kept)


def _scaled(m, factor=1.02, name=None):
    name = name or next(k for k, v in m.params.items() if isinstance(v, float) and v > 0)
    return {name: m.params[name] * factor}


def _check_same(new, old):
    assert type(new) is type(old)
    assert list(new.extra_poses) == list(old.extra_poses)
    for key, value in old.extra_poses.items():
        np.testing.assert_array_equal(new.extra_poses[key], value)
    assert new.params == old.params
    np.testing.assert_array_equal(new.home_q, old.home_q)
    for pose in [old.home_pose, *old.extra_poses.values()]:
        np.testing.assert_array_equal(new.ik(pose), old.ik(pose))
    if hasattr(old, "characteristic_length"):
        assert new.characteristic_length == old.characteristic_length
        assert new.length_given == old.length_given


@pytest.mark.parametrize("machine_id", ["orthoglide", "linear-delta", "five-bar", "delta",
                                        "verne", "gough-stewart"])
def test_with_params_gives_the_former_two_step_machine(machine_id):
    m = machine(machine_id)
    first = next(iter(m.extra_poses.values()))
    m = replace(m, extra_poses={**m.extra_poses, "mine": first + 0.001})
    overrides = _scaled(m)
    new = m.with_params(**overrides)
    _check_same(new, _two_step(m, **overrides))
    assert "mine" in new.extra_poses


@pytest.mark.parametrize(("machine_id", "platform"), [("verne", "r"),
                                                     ("gough-stewart", "platform_radius")])
def test_a_full_pose_machine_keeps_a_given_length_and_takes_the_new_default_else(machine_id,
                                                                               platform):
    m = machine(machine_id)
    assert not m.length_given
    overrides = _scaled(m, 1.1, platform)
    new = m.with_params(**overrides)
    _check_same(new, _two_step(m, **overrides))
    radius = float(np.linalg.norm(new.model.rod_platform, axis=1).mean())
    assert new.characteristic_length == radius != m.characteristic_length
    assert not new.length_given  # a default stays a default ...
    again = new.with_params(**_scaled(new, 1.1, platform))
    assert not again.length_given  # ... and follows the geometry again
    assert again.characteristic_length == float(
        np.linalg.norm(again.model.rod_platform, axis=1).mean()) != new.characteristic_length
    given = m.with_characteristic_length(0.37).with_params(**overrides)
    assert given.characteristic_length == 0.37 and given.length_given
    _check_same(given, _two_step(m.with_characteristic_length(0.37), **overrides))


@pytest.mark.parametrize("machine_id", ["orthoglide", "verne"])
def test_with_params_builds_once(machine_id, monkeypatch):
    m = machine(machine_id)
    cls = type(m)
    built = []
    original = cls.__post_init__

    def counted(self):
        built.append(self)
        original(self)

    monkeypatch.setattr(cls, "__post_init__", counted)
    m.with_params(**_scaled(m))
    assert len(built) == 1
