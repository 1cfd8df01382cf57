"""The part of the machine protocol that every family shares.

Every machine class (:class:`~pkmkit.machines.machine.Machine`,
:class:`~pkmkit.machines.full_pose.FullPoseMachine`,
:class:`~pkmkit.machines.joint_chain.JointChainMachine`) derives from :class:`MachineFace`, so
calling code asks the machine rather than testing its class: ``machine.family`` says which
family it is where an algorithm's physics truly differs (a dispatch table, never a chain of
class-name tests), ``machine.actuator_quantities`` whether each actuator is a length or an angle.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from pkmkit.exceptions import UnsupportedOperationError
from pkmkit.machines.stiffness_model import StiffnessModel

#: The machine families: rod legs with a translational platform, rod legs with a full-pose
#: (6-DOF) platform, joint chains (possibly hyperstatic) with heads.
FAMILIES = ("translational", "full-pose", "chain")

#: How each family writes the orientation part of a pose row (:attr:`MachineFace.pose_orientation`).
POSE_ORIENTATIONS = {"translational": None, "full-pose": "rotvec", "chain": "axis"}


class MachineFace(StiffnessModel):
    """Mixin of the family-independent protocol attributes.

    Needs ``actuator_quantities`` (``"length"`` or ``"angle"`` per actuator) from the class.
    """

    #: One of :data:`FAMILIES`.
    family: ClassVar[str]

    @property
    def position_controlled(self) -> bool:
        """True when the machine's orientation follows its position (a full-pose machine with
        fewer than six actuators): ``ik``/``jacobian`` also take positions ``(N, 3)``. False
        for every other machine."""
        return False

    @property
    def length_scale(self) -> float:
        """The length L (m) that turns angles into metres when errors, readings and
        identifiability mix them: a full-pose machine's characteristic length, a joint chain's
        closure scale, the mean equivalent-leg length of a translational machine."""
        from pkmkit.model.rod_defects import rod_set

        return float(np.mean(rod_set(self.model).length))

    @property
    def orientation_fixed(self) -> bool:
        """True when the platform only translates (its orientation never changes: nothing to
        measure or command in it); False for full-pose platforms and joint chains."""
        return self.family == "translational"

    @property
    def six_dof(self) -> bool:
        """True when the machine commands all six coordinates of its platform pose (position
        and rotation vector): a full-pose machine with six actuators or more. False for
        translating platforms, position-controlled full-pose machines and joint chains (whose
        pose is a tool point and axis, five degrees of freedom)."""
        return False

    @property
    def incompatible_defects(self) -> bool:
        """True when geometric defects may be incompatible with the closure (a hyperstatic
        joint-chain machine assembles them only in least squares; the compatible ones span a
        subspace, :mod:`pkmkit.geometric_errors.compatibility`); False for rod legs, whose
        every rod closes whatever its defects."""
        return False

    @property
    def closed_form_inverse(self) -> bool:
        """True when the inverse model of a pose is a closed form (rod by rod), smooth in the
        pose; False when it is solved numerically from a start (joint chains)."""
        return True

    @property
    def inverse_continues(self) -> bool:
        """True when ``ik(x, full_output=True)`` returns its complete ``solution`` and
        ``ik(x, start=...)`` starts from one (a neighbouring point's: continuation over a grid,
        :mod:`pkmkit.analysis.continuation`); False for closed-form inverses."""
        return False

    def continuation_starts(self, points: np.ndarray, start: np.ndarray) -> np.ndarray:
        """The starts a grid's continuation gives ``ik(points, start=...)`` (machines whose
        inverse continues): ``start (N, ·)`` — the neighbours' solutions, NaN rows none — with
        the rows a better start answers replaced (a joint chain's closed-form start,
        :meth:`~pkmkit.machines.warm_starts.ChainWarmStart.continuation_starts`); here
        ``start`` itself."""
        return start

    def criteria_rates(self, points: np.ndarray, inverse: Any, jacobians: Any,
                       axes: tuple[int, ...], *, factors: bool = False) -> Any:
        """Derivatives of what the workspace criteria read (actuator coordinates, rod
        shortfalls, parallel measure, transmission factors) along the pose coordinates
        ``axes`` at ``points``, given their inverse and velocity models, or None: no analytic
        derivatives (callers then difference). Full-pose machines answer
        (:mod:`pkmkit.machines.full_pose_criteria_rates`)."""
        return None

    def translation_lines(self, points: np.ndarray) -> Any:
        """Rows of ``points`` (as given to ``ik``) whose inverse model is another row's shifted
        along a common slide axis, so that their velocity model and criteria rates are that
        row's (:class:`pkmkit.machines.slide_columns.SlideColumns`; their strokes are their
        own), or None: every row its own. Position-controlled full-pose machines with parallel
        slides answer (the Verne module)."""
        return None

    @property
    def angular_actuators(self) -> np.ndarray:
        """``(n_actuators,)`` bool: True for angular actuators (cranks, revolute joints), whose
        values are radians inside pkmkit and degrees in files and on the command line."""
        return np.array([q == "angle" for q in self.actuator_quantities], dtype=bool)

    def parameters(self):
        """The machine's one parameter vector (:class:`pkmkit.model.parameter_vector.
        ParameterVector`): its nominal parameters, then its defects
        (:mod:`pkmkit.machines.parameter_vector`)."""
        from pkmkit.machines.parameter_vector import machine_parameters

        return machine_parameters(self)

    def with_parameters(self, vector: Any):
        """The machine rebuilt from a changed :meth:`parameters` vector (or its values).

        Raises:
            InputError: a vector of another machine. ParameterError: values the machine cannot
                be built from.
        """
        from pkmkit.machines.parameter_vector import machine_with_parameters

        return machine_with_parameters(self, vector)

    def defects(self) -> np.ndarray:
        """``(d,)`` the machine's geometric defects (SI; zeros when nominal), in the order of
        :func:`pkmkit.geometric_errors.model.defect_set`."""
        from pkmkit.model.defect_rule import defects

        return defects(self)

    def with_defects(self, values: Any):
        """The machine's nominal geometry with ``values`` (mapping name → SI value, absent
        names 0, or a full vector) applied exactly, **replacing** its defects — the one rule of
        :mod:`pkmkit.model.defect_rule` (joint chains solve their home closure again, in least
        squares if the defects are incompatible).

        Raises:
            ParameterError: an unknown name, a mis-shaped vector, defects too large to apply.
        """
        from pkmkit.model.defect_rule import with_defects

        return with_defects(self, values)

    def skeleton(self, q: Any = None):
        """The polylines a drawing or a 3-D view shows at actuator values ``q (n,)`` (SI;
        default home), the same for every family: see :mod:`pkmkit.machines.skeleton`.

        Raises:
            NoAssemblyError: no assembly at ``q``.
        """
        from pkmkit.machines.skeleton import skeleton

        return skeleton(self, q)

    @property
    def pose_orientation(self) -> str | None:
        """The orientation part of a pose row: None (position only, ``dims`` values),
        ``"rotvec"`` (position then rotation vector, 6 values) or ``"axis"`` (tool point then
        unit tool axis, 6 values)."""
        return POSE_ORIENTATIONS[self.family]


def require_translational(machine, what: str,
                          instead: str = "run its poses through ik/jacobian instead") -> None:
    """Refuse, with a typed error naming why, an algorithm written for translational rod-leg
    machines (their closed forms in the batch-last layout) on a machine of another family.

    Raises:
        UnsupportedOperationError: ``machine.family`` is not ``"translational"`` (an
            :class:`~pkmkit.exceptions.InputError`).
    """
    if machine.family != "translational":
        raise UnsupportedOperationError(
            what, machine.id, machine.family,
            "it is computed for translational rod-leg machines (3-D or planar platforms that "
            f"only translate); {instead}")
