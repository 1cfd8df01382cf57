"""One rule for "plain numbers" across the machine families (native/plain_numbers.c).

Every input kind goes to ``m.ik`` / ``m.fk`` of one machine of each family with a C one-pose
entry (rod machines: linear-delta; full-pose rod machines: gough-stewart; joint chains:
tripteor-x7). Oracle: the same call with the extension switched off (``PKMKIT_NATIVE=0``:
the families' Python and batch paths, which never run the C reader), the same answer to
1e-9 or the same typed error. And whether the C entry itself answered (read the input) or
handed it over (None / NotImplemented) must be the same for every family: one rule.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import PkmError
from pkmkit.machines import chain_one_native, full_pose_one
from pkmkit.machines.full_pose import FullPoseMachine
from pkmkit.machines.machine import Machine

try:
    from pkmkit.native import kernels as _kernels
except ImportError:  # pragma: no cover - the optional extension is not built
    _kernels = None

pytestmark = pytest.mark.skipif(_kernels is None, reason="the C extension is not built")

FAMILIES = ("linear-delta", "gough-stewart", "tripteor-x7")


class Sub(float):
    """A float subclass (as NumPy's float64 is one)."""


def _c_entry(m, kind: str):
    """The family's C one-pose call of kind "ik" (a pose) or "fk" (a configuration)."""
    if isinstance(m, Machine):
        if kind == "ik":
            return lambda v: _kernels.rod_ik_one(m._one_pack, v, "ignore")
        return lambda v: _kernels.rod_fk_one(m._one_pack, v, 1, "ignore")
    if isinstance(m, FullPoseMachine):
        one = full_pose_one.native_one(m)
        return (lambda v: one.ik(v, False)) if kind == "ik" else (lambda v: one.fk(v, False))
    p = chain_one_native.packed(m)
    assert p is not None, m
    if kind == "ik":
        return lambda v: p.ik(p.capsule, v, True, False)
    return lambda v: p.fk(p.capsule, v, True, False)


def _kinds(v: np.ndarray) -> dict[str, object]:
    """Every input kind built from one reachable vector v (the ints: its rounded values)."""
    wide = np.zeros((v.size, 3))
    wide[:, 1] = v
    ints = [int(t) for t in np.round(v)]
    return {
        "list": v.tolist(), "tuple": tuple(v.tolist()), "float subclass": [Sub(t) for t in v],
        "numpy float64 items": [np.float64(t) for t in v], "float64 strided": wide[:, 1],
        "float64 reversed view": v[::-1].copy()[::-1], "float32": v.astype(np.float32),
        "numpy float32 items": [np.float32(t) for t in v],
        "int": ints, "int64": np.array(ints, dtype=np.int64),
        "int32": np.array(ints, dtype=np.int32), "numpy int64 items": [np.int64(t) for t in ints],
        "bool": [True, *v.tolist()[1:]], "huge int": [10**400, *v.tolist()[1:]],
        "nan": [np.nan, *v.tolist()[1:]], "inf": [*v.tolist()[:-1], np.inf],
        "1e10": [1e10, *v.tolist()[1:]], "2-D": v[None], "wrong length": [*v.tolist(), 0.0],
        "short": v.tolist()[:-1], "string item": ["0", *v.tolist()[1:]], "string": "abc",
        "big-endian": v.astype(">f8"), "none": None,
    }


# what the C reader does with each kind, the same for every family: read it (and answer for
# a reachable vector) or hand it over. Kinds of rounded values may be unreachable: not listed.
READ = {"list", "tuple", "float subclass", "numpy float64 items", "float64 strided",
        "float64 reversed view"}
HANDED = {"float32", "numpy float32 items", "int32", "numpy int64 items", "bool", "huge int",
          "nan", "inf", "1e10", "2-D", "wrong length", "short", "string item", "string",
          "big-endian", "none"}


def _outcome(call, given):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            return np.asarray(call(given), dtype=float)
        except PkmError as error:
            return type(error)


def _same(a, b) -> bool:
    if isinstance(a, type) or isinstance(b, type):
        return a is b
    return a.shape == b.shape and bool(np.allclose(a, b, rtol=0, atol=1e-9, equal_nan=True))


@pytest.fixture(scope="module")
def machines():
    found = {}
    for name in FAMILIES:
        m = pkmkit.machine(name)
        q = np.asarray(m.ik(m.home_pose), dtype=float)
        found[name] = (m, np.asarray(m.home_pose, dtype=float), q)
    return found


def test_the_c_entries_read_and_hand_over_the_same_kinds(machines):
    seen: dict[tuple[str, str], dict[str, bool]] = {}
    for name, (m, x, q) in machines.items():
        for kind, vector in (("ik", x), ("fk", q)):
            entry = _c_entry(m, kind)
            for label, given in _kinds(vector).items():
                got = entry(given)
                seen.setdefault((kind, label), {})[name] = (
                    got is not None and got is not NotImplemented)
    for (kind, label), answered in seen.items():
        if label in READ:
            assert all(answered.values()), (kind, label, answered)
        elif label in HANDED:
            assert not any(answered.values()), (kind, label, answered)
    assert {label for _, label in seen} == READ | HANDED | {"int", "int64"}


def test_the_int64_vector_and_the_int_list_are_read_alike(machines):
    """An int64 vector is read as the list of the same Python ints is (both TAKEN)."""
    for name, (m, x, q) in machines.items():
        for kind, vector in (("ik", x), ("fk", q)):
            entry = _c_entry(m, kind)
            ints = [int(t) for t in np.round(vector)]
            a, b = entry(ints), entry(np.array(ints, dtype=np.int64))
            assert (a is None and b is None) or np.array_equal(a, b), (name, kind)


@pytest.mark.parametrize("kind", ["ik", "fk"])
def test_every_kind_gives_the_paths_without_the_extension(machines, monkeypatch, kind):
    with_c = {}
    for name, (m, x, q) in machines.items():
        call = m.ik if kind == "ik" else m.fk
        with_c[name] = {label: _outcome(call, given)
                        for label, given in _kinds(x if kind == "ik" else q).items()}
    monkeypatch.setenv("PKMKIT_NATIVE", "0")
    for name, (_, x, q) in machines.items():
        m = pkmkit.machine(name)  # a fresh machine: no cached C pack
        call = m.ik if kind == "ik" else m.fk
        for label, given in _kinds(x if kind == "ik" else q).items():
            want = _outcome(call, given)
            assert _same(with_c[name][label], want), (name, kind, label, with_c[name][label], want)
    for label in READ:  # the C path answered these: values, never an error, in every family
        assert all(not isinstance(with_c[n][label], type) for n in machines), label
