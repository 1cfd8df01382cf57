"""``numerics.pivoted_qr``: LAPACK's factorisation where no columns tie, the first of tied
columns whatever their last bits (the calibration selected ``dq5`` or ``dL5`` of the same
hexapod depending on which inverse model rounded the Jacobian)."""

import numpy as np
import pytest
import scipy.linalg

from pkmkit.calibration.identifiability import identifiable_parameters
from pkmkit.numerics.pivoted_qr import pivoted_qr


@pytest.mark.parametrize("shape", [(12, 5), (40, 17), (6, 9), (25, 25), (1, 3)])
def test_the_factorisation_is_lapacks_where_nothing_ties(shape):
    rng = np.random.default_rng(sum(shape))
    a = rng.normal(size=shape) * rng.uniform(0.1, 10.0, size=shape[1])
    q, r, piv = pivoted_qr(a)
    _, r_ref, piv_ref = scipy.linalg.qr(a, pivoting=True, mode="economic")
    k = min(shape)
    assert q.shape == (shape[0], k) and r.shape == (k, shape[1])
    np.testing.assert_allclose(q @ r, a[:, piv], atol=1e-12 * np.abs(a).max())
    np.testing.assert_allclose(q.T @ q, np.eye(k), atol=1e-13)
    assert np.allclose(np.tril(r, -1), 0.0)
    np.testing.assert_array_equal(piv, piv_ref)
    np.testing.assert_allclose(np.abs(np.diag(r)), np.abs(np.diag(r_ref)), rtol=1e-10)
    assert (np.diff(np.abs(np.diag(r))) <= 1e-12).all()


def test_tied_columns_are_taken_in_the_given_order_whatever_their_last_bits():
    rng = np.random.default_rng(5)
    base = rng.normal(size=(30, 4))
    for bump in (1.0 + 1e-13, 1.0 - 1e-13):
        # columns 1 and 3 the same effect (an offset and a length), 3 a few ulps larger or
        # smaller: LAPACK follows the bits, the selection keeps column 1
        a = base.copy()
        a[:, 3] = a[:, 1] * bump
        a[:, 1] *= 3.0  # the largest norm: column 1 first, then the tie plays out later
        a[:, 3] *= 3.0
        _, r, piv = pivoted_qr(a)
        assert piv[0] == 1 and 3 in piv[2:]
        assert abs(r[3, 3]) < 1e-12 * abs(r[0, 0])
        names = ("a", "offset", "b", "length")
        for scaled in (a, a[:, [0, 3, 2, 1]]):
            order = names if scaled is a else tuple(names[i] for i in (0, 3, 2, 1))
            chosen = identifiable_parameters(scaled, order, np.ones(4))
            assert chosen.rank == 3
            assert order[1] in {order[i] for i in chosen.selected}  # the one named first


def test_a_zero_matrix_and_zero_columns():
    q, r, piv = pivoted_qr(np.zeros((4, 3)))
    assert np.all(r == 0.0) and sorted(piv) == [0, 1, 2]
    a = np.zeros((5, 3))
    a[:, 2] = 1.0
    q, r, piv = pivoted_qr(a)
    assert piv[0] == 2 and abs(r[0, 0]) == pytest.approx(np.sqrt(5.0))
    np.testing.assert_allclose(q @ r, a[:, piv], atol=1e-15)
