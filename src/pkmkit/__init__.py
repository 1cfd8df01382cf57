"""pkmkit — parallel kinematic machine tools: models, kinematics, Jacobians, batched solvers.

Quick start::

    import pkmkit
    m = pkmkit.machine("linear-delta")          # seed 000, (R, r, L) = (0.7, 0.15, 1.3) m
    q = m.ik([0.25, 0.25, 0.0])                 # -> [1.2400, 1.1675, 0.9417] m
    x = m.fk(q)                                 # working assembly mode
    modes = m.fk_all(q)                         # every real assembly mode, labelled
    jac = m.jacobian([0.0, 0.0, 0.0])           # A, B, J, singular values, condition, status

SI units everywhere in the Python API (m, rad).
"""

from pkmkit.errors import (
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
