"""One parameter vector (issue 19 §2): every built-in machine and a machine file of each family
gives a flat vector with an immutable index (name, unit, role, owner, source) — nominal
parameters then defects — and is rebuilt from a changed one."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import InputError, ParameterError
from pkmkit.geometric_errors.model import defect_set
from pkmkit.model.parameter_vector import ROLES, UNITS, ParameterVector, parameter_block

EXAMPLES = Path(__file__).resolve().parents[2] / "docs" / "examples"
FILES = ("my-machine.toml", "hexapod-6-6.toml", "planar-3rpr.toml", "strut-tripod.toml")


def _machines():
    for name in pkmkit.machines():
        yield pytest.param(lambda name=name: pkmkit.machine(name), id=name)
    for file in FILES:
        yield pytest.param(lambda file=file: pkmkit.load(str(EXAMPLES / file)), id=file)


@pytest.fixture(params=list(_machines()))
def machine(request):
    return request.param()


def test_every_machine_has_one_indexed_vector(machine):
    v = machine.parameters()
    ds = defect_set(machine)
    idx = v.index
    assert isinstance(v, ParameterVector) and v.values.shape == (len(idx),)
    assert set(idx.roles) <= set(ROLES) and set(idx.units) <= set(UNITS)
    defects = idx.select("defect")
    assert [idx.names[i] for i in defects] == list(ds.names)
    assert [idx.owners[i] for i in defects] == list(ds.owners)
    assert [idx.units[i] for i in defects] == list(ds.units)
    assert len(idx.select("nominal")) > 0
    # nominal entries first, then defects, names unique
    assert list(idx.select("nominal")) + list(defects) == list(range(len(idx)))
    with pytest.raises(ValueError, match="read-only"):
        v.values[0] = 1.0
    if machine.kind is not None:
        for spec in machine.kind.parameters:
            got = [v[n] for n, s in zip(idx.names, idx.sources, strict=True) if s == spec.name]
            np.testing.assert_array_equal(got, np.ravel(machine.params[spec.name]))


def test_the_same_vector_gives_the_same_machine(machine):
    assert machine.with_parameters(machine.parameters()) is machine


def _home_tool(m, q):
    if m.family == "chain":
        return m.fk(q[None], full_output=True, strokes="ignore").pose[0]
    return np.asarray(m.fk(q, strokes="ignore"))


def test_a_changed_vector_rebuilds_the_machine_and_reads_back(machine):
    v = machine.parameters()
    idx = v.index
    length = next(i for i in idx.select("nominal") if idx.units[i] == "m"
                  and not idx.names[i].startswith(("q_min", "q_max", "length_m", "char",
                                                   "parallelogram", "tool", "spindle")))
    defect = idx.select("defect")[0]
    changed = v.replace({idx.names[length]: v.values[length] + 1e-4,
                         idx.names[defect]: 2e-4})
    try:
        rebuilt = machine.with_parameters(changed)
    except ParameterError as exc:  # an element-by-element chain that no longer closes
        assert machine.family == "chain" and "do not close" in str(exc)
        return
    np.testing.assert_allclose(rebuilt.parameters().values, changed.values, rtol=0, atol=1e-12)
    assert rebuilt.defects()[0] == 2e-4
    # the rebuilt machine's geometry moved (a parameter that changes nothing would hide a
    # rebuild that ignores it)
    q = machine.home_q
    assert np.abs(_home_tool(rebuilt, q) - _home_tool(machine, q)).max() > 1e-6


def test_defects_survive_a_nominal_change_and_are_absolute():
    tripteor = pkmkit.machine("tripteor-x7").with_defects({"dK21": 1e-3})
    v = tripteor.parameters()
    moved = tripteor.with_parameters(v.replace(L=v["L"] + 1e-3))
    assert moved.parameters()["dK21"] == 1e-3 and moved.parameters()["L"] == v["L"] + 1e-3
    hexapod = pkmkit.machine("gough-stewart").with_defects({"dL2": 1e-3})
    w = hexapod.parameters()  # a kind's machine with defects keeps its kind's names
    assert w.names[0] == "base_radius" and w["dL2"] == 1e-3 and hexapod.kind is None
    wider = hexapod.with_parameters(w.replace(base_radius=w["base_radius"] + 1e-2))
    assert wider.defects()[defect_set(wider).index("dL2")] == 1e-3
    assert wider.parameters()["base_radius"] == w["base_radius"] + 1e-2
    back = wider.with_defects({})  # zero defects: the kind's machine, whole again
    assert back.kind is not None and back.params["base_radius"] == w["base_radius"] + 1e-2
    dietmaier = pkmkit.machine("dietmaier-hexapod").with_defects({"dL2": 1e-3})
    d = dietmaier.parameters()  # a machine described rod by rod: its rods' geometry
    assert d.names[0] == "A1x"
    np.testing.assert_allclose(d["L2"], pkmkit.machine("dietmaier-hexapod").model.rod_length[1])
    longer = dietmaier.with_parameters(d.replace(L2=d["L2"] + 5e-3))
    np.testing.assert_allclose(longer.model.rod_length[1], d["L2"] + 6e-3, rtol=0, atol=1e-15)


def test_bad_vectors_are_typed_errors():
    m = pkmkit.machine("linear-delta")
    v = m.parameters()
    with pytest.raises(InputError, match="does not belong"):
        pkmkit.machine("delta").with_parameters(v)
    with pytest.raises(InputError, match="finite values"):
        m.with_parameters(np.zeros(3))
    with pytest.raises(ParameterError, match="unknown parameter 'nope'"):
        v.replace(nope=1.0)
    with pytest.raises(ParameterError):  # the kind's own validation (R > 0)
        m.with_parameters(v.replace(R=-1.0))


def test_a_set_up_block_joins_a_machine_vector():
    m = pkmkit.machine("linear-delta")
    setup = parameter_block(("frame_rx", "frame_x"), ("rad", "m"), [0.01, 0.2], role="set-up",
                            owners="frame")
    both = m.parameters() + setup
    assert both.index.roles[-2:] == ("set-up", "set-up") and both["frame_x"] == 0.2
    assert both.role("set-up").names == ("frame_rx", "frame_x")
    with pytest.raises(ParameterError, match="repeated"):
        _ = setup + setup


def test_machine_files_keep_their_naming_schemes():
    hexapod = pkmkit.load(str(EXAMPLES / "hexapod-6-6.toml"))
    v = hexapod.parameters()
    i = v.index.position("L3")
    assert (v.index.sources[i], v.index.owners[i], v.index.units[i]) == ("rods.2.length",
                                                                          "rod 3", "m")
    np.testing.assert_allclose(v["L3"], hexapod.model.rod_length[2])
    np.testing.assert_allclose([v["A2x"], v["A2y"], v["A2z"]], hexapod.model.rod_base[1])
    planar = pkmkit.load(str(EXAMPLES / "planar-3rpr.toml"))
    w = planar.parameters()
    nominal = w.role("nominal")
    assert nominal.names == planar.model.parameter_names()
    np.testing.assert_allclose(nominal.values, planar.model.parameter_values(), atol=1e-15)
    delta = pkmkit.machine("linear-delta").parameters()
    assert [delta.index.sources[delta.index.position(f"angles[{k}]")] for k in range(3)] == [
        "angles"] * 3
    assert delta.index.units[delta.index.position("angles[1]")] == "rad"
