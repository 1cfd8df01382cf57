"""Joint-chain batches in chunks (issue 22 §6): ``ik``, ``fk`` and ``jacobian`` of a batch of
more than ``chunk_rows`` rows run chunk by chunk (pkmkit.machines.chunks) and give the
unchunked result bit for bit — row-aligned ``start``, ``q0`` and ``tool_length`` cut with the
rows, an array two fields share still shared, NumPy and compiled paths; a small chunk size puts
chunk boundaries inside the test batches."""

from __future__ import annotations

import importlib.util
import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.machines.chunks import CHAIN_CHUNK_ROWS, NUMPY_CHAIN_CHUNK_ROWS, chunked
from pkmkit.machines.joint_chain import JointChainMachine
from pkmkit.numerics.jit import SOLVER_ROWS
from tests.machines.test_chain_batch_independence import actuators, poses
from tests.machines.test_chunks import same


@pytest.fixture(params=["0", "1"], ids=["numpy", "compiled"])
def path(request, monkeypatch):
    if request.param == "1":
        pytest.importorskip("numba")
    monkeypatch.setenv("PKMKIT_COMPILED", request.param)
    return request.param


_FK = JointChainMachine.__dict__["fk"]


def whole_then_chunked(call, monkeypatch, size):
    """The call on the whole batch, then in chunks of at most ``size`` rows, with the row
    counts of the direct model's chunks."""
    seen = []

    def counting(self, q, **kwargs):
        seen.append(len(q) if np.ndim(q) == 2 else 1)
        return _FK.__wrapped__(self, q, **kwargs)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        monkeypatch.setattr(JointChainMachine, "chunk_rows", 10**9)
        whole = call()
        monkeypatch.setattr(JointChainMachine, "chunk_rows", size)
        monkeypatch.setattr(JointChainMachine, "fk", chunked(counting))
        try:
            return whole, call(), seen
        finally:
            monkeypatch.setattr(JointChainMachine, "fk", _FK)


@pytest.mark.parametrize(("ident", "size"), [  # the TriMule's (8 s of CPU): `.ci/run` stage 2
    ("tripteor-x7", 4), pytest.param("trimule-600", 9, marks=pytest.mark.ci)])
def test_chain_batches_in_chunks_are_the_whole_batch(ident, size, path, monkeypatch):
    """Six chunks on the compiled kernels; on the NumPy engine two (of 11 rows each: a call
    there costs ≈ 0.1 s whatever its rows), and without the pose a kilometre below home
    (``poses``' row 4), which iterates to the engine's limit: 0.6 s of CPU in each of the ten
    calls holding it. The joining is the same code on both paths (pkmkit.machines.chunks);
    the NumPy engine's rows without a closure are checked in pieces by
    test_chain_batch_independence.py and in a chunk of their own below (docs/testing.md,
    "Fifth round": the bugs planted in the chunking and in pkmkit.numerics.rowwise that the
    NumPy case still catches; 5.9 s of CPU before, 3.1 s after, in one process)."""
    m = pkmkit.machine(ident)
    x, q = poses(m), actuators(m)
    if path == "0" and ident == "tripteor-x7":
        x, size = np.delete(x, 4, axis=0), 12
    tools = 0.1 + 0.01 * np.arange(len(x))
    calls = {
        "ik": lambda: m.ik(x, tool_length=tools),
        "ik full": lambda: m.ik(x, full_output=True, q0=np.tile(m.home_q, (len(x), 1))),
        "fk full": lambda: m.fk(q, full_output=True),
        "jacobian": lambda: m.jacobian(x),
        "jacobian(q=)": lambda: m.jacobian(q=q),
    }
    for name, call in calls.items():
        whole, chunked, seen = whole_then_chunked(call, monkeypatch, size)
        same(whole, chunked, f"{ident} {name}")
        if name == "fk full":  # cut into chunks of at most `size` rows
            assert seen and max(seen) <= size and sum(seen) == len(q), seen
    # a warm start per row is cut with the rows (a previous result's closures)
    first = m.fk(q, full_output=True)
    start = np.concatenate([first.platform, first.passive], axis=1)
    whole, chunked, _ = whole_then_chunked(lambda: m.fk(q, start=start, full_output=True),
                                           monkeypatch, size)
    same(whole, chunked, f"{ident} fk from start")
    # the inverse result's pose is its direct record's, in chunks as whole
    whole, chunked, _ = whole_then_chunked(lambda: m.ik(x, full_output=True), monkeypatch,
                                           size)
    assert (chunked.pose is chunked.direct.pose) == (whole.pose is whole.direct.pose)


def test_chain_chunks_are_small(monkeypatch):
    """The chunk size keeps the engine's working set within ≈ 30 MB (≈ 16 kB per row on the
    NumPy engine, ≈ 1.3 kB for ik and fk compiled, 7.5 kB for the velocity model) and is far
    above the batch size from which the compiled kernels run (every chunk takes the batch's
    path)."""
    m = pkmkit.machine("tripteor-x7")
    monkeypatch.setenv("PKMKIT_COMPILED", "0")
    assert m.chunk_rows == NUMPY_CHAIN_CHUNK_ROWS
    if importlib.util.find_spec("numba") is not None:
        monkeypatch.setenv("PKMKIT_COMPILED", "1")
        assert m.chunk_rows == CHAIN_CHUNK_ROWS
    assert 4 * SOLVER_ROWS <= NUMPY_CHAIN_CHUNK_ROWS // 2
    assert NUMPY_CHAIN_CHUNK_ROWS * 16e3 <= 17e6 and CHAIN_CHUNK_ROWS * 7.5e3 <= 32e6


def test_a_chunked_inverse_record_stays_lazy(path, monkeypatch):
    """Joining the chunks of ``ik(full_output=True)`` keeps its direct model unread (a
    workspace study reads only the strokes: joining used to run ``fk`` on every chunk), and the
    joined fields, read later, are the whole call's — also where a chunk has no solved row, so
    that its ``direct`` is None and the chunks' records cannot be joined (the whole call then
    gives the field)."""
    m = pkmkit.machine("tripteor-x7")
    x = poses(m)[[0, 1, 2, 3, 5, 6]]  # reached rows, one beyond a stroke, a tilted axis
    x = np.concatenate([x, np.tile(x[:1] + [0.0, 0.0, 9.0, 0.0, 0.0, 0.0][:x.shape[1]],
                                   (6, 1))])  # the second chunk: out of reach only
    calls = []

    def counting(self, q, **kwargs):
        calls.append(len(q) if np.ndim(q) == 2 else 1)
        return _FK(self, q, **kwargs)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        monkeypatch.setattr(JointChainMachine, "chunk_rows", 10**9)
        whole = m.ik(x, full_output=True)
        monkeypatch.setattr(JointChainMachine, "chunk_rows", 6)
        monkeypatch.setattr(JointChainMachine, "fk", counting)
        joined = m.ik(x, full_output=True)
        assert calls == []  # nothing read yet
        np.testing.assert_array_equal(joined.q, whole.q)
        np.testing.assert_array_equal(joined.out_of_stroke, whole.out_of_stroke)
        assert calls == []
        same(whole, joined, "tripteor-x7 ik full, lazy chunks")
    assert calls  # reading the direct model ran it
