"""Wheel odometry from /joint_states (the odometry part of diff_drive_controller), as the
real TWIL estimates its pose: nav_msgs/Odometry on `topic` and odom -> base_link on /tf.

It integrates the measured wheel angles, never the simulator's ground truth (qbot's
original files used ground truth as odometry; that hides every slip and drift).

`left_wheel` / `right_wheel` take one joint name or a list of them, as diff_drive_controller's
do; with a list (qbot's front and rear wheels of a side) the side's angle is the mean of its
wheels' angles.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from twil_control.errors import InputError

from ..control.diff_odometry import WheelOdometry
from ..control.transforms import quat_from_yaw
from ..core.odometry_msg import covariance, odometry_msg
from ..core.ros_node import RosNode
from ..core.tf import TfBroadcaster, transform_stamped


@dataclass
class WheelOdometryParams:
    left_wheel: Any = "left_wheel_joint"  # a joint name, or a list of joint names (averaged)
    right_wheel: Any = "right_wheel_joint"
    wheel_radius: float = 0.075
    wheel_separation: float = 0.322
    odom_frame_id: str = "odom"
    base_frame_id: str = "base_link"
    enable_odom_tf: bool = True
    topic: str = "odom"
    joint_states: str = "/joint_states"
    velocity_rolling_window_size: int = 10
    # Diagonals (x, y, z, roll, pitch, yaw); z and the tilts are unobservable from the wheels,
    # so they get a large variance, as diff_drive_controller's defaults do.
    pose_covariance_diagonal: list[float] = field(default_factory=lambda: [1e-3, 1e-3, 1e6, 1e6, 1e6, 1e-2])
    twist_covariance_diagonal: list[float] = field(default_factory=lambda: [1e-3, 1e-3, 1e6, 1e6, 1e6, 1e-2])


class WheelOdometryNode(RosNode):
    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        p = self.params = self.typed_params(WheelOdometryParams)
        for label in ("pose_covariance_diagonal", "twist_covariance_diagonal"):
            if len(getattr(p, label)) != 6:
                raise InputError(f"node {self.fqn}: ~{label} needs 6 values (x y z roll pitch yaw)")
        self.odometry = WheelOdometry(p.wheel_radius, p.wheel_separation, p.velocity_rolling_window_size)
        self._pose_cov = covariance(p.pose_covariance_diagonal)
        self._twist_cov = covariance(p.twist_covariance_diagonal)
        self._pub = self.create_publisher(p.topic, "nav_msgs/Odometry")
        self._tf = TfBroadcaster(self) if p.enable_odom_tf else None
        self._sides = tuple(self._names(label) for label in ("left_wheel", "right_wheel"))
        self._indices: tuple[list[int], list[int]] | None = None
        self.create_subscription(p.joint_states, "sensor_msgs/JointState", self._on_joint_states)

    def _names(self, label: str) -> list[str]:
        value = getattr(self.params, label)
        names = [value] if isinstance(value, str) else value
        if not (isinstance(names, list) and names and all(isinstance(n, str) for n in names)):
            raise InputError(
                f"node {self.fqn}: ~{label} must be a joint name or a non-empty list of "
                f"joint names (got {value!r})"
            )
        return names

    def _on_joint_states(self, msg) -> None:
        p = self.params
        if self._indices is None:
            try:
                self._indices = tuple([msg.name.index(n) for n in side] for side in self._sides)
            except ValueError:
                self.log_once(
                    40,
                    "names",
                    f"joint states lack {p.left_wheel} or {p.right_wheel} "
                    f"(have: {', '.join(msg.name)}); no odometry",
                )
                return
        # the mean of each side's angles in plain floats (100 Hz, where np.mean's call costs more
        # than the sum; for one or two wheels a side this is np.mean's result to the bit)
        position = msg.position
        left, right = (float(sum([position[i] for i in side])) / len(side) for side in self._indices)
        t = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
        if not (math.isfinite(left) and math.isfinite(right)):
            self.log_once(40, "nan", "non-finite wheel positions in joint states; skipped")
            return
        self.odometry.update(left, right, t)  # the first call only records the angles
        odo = self.odometry
        quat = quat_from_yaw(odo.heading)
        position = (odo.x, odo.y, 0.0)
        self._pub.publish(
            odometry_msg(
                t,
                p.odom_frame_id,
                p.base_frame_id,
                position,
                quat,
                (odo.linear, 0.0, 0.0),
                (0.0, 0.0, odo.angular),
                self._pose_cov,
                self._twist_cov,
            )
        )
        if self._tf is not None:
            self._tf.send(transform_stamped(p.odom_frame_id, p.base_frame_id, t, position, quat))
