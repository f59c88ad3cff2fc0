"""A user's robot description added to the plant (gazebo_ros spawn_model -urdf / -sdf's role).

The URDF goes through description.drake_urdf (meshes converted, ``<gazebo reference>``
properties mapped) and Drake's parser; its root link takes the spawn pose as Gazebo places a
model (x y z roll pitch yaw of the root link in the world); ``-J`` joint positions become the
joints' default positions. An SDF model arrives normalised (description.gazebo_world: renamed,
its pose composed after the spawn pose, as Gazebo places it). Drive plugins' wheel joints get
actuators whose effort limit is the plugin's torque.
"""

from __future__ import annotations

import math
from pathlib import Path

from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.parsing import Parser
from pydrake.multibody.tree import JointActuatorIndex, ModelInstanceIndex

from ..description.drake_urdf import urdf_for_drake
from ..description.urdf import DescriptionError, RobotDescription

__all__ = ["add_sdf", "add_urdf", "set_effort_limits"]


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
    set_effort_limits(plant, instances, limits)
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
    plant, parser: Parser, text: bytes, source: str, drive_effort_limits: dict[str, float] | None = None
) -> list[ModelInstanceIndex]:
    """Add a normalised SDF model (``-sdf -file`` / ``-param``: named and posed already)."""
    try:
        instances = list(parser.AddModelsFromString(text.decode("utf-8"), "sdf"))
    except RuntimeError as error:
        raise DescriptionError(f"{source}: Drake cannot load it: {error}") from None
    set_effort_limits(plant, instances, dict(drive_effort_limits or {}))
    return instances


def set_effort_limits(plant, instances: list[ModelInstanceIndex], limits: dict[str, float]) -> None:
    """The effort limit (N m) of the actuators of the named joints of these instances (a drive
    plugin's torque); other actuators keep theirs."""
    if not limits:
        return
    wanted = {int(i) for i in instances}
    # GetJointActuatorIndices(instance) is empty before Finalize(): go through them all
    for index in range(plant.num_actuators()):
        actuator = plant.get_joint_actuator(JointActuatorIndex(index))
        limit = limits.get(actuator.joint().name())
        if (
            int(actuator.model_instance()) in wanted
            and limit is not None
            and math.isfinite(limit)
            and limit > 0
        ):
            actuator.set_effort_limit(limit)


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
