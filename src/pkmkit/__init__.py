"""pkmkit — parallel kinematic machine tools: models, kinematics, Jacobians, batched solvers.

Quick start:

>>> import pkmkit
>>> m = pkmkit.machine("linear-delta")          # seed 000, (R, r, L) = (0.7, 0.15, 1.3) m
>>> q = m.ik([0.25, 0.25, 0.0])                 # actuator coordinates, m
>>> [round(v, 6) for v in q.tolist()]
[1.23996, 1.167543, 0.941723]
>>> x = m.fk(q)                                 # working assembly mode
>>> [round(v, 9) + 0.0 for v in x.tolist()]
[0.25, 0.25, 0.0]
>>> m.fk_all(q).labels                          # every real assembly mode, labelled
('nacelle-below', 'nacelle-above')
>>> jac = m.jacobian([0.0, 0.0, 0.0])           # A, B, J, singular values, condition, status
>>> jac.status, round(float(jac.condition), 4)
('regular', 3.0288)
>>> res = m.ik([[0.25, 0.25, 0.0], [2.0, 0.0, 0.0]], full_output=True)  # a batch never raises
>>> [pkmkit.Status(s).label for s in res.status]
['ok', 'unreachable']

SI units everywhere in the Python API (m, rad).
"""

import sys
import types
from typing import TYPE_CHECKING

from pkmkit.exceptions import (
    ConvergenceError,
    InputError,
    MachineFileError,
    NoAssemblyError,
    ParameterError,
    PkmError,
    SingularConfigurationError,
    UnknownMachineError,
    UnknownParameterError,
    UnreachablePoseError,
)
from pkmkit.status import Status

if TYPE_CHECKING:  # what the names below resolve to, for type checkers and editors
    from pkmkit.machines import Machine, Singularity, load, machine, machines

__version__ = "0.1.0"

#: Names served by :mod:`pkmkit.machines`, imported on first use: ``import pkmkit`` (and so
#: ``pkmkit --help``) loads neither NumPy nor the machine library (issue 22 §5).
_FROM_MACHINES = ("Machine", "Singularity", "load", "machine")


def __getattr__(name: str):
    if name in _FROM_MACHINES:
        from importlib import import_module  # `from pkmkit import machines` is the function

        value = getattr(import_module("pkmkit.machines"), name)
        globals()[name] = value  # later look-ups skip this function
        return value
    raise AttributeError(f"module 'pkmkit' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *_FROM_MACHINES, "machines"})


class _Package(types.ModuleType):
    """``pkmkit.machines`` is the function listing the built-in machines, as it was when this
    package imported it eagerly; the import system's binding of the ``pkmkit.machines``
    sub-package to this attribute, once it is loaded, leaves the function in place."""

    @property
    def machines(self):
        from pkmkit.machines.registry import machines

        return machines

    @machines.setter
    def machines(self, value) -> None:
        pass  # the sub-package itself stays in sys.modules["pkmkit.machines"]


sys.modules[__name__].__class__ = _Package

__all__ = [
    "ConvergenceError",
    "InputError",
    "Machine",
    "MachineFileError",
    "NoAssemblyError",
    "ParameterError",
    "PkmError",
    "SingularConfigurationError",
    "Singularity",
    "Status",
    "UnknownMachineError",
    "UnknownParameterError",
    "UnreachablePoseError",
    "__version__",
    "load",
    "machine",
    "machines",
]
