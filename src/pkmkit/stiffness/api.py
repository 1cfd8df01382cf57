"""``stiffness(machine, ...)``: the elastostatic model of any machine, one entry point.

Rod-leg machines (translating platforms and full-pose ones) go through
:mod:`pkmkit.stiffness.rod_legs`, joint-chain machines through the VJM of
:mod:`pkmkit.stiffness.joint_chains`; the result is the same :class:`StiffnessResult`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.numerics.arrays import as_batch
from pkmkit.numerics.magnitudes import MAX_FORCE
from pkmkit.status import Status
from pkmkit.stiffness.data import StiffnessData, default_data
from pkmkit.stiffness.frames import move_compliance
from pkmkit.stiffness.joint_chains import chain_compliance
from pkmkit.stiffness.results import StiffnessResult, summarize
from pkmkit.stiffness.rod_legs import rod_leg_compliance


def twist_names(machine: Any) -> tuple[str, ...]:
    """Names of the twist coordinates of a machine's stiffness: ``dx, dy[, dz]`` for a
    translating platform, ``dx, dy, dz, rx, ry, rz`` otherwise (``machine.twist_names``)."""
    return machine.twist_names


def check_data(machine: Any, data: StiffnessData) -> None:
    """Refuse elastic data of the other family (rods on a joint-chain machine, links on a
    rod-leg machine) with an :class:`InputError`."""
    chains = machine.elastic_members == "links"
    if chains and data.rod_section is not None:
        raise InputError("a joint-chain machine has links, not rods: give link_section")
    if not chains and (data.link_section is not None or data.link_sections):
        raise InputError("a rod-leg machine has rods, not links: give rod_section")


def stiffness(machine: Any, pose: Any = None, *, q: Any = None, wrench: Any = None,
              data: StiffnessData | None = None, reference: Any = None,
              tool_length: float | None = None) -> StiffnessResult:
    """Cartesian stiffness, compliance, eigen-stiffnesses and deflection of a machine.

    Args:
        machine: any pkmkit machine.
        pose: rod-leg machines: pose ``(dims,)`` / ``(N, dims)`` (positions ``(3,)`` for a
            machine with fewer than six actuators and a full pose); joint-chain machines: tool
            point and axis ``(6,)`` / ``(N, 6)`` (solved by the inverse model), or give ``q``.
        q: joint-chain machines: actuator coordinates ``(n,)`` / ``(N, n)`` instead of a pose.
        wrench: ``(d,)`` or ``(N, d)`` force (N) then moment (N·m) at the reference point, d
            the twist width (a translating platform: its force components only).
        data: the elastic data (default: :func:`~pkmkit.stiffness.data.default_data`).
        reference: ``(3,)`` offset (m) of the reference point from the default one, in the
            platform frame (full-pose machines; default the platform origin) or in the tool
            frame (joint-chain machines; default the tool point). A translating platform's
            stiffness is the same at every point: ``reference`` is refused there.
        tool_length: joint-chain machines: tool length (m; default the machine's).

    Returns:
        :class:`StiffnessResult` (batch axis dropped for a single configuration).

    Raises:
        InputError: mis-shaped input, a wrench of the wrong width, a reference on a
            translating platform; the machine's typed errors for a single bad configuration.
    """
    data = data or default_data(machine)
    names = twist_names(machine)
    d = len(names)
    chains = machine.stiffness_from_actuators
    check_data(machine, data)
    if chains:
        if (pose is None) == (q is None):
            raise InputError("give either a pose (tool point and axis) or q")
        if q is None:
            xb, single = as_batch(pose, 6, "pose")
            qb = np.atleast_2d(machine.ik(xb[0] if single else xb, tool_length=tool_length,
                                          strokes="ignore"))
        else:
            qb, single = as_batch(q, machine.n_actuators, "q")
            if single:
                machine.fk(qb[0], tool_length=tool_length, strokes="ignore")  # typed errors
        c, status, system = chain_compliance(machine, qb, data, tool_length=tool_length)
        where = "the tool point"
        axes = system.tool_axes
    else:
        if q is not None:
            raise InputError("rod-leg machines take a pose, not q")
        c, status, _, single = rod_leg_compliance(machine, pose, data)
        where = "the platform" if machine.orientation_fixed else "the platform reference point"
        axes = None
    if reference is not None:
        offset = np.asarray(reference, dtype=float).reshape(-1)
        if offset.shape != (3,) or not np.isfinite(offset).all():
            raise InputError(f"reference must be 3 finite numbers (m), got {reference!r}")
        if d < 6:
            raise InputError("a translating platform has the same stiffness at every point: "
                             "reference does not apply")
        if axes is None:
            from pkmkit.spatial.rotation import rotvec_to_matrix

            poses = np.atleast_2d(np.asarray(pose, dtype=float))
            if poses.shape[1] == 6:
                axes = rotvec_to_matrix(poses[:, 3:])
            else:  # positions of a position-controlled machine: its orientation from ik
                inv = machine.ik(pose, full_output=True, strokes="ignore")
                axes = rotvec_to_matrix(np.atleast_2d(inv.pose)[:, 3:])
        world = np.einsum("nij,j->ni", np.nan_to_num(axes), offset)
        c = move_compliance(c, world)
        where += f" moved by {offset.tolist()} m (its own frame)"
    w = None
    if wrench is not None:
        w = np.asarray(wrench, dtype=float)
        if w.shape[-1] != d or w.ndim > 2 or not np.isfinite(w).all():
            raise InputError(f"wrench must have {d} finite components ({', '.join(names)} "
                             f"forces then moments), got shape {w.shape}")
        big = np.argwhere(~(np.abs(np.atleast_2d(w)) <= MAX_FORCE))
        if big.size:
            row, k = (int(i) for i in big[0])
            where = f"row {row}, " if w.ndim == 2 else ""
            raise InputError(f"wrench {where}component {k + 1} ({names[k]}) = "
                             f"{np.atleast_2d(w)[row, k]:g} is beyond {MAX_FORCE:g} N (or N·m), "
                             "the largest load pkmkit accepts: check the units")
    result = summarize(c, status, names, where, w)
    if single:
        if result.status[0] != Status.OK:
            from pkmkit.exceptions import SingularConfigurationError

            raise SingularConfigurationError(
                f"no stiffness at this configuration ({Status(int(result.status[0])).label}): "
                "a singular configuration or a mechanism (some motion costs no energy)")
        return result.single()
    return result
