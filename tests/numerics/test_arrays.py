import numpy as np
import pytest

from pkmkit.exceptions import InputError
from pkmkit.numerics.arrays import as_batch, finite_rows, require_finite, restore_shape


def test_single_row_becomes_batch_of_one():
    arr, single = as_batch([1, 2, 3], 3, "pose")
    assert single and arr.shape == (1, 3) and arr.dtype == np.float64
    assert restore_shape(arr, single).shape == (3,)


def test_batch_kept():
    arr, single = as_batch(np.zeros((5, 2)), 2, "q")
    assert not single and arr.shape == (5, 2)
    assert restore_shape(arr, single).shape == (5, 2)


@pytest.mark.parametrize(
    "value, message",
    [
        ([1, 2], "3 components"),
        (np.zeros((4, 2)), r"\(N, 3\)"),
        (np.zeros((2, 2, 3)), "shape"),
        (np.zeros((0, 3)), "empty"),
        (["a", "b", "c"], "real numbers"),
        (5.0, "shape"),
    ],
)
def test_bad_shapes_are_typed_errors(value, message):
    with pytest.raises(InputError, match=message):
        as_batch(value, 3, "pose")


def test_finite_rows_and_require_finite():
    arr = np.array([[0.0, 1.0], [np.nan, 0.0], [0.0, np.inf]])
    assert finite_rows(arr).tolist() == [True, False, False]
    assert finite_rows(arr[:0]).shape == (0,)
    with pytest.raises(InputError, match="component 1 is not finite"):
        require_finite(np.array([[0.0, np.inf]]), "pose")
