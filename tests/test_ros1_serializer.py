"""The generated ROS 1 serialisers (core/ros1_serializer.py) give rosbags' serialize_ros1 bytes
exactly, on every message type of the project's typestore (Noetic, TFMessage, gazebo_msgs, the
package's own), with random values, empty and filled sequences, non-ASCII strings; and what rosbags
refuses (a list where a numpy array belongs, a wrong fixed-array length, an out-of-range integer)
is still refused, with rosbags' own error."""

from __future__ import annotations

import numpy as np
import pytest
from rosbags.interfaces import Nodetype
from rosbags.serde import SerdeError

from twil_control.core import messages
from twil_control.core.ros1_serializer import CODES, Serializers

STORE = messages.typestore()
DTYPES = {
    "bool": np.bool_,
    "byte": np.int8,
    "char": np.uint8,
    "int8": np.int8,
    "int16": np.int16,
    "int32": np.int32,
    "int64": np.int64,
    "uint8": np.uint8,
    "uint16": np.uint16,
    "uint32": np.uint32,
    "uint64": np.uint64,
    "float32": np.float32,
    "float64": np.float64,
}


def _number(base: str, rng: np.random.Generator):
    if base == "bool":
        return bool(rng.integers(2))
    if base.startswith("float"):
        return float(rng.normal() * 1e3)
    info = np.iinfo(DTYPES[base])
    return int(info.min) + int(rng.integers(0, 2**62)) % (int(info.max) - int(info.min) + 1)


def _array(base: str, n: int, rng: np.random.Generator) -> np.ndarray:
    return np.array([_number(base, rng) for _ in range(n)], dtype=DTYPES[base])


def _value(desc, rng: np.random.Generator, length: int):
    """A random value of a field: sequences get `length` elements (0 for the empty case)."""
    kind = desc[0]
    if kind == Nodetype.NAME:
        return _message(desc[1], rng, length)
    if kind == Nodetype.BASE:
        base = desc[1][0]
        return rng.choice(["", "odom", "base_link", "räder/ß"]) if base == "string" else _number(base, rng)
    sub, n = desc[1] if kind == Nodetype.ARRAY else (desc[1][0], length)
    if sub[0] == Nodetype.BASE and sub[1][0] in CODES:
        return _array(sub[1][0], n, rng)
    return [_value(sub, rng, length) for _ in range(n)]


def _message(typename: str, rng: np.random.Generator, length: int):
    fields = STORE.fielddefs[typename][1]
    cls = STORE.types[typename]
    values = {
        (f"{name}_" if name in ("from", "class", "def", "global") else name): _value(desc, rng, length)
        for name, desc in fields
    }
    return cls(**values)


@pytest.mark.parametrize("length", [0, 3])
def test_every_type_serialises_to_rosbags_bytes(length):
    rng = np.random.default_rng(length)
    fast = Serializers(STORE)
    checked = 0
    for typename in sorted(STORE.fielddefs):
        msg = _message(typename, rng, length)
        expected = bytes(STORE.serialize_ros1(msg, typename))
        assert fast.serialize(msg, typename) == expected, typename
        checked += 1
    assert checked >= 170  # Noetic's types and the project's
    assert fast.fallbacks == 0  # every one through its generated function


def test_heavy_nested_types_are_generated_not_left_to_rosbags():
    fast = Serializers(STORE)
    rng = np.random.default_rng(1)
    for typename in ("nav_msgs/msg/Path", "tf2_msgs/msg/TFMessage", "nav_msgs/msg/OccupancyGrid"):
        fast.serialize(_message(typename, rng, 2), typename)
        assert fast._functions[typename], typename


def test_published_message_serialises_through_messages_serialize():
    path = messages.msg_class("nav_msgs/Path")(
        header=messages.header("odom", 1.25, seq=7),
        poses=[_message("geometry_msgs/msg/PoseStamped", np.random.default_rng(i), 0) for i in range(50)],
    )
    assert messages.serialize(path) == bytes(STORE.serialize_ros1(path, "nav_msgs/msg/Path"))


def _scan(**changes):
    rng = np.random.default_rng(2)
    msg = _message("sensor_msgs/msg/LaserScan", rng, 4)
    for key, value in changes.items():
        setattr(msg, key, value)
    return msg


@pytest.mark.parametrize(
    ("msg", "typename", "error"),
    [
        (_scan(ranges=[1.0, 2.0]), "sensor_msgs/msg/LaserScan", AttributeError),  # a list, not numpy
        (
            _message("nav_msgs/msg/Odometry", np.random.default_rng(3), 0),
            "nav_msgs/msg/Odometry",
            SerdeError,
        ),  # covariance of the wrong length (set below)
        (_message("std_msgs/msg/UInt8", np.random.default_rng(4), 0), "std_msgs/msg/UInt8", Exception),
    ],
)
def test_what_rosbags_refuses_is_refused_alike(msg, typename, error):
    if typename == "nav_msgs/msg/Odometry":
        msg.pose.covariance = np.zeros(35)
    if typename == "std_msgs/msg/UInt8":
        msg.data = 300  # out of range for uint8
    with pytest.raises(error) as rosbags_error:
        STORE.serialize_ros1(msg, typename)
    with pytest.raises(error) as ours:
        Serializers(STORE).serialize(msg, typename)
    assert type(ours.value) is type(rosbags_error.value)


def test_big_endian_array_falls_back_to_rosbags_bytes():
    msg = _scan(ranges=np.array([1.5, 2.5, np.inf], dtype=">f4"))
    fast = Serializers(STORE)
    assert fast.serialize(msg, "sensor_msgs/msg/LaserScan") == bytes(
        STORE.serialize_ros1(msg, "sensor_msgs/msg/LaserScan")
    )
    assert fast.fallbacks == 1
