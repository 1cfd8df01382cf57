"""Boolean masks on a grid in NumPy: windows, erosion and connected parts (face neighbours).

The workspace maps used ``scipy.ndimage`` for these three (``minimum_filter``,
``binary_erosion``, ``label``), whose import costs ≈ 0.15–0.2 s of a `pkmkit workspace`
run on top of SciPy's optimisers (issue 22 §3, docs/benchmarks.md "Session 35: the hexapod's
workspace"). On boolean masks each is exact, so these give the same masks and the same
labels (numbered in the order of each part's first point in C order, as ``ndimage.label``);
tests/analysis/test_grid_masks.py checks them against ``scipy.ndimage``."""

from __future__ import annotations

import numpy as np


def window_all(mask: np.ndarray, k: int) -> np.ndarray:
    """True where the k-point window ``[i − k//2, i − k//2 + k − 1]`` along every axis is all
    true in ``mask`` (outside the grid counts as false): ``ndimage.minimum_filter(mask,
    size=k, mode="constant", cval=0)`` on a boolean mask, one axis at a time by running
    sums."""
    out = np.asarray(mask, dtype=bool)
    if k < 1:
        raise ValueError(f"window_all: k must be at least 1 (got {k})")
    left = k // 2
    for axis in range(out.ndim):
        n = out.shape[axis]
        pad = [(0, 0)] * out.ndim
        pad[axis] = (left + 1, k - 1 - left)  # one more zero in front: the running sum's 0
        sums = np.cumsum(np.pad(out, pad).astype(np.int64), axis=axis)
        upper = np.take(sums, np.arange(k, k + n), axis=axis)
        lower = np.take(sums, np.arange(0, n), axis=axis)
        out = (upper - lower) == k
    return out


def erode_faces(mask: np.ndarray) -> np.ndarray:
    """True where ``mask`` and its 2·ndim face neighbours are true (off the grid: false):
    ``ndimage.binary_erosion(mask, border_value=0)`` with its default (face) structure."""
    mask = np.asarray(mask, dtype=bool)
    padded = np.pad(mask, 1)
    out = mask.copy()
    inner = tuple(slice(1, -1) for _ in range(mask.ndim))
    for axis in range(mask.ndim):
        for shift in (-1, 1):
            window = list(inner)
            window[axis] = slice(1 + shift, padded.shape[axis] - 1 + shift)
            out &= padded[tuple(window)]
    return out


def label_faces(mask: np.ndarray) -> tuple[np.ndarray, int]:
    """``(labels, count)`` of the parts of ``mask`` connected through faces, as
    ``ndimage.label(mask, structure=generate_binary_structure(ndim, 1))``: 0 off the mask,
    1…count on it, the parts numbered in the order of their first point (C order).

    Each point points to the smallest flat index of its part found so far; every round hooks
    the smaller of two neighbours' pointers onto the larger (``minimum.at``) and then follows
    pointers to their ends, until no neighbour pair disagrees."""
    mask = np.asarray(mask, dtype=bool)
    flat = mask.ravel()
    index = np.arange(flat.size).reshape(mask.shape)
    heads, tails = [], []
    for axis in range(mask.ndim):
        first = tuple(slice(0, -1) if a == axis else slice(None) for a in range(mask.ndim))
        second = tuple(slice(1, None) if a == axis else slice(None) for a in range(mask.ndim))
        both = mask[first] & mask[second]
        heads.append(index[first][both])
        tails.append(index[second][both])
    u, v = np.concatenate(heads), np.concatenate(tails)
    parent = np.arange(flat.size)
    while True:
        low = np.minimum(parent[u], parent[v])
        hooked = parent.copy()
        np.minimum.at(hooked, parent[u], low)
        np.minimum.at(hooked, parent[v], low)
        while True:  # follow the pointers to their roots
            jumped = hooked[hooked]
            if np.array_equal(jumped, hooked):
                break
            hooked = jumped
        if np.array_equal(hooked, parent):
            break
        parent = hooked
    roots = parent[flat]
    firsts, numbers = np.unique(roots, return_inverse=True)  # a root is its part's first point
    labels = np.zeros(flat.size, dtype=np.int32)
    labels[flat] = numbers.ravel() + 1
    return labels.reshape(mask.shape), int(firsts.size)
