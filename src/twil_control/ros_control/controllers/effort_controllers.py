"""effort_controllers/JointPositionController (ros_controllers, ROS 1): PID from position to effort.

The error rate is differentiated numerically, as ROS does for a position-only command; a
non-finite target is refused and the previous one kept. Not replicated: URDF joint limits and
angle wrapping (the simulator enforces limits) and the state topic (docs/ros_control.md).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from twil_control.control.pid import Pid
from twil_control.core.param_rules import param
from twil_control.core.params import ParamError

from ..controller_interface import Controller
from ..hardware_interface import EFFORT_JOINT_INTERFACE, HardwareInterfaceError
from ..registry import controller_type
from .forward_command import Float64Command


@dataclass
class PidParams:
    ros_package: ClassVar[str] = "effort_controllers"
    p: float = param(finite=True)
    i: float = param(0.0, finite=True)
    d: float = param(0.0, finite=True)
    i_clamp: float = param(0.0, finite=True)
    i_clamp_min: float | None = param(None, finite=True)
    i_clamp_max: float | None = param(None, finite=True)
    antiwindup: bool = False
    publish_state: bool = False


@dataclass
class JointPositionParams:
    ros_package: ClassVar[str] = "effort_controllers"
    type: str
    joint: str
    pid: PidParams


@controller_type("effort_controllers/JointPositionController")
class JointPositionController(Controller):
    hardware_interfaces = (EFFORT_JOINT_INTERFACE,)

    def init(self, hw, root_nh, controller_nh) -> bool:
        try:
            params = controller_nh.typed_params(JointPositionParams)
            self.joint = hw.get_handle(EFFORT_JOINT_INTERFACE, params.joint)
            g = params.pid
            self.pid = Pid(g.p, g.i, g.d, g.i_clamp, g.antiwindup, i_min=g.i_clamp_min, i_max=g.i_clamp_max)
        except (ParamError, HardwareInterfaceError, ValueError) as error:
            return self.fail(str(error))
        self.command = Float64Command(self, controller_nh, "position command")
        return True

    def set_command(self, position: float) -> None:
        """JointPositionController::setCommand."""
        self.command.buffer.write_from_non_rt(float(position))

    def starting(self, time: float) -> None:
        self.command.buffer.init_rt(self.joint.position)
        self.pid.reset()

    def update(self, time: float, period: float) -> None:
        error = self.command.buffer.read_from_rt() - self.joint.position
        self.joint.set_command(self.pid.compute_command_from_error(error, period))
