"""twil_control/CartLinearizingController: the paper's ``cart_linearizing_controller`` for TWIL + WAM.

One MIMO controller (the paper's section 4; ros_control assumes SISO ones): one update() drives
the two wheels and the seven arm joints on the EffortJointInterface, because the platform law,
its feedback linearisation and the arm's computed torque all need the whole robot's state.
The update's seven steps, the parameters and the command are in docs/cart_controller.md; the
update itself is one compiled call (control/cart_kernel.cart_step).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, make_dataclass

import numpy as np

from twil_control.control import cart_kernel
from twil_control.control.backstepping import (
    GAIN_NAMES,
    LAWS,
    BacksteppingLaw,
    backstepping_state,
    validate_gains,
)
from twil_control.control.diff_odometry import odometry_step
from twil_control.control.platform_model import IDENTIFIED, PlatformConstants
from twil_control.control.transforms import yaw_from_quat
from twil_control.core.messages import header, msg_class
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

TYPE_NAME = "twil_control/CartLinearizingController"
COMMAND_TYPE = "twil_control/CartLinearizingCommand"
STATUS_TYPE = "twil_control/CartLinearizingStatus"
POSE_SOURCES = ("odometry", "ground_truth")
PLATFORM_CONSTANTS = ("derived", "identified")  # K5..K8 from the description, or the lab's
ARM_JOINTS = [f"wam_joint_{i}" for i in range(1, 8)]


#: the backstepping gains (27)-(28), (43), (46)-(47), each a required finite number > 0
GainParams = make_dataclass("GainParams", [(name, float, param(gt=0)) for name in GAIN_NAMES])


@dataclass
class CartLinearizingParams:
    type: str
    gains: GainParams  # pyright: ignore[reportInvalidTypeForm] (a dataclass made from GAIN_NAMES)
    left_wheel_joint: str = "left_wheel_joint"
    right_wheel_joint: str = "right_wheel_joint"
    arm_joints: list[str] = param(factory=lambda: list(ARM_JOINTS), nonempty=True)
    wheel_radius: float = param(0.075, gt=0)
    wheel_separation: float = param(0.322, gt=0)
    law: str = param("corrected", choices=LAWS)
    goal_tolerance: float = param(0.005, ge=0)
    pose_source: str = param("odometry", choices=POSE_SOURCES)
    model: str = "twil_wam"
    base_link: str = "base_link"
    kp: float | list[float] = gains_param(25.0)
    kd: float | list[float] = gains_param(10.0)
    status_rate: float = param(100.0, gt=0)
    wheel_effort_limit: float | None = param(None, gt=0)  # N m; None: the plant's actuator limits
    reference_timeout: float = param(0.1, ge=0)
    platform_constants: str = param("derived", choices=PLATFORM_CONSTANTS)


def _given_constants(p: CartLinearizingParams) -> tuple | None:
    """The lab's identified K5..K8 with platform_constants identified; None: derive them."""
    k = IDENTIFIED
    return (k.K5, k.K6, k.K7, k.K8) if p.platform_constants == "identified" else None


@controller_type(TYPE_NAME)
class CartLinearizingController(Controller):
    hardware_interfaces = (EFFORT_JOINT_INTERFACE,)

    def init(self, hw: RobotHW, root_nh: ControllerNodeHandle, controller_nh: ControllerNodeHandle) -> bool:
        from twil_control.world.platform_dynamics import PlatformMassModel, PlatformModelError

        try:
            p = controller_nh.typed_params(CartLinearizingParams)
            self.gains = validate_gains(asdict(p.gains))
            wheels = [p.right_wheel_joint, p.left_wheel_joint]
            joints = wheels + list(p.arm_joints)
            if len(set(joints)) != len(joints):
                return self.fail(f"{self.name}: a joint is named twice in {joints}")
            for j in joints:
                hw.get_handle(EFFORT_JOINT_INTERFACE, j)
            n = len(p.arm_joints)
            self.kp = per_joint(controller_nh, "kp", p.kp, p.arm_joints)
            self.kd = per_joint(controller_nh, "kd", p.kd, p.arm_joints)
            sim = hw.simulation
            self.model = PlatformMassModel(p.model, list(p.arm_joints), wheels, base_link=p.base_link)
            if sim is not None:  # the simulated plant's gravity, so model and plant agree exactly
                self.model.set_gravity(sim.plant.gravity_field().gravity_vector())
            if p.pose_source == "ground_truth":
                if sim is None:
                    return self.fail(
                        f"{self.name}: pose_source ground_truth needs the simulated hardware "
                        "(a Drake plant); use pose_source odometry"
                    )
                plant = sim.plant
                bodies = [
                    plant.GetBodyByName(p.base_link, i)
                    for i in sim.instances
                    if plant.HasBodyNamed(p.base_link, i)
                ]
                if not bodies or not bodies[0].is_floating_base_body():
                    return self.fail(f"{self.name}: no free body '{p.base_link}' in the simulated model")
                self._pose_q = bodies[0].floating_positions_start()
                self._pose_v = plant.num_positions() + bodies[0].floating_velocities_start_in_v()
            if p.wheel_effort_limit is not None:
                self.wheel_limit = float(p.wheel_effort_limit)
            else:
                self.wheel_limit = float(min(hw.effort_limit[hw.joint_index(j)] for j in wheels))
        except ParamError as error:  # names the parameter and where it was set
            return self.fail(str(error))
        except (HardwareInterfaceError, PlatformModelError, ValueError, KeyError) as error:
            return self.fail(f"{self.name}: {error}")
        self.params = p
        self.hw = hw
        self._sim = hw.simulation
        self.n = n
        self.r, self.b = p.wheel_radius, p.wheel_separation / 2.0
        self.platform_law = BacksteppingLaw(self.gains, law=p.law, goal_tolerance=p.goal_tolerance)
        self._iw = np.array([hw.joint_index(j) for j in wheels])  # [right, left]
        self._ia = np.array([hw.joint_index(j) for j in p.arm_joints])
        self._effort = hw.command(EFFORT_JOINT_INTERFACE)
        zero = np.zeros(n)
        self.reference: RealtimeBuffer[tuple] = RealtimeBuffer(((0.0, 0.0, 0.0), zero, zero, zero, 0.0))
        self._now = controller_nh.now
        # the compiled update's arrays (control/cart_kernel.py); the properties below read them
        self._planar = p.pose_source == "odometry"
        model = self.model
        out = self._out = np.zeros(cart_kernel.out_size(n))
        self._out_v, self._out_tau, self._out_tau_raw = (
            out[i : i + 2] for i in (cart_kernel.OUT_V, cart_kernel.OUT_TAU, cart_kernel.OUT_TAU_RAW)
        )
        self._inp = np.zeros(cart_kernel.IN_SIZE)  # the pose (property `pose`) is in it
        self._inp[cart_kernel.IN_PLANAR] = 1.0 if self._planar else 0.0
        self._odometry = np.zeros(cart_kernel.ODO_SIZE)  # (0, 0, 0) where first started
        self._params = cart_kernel.step_params(
            self.r,
            self.b,
            model.wheel_inertia,
            self.wheel_limit,
            self.platform_law.tolerance,
            p.reference_timeout,
            self.platform_law.law,
            _given_constants(p),
            self.gains.vector,
            self.kp,
            self.kd,
        )
        x, q_base, v_base, arm_qx, arm_vx = model.layout
        self._x, self._q_base, self._v_base = x, q_base, v_base
        self._arm_v = arm_vx - model.plant.num_positions()  # the arm's rows of tau
        self._index = cart_kernel.step_index(
            q_base, v_base, v_base - model.plant.num_positions(), self._iw, arm_qx, arm_vx, self._ia
        )
        self._step_arrays = (
            self._odometry,
            x,
            model.kernel.tree,
            model.kernel.extra,
            model.work,
            model.M,
            model.vdot,
            model.tau,
            out,
            self._effort,
        )
        self.topic = controller_nh.resolve("command")
        self.burst = BurstLog(self)
        controller_nh.create_subscription("command", COMMAND_TYPE, self.command_cb)
        self.status_pub = controller_nh.create_realtime_publisher("status", STATUS_TYPE)
        self._status_cls = msg_class(STATUS_TYPE)
        self._status_period = 1.0 / p.status_rate
        self._due = 0.0
        self._seq = 0
        return True

    # -- command ---------------------------------------------------------------------------
    def command_cb(self, msg) -> None:
        pose = (float(msg.platform_pose.x), float(msg.platform_pose.y), float(msg.platform_pose.theta))
        if not all(math.isfinite(v) for v in pose):
            self.burst.bad(
                f"refusing command on {self.topic}: non-finite platform_pose {pose}; "
                "keeping the previous reference"
            )
            return
        fields = joint_reference_fields(
            msg,
            ("arm_positions", "arm_velocities", "arm_accelerations"),
            self.params.arm_joints,
            self.topic,
            self.burst,
        )
        if fields is None:
            return
        fields = tuple(
            np.array(f, dtype=float) for f in fields
        )  # writable copies: the compiled update's types
        self.burst.good()
        stamp = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
        self.reference.write_from_non_rt((pose, *fields, stamp if stamp > 0.0 else self._now()))

    def set_reference(self, pose, q_r, qd_r=None, qdd_r=None, stamp: float | None = None) -> None:
        """Set the reference directly (tests, other in-process users); stamp None = now."""
        zero = np.zeros(self.n)
        self.reference.write_from_non_rt(
            (
                tuple(float(v) for v in pose),
                np.array(q_r, dtype=float),
                zero if qd_r is None else np.array(qd_r, dtype=float),
                zero if qdd_r is None else np.array(qdd_r, dtype=float),
                self._now() if stamp is None else float(stamp),
            )
        )

    # -- pose ------------------------------------------------------------------------------
    @property
    def pose(self) -> tuple[float, float, float]:
        """The platform pose (x, y, theta) of the last update."""
        inp = self._inp
        return float(inp[0]), float(inp[1]), float(inp[2])

    # -- real-time loop --------------------------------------------------------------------
    def _read_pose(self) -> None:
        """With ground truth, the base's true state into x and its pose into `_inp` (the
        odometry is integrated inside the compiled update)."""
        assert self._sim is not None  # init refuses ground_truth without the simulated hardware
        q = self._sim.plant_state
        i, j = self._pose_q, self._pose_v
        self._x[self._q_base : self._q_base + 7] = q[i : i + 7]
        self._x[self._v_base : self._v_base + 6] = q[j : j + 6]
        w, x, y, z = q[i], q[i + 1], q[i + 2], q[i + 3]
        self._inp[0], self._inp[1], self._inp[2] = q[i + 4], q[i + 5], yaw_from_quat((x, y, z, w))

    def starting(self, time: float) -> None:
        zero = np.zeros(self.n)
        arm = self.hw.position[self._ia].copy()
        if self._planar:  # the odometry frame starts at (0, 0, 0) where first started
            position = self.hw.position
            odometry_step(self._odometry, position[self._iw[1]], position[self._iw[0]], self.r, 2.0 * self.b)
            self._inp[:3] = self._odometry[:3]
        else:
            self._read_pose()
        self.reference.init_rt((self.pose, arm, zero, zero, time))
        self._due = time

    def update(self, time: float, period: float) -> None:
        # one compiled call does everything but the ground-truth pose and the status (cart_step)
        pose_ref, q_s, qd_s, qdd_s, stamp = self.reference.read_from_rt()
        inp = self._inp
        inp[3], inp[4], inp[5] = pose_ref
        inp[6] = time - stamp
        if not self._planar:
            self._read_pose()
        hw = self.hw
        cart_kernel.cart_step(
            inp, self._params, self._index, hw.position, hw.velocity, q_s, qd_s, qdd_s, *self._step_arrays
        )
        if time >= self._due - 0.5 * period:
            self._publish_status(time, period, pose_ref)

    def _publish_status(self, time: float, period: float, pose_ref) -> None:
        self._due += self._status_period
        if self._due + 0.5 * period <= time:
            self._due = time + self._status_period
        # two copies here; the message is built outside the cycle from them (_status)
        self.status_pub.publish_built(
            self._status, time, self._seq, self.pose, pose_ref, self._out.copy(), self.model.tau.copy()
        )
        self._seq += 1

    # -- the last update's results (views of the arrays the update writes) ---------------------
    @property
    def u(self) -> tuple[float, float]:
        """Platform velocity (u1, u2) from the wheel rates."""
        return float(self._out[cart_kernel.OUT_U]), float(self._out[cart_kernel.OUT_U + 1])

    @property
    def v(self) -> np.ndarray:
        """The backstepping law's (v1, v2)."""
        return self._out_v

    @property
    def tau_platform(self) -> np.ndarray:
        """Wheel torques [right, left] applied (after the saturation scaling)."""
        return self._out_tau

    @property
    def tau_platform_raw(self) -> np.ndarray:
        """The feedback-linearised pair before scaling."""
        return self._out_tau_raw

    @property
    def torque_scale(self) -> float:
        return float(self._out[cart_kernel.OUT_SCALE])

    @property
    def tau_arm(self) -> np.ndarray:
        """Arm joint torques (a copy)."""
        return self.model.tau[self._arm_v]

    @property
    def platform_constants(self) -> PlatformConstants:
        """K5..K8 of the last update (derived at the arm's pose, or the identified ones)."""
        return PlatformConstants(*self._out[cart_kernel.OUT_K : cart_kernel.OUT_K + 4])

    def stopping(self, time: float) -> None:
        self._effort[self._iw] = 0.0
        self._effort[self._ia] = 0.0

    def _status(self, time, seq, pose, pose_ref, out, tau):
        """The status message, built outside the real-time cycle (RealtimePublisher) from the
        copies of the update's `_out` and the model's tau."""
        u = (float(out[cart_kernel.OUT_U]), float(out[cart_kernel.OUT_U + 1]))
        try:
            st = backstepping_state(pose, pose_ref, u, self.gains)
            vals = dict(
                e=st.e,
                psi=st.psi,
                alpha=st.alpha,
                e1=st.e1,
                e2=st.e2,
                V1=st.V1,
                V1_dot_predicted=st.V1dot_pred,
            )
        except ValueError:
            vals = {k: math.nan for k in ("e", "psi", "alpha", "e1", "e2", "V1", "V1_dot_predicted")}
        return self._status_cls(
            header=header("", time, seq),
            **vals,
            u1=u[0],
            u2=u[1],
            tau_right=float(out[cart_kernel.OUT_TAU]),
            tau_left=float(out[cart_kernel.OUT_TAU + 1]),
            torque_scale=float(out[cart_kernel.OUT_SCALE]),
            arm_torques=tau[self._arm_v],
            x=float(pose[0]),
            y=float(pose[1]),
            theta=float(pose[2]),
        )


__all__ = ["CartLinearizingController", "CartLinearizingParams", "TYPE_NAME", "GAIN_NAMES"]
