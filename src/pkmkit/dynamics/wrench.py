"""Cutting-force time series for the inverse dynamics.

A wrench file is a CSV table with a header ``t,fx,fy,fz`` (s, N) — extra columns are ignored —
one row per instant, times strictly increasing. The force at a trajectory sample is linearly
interpolated, and held at the first / last value before / after the table (a cut that starts
late or ends early: pad the file with zero rows to say so).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.io.table import read_table
from pkmkit.numerics.magnitudes import MAX_FORCE

COLUMNS = ("t", "fx", "fy", "fz")


@dataclass(frozen=True)
class WrenchSeries:
    """A force on the tool against time.

    Attributes:
        t: ``(K,)`` s, strictly increasing.
        force: ``(K, 3)`` N.
    """

    t: np.ndarray
    force: np.ndarray

    def __post_init__(self) -> None:
        t, f = np.asarray(self.t, dtype=float), np.asarray(self.force, dtype=float)
        if t.ndim != 1 or f.shape != (t.size, 3) or t.size == 0:
            raise InputError(f"a wrench series needs times (K,) and forces (K, 3); got "
                             f"{t.shape} and {f.shape}")
        if not (np.isfinite(t).all() and np.isfinite(f).all()):
            bad = int(np.flatnonzero(~(np.isfinite(t) & np.isfinite(f).all(axis=1)))[0])
            raise InputError(f"the wrench series has a non-finite value in row {bad + 1}")
        big = np.flatnonzero(~(np.abs(f) <= MAX_FORCE).all(axis=1))
        if big.size:
            k = int(big[0])
            raise InputError(f"the wrench series' row {k + 1} has a force of "
                             f"{np.abs(f[k]).max():g} N, beyond {MAX_FORCE:g} N, the largest "
                             "pkmkit accepts: check the units")
        if (np.diff(t) <= 0).any():
            bad = int(np.flatnonzero(np.diff(t) <= 0)[0])
            raise InputError(f"the wrench series' times must increase: row {bad + 2} has "
                             f"t = {t[bad + 1]:g} after {t[bad]:g}")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "force", f)

    def at(self, times: np.ndarray) -> np.ndarray:
        """Forces ``(N, 3)`` N at ``times`` ``(N,)`` s (linear, held at the ends)."""
        times = np.asarray(times, dtype=float)
        return np.column_stack([np.interp(times, self.t, self.force[:, k]) for k in range(3)])


def load_wrench_series(path: str | Path) -> WrenchSeries:
    """Read a wrench file (see the module docstring).

    Raises:
        InputError: unreadable file, missing columns, a bad cell (with its line), times that do
            not increase.
    """
    table = read_table(path, COLUMNS)
    try:
        return WrenchSeries(table[:, 0], table[:, 1:4])
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None
