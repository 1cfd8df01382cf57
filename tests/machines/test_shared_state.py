"""Shared state (docs/testing.md, "Audit of shared state, session 34"): no caller can corrupt
another's answer.

- Records are read-only (docs/kinematics.md, "Records are read-only"): every array field of
  every record (``ik``/``fk`` with ``full_output``, ``jacobian``; one pose and a batch; the
  lazy ones whose fields are computed when read) refuses an in-place write, so a field derived
  later (a lazy ``mode`` from ``q``, ``J_inv`` from ``J``) is what it would have been; the
  caller's own arrays stay writeable, and the record does not follow them when they change.
- The built-machine cache (:mod:`pkmkit.machines.built_machines`) shares the frozen model, the
  closed forms' constants and whatever is cached on them later between the copies it hands
  out: every array reachable from those shared parts is read-only, before and after use, so a
  write cannot reach the next ``pkmkit.machine(...)``.
- The one-pose velocity kernels' ``layout`` (an ``lru_cache``) hands out a read-only mapping.

Each check fails on the code before session 34 (the planted bugs are the old code: a
``_get`` handing out its cached array, a template kept without :func:`freeze_shared`).
"""

from __future__ import annotations

import dataclasses
import pickle
import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.machines import built_machines, registry
from pkmkit.machines.lazy_records import read_only

PRESETS = registry.machines()


def _calls(m):
    """``(label, call, argument)`` of the record-returning calls at the home pose."""
    x = np.array(m.home_pose, dtype=float)
    q = np.array(m.home_q, dtype=float)
    xs, qs = np.repeat(x[None], 3, axis=0), np.repeat(q[None], 3, axis=0)

    def ik(a):
        return m.ik(a, full_output=True)

    def fk(a):
        return m.fk(a, full_output=True)

    return [("ik one", ik, x), ("ik batch", ik, xs), ("fk one", fk, q), ("fk batch", fk, qs),
            ("jacobian one", m.jacobian, x), ("jacobian batch", m.jacobian, xs)]


def _array_fields(record):
    return {f.name: getattr(record, f.name) for f in dataclasses.fields(record)
            if isinstance(getattr(record, f.name), np.ndarray)}


def _writeable(obj, seen=None, path="") -> list[str]:
    """Paths of the writeable arrays reachable from ``obj`` (pkmkit objects' attributes and
    slots, dictionaries, lists, tuples)."""
    seen = set() if seen is None else seen
    if isinstance(obj, np.ndarray):
        return [path] if obj.flags.writeable else []
    if id(obj) in seen or isinstance(obj, str | bytes | int | float | type(None)):
        return []
    seen.add(id(obj))
    if isinstance(obj, dict):
        items = [(f"[{k!r}]", v) for k, v in obj.items()]
    elif isinstance(obj, list | tuple):
        items = [(f"[{i}]", v) for i, v in enumerate(obj)]
    elif type(obj).__module__.startswith("pkmkit."):
        items = [(f".{k}", v) for k, v in getattr(obj, "__dict__", {}).items()]
        items += [(f".{k}", getattr(obj, k)) for k in getattr(type(obj), "__slots__", ())
                  if hasattr(obj, k)]
    else:
        return []
    return [p for key, value in items for p in _writeable(value, seen, path + key)]


@pytest.mark.parametrize("name", PRESETS)
def test_every_record_field_is_read_only(name):
    """Every array field of every record refuses a write; the call's own argument stays
    writeable (a view is handed out, the caller's array is not frozen)."""
    m = pkmkit.machine(name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for label, call, arg in _calls(m):
            record = call(arg)
            fields = _array_fields(record)
            assert fields, (name, label)
            for field, value in fields.items():
                assert not value.flags.writeable, (name, label, field)
                with pytest.raises(ValueError):
                    value.flat[0] = 9.0
                assert getattr(record, field) is value, (name, label, field)  # same view
            assert arg.flags.writeable


@pytest.mark.parametrize("name", ["gough-stewart", "trimule-600", "delta"])
def test_a_write_cannot_change_a_field_derived_later(name):
    """The session-33 defect: ``rec.q[0] = 9`` on a lazy batch record changed the ``mode``,
    ``direct`` or ``pose`` it computed afterwards. The write now raises, and the derived
    fields equal those of a record nobody touched."""
    m = pkmkit.machine(name)
    xs = np.repeat(np.array(m.home_pose, dtype=float)[None], 3, axis=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        touched, clean = m.ik(xs, full_output=True), m.ik(xs.copy(), full_output=True)
        with pytest.raises(ValueError):
            touched.q[0] = 9.0
        for field in ("mode", "pose"):
            np.testing.assert_array_equal(getattr(touched, field), getattr(clean, field))
        jac, ref = m.jacobian(xs), m.jacobian(xs.copy())
        with pytest.raises(ValueError):
            jac.J[...] = 0.0
        np.testing.assert_array_equal(jac.singular_values, ref.singular_values)
        np.testing.assert_array_equal(jac.condition, ref.condition)


@pytest.mark.parametrize("name", ["orthoglide", "verne", "tripteor-x7"])
def test_records_do_not_follow_the_callers_arrays(name):
    """A record made from the caller's arrays keeps its answer when the caller changes them
    afterwards (every field, lazy ones read after the change)."""
    m = pkmkit.machine(name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for label, call, arg in _calls(m):
            ref = call(arg.copy())
            mine = arg.copy()
            record = call(mine)
            mine[...] = 0.123
            for field, value in _array_fields(record).items():
                np.testing.assert_array_equal(value, getattr(ref, field),
                                              err_msg=f"{name} {label} {field}")


def test_pickled_and_copied_records_stay_read_only():
    m = pkmkit.machine("linear-delta")
    xs = np.repeat(np.array(m.home_pose, dtype=float)[None], 2, axis=0)
    for record in (m.ik(xs, full_output=True), m.jacobian(xs), m.fk(m.ik(xs), full_output=True)):
        for again in (pickle.loads(pickle.dumps(record)), dataclasses.replace(record)):
            for field, value in _array_fields(again).items():
                assert not value.flags.writeable, (type(record).__name__, field)


def test_read_only_is_a_view_not_a_copy_nor_a_freeze():
    mine = np.arange(4.0)
    seen = read_only(mine)
    assert not seen.flags.writeable and mine.flags.writeable
    assert np.shares_memory(seen, mine) and read_only(seen) is seen
    assert read_only([1.0]) == [1.0]


def _exercise(m) -> None:
    """Calls that fill what a machine caches lazily on its shared parts (kernel arrays of a
    joint chain's model, velocity legs of the closed forms)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for _, call, arg in _calls(m):
            record = call(arg)
            for f in dataclasses.fields(record):
                getattr(record, f.name)
        m.ik(np.repeat(np.array(m.home_pose, dtype=float)[None], 70, axis=0))
    from pkmkit.model.defect_rule import defect_index

    defect_index(m)  # kept on the model (a rod-leg machine's) by the identification
    if m.family == "chain":  # what the batch solver and the identification keep on the model
        from pkmkit.model.chains import cached_defect_twists
        from pkmkit.solve.chain_rows import model_arrays

        model_arrays(m.model, np.asarray(m.passive_variables, dtype=int))
        cached_defect_twists(m.model)


@pytest.mark.parametrize("name", PRESETS)
def test_no_writeable_array_is_shared_between_loads(name):
    """Every array reachable from what two loads of a preset share is read-only, before and
    after the machine is used; writing into one raises, and the next load is intact."""
    a, b = pkmkit.machine(name), pkmkit.machine(name)
    shared = {k: v for k, v in vars(a).items() if vars(b).get(k) is v}
    assert "model" in shared
    assert _writeable(shared) == [], name
    _exercise(a)
    shared = {k: v for k, v in vars(a).items() if vars(b).get(k) is v}
    assert _writeable(shared) == [], name
    arrays = [v for v in vars(a.model).values() if isinstance(v, np.ndarray) and v.size]
    before = arrays[0].copy()
    with pytest.raises(ValueError):
        arrays[0].flat[0] = 123.0
    again = pkmkit.machine(name)
    name_of = next(k for k, v in vars(a.model).items() if v is arrays[0])
    np.testing.assert_array_equal(getattr(again.model, name_of), before)


def test_what_is_copied_stays_writeable_and_private():
    """The parts each load copies (params, extra poses) stay the caller's to change."""
    built_machines.forget()
    a = pkmkit.machine("gough-stewart")
    poses = [v for v in a.extra_poses.values() if isinstance(v, np.ndarray)]
    if poses:
        assert poses[0].flags.writeable
        poses[0].flat[0] += 1.0
        b = pkmkit.machine("gough-stewart")
        key = next(k for k, v in a.extra_poses.items() if v is poses[0])
        assert b.extra_poses[key].flat[0] != poses[0].flat[0]


@pytest.mark.parametrize("module", ["pkmkit.machines.full_pose_velocity_one",
                                    "pkmkit.machines.full_pose_velocity_kernel"])
def test_cached_layout_is_read_only(module):
    """``layout`` is an ``lru_cache``: the mapping it returns is every later caller's."""
    if module.endswith("kernel"):
        pytest.importorskip("numba")
    import importlib

    layout = importlib.import_module(module).layout
    spots = layout(6, 6)
    with pytest.raises(TypeError):
        spots["J"] = (0, 0)
    assert layout(6, 6)["J"] == (6 * 6 + 6 * 6, 6 * 6 + 6 * 6 + 36)


@pytest.mark.parametrize("name", ["delta", "gough-stewart"])
def test_every_assembly_mode_and_jacobian_rates_are_read_only(name):
    """``fk_all`` (:class:`AssemblyModes`, :class:`PoseSolutions`) and ``jacobian_dot``
    (:class:`JacobianRates`): the same base class, the same contract."""
    m = pkmkit.machine(name)
    x = np.array(m.home_pose, dtype=float)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        records = (m.fk_all(np.array(m.home_q, dtype=float)),
                   m.jacobian_dot(x, np.full(x.shape, 0.01)))
    for record in records:
        fields = _array_fields(record)
        assert fields
        for field, value in fields.items():
            assert not value.flags.writeable, (type(record).__name__, field)
