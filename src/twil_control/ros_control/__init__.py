"""ros_control (ROS 1) replica: hardware_interface, controller_interface, controller_manager.

Pure Python, no Drake and no robotics math: the simulator provides a RobotHW subclass and calls
``ControllerManager.update(time, period)`` at the control rate; the controllers' math lives in
twil_control.control. What each part does and where it differs from ROS: docs/ros_control.md.
"""

from . import registry
from .controller_interface import (
    ABORTED,
    INITIALIZED,
    RUNNING,
    STATES,
    STOPPED,
    WAITING,
    Controller,
    ControllerLifecycle,
)
from .controller_manager import SERVICES, ControllerManager
from .hardware_interface import (
    COMMAND_INTERFACES,
    EFFORT_JOINT_INTERFACE,
    JOINT_STATE_INTERFACE,
    POSITION_JOINT_INTERFACE,
    VELOCITY_JOINT_INTERFACE,
    ControllerInfo,
    HardwareInterfaceError,
    InterfaceResources,
    JointHandle,
    JointStateHandle,
    RobotHW,
)
from .registry import ControllerTypeError, controller_type
from .srv import BEST_EFFORT, STRICT, ControllerState, ControllerStateInfo

__all__ = [
    "ABORTED",
    "BEST_EFFORT",
    "COMMAND_INTERFACES",
    "Controller",
    "ControllerLifecycle",
    "ControllerInfo",
    "ControllerManager",
    "ControllerState",
    "ControllerStateInfo",
    "ControllerTypeError",
    "EFFORT_JOINT_INTERFACE",
    "HardwareInterfaceError",
    "INITIALIZED",
    "InterfaceResources",
    "JOINT_STATE_INTERFACE",
    "JointHandle",
    "JointStateHandle",
    "POSITION_JOINT_INTERFACE",
    "RUNNING",
    "RobotHW",
    "SERVICES",
    "STATES",
    "STOPPED",
    "STRICT",
    "VELOCITY_JOINT_INTERFACE",
    "WAITING",
    "controller_type",
    "registry",
]
