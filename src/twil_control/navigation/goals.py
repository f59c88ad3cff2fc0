"""Goal poses a navigation stack refuses before planning (move_base rejects them), from any
geometry_msgs/PoseStamped-like object (the node's messages, a GUI's or a Foxglove client's).
"""

from __future__ import annotations

import math

#: How far off 1 a goal quaternion's norm may be.
QUAT_TOLERANCE = 1e-3


def validate_goal(msg) -> str | None:
    """Why a goal pose must be rejected, or None: non-finite values, or a quaternion that is zero or
    whose norm is off 1 by more than QUAT_TOLERANCE."""
    p, q = msg.pose.position, msg.pose.orientation
    values = [p.x, p.y, p.z, q.x, q.y, q.z, q.w]
    if not all(math.isfinite(v) for v in values):
        return f"goal pose has NaN or infinite values (position {p.x}, {p.y}, {p.z}; orientation {q.x}, {q.y}, {q.z}, {q.w})"
    norm = math.sqrt(q.x**2 + q.y**2 + q.z**2 + q.w**2)
    if norm == 0.0:
        return "goal orientation is the zero quaternion (0, 0, 0, 0), which is no rotation at all"
    if abs(norm - 1.0) > QUAT_TOLERANCE:
        return (
            f"goal orientation quaternion is not normalised: |q| = {norm:.6f}, off 1 by more than "
            f"{QUAT_TOLERANCE}"
        )
    return None
