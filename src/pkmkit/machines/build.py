"""Building a machine of the right family from a kind and its parameters."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from pkmkit.machines.full_pose import FullPoseMachine
from pkmkit.machines.joint_chain import JointChainMachine
from pkmkit.machines.machine import Machine, MachineKind
from pkmkit.model.chains import JointChainModel


def build_machine(
    kind: MachineKind,
    params: Mapping[str, Any],
    *,
    id: str,
    name: str = "",
    description: str = "",
    source: str = "",
) -> Machine:
    """Build a machine of ``kind`` from validated SI parameters: a :class:`Machine`, a
    :class:`~pkmkit.machines.full_pose.FullPoseMachine` when the kind builds a full-pose rod
    model, or a :class:`~pkmkit.machines.joint_chain.JointChainMachine` for a joint-chain one."""
    model = kind.build(params)
    common = dict(id=id, name=name or kind.title, kind=kind, params=dict(params), model=model,
                  description=description, source=source or kind.source,
                  extra_poses=kind.reference_poses(params, model))
    if isinstance(model, JointChainModel):
        return JointChainMachine(**common, tool_length=float(params.get("tool_length", 0.0)))
    if model.full_pose:
        return FullPoseMachine(**common)
    return Machine(**common)
