"""A joint chain's row does not depend on the rows solved beside it (issue 22 §6): ``ik`` and
``fk`` of a batch equal, bit for bit, the same rows called in pieces of 1, 4, 9 and uneven
sizes — on the NumPy engine and on the compiled kernels, with rows unreachable, beyond a
stroke, without assembly and not finite among them.

The engine used to give a row another rounding when it was alone in its batch or alone still
iterating (``np.einsum`` over a batch axis of length one sums in another order), and when
every row was active (its unknowns were then a transposed view whose batch axis is not
contiguous); the direct model's start (a matrix product over the rows) likewise. One unit in
the last place on one row was enough to move a pose 5 m out of the workspace between a batch
and its chunks (:mod:`pkmkit.numerics.rowwise`)."""

from __future__ import annotations

import dataclasses
import itertools
import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.status import Status

PIECES = {"ones": [1] * 23, "fours": [4] * 5 + [3], "nines": [9, 9, 5], "uneven": [5, 2, 11, 1, 4]}
#: the NumPy engine's pieces (its calls cost 0.03–0.6 s each: the ``ik`` test took 4.3 s of
#: CPU with PIECES, 2.6 s with these): alone every row up to the one not finite (the reached
#: rows, the one beyond a stroke, the one without a closure), then the uneven pieces. Planted
#: in pkmkit.numerics.rowwise, a batch of one computed as it comes and a batch axis left
#: transposed each still fail both tests (docs/testing.md, "Fifth round").
NUMPY_PIECES = {"ones": [1] * 15 + [8], "uneven": PIECES["uneven"]}


def same(a, b, where: str) -> None:
    """Bit for bit: arrays (NaN where NaN), tuples, records field by field."""
    assert type(a) is type(b), where
    if isinstance(a, np.ndarray):
        assert a.dtype == b.dtype and a.shape == b.shape, where
        diff = np.ascontiguousarray(a).view(np.uint8) != np.ascontiguousarray(b).view(np.uint8)
        assert not diff.any(), f"{where}: rows {np.unique(np.nonzero(diff.reshape(len(a), -1))[0])}"
    elif dataclasses.is_dataclass(a):
        for f in dataclasses.fields(a):
            same(getattr(a, f.name), getattr(b, f.name), f"{where}.{f.name}")
    else:
        assert a == b, where


def rows_of(result, a: int, b: int, n: int):
    """Rows ``a:b`` of a batch result of ``n`` rows (per-row arrays, tuples and records
    cut; fields describing the call kept)."""
    if isinstance(result, np.ndarray):
        return result[a:b] if result.ndim and result.shape[0] == n else result
    if isinstance(result, tuple) and len(result) == n:
        return result[a:b]
    if dataclasses.is_dataclass(result):
        return dataclasses.replace(result, **{
            f.name: rows_of(getattr(result, f.name), a, b, n)
            for f in dataclasses.fields(result) if f.init})
    return result


def check_pieces(call, rows: np.ndarray, whole, sizes: list[int], where: str) -> None:
    """Every piece of ``rows`` (of the given sizes, in order) called alone gives the batch's
    rows bit for bit (a piece without any solved row has no direct record and no closure: then
    the batch's rows are not solved either)."""
    edges = np.cumsum([0, *sizes])
    assert edges[-1] == len(rows)
    for a, b in itertools.pairwise(edges.tolist()):
        part, expected = call(rows[a:b]), rows_of(whole, a, b, len(rows))
        if getattr(part, "direct", False) is None:
            assert np.isnan(expected.q).all(), where
            part = dataclasses.replace(part, direct=expected.direct)
        if getattr(part, "closure", False) is None:  # likewise: no closure found in the piece
            assert np.isnan(expected.closure).all(), where
            part = dataclasses.replace(part, closure=expected.closure)
        same(part, expected, f"{where}, rows {a}:{b}")


def poses(m, n: int = 23) -> np.ndarray:
    """Poses over and beyond the default box: reached, 5 m away (reached beyond the strokes:
    the legs' slides are not bounded geometrically), a kilometre below home with the tool axis
    reversed (no closure found: the legs' joints are not bounded either, and from its
    first-order start the inverse reaches home's point with the axis reversed, the head half a
    turn beyond its stroke), tilted tool axes, a row not finite."""
    rng = np.random.default_rng(1)
    lo, hi = m.default_box()
    x = np.tile(np.asarray(m.home_pose, dtype=float), (n, 1))
    x[:, :3] = lo + (hi - lo) * (-0.3 + 1.6 * rng.random((n, 3)))
    x[3, :3] += 5.0
    x[4] = [*(np.asarray(m.home_pose[:3]) - [0.0, 0.0, 1e3]), 0.0, 0.0, -1.0]
    x[5, 3:] = [1.0, 0.0, 0.2]
    x[9, 3:] = [0.3, -0.2, 1.0]
    x[14] = np.nan
    return x


def actuators(m, n: int = 23) -> np.ndarray:
    """Actuator values around home: assemblies, one far beyond (no assembly), one beyond a
    stroke, one not finite."""
    rng = np.random.default_rng(2)
    q = np.tile(m.home_q, (n, 1)) + 0.3 * (rng.random((n, m.n_actuators)) - 0.5)
    q[2, :3] += [1.0, -1.0, 0.0]
    q[7, 0] = m.model.q_max[m._actuated[0]] + 0.05
    q[11] = np.nan
    return q


#: the TriMule's cases take 7 s of the ordinary run's CPU: `.ci/run`'s second stage runs them
MACHINES = ["tripteor-x7", pytest.param("trimule-600", marks=pytest.mark.ci)]


@pytest.fixture(params=["0", "1"], ids=["numpy", "compiled"])
def path(request, monkeypatch):
    if request.param == "1":
        pytest.importorskip("numba")
    monkeypatch.setenv("PKMKIT_COMPILED", request.param)
    return request.param


@pytest.mark.parametrize("ident", MACHINES)
def test_inverse_rows_do_not_depend_on_their_batch(ident, path):
    m = pkmkit.machine(ident)
    x = poses(m)

    def call(rows):
        return m.ik(rows, full_output=True)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        whole = call(x)
        # the batch holds what the test means: reached rows, a row beyond a stroke, a row out
        # of reach, a row not finite
        assert (whole.status == Status.OK).sum() >= 8
        assert whole.out_of_stroke[3]
        assert whole.status[4] not in (Status.OK, Status.INVALID_INPUT)
        assert whole.status[14] == Status.INVALID_INPUT
        for name, sizes in (PIECES if path == "1" else NUMPY_PIECES).items():
            check_pieces(call, x, whole, sizes, f"{ident} ik in {name}")


@pytest.mark.parametrize("ident", MACHINES)
def test_direct_rows_do_not_depend_on_their_batch(ident, path):
    m = pkmkit.machine(ident)
    q = actuators(m)

    def call(rows):
        return m.fk(rows, full_output=True)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        whole = call(q)
        assert (whole.status == Status.OK).sum() >= 8
        assert whole.status[2] == Status.NO_ASSEMBLY
        assert whole.out_of_stroke[7]
        assert whole.status[11] == Status.INVALID_INPUT
        for name, sizes in (PIECES if path == "1" else NUMPY_PIECES).items():
            check_pieces(call, q, whole, sizes, f"{ident} fk in {name}")
