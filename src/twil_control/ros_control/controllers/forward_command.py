"""forward_command_controller (ROS 1) and the effort, velocity and position controllers built on it.

One joint's command from std_msgs/Float64, or a group's from std_msgs/Float64MultiArray (a
message of the wrong length refused, as in ROS). starting() holds the joint where it is; unlike
ROS, a non-finite command is refused and the previous one kept, so it never reaches the
hardware (docs/ros_control.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from twil_control.core.params import ParamError

from ..controller_interface import Controller, ControllerNodeHandle
from ..hardware_interface import (
    EFFORT_JOINT_INTERFACE,
    POSITION_JOINT_INTERFACE,
    VELOCITY_JOINT_INTERFACE,
    HardwareInterfaceError,
)
from ..realtime_tools import RealtimeBuffer
from ..registry import controller_type


@dataclass
class JointParams:
    ros_package: ClassVar[str] = "forward_command_controller"
    type: str
    joint: str


@dataclass
class JointGroupParams:
    ros_package: ClassVar[str] = "forward_command_controller"
    type: str
    joints: list[str]


class BurstLog:
    """Log a refused command once per burst: again only after a good command came in between."""

    def __init__(self, controller: Controller) -> None:
        self.controller = controller
        self.active = False

    def bad(self, message: str) -> None:
        if not self.active:
            self.active = True
            self.controller.log.error(
                "%s: %s (further refusals are not logged until a valid command arrives)",
                self.controller.name,
                message,
            )

    def good(self) -> None:
        self.active = False


class Float64Command:
    """A one-joint controller's std_msgs/Float64 ``command`` subscription: a finite value goes to
    the RealtimeBuffer update() reads; a non-finite one is refused and the previous one kept
    (logged once per burst of them). `what` names the command in that log line."""

    def __init__(self, controller: Controller, controller_nh: ControllerNodeHandle, what: str) -> None:
        self.buffer = RealtimeBuffer(0.0)
        self.topic = controller_nh.resolve("command")
        self.burst = BurstLog(controller)
        self.what = what
        controller_nh.create_subscription("command", "std_msgs/Float64", self.on_message)

    def on_message(self, msg) -> None:
        value = float(msg.data)
        if not math.isfinite(value):
            self.burst.bad(
                f"ignoring non-finite {self.what} {value} on {self.topic}; keeping {self.buffer.read_from_rt()}"
            )
            return
        self.burst.good()
        self.buffer.write_from_non_rt(value)


def joint_reference_fields(msg, names: tuple[str, str, str], joints: list[str], topic: str, burst: BurstLog):
    """(positions, velocities, accelerations) arrays from the three array fields `names` of a
    command (the first required, the other two empty for zero), one value per joint; None after
    logging the refusal (wrong length or a non-finite value)."""
    n, fields = len(joints), []
    for name, required in zip(names, (True, False, False)):
        values = np.asarray(getattr(msg, name), dtype=float).ravel()
        if values.size == 0 and not required:
            values = np.zeros(n)
        if values.size != n:
            burst.bad(
                f"refusing command on {topic}: {name} has {values.size} values, expected {n} "
                f"({', '.join(joints)})"
                + ("" if required else " or none")
                + "; keeping the previous reference"
            )
            return None
        if not np.all(np.isfinite(values)):
            burst.bad(
                f"refusing command on {topic}: non-finite {name} {values.tolist()}; "
                "keeping the previous reference"
            )
            return None
        fields.append(values)
    return tuple(fields)


class ForwardCommandController(Controller):
    """forward_command_controller::ForwardCommandController<T>: one joint, Float64 commands."""

    interface: ClassVar[str]

    def init(self, hw, root_nh, controller_nh) -> bool:
        try:
            params = controller_nh.typed_params(JointParams)
            self.joint = hw.get_handle(self.interface, params.joint)
        except (ParamError, HardwareInterfaceError) as error:
            return self.fail(str(error))
        self.command = Float64Command(self, controller_nh, "command")
        return True

    def starting(self, time: float) -> None:
        self.command.buffer.init_rt(
            self.joint.position if self.interface == POSITION_JOINT_INTERFACE else 0.0
        )

    def update(self, time: float, period: float) -> None:
        self.joint.set_command(self.command.buffer.read_from_rt())


class ForwardJointGroupCommandController(Controller):
    """forward_command_controller::ForwardJointGroupCommandController<T>: Float64MultiArray commands."""

    interface: ClassVar[str]

    def init(self, hw, root_nh, controller_nh) -> bool:
        try:
            params = controller_nh.typed_params(JointGroupParams)
        except ParamError as error:
            return self.fail(str(error))
        if not params.joints:
            return self.fail(f"List of joint names is empty (parameter '{controller_nh.namespace}/joints')")
        if len(set(params.joints)) != len(params.joints):
            return self.fail(
                f"Parameter '{controller_nh.namespace}/joints' lists a joint twice: {params.joints}"
            )
        try:
            self.joints = [hw.get_handle(self.interface, j) for j in params.joints]
        except HardwareInterfaceError as error:
            return self.fail(str(error))
        self.hw = hw
        self.index = np.array([hw.joint_index(j) for j in params.joints], dtype=int)
        self.commands = hw.command(self.interface)
        self.command_buffer = RealtimeBuffer(np.zeros(len(self.joints)))
        self.topic = controller_nh.resolve("command")
        self.burst = BurstLog(self)
        controller_nh.create_subscription("command", "std_msgs/Float64MultiArray", self.command_cb)
        return True

    def command_cb(self, msg) -> None:
        data = np.asarray(msg.data, dtype=float)
        if data.shape != (len(self.joints),):
            self.burst.bad(
                f"Dimension of command ({data.size}) does not match number of joints "
                f"({len(self.joints)})! Not executing! (on {self.topic})"
            )
            return
        if not np.all(np.isfinite(data)):
            self.burst.bad(
                f"ignoring command with non-finite values {data.tolist()} on {self.topic}; keeping "
                f"{self.command_buffer.read_from_rt().tolist()}"
            )
            return
        self.burst.good()
        self.command_buffer.write_from_non_rt(data.copy())

    def starting(self, time: float) -> None:
        if self.interface == POSITION_JOINT_INTERFACE:
            self.command_buffer.init_rt(self.hw.position[self.index].copy())
        else:
            self.command_buffer.init_rt(np.zeros(len(self.joints)))

    def update(self, time: float, period: float) -> None:
        self.commands[self.index] = self.command_buffer.read_from_rt()


def _single(type_name: str, iface: str) -> type[ForwardCommandController]:
    cls = type(
        type_name.split("/")[1],
        (ForwardCommandController,),
        {
            "interface": iface,
            "hardware_interfaces": (iface,),
            "__module__": __name__,
            "__doc__": f"{type_name}: ForwardCommandController<{iface}>.",
        },
    )
    return controller_type(type_name)(cls)


def _group(type_name: str, iface: str) -> type[ForwardJointGroupCommandController]:
    cls = type(
        type_name.split("/")[1],
        (ForwardJointGroupCommandController,),
        {
            "interface": iface,
            "hardware_interfaces": (iface,),
            "__module__": __name__,
            "__doc__": f"{type_name}: ForwardJointGroupCommandController<{iface}>.",
        },
    )
    return controller_type(type_name)(cls)


JointEffortController = _single("effort_controllers/JointEffortController", EFFORT_JOINT_INTERFACE)
JointGroupEffortController = _group("effort_controllers/JointGroupEffortController", EFFORT_JOINT_INTERFACE)
JointVelocityController = _single("velocity_controllers/JointVelocityController", VELOCITY_JOINT_INTERFACE)
JointGroupVelocityController = _group(
    "velocity_controllers/JointGroupVelocityController", VELOCITY_JOINT_INTERFACE
)
PositionJointPositionController = _single(
    "position_controllers/JointPositionController", POSITION_JOINT_INTERFACE
)
JointGroupPositionController = _group(
    "position_controllers/JointGroupPositionController", POSITION_JOINT_INTERFACE
)
