"""Reading a URDF export back: its tree, put in pkmkit's configurations, closes every loop of the
closures YAML and carries the platform where pkmkit puts it (what ``pkmkit export --to urdf``
checks before it writes the files).

Two readers: Pinocchio (``pinocchio.buildModelFromXML``, its frames and
``RigidConstraintModel`` placements) when it is installed, else a small pure-Python URDF reader
(:func:`read_urdf`, :func:`link_placements`: ``xml.etree`` and the URDF conventions — origin
``xyz``/``rpy`` with ``R = Rz(yaw) Ry(pitch) Rx(roll)``, revolute and continuous joints turning
about their axis, prismatic ones sliding along it).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np
import yaml

from pkmkit.export.base import ExportCheckError, platform_points, sample_poses
from pkmkit.export.urdf import UrdfExport, configuration

#: Largest closure residual and platform error a written export may have (m).
TOLERANCE = 1e-9


@dataclass(frozen=True)
class UrdfJointRecord:
    """A joint as the file says: ``type``, ``parent``/``child`` links, ``origin (4, 4)``,
    ``axis (3,)``."""

    name: str
    type: str
    parent: str
    child: str
    origin: np.ndarray
    axis: np.ndarray


def _numbers(element, attribute: str, default: str) -> np.ndarray:
    text = default if element is None else element.get(attribute, default)
    return np.array([float(v) for v in text.split()])


def _rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    from pkmkit.spatial.rotation import axis_rotation

    return axis_rotation(axis[None], np.array([angle]))[0]


def read_urdf(text: str) -> dict[str, UrdfJointRecord]:
    """The joints of a URDF document by child link (pure Python).

    Raises:
        ExportCheckError: the text is not a URDF tree (malformed, a link with two parents).
    """
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise ExportCheckError(f"the generated URDF is not XML: {exc}") from None
    joints: dict[str, UrdfJointRecord] = {}
    for element in root.iter("joint"):
        origin = element.find("origin")
        roll, pitch, yaw = _numbers(origin, "rpy", "0 0 0")
        transform = np.eye(4)
        transform[:3, :3] = (_rotation(np.array([0, 0, 1.0]), yaw)
                             @ _rotation(np.array([0, 1.0, 0]), pitch)
                             @ _rotation(np.array([1.0, 0, 0]), roll))
        transform[:3, 3] = _numbers(origin, "xyz", "0 0 0")
        axis = _numbers(element.find("axis"), "xyz", "1 0 0")
        record = UrdfJointRecord(element.get("name"), element.get("type"),
                                 element.find("parent").get("link"),
                                 element.find("child").get("link"), transform,
                                 axis / np.linalg.norm(axis))
        if record.child in joints:
            raise ExportCheckError(f"link {record.child!r} has two parent joints")
        joints[record.child] = record
    return joints


def link_placements(joints: dict[str, UrdfJointRecord], values: dict[str, float]
                    ) -> dict[str, np.ndarray]:
    """Every link's placement ``(4, 4)`` in the root's frame for joint ``values`` (m or rad)."""
    out: dict[str, np.ndarray] = {}

    def place(link: str) -> np.ndarray:
        if link in out:
            return out[link]
        if link not in joints:
            out[link] = np.eye(4)
            return out[link]
        joint = joints[link]
        motion = np.eye(4)
        if joint.type in ("revolute", "continuous"):
            motion[:3, :3] = _rotation(joint.axis, values[joint.name])
        elif joint.type == "prismatic":
            motion[:3, 3] = joint.axis * values[joint.name]
        out[link] = place(joint.parent) @ joint.origin @ motion
        return out[link]

    for child in joints:
        place(child)
    return out


def _python_reader(export: UrdfExport):
    joints = read_urdf(export.urdf)

    def evaluate(values: dict[str, float]) -> tuple[list[float], np.ndarray]:
        placed = link_placements(joints, values)
        gaps = [float(np.linalg.norm(placed[a][:3, 3] - placed[b][:3, 3]))
                for a, b in _pairs(export)]
        return gaps, placed["platform"]

    return evaluate


def closure_pairs(closures: str, kind: str) -> list[tuple[str, str]]:
    """The ``(frame, frame)`` pairs of a closures YAML, every one of type ``kind`` (``"3D"``,
    ``"6D"``).

    Raises:
        ExportCheckError: a closure of another type.
    """
    data = yaml.safe_load(closures)
    if list(data.get("type", [])) != [kind] * len(data["closed_loop"]):
        raise ExportCheckError(f"the closures YAML holds a closure other than {kind}")
    return [tuple(p) for p in data["closed_loop"]]


def _pairs(export: UrdfExport) -> list[tuple[str, str]]:
    return closure_pairs(export.closures, "3D")


def pinocchio_module(use_pinocchio: bool | None):
    """The ``pinocchio`` module for a read-back check, or None for the pure-Python reader.

    Args:
        use_pinocchio: None: Pinocchio when installed; True: require it (ImportError if
            missing); False: never.
    """
    if use_pinocchio is False:
        return None
    try:
        import pinocchio
    except ImportError:
        if use_pinocchio:
            raise
        return None
    return pinocchio


def pinocchio_configuration(pin, model, values: dict[str, float]) -> np.ndarray:
    """Pinocchio's configuration vector of a URDF tree from joint ``values`` by name (m or
    rad; a continuous joint takes (cos, sin))."""
    q = pin.neutral(model)
    for jid in range(1, model.njoints):
        joint, value = model.joints[jid], values[model.names[jid]]
        if joint.nq == 2:  # continuous: (cos, sin)
            q[joint.idx_q:joint.idx_q + 2] = np.cos(value), np.sin(value)
        else:
            q[joint.idx_q] = value
    return q


def _pinocchio_reader(export: UrdfExport, pin):
    try:
        model = pin.buildModelFromXML(export.urdf)
    except (RuntimeError, ValueError) as exc:
        raise ExportCheckError(f"Pinocchio refuses the generated URDF: {exc}") from None
    data = model.createData()
    constraints = []
    for a, b in _pairs(export):
        f1, f2 = (model.frames[model.getFrameId(n)] for n in (a, b))
        constraints.append(pin.RigidConstraintModel(
            pin.ContactType.CONTACT_3D, model, f1.parentJoint, f1.placement, f2.parentJoint,
            f2.placement, pin.ReferenceFrame.LOCAL))
    platform = model.getFrameId("platform")

    def evaluate(values: dict[str, float]) -> tuple[list[float], np.ndarray]:
        pin.forwardKinematics(model, data, pinocchio_configuration(pin, model, values))
        pin.updateFramePlacements(model, data)
        gaps = [float(np.linalg.norm((data.oMi[c.joint1_id] * c.joint1_placement).translation
                                     - (data.oMi[c.joint2_id] * c.joint2_placement).translation))
                for c in constraints]
        return gaps, data.oMf[platform].homogeneous

    return evaluate


def check_urdf_export(machine, export: UrdfExport, *, use_pinocchio: bool | None = None
                      ) -> tuple[float, str]:
    """Read the written tree back and put it in pkmkit's configurations (home, the named poses,
    random poses near home: :func:`~pkmkit.export.base.sample_poses`; the actuators at pkmkit's
    inverse model, the passive joints from pkmkit's geometry): every closure's two frames must
    coincide and the platform frame sit at pkmkit's pose. Returns ``(largest error (m), reader)``
    with the reader ``"pinocchio"`` or ``"python"``.

    Args:
        use_pinocchio: None: Pinocchio when installed; True: require it; False: the pure-Python
            reader.

    Raises:
        ExportCheckError: a closure or the platform off by more than :data:`TOLERANCE`, or a
            file a reader refuses.
    """
    pin = pinocchio_module(use_pinocchio)
    evaluate = _pinocchio_reader(export, pin) if pin is not None else _python_reader(export)
    poses, q = sample_poses(machine)
    home = yaml.safe_load(export.closures)["home"]
    worst = max(evaluate({k: float(v) for k, v in home.items()})[0], default=0.0)
    for x, qk in zip([machine.home_pose, *poses], [machine.home_q, *q], strict=True):
        gaps, placement = evaluate(configuration(machine, export, x, qk))
        p, rot, _ = platform_points(machine, x)
        worst = max(worst, *gaps, float(np.abs(placement[:3, 3] - p).max()),
                    float(np.abs(placement[:3, :3] - rot).max()) * _radius(machine))
    if not worst <= TOLERANCE:
        raise ExportCheckError(f"the generated URDF does not close pkmkit's configurations "
                               f"(off by {worst:.3g} m): not written")
    return worst, "pinocchio" if pin is not None else "python"


def _radius(machine) -> float:
    """The platform's size (m): turns an orientation error into a displacement of its joints."""
    return max(float(np.linalg.norm(machine.model.rod_platform, axis=1).max()), 1.0)
