"""Gravity deflection in the error budget: the tool target's deflection under the weight of a
(calibrated) machine's moving parts, targets aimed so that the *loaded* tool point reaches them
(``pkmkit compensate --gravity``), and the deflection predicted at measured configurations
beside a calibration's residual (the calibration report).

Deflection models (linear, quasi-static; :mod:`pkmkit.stiffness`), with *illustrative* masses —
no source gives the masses, and every figure says so:

- joint-chain machines: the virtual-joint model under the weights of
  :func:`pkmkit.stiffness.chain_gravity.illustrative_masses`;
- translating rod-leg machines on slides: :func:`pkmkit.stiffness.loads.load_deflection` under
  :func:`pkmkit.dynamics.defaults.default_masses`;
- full-pose rod machines (hexapods, Verne-type module): the platform's weight at its centre of
  mass and its rods' and struts' shares, :mod:`pkmkit.stiffness.platform_gravity`, under
  :func:`pkmkit.stiffness.platform_gravity.platform_masses`, at the tool tip;
- other machines (cranks): :class:`~pkmkit.exceptions.InputError`.

Aiming. Commanded ``q``, the machine's loaded tool point is ``x(q) + δ(q)``. For a target X,
the aimed target ``X_g = X − δ(q_X)`` (``q_X`` the inverse model of X; a tool axis a turns by
``−δθ × a``) gives ``x(q_g) + δ(q_g) = X + δ(q_g) − δ(q_X)``: the error left is the change of the
deflection over the deflection itself, second order (10 µm of sag varying by 10 µm over 0.1 m
leaves 1 nm). The compensation of :mod:`pkmkit.calibration.compensation` then makes the nominal
controller command ``q_g``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.calibration.controller import as_targets, commanded_q
from pkmkit.exceptions import PkmError
from pkmkit.machines.protocol import require_translational


@dataclass(frozen=True)
class GravityDeflection:
    """The tool's small displacement under gravity at N configurations.

    Attributes:
        deflection: ``(N, 6)`` tool point displacement (m) then rotation (rad), base axes; NaN
            rows where the configuration does not assemble or is singular.
        note: where the masses come from (illustrative values: say so beside every figure).
    """

    deflection: np.ndarray
    note: str


def gravity_deflection(machine: Any, q: Any, *, tool_length: float | None = None,
                       masses_of: Any = None
                       ) -> GravityDeflection:
    """Tool deflection of ``machine`` under its own weight at actuator values ``q (N, n)``
    (module docstring for the models and masses). ``masses_of``: the machine whose illustrative
    masses apply (the nominal built-in of a calibrated machine file, which has no kind of its
    own; default ``machine``).

    Raises:
        InputError: as the models (cranks: no weight model).
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    if machine.stiffness_from_actuators:
        from pkmkit.stiffness.chain_gravity import chain_gravity_deflection, illustrative_masses

        masses = illustrative_masses(machine)
        defl, _ = chain_gravity_deflection(machine, q, masses, tool_length=tool_length)
        return GravityDeflection(defl, masses.note)
    if not machine.orientation_fixed:
        return _platform_gravity(machine, q, tool_length, masses_of or machine)
    require_translational(machine, "gravity deflection",
                          "its platform neither translates nor is a full-pose rod platform")
    from pkmkit.dynamics.defaults import default_masses
    from pkmkit.stiffness.loads import load_deflection

    masses = default_masses(masses_of or machine)
    out = np.full((len(q), 6), np.nan)
    ok = np.isfinite(q).all(axis=1)
    if ok.any():
        poses = np.atleast_2d(machine.fk(q[ok], strokes="ignore"))
        good = np.isfinite(poses).all(axis=1)
        rows = np.flatnonzero(ok)[good]
        out[rows, :machine.dims] = load_deflection(machine, poses[good], masses).gravity
        out[rows, machine.dims:] = 0.0
    note = ("illustrative masses of pkmkit.dynamics.defaults (no source gives them): carriages "
            f"{float(np.max(masses.carriage_mass)):g} kg, platform {masses.platform_mass:g} kg")
    return GravityDeflection(out, note)


def _platform_gravity(machine: Any, q: np.ndarray, tool_length: float | None,
                      masses_of: Any) -> GravityDeflection:
    """A full-pose rod machine: :mod:`pkmkit.stiffness.platform_gravity` at the tool tip
    ``tool_length`` below the platform frame's origin."""
    from pkmkit.stiffness.platform_gravity import platform_gravity_deflection, platform_masses

    masses = platform_masses(masses_of)
    out = np.full((len(q), 6), np.nan)
    ok = np.isfinite(q).all(axis=1)
    if ok.any():
        poses = np.atleast_2d(machine.fk(q[ok], strokes="ignore"))
        good = np.isfinite(poses).all(axis=1)
        rows = np.flatnonzero(ok)[good]
        tip = [0.0, 0.0, -(tool_length or 0.0)]
        out[rows] = platform_gravity_deflection(machine, poses[good], masses, point=tip)[0]
    rods = masses.rod_mass + masses.strut_parts(machine.model.n_rods)[0]
    slides = bool((machine.model.rod_kind == 0).any())
    note = ("illustrative masses of pkmkit.dynamics.defaults (no source gives them): platform "
            f"{masses.platform_mass:g} kg at its frame origin"
            + (f", carriages {float(np.max(masses.carriage_mass)):g} kg" if slides else "")
            + f", rods or struts up to {float(np.max(rods)):.3g} kg")
    return GravityDeflection(out, note)


def aim_loaded(machine: Any, targets: Any, *, tool_length: float | None = None,
               masses_of: Any = None
               ) -> tuple[np.ndarray, GravityDeflection]:
    """Targets ``(N, w)`` (:func:`~pkmkit.calibration.controller.as_targets`) moved against
    ``machine``'s gravity deflection so that its loaded tool point reaches ``targets`` to second
    order (module docstring), and the deflection at the targets. Rows the machine cannot reach
    stay as given (the compensation flags them).

    Raises:
        UnsupportedOperationError, InputError: as :func:`gravity_deflection`.
    """
    x = as_targets(machine, targets)
    q = commanded_q(machine, x, tool_length)
    sag = gravity_deflection(machine, q, tool_length=tool_length, masses_of=masses_of)
    d = sag.deflection
    ok = np.isfinite(d).all(axis=1)
    aimed = x.copy()
    aimed[ok, :3] -= d[ok, :3]
    if x.shape[1] == 6 and machine.pose_orientation == "axis":
        axis = x[ok, 3:6] - np.cross(d[ok, 3:6], x[ok, 3:6])
        aimed[ok, 3:6] = axis / np.linalg.norm(axis, axis=1, keepdims=True)
    elif x.shape[1] == 6:  # a platform rotation vector: turned back by the sag's rotation
        from pkmkit.spatial.rotation import compose_rotvec

        aimed[ok, 3:6] = compose_rotvec(-d[ok, 3:6], x[ok, 3:6])
    return aimed, sag


class LoadedAim:
    """The gravity aim of :func:`aim_loaded` as a correction field ``(k, 3) → (k, 3)`` for
    :func:`pkmkit.calibration.corrected_program.correct_path` (tool-point targets), keeping the
    deflections it met (``sizes``, m) and the masses' ``note``. A point the machine reaches but
    whose deflection is undefined (a singular configuration) is NaN: its block is refused rather
    than left uncorrected."""

    def __init__(self, machine: Any, tool_length: float | None = None, masses_of: Any = None):
        self.machine = machine
        self.masses_of = masses_of
        self.tool_length = tool_length
        self.sizes: list[np.ndarray] = []
        self.note = ""

    def __call__(self, targets: np.ndarray) -> np.ndarray:
        aimed, sag = aim_loaded(self.machine, targets, tool_length=self.tool_length,
                                masses_of=self.masses_of)
        size = np.linalg.norm(sag.deflection[:, :3], axis=1)
        self.sizes.append(size[np.isfinite(size)])
        self.note = sag.note
        aimed = np.array(aimed, dtype=float)
        aimed[~np.isfinite(size)] = np.nan
        return aimed

    def summary(self, scale: float = 1.0) -> dict[str, Any]:
        """``deflection_rms``, ``deflection_max`` (in units of ``scale`` m; None if none) and
        ``masses`` (the note)."""
        size = np.concatenate(self.sizes) if self.sizes else np.zeros(0)
        return {"deflection_rms": float(np.sqrt(np.mean(size**2))) / scale if size.size
                else None,
                "deflection_max": float(size.max()) / scale if size.size else None,
                "masses": self.note}


def gravity_beside_residual(result: Any, measurements: Any) -> dict[str, Any] | None:
    """The gravity deflection of the identified machine predicted at the measured
    configurations, beside the calibration's residual: whether elasticity could explain it.

    Returns None without measured actuator values (machined parts); otherwise a dict (SI):
    ``configurations``, ``rms`` and ``max`` of the tool point's deflection, ``rms_varying``
    (its RMS about the mean deflection: the part a fitted frame cannot absorb — a constant sag
    looks like a frame offset), ``residual_rms`` (after identification) and ``note`` (the
    masses), or ``{"available": False, "reason": …}`` for a machine without a gravity model.
    """
    q = getattr(measurements, "q", None)
    if q is None:
        return None
    tl = getattr(measurements, "tool_length", None)
    if tl is not None:
        values = np.unique(np.asarray(tl, dtype=float))
        if values.size != 1:
            return {"available": False, "reason": "the measurements use several tool lengths"}
        tl = float(values[0])
    try:
        sag = gravity_deflection(result.machine, q, tool_length=tl)
    except PkmError as exc:
        return {"available": False, "reason": str(exc)}
    points = sag.deflection[:, :3]
    points = points[np.isfinite(points).all(axis=1)]
    if not len(points):
        return {"available": False, "reason": "no measured configuration assembles"}
    size = np.linalg.norm(points, axis=1)
    varying = np.linalg.norm(points - points.mean(axis=0), axis=1)
    return {"available": True, "configurations": len(points),
            "rms": float(np.sqrt(np.mean(size**2))), "max": float(size.max()),
            "rms_varying": float(np.sqrt(np.mean(varying**2))),
            "residual_rms": float(result.after.rms), "note": sag.note}
