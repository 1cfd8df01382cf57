"""Choosing which defects an analysis works on: by name (exact or shell-style pattern), by kind,
by owner (the joint, rod or actuator a defect belongs to) and by where it sits (in the closed
loops or in the serial head of a joint-chain machine).

Every analysis of :mod:`pkmkit.geometric_errors` (compatibility, identifiability, sensitivity,
tolerances)
takes the same selection arguments and resolves them here, so that an unknown name is reported
the same way everywhere.
"""

from __future__ import annotations

import fnmatch
from collections.abc import Iterable, Sequence

import numpy as np

from pkmkit.exceptions import ParameterError
from pkmkit.geometric_errors.model import defect_set

SCOPES = ("all", "loops", "head")
_WILDCARDS = set("*?[")


def _is_pattern(text: str) -> bool:
    return bool(_WILDCARDS & set(text))


def _as_list(value: str | Iterable[str] | None) -> list[str]:
    if value is None:
        return []
    if isinstance(value, str):
        return [v.strip() for v in value.split(",") if v.strip()]
    return [str(v).strip() for v in value]


def loop_defects(machine) -> np.ndarray:
    """``(d,)`` bool: the defect belongs to a closed loop (every defect of a rod machine; the
    legs' elements of a joint-chain machine, not its head): the machine's
    ``loop_defect_mask`` (:mod:`pkmkit.machines.defect_masks`)."""
    return machine.loop_defect_mask()


def reference_joint_defects(machine) -> np.ndarray:
    """``(d,)`` bool: the defects of the first element of the first leg of a joint-chain machine
    — the joint the thesis aligns the fixed frame with (D_ICS^L11 of the Tripteor, D_R0^L1 of
    the crank–slider) and keeps nominal. All False for a rod machine. The machine's
    ``reference_joint_defect_mask`` (:mod:`pkmkit.machines.defect_masks`)."""
    return machine.reference_joint_defect_mask()


def _match(names: Sequence[str], owners: Sequence[str], token: str, what: str) -> np.ndarray:
    """Defects whose name (or owner) equals / matches ``token``."""
    if _is_pattern(token):
        hit = np.array([fnmatch.fnmatchcase(n, token) or fnmatch.fnmatchcase(o, token)
                        for n, o in zip(names, owners, strict=True)], dtype=bool)
        if not hit.any():
            raise ParameterError(f"{what}: the pattern {token!r} matches no defect of this "
                                 "machine", token)
        return hit
    hit = np.array([n == token or o == token for n, o in zip(names, owners, strict=True)],
                   dtype=bool)
    if not hit.any():
        preview = ", ".join(names[:12]) + (", …" if len(names) > 12 else "")
        owners_preview = ", ".join(dict.fromkeys(owners))
        raise ParameterError(f"{what}: unknown defect or owner {token!r}; defects are named like "
                             f"{preview}; owners: {owners_preview}", token)
    return hit


def select_defects(machine, parameters: str | Iterable[str] | None = None, *,
                   kinds: str | Iterable[str] | None = None,
                   exclude: str | Iterable[str] | None = None,
                   scope: str = "all", reference_nominal: bool = False) -> np.ndarray:
    """Indices ``(p,)`` (in defect-set order) of the selected defects.

    Args:
        machine: any machine.
        parameters: names, owners (``"psi2"``, ``"rod 3"``) or shell patterns (``"dA*"``,
            ``"d?13"``) to keep; a comma-separated string or a sequence. Default: every defect.
        kinds: keep only these kinds (``"orientation"``, ``"position"``, ``"spin"`` for joint
            chains; ``"base"``, ``"platform"``, ``"length"``, ``"axis"``, ``"pivot"``,
            ``"offset"`` for rods).
        exclude: names, owners or patterns to leave out (held at zero).
        scope: ``"all"``, ``"loops"`` (the closed legs only) or ``"head"`` (a joint-chain
            machine's serial head).
        reference_nominal: leave out the defects of the first joint of the first leg (the
            thesis's choice: the fixed frame is aligned with it, D_ICS^L11 stays nominal).

    Raises:
        ParameterError: an unknown name, kind or scope, a pattern matching nothing, or a
            selection left empty.
    """
    ds = defect_set(machine)
    names, owners = ds.names, ds.owners
    keep = np.ones(len(ds), dtype=bool)
    wanted = _as_list(parameters)
    if wanted:
        keep = np.zeros(len(ds), dtype=bool)
        for token in wanted:
            keep |= _match(names, owners, token, "parameters")
    kind_list = _as_list(kinds)
    if kind_list:
        valid = sorted(set(ds.kinds))
        for k in kind_list:
            if k not in valid:
                raise ParameterError(f"unknown defect kind {k!r} for {machine.id!r}; valid "
                                     f"kinds: {', '.join(valid)}", k)
        keep &= np.isin(np.asarray(ds.kinds), kind_list)
    for token in _as_list(exclude):
        keep &= ~_match(names, owners, token, "exclude")
    if scope not in SCOPES:
        raise ParameterError(f"unknown scope {scope!r}; valid scopes: {', '.join(SCOPES)}",
                             "scope")
    if scope == "loops":
        keep &= loop_defects(machine)
    elif scope == "head":
        keep &= ~loop_defects(machine)
    if reference_nominal:
        keep &= ~reference_joint_defects(machine)
    if not keep.any():
        raise ParameterError(f"the defect selection of {machine.id!r} is empty")
    return np.flatnonzero(keep)
