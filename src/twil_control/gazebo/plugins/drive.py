"""libgazebo_ros_diff_drive.so and libgazebo_ros_skid_steer_drive.so, as the plugins behave.

cmd_vel becomes wheel speeds held by the joints' velocity motors (Drake's implicit joint PD here,
ODE's joint motor in Gazebo), with the plugins' limits, legacyMode and no command timeout.
Odometry is the simulator's ground truth by default, as Gazebo publishes it, which never drifts
and so hides every slip; ``odometrySource encoder`` integrates the wheel angles instead, the
skid steer too. Parameters and behaviour: docs/robots.md, "Plugins".
"""

from __future__ import annotations

import math

import numpy as np

from twil_control.errors import InputError

from ...control import skid_steer
from ...control.diff_odometry import WheelOdometry
from ...control.speed_limiter import SpeedLimiter
from ...control.transforms import quat_from_yaw, urdf_joint_pose, yaw_from_quat
from ...core.messages import header, msg_class
from ...core.odometry_msg import covariance, odometry_msg
from ...core.tf import TfBroadcaster, transform_stamped
from . import PluginNode
from .ros_control import VELOCITY_GAIN

#: gazebo_ros_diff_drive's fixed covariances (x, y, z, roll, pitch, yaw)
_DIFF_DRIVE_COVARIANCE = (1e-5, 1e-5, 1e12, 1e12, 1e12, 1e-3)


class DrivePlugin:
    def __init__(self, host, sim, model: str, config, description) -> None:
        from ...world.robot_hw_sim import JointConfig, PidGainsConfig, set_implicit_pd_gains

        self.node = node = PluginNode(host, config.namespace)
        self.config = c = config
        self.model = model
        self.description = description
        self.radius = c.wheel_diameter / 2.0
        self.joints = c.left_joints + c.right_joints
        set_implicit_pd_gains(
            sim.plant,
            {j: JointConfig(["velocity"], None, PidGainsConfig(p=0.0, d=VELOCITY_GAIN)) for j in self.joints},
            f"{node.fqn} ({model} drive)",
        )
        if c.kind == "diff_drive" and c.legacy_mode:
            node.log.warning(
                "%s: %s drive of %s has legacyMode true (the plugin's default): its turns go "
                "the wrong way, as in Gazebo; set <legacyMode>false</legacyMode>",
                description.source,
                c.kind,
                model,
            )
        self.period = 1.0 / c.update_rate if c.update_rate > 0 else sim.config.time_step
        self.command = (0.0, 0.0)
        self.limiters = [
            SpeedLimiter(has_acceleration_limits=True, max_acceleration=c.wheel_acceleration)
            for _ in range(2)
        ]
        self.instructed = [0.0, 0.0]  # the ramped wheel speeds (m/s), L, R
        self.odometry = WheelOdometry(self.radius, c.wheel_separation)
        node.create_subscription(c.command_topic, "geometry_msgs/Twist", self._on_command)
        self._odom_pub = node.create_publisher(c.odometry_topic, "nav_msgs/Odometry")
        self._tf = TfBroadcaster(node) if (c.publish_tf or c.publish_wheel_tf) else None
        self._joint_pub = (
            node.create_publisher("joint_states", "sensor_msgs/JointState")
            if c.publish_wheel_joint_state
            else None
        )
        if c.kind == "diff_drive":
            diag = _DIFF_DRIVE_COVARIANCE
        else:
            diag = (c.covariance[0], c.covariance[1], 1e6, 1e6, 1e6, c.covariance[2])
        self._cov = covariance(diag)
        self.system = None

    def _on_command(self, msg) -> None:
        v, w = float(msg.linear.x), float(msg.angular.z)
        if not (math.isfinite(v) and math.isfinite(w)):
            self.node.log_once(
                40,
                "nan",
                f"{self.config.kind} of {self.model}: non-finite cmd_vel "
                f"({v}, {w}) refused; keeping the previous command",
            )
            return
        self.command = (v, w)

    def build_systems(self, sim) -> None:
        from ...world.body_state import floating_indices
        from ...world.wheel_drive import WheelVelocityDrive

        plant = sim.plant
        instance = sim.robot_instances(self.model)[0]
        root = plant.GetBodyByName(self.description.root, instance)
        if not (root.is_floating_base_body() and root.has_quaternion_dofs()):
            raise InputError(
                f"{self.node.fqn}: the {self.config.kind} plugin of {self.model} needs a "
                f"free-floating root link; {self.description.root} is not"
            )
        self._q0, self._v0 = floating_indices(plant, root)
        self.system = sim.add_system(
            WheelVelocityDrive(sim, instance, self.joints, self.period, self._update),
            f"{self.node.fqn}/{self.model}/{self.config.kind}",
        )
        self._wheel_joints = [self.description.joints[joint] for joint in self.joints]

    # -- every update (a Drake discrete update) ---------------------------------------------
    def _update(self, t: float, x):
        c = self.config
        self.node.master.clock.advance_to(t)
        left_w, right_w = skid_steer.wheel_speeds(*self.command, self.radius, c.wheel_separation / 2.0)
        target = [float(left_w) * self.radius, float(right_w) * self.radius]  # m/s at the rim
        if c.kind == "diff_drive" and c.legacy_mode:
            target.reverse()
        q, v = x[self.system.q_index], x[self.system.v_index]
        half = len(c.left_joints)
        measured = [float(v[:half].mean()) * self.radius, float(v[half:].mean()) * self.radius]
        for side in (0, 1):
            if c.wheel_acceleration > 0 and abs(target[side] - measured[side]) >= 0.01:
                self.instructed[side] = self.limiters[side].limit_acceleration(
                    target[side], self.instructed[side], self.period
                )
            else:
                self.instructed[side] = target[side]
        self._publish(t, x, q, v)
        return [self.instructed[0] / self.radius] * half + [self.instructed[1] / self.radius] * (
            len(self.joints) - half
        )

    def _publish(self, t: float, x, q, v) -> None:
        from ...world.body_state import floating_pose_twist

        c = self.config
        half = len(c.left_joints)
        if c.odometry_source == "encoder":
            self.odometry.update(float(q[:half].mean()), float(q[half:].mean()), t)
            position, quat = (
                (self.odometry.x, self.odometry.y, 0.0),
                tuple(quat_from_yaw(self.odometry.heading)),
            )
            linear, angular = (self.odometry.linear, 0.0, 0.0), (0.0, 0.0, self.odometry.angular)
        else:  # world: the model's true pose, its velocity turned into the heading's frame
            position, quat, v_w, w_w = floating_pose_twist(x, self._q0, self._v0)
            yaw = yaw_from_quat(quat)
            cy, sy = math.cos(yaw), math.sin(yaw)
            linear = (cy * v_w[0] + sy * v_w[1], cy * v_w[1] - sy * v_w[0], 0.0)
            angular = (0.0, 0.0, w_w[2])
        self._odom_pub.publish(
            odometry_msg(
                t, c.odometry_frame, c.robot_base_frame, position, quat, linear, angular, self._cov, self._cov
            )
        )
        transforms = []
        if c.publish_tf:
            transforms.append(transform_stamped(c.odometry_frame, c.robot_base_frame, t, position, quat))
        if c.publish_wheel_tf:
            for joint, angle in zip(self._wheel_joints, q.tolist()):
                pose = urdf_joint_pose(joint.type, joint.xyz, joint.origin_quaternion, joint.axis, angle)
                transforms.append(transform_stamped(joint.parent, joint.child, t, *pose))
        if transforms:
            self._tf.send(*transforms)
        if self._joint_pub is not None:
            self._joint_pub.publish(
                msg_class("sensor_msgs/JointState")(
                    header=header("", t),
                    name=list(self.joints),
                    position=q.astype(float),
                    velocity=v.astype(float),
                    effort=np.zeros(0),
                )
            )
