"""pkmkit.numerics.rowwise.einsum: a batch entry gets the same rounding whatever the batch —
alone in a batch of one, in a batch of many, or in a batch whose batch axis is a strided
(transposed) view."""

from __future__ import annotations

import numpy as np
import pytest

from pkmkit.numerics.rowwise import einsum

SPECS = [("mk,mk->k", [(24,), (24,)]), ("mnk,mk->nk", [(24, 21), (24,)]),
         ("ijk,jk->ik", [(7, 4), (4,)]), ("jik,ik->jk", [(4, 7), (7,)]),
         ("abk,cbk->ack", [(3, 3), (3, 3)]), ("ak,ak->k", [(3,), (3,)])]


@pytest.mark.parametrize(("spec", "shapes"), SPECS)
def test_an_entry_alone_or_strided_is_computed_as_in_its_batch(spec, shapes):
    rng = np.random.default_rng(0)
    k = 37
    ops = [rng.standard_normal((*s, k)) * 10.0 ** rng.uniform(-3, 3, (*s, k)) for s in shapes]
    whole = einsum(spec, *ops)
    for i in range(k):
        alone = einsum(spec, *[a[..., i:i + 1].copy() for a in ops])
        assert np.array_equal(alone[..., 0], whole[..., i])
    # the same operands with a non-contiguous batch axis (the transpose of a row-first copy)
    strided = [np.ascontiguousarray(np.moveaxis(a, -1, 0)) for a in ops]
    views = [np.moveaxis(a, 0, -1) for a in strided]
    assert np.array_equal(einsum(spec, *views), whole)


def test_plain_einsum_is_not_so():
    """What the wrapper is for: NumPy's own einsum rounds a batch of one differently."""
    rng = np.random.default_rng(0)
    a = rng.standard_normal((24, 37)) * 10.0 ** rng.uniform(-3, 3, (24, 37))
    whole = np.einsum("mk,mk->k", a, a)
    alone = [np.einsum("mk,mk->k", a[:, i:i + 1].copy(), a[:, i:i + 1].copy())[0]
             for i in range(37)]
    assert not np.array_equal(np.array(alone), whole)
