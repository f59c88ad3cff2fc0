"""What a Foxglove client may publish, and the checks a message passes before it is published.

A client may publish on a topic the launch already has, with that topic's type, and only
these types: goals (geometry_msgs/PoseStamped, checked as the goal panel checks its form:
X and Y in the panel's ranges, and as move_base checks a goal: finite values, a unit
quaternion), velocity commands (geometry_msgs/Twist, every component finite) and goal
cancels (actionlib_msgs/GoalID). Anything else is refused with a sentence saying why; a
refused message never reaches the bus.
"""

from __future__ import annotations

import math

from twil_control.errors import InputError

from ..core import messages
from ..navigation.goals import validate_goal
from ..view.panel import PanelInputError, parse_field

GOAL, TWIST, CANCEL = "geometry_msgs/PoseStamped", "geometry_msgs/Twist", "actionlib_msgs/GoalID"
ACCEPTED = (GOAL, TWIST, CANCEL)


def check_topic(topic: str, schema_name: str, encoding: str, topic_types: dict[str, str]) -> str | None:
    """Why a client channel cannot publish (None: it can)."""
    if encoding != "ros1":
        return f"{topic}: message encoding '{encoding}' is not accepted; publish ROS 1 ('ros1') messages"
    if schema_name not in ACCEPTED:
        return f"{topic}: {schema_name or 'a schemaless channel'} is not accepted; clients may publish {', '.join(ACCEPTED)}"
    if topic not in topic_types:
        return f"{topic}: no such topic in this launch (nothing would receive it)"
    if topic_types[topic] != schema_name:
        return f"{topic} carries {topic_types[topic]}, not {schema_name}"
    return None


def decode(data: bytes, schema_name: str):
    """The typestore message of a client's ROS 1 bytes, or ValueError saying why not."""
    try:
        return messages.deserialize(bytes(data), schema_name)
    except Exception as error:  # rosbags raises several types on short or garbled input
        raise InputError(
            f"{len(data)} bytes that are not a ROS 1 {schema_name} ({type(error).__name__}: {error})"
        ) from None


def check_message(schema_name: str, msg) -> str | None:
    """Why a decoded client message must be refused (None: publish it)."""
    if schema_name == GOAL:
        reason = validate_goal(msg)
        if reason is not None:
            return reason
        try:
            parse_field("x", msg.pose.position.x)
            parse_field("y", msg.pose.position.y)
        except PanelInputError as error:
            return f"goal {error}"
        return None
    if schema_name == TWIST:
        values = (msg.linear.x, msg.linear.y, msg.linear.z, msg.angular.x, msg.angular.y, msg.angular.z)
        if not all(math.isfinite(v) for v in values):
            return f"velocity command with NaN or infinite values (linear {values[:3]}, angular {values[3:]})"
        return None
    return None
