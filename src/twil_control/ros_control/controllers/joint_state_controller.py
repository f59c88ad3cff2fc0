"""joint_state_controller/JointStateController (ros_controllers, ROS 1).

Publishes sensor_msgs/JointState of the JointStateInterface at ``publish_rate`` Hz, stamped with
the controller manager's time. Its schedule advances by exactly 1/rate from the first update
after starting(), so 100 Hz at 1 kHz is exactly 100 messages a simulated second, where ROS's
loses the first period and can skip on floating-point ties (docs/ros_control.md).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from twil_control.core.messages import header, msg_class
from twil_control.core.param_rules import param
from twil_control.core.params import ParamError

from ..controller_interface import Controller
from ..hardware_interface import JOINT_STATE_INTERFACE, HardwareInterfaceError
from ..realtime_tools import PublishSchedule
from ..registry import controller_type


@dataclass
class ExtraJoint:
    ros_package: ClassVar[str] = "joint_state_controller"
    name: str
    position: float = param(0.0, finite=True)
    velocity: float = param(0.0, finite=True)
    effort: float = param(0.0, finite=True)


@dataclass
class JointStateControllerParams:
    ros_package: ClassVar[str] = "joint_state_controller"
    type: str
    publish_rate: float = param(gt=0)
    joints: list[str] | None = None
    extra_joints: list[ExtraJoint] = field(default_factory=list)
    topic: str = "joint_states"


@controller_type("joint_state_controller/JointStateController")
class JointStateController(Controller):
    hardware_interfaces = (JOINT_STATE_INTERFACE,)

    def init(self, hw, root_nh, controller_nh) -> bool:
        if not controller_nh.has_param("publish_rate"):
            return self.fail(
                f"Parameter 'publish_rate' not set: "
                f"'{controller_nh.namespace}/publish_rate' is required (messages per second)"
            )
        try:
            params = controller_nh.typed_params(JointStateControllerParams)
        except ParamError as error:
            return self.fail(str(error))
        joints = list(hw.joints_of(JOINT_STATE_INTERFACE)) if params.joints is None else params.joints
        try:
            for j in joints:
                hw.get_handle(JOINT_STATE_INTERFACE, j)
        except HardwareInterfaceError as error:
            return self.fail(f"Parameter '{controller_nh.namespace}/joints': {error}")
        self.hw = hw
        self.index = np.array([hw.joint_index(j) for j in joints], dtype=int)
        extra = [e for e in params.extra_joints if e.name not in joints]
        self.names = joints + [e.name for e in extra]
        self.extra = np.array([[e.position, e.velocity, e.effort] for e in extra]).reshape(-1, 3)
        self.schedule = PublishSchedule(params.publish_rate)
        self.publisher = root_nh.create_realtime_publisher(params.topic, "sensor_msgs/JointState")
        self._msg_class = msg_class("sensor_msgs/JointState")
        self._seq = 0
        return True

    def starting(self, time: float) -> None:
        self.schedule.start(time)

    def update(self, time: float, period: float) -> None:
        if not self.schedule.is_due(time, period):
            return
        i, hw, extra = self.index, self.hw, self.extra
        if extra.size:
            position = np.concatenate([hw.position[i], extra[:, 0]])
            velocity = np.concatenate([hw.velocity[i], extra[:, 1]])
            effort = np.concatenate([hw.effort[i], extra[:, 2]])
        else:  # fancy indexing copies: the message owns its arrays
            position, velocity, effort = hw.position[i], hw.velocity[i], hw.effort[i]
        self.publisher.publish_built(self._build, time, self._seq, position, velocity, effort)
        self._seq += 1

    def _build(self, time, seq, position, velocity, effort):
        """The message, built outside the real-time cycle (RealtimePublisher)."""
        return self._msg_class(
            header=header("", time, seq),
            name=list(self.names),
            position=position,
            velocity=velocity,
            effort=effort,
        )
