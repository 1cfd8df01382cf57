"""Batch plumbing shared by the kinematics commands: the single-or-batch options, output
columns."""

from __future__ import annotations

import click
import numpy as np

from .batch import status_names


def named(names, values: np.ndarray) -> dict[str, np.ndarray]:
    """Columns ``names`` of a ``(N, k)`` array."""
    return {name: values[:, j] for j, name in enumerate(names)}


def status_column(status: np.ndarray):
    """The ``status`` column: one label per row."""
    from pkmkit.io.table import Labels

    return Labels(np.asarray(status), status_names())


def mode_column(m, sign: np.ndarray):
    """Assembly-mode names of det A signs (empty where 0: no configuration)."""
    from pkmkit.io.table import Labels

    sign = np.nan_to_num(np.asarray(sign, dtype=float))
    codes = np.where(sign < 0, 1, np.where(sign > 0, 2, 0))
    return Labels(codes, ["", m.mode_label(-1), m.mode_label(1)])


def require_batch_pair(single: str | None, input_: str | None, output: str | None,
                       flag: str) -> None:
    """``flag`` (one configuration) or ``--input TABLE --output TABLE``, not both.

    Raises:
        click.UsageError: neither, both, or one of ``--input``/``--output`` alone.
    """
    if input_ is None and single is None:
        raise click.UsageError(f"give {flag} or --input TABLE --output TABLE")
    if input_ is not None and single is not None:
        raise click.UsageError(f"{flag} and --input are exclusive")
    if input_ is not None and output is None:
        raise click.UsageError("--input needs --output TABLE (- for standard output)")
    if input_ is None and output is not None:
        raise click.UsageError("--output goes with --input TABLE")
