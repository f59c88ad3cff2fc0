"""twil_control/SkidSteerPwmController: qbot's drive (``gazebo_ros_skid_steer_drive``'s role) as a
ros_control controller, so the controller manager runs it every control period (1 kHz).

Framework glue only: cmd_vel through diff_drive_controller's limits, the qbot report's wheel
speeds, PWM and DC motor (the math in twil_control.control, one compiled call per update), or
an ideal PI wheel servo for comparison. The chain, the parameters and ~pwm_duty: docs/qbot.md.
Odometry is not published here: twil_control/wheel_odometry integrates /joint_states, as the
real robot would.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import cast

import numpy as np

from twil_control.control import dc_motor, skid_steer, skid_steer_kernel
from twil_control.control.pwm import PwmVelocityController
from twil_control.core.messages import msg_class
from twil_control.core.param_rules import param
from twil_control.core.params import ParamError
from twil_control.ros_control.controller_interface import Controller, ControllerNodeHandle
from twil_control.ros_control.controllers.diff_drive_controller import AngularLimits, LinearLimits
from twil_control.ros_control.controllers.forward_command import BurstLog
from twil_control.ros_control.hardware_interface import (
    EFFORT_JOINT_INTERFACE,
    HardwareInterfaceError,
    RobotHW,
)
from twil_control.ros_control.realtime_tools import RealtimeBuffer
from twil_control.ros_control.registry import controller_type

MODES = ("pwm", "ideal")


@dataclass
class IdealGains:
    """PI on wheel speed error (N m s/rad, N m/rad) for ``velocity_mode: ideal``."""

    p: float = param(0.2, ge=0)
    i: float = param(5.0, ge=0)
    i_clamp: float = param(5.0, ge=0)


@dataclass
class SkidSteerPwmParams:
    type: str
    left_wheel: list[str] = param(factory=lambda: ["left_front", "left_rear"], nonempty=True)
    right_wheel: list[str] = param(factory=lambda: ["right_front", "right_rear"], nonempty=True)
    wheel_separation: float = param(0.36, gt=0)  # the track width 2c
    wheel_radius: float = param(0.055, gt=0)  # the radius, not the diameter
    cmd_vel_topic: str = "/qbot/cmd_vel"
    cmd_vel_timeout: float = param(0.5, gt=0)  # s
    velocity_mode: str = param("pwm", choices=MODES)
    pwm_publish_rate: float = param(50.0, gt=0)  # Hz
    motor: dc_motor.DcMotorParams = field(default_factory=dc_motor.DcMotorParams)
    ideal: IdealGains = field(default_factory=IdealGains)
    linear: LinearLimits = field(default_factory=LinearLimits)
    angular: AngularLimits = field(default_factory=AngularLimits)


@controller_type("twil_control/SkidSteerPwmController")
class SkidSteerPwmController(Controller):
    hardware_interfaces = (EFFORT_JOINT_INTERFACE,)

    def init(self, hw: RobotHW, root_nh: ControllerNodeHandle, controller_nh: ControllerNodeHandle) -> bool:
        try:
            p = self.params = controller_nh.typed_params(SkidSteerPwmParams)
            self.motor = p.motor
            self.left = [hw.get_handle(EFFORT_JOINT_INTERFACE, j) for j in p.left_wheel]
            self.right = [hw.get_handle(EFFORT_JOINT_INTERFACE, j) for j in p.right_wheel]
            self.limit_v = p.linear.x.limiter()
            self.limit_w = p.angular.z.limiter()
        except (ParamError, HardwareInterfaceError, ValueError) as error:
            return self.fail(str(error))
        self.node = controller_nh.node
        self.r, self.c = p.wheel_radius, p.wheel_separation / 2.0
        vmax = self.motor.max_voltage
        self.pwm = (PwmVelocityController(vmax, -vmax), PwmVelocityController(vmax, -vmax))
        # (v, w, stamp); stamp None = no command yet
        self.command_buffer: RealtimeBuffer[tuple] = RealtimeBuffer((0.0, 0.0, None))
        self.topic = controller_nh.resolve(p.cmd_vel_topic)
        self.burst = BurstLog(self)
        controller_nh.create_subscription(p.cmd_vel_topic, "geometry_msgs/Twist", self.cmd_vel_cb)
        self.duty_pub = controller_nh.create_realtime_publisher("pwm_duty", "std_msgs/UInt8MultiArray")
        self._duty_msg = msg_class("std_msgs/UInt8MultiArray")
        self._layout = msg_class("std_msgs/MultiArrayLayout")
        self._joints = self.left + self.right
        self._side = np.array([0] * len(self.left) + [1] * len(self.right))
        # the compiled PWM drive (control/skid_steer_kernel.py): the limiters', motor's and PWM's
        # settings as arrays; the ideal mode uses the objects (the same functions inside)
        self._hw_joints = np.array([hw.joint_index(j) for j in p.left_wheel + p.right_wheel])
        self._velocity, self._effort = hw.velocity, hw.command(EFFORT_JOINT_INTERFACE)
        self._limits = np.array([self.limit_v.row, self.limit_w.row])
        self._history = np.zeros((2, 2))
        self._motor = skid_steer_kernel.motor_row(self.motor)
        pwm = self.pwm[0]
        self._pwm_shape = (pwm.period_ticks, pwm.v_high, pwm.v_low)
        self._out = np.zeros(skid_steer_kernel.OUT_SIZE)
        self._integral = np.zeros(len(self._joints))
        self._next_pub = 0.0
        #: the last limited command (v, w) and wheel targets (left, right) in rad/s, for tests
        self.limited = (0.0, 0.0)
        self.targets = (0.0, 0.0)
        return True

    # -- non-real-time side --------------------------------------------------------------
    def cmd_vel_cb(self, msg) -> None:
        v, w = float(msg.linear.x), float(msg.angular.z)
        if not (math.isfinite(v) and math.isfinite(w)):
            self.burst.bad(
                f"ignoring non-finite cmd_vel (linear.x={v}, angular.z={w}) on {self.topic}; "
                "keeping the previous command"
            )
            return
        self.burst.good()
        self.command_buffer.write_from_non_rt((v, w, self.node.now()))

    # -- real-time side ------------------------------------------------------------------
    def starting(self, time: float) -> None:
        self.command_buffer.init_rt((0.0, 0.0, None))
        self.limit_v.reset(0.0)
        self.limit_w.reset(0.0)
        self._history[:] = 0.0
        self._integral[:] = 0.0
        self._next_pub = time

    def stopping(self, time: float) -> None:
        for joint in self.left + self.right:
            joint.set_command(0.0)

    def update(self, time: float, period: float) -> None:
        p = self.params
        v, w, stamp = self.command_buffer.read_from_rt()
        if stamp is None or time - stamp > p.cmd_vel_timeout:
            v, w = 0.0, 0.0  # brake: diff_drive_controller's cmd_vel_timeout
        if p.velocity_mode == "pwm":
            out = self._out
            skid_steer_kernel.pwm_drive(
                v,
                w,
                period,
                self._limits,
                self._history,
                self.r,
                self.c,
                self._motor,
                *self._pwm_shape,
                self._side,
                self._hw_joints,
                self._velocity,
                self._effort,
                out,
            )
            self.limited, self.targets = (out[0], out[1]), (out[2], out[3])
            self._publish_duty(time, period, int(out[4]), int(out[5]))
            return
        self._ideal_update(time, period, v, w)

    def _ideal_update(self, time: float, period: float, v: float, w: float) -> None:
        """velocity_mode ideal (a PI wheel servo, for comparison), through the Python API of the
        drive chain's equations (the functions the compiled PWM drive composes)."""
        p = self.params
        v = self.limit_v.step(v, period)
        w = self.limit_w.step(w, period)
        self.limited = (v, w)
        w_left, w_right = skid_steer.wheel_speeds(v, w, self.r, self.c)
        self.targets = (w_left, w_right)
        # One vectorised motor-model call per update (this runs every millisecond).
        volts = cast(np.ndarray, dc_motor.voltage_for_speed(np.array([w_left, w_right]), 0.0, self.motor))
        for side in (0, 1):
            self.pwm[side].set_velocity(float(volts[side]) / self.motor.max_voltage)  # saturates
        joints = self._joints
        speeds = np.array([joint.velocity for joint in joints])
        error = np.where(self._side == 0, w_left, w_right) - speeds
        self._integral = np.clip(
            self._integral + p.ideal.i * error * period, -p.ideal.i_clamp, p.ideal.i_clamp
        )
        tau = p.ideal.p * error + self._integral
        for joint, effort in zip(joints, tau.tolist()):
            joint.set_command(effort)
        self._publish_duty(time, period, self.pwm[0].duty, self.pwm[1].duty)

    def _publish_duty(self, time: float, period: float, left: int, right: int) -> None:
        rate = self.params.pwm_publish_rate
        if time >= self._next_pub - 0.5 * period:
            self._next_pub += 1.0 / rate
            if self._next_pub < time:
                self._next_pub = time + 1.0 / rate
            self.duty_pub.publish_built(self._duty, left, right)

    def _duty(self, left: int, right: int):
        """~pwm_duty, built after the control cycle (RealtimePublisher)."""
        return self._duty_msg(
            layout=self._layout(dim=[], data_offset=0), data=np.array([left, right], dtype=np.uint8)
        )
