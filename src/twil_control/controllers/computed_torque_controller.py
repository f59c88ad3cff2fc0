"""effort_controllers/ComputedTorqueController: the lab's WAM computed-torque controller, law (53).

The bracket comes from the pure law (control/computed_torque.py) and M a + C qd - tau_g from one
inverse-dynamics pass of a control model built from the same description as the simulated
plant, with the plant's own gravity: computed torque cancels the model only if the model is the
plant. Parameters, gravity and the command's second-order hold: docs/computed_torque.md.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from twil_control.control.computed_torque import ComputedTorqueLaw
from twil_control.control.trajectory import held_reference
from twil_control.core.param_rules import param
from twil_control.core.params import ParamError
from twil_control.ros_control.controller_interface import Controller, ControllerNodeHandle
from twil_control.ros_control.controllers.forward_command import BurstLog, joint_reference_fields
from twil_control.ros_control.hardware_interface import (
    EFFORT_JOINT_INTERFACE,
    HardwareInterfaceError,
    RobotHW,
)
from twil_control.ros_control.realtime_tools import RealtimeBuffer
from twil_control.ros_control.registry import controller_type

from .joint_gains import gains_param, per_joint

TYPE_NAME = "effort_controllers/ComputedTorqueController"
COMMAND_TYPE = "trajectory_msgs/JointTrajectoryPoint"


@dataclass
class ComputedTorqueParams:
    type: str
    joints: list[str] = param(nonempty=True)
    kp: float | list[float] = gains_param(25.0)
    kd: float | list[float] = gains_param(10.0)
    root_link: str = "wam_base_link"
    tip_link: str = "wam_link_7"
    model: str = "wam"
    reference_timeout: float = param(0.1, ge=0)


@controller_type(TYPE_NAME)
class ComputedTorqueController(Controller):
    hardware_interfaces = (EFFORT_JOINT_INTERFACE,)

    def init(self, hw: RobotHW, root_nh: ControllerNodeHandle, controller_nh: ControllerNodeHandle) -> bool:
        from twil_control.world.arm_dynamics import ArmControlModel, ArmModelError, plant_gravity_and_base

        try:
            p = controller_nh.typed_params(ComputedTorqueParams)
            self.handles = [hw.get_handle(EFFORT_JOINT_INTERFACE, j) for j in p.joints]
            n = len(p.joints)
            self.kp = per_joint(controller_nh, "kp", p.kp, p.joints)
            self.kd = per_joint(controller_nh, "kd", p.kd, p.joints)
            gravity, R_WB = plant_gravity_and_base(hw, p.root_link)
            self.model = ArmControlModel(p.model, p.joints, root_link=p.root_link, gravity=gravity, R_WB=R_WB)
            if not self.model.plant.HasBodyNamed(p.tip_link):
                return self.fail(f"{self.name}: tip_link '{p.tip_link}' is not a link of {p.model}")
        except ParamError as error:  # names the parameter and where it was set
            return self.fail(str(error))
        except (HardwareInterfaceError, ArmModelError, ValueError) as error:
            return self.fail(f"{self.name}: {error}")
        self.params = p
        self.n = n
        self.hw = hw
        self.law = ComputedTorqueLaw(n, self.kp, self.kd)
        idx = np.array([hw.joint_index(j) for j in p.joints])
        # a slice (a view, no copy) when the joints are contiguous in the hardware's order
        contiguous = bool(np.array_equal(idx, np.arange(idx[0], idx[0] + n)))
        self._idx = slice(int(idx[0]), int(idx[0]) + n) if contiguous else idx
        self.tau = np.zeros(n)
        self._effort = hw.command(EFFORT_JOINT_INTERFACE)
        zero = np.zeros(n)
        self.reference: RealtimeBuffer[tuple] = RealtimeBuffer((zero, zero, zero, 0.0, False))
        self._now = controller_nh.now
        self.topic = controller_nh.resolve("command")
        self.burst = BurstLog(self)
        controller_nh.create_subscription("command", COMMAND_TYPE, self.command_cb)
        return True

    # -- command ---------------------------------------------------------------------------
    def command_cb(self, msg) -> None:
        fields = joint_reference_fields(
            msg, ("positions", "velocities", "accelerations"), self.params.joints, self.topic, self.burst
        )
        if fields is None:
            return
        self.burst.good()
        self.set_reference(*fields)

    def set_reference(self, q_r, qd_r=None, qdd_r=None) -> None:
        """Set the reference directly (tests, other in-process users): a sample taken now."""
        zero = np.zeros(self.n)
        qd = zero if qd_r is None else np.asarray(qd_r, float)
        qdd = zero if qdd_r is None else np.asarray(qdd_r, float)
        self.reference.write_from_non_rt(
            (np.asarray(q_r, float), qd, qdd, self._now(), bool(qd.any() or qdd.any()))
        )

    def held_reference(self, time: float):
        """(q_r, qd_r, qdd_r) at `time`: the last sample held to second order (docs/computed_torque.md)."""
        q, qd, qdd, stamp, moving = self.reference.read_from_rt()
        if not moving:  # a step, or the pose held at start: nothing to extrapolate
            return q, qd, qdd
        return held_reference(q, qd, qdd, time - stamp, self.params.reference_timeout)

    # -- real-time loop --------------------------------------------------------------------
    def starting(self, time: float) -> None:
        zero = np.zeros(self.n)
        self.reference.init_rt((self.hw.position[self._idx].copy(), zero, zero, time, False))

    def update(self, time: float, period: float) -> None:
        q = self.hw.position[self._idx]
        qd = self.hw.velocity[self._idx]
        q_r, qd_r, qdd_r = self.held_reference(time)
        # (53) as inverse dynamics of the commanded acceleration: M a + C qd - tau_g
        self.tau = self.model.inverse_dynamics(q, qd, self.law.acceleration(q, qd, q_r, qd_r, qdd_r))
        self._effort[self._idx] = self.tau
