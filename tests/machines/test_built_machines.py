"""Loading a machine file again copies the machine built before (pkmkit.machines.built_machines).

The oracle is the uncached path: ``machine_from_document(read_machine_document(path))`` builds
the machine from the file every time. Each test fails on a planted bug in the cache: the kept
template handed out itself, a shallow copy (dictionaries and arrays shared), a key without the
file's text, without the path or without the id.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest

from pkmkit.exceptions import MachineFileError
from pkmkit.machines import built_machines
from pkmkit.machines.registry import load, machine, machine_from_document, machines, preset_path
from pkmkit.model.machine_file import read_machine_document
from pkmkit.numerics import jit


def _uncached(machine_id: str):
    return machine_from_document(read_machine_document(preset_path(machine_id)),
                                 machine_id=machine_id)


def _same_machine(m, oracle) -> None:
    assert type(m) is type(oracle)
    assert (m.id, m.name, m.description, m.source) == (
        oracle.id, oracle.name, oracle.description, oracle.source)
    assert m.params.keys() == oracle.params.keys()
    for key, value in oracle.params.items():
        np.testing.assert_array_equal(np.asarray(m.params[key]), np.asarray(value))
    assert m.extra_poses.keys() == oracle.extra_poses.keys()
    for key, value in oracle.extra_poses.items():
        np.testing.assert_array_equal(m.extra_poses[key], value)
    np.testing.assert_array_equal(m.home_q, oracle.home_q)
    np.testing.assert_array_equal(m.home_pose, oracle.home_pose)


@pytest.mark.parametrize("machine_id", machines())
def test_a_second_load_is_a_new_machine_equal_to_a_fresh_build(machine_id):
    oracle = _uncached(machine_id)
    first, second = machine(machine_id), machine(machine_id)
    assert first is not second and first.params is not second.params
    _same_machine(second, oracle)
    pose = oracle.home_pose
    np.testing.assert_array_equal(second.ik(pose), oracle.ik(pose))
    np.testing.assert_array_equal(second.fk(oracle.home_q), oracle.fk(oracle.home_q))


@pytest.mark.parametrize("machine_id", ["orthoglide", "verne", "tripteor-x7"])
def test_changing_a_loaded_machine_in_place_does_not_reach_the_next_load(machine_id):
    oracle = _uncached(machine_id)
    m = machine(machine_id)
    assert m.extra_poses, "the check needs a machine with named poses"
    for value in m.extra_poses.values():
        value[...] = 123.0
    m.extra_poses["added"] = np.zeros(m.dims)
    m.params["added"] = 1.0
    for name in list(m.params)[:-1]:
        if isinstance(m.params[name], float):
            m.params[name] = -1.0
    for value in vars(m).values():  # lazily filled and private state too
        if isinstance(value, np.ndarray) and value.flags.writeable:
            value[...] = -7
        elif isinstance(value, dict):
            value["added"] = None
    again = machine(machine_id)
    _same_machine(again, oracle)
    np.testing.assert_array_equal(again.ik(oracle.home_pose), oracle.ik(oracle.home_pose))


def test_a_rewritten_file_is_built_again(tmp_path):
    path = tmp_path / "delta.toml"
    text = '[machine]\nkind = "linear-delta"\nunits = "mm"\n[parameters]\nL = {}\n'
    path.write_text(text.format(600))
    assert load(path).params["L"] == pytest.approx(0.6)
    path.write_text(text.format(610))  # the same size, maybe the same time stamp
    assert load(path).params["L"] == pytest.approx(0.61)


def test_the_same_text_at_two_paths_gives_each_file_its_id(tmp_path):
    text = '[machine]\nkind = "orthoglide"\n'
    (tmp_path / "one.toml").write_text(text)
    (tmp_path / "two.toml").write_text(text)
    assert load(tmp_path / "one.toml").id == "one"
    assert load(tmp_path / "two.toml").id == "two"


def test_an_alias_and_its_preset_keep_their_ids():
    assert machine("linear-delta").id == "linear-delta"
    assert machine("linear-delta-ch3").id == "linear-delta-ch3"
    assert machine("linear-delta").id == "linear-delta"


def test_a_file_that_fails_fails_every_time(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text('[machine]\nkind = "orthoglide"\n[parameters]\nnot_a_parameter = 1\n')
    for _ in range(2):
        with pytest.raises(MachineFileError, match="not_a_parameter"):
            load(path)
    path.write_text('[machine]\nkind = "orthoglide"\n')
    assert load(path).id == "bad"
    path.write_text('[machine]\nkind = "orthoglide"\n[parameters]\nnot_a_parameter = 1\n')
    with pytest.raises(MachineFileError, match="not_a_parameter"):
        load(path)


def test_overrides_build_the_machine_they_ask_for():
    base = machine("orthoglide")
    name = next(k for k, v in base.params.items() if isinstance(v, float) and v > 0)
    changed = machine("orthoglide", **{name: base.params[name] * 1.01})
    assert changed.params[name] == pytest.approx(base.params[name] * 1.01)
    assert machine("orthoglide").params[name] == base.params[name]


def test_the_engine_is_part_of_the_key(monkeypatch):
    """A build may read the engine (a joint chain closes its legs at home with the compiled
    closure when there is one): each part of the choice changes the key on its own."""
    key = built_machines.engine_key()
    with monkeypatch.context() as patch:
        patch.setenv("PKMKIT_COMPILED", "1")  # the extension stays: only the mode differs
        assert built_machines.engine_key() != key
    with monkeypatch.context() as patch:
        patch.setenv("PKMKIT_NATIVE", "1")
        assert built_machines.engine_key() != key
    if jit.native_kernels() is not None:
        with monkeypatch.context() as patch:
            patch.setattr(jit, "_native", None)  # as without the extension
            assert built_machines.engine_key() != key
    with monkeypatch.context() as patch:
        if "numba" in sys.modules:
            patch.delitem(sys.modules, "numba")
        else:
            patch.setitem(sys.modules, "numba", sys)
        assert built_machines.engine_key() != key
    assert built_machines.engine_key() == key


def test_at_most_max_kept_templates_are_kept(tmp_path, monkeypatch):
    monkeypatch.setattr(built_machines, "MAX_KEPT", 2)
    built_machines.forget()
    calls = []
    for i in range(4):
        built_machines.built(("k", i), lambda i=i: calls.append(i) or _Plain(i))
    assert calls == [0, 1, 2, 3]
    built_machines.built(("k", 3), lambda: calls.append("again") or _Plain(3))
    built_machines.built(("k", 0), lambda: calls.append("rebuilt") or _Plain(0))
    assert calls == [0, 1, 2, 3, "rebuilt"]
    built_machines.forget()


class _Plain:
    def __init__(self, value: int) -> None:
        self.value = value
