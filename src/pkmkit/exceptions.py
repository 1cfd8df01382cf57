"""Typed errors raised by pkmkit.

Every error pkmkit raises on bad input derives from :class:`PkmError`, so callers (and the CLI)
can catch one type. Each subclass carries the structured facts a caller may want to inspect
(which leg, which pose, which file line) besides a human-readable message that states what is
wrong and where.
"""

from __future__ import annotations

from collections.abc import Iterable


class PkmError(Exception):
    """Base class of every error pkmkit raises on purpose."""


class InputError(PkmError, ValueError):
    """An array argument has the wrong shape, dtype or non-finite values."""


class UnknownMachineError(PkmError, KeyError):
    """A machine id is not in the library."""

    def __init__(self, name: str, valid: Iterable[str]):
        self.name = name
        self.valid = sorted(valid)
        super().__init__(f"unknown machine {name!r}; valid ids: {', '.join(self.valid)}")

    def __str__(self) -> str:  # KeyError would quote the whole message otherwise
        return self.args[0]


class ParameterError(PkmError, ValueError):
    """A machine parameter is unknown, mis-shaped or outside its admissible domain.

    Attributes:
        parameter: the parameter's name (or dotted path in a machine file, e.g. ``legs.2.axis``)
            when the error concerns one parameter, else ``None``.
    """

    def __init__(self, message: str, parameter: str | None = None):
        self.parameter = parameter
        super().__init__(message)


class UnknownParameterError(ParameterError):
    """A parameter name does not belong to the machine."""

    def __init__(self, name: str, machine: str, valid: Iterable[str]):
        self.name = name
        self.valid = sorted(valid)
        super().__init__(
            f"unknown parameter {name!r} for machine {machine!r}; "
            f"valid parameters: {', '.join(self.valid)}",
            parameter=name,
        )


class MachineFileError(PkmError, ValueError):
    """A machine file cannot be read, parsed or validated.

    Attributes:
        path: the file.
        line: 1-based line of the offending entry when it is known, else ``None``.
    """

    def __init__(self, path: str, message: str, line: int | None = None):
        self.path = str(path)
        self.line = line
        where = f"{self.path}:{line}" if line is not None else self.path
        super().__init__(f"{where}: {message}")


class UnreachablePoseError(PkmError, ValueError):
    """A pose cannot be reached: a leg cannot close (inverse model).

    Attributes:
        leg: 0-based index of the first leg that cannot close.
        leg_name: its name.
        shortfall: by how much the leg is too short (or too long), in metres (> 0).
        too_long: the leg's rod is too long rather than too short (a crank arm whose tip circle
            passes too close to the platform joint).

    ``detail`` replaces the default explanation (e.g. a full pose whose orientation a machine
    with fewer than six actuators cannot take).
    """

    def __init__(self, leg: int, leg_name: str, shortfall: float, pose_index: int | None = None,
                 *, too_long: bool = False, detail: str | None = None):
        self.leg = leg
        self.leg_name = leg_name
        self.shortfall = float(shortfall)
        self.pose_index = pose_index
        self.too_long = too_long
        where = f"pose {pose_index}: " if pose_index is not None else ""
        how = "too long" if too_long else "too short"
        super().__init__(
            f"{where}pose unreachable: " + (detail if detail is not None else
                                            f"{leg_name} (leg index {leg}) is {how} by "
                                            f"{self.shortfall:.6g} m to reach it")
        )


class NoAssemblyError(PkmError, ValueError):
    """Actuator coordinates admit no real assembly (direct model), or not the requested mode."""

    def __init__(self, message: str, pose_index: int | None = None):
        self.pose_index = pose_index
        where = f"pose {pose_index}: " if pose_index is not None else ""
        super().__init__(f"{where}{message}")


class SingularConfigurationError(PkmError, ValueError):
    """The requested quantity does not exist at a singular configuration."""


class ConvergenceError(PkmError, RuntimeError):
    """The least-squares engine did not converge for a single (non-batched) call."""


class IdentificationDivergedError(ConvergenceError):
    """A calibration's identification did not converge.

    Attributes:
        result: what is known without it — a calibration result of the nominal machine with its
            set-up fitted alone, nothing identified, ``converged`` False
            (:class:`pkmkit.calibration.results.CalibrationResult`) — from which the judged
            call (:func:`pkmkit.calibration.calibrate`) still gives a verdict; or None.
    """

    def __init__(self, message: str, result=None):
        self.result = result
        super().__init__(message)


class OutOfStrokeError(PkmError, ValueError):
    """A joint value lies outside its stroke (joint-chain machines).

    Attributes:
        joint: the joint's name; value: its value; stroke: ``(min, max)`` (SI units, rad or m);
        pose_index: the row, when the value came from a batch.
    """

    def __init__(self, message: str, joint: str, value: float, stroke: tuple[float, float],
                 pose_index: int | None = None):
        self.joint = joint
        self.value = float(value)
        self.stroke = (float(stroke[0]), float(stroke[1]))
        self.pose_index = pose_index
        where = f"pose {pose_index}: " if pose_index is not None else ""
        super().__init__(f"{where}{message}")


class ClosureMissError(NoAssemblyError):
    """The legs of a joint-chain machine do not close on a common platform pose.

    Attributes:
        leg: 0-based index of the leg that misses the platform most; leg_name: its name.
        translation: by how much it misses it at the least-squares point (m).
        rotation: by which angle (rad).
        residual: the largest closure residual (m; rotation rows × the characteristic length).
    """

    def __init__(self, message: str, leg: int, leg_name: str, translation: float,
                 rotation: float, residual: float, pose_index: int | None = None):
        self.leg = leg
        self.leg_name = leg_name
        self.translation = float(translation)
        self.rotation = float(rotation)
        self.residual = float(residual)
        super().__init__(message, pose_index)


class StrokeWarning(UserWarning):
    """A single direct or inverse model computed a configuration beyond a joint's stroke."""
class MeasurementError(InputError):
    """A measurement type the machine cannot provide (or a setup it needs is missing).

    Attributes:
        kind: the measurement type asked for.
    """

    def __init__(self, message: str, kind: str | None = None):
        self.kind = kind
        super().__init__(message)


class IdentifiabilityError(PkmError, ValueError):
    """An identification problem that cannot be posed: fewer scalar measurements than
    parameters, or (when full rank is required) a rank-deficient identification Jacobian.

    Attributes:
        rank: numerical rank found. n_parameters: parameters asked for. n_measurements: scalar
            measurements (rows) available.
    """

    def __init__(self, message: str, *, rank: int, n_parameters: int, n_measurements: int):
        self.rank = rank
        self.n_parameters = n_parameters
        self.n_measurements = n_measurements
        super().__init__(message)


class ToleranceFileError(MachineFileError):
    """A tolerance file cannot be read or holds a bad entry (path and line in the message)."""


class UnsupportedExportError(PkmError, ValueError):
    """A machine that a format cannot express (or that pkmkit does not export to it yet).

    Attributes:
        format: the format (``"linuxcnc"``, ``"klipper"``, ``"mjcf"``).
        machine: the machine's id.
        reason: why, in words a user can act on.
    """

    def __init__(self, fmt: str, machine: str, reason: str):
        self.format = fmt
        self.machine = machine
        self.reason = reason
        super().__init__(f"cannot export {machine!r} to {fmt}: {reason}")


class ExportCheckError(PkmError, RuntimeError):
    """A written export that does not reproduce pkmkit's model (a bug, never a user error): the
    command that made it writes nothing."""


class UnsupportedOperationError(InputError):
    """An operation of the machine protocol that a machine (family) does not provide, with the
    reason (e.g. the direct model's every assembly mode of a joint-chain machine, or the inverse
    dynamics of a full-pose platform). A subclass of :class:`InputError`: the call cannot be
    served for this machine whatever its arguments.

    Attributes:
        operation: what was asked (``"fk_all"``, ``"jacobian_dot"``, ``"inverse dynamics"``).
        machine: the machine's id. family: its family. reason: why, in words a user can act on.
    """

    def __init__(self, operation: str, machine: str, family: str, reason: str):
        self.operation = operation
        self.machine = machine
        self.family = family
        self.reason = reason
        super().__init__(f"{operation} is not available for {machine!r} (a {family} machine): "
                         f"{reason}")
