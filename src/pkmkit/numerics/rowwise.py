"""Contractions of batch-last arrays whose every batch entry is computed the same way whatever
the batch: a row's result does not depend on the rows solved beside it (issue 22 §6 — a batch
cut into chunks gives the unchunked result bit for bit).

``np.einsum`` (without ``optimize``) over operands whose batch axis is last runs its inner loop
along that axis and accumulates every contraction index in order, one product after the other,
as a loop of multiplies and adds would — the same rounding at every batch position and for
every batch of two or more. A batch of **one** entry is different: the batch axis of length
one is dropped and the inner loop runs along the contracted axis, through NumPy's unrolled
(SIMD) sum of products, which adds in another order — results one unit in the last place
away. An iterative solver whose active set shrinks to one row (the others converged) then
moves that row by a rounding, and a later stopping test can amplify it. :func:`einsum` here
computes a batch of one as a batch of two identical entries and keeps the first, and copies an
operand whose batch axis is not contiguous (a transposed ``(n, N)`` view: the inner loop would
run along another axis, as for a batch of one).
"""

from __future__ import annotations

import numpy as np


def einsum(spec: str, *operands: np.ndarray) -> np.ndarray:
    """``np.einsum(spec, *operands)`` for an explicit ``spec`` whose output's last index is the
    batch axis (last axis of the operands that carry it): a batch of one entry computed as a
    batch of two, so that it gets the batch's rounding (module docstring).

    Args:
        spec: e.g. ``"mnk,mk->nk"`` (batch index ``k``; operands without it broadcast).
        operands: float arrays, batch axis last where the spec has it.
    """
    inputs, output = spec.split("->")
    batch = output[-1]
    terms = inputs.split(",")
    carried = [t.endswith(batch) for t in terms]
    if any(c and a.shape[-1] == 1 for c, a in zip(carried, operands, strict=True)):
        doubled = [np.concatenate([a, a], axis=-1) if c else a
                   for c, a in zip(carried, operands, strict=True)]
        return np.ascontiguousarray(np.einsum(spec, *doubled)[..., :1])
    # the inner loop runs along the axis of smallest stride: the batch axis must be it
    return np.einsum(spec, *[np.ascontiguousarray(a) if c and a.strides[-1] != a.itemsize
                             else a for c, a in zip(carried, operands, strict=True)])
