"""Building nav_msgs/Odometry and TransformStamped messages from plain numbers."""

from __future__ import annotations

import numpy as np

from .messages import header, msg_class


def pose_msg(position, quaternion):
    return msg_class("geometry_msgs/Pose")(
        position=msg_class("geometry_msgs/Point")(
            x=float(position[0]), y=float(position[1]), z=float(position[2])
        ),
        orientation=msg_class("geometry_msgs/Quaternion")(
            x=float(quaternion[0]), y=float(quaternion[1]), z=float(quaternion[2]), w=float(quaternion[3])
        ),
    )


def twist_msg(linear, angular):
    vec = msg_class("geometry_msgs/Vector3")
    return msg_class("geometry_msgs/Twist")(
        linear=vec(x=float(linear[0]), y=float(linear[1]), z=float(linear[2])),
        angular=vec(x=float(angular[0]), y=float(angular[1]), z=float(angular[2])),
    )


def covariance(diagonal) -> np.ndarray:
    """A 6x6 row-major covariance (x, y, z, roll, pitch, yaw) from its diagonal."""
    return np.diag(np.asarray(diagonal, dtype=float)).reshape(36)


def odometry_msg(
    t: float,
    frame_id: str,
    child_frame_id: str,
    position,
    quaternion,
    linear,
    angular,
    pose_covariance,
    twist_covariance,
):
    """nav_msgs/Odometry: pose in frame_id, twist in child_frame_id (REP 105)."""
    return msg_class("nav_msgs/Odometry")(
        header=header(frame_id, t),
        child_frame_id=child_frame_id,
        pose=msg_class("geometry_msgs/PoseWithCovariance")(
            pose=pose_msg(position, quaternion), covariance=np.asarray(pose_covariance, dtype=float)
        ),
        twist=msg_class("geometry_msgs/TwistWithCovariance")(
            twist=twist_msg(linear, angular), covariance=np.asarray(twist_covariance, dtype=float)
        ),
    )
