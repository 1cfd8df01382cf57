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
from pkmkit.machines import Machine, Singularity, load, machine, machines
from pkmkit.status import Status

__version__ = "0.1.0"

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
