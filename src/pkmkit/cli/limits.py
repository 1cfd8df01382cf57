"""Magnitudes and sizes the commands refuse up front (issue 18 §5).

A value orders of magnitude beyond anything a machine tool meets is a unit slip or a typo, and
computing with it gives ``inf``/``nan`` or a number nobody can use; a size that would need
gigabytes of memory or hours is refused before any work, naming the limit:

=============================== ==================================================
``--tool-length``               \\|L\\| ≤ :data:`MAX_TOOL_LENGTH` (100 m)
``--wrench``                    every component ≤ :data:`MAX_FORCE` (1e9 N, N·m)
``--noise`` SIGMA               0 ≤ σ ≤ :data:`MAX_NOISE` (1 m)
``--poses N`` (simulated)       N ≤ :data:`MAX_SIMULATED` (1e6 rows)
``--monte-carlo``               samples × map points ≤ :data:`MAX_SAMPLED` (5e7)
``compensate --step``           path length / step ≤ :data:`MAX_PIECES` (2e6)
``path --feed``                 beyond :data:`MAX_FEED` (10 m/s) it must be reached
=============================== ==================================================

When a length read in metres would be a sensible value in millimetres, the message asks "did
you mean --units mm?".
"""

from __future__ import annotations

import math

import click
import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.model.parameters import length_scale
from pkmkit.numerics.magnitudes import MAX_FORCE

from .unit_text import UNITS_KEY

#: Longest tool (m): the tools of the seed machines are 0.1–0.2 m long.
MAX_TOOL_LENGTH = 100.0
#: Largest standard deviation of a reading noise (m).
MAX_NOISE = 1.0
#: Most simulated measurement rows (a few hundred bytes each, and Jacobians when calibrated).
MAX_SIMULATED = 1_000_000
#: Most sampled machine evaluations of a Monte Carlo tolerance analysis.
MAX_SAMPLED = 50_000_000
#: Most pieces a compensated program may be cut into (as many as a path holds segments).
MAX_PIECES = 2_000_000
#: Fastest plausible machining feed (m/s); a faster one the path never reaches is a unit slip.
MAX_FEED = 10.0


def _hint(value_m: float, limit_m: float, units: str) -> str:
    """``"; did you mean --units mm?"`` when the value read in metres fits in millimetres."""
    if units == "m" and abs(value_m) * 1e-3 <= limit_m:
        return "; did you mean --units mm?"
    return ""


def check_tool_length(ctx: click.Context, param: click.Parameter, value: float | None
                      ) -> float | None:
    """Click callback of ``--tool-length``: finite and at most :data:`MAX_TOOL_LENGTH` in
    ``--units`` (an eager option, read first)."""
    if value is None:
        return value
    units = ctx.meta.get(UNITS_KEY, "m")
    try:
        check_tool_lengths(np.array([value]) * length_scale(units), units, "")
    except InputError as exc:
        raise click.BadParameter(str(exc).lstrip(": ")) from None
    return value


def check_tool_lengths(si: np.ndarray, units: str, what: str = "--tool-lengths") -> np.ndarray:
    """Tool lengths ``si`` (m): finite and at most :data:`MAX_TOOL_LENGTH` (message in
    ``units``)."""
    si = np.asarray(si, dtype=float)
    scale = length_scale(units)
    for value in si.ravel():
        if not math.isfinite(value):
            raise InputError(f"{what}: a tool length must be finite, got {value / scale!r}")
        if abs(value) > MAX_TOOL_LENGTH:
            raise InputError(
                f"{what}: {value / scale:g} {units} is beyond {MAX_TOOL_LENGTH / scale:g} "
                f"{units}, the longest tool pkmkit accepts{_hint(value, MAX_TOOL_LENGTH, units)}")
    return si


def check_wrench(values: np.ndarray, what: str = "--wrench") -> np.ndarray:
    """``values`` (N, N·m) if every component is at most :data:`MAX_FORCE`."""
    values = np.asarray(values, dtype=float)
    big = np.flatnonzero(~(np.abs(values) <= MAX_FORCE))
    if big.size:
        raise InputError(f"{what}: component {int(big[0]) + 1} = {values[big[0]]:g} is beyond "
                         f"{MAX_FORCE:g} N (or N·m), the largest force pkmkit accepts")
    return values


def check_noise(sigma_si: float, units: str, what: str = "--noise") -> float:
    """A reading noise σ (m): finite, ≥ 0 and at most :data:`MAX_NOISE`."""
    scale = length_scale(units)
    if not (math.isfinite(sigma_si) and sigma_si >= 0):
        raise InputError(f"{what} must be a finite standard deviation ≥ 0, got "
                         f"{sigma_si / scale:g} {units}")
    if sigma_si > MAX_NOISE:
        raise InputError(f"{what} {sigma_si / scale:g} {units} is beyond "
                         f"{MAX_NOISE / scale:g} {units}, the largest reading noise pkmkit "
                         f"accepts{_hint(sigma_si, MAX_NOISE, units)}")
    return sigma_si


def check_count(count: float, limit: float, what: str, lower: str) -> None:
    """Refuse a size ``count`` beyond ``limit`` before any work: ``what`` names what is
    counted (``"simulated measurements"``), ``lower`` says what to change."""
    if not count <= limit:
        raise InputError(f"{count:.3g} {what}, above the limit of {limit:.3g} (memory and "
                         f"time); {lower}")


def check_feed_reached(feed_si: float, peak_si: float, units: str) -> None:
    """Refuse a feed beyond :data:`MAX_FEED` that the path never approaches (its tool speed
    peaks below half of it): ``--feed 120`` meant in mm/s ran at a few cm/s without a word."""
    if feed_si > MAX_FEED and not peak_si >= 0.5 * feed_si:
        scale = length_scale(units)
        raise InputError(f"--feed {feed_si / scale:g} {units}/s is never reached: the tool peaks "
                         f"at {peak_si / scale:.4g} {units}/s on this path (accelerations, "
                         f"curvature), and no machining feed exceeds {MAX_FEED / scale:g} "
                         f"{units}/s{_hint(feed_si, MAX_FEED, units)}")
