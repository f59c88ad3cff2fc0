"""move_base's output for the TWIL platform (base_local_planner twil_control/BacksteppingLocalPlanner):
twil_control/CartLinearizingCommand on the cart controller's command topic instead of a Twist.

The platform part is the waypoint follower's reference, transformed from the local costmap's
frame into `command_frame` (the frame of the controller's pose_source). The arm part holds the
arm where it was when the goal arrived (the arm_joints of the controller's parameters, read from
/joint_states): move_base moves the base only. A stop (move_base's zero Twist) is a reference at
the pose the platform had when it was asked to stop, which the backstepping law brakes onto
(erratum 4's brake below its goal_tolerance), held until the next reference.
"""

from __future__ import annotations

import math

import numpy as np

from twil_control.errors import InputError

from ..core.messages import header, msg_class
from ..core.tf import TfBuffer
from ..navigation.backstepping_planner import BacksteppingPlannerParams
from .costmap_ros import pose2d

COMMAND_TYPE = "twil_control/CartLinearizingCommand"


class CartCommandOutput:
    def __init__(self, node, params: BacksteppingPlannerParams, tf: TfBuffer) -> None:
        self.node, self.p, self.tf = node, params, tf
        key = f"{params.controller.rstrip('/')}/arm_joints"
        joints = node.get_param(key, None)
        if not (isinstance(joints, list) and joints and all(isinstance(j, str) for j in joints)):
            raise InputError(
                f"node {node.fqn}: BacksteppingLocalPlanner needs the cart controller's arm joint "
                f"names in parameter {key} (a list of strings; got {joints!r}): load the controller's "
                f"configuration, or set ~BacksteppingLocalPlanner/controller to its namespace"
            )
        self.arm_joints = list(joints)
        self._positions: dict[str, float] = {}
        self.arm_hold: np.ndarray | None = None
        self._held_pose: tuple[float, float, float] | None = None
        self._pub = node.create_publisher(f"{params.controller.rstrip('/')}/command", COMMAND_TYPE)
        node.create_subscription(params.joint_states, "sensor_msgs/JointState", self._on_joints)
        self._cls = msg_class(COMMAND_TYPE)
        self._pose2d = msg_class("geometry_msgs/Pose2D")

    def _on_joints(self, msg) -> None:
        for name, q in zip(msg.name, msg.position):
            self._positions[name] = float(q)

    def latch_arm(self) -> bool:
        """Hold the arm where it is now (at each new goal); False when /joint_states has not
        reported every arm joint yet."""
        if not all(j in self._positions for j in self.arm_joints):
            return False
        self.arm_hold = np.array([self._positions[j] for j in self.arm_joints])
        return True

    def send(self, pose, frame: str) -> None:
        """A reference pose (x, y, yaw) given in `frame`."""
        self._held_pose = None
        self._publish(self._to_command_frame(pose, frame))

    def stop(self, pose, frame: str) -> None:
        """Hold the platform at `pose` (its pose in `frame` now), or at the pose of the first stop
        since the last reference."""
        if self._held_pose is None:
            self._held_pose = self._to_command_frame(pose, frame)
        self._publish(self._held_pose)

    def _to_command_frame(self, pose, frame: str) -> tuple[float, float, float]:
        if frame == self.p.command_frame:
            return tuple(float(v) for v in pose)
        tx, ty, tyaw = pose2d(*self.tf.lookup_transform(self.p.command_frame, frame))
        c, s = math.cos(tyaw), math.sin(tyaw)
        return (
            tx + c * pose[0] - s * pose[1],
            ty + s * pose[0] + c * pose[1],
            math.remainder(pose[2] + tyaw, 2 * math.pi),
        )

    def _publish(self, pose) -> None:
        if self.arm_hold is None and not self.latch_arm():
            self.node.log_once(
                30,
                "no-arm",
                f"no {', '.join(self.arm_joints)} on {self.p.joint_states} yet: "
                "the platform waits (its command carries the arm's positions)",
            )
            return
        empty = np.zeros(0)
        self._pub.publish(
            self._cls(
                header=header(self.p.command_frame, self.node.now()),
                platform_pose=self._pose2d(x=float(pose[0]), y=float(pose[1]), theta=float(pose[2])),
                arm_positions=self.arm_hold.copy(),
                arm_velocities=empty,
                arm_accelerations=empty,
            )
        )
