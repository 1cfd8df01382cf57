"""The C twins of the identification's chain kernels (``pkmkit.native.kernels``,
native/chain_linearise.c): ``chain_linearise_rows`` (twin of
:func:`pkmkit.solve.chain_kernel._linearise_rows`: C_U, the defect columns C_δ, the tool frame
and its defect twists) and ``absorb`` (twin of :func:`pkmkit.solve.chain_linalg._absorb_rows`:
``dU = −C_U⁺ C_δ`` by the normal equations) against the Numba kernels, bit for bit, on solved,
random, column-twist and non-finite rows and on regular, rank-deficient, zero and non-finite
C_U; the independent oracles (the NumPy closure with ``defects=True``, LAPACK's pseudo-inverse)
are tests/solve/test_chain_kernel.py's, which now run these twins; the argument checks; a fresh
``pkmkit calibrate`` on the Tripteor without Numba."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import pkmkit
from pkmkit.calibration import random_defects
from pkmkit.model.defect_rule import add_defects
from pkmkit.solve import chain_rows
from pkmkit.solve.chains import closure, with_column_twists
from pkmkit.spatial.rotation import rotvec_to_matrix

try:
    from pkmkit.native import kernels as _kernels
except ImportError:  # built without a compiler (tests/native/test_kernels.py checks CI)
    _kernels = None

pytestmark = pytest.mark.skipif(_kernels is None or not hasattr(_kernels, "absorb"),
                                reason="pkmkit.native.kernels was not built")
numba_kernel = pytest.importorskip("pkmkit.solve.chain_kernel")
numba_linalg = pytest.importorskip("pkmkit.solve.chain_linalg")
SRC = Path(pkmkit.__file__).resolve().parents[1]


def _same_bits(a, b):
    """The same values bit for bit, NaN for NaN (any payload)."""
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape and a.dtype == b.dtype
    if a.dtype.kind != "f":
        np.testing.assert_array_equal(a, b)
        return
    nan = np.isnan(a)
    np.testing.assert_array_equal(nan, np.isnan(b))
    np.testing.assert_array_equal(a[~nan].view(np.int64), b[~nan].view(np.int64))


def _linearised(model, values, platform, passive, kernel, monkeypatch):
    """``chain_rows.linearise`` with ``kernel`` as the compiled ``_linearise_rows``."""
    from pkmkit.numerics import jit

    real = jit.kernel
    monkeypatch.setattr(jit, "kernel", lambda module, name: kernel if name == "_linearise_rows"
                        else real(module, name))
    try:
        return chain_rows.linearise(model, values, platform, passive)
    finally:
        monkeypatch.setattr(jit, "kernel", real)


@pytest.mark.parametrize("name", ["tripteor-x7", "trimule-600"])
@pytest.mark.parametrize("case", ["solved", "random", "column twists"])
def test_linearise_c_writes_the_numba_kernels_bits(name, case, monkeypatch):
    """Every output (C_U, C_δ, tool rotation, position, defect twists) the same bits through C
    and Numba: at solved configurations of a machine with defects, at random states with a
    non-finite row, and on a model whose defects are column twists spread over its elements
    (several per element, the head's included)."""
    m = pkmkit.machine(name)
    rng = np.random.default_rng(60)
    machine = add_defects(m, random_defects(m, rng))
    model = machine.model
    passive = machine.passive_variables
    if case == "solved":
        q = machine.measurement_configurations(25, rng)
        direct = machine.fk(q, full_output=True, strokes="ignore")
        values = np.tile(model.home, (len(q), 1))
        values[:, np.flatnonzero(model.actuated)] = q
        values[:, passive] = direct.passive
        platform = direct.platform
    else:
        if case == "column twists":
            elements = rng.integers(0, len(model.elements), 25)
            model = with_column_twists(model, elements, rng.normal(size=(25, 6)))
        values = machine.home_values[None] + rng.normal(0.0, 0.3, (20, model.n_variables))
        platform = machine.home_platform[None] + rng.normal(0.0, [0.05] * 3 + [1.0] * 3,
                                                            (20, 6))
        values[3, passive[0]] = np.nan
        platform[4, 5] = np.inf
    outs = [_linearised(model, np.ascontiguousarray(values), platform, passive, k, monkeypatch)
            for k in (_kernels.chain_linearise_rows, numba_kernel._linearise_rows)]
    for a, b in zip(*outs, strict=True):
        _same_bits(a, b)
    _, cd, _, _, tool_tw = outs[0]
    assert np.nanmax(np.abs(cd)) > 0 and np.nanmax(np.abs(tool_tw)) > 0
    if case == "solved":  # the oracle on one row: the NumPy closure with defects=True
        rot = rotvec_to_matrix(platform[:2, 3:]).transpose(1, 2, 0)
        c = closure(model, rot, platform[:2, :3].T, values[:2].T, defects=True)
        np.testing.assert_allclose(cd[:2], c.defects.transpose(2, 0, 1), rtol=0,
                                   atol=1e-12 * np.abs(c.defects).max())


def _absorb(kernel, cu, cd):
    n, r, u = cu.shape
    du, rest = np.full((n, u, cd.shape[2]), -7.0), np.full((n, r, cd.shape[2]), -7.0)
    ok = np.ones(n, dtype=np.bool_)
    kernel(np.ascontiguousarray(cu), np.ascontiguousarray(cd), du, rest, ok)
    return du, rest, ok


def test_absorb_c_writes_the_numba_kernels_bits():
    """Regular, rank-deficient (a repeated column, a column within 1e-6 of another), zero,
    tiny, huge and non-finite C_U, and closure Jacobians of the Tripteor: dU, the remainder
    and the flags bit for bit, every row written."""
    rng = np.random.default_rng(61)
    cu, cd = rng.normal(size=(12, 18, 16)), rng.normal(size=(12, 18, 30))
    cu[2, :, 7] = cu[2, :, 3] * 2.0
    cu[3, :, 9] = cu[3, :, 1] + 1e-6 * rng.normal(size=18)
    cu[4] = 0.0
    cu[5] *= 1e-160
    cu[6] *= 1e160
    cu[7, 2, 2] = np.nan
    cd[8, 0, 0] = np.inf
    m = pkmkit.machine("tripteor-x7")
    q = m.measurement_configurations(10, rng)
    direct = m.fk(q, full_output=True)
    values = np.tile(m.model.home, (len(q), 1))
    values[:, np.flatnonzero(m.model.actuated)] = q
    values[:, m.passive_variables] = direct.passive
    lin = chain_rows.linearise(m.model, values, direct.platform, m.passive_variables)
    cu = np.concatenate([cu, lin[0][:, :, :16]])
    cd = np.concatenate([cd, lin[1][:, :, :30]])
    c_out = _absorb(_kernels.absorb, cu, cd)
    numba_out = _absorb(numba_linalg._absorb_rows, cu, cd)
    for a, b in zip(c_out, numba_out, strict=True):
        _same_bits(a, b)
    du, rest, ok = c_out
    assert not (du == -7.0).any() and not (rest == -7.0).any()
    assert not ok[2] and not ok[4] and ok[0] and ok[12:].all()
    assert np.isnan(du[~ok]).all()


@pytest.mark.parametrize("which,value,error", [
    (0, np.zeros((2, 18, 16), dtype=np.float32), TypeError),
    (1, np.zeros((2, 17, 30)), ValueError),
    (2, np.zeros((2, 15, 30)), ValueError),
    (3, np.zeros((2, 18, 29)), ValueError),
    (4, np.ones(2, dtype=np.int64), TypeError),
    (4, np.ones(3, dtype=np.bool_), ValueError),
])
def test_absorb_refuses_bad_arguments(which, value, error):
    args = [np.zeros((2, 18, 16)), np.zeros((2, 18, 30)), np.zeros((2, 16, 30)),
            np.zeros((2, 18, 30)), np.ones(2, dtype=np.bool_)]
    args[which] = value
    with pytest.raises(error):
        _kernels.absorb(*args)
    with pytest.raises(TypeError, match="5 positional"):
        _kernels.absorb(*args[:4])


def _linearise_call(m):
    from pkmkit.model.chains import cached_defect_twists

    model = m.model
    args = list(chain_rows.model_arrays(model, m.passive_variables))
    owner = np.asarray(model.defect_index.element, dtype=np.int64)
    d = len(owner)
    order = np.argsort(owner, kind="stable").astype(np.int64)
    starts = np.concatenate([[0], np.cumsum(np.bincount(owner, minlength=len(
        model.elements)))]).astype(np.int64)
    n = 6 + len(m.passive_variables)
    rows = 6 * len(model.legs)
    return [*args, np.ascontiguousarray(cached_defect_twists(model), dtype=float), order,
            starts, np.array(model.head, dtype=np.int64), np.zeros((2, model.n_variables)),
            np.zeros((2, n)), 1.0, np.zeros((2, rows, n)), np.zeros((2, rows, d)),
            np.zeros((2, 3, 3)), np.zeros((2, 3)), np.zeros((2, 6, d))]


@pytest.mark.parametrize("which,value,error", [
    (7, lambda a: a + 10_000, ValueError),               # order beyond the defects
    (8, lambda a: a[::-1].copy(), ValueError),           # starts decreasing
    (8, lambda a: a[:-1].copy(), ValueError),            # starts not (E + 1,)
    (9, lambda a: a + 10_000, ValueError),               # head element out of range
    (6, lambda a: a[:, :5].copy(), ValueError),          # local not (D, 6)
    (14, lambda a: a[:, :, :-1].copy(), ValueError),     # cd columns ≠ D
    (17, lambda a: a[:1].copy(), ValueError),            # tool_tw rows ≠ N
    (15, lambda a: np.zeros((2, 3, 3), dtype=np.float32), TypeError),
])
def test_linearise_refuses_bad_arguments(which, value, error):
    args = _linearise_call(pkmkit.machine("tripteor-x7"))
    args[which] = value(args[which])
    args[13][...] = -5.0
    with pytest.raises(error):
        _kernels.chain_linearise_rows(*args)
    assert (args[13] == -5.0).all()
    with pytest.raises(TypeError, match="18 positional"):
        _kernels.chain_linearise_rows(*args[:17])


def test_jit_dispatch(monkeypatch):
    from pkmkit.numerics import jit

    monkeypatch.delenv("PKMKIT_COMPILED", raising=False)
    monkeypatch.delenv("PKMKIT_NATIVE", raising=False)
    assert jit.kernel(chain_rows.KERNEL, "_linearise_rows") is _kernels.chain_linearise_rows
    assert jit.kernel(chain_rows.LINALG, "_absorb_rows") is _kernels.absorb
    assert chain_rows.linearise_native()
    monkeypatch.setenv("PKMKIT_NATIVE", "0")
    assert jit.kernel(chain_rows.KERNEL, "_linearise_rows") is numba_kernel._linearise_rows
    assert jit.kernel(chain_rows.LINALG, "_absorb_rows") is numba_linalg._absorb_rows
    assert not chain_rows.linearise_native()


@pytest.mark.ci  # three fresh processes (≈ 4 s of CPU each): .ci/run's second stage
def test_a_fresh_chain_calibration_does_not_import_numba(tmp_path):
    """``pkmkit calibrate tripteor-x7`` (simulated tracker points) in a fresh process: the
    identification's closure, linearisation and absorption through the C kernels, no Numba,
    and the same report as with the Numba kernels at every batch size (``PKMKIT_NATIVE=0`` and
    ``PKMKIT_COMPILED=1``: without the latter, a process without the C kernels solves its small
    closures by the NumPy engine until Numba is imported, which rounds differently)."""
    env = {"PYTHONPATH": str(SRC), "PATH": "/usr/bin:/bin"}
    ident = tmp_path / "ident.csv"
    subprocess.run([sys.executable, "-m", "pkmkit.cli.main", "simulate-measurements",
                    "tripteor-x7", "--measure", "point", "--poses", "40", "--defects", "random",
                    "--seed", "7", "--units", "mm", "--out", str(ident)], env=env, check=True,
                   capture_output=True, timeout=300)
    code = ("import sys\nfrom pkmkit.cli.main import main\n"
            "sys.argv = ['pkmkit', *sys.argv[1:]]\n"
            "try:\n    main()\nexcept SystemExit as e:\n    assert e.code in (0, 3, None), e.code\n"
            "print('NUMBA', 'numba' in sys.modules, 'pkmkit.native.kernels' in sys.modules)")
    outputs = []
    for switches in ({"PKMKIT_NATIVE": "1"}, {"PKMKIT_NATIVE": "0", "PKMKIT_COMPILED": "1"}):
        out = subprocess.run([sys.executable, "-c", code, "calibrate", "tripteor-x7",
                              "--measure", "point", "--measurements", str(ident), "--json"],
                             capture_output=True, text=True, env={**env, **switches},
                             timeout=300, check=True).stdout
        outputs.append(out)
    assert outputs[0].strip().splitlines()[-1] == "NUMBA False True"
    assert outputs[1].strip().splitlines()[-1].startswith("NUMBA True")

    def stable(text):  # the report without its timing
        return [line for line in text.splitlines()[:-1] if "second" not in line
                and "time" not in line]

    assert stable(outputs[0]) == stable(outputs[1])
