"""What every machine class shares: the kind a machine is built from, the thresholds, and the
checks that turn array arguments into batches (typed errors for a bad single row)."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.model.parameters import ParameterSpec
from pkmkit.model.rods import RodModel
from pkmkit.numerics.arrays import as_batch, require_finite, restore_shape

#: Default threshold on the singularity measures (dimensionless).
SINGULARITY_TOL = 1e-6
#: The home configuration must be at least this far from any singularity (same measures).
HOME_TOL = 1e-4
#: Pose or actuator coordinates beyond this magnitude (m) are rejected as invalid input.
MAX_COORDINATE = 1e9
#: A numeric ``dof="full"`` solution whose platform turned by more than this (rad) is another
#: assembly of the rods than the translating platform's modes.
TURNED_TOL = 1e-6


@dataclass(frozen=True)
class MachineKind:
    """A family of machines built from named parameters.

    Attributes:
        kind: identifier (``"linear-delta"``).
        title: one-line human description.
        parameters: declared parameters with defaults.
        build: ``params (SI) -> RodModel``; raises :class:`ParameterError` on inconsistent values.
        reference_poses: ``(params, model) -> {name: pose}``, sample poses for summaries.
        source: where the model comes from (seed, section).
        default_box: ``(params, model) -> (lower (dims,), upper (dims,))``, a sensible region for
            workspace studies (None: around home, see :meth:`Machine.default_box`).
        head_flip: names ``(turn, tilt)`` of a joint-chain head with two branches ``(a, c)`` and
            ``(a ± π, −c)`` (:mod:`pkmkit.machines.head_branches`), or None.
        inverse_start: ``(params, targets (N, 6), tool lengths (N,), branch (N,) ±1 or None)
            -> (N, 6 + n_var)``, a joint chain's closed-form start of the inverse model (NaN
            rows declined; branch None: the head's branch nearest home), or None: the
            first-order start (:func:`pkmkit.machines.chain_starts.inverse_starts`).
        direct_start: ``(params, q (N, n)) -> (N, 6 + n_var)``, a joint chain's closed-form
            start of the direct model (NaN rows declined), or None: home moved to first order
            (:func:`pkmkit.machines.chain_starts.default_start`).
    """

    kind: str
    title: str
    parameters: tuple[ParameterSpec, ...]
    build: Callable[[Mapping[str, Any]], RodModel]
    reference_poses: Callable[[Mapping[str, Any], RodModel], dict[str, np.ndarray]]
    source: str = ""
    default_box: Callable[[Mapping[str, Any], RodModel], tuple[np.ndarray, np.ndarray]] | None = (
        None)
    head_flip: tuple[str, str] | None = None
    inverse_start: Callable[..., np.ndarray] | None = None
    direct_start: Callable[..., np.ndarray] | None = None


def _valid_rows(arr: np.ndarray) -> np.ndarray:
    """Rows ``(N,)`` whose entries are finite and within ±MAX_COORDINATE (column by column: a
    reduction along a short last axis costs several times the comparisons)."""
    with np.errstate(invalid="ignore"):
        if arr.ndim != 2 or not 0 < arr.shape[1] <= 8:
            return (np.abs(arr) <= MAX_COORDINATE).all(axis=1)
        ok = np.abs(arr[:, 0]) <= MAX_COORDINATE
        for j in range(1, arr.shape[1]):
            ok &= np.abs(arr[:, j]) <= MAX_COORDINATE
        return ok


def _checked_batch(value: Any, width: int, name: str) -> tuple[np.ndarray, bool]:
    """:func:`as_batch`, and for a single row: finite, sane magnitudes (typed errors)."""
    arr, single = as_batch(value, width, name)
    if single:
        require_finite(arr, name)
        if not _valid_rows(arr)[0]:
            raise InputError(f"{name} {arr[0].tolist()} has a coordinate beyond "
                             f"{MAX_COORDINATE:g} m")
    return arr, single


def _rows_like(value: Any, width: int, name: str, rows: int) -> np.ndarray:
    """A warm start given for one row or for every row, as ``(rows, width)``."""
    arr, single = as_batch(value, width, name)
    if single:
        return np.tile(arr, (rows, 1))
    if arr.shape[0] != rows:
        raise InputError(f"{name} has {arr.shape[0]} rows but the input has {rows}")
    return arr.copy()


def _restore(result, single: bool, names: tuple[str, ...]):
    values = {k: getattr(result, k) for k in result.__dataclass_fields__}
    for k in names:
        if values[k] is not None:
            values[k] = restore_shape(values[k], single)
    return type(result)(**values)
