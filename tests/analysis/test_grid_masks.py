"""The workspace's boolean grid operations in NumPy (:mod:`pkmkit.analysis.grid_masks`)
against ``scipy.ndimage`` — the oracle, the implementation they replace (issue 22 §3): the
same windows, erosions and labels (numbers included) on random masks of 1 to 3 dimensions
and many densities, and on the shapes that stress a labelling (a spiral, a comb, one
point, none, all)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from pkmkit.analysis.grid_masks import erode_faces, label_faces, window_all


def _masks():
    rng = np.random.default_rng(35)
    for shape in [(1,), (17,), (1, 1), (9, 13), (40, 3), (7, 8, 9), (25, 14, 10), (2, 1, 30)]:
        for density in (0.1, 0.45, 0.6, 0.9):
            yield rng.random(shape) < density
    yield np.zeros((5, 6, 7), dtype=bool)
    yield np.ones((5, 6, 7), dtype=bool)
    comb = np.zeros((21, 21), dtype=bool)
    comb[::2] = True
    comb[:, 0] = True  # the teeth joined at their left end: one part, long paths
    yield comb
    spiral = np.zeros((31, 31), dtype=bool)
    lo, hi = 0, 30
    while lo <= hi:  # a one-point-wide spiral: the longest path a labelling can meet
        spiral[lo, lo:hi + 1] = spiral[lo:hi + 1, hi] = True
        spiral[hi, lo:hi + 1] = True
        spiral[lo + 2:hi + 1, lo] = True
        lo, hi = lo + 2, hi - 2
        if lo <= hi:
            spiral[lo - 1, lo] = True
    yield spiral
    dot = np.zeros((4, 5, 6), dtype=bool)
    dot[2, 3, 4] = True
    yield dot


MASKS = list(_masks())


@pytest.mark.parametrize("mask", MASKS, ids=[f"{m.shape}-{m.sum()}" for m in MASKS])
def test_labels_as_ndimage(mask):
    structure = ndimage.generate_binary_structure(mask.ndim, 1)
    expected, count = ndimage.label(mask, structure=structure)
    labels, mine = label_faces(mask)
    assert mine == count
    np.testing.assert_array_equal(labels, expected)


@pytest.mark.parametrize("mask", MASKS, ids=[f"{m.shape}-{m.sum()}" for m in MASKS])
def test_erosion_and_windows_as_ndimage(mask):
    np.testing.assert_array_equal(erode_faces(mask), ndimage.binary_erosion(mask,
                                                                            border_value=0))
    for k in (1, 2, 3, 4, 7, max(mask.shape) + 2):
        expected = ndimage.minimum_filter(mask.view(np.uint8), size=k, mode="constant",
                                          cval=0).astype(bool)
        np.testing.assert_array_equal(window_all(mask, k), expected)


def test_a_window_of_no_points_is_refused():
    with pytest.raises(ValueError, match="at least 1"):
        window_all(np.ones((3, 3), dtype=bool), 0)
