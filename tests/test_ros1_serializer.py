"""The generated ROS 1 serializer writes exactly rosbags' serialize_ros1 bytes.

Every type of the project's typestore (Noetic, TFMessage, the package's .msg files: a
superset of what the project publishes) is filled with seeded random content - empty and
long arrays, non-ASCII strings, integer extremes, negative numbers, NaN/inf/-0.0, bools - and
its bytes compared with rosbags'; the bytes are read back with rosbags' deserialize_ros1.
Array kinds Noetic does not use (bool[], char[], fixed arrays of strings and messages, empty
messages in arrays) are covered by a test type in a separate typestore. The comparison is
shown to catch broken serializers (fields swapped, a type changed, a field dropped), and
values the generated code does not take are shown to end as rosbags ends them.
"""
from __future__ import annotations

import math
import re
import zlib
from types import SimpleNamespace

import numpy as np
import pytest
from rosbags.interfaces import Nodetype
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from twil_control import PACKAGE_ROOT
from twil_control.core import messages
from twil_control.core.ros1_serializer import (ARRAY_DTYPES, Ros1Serializer, UnsupportedType,
                                               generate)

STORE = messages.typestore()
ALL_TYPES = sorted(STORE.fielddefs)
HOT_TYPES = [
    "nav_msgs/msg/Odometry", "tf2_msgs/msg/TFMessage", "sensor_msgs/msg/JointState",
    "std_msgs/msg/UInt8MultiArray", "sensor_msgs/msg/LaserScan", "geometry_msgs/msg/Twist",
    "nav_msgs/msg/OccupancyGrid", "nav_msgs/msg/Path", "actionlib_msgs/msg/GoalStatusArray",
]
INT_RANGES = {
    "byte": (-2**7, 2**7 - 1), "int8": (-2**7, 2**7 - 1), "char": (0, 2**8 - 1),
    "uint8": (0, 2**8 - 1), "int16": (-2**15, 2**15 - 1), "uint16": (0, 2**16 - 1),
    "int32": (-2**31, 2**31 - 1), "uint32": (0, 2**32 - 1),
    "int64": (-2**63, 2**63 - 1), "uint64": (0, 2**64 - 1),
}
SPECIAL_FLOATS = [math.nan, math.inf, -math.inf, -0.0, 0.0, -1.5]
STRINGS = ["", "base_link", "Ünïcödé ñ 日本語 🙂", "a" * 300]
ARRAY_LENGTHS = [0, 1, 3, 1000]


def _message_types_named_in_source() -> set[str]:
    """Every ``pkg/Type`` string literal in the package that names a message type."""
    names = set()
    for path in (PACKAGE_ROOT / "src/twil_control").rglob("*.py"):
        for name in re.findall(r"\"([a-z_0-9]+/(?:msg/)?[A-Z][A-Za-z0-9]*)\"", path.read_text()):
            full = messages.full_type_name(name)
            if full in STORE.fielddefs:
                names.add(full)
    return names


# -- seeded random messages ---------------------------------------------------------------

def _scalar(rng, base: str):
    if base == "string":
        if rng.random() < 0.5:
            return STRINGS[rng.integers(len(STRINGS))]
        return "".join(chr(c) for c in rng.integers(0x20, 0xD7FF, rng.integers(0, 20)))
    if base == "bool":
        return bool(rng.random() < 0.5)
    if base in INT_RANGES:
        lo, hi = INT_RANGES[base]
        drawn = int(rng.integers(lo, hi, endpoint=True, dtype=np.int64 if lo < 0 else np.uint64))
        return [lo, hi, 0, drawn][rng.integers(4)]
    value = SPECIAL_FLOATS[rng.integers(len(SPECIAL_FLOATS))] if rng.random() < 0.4 \
        else float(rng.normal() * 10.0 ** rng.integers(-30, 30))
    return float(np.float32(value)) if base == "float32" else value


def _primitive_array(rng, base: str, n: int) -> np.ndarray:
    dtype = ARRAY_DTYPES[base]
    if base == "bool":
        return rng.random(n) < 0.5
    if base in INT_RANGES:
        lo, hi = INT_RANGES[base]
        return rng.integers(lo, hi, n, endpoint=True, dtype=dtype)
    values = rng.normal(size=n) * 1e3
    values[rng.random(n) < 0.1] = np.nan
    values[rng.random(n) < 0.05] = -np.inf
    return values.astype(dtype)


def random_message(store, typename: str, rng, depth: int = 0):
    values = {}
    for name, desc in store.get_msgdef(typename).fields:
        # rosbags' member of empty messages is not on the wire; it reads back as 0
        values[name] = 0 if name == "structure_needs_at_least_one_member" \
            else _random_field(store, desc, rng, depth)
    return store.types[typename](**values)


def _random_field(store, desc, rng, depth: int):
    kind = desc[0]
    if kind == Nodetype.BASE:
        return _scalar(rng, desc[1][0])
    if kind == Nodetype.NAME:
        return random_message(store, desc[1], rng, depth + 1)
    element, length = desc[1]
    if kind == Nodetype.SEQUENCE:
        nested = element[0] == Nodetype.NAME or element[1][0] == "string"
        length = int(rng.integers(0, 4 if depth < 2 else 2)) if nested \
            else ARRAY_LENGTHS[rng.integers(len(ARRAY_LENGTHS))]
    if element[0] == Nodetype.NAME:
        return [random_message(store, element[1], rng, depth + 1) for _ in range(length)]
    if element[1][0] == "string":
        return [_scalar(rng, "string") for _ in range(length)]
    return _primitive_array(rng, element[1][0], length)


def with_lists(msg):
    """The message with every primitive numpy array replaced by a Python list."""
    if isinstance(msg, np.ndarray):
        return msg.tolist()
    if isinstance(msg, list):
        return [with_lists(m) for m in msg]
    if hasattr(msg, "__msgtype__"):
        return type(msg)(**{k: with_lists(v) for k, v in vars(msg).items() if k != "__msgtype__"})
    return msg


def first_mismatch(serialize, store, msgs) -> str | None:
    """None if ``serialize`` gives rosbags' bytes for every message, else what differs."""
    for i, msg in enumerate(msgs):
        ours = serialize(msg)
        theirs = bytes(store.serialize_ros1(msg, msg.__msgtype__))
        if type(ours) is not bytes or ours != theirs:
            at = next((k for k, (a, b) in enumerate(zip(ours, theirs)) if a != b),
                      min(len(ours), len(theirs)))
            return (f"message {i} ({msg.__msgtype__}): {len(ours)} vs {len(theirs)} bytes, "
                    f"first difference at {at}")
    return None


def same_values(a, b) -> bool:
    """Field by field, NaN equal to NaN (numpy arrays compared bit for bit)."""
    if isinstance(b, np.ndarray):
        return np.asarray(a, b.dtype).tobytes() == b.tobytes()
    if isinstance(a, list):
        return len(a) == len(b) and all(same_values(x, y) for x, y in zip(a, b))
    if hasattr(a, "__msgtype__"):
        return all(same_values(v, getattr(b, k)) for k, v in vars(a).items())
    if isinstance(a, float) and math.isnan(a):
        return math.isnan(b)
    return a == b


# -- equality with rosbags ----------------------------------------------------------------

def test_every_type_the_project_names_is_in_the_tested_store_and_generated():
    named = _message_types_named_in_source()
    ours = {f"{messages.PACKAGE}/msg/{p.stem}" for p in messages.MSG_DIR.glob("*.msg")}
    assert {"nav_msgs/msg/Odometry", "tf2_msgs/msg/TFMessage", "nav_msgs/msg/Path"} <= named
    serializer = Ros1Serializer(STORE)
    for name in sorted(named | ours | set(HOT_TYPES)):
        assert name in ALL_TYPES
        assert serializer.function(name) is not None, f"{name} has no generated serializer"


@pytest.mark.parametrize("typename", ALL_TYPES)
def test_generated_bytes_equal_rosbags_and_read_back(typename):
    rng = np.random.default_rng(zlib.crc32(typename.encode()))  # a seed per type, stable
    func = generate(STORE, typename)  # called directly: no fallback can hide a difference
    msgs = [random_message(STORE, typename, rng) for _ in range(6)]
    assert first_mismatch(func, STORE, msgs) is None
    for msg in msgs:
        back = STORE.deserialize_ros1(func(msg), typename)  # rosbags checks the length too
        assert same_values(msg, back)


@pytest.mark.parametrize("typename", HOT_TYPES)
def test_hot_types_many_seeds_and_lists(typename):
    func = generate(STORE, typename)
    for seed in range(40):
        rng = np.random.default_rng(seed)
        msg = random_message(STORE, typename, rng)
        assert first_mismatch(func, STORE, [msg]) is None, f"seed {seed}"
        # Python lists in primitive arrays: the bytes rosbags writes for the numpy arrays
        assert func(with_lists(msg)) == bytes(STORE.serialize_ros1(msg, typename)), f"seed {seed}"
        assert messages.serialize(msg) == bytes(STORE.serialize_ros1(msg, typename))


ALL_KINDS_MSG = """bool flag
bool[] flags
bool[3] flags3
char c
char[] cs
byte b
byte[] bs
uint16[] u16s
string[2] names2
string[] names
geometry_msgs/Point[2] points2
std_msgs/Empty e
std_msgs/Empty[] es
std_msgs/Empty[2] es2
time t
duration d
time[] ts
int64[4] i64s
float32[] f32s
std_msgs/Header header
"""


@pytest.fixture(scope="module")
def kinds_store():
    store = get_typestore(Stores.ROS1_NOETIC)
    store.register(get_types_from_msg(ALL_KINDS_MSG, "serializer_test/msg/AllKinds"))
    return store


def test_array_kinds_noetic_lacks(kinds_store):
    func = generate(kinds_store, "serializer_test/msg/AllKinds")
    rng = np.random.default_rng(3)
    msgs = [random_message(kinds_store, "serializer_test/msg/AllKinds", rng) for _ in range(50)]
    assert first_mismatch(func, kinds_store, msgs) is None
    assert first_mismatch(lambda m: func(with_lists(m)), kinds_store, msgs) is None
    for msg in msgs:
        assert same_values(msg, kinds_store.deserialize_ros1(func(msg), msg.__msgtype__))
    # an empty message writes nothing: rosbags' placeholder member is not on the wire
    empty = kinds_store.types["std_msgs/msg/Empty"](structure_needs_at_least_one_member=0)
    assert generate(kinds_store, "std_msgs/msg/Empty")(empty) == b""


# -- the comparison catches broken serializers --------------------------------------------

class _MutatedStore:
    """The store with one type's field list changed (what a generator bug would do)."""

    def __init__(self, store, typename: str, mutate) -> None:
        self._store, self._typename, self._mutate = store, typename, mutate

    def get_msgdef(self, name: str):
        fields = list(self._store.get_msgdef(name).fields)
        return SimpleNamespace(fields=self._mutate(fields) if name == self._typename else fields)


def _swap_first_two(fields):
    return [fields[1], fields[0], *fields[2:]]


def _float64_as_float32(fields):
    return [(n, (Nodetype.BASE, ("float32", 0)) if d == (Nodetype.BASE, ("float64", 0)) else d)
            for n, d in fields]


@pytest.mark.parametrize("inner, mutate, outer", [
    ("geometry_msgs/msg/Point", _swap_first_two, "nav_msgs/msg/Odometry"),
    ("geometry_msgs/msg/Vector3", _float64_as_float32, "geometry_msgs/msg/Twist"),
    ("std_msgs/msg/Header", lambda f: f[1:], "tf2_msgs/msg/TFMessage"),
    ("sensor_msgs/msg/JointState", _swap_first_two, "sensor_msgs/msg/JointState"),
])
def test_comparison_detects_a_broken_serializer(inner, mutate, outer):
    rng = np.random.default_rng(11)
    msgs = [random_message(STORE, outer, rng) for _ in range(5)]
    broken = generate(_MutatedStore(STORE, inner, mutate), outer)
    assert first_mismatch(broken, STORE, msgs) is not None
    intact = generate(_MutatedStore(STORE, inner, lambda f: f), outer)
    assert first_mismatch(intact, STORE, msgs) is None


# -- values the generated code does not take end as rosbags ends them ------------------------

def _outcome(serialize, msg):
    try:
        return "bytes", bytes(serialize(msg))
    except Exception as exc:  # noqa: BLE001 - the exception's type is what is compared
        return "error", type(exc)


def _joint_state(position):
    return messages.msg_class("sensor_msgs/JointState")(
        header=messages.header("base", 1.5, seq=7), name=["a", "b", "c"],
        position=position, velocity=np.zeros(3), effort=np.array([]))


@pytest.mark.parametrize("case, msg", [
    ("int64 array in a float64[]: rosbags writes the raw int64 bits",
     _joint_state(np.array([1, -2, 3], dtype=np.int64))),
    ("float32 array in a float64[]", _joint_state(np.array([1, 2, 3], dtype=np.float32))),
    ("big-endian float64 array", _joint_state(np.array([1.5, -2, 3], dtype=">f8"))),
    ("2-D array", _joint_state(np.zeros((3, 2)))),
    ("bytes instead of an array", _joint_state(b"abc")),
    ("negative uint32 seq", messages.msg_class("std_msgs/Header")(
        seq=-1, stamp=messages.time_msg(0.0), frame_id="x")),
    ("float32 out of range", messages.msg_class("sensor_msgs/LaserScan")(
        header=messages.header("l", 0.0), angle_min=1e300, angle_max=0.0, angle_increment=0.0,
        time_increment=0.0, scan_time=0.0, range_min=0.0, range_max=0.0,
        ranges=np.zeros(2, np.float32), intensities=np.zeros(0, np.float32))),
    ("covariance of 35", messages.msg_class("geometry_msgs/PoseWithCovariance")(
        pose=messages.msg_class("geometry_msgs/Pose")(
            position=messages.msg_class("geometry_msgs/Point")(x=0.0, y=0.0, z=0.0),
            orientation=messages.msg_class("geometry_msgs/Quaternion")(x=0.0, y=0.0, z=0.0, w=1.0)),
        covariance=np.zeros(35))),
    ("bytes as a string", messages.msg_class("std_msgs/String")(data=b"abc")),
])
def test_values_refused_by_the_fast_path_end_as_rosbags_ends_them(case, msg):
    theirs = _outcome(lambda m: STORE.serialize_ros1(m, m.__msgtype__), msg)
    assert _outcome(Ros1Serializer(STORE).serialize, msg) == theirs, case
    with pytest.raises(Exception):  # the generated function refused it: rosbags decided
        generate(STORE, msg.__msgtype__)(msg)


def test_unsupported_type_is_serialised_by_rosbags():
    fields = [("x", (Nodetype.BASE, ("float128", 0)))]
    store = SimpleNamespace(get_msgdef=lambda name: SimpleNamespace(fields=fields),
                            serialize_ros1=lambda msg, name: memoryview(b"from rosbags"))
    with pytest.raises(UnsupportedType, match="float128"):
        generate(store, "pkg/msg/Wide")
    serializer = Ros1Serializer(store)
    assert serializer.function("pkg/msg/Wide") is None
    msg = SimpleNamespace(__msgtype__="pkg/msg/Wide", x=1.0)
    assert serializer.serialize(msg) == b"from rosbags"


def test_one_function_per_type():
    serializer = Ros1Serializer(STORE)
    first = serializer.function("nav_msgs/msg/Odometry")
    assert serializer.function("nav_msgs/msg/Odometry") is first
