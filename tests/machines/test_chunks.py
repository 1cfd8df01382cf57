"""Batch calls in chunks (pkmkit.machines.chunks): the chunked result is the unchunked one,
bit for bit, for every family and call; a small chunk size puts chunk boundaries inside the
test batches (rows unreachable, non-finite or out of stroke fall on either side)."""

from __future__ import annotations

import dataclasses
import importlib
import itertools

import numpy as np
import pytest

import pkmkit
from pkmkit.machines import chunks


def same(a, b, where="result") -> None:
    """Equal bit for bit: arrays (NaN where NaN, same dtype), tuples, records field by field."""
    assert type(a) is type(b), where
    if isinstance(a, np.ndarray):
        assert a.dtype == b.dtype and a.shape == b.shape, where
        assert np.array_equal(np.ascontiguousarray(a).view(np.uint8),
                              np.ascontiguousarray(b).view(np.uint8)), where
    elif dataclasses.is_dataclass(a):
        for f in dataclasses.fields(a):
            same(getattr(a, f.name), getattr(b, f.name), f"{where}.{f.name}")
    else:
        assert a == b, where


def both(call, monkeypatch, size):
    """The call unchunked, then in chunks of ``size`` rows."""
    whole = call()
    monkeypatch.setattr(chunks, "CHUNK_ROWS", size)
    return whole, call()


def poses(m, n, seed=0):
    """Poses around home over the default box, some out of reach, one NaN, one huge."""
    rng = np.random.default_rng(seed)
    lo, hi = m.default_box()
    x = np.tile(np.asarray(m.home_pose, dtype=float), (n, 1))
    width = hi - lo
    x[:, :3] = lo - 0.5 * width + 2.0 * width * rng.random((n, 3))
    if x.shape[1] == 6 and m.dims == 6 and not hasattr(m, "passive_names"):
        x[:, 3:] += 0.1 * (2.0 * rng.random((n, 3)) - 1.0)
    x[3] = np.nan
    x[n - 2, 0] = 1e9
    return x


@pytest.fixture(params=["0", "1"])
def compiled(request, monkeypatch):
    """Both the NumPy and the compiled paths (the whole batch and its chunks take the same)."""
    monkeypatch.setenv("PKMKIT_COMPILED", request.param)
    return request.param


@pytest.mark.parametrize("ident", ["linear-delta", "delta", "gough-stewart", "verne"])
@pytest.mark.parametrize("full_output", [False, True])
@pytest.mark.parametrize("strokes", ["flag", "refuse"])
def test_rod_machines_ik_fk_chunked_equal(ident, full_output, strokes, compiled, monkeypatch):
    m = pkmkit.machine(ident)
    x = poses(m, 41)
    q = m.ik(x, strokes="ignore")
    q[5] = q[4] + 0.3  # no assembly, or beyond a stroke
    for call in (lambda: m.ik(x, full_output=full_output, strokes=strokes),
                 lambda: m.fk(q, full_output=full_output, strokes=strokes)):
        monkeypatch.setattr(chunks, "CHUNK_ROWS", 1 << 16)
        whole, parts = both(call, monkeypatch, 6)
        same(whole, parts)


def test_numeric_methods_and_row_arguments_chunked_equal(monkeypatch):
    """The engine's batches (numeric ik / fk of a translational machine, warm starts with one
    row per pose cut with the poses) and the full-pose fk from x0."""
    m = pkmkit.machine("linear-delta")
    x = poses(m, 23, seed=1)
    q0 = m.ik(x + 1e-3, strokes="ignore")
    whole, parts = both(lambda: m.ik(x, method="numeric", q0=q0, full_output=True),
                        monkeypatch, 5)
    same(whole, parts)
    monkeypatch.setattr(chunks, "CHUNK_ROWS", 1 << 16)
    q = m.ik(x, strokes="ignore")
    whole, parts = both(lambda: m.fk(q, method="numeric", x0=x, dof="full", full_output=True),
                        monkeypatch, 5)
    same(whole, parts)
    monkeypatch.setattr(chunks, "CHUNK_ROWS", 1 << 16)
    h = pkmkit.machine("gough-stewart")
    xh = poses(h, 17, seed=2)
    qh = h.ik(xh, strokes="ignore")
    whole, parts = both(lambda: h.fk(qh, x0=xh, full_output=True), monkeypatch, 4)
    same(whole, parts)


def test_chunks_are_nearly_equal_and_cover_the_batch():
    bounds = chunks.chunk_bounds(50, 7)
    sizes = [stop - start for start, stop in bounds]
    assert bounds[0][0] == 0 and bounds[-1][1] == 50
    assert all(a[1] == b[0] for a, b in itertools.pairwise(bounds))
    assert max(sizes) <= 7 and max(sizes) - min(sizes) <= 1
    assert chunks.chunk_bounds(7, 7) == [(0, 7)]


def test_a_batch_runs_chunk_by_chunk(monkeypatch):
    """The method body sees chunks of at most CHUNK_ROWS rows (fails if nothing is chunked)."""
    m = pkmkit.machine("gough-stewart")
    seen = []
    full_pose = importlib.import_module("pkmkit.machines.full_pose")

    checked = full_pose._checked_batch

    def spy(x, width, what):
        seen.append(np.shape(x)[0])
        return checked(x, width, what)

    monkeypatch.setattr(full_pose, "_checked_batch", spy)
    monkeypatch.setattr(chunks, "CHUNK_ROWS", 10)
    m.ik(poses(m, 25), strokes="ignore")
    assert seen == [8, 8, 9]


def test_call_fields_are_not_joined(monkeypatch):
    """A record's per-call fields (the branches of a 3-leg machine) are not taken for rows even
    when the chunks have as many rows as the machine has legs."""
    m = pkmkit.machine("linear-delta")
    x = poses(m, 9)
    whole, parts = both(lambda: m.ik(x, full_output=True), monkeypatch, 3)
    assert parts.branches.shape == (3,)
    same(whole, parts)


def test_a_list_and_a_single_pose_are_passed_whole(monkeypatch):
    m = pkmkit.machine("linear-delta")
    x = poses(m, 8)
    monkeypatch.setattr(chunks, "CHUNK_ROWS", 3)
    same(m.ik(x.tolist()), m.ik(x))
    same(m.ik(m.home_pose), np.asarray(m.home_q))


def test_a_translational_batch_runs_chunk_by_chunk(monkeypatch):
    """ik and fk of a translational machine see chunks (fails if nothing is chunked)."""
    machine_module = importlib.import_module("pkmkit.machines.machine")
    checked = machine_module._checked_batch
    seen = []

    def spy(x, width, what):
        seen.append(np.shape(x)[0])
        return checked(x, width, what)

    m = pkmkit.machine("linear-delta")
    x = poses(m, 25)
    q = m.ik(x, strokes="ignore")
    monkeypatch.setattr(machine_module, "_checked_batch", spy)
    monkeypatch.setattr(chunks, "CHUNK_ROWS", 10)
    m.ik(x, full_output=True)
    m.fk(q, full_output=True)
    assert seen == [8, 8, 9, 8, 8, 9]


def test_a_lazy_record_is_joined_lazily_and_a_field_that_does_not_join_comes_from_the_whole():
    """chunks keeps a lazy record (pkmkit.machines.lazy_records) lazy: its given fields are
    joined at once, any other field read from the chunks' records and joined when first read;
    a field the chunks cannot join (None in one chunk, an array in another) is the whole
    call's."""
    import dataclasses

    from pkmkit.machines.chunks import chunked
    from pkmkit.machines.lazy_records import lazy_record_class

    @dataclasses.dataclass(frozen=True)
    class Record:
        q: np.ndarray
        twice: np.ndarray | None

    Lazy = lazy_record_class(Record, "Lazy", lambda r: "", "a test record")
    reads = []

    class Evaluation:
        def __init__(self, q):
            self.q = q

        def field(self, name):
            reads.append(len(self.q))
            return None if np.isnan(self.q).all() else 2.0 * self.q

    class Toy:
        chunk_rows = 4

        @chunked
        def ik(self, x):
            return Lazy(Evaluation(x), q=x.copy())

    x = np.arange(10.0)[:, None]
    joined = Toy().ik(x)
    assert type(joined) is Lazy and reads == []
    np.testing.assert_array_equal(joined.q, x)
    np.testing.assert_array_equal(joined.twice, 2.0 * x)
    assert reads == [3, 3, 4]  # each chunk's field, when read
    x[:3] = np.nan  # the first chunk's field is None: the whole call's field
    reads.clear()
    joined = Toy().ik(x)
    assert reads == []
    np.testing.assert_array_equal(joined.twice, 2.0 * x)
    assert reads == [3, 3, 4, 10]
