"""``ik(X, out=Q)`` and ``fk(Q, out=X)`` on every family (pkmkit.machines.out_arrays, issue 22
§2): the caller's array is filled and returned, bit for bit what the call without ``out``
gives (whatever ``out`` held before: NaN, garbage), also in chunks and with
``full_output=True`` (the record's q is ``out``); every misfit ``out`` is a typed error naming
it, never a silent copy."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import InputError
from pkmkit.machines import chunks
from pkmkit.numerics import jit
from pkmkit.status import Status

EXAMPLES = Path(__file__).resolve().parents[2] / "docs" / "examples"
FILES = ("my-machine.toml", "hexapod-6-6.toml", "planar-3rpr.toml")


def _machines():
    for name in pkmkit.machines():
        yield pytest.param(name, id=name)
    for file in FILES:
        yield pytest.param(str(EXAMPLES / file), id=file)


@pytest.fixture(params=list(_machines()), scope="module")
def machine(request):
    name = request.param
    return pkmkit.load(name) if name.endswith(".toml") else pkmkit.machine(name)


def bits(a: np.ndarray) -> bytes:
    """The array's bytes in row order (NaN payloads included)."""
    return np.ascontiguousarray(a).tobytes()


def poses(m, rows: int = 6) -> np.ndarray:
    """Poses near home (positions moved by up to 1 mm), one out of reach, one NaN."""
    x = np.tile(np.asarray(m.home_pose, dtype=float), (rows, 1))
    k = min(3, m.dims)
    x[:, :k] += 1e-3 * np.sin(np.arange(rows * k, dtype=float)).reshape(rows, k)
    x[1, 0] += 100.0  # out of reach (m)
    x[3, :] = np.nan
    return x


def garbage(shape) -> np.ndarray:
    """A reused buffer: stale NaN and huge values (C-contiguous float64)."""
    out = np.full(shape, np.nan)
    out.ravel()[::3] = 1e300
    return out


@pytest.fixture(params=["auto", "1"])
def compiled(request, monkeypatch):
    """The default choice (NumPy for a small batch of a rod machine) and the compiled kernels
    forced (which write into out themselves)."""
    if request.param == "auto":
        monkeypatch.delenv("PKMKIT_COMPILED", raising=False)
    else:
        monkeypatch.setenv("PKMKIT_COMPILED", request.param)
    return request.param


def test_ik_out_is_filled_and_returned_bit_for_bit(machine, compiled):
    x = poses(machine)
    expected = machine.ik(x)
    out = garbage(expected.shape)
    got = machine.ik(x, out=out)
    assert got is out
    assert bits(out) == bits(expected)
    again = machine.ik(x, out=out)  # reused: the same bits again
    assert again is out and bits(out) == bits(expected)


def test_fk_out_is_filled_and_returned_bit_for_bit(machine):
    q = machine.ik(poses(machine))
    expected = machine.fk(q)
    out = garbage(expected.shape)
    assert machine.fk(q, out=out) is out
    assert bits(out) == bits(expected)


def test_full_output_record_q_is_out_with_the_same_statuses(machine, compiled):
    x = poses(machine)
    plain = machine.ik(x, full_output=True, strokes="refuse")
    out = garbage(plain.q.shape)
    found = machine.ik(x, full_output=True, strokes="refuse", out=out)
    assert np.shares_memory(found.q, out) and found.q.shape == out.shape  # a read-only view
    assert not found.q.flags.writeable
    assert bits(out) == bits(plain.q)
    np.testing.assert_array_equal(found.status, plain.status)
    np.testing.assert_array_equal(found.mode, plain.mode)  # det A read from out (rod legs)
    assert found.status[3] == Status.INVALID_INPUT  # (row 1 is out of reach where rods end)
    assert np.isnan(out[found.status != Status.OK]).all()
    assert np.isfinite(out[found.status == Status.OK]).all()


def test_each_misfit_out_is_a_typed_error_naming_it(machine):
    x = poses(machine)
    n = machine.n_actuators
    rows = x.shape[0]
    misfits = {
        "float32": np.zeros((rows, n), dtype=np.float32),
        "int": np.zeros((rows, n), dtype=np.int64),
        "rows": np.zeros((rows + 1, n)),
        "columns": np.zeros((rows, n + 1)),
        "flat": np.zeros(rows * n),
        "order": np.zeros((rows, n), order="F") if n > 1 else np.zeros((rows, 2))[:, :1],
        "strided": np.zeros((rows, 2 * n))[:, ::2],
        "list": [[0.0] * n] * rows,
    }
    read_only = np.zeros((rows, n))
    read_only.flags.writeable = False
    misfits["read-only"] = read_only
    for label, out in misfits.items():
        with pytest.raises(InputError, match="out") as caught:
            machine.ik(x, out=out)
        assert "ik" in str(caught.value), label
    with pytest.raises(InputError, match="single row"):
        machine.ik(machine.home_pose, out=np.zeros(n))


def test_out_sharing_memory_with_the_input_is_refused(machine):
    x = poses(machine)
    rows, width, n = x.shape[0], x.shape[1], machine.n_actuators
    block = np.zeros((rows, width + n))  # x and out side by side in one array: overlapping
    block[:, :width] = x
    with pytest.raises(InputError, match="shares memory"):
        machine.ik(block[:, :width], out=_c_view(block, n))
    q = np.ascontiguousarray(machine.ik(x))  # a rod machine's q is column-major
    q[~np.isfinite(q)] = 0.0
    if n == machine.home_pose.shape[0]:  # fk into its own input
        with pytest.raises(InputError, match="shares memory"):
            machine.fk(q, out=q)


def _c_view(block: np.ndarray, n: int) -> np.ndarray:
    """A C-contiguous ``(N, n)`` view over the same memory as ``block``'s first columns."""
    return block.ravel()[: block.shape[0] * n].reshape(block.shape[0], n)


@pytest.mark.parametrize("ident", ["linear-delta", "gough-stewart", "verne", "five-bar"])
@pytest.mark.parametrize("full", [False, True])
def test_chunked_batches_write_into_out(ident, full, monkeypatch):
    """Batches above the chunk size: each chunk writes its rows of out, nothing is joined
    into a new array, and the result is the unchunked call's, bit for bit."""
    m = pkmkit.machine(ident)
    x = np.tile(poses(m), (50, 1))
    expected = m.ik(x, full_output=full)
    monkeypatch.setattr(chunks, "CHUNK_ROWS", 64)
    out = garbage((x.shape[0], m.n_actuators))
    got = m.ik(x, full_output=full, out=out)
    if full:  # the record's q: a read-only view of out
        assert np.shares_memory(got.q, out) and got.q.shape == out.shape
    else:
        assert got is out
    assert bits(out) == bits(expected if not full else expected.q)
    if full:
        np.testing.assert_array_equal(got.status, expected.status)
    x_out = garbage(x.shape if m.dims == x.shape[1] else (x.shape[0], m.dims))
    q = np.where(np.isfinite(out), out, m.home_q)
    assert m.fk(q, out=x_out) is x_out
    monkeypatch.setattr(chunks, "CHUNK_ROWS", 1 << 16)
    assert bits(x_out) == bits(m.fk(q))


@pytest.mark.parametrize("ident", ["gough-stewart", "linear-delta"])
def test_compiled_kernels_write_into_out_across_threads(ident, monkeypatch):
    """A batch the compiled inverse cuts into pieces for its threads: every piece lands in
    the caller's out (the rows of a piece written elsewhere would stay garbage)."""
    monkeypatch.setenv("PKMKIT_COMPILED", "1")
    m = pkmkit.machine(ident)
    x = np.tile(poses(m), (3 * jit.THREAD_ROWS // 6 + 1, 1))
    expected = m.ik(x)
    out = garbage(expected.shape)
    assert m.ik(x, out=out) is out
    assert bits(out) == bits(expected)


@pytest.mark.parametrize("ident", ["linear-delta", "orthoglide", "five-bar", "gough-stewart",
                                   "verne"])
def test_compiled_inverse_allocates_no_array_of_the_output_size(ident, monkeypatch):
    """The compiled inverse writes q into out itself: the memory NumPy allocates during
    ``ik(X, out=Q)`` (tracemalloc's peak) stays below the size of q, and with
    ``full_output=True`` is at least q's size below the call without out — a kernel writing a
    temporary then copied into out (the same values) fails it."""
    tracemalloc = pytest.importorskip("tracemalloc")
    monkeypatch.setenv("PKMKIT_COMPILED", "1")
    m = pkmkit.machine(ident)
    x = np.tile(np.asarray(m.home_pose, dtype=float), (100_000, 1))
    x[:, 0] += np.linspace(-1e-3, 1e-3, x.shape[0])
    out = np.empty((x.shape[0], m.n_actuators))

    def peak(**options) -> int:
        m.ik(x, **options)  # warm: kernels loaded, machine caches built
        tracemalloc.start()
        try:
            m.ik(x, **options)
            return tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()

    assert peak() >= out.nbytes  # the measure sees the output of a call without out
    assert peak(out=out) < 0.6 * out.nbytes
    assert peak(full_output=True) - peak(full_output=True, out=out) >= out.nbytes


def test_positions_of_a_position_controlled_machine_fill_out():
    """The Verne module given positions (N, 3): its q (N, n) into out, the record's q out and
    its full poses as without out; out of the positions' width refused."""
    m = pkmkit.machine("verne")
    x = np.array([[0.0, 0.0, 0.0], [0.05, -0.02, 0.01], [5.0, 0.0, 0.0], [np.nan] * 3])
    plain = m.ik(x, full_output=True)
    out = garbage(plain.q.shape)
    found = m.ik(x, full_output=True, out=out)
    assert np.shares_memory(found.q, out) and bits(out) == bits(plain.q)  # a read-only view
    assert bits(found.pose) == bits(plain.pose)
    np.testing.assert_array_equal(found.status, plain.status)
    again = garbage(plain.q.shape)
    assert m.ik(x, out=again) is again and bits(again) == bits(plain.q)
    with pytest.raises(InputError, match="out must be float64 of shape"):
        m.ik(x, out=np.zeros((4, 3 + m.n_actuators)))
    with pytest.raises(InputError, match="single row"):
        m.ik(x[0], out=np.zeros(m.n_actuators))
