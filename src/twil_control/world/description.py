"""A user's robot description added to the plant (gazebo_ros spawn_model -urdf / -sdf's role).

The URDF goes through description.drake_urdf (meshes converted, ``<gazebo reference>``
properties mapped) and Drake's parser; its root link takes the spawn pose as Gazebo places a
model (x y z roll pitch yaw of the root link in the world); ``-J`` joint positions become the
joints' default positions. Drive plugins' wheel joints get actuators whose effort limit is the
plugin's torque.
"""

from __future__ import annotations

import math
from pathlib import Path

from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.parsing import Parser
from pydrake.multibody.tree import JointActuatorIndex, ModelInstanceIndex

from ..description.drake_urdf import urdf_for_drake
from ..description.urdf import DescriptionError, RobotDescription

__all__ = ["add_sdf", "add_urdf"]


def add_urdf(
    plant,
    parser: Parser,
    description: RobotDescription,
    model_name: str,
    pose: tuple[float, ...],
    joint_positions: dict[str, float],
    base_dir: Path | None = None,
    drive_effort_limits: dict[str, float] | None = None,
) -> tuple[list[ModelInstanceIndex], list[str]]:
    """Add the description as model ``model_name`` at ``pose`` (x, y, z, roll, pitch, yaw);
    returns the model instances and the warnings to log."""
    description.check_inertia()
    limits = dict(drive_effort_limits or {})
    text, warnings = urdf_for_drake(description, model_name, base_dir, tuple(limits))
    try:
        instances = list(parser.AddModelsFromString(text, "urdf"))
    except RuntimeError as error:  # Drake's parser diagnostics
        raise DescriptionError(f"{description.source}: Drake cannot load it: {error}") from None
    instance = instances[0]
    # GetJointActuatorIndices(instance) is empty before Finalize(): go through them all
    actuators = {
        a.joint().name(): a
        for a in (plant.get_joint_actuator(JointActuatorIndex(i)) for i in range(plant.num_actuators()))
        if a.model_instance() == instance
    }
    for joint, limit in limits.items():
        if joint in actuators and math.isfinite(limit) and limit > 0:
            actuators[joint].set_effort_limit(limit)
    _place(plant, instance, description.root, pose)
    for name, value in joint_positions.items():
        if not plant.HasJointNamed(name, instance):
            raise DescriptionError(
                f"{description.source}: -J {name} {value}: no joint {name!r} "
                f"(joints: {', '.join(description.joints)})"
            )
        joint = plant.GetJointByName(name, instance)
        if joint.num_positions() != 1:
            raise DescriptionError(
                f"{description.source}: -J {name}: joint of type "
                f"{joint.type_name()} has {joint.num_positions()} positions"
            )
        joint.set_default_positions([value])
    return instances, warnings


def add_sdf(
    plant, parser: Parser, text: str, model_name: str, pose: tuple[float, ...], source: str
) -> list[ModelInstanceIndex]:
    """Add an SDF model (``-sdf -file`` / ``-param``) named ``model_name`` at ``pose``."""
    import xml.etree.ElementTree as ET

    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise DescriptionError(f"{source}: not valid XML: {exc}") from None
    model = root.find("model") if root.tag == "sdf" else None
    if model is None:
        raise DescriptionError(f"{source}: an SDF model file is <sdf><model>...</model></sdf>")
    model.set("name", model_name)
    try:
        instances = list(parser.AddModelsFromString(ET.tostring(root, encoding="unicode"), "sdf"))
    except RuntimeError as error:
        raise DescriptionError(f"{source}: Drake cannot load it: {error}") from None
    links = model.findall("link")
    if links:
        _place(plant, instances[0], links[0].get("name"), pose)
    return instances


def _place(plant, instance: ModelInstanceIndex, root_link: str, pose: tuple[float, ...]) -> None:
    """The root link's default pose (a floating base; a welded root stays where it is welded)."""
    x, y, z, roll, pitch, yaw = pose
    if root_link == "world":  # a URDF rooted at "world" is welded where its joints say
        return
    body = plant.GetBodyByName(root_link, instance)
    welded = {int(b.index()) for b in plant.GetBodiesWeldedTo(plant.world_body())}
    if int(body.index()) in welded:
        return
    plant.SetDefaultFloatingBaseBodyPose(body, RigidTransform(RollPitchYaw(roll, pitch, yaw), [x, y, z]))
