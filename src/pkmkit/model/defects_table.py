"""The ``[defects]`` table of a machine file: geometric defects applied to the machine the rest
of the file describes (a calibrated machine, or a simulated "true" one).

::

    [machine]
    kind = "tripteor"
    units = "mm"
    [parameters]
    ...
    [defects]          # name = value; lengths in the file's units, direction components
    da13 = 0.012       # dimensionless (≈ rad), angles (spins, crank offsets) in degrees
    dJ62 = -0.0004

Names are the machine's defect names (``pkmkit.geometric_errors.model.defect_set``: ``dA1x``,
``dL3``,
``dq2`` for rod machines; ``dI21``, ``da13``, ``dS62`` for joint chains). The defects are applied
exactly (:mod:`pkmkit.model.rod_defects`, :meth:`pkmkit.model.chains.JointChainModel.
with_defects`) after any parameter override; a rod machine of a built-in kind keeps its id but no
longer has named parameters (its geometry is no longer the kind's).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from typing import Any

import numpy as np

from pkmkit.exceptions import ParameterError
from pkmkit.model.parameters import is_plain_number


def defect_index(machine):
    """The defect index of ``machine``: names, units (``"m"``, ``"1"``, ``"rad"``)."""
    from pkmkit.model.defect_rule import defect_index as index

    return index(machine)


def defects_from_table(machine, table: Mapping[str, Any], scale: float) -> np.ndarray:
    """The SI defect vector of a ``[defects]`` table (values in file units: lengths × scale,
    ``rad`` defects in degrees).

    Raises:
        ParameterError: an unknown name (``parameter`` = the name) or a value that is not a
            finite number.
    """
    index = defect_index(machine)
    delta = np.zeros(len(index.names))
    for name, value in table.items():
        if name not in index.names:
            preview = ", ".join(index.names[:12]) + (", …" if len(index.names) > 12 else "")
            raise ParameterError(f"unknown defect {name!r} for this machine; its defects are "
                                 f"named like {preview}", name)
        try:  # an integer too large for a float (a TOML literal of 400 digits) is not finite
            finite = is_plain_number(value) and np.ndim(value) == 0 and np.isfinite(float(value))
        except OverflowError:
            finite = False
        if not finite:
            raise ParameterError(f"defect {name!r} must be a finite number, got {value!r}", name)
        unit = index.units[index.names.index(name)]
        factor = scale if unit == "m" else (np.pi / 180.0 if unit == "rad" else 1.0)
        delta[index.names.index(name)] = float(value) * factor
    return delta


def table_from_defects(machine, delta: np.ndarray, scale: float, *, digits: int = 10
                       ) -> dict[str, float]:
    """The inverse of :func:`defects_from_table`: non-zero defects in file units."""
    index = defect_index(machine)
    out = {}
    for name, unit, value in zip(index.names, index.units, delta, strict=True):
        if value == 0.0:
            continue
        factor = scale if unit == "m" else (np.pi / 180.0 if unit == "rad" else 1.0)
        out[name] = float(f"{value / factor:.{digits}g}")
    return out


def apply_defect_vector(machine, delta: np.ndarray):
    """Deprecated: ``machine.with_defects(delta)`` (:func:`pkmkit.model.defect_rule.
    with_defects`, which **replaces** the machine's defects; it used to add them on joint
    chains). For defects on top of the machine's own use
    :func:`pkmkit.model.defect_rule.add_defects`."""
    warnings.warn("apply_defect_vector is deprecated: use machine.with_defects(delta) (replaces "
                  "the machine's defects) or pkmkit.model.defect_rule.add_defects (adds to "
                  "them)", DeprecationWarning, stacklevel=2)
    from pkmkit.model.defect_rule import with_defects

    return with_defects(machine, delta)
