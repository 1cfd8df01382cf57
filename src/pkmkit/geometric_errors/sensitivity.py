"""Sensitivity analysis in the spirit of Chanal et al. 2012 (seed 002, Fig. 2.4): for each defect,
the largest tool displacement over a region of the workspace for a given defect size.

For each configuration of the region and each defect δ_j of size s_j, the first-order tool
displacement is ``s_j ∂p/∂δ_j`` (:func:`pkmkit.geometric_errors.model.tool_sensitivity`, through the
closure). The table keeps, per defect, the largest |dx|, |dy|, |dz|, the largest displacement
norm and where it occurs, and the largest rotation of the tool frame. With ``exact=True`` the
largest displacement is also computed on the exact model (the machine with that one defect of
that size, its direct model at the same actuator coordinates): the two agree to second order
in the size, a check of the first-order model.

Default sizes: 10 µm for lengths and, for angle-like defects (direction components, rad), the
same 10 µm over the machine's characteristic length L, so both kinds are compared at the same
order of displacement at the tool.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.geometric_errors.blas_threads import single_blas
from pkmkit.geometric_errors.configurations import sample_configurations
from pkmkit.geometric_errors.identifiability import ANGLE_UNITS, characteristic_length
from pkmkit.geometric_errors.model import defect_set, tool_sensitivity, with_defects
from pkmkit.geometric_errors.selection import select_defects
from pkmkit.numerics.magnitudes import MAX_CONFIGURATIONS, check_count

#: Default length defect size (m).
LENGTH_SIZE = 1e-5
#: Most (configuration, defect) pairs of one analysis: each holds a 6-vector of the tool
#: sensitivity (and its rotation part), 2e7 of them ≈ 1 GB.
MAX_SENSITIVITY_ENTRIES = 20_000_000


@dataclass(frozen=True)
class SensitivityTable:
    """Largest tool displacement per defect over a region.

    Attributes:
        names, units, kinds, owners: ``(p,)`` the defects.
        size: ``(p,)`` defect size used (SI).
        max_components: ``(p, 3)`` largest |dx|, |dy|, |dz| of the tool point (m).
        max_displacement: ``(p,)`` largest displacement norm (m).
        max_rotation: ``(p,)`` largest tool-frame rotation (rad).
        where: ``(p, k)`` region point of the largest displacement.
        exact_max: ``(p,)`` the same from the exact model, or None.
        points: ``(N, k)`` region points; q: ``(N, n)`` configurations; point_names: names of
            the region coordinates.
    """

    names: tuple[str, ...]
    units: tuple[str, ...]
    kinds: tuple[str, ...]
    owners: tuple[str, ...]
    size: np.ndarray
    max_components: np.ndarray
    max_displacement: np.ndarray
    max_rotation: np.ndarray
    where: np.ndarray
    exact_max: np.ndarray | None
    points: np.ndarray = field(repr=False)
    q: np.ndarray = field(repr=False)
    point_names: tuple[str, ...] = ()

    def order(self) -> np.ndarray:
        """Indices from the most to the least influential defect."""
        return np.argsort(-self.max_displacement, kind="stable")

    def rows(self) -> list[dict[str, Any]]:
        """One dict per defect, most influential first (SI units)."""
        out = []
        for i in self.order():
            row = {"name": self.names[i], "unit": self.units[i], "kind": self.kinds[i],
                   "owner": self.owners[i], "size": float(self.size[i]),
                   "max_dx": float(self.max_components[i, 0]),
                   "max_dy": float(self.max_components[i, 1]),
                   "max_dz": float(self.max_components[i, 2]),
                   "max_displacement": float(self.max_displacement[i]),
                   "max_rotation": float(self.max_rotation[i]),
                   "where": dict(zip(self.point_names, self.where[i].tolist(), strict=False))}
            if self.exact_max is not None:
                row["exact_max_displacement"] = float(self.exact_max[i])
            out.append(row)
        return out


@single_blas
def sensitivity_analysis(machine, *, region: Any = None, n_points: int = 200,
                         q: Any = None, length_size: float = LENGTH_SIZE,
                         angle_size: float | None = None, parameters: Any = None,
                         kinds: Any = None, exclude: Any = None, scope: str = "all",
                         exact: bool = False, tool_length: Any = None,
                         seed: int | None = 0) -> SensitivityTable:
    """Largest tool displacement per defect over a region (module docstring).

    Args:
        region: ``(lower, upper)`` in region coordinates
        (:mod:`pkmkit.geometric_errors.configurations`);
            default the machine's default region.
        n_points: configurations drawn in the region (Halton points), unless ``q`` is given.
        q: ``(N, n)`` configurations instead of a region.
        length_size: size of length defects (m, > 0).
        angle_size: size of angle-like defects; default ``length_size / L``.
        parameters, kinds, exclude, scope: defect selection.
        exact: also compute the largest displacement on the exact model.
        tool_length: joint-chain machines: tool length (m).

    Raises:
        InputError: non-positive sizes, a bad region; ``n_points`` (or the rows of ``q``)
            not a whole number in [1, :data:`~pkmkit.numerics.magnitudes.MAX_CONFIGURATIONS`]
            or configurations × defects beyond :data:`MAX_SENSITIVITY_ENTRIES`, refused
            before any work.
    """
    if not (np.isfinite(length_size) and length_size > 0):
        raise InputError(f"length_size must be > 0, got {length_size}")
    big_l = characteristic_length(machine)
    if angle_size is None:
        angle_size = length_size / big_l
    if not (np.isfinite(angle_size) and angle_size > 0):
        raise InputError(f"angle_size must be > 0, got {angle_size}")
    defects = len(defect_set(machine))
    if q is None:
        n = check_count(n_points, "n_points", MAX_CONFIGURATIONS,
                        lower="lower n_points or give the configurations (q)")
    else:
        q = np.asarray(q, dtype=float)
        n = check_count(q.size // max(machine.n_actuators, 1) if q.ndim else 1,
                        "the number of configurations (rows of q)", MAX_CONFIGURATIONS)
    check_count(n * defects, "configurations × defects", MAX_SENSITIVITY_ENTRIES,
                lower=f"lower n_points: {defects} defects, {n} configurations")
    if q is None:
        conf = sample_configurations(machine, n, region=region, seed=seed,
                                     method="halton")
        qb, points, point_names = conf.q, conf.points, conf.names
    else:
        qb = np.atleast_2d(np.asarray(q, dtype=float))
        points, point_names = qb, tuple(machine.actuator_names)
    ds = defect_set(machine)
    columns = select_defects(machine, parameters, kinds=kinds, exclude=exclude, scope=scope)
    size = np.array([angle_size if ds.units[i] in ANGLE_UNITS else length_size
                     for i in columns])
    sens = tool_sensitivity(machine, qb, tool_length=tool_length)
    disp = sens.point[:, :, columns] * size  # (N, 3, p)
    rot = np.linalg.norm(sens.rotation[:, :, columns], axis=1) * size
    norm = np.linalg.norm(disp, axis=1)  # (N, p)
    arg = np.argmax(norm, axis=0)
    exact_max = None
    if exact:
        exact_max = _exact_max(machine, qb, columns, size, tool_length)
    return SensitivityTable(
        names=tuple(ds.names[i] for i in columns), units=tuple(ds.units[i] for i in columns),
        kinds=tuple(ds.kinds[i] for i in columns), owners=tuple(ds.owners[i] for i in columns),
        size=size, max_components=np.abs(disp).max(axis=0).T, max_displacement=norm.max(axis=0),
        max_rotation=rot.max(axis=0), where=points[arg], exact_max=exact_max, points=points,
        q=qb, point_names=point_names)


def _tool_points(machine, q: np.ndarray, tool_length: Any) -> np.ndarray:
    from pkmkit.geometric_errors.measurements import measure

    setup = {} if tool_length is None else {"tool_length": tool_length}
    return measure(machine, "point", q, setup)


def _exact_max(machine, q: np.ndarray, columns: np.ndarray, size: np.ndarray,
               tool_length: Any) -> np.ndarray:
    nominal = _tool_points(machine, q, tool_length)
    ds = defect_set(machine)
    out = np.empty(len(columns))
    for k, (i, s) in enumerate(zip(columns, size, strict=True)):
        moved = _tool_points(with_defects(machine, {ds.names[i]: float(s)}), q, tool_length)
        out[k] = float(np.nanmax(np.linalg.norm(moved - nominal, axis=1)))
    return out
