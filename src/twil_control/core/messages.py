"""Message types: the rosbags ROS 1 Noetic typestore, plus what Noetic's store lacks.

Messages on the bus are instances of the typestore's classes, so what is published is what is
recorded, byte for byte, with no conversion. Type names are accepted in ROS 1 form
(``sensor_msgs/JointState``) and rosbags form (``sensor_msgs/msg/JointState``).

Registered on top of Noetic: tf2_msgs/TFMessage and gazebo_msgs' ModelState(s) and LinkState(s)
(missing from the store) and every .msg file in this package's ``msg/`` folder as
``twil_control/<Name>``.
"""

from __future__ import annotations

import functools
from pathlib import Path

from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

from twil_control.errors import TwilControlError

from .ros1_serializer import Serializers

MSG_DIR = Path(__file__).resolve().parents[1] / "msg"
PACKAGE = "twil_control"

_EXTRA_DEFINITIONS = {
    "tf2_msgs/msg/TFMessage": "geometry_msgs/TransformStamped[] transforms\n",
    # gazebo_msgs (the simulator node's topics), with gazebo_ros's definitions
    "gazebo_msgs/msg/ModelState": (
        "string model_name\ngeometry_msgs/Pose pose\ngeometry_msgs/Twist twist\nstring reference_frame\n"
    ),
    "gazebo_msgs/msg/ModelStates": "string[] name\ngeometry_msgs/Pose[] pose\ngeometry_msgs/Twist[] twist\n",
    "gazebo_msgs/msg/LinkState": (
        "string link_name\ngeometry_msgs/Pose pose\ngeometry_msgs/Twist twist\nstring reference_frame\n"
    ),
    "gazebo_msgs/msg/LinkStates": "string[] name\ngeometry_msgs/Pose[] pose\ngeometry_msgs/Twist[] twist\n",
}


class MessageTypeError(TwilControlError, KeyError):
    """An unknown message type name."""


@functools.cache
def typestore() -> Typestore:
    """The process-wide typestore (Noetic + TFMessage + this package's messages)."""
    store = get_typestore(Stores.ROS1_NOETIC)
    types = {}
    for name, text in _EXTRA_DEFINITIONS.items():
        types.update(get_types_from_msg(text, name))
    for path in sorted(MSG_DIR.glob("*.msg")):
        types.update(get_types_from_msg(path.read_text(), f"{PACKAGE}/msg/{path.stem}"))
    store.register(types)
    return store


def full_type_name(name: str) -> str:
    """``pkg/Type`` or ``pkg/msg/Type`` -> ``pkg/msg/Type`` (the typestore's key)."""
    parts = name.split("/")
    if len(parts) == 2:
        return f"{parts[0]}/msg/{parts[1]}"
    if len(parts) == 3 and parts[1] == "msg":
        return name
    raise MessageTypeError(f"message type '{name}' is not of the form package/Type")


def ros1_type_name(name: str) -> str:
    """``pkg/msg/Type`` -> ``pkg/Type``, the name ROS 1 tools print."""
    pkg, _, typ = full_type_name(name).split("/")
    return f"{pkg}/{typ}"


@functools.cache  # 1 kHz publishers call this (via header()); a type's class never changes
def msg_class(name: str):
    """The typestore class of a message type; unknown types raise MessageTypeError."""
    full = full_type_name(name)
    try:
        return typestore().types[full]
    except KeyError:
        raise MessageTypeError(
            f"unknown message type '{name}'; add a .msg file to {MSG_DIR} or use a ROS Noetic type"
        ) from None


def definition(name: str) -> tuple[str, str]:
    """(message definition text, md5sum) as ROS 1 writes them into bag connections."""
    return typestore().generate_msgdef(full_type_name(name))


@functools.cache
def _serializers() -> Serializers:
    return Serializers(typestore())


def serialize(msg) -> bytes:
    """ROS 1 wire bytes of a typestore message, rosbags' serialize_ros1's bytes from a generated
    function per type (core/ros1_serializer.py). Numeric arrays must be numpy arrays, as the
    typestore's classes declare them."""
    return _serializers().serialize(msg, msg.__msgtype__)


def deserialize(data: bytes, name: str):
    return typestore().deserialize_ros1(data, full_type_name(name))


def time_msg(t: float):
    """builtin Time (sec, nanosec) of a simulated time in seconds, rounded to the nanosecond."""
    ns = int(round(t * 1e9))
    return msg_class("builtin_interfaces/msg/Time")(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def to_sec(stamp) -> float:
    return stamp.sec + stamp.nanosec * 1e-9


def header(frame_id: str, t: float, seq: int = 0):
    return msg_class("std_msgs/Header")(seq=seq, stamp=time_msg(t), frame_id=frame_id)
