"""One inverse-kinematics call for every machine family, in SI, for the command line.

:func:`inverse` asks ``machine.ik`` for its full output and returns one result type,
:class:`InverseRows`, whatever the family; :func:`inverse_options` keeps the options a machine's
``ik`` takes and refuses, with a typed error, those it does not. ``pkmkit ik`` (single pose and
batch alike) is written over these two.

The families' ``ik(full_output=True)`` records still differ in what they carry (a joint
chain's :class:`~pkmkit.machines.chain_results.ChainInverseResult` adds its direct model, whose
passive joints the command line shows; its status is judged from q): each machine reads its own
into the shared fields (``machine.inverse_rows``, :mod:`pkmkit.machines.inverse_rows`), so
nothing here looks the family up.
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.exceptions import InputError


@dataclass(frozen=True)
class InverseRows:
    """Inverse kinematics of N poses, the same fields for every family (SI).

    Attributes:
        q: ``(N, n)`` actuator values (m, rad; NaN where there is none).
        status: ``(N,)`` :class:`~pkmkit.status.Status` codes (strokes not judged here).
        mode: ``(N,)`` assembly-mode sign (det A) of each configuration, or None (joint chains).
        branches: ``(n,)`` inverse-model branch of each leg (±1), or None.
        pose: ``(N, 6)`` full poses found from positions (a position-controlled machine given
            positions), else None.
        passive: ``(N, n_p)`` passive joint values (rad, m) of joint chains, else None.
    """

    q: np.ndarray
    status: np.ndarray
    mode: np.ndarray | None = None
    branches: np.ndarray | None = None
    pose: np.ndarray | None = None
    passive: np.ndarray | None = None


def inverse_options(machine, **given: Any) -> dict[str, Any]:
    """The options of ``given`` that were given (not None) and that ``machine.ik`` takes.

    Raises:
        InputError: an option was given that ``machine.ik`` does not take (named with the
            machine and its family).
    """
    accepted = inspect.signature(machine.ik).parameters
    out = {}
    for name, value in given.items():
        if value is None:
            continue
        if name not in accepted:
            raise InputError(f"the inverse model of {machine.id!r} ({machine.family} machine) "
                             f"takes no {name.replace('_', ' ')}")
        out[name] = value
    return out


def inverse(machine, x: Any, *, out: np.ndarray | None = None, mode: bool = True,
            **options: Any) -> InverseRows:
    """``machine.ik(x, full_output=True, strokes="ignore", **options)`` as :class:`InverseRows`
    (rows ``(N, …)`` also for one pose ``x (dims,)``, whose errors — unreachable, no
    convergence — are raised as ``ik`` raises them), read by the machine's own
    ``inverse_rows`` (:mod:`pkmkit.machines.inverse_rows`). ``out``: a batch's ``(N, n)``
    array q is written into (``ik``'s ``out``, :mod:`pkmkit.machines.out_arrays`), e.g. one
    reused from chunk to chunk. ``mode=False``: the assembly modes are not read (``mode`` is
    None), for a caller that does not show them — a full-pose machine's record computes them
    when read, one 6×6 Jacobian and determinant per row, about 25× its inverse kernel's cost
    (issue 22 §5: half the CPU of ``pkmkit ik gough-stewart --input``)."""
    if out is not None:
        options["out"] = out
    found = machine.ik(x, full_output=True, strokes="ignore", **options)
    return InverseRows(**machine.inverse_rows(found, mode=mode))
