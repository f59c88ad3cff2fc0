"""A spawned model's true planar pose over a run, from a bag's /gazebo/model_states."""

from __future__ import annotations

import math

import numpy as np


def yaw(q) -> float:
    """The heading of a geometry_msgs/Quaternion."""
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


def model_truth(bag: dict, model: str) -> np.ndarray:
    """(t s, x, y, yaw) rows of `model` from /gazebo/model_states (bag: topic -> [(t ns, msg)])."""
    rows = []
    for t, m in bag["/gazebo/model_states"]:
        pose = m.pose[list(m.name).index(model)]
        rows.append((t * 1e-9, pose.position.x, pose.position.y, yaw(pose.orientation)))
    return np.array(rows)
