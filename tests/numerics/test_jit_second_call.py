"""``jit.compiled_from_second_call``: the rule shared by the full-pose single calls and the
every-mode tracker — a one-shot call does not import Numba, the next call of the same owner
runs compiled."""

import types

from pkmkit.numerics import jit


def _numba_not_imported(monkeypatch, available: bool = True) -> None:
    monkeypatch.setattr(jit, "use_compiled_solver",
                        lambda rows, **_: available and rows >= jit.SOLVER_ROWS)


def test_the_first_call_of_each_owner_stays_on_numpy_the_next_runs_compiled(monkeypatch):
    _numba_not_imported(monkeypatch)
    a, b = types.SimpleNamespace(), types.SimpleNamespace()
    assert not jit.compiled_from_second_call(a, "direct")
    assert jit.compiled_from_second_call(a, "direct")
    assert not jit.compiled_from_second_call(a, "velocity")  # another solver: its own count
    assert not jit.compiled_from_second_call(b, "direct")  # another machine
    assert jit.compiled_from_second_call(b, "direct")


def test_never_without_numba_and_always_once_imported(monkeypatch):
    owner = types.SimpleNamespace()
    _numba_not_imported(monkeypatch, available=False)
    assert not any(jit.compiled_from_second_call(owner, "direct") for _ in range(3))
    monkeypatch.setattr(jit, "use_compiled_solver", lambda rows, **_: True)
    assert jit.compiled_from_second_call(types.SimpleNamespace(), "direct")
