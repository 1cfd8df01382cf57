"""Hostile input strategies shared by the fuzz tests."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import event
from hypothesis import strategies as st

from pkmkit.exceptions import PkmError

from .conftest import bounded

#: Numbers a careless or hostile caller may pass.
HOSTILE_FLOATS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, -0.0, 1e-300, -1e-300, 1e300, -1e300, 1e9, 1e10, math.nan, math.inf,
                     -math.inf, 5e-324]),
    st.floats(-2.0, 2.0),
)
#: Numbers in a plausible range (metres around a machine).
PLAUSIBLE = st.floats(-2.0, 2.0, allow_nan=False)
#: Values that are not numbers at all.
NON_NUMBERS = st.one_of(st.text(max_size=5), st.none(), st.booleans(),
                        st.lists(st.text(max_size=2), max_size=3), st.just(object()),
                        st.dictionaries(st.text(max_size=2), st.integers(), max_size=2))


def weighted(*choices: tuple[int, st.SearchStrategy]) -> st.SearchStrategy:
    """``choices`` of ``(weight, strategy)``, drawn in proportion to the weights (``one_of``
    of repeated strategies would not weight them)."""
    table = [strategy for weight, strategy in choices for _ in range(weight)]
    return st.integers(0, len(table) - 1).flatmap(lambda k: table[k])


def arrays(width: int, *, plausible_weight: int = 8) -> st.SearchStrategy:
    """Batches ``(N, width)`` (or single rows) mixing plausible and hostile numbers, plus
    wrongly shaped and non-numeric values (one draw in six)."""
    number = weighted((plausible_weight, PLAUSIBLE), (1, HOSTILE_FLOATS))
    row = st.lists(number, min_size=width, max_size=width)
    good = st.one_of(row.map(np.array),
                     st.lists(row, min_size=1, max_size=40).map(np.array))
    bad = st.one_of(
        st.lists(number, min_size=0, max_size=width + 2).filter(lambda v: len(v) != width),
        st.lists(st.lists(number, min_size=width + 1, max_size=width + 1), min_size=1,
                 max_size=3),
        st.just(np.zeros((0, width))), st.just(np.zeros((2, 2, width))), NON_NUMBERS,
        st.lists(st.one_of(number, st.text(max_size=2)), min_size=width, max_size=width),
    )
    return weighted((5, good), (1, bad))


def call(func, *args, **kwargs):
    """Run ``func``: its result, or None when it raised a :class:`PkmError` (the only
    exception bad input may give). Any other exception, or a hang, fails the test."""
    name = getattr(func, "__name__", type(func).__name__)
    with bounded():
        try:
            result = func(*args, **kwargs)
        except PkmError as exc:
            assert str(exc), "an error without a message"
            event(f"{name}: {type(exc).__name__}")
            return None
    event(f"{name}: answer")
    return result
