"""A full-pose machine's batched inverse record whose assembly mode is computed when read.

The mode of a configuration is the sign of det A of its velocity model (A ẋ = B q̇), one 6×6
matrix per row: about a tenth of a hexapod workspace study's CPU when computed with every
inverse, though the study takes the mode from the velocity model it evaluates anyway
(``in_working_mode``). A batch's record therefore computes ``mode`` at its first read, from
copies of the poses and coordinates it was made with; one pose's record has it at once."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from pkmkit.machines.lazy_records import lazy_record_class
from pkmkit.machines.results import InverseResult


def assembly_modes(forms: Any, n_rods: int, x: np.ndarray, q: np.ndarray) -> np.ndarray:
    """``(N,)`` int: the sign of det A at pose rows ``x (N, 6)`` with actuator coordinates
    ``q (N, n)`` (``forms``: the machine's :class:`~pkmkit.machines.full_pose_forms.FullPoseForms`);
    0 where a row has no configuration (non-finite ``x`` or ``q``) or the machine has not six
    rods (no square A)."""
    ok = np.isfinite(q).all(axis=1) & np.isfinite(x).all(axis=1)
    out = np.zeros(x.shape[0], dtype=int)
    if ok.any() and n_rods == 6:
        a, _ = forms.jacobians(x[ok], q[ok])
        out[ok] = np.sign(np.linalg.det(a)).astype(int)
    return out


class _ModeEvaluation:
    """The fields a lazy inverse record may not be given: ``mode`` and, when not given,
    ``shortfall`` (per rod, :meth:`~pkmkit.machines.full_pose_forms.FullPoseForms.shortfall`
    of the poses: a NumPy pass over every row costing ≈ 20× the fused inverse kernel, that
    ``pkmkit ik --input`` never reads; issue 22 §5)."""

    def __init__(self, forms: Any, n_rods: int, x: np.ndarray, q: np.ndarray,
                 finite_only: bool = False) -> None:
        # copies: the caller may change its poses, or the record's q, before the first read
        self._forms, self._n_rods, self._finite_only = forms, n_rods, finite_only
        self._x, self._q = np.array(x, dtype=float), np.array(q, dtype=float)

    def field(self, name: str) -> Any:
        if name == "shortfall":
            if not self._finite_only:
                return self._forms.shortfall(self._x)
            ok = np.isfinite(self._x).all(axis=1)
            out = np.full((self._x.shape[0], self._n_rods), np.nan)
            out[ok] = self._forms.shortfall(self._x[ok])
            return out
        if name != "mode":
            raise AttributeError(name)
        return assembly_modes(self._forms, self._n_rods, self._x, self._q)


#: The batch record whose ``mode`` is computed when first read.
LazyInverseResult = lazy_record_class(
    InverseResult, "Lazy",
    lambda r: f"{len(r.q)} poses, {r.q.shape[1]} actuators; the assembly mode computed when read",
    "A full-pose machine's batched inverse record, its assembly mode computed when read "
    "(module doc).")


def lazy_inverse_record(forms: Any, n_rods: int, x: np.ndarray, finite_only: bool = False,
                        **fields: Any) -> Any:
    """The batch inverse record of pose rows ``x (N, 6)`` with the given ``fields`` (every
    field of :class:`~pkmkit.machines.results.InverseResult` but ``mode``, which is computed
    from ``x`` and ``fields["q"]`` when read, and optionally ``shortfall``, computed from
    ``x`` when read: NaN on the rows of ``x`` that are not finite if ``finite_only``)."""
    defaults = {f.name: f.default for f in dataclasses.fields(InverseResult)
                if f.default is not dataclasses.MISSING and f.name != "shortfall"}
    return LazyInverseResult(_ModeEvaluation(forms, n_rods, x, fields["q"], finite_only),
                             **{**defaults, **fields})
