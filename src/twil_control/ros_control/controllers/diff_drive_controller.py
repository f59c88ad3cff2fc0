"""diff_drive_controller/DiffDriveController (ros_controllers, ROS 1 Noetic): a differential or
skid-steer base on the VelocityJointInterface, its odometry from the wheel encoders.

Framework glue only: wheel speeds, speed limits and odometry are control/'s, composed into one
compiled call per update (control.diff_drive_kernel). ROS's parameter names and defaults,
wheel geometry read from the URDF when absent, as ROS does; the parameters and topics:
docs/ros_control.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from twil_control.control import diff_drive_kernel
from twil_control.control.diff_odometry import WheelOdometry, raise_for
from twil_control.control.speed_limiter import SpeedLimiter
from twil_control.control.transforms import quat_from_yaw
from twil_control.core.messages import header, msg_class
from twil_control.core.odometry_msg import odometry_msg
from twil_control.core.params import ParamError
from twil_control.core.tf import transform_stamped
from twil_control.errors import InputError

from ..controller_interface import RUNNING, Controller
from ..hardware_interface import VELOCITY_JOINT_INTERFACE, HardwareInterfaceError
from ..realtime_tools import PublishSchedule, RealtimeBuffer
from ..registry import controller_type


@dataclass
class LimitParams:
    """diff_drive_controller's per-axis limits (``linear/x`` or ``angular/z``)."""

    ros_package: ClassVar[str] = "diff_drive_controller"

    has_velocity_limits: bool = False
    max_velocity: float = 0.0
    min_velocity: float | None = None
    has_acceleration_limits: bool = False
    max_acceleration: float = 0.0
    min_acceleration: float | None = None
    has_jerk_limits: bool = False
    max_jerk: float = 0.0
    min_jerk: float | None = None

    def limiter(self) -> SpeedLimiter:
        return SpeedLimiter(
            self.has_velocity_limits,
            self.has_acceleration_limits,
            self.min_velocity,
            self.max_velocity,
            self.min_acceleration,
            self.max_acceleration,
            has_jerk_limits=self.has_jerk_limits,
            min_jerk=self.min_jerk,
            max_jerk=self.max_jerk,
        )


@dataclass
class LinearLimits:
    ros_package: ClassVar[str] = "diff_drive_controller"
    x: LimitParams = field(default_factory=LimitParams)


@dataclass
class AngularLimits:
    ros_package: ClassVar[str] = "diff_drive_controller"
    z: LimitParams = field(default_factory=LimitParams)


def _covariance_default() -> list[float]:
    return [1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3]


@dataclass
class DiffDriveParams:
    ros_package: ClassVar[str] = "diff_drive_controller"
    type: str
    left_wheel: Any
    right_wheel: Any
    wheel_separation: float | None = None
    wheel_radius: float | None = None
    wheel_separation_multiplier: float = 1.0
    wheel_radius_multiplier: float = 1.0
    left_wheel_radius_multiplier: float | None = None
    right_wheel_radius_multiplier: float | None = None
    publish_rate: float = 50.0
    cmd_vel_timeout: float = 0.5
    base_frame_id: str = "base_link"
    odom_frame_id: str = "odom"
    enable_odom_tf: bool = True
    open_loop: bool = False
    velocity_rolling_window_size: int = 10
    pose_covariance_diagonal: list[float] = field(default_factory=_covariance_default)
    twist_covariance_diagonal: list[float] = field(default_factory=_covariance_default)
    publish_cmd: bool = False
    allow_multiple_cmd_vel_publishers: bool = True
    publish_wheel_joint_controller_state: bool = False
    linear: LinearLimits = field(default_factory=LinearLimits)
    angular: AngularLimits = field(default_factory=AngularLimits)


def _joints(value: Any, name: str) -> list[str]:
    joints = [value] if isinstance(value, str) else value
    if not (isinstance(joints, list) and joints and all(isinstance(j, str) for j in joints)):
        raise InputError(f"'{name}' must be a joint name or a non-empty list of them (got {value!r})")
    return joints


def _search_param(nh, name: str):
    """ros::NodeHandle::searchParam: ``name`` in the handle's namespace, then its parents'."""
    parts = [p for p in nh.namespace.split("/") if p]
    for depth in range(len(parts), -1, -1):
        key = "/" + "/".join(parts[:depth] + [name])
        if nh.node.master.params.has(key):
            return nh.node.master.params.get(key)
    return None


def wheel_geometry_from_urdf(urdf: str, left: str, right: str) -> tuple[float, float]:
    """(separation, radius) as diff_drive_controller reads them from the URDF."""
    from twil_control.description.urdf import parse_urdf

    description = parse_urdf(urdf, "robot_description")
    lj = description.joint(left, "diff_drive_controller left_wheel")
    rj = description.joint(right, "diff_drive_controller right_wheel")
    separation = math.dist(lj.xyz, rj.xyz)
    link = description.links[lj.child].element
    for shape in ("cylinder", "sphere"):
        found = link.find(f"collision/geometry/{shape}") if link is not None else None
        radius = found.get("radius") if found is not None else None
        if radius:
            return separation, float(radius)
    raise InputError(
        f"wheel link {lj.child!r} has no collision cylinder or sphere to read the wheel "
        f"radius from: set 'wheel_radius'"
    )


@controller_type("diff_drive_controller/DiffDriveController")
class DiffDriveController(Controller):
    hardware_interfaces = (VELOCITY_JOINT_INTERFACE,)

    def init(self, hw, root_nh, controller_nh) -> bool:
        try:
            p = self.params = controller_nh.typed_params(DiffDriveParams)
            left, right = _joints(p.left_wheel, "left_wheel"), _joints(p.right_wheel, "right_wheel")
            self.left = [hw.get_handle(VELOCITY_JOINT_INTERFACE, j) for j in left]
            self.right = [hw.get_handle(VELOCITY_JOINT_INTERFACE, j) for j in right]
            separation, radius = p.wheel_separation, p.wheel_radius
            if separation is None or radius is None:
                urdf = _search_param(controller_nh, "robot_description")
                if not isinstance(urdf, str):
                    raise InputError(
                        "wheel_separation / wheel_radius are not set and no "
                        "robot_description parameter holds a URDF to read them from"
                    )
                from_urdf = wheel_geometry_from_urdf(urdf, left[0], right[0])
                separation = from_urdf[0] if separation is None else separation
                radius = from_urdf[1] if radius is None else radius
            sides = (p.left_wheel_radius_multiplier, p.right_wheel_radius_multiplier)
            multipliers = {m for m in sides if m is not None}
            if len(multipliers) > 1:
                raise InputError(
                    "left_wheel_radius_multiplier and right_wheel_radius_multiplier differ; "
                    "this odometry takes one wheel radius"
                )
            radius *= multipliers.pop() if multipliers else p.wheel_radius_multiplier
            separation *= p.wheel_separation_multiplier
            self.separation, self.radius = separation, radius
            self.odometry = WheelOdometry(radius, separation, p.velocity_rolling_window_size)
            self.limit_lin, self.limit_ang = p.linear.x.limiter(), p.angular.z.limiter()
            for label in ("pose_covariance_diagonal", "twist_covariance_diagonal"):
                if len(getattr(p, label)) != 6:
                    raise InputError(f"'{label}' needs 6 values (got {getattr(p, label)})")
            if not (p.publish_rate > 0 and p.cmd_vel_timeout > 0):
                raise InputError(
                    f"publish_rate and cmd_vel_timeout must be > 0 (got {p.publish_rate}, "
                    f"{p.cmd_vel_timeout})"
                )
        except (ParamError, HardwareInterfaceError, ValueError) as error:
            return self.fail(str(error))
        self.node = controller_nh.node
        self.hw = hw
        self._left_i = np.array([hw.joint_index(j) for j in left], dtype=np.int64)
        self._right_i = np.array([hw.joint_index(j) for j in right], dtype=np.int64)
        # the compiled update's arrays (control/diff_drive_kernel.py)
        self._command = hw.command(VELOCITY_JOINT_INTERFACE)
        self._limits = np.array([self.limit_lin.row, self.limit_ang.row])
        self._history = np.zeros((2, 2))
        self._out = np.zeros(diff_drive_kernel.OUT_SIZE)
        self.command: RealtimeBuffer[tuple] = RealtimeBuffer((0.0, 0.0, None))  # (lin, ang, stamp)
        self.schedule = PublishSchedule(p.publish_rate)
        self.topic = controller_nh.resolve("cmd_vel")
        controller_nh.create_subscription("cmd_vel", "geometry_msgs/Twist", self._on_cmd_vel)
        self.odom_pub = controller_nh.create_realtime_publisher("odom", "nav_msgs/Odometry")
        self.tf_pub = (
            controller_nh.create_realtime_publisher("/tf", "tf2_msgs/TFMessage") if p.enable_odom_tf else None
        )
        self.cmd_pub = (
            controller_nh.create_realtime_publisher("cmd_vel_out", "geometry_msgs/TwistStamped")
            if p.publish_cmd
            else None
        )
        self._pose_cov = np.diag(p.pose_covariance_diagonal).reshape(36).astype(float)
        self._twist_cov = np.diag(p.twist_covariance_diagonal).reshape(36).astype(float)
        return True

    @property
    def limited(self) -> tuple[float, float]:
        """The last limited command (v, w)."""
        return float(self._out[0]), float(self._out[1])

    def _on_cmd_vel(self, msg) -> None:
        if self.state != RUNNING:
            self.log.error("%s: Can't accept new commands. Controller is not running.", self.name)
            return
        lin, ang = float(msg.linear.x), float(msg.angular.z)
        if not (math.isfinite(lin) and math.isfinite(ang)):
            self.log.error("%s: Received NaN in velocity command. Ignoring. (on %s)", self.name, self.topic)
            return
        self.command.write_from_non_rt((lin, ang, self.node.now()))

    def starting(self, time: float) -> None:
        self._brake()
        self._history[:] = 0.0  # the limiters' history: at rest
        self.schedule.start(time)
        self.odometry.reset(self.odometry.x, self.odometry.y, self.odometry.heading)

    def stopping(self, time: float) -> None:
        self._brake()

    def _brake(self) -> None:
        for joint in self.left + self.right:
            joint.set_command(0.0)

    def update(self, time: float, period: float) -> None:
        lin, ang, stamp = self.command.read_from_rt()
        if stamp is None or time - stamp > self.params.cmd_vel_timeout:
            lin = ang = 0.0
        odometry = self.odometry
        status = diff_drive_kernel.diff_drive_update(
            lin,
            ang,
            time,
            period,
            self.params.open_loop,
            self.hw.position,
            self._left_i,
            self._right_i,
            self.radius,
            self.separation,
            odometry.state,
            odometry.window,
            self._limits,
            self._history,
            self._command,
            self._out,
        )
        raise_for(status, time, odometry.state, "the wheel angles")
        if self.schedule.is_due(time, period):
            self._publish_odometry(time)
        if self.cmd_pub is not None:
            self.cmd_pub.publish_built(self._cmd_msg, time, float(self._out[0]), float(self._out[1]))

    def _publish_odometry(self, time: float) -> None:
        p, odo = self.params, self.odometry
        pose = (odo.x, odo.y, 0.0), tuple(quat_from_yaw(odo.heading))
        twist = (odo.linear, 0.0, 0.0), (0.0, 0.0, odo.angular)
        self.odom_pub.publish_built(
            odometry_msg,
            time,
            p.odom_frame_id,
            p.base_frame_id,
            *pose,
            *twist,
            self._pose_cov,
            self._twist_cov,
        )
        if self.tf_pub is not None:
            self.tf_pub.publish_built(self._tf_msg, time, pose)

    def _tf_msg(self, time: float, pose):
        transform = transform_stamped(self.params.odom_frame_id, self.params.base_frame_id, time, *pose)
        return msg_class("tf2_msgs/TFMessage")(transforms=[transform])

    def _cmd_msg(self, time: float, lin: float, ang: float):
        twist = msg_class("geometry_msgs/Twist")
        vec = msg_class("geometry_msgs/Vector3")
        return msg_class("geometry_msgs/TwistStamped")(
            header=header(self.params.base_frame_id, time),
            twist=twist(linear=vec(x=lin, y=0.0, z=0.0), angular=vec(x=0.0, y=0.0, z=ang)),
        )
