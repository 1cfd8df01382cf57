"""Stiffness indices over many poses: the figures of stiffness maps, workspace criteria and
design metrics, batched.

- ``stiffness``: the smallest translational stiffness ``kt_min`` (N/m) — the smallest
  eigenvalue of ``(C_tt)⁻¹``, what a pure force at the reference point meets in its weakest
  direction (:attr:`~pkmkit.stiffness.results.StiffnessResult.translational`);
- ``deflection``: the norm of the translational deflection ``|C_t· w|`` (m) under a given
  wrench ``w`` at the reference point (forces then moments; a translating platform: forces).

Both come from one batched evaluation of the machine's compliance (:func:`stiffness`); poses
the machine cannot take (unreachable, singular, a mechanism) are NaN.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.status import Status
from pkmkit.stiffness.api import check_data, stiffness, twist_names
from pkmkit.stiffness.compiled import rod_stiffness
from pkmkit.stiffness.data import StiffnessData, default_data
from pkmkit.stiffness.joint_chains import chain_compliance
from pkmkit.stiffness.results import RIGID_TOL
from pkmkit.stiffness.rod_legs import check_rod_data, rod_leg_compliance

#: Names and descriptions of the stiffness indices (map, workspace, design metrics).
STIFFNESS_INDICES = {
    "stiffness": "smallest translational stiffness (N/µm)",
    "deflection": "tool-point deflection under the wrench (µm)",
}
#: Display factor of each index: N/m → N/µm, m → µm.
DISPLAY_FACTOR = {"stiffness": 1e-6, "deflection": 1e6}
DISPLAY_UNIT = {"stiffness": "N/µm", "deflection": "µm"}
#: Poses evaluated per call of :func:`stiffness` (bounds the (N, d, d) temporaries).
CHUNK = 1 << 15


@dataclass(frozen=True)
class StiffnessFigures:
    """Stiffness figures at M poses (NaN where the machine has no stiffness).

    Attributes:
        smallest: ``(M,)`` smallest translational stiffness, N/m.
        deflection: ``(M,)`` norm of the translational deflection under the wrench, m, or None.
        vectors: ``(M, d)`` the deflection twists (m, rad), or None.
    """

    smallest: np.ndarray
    deflection: np.ndarray | None
    vectors: np.ndarray | None


def check_wrench(machine: Any, wrench: Any) -> np.ndarray | None:
    """A wrench as a float array of the machine's twist width (see :func:`twist_names`).

    Raises:
        InputError: a wrench of the wrong width or not finite.
    """
    if wrench is None:
        return None
    d = len(twist_names(machine))
    w = np.asarray(wrench, dtype=float).reshape(-1)
    if w.shape != (d,) or not np.isfinite(w).all():
        raise InputError(f"the wrench must have {d} finite components "
                         f"({', '.join(twist_names(machine))}: forces then moments), got "
                         f"{np.asarray(wrench).tolist()!r}")
    return w


def stiffness_figures(machine: Any, points: Any = None, *, q: Any = None,
                      data: StiffnessData | None = None, wrench: Any = None
                      ) -> StiffnessFigures:
    """Smallest translational stiffness and deflection at many poses, in chunks of
    :data:`CHUNK`.

    Args:
        machine: any pkmkit machine.
        points: ``(M, dims)`` poses (joint-chain machines: tool point and axis), or give ``q``.
        q: ``(M, n)`` actuator coordinates (joint-chain machines; NaN rows are skipped); a
            joint chain given both uses ``q`` (its configuration, no inverse model to solve),
            a rod-leg machine uses ``points``.
        data: the elastic data (default: the machine's).
        wrench: ``(d,)`` load at the reference point (N, N·m) for the deflection, or None.

    Returns:
        :class:`StiffnessFigures`; NaN where a pose is unreachable or singular.
    """
    w = check_wrench(machine, wrench)
    chains = machine.stiffness_from_actuators
    if points is not None and not chains:
        q = None  # rod legs: the compliance is computed at the poses (q follows from them)
    if q is None and points is None:
        raise InputError("stiffness_figures needs poses or actuator coordinates")
    rows = np.atleast_2d(np.asarray(q if q is not None else points, dtype=float))
    m = len(rows)
    d = len(twist_names(machine))
    smallest = np.full(m, np.nan)
    vectors = None if w is None else np.full((m, d), np.nan)
    ok = np.isfinite(rows).all(axis=1)
    index = np.flatnonzero(ok)
    every = index.size == m  # no row to skip: no copies
    fast = None if chains else _compiled(machine, rows if every else rows[index], data)
    if fast is not None:  # the whole batch in one compiled pass (no large temporaries)
        if every:
            smallest = fast.smallest
        else:
            smallest[index] = fast.smallest
        if vectors is not None:
            vectors[index] = np.einsum("nij,j->ni", fast.compliance, w)
        index = index[:0]
    for start in range(0, index.size, CHUNK):
        take = index[start:start + CHUNK]
        if chains and q is None:  # tool poses: through the inverse model of stiffness()
            r = stiffness(machine, rows[take], data=data, wrench=w)
            smallest[take] = r.translational[:, 0]
            if vectors is not None:
                vectors[take] = r.deflection
            continue
        c = _compliance(machine, rows[take], data, chains)
        smallest[take] = _smallest(c, d)
        if vectors is not None:
            vectors[take] = np.einsum("nij,j->ni", c, w)
    deflection = None if vectors is None else np.linalg.norm(vectors[:, :min(d, 3)], axis=1)
    return StiffnessFigures(smallest=smallest, deflection=deflection, vectors=vectors)


def _compiled(machine: Any, rows: np.ndarray, data: StiffnessData | None):
    """The compiled translating-platform result (compliance and smallest stiffness) at
    poses ``rows``, or None where it does not apply (:mod:`pkmkit.stiffness.compiled`)."""
    if not machine.orientation_fixed:
        return None
    data = data or default_data(machine)
    check_data(machine, data)
    check_rod_data(machine, data)
    return rod_stiffness(machine, rows, data)


def _compliance(machine: Any, rows: np.ndarray, data: StiffnessData | None,
                chains: bool) -> np.ndarray:
    """``(k, d, d)`` compliance at poses (rod legs) or actuator coordinates (joint chains),
    NaN where the configuration fails — the compliance of :func:`stiffness` without its
    summary (eigen-decomposition, inverse), which the indices do not need."""
    data = data or default_data(machine)
    check_data(machine, data)
    if chains:
        c, status, _ = chain_compliance(machine, rows, data)
    else:
        c, status, _, _ = rod_leg_compliance(machine, rows, data)
    c = 0.5 * (c + np.swapaxes(c, 1, 2))
    c[(status != Status.OK) | ~np.isfinite(c).all(axis=(1, 2))] = np.nan
    return c


def _smallest(c: np.ndarray, d: int) -> np.ndarray:
    """``(k,)`` smallest translational stiffness 1/λ_max(C_tt) (inf where the translational
    block is rigid, as :func:`~pkmkit.stiffness.results.summarize` judges it; NaN rows stay
    NaN)."""
    out = np.full(len(c), np.nan)
    ok = np.isfinite(c).all(axis=(1, 2))
    if not ok.any():
        return out
    t = min(d, 3)
    lam = np.linalg.eigvalsh(c[ok][:, :t, :t])[:, -1]
    top = lam if d <= 3 else np.abs(np.linalg.eigvalsh(c[ok])[:, -1])
    rigid = lam <= RIGID_TOL * top
    with np.errstate(divide="ignore"):
        out[ok] = np.where(rigid, np.inf, 1.0 / np.where(rigid, 1.0, lam))
    return out


def stiffness_index(machine: Any, points: Any, name: str, *, data: StiffnessData | None = None,
                    wrench: Any = None) -> np.ndarray:
    """``(M,)`` one stiffness index (:data:`STIFFNESS_INDICES`, SI units: N/m or m) at poses
    ``points (M, dims)``.

    Raises:
        InputError: an unknown index, ``deflection`` without a wrench.
    """
    if name not in STIFFNESS_INDICES:
        raise InputError(f"unknown stiffness index {name!r}; valid: "
                         f"{', '.join(STIFFNESS_INDICES)}")
    if name == "deflection" and wrench is None:
        raise InputError("the deflection index needs a wrench (--wrench FX,FY,FZ[,MX,MY,MZ])")
    figures = stiffness_figures(machine, points, data=data,
                                wrench=wrench if name == "deflection" else None)
    return figures.smallest if name == "stiffness" else figures.deflection
