"""The geometric-error part of the machine protocol, one mixin per family: what
:mod:`pkmkit.geometric_errors` asks a machine instead of testing its family.

- :mod:`~pkmkit.machines.defect_linearisation`: ``closure_linearisation(q)``,
  ``tool_sensitivity(q)``;
- :mod:`~pkmkit.machines.parameter_columns`: ``nominal_sensitivity(vector, positions, q,
  sens)``, ``held_tool_actuators(q, pose, point, rotation)``;
- :mod:`~pkmkit.machines.error_regions`: ``region_names()``, ``region_sizes()``,
  ``default_region()``, ``configurations_at(points)``, ``mechanism_configurations(n, seed=)``;
- :mod:`~pkmkit.machines.defect_masks`: ``loop_defect_mask()``,
  ``reference_joint_defect_mask()``;
- :mod:`~pkmkit.machines.defect_samples`: ``sampled_tool_points(q, samples, tool_length=)``;
- :mod:`~pkmkit.machines.tool_readings`: ``tool_readings(q, tool_length=)``,
  ``measures_machined_parts``, ``part_actuators(points)``, ``part_sensitivity(points)``.
"""

from __future__ import annotations

from pkmkit.machines.defect_linearisation import (
    ChainLinearisation,
    FullPoseLinearisation,
    TranslationalLinearisation,
)
from pkmkit.machines.defect_masks import ChainDefectMasks, RodDefectMasks
from pkmkit.machines.defect_samples import ChainDefectSamples, RodDefectSamples
from pkmkit.machines.error_regions import ChainRegions, FullPoseRegions, TranslationalRegions
from pkmkit.machines.parameter_columns import (
    ChainParameterColumns,
    FullPoseParameterColumns,
    TranslationalParameterColumns,
)
from pkmkit.machines.tool_readings import ChainReadings, FullPoseReadings, TranslationalReadings


class TranslationalErrors(TranslationalLinearisation, TranslationalParameterColumns,
                          TranslationalRegions, RodDefectMasks, RodDefectSamples,
                          TranslationalReadings):
    """Rod legs on a translating platform (:class:`~pkmkit.machines.machine.Machine`)."""


class FullPoseErrors(FullPoseLinearisation, FullPoseParameterColumns, FullPoseRegions,
                     RodDefectMasks, RodDefectSamples, FullPoseReadings):
    """Rod legs on a turning platform (:class:`~pkmkit.machines.full_pose.FullPoseMachine`)."""


class ChainErrors(ChainLinearisation, ChainParameterColumns, ChainRegions, ChainDefectMasks,
                  ChainDefectSamples, ChainReadings):
    """Joint chains (:class:`~pkmkit.machines.joint_chain.JointChainMachine`)."""
