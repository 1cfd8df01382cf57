"""The compiled elastostatics of large batches: when they apply, and the calls around the
kernels of :mod:`pkmkit.stiffness.kernels`.

- translating rod-leg machines with one slide or strut leg per actuator (Orthoglide, linear
  Delta, five-bar): compliance and smallest translational stiffness in one pass;
- full-pose machines with six slide or strut rods, one per actuator (hexapods): compliance and
  stiffness ``(N, 6, 6)``;
- joint chains without link springs whose free unknowns the closure fixes
  (:func:`pkmkit.stiffness.kernels.chain_reduced`; the others go through the SVD path).

Every result equals the NumPy path's (``tests/stiffness/test_compiled.py``, 1e-12 relative,
same status codes). Batches below :data:`pkmkit.numerics.jit.MIN_ROWS` rows, ``PKMKIT_COMPILED=0``
and a missing Numba keep the NumPy paths.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.machines.machine import SINGULARITY_TOL
from pkmkit.model.rods import SLIDE, STRUT
from pkmkit.numerics import jit
from pkmkit.status import Status
from pkmkit.stiffness.data import StiffnessData


@dataclass(frozen=True)
class RodStiffness:
    """Compiled results at N poses (NaN rows where ``status`` is not OK).

    Attributes:
        compliance: ``(N, d, d)`` m/N, rad/(N·m) (None when not asked for). status: ``(N,)``.
        smallest: ``(N,)`` smallest translational stiffness (N/m) of a translating platform,
            else None. stiffness: ``(N, 6, 6)`` of a six-rod platform, else None.
    """

    compliance: np.ndarray | None
    status: np.ndarray
    smallest: np.ndarray | None = None
    stiffness: np.ndarray | None = None


def rod_kernel(machine: Any) -> str | None:
    """``"translational"``, ``"six-rods"`` or None: which compiled kernel covers a rod-leg
    machine (module docstring)."""
    model = machine.model
    if machine.orientation_fixed:
        one_each = model.n_legs == model.dims == machine.n_actuators
        kinds = np.isin(model.leg_kind, (SLIDE, STRUT)).all()
        return "translational" if one_each and kinds else None
    if not machine.six_dof or model.n_rods != 6 or machine.n_actuators != 6:
        return None
    one_each = np.array_equal(np.sort(model.rod_actuator), np.arange(6))
    return "six-rods" if one_each and np.isin(model.rod_kind, (SLIDE, STRUT)).all() else None


def rod_stiffness(machine: Any, x: np.ndarray, data: StiffnessData, *,
                  compliance: bool = True) -> RodStiffness | None:
    """The compliance of a rod-leg machine at poses ``x (N, dims)`` by the compiled kernels,
    or None where they do not apply (a small batch, no Numba, a machine they do not cover).
    The elastic data are checked by the caller (:func:`pkmkit.stiffness.rod_legs.
    rod_leg_compliance`). ``compliance=False``: a six-rod platform's stiffness alone (its
    ``compliance`` is then None)."""
    which = rod_kernel(machine)
    if which is None or x.ndim != 2 or not jit.use_compiled(x.shape[0]):
        return None
    from pkmkit.stiffness import kernels

    x = np.ascontiguousarray(x, dtype=float)
    q = np.ascontiguousarray(machine.ik(x, strokes="ignore"), dtype=float)
    status = np.zeros(len(x), dtype=np.int64)
    bad = ~np.isfinite(q).all(axis=1)
    if bad.any():  # the status codes of the full inverse model, on these rows only
        inv = machine.ik(x[bad], full_output=True, strokes="ignore")
        status[bad] = np.atleast_1d(inv.status)
    model = machine.model
    c_q = 1.0 / data.actuator_stiffness
    limit = 1.0 / SINGULARITY_TOL
    n, d = x.shape
    if which == "translational":
        out_c = np.empty((n, d, d))
        from pkmkit.machines.closed_form import RodClosedForm

        forms = RodClosedForm(model)
        c_r = np.zeros(d)
        if data.rod_section is not None:
            counts = np.bincount(model.rod_leg, minlength=model.n_legs)
            c_r = 1.0 / (data.rod_material.E * data.rod_section.area * counts)
        smallest = np.empty(n)
        strut = np.ascontiguousarray(model.leg_kind == STRUT)
        centre0 = np.ascontiguousarray(forms.centre0)
        axis = np.ascontiguousarray(forms.axis)

        def work(start: int, stop: int) -> None:
            kernels.translational(x[start:stop], q[start:stop], centre0, axis, strut,
                                  model.leg_length, c_q, c_r, limit,
                                  out_c[start:stop], smallest[start:stop],
                                  status[start:stop])

        jit.run_chunks(work, n)
        return RodStiffness(out_c, status, smallest=smallest)
    c_r = np.zeros(6)
    if data.rod_section is not None:
        c_r[:] = 1.0 / (data.rod_material.E * data.rod_section.area)
    stiffness = np.empty((n, 6, 6))
    out_c = np.empty((n if compliance else 0, 6, 6))
    strut = np.ascontiguousarray(model.rod_kind == STRUT)
    actuator = np.ascontiguousarray(model.rod_actuator, dtype=np.int64)
    arrays = [np.ascontiguousarray(a, dtype=float)
              for a in (model.rod_base, model.rod_platform, model.rod_axis, model.rod_length)]

    def work6(start: int, stop: int) -> None:
        kernels.six_rods(x[start:stop], q[start:stop], *arrays[:3], strut, arrays[3], actuator,
                         c_q, c_r, float(machine.characteristic_length), limit,
                         out_c[start:stop] if compliance else out_c, stiffness[start:stop],
                         status[start:stop])

    jit.run_chunks(work6, n)
    return RodStiffness(out_c if compliance else None, status, stiffness=stiffness)


def chain_reduced_compliance(g: np.ndarray, t: np.ndarray, columns: dict, c_s: np.ndarray,
                             status: np.ndarray, rank_tol: float
                             ) -> tuple[np.ndarray, np.ndarray] | None:
    """Tool-point compliance ``(k, 6, 6)`` and the mask of rows solved by
    :func:`pkmkit.stiffness.kernels.chain_reduced` (rows with ``status`` OK whose free unknowns
    the closure fixes), or None when it does not apply (link springs, a small batch, no
    Numba).

    Args:
        g: ``(k, r, nz)`` closure constraints. t: ``(k, 6, nz)`` tool twist.
        columns: column ranges by role (:class:`~pkmkit.stiffness.joint_chains.ChainSystem`).
        c_s: ``(n_a,)`` drive compliances. status: ``(k,)``. rank_tol: the SVD path's.
    """
    links = columns["links"]
    if links.stop > links.start or not jit.use_compiled(g.shape[0]):  # by size alone
        return None
    from pkmkit.stiffness import kernels

    free = np.r_[np.arange(6), np.arange(columns["passive"].start, columns["passive"].stop)]
    springs = np.arange(columns["actuators"].start, columns["actuators"].stop)
    out = np.full((g.shape[0], 6, 6), np.nan)
    done = np.asarray(status == Status.OK)
    done = done.copy()
    # the assembled arrays are batch-last views: one contiguous copy (a strided read per
    # entry would miss the cache on every element)
    kernels.chain_reduced(np.ascontiguousarray(g), np.ascontiguousarray(t), free, springs,
                          np.ascontiguousarray(c_s, dtype=float), rank_tol, out, done)
    return out, done
