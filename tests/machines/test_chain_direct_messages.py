"""A joint chain's batched direct model writes its per-row diagnoses only for the rows that have
any (issue 22 §3, fifth pass): each row's message must be the one that row gets alone — the same
parts, in the same order, on the same row — and ``""`` for a silent row."""

from __future__ import annotations

import warnings

import numpy as np

import pkmkit


def test_each_rows_message_is_its_own():
    m = pkmkit.machine("trimule-600")
    rng = np.random.default_rng(2)
    q = m.home_q + (rng.random((80, m.n_actuators)) - 0.5) * 0.6
    q[::9] = np.nan  # not finite
    q[4::9, 0] = 1e12  # beyond the largest coordinate
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        batch = m.fk(q, full_output=True, check_singular=True).messages
        alone = [m.fk(row[None], full_output=True, check_singular=True).messages[0]
                 for row in q]
    assert list(batch) == alone
    assert any(";" in text for text in alone)  # rows with two diagnoses
    assert "" in alone and sum(bool(t) for t in alone) > 20
