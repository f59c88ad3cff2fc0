"""gazebo_ros_control's role: the hardware adapter and the controller manager for one robot.

Lives in the robot's control namespace (e.g. /twil/ros_control): the controller manager's
services are <ns>/controller_manager/..., controllers read their params from <ns>/<name>.
Private params (~): the spawned ``model``, the ``control_period`` and the ``joints`` with their
interfaces, e.g. ``wam_joint_1: {interfaces: [effort, position], pid: {p: 100.0, d: 10.0}}``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from twil_control.errors import InputError

from ..core.ros_node import RosNode
from .model_param import model_instances


@dataclass
class RobotHWSimParams:
    model: str
    joints: dict = field(default_factory=dict)  # joint -> JointConfig (checked in __init__)
    control_period: float = 0.001

    def __post_init__(self) -> None:
        if not (self.control_period > 0 and math.isfinite(self.control_period)):
            raise InputError(
                f"control_period must be a positive number of seconds (got {self.control_period})"
            )
        if not self.joints:
            raise InputError("joints must declare at least one joint's transmission")


class RobotHWSimNode(RosNode):
    required_by_default = True

    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        from ..core.typed_params import load_typed
        from ..world.robot_hw_sim import JointConfig

        self.params = self.typed_params(RobotHWSimParams)
        base = self.resolve("~joints")
        self.joint_configs = {
            name: load_typed(self.master.params, f"{base}/{name}", JointConfig) for name in self.params.joints
        }
        self.hw = None
        self.manager = None
        self.system = None

    def build_world(self, sim) -> None:
        from ..world.robot_hw_sim import set_implicit_pd_gains

        set_implicit_pd_gains(sim.plant, self.joint_configs, self.fqn)  # before Finalize()

    def build_systems(self, sim) -> None:
        self.hw, self.manager, self.system = start_hardware(
            sim, self, self.params.model, self.joint_configs, self.params.control_period, self.fqn
        )


def start_hardware(sim, node, model: str, joint_configs: dict, period: float, label: str):
    """The hardware adapter of `model`'s joints, its controller manager (owned by, and
    advertising on, `node`) and the control loop system, run every `period` rounded up to whole
    plant steps as gazebo_ros_control runs it: (hw, manager, system)."""
    from ..ros_control.controller_manager import ControllerManager
    from ..world.robot_hw_sim import ControllerManagerSystem, DrakeRobotHW, control_update_period

    step = sim.config.time_step
    runs_at = control_update_period(period, step)
    if period < step * (1 - 1e-9):
        node.log.error(  # gazebo_ros_control's error, and what it then does
            "%s: desired controller update period (%g s) is faster than the simulation period "
            "(%g s): the controllers run once per physics step, with the step as their period",
            label,
            period,
            step,
        )
    elif abs(runs_at - period) > 1e-9 * period:
        node.log.warning(
            "%s: controller update period %g s is not a whole number of physics steps (%g s): the "
            "controllers run every %g s, as gazebo_ros_control runs them",
            label,
            period,
            step,
            runs_at,
        )
    hw = DrakeRobotHW(sim.plant, model_instances(node, sim, model), joint_configs, label)
    manager = ControllerManager(hw, node)
    system = sim.add_system(
        ControllerManagerSystem(sim, hw, manager, node.master.clock, runs_at), f"{label}/controller_manager"
    )
    return hw, manager, system
