"""``rostopic pub`` for a sequence: publishes given messages once each, at given simulated times.

Node type ``rostopic/timed_pub``. Messages are built from the typestore's field definitions and
all checked when the node is constructed, so an unknown field stops the launch before time
starts, naming the allowed ones. Parameters and message format: docs/launch_files.md, "The
project's own publishers".
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from twil_control.errors import TwilControlError

from ..core import messages
from ..core.messages import msg_class, typestore
from ..core.paths import InputPathError, find_file
from ..core.ros_node import RosNode
from ..core.yaml_io import YamlError, display_path, load_yaml

# numpy dtypes of ROS base types that become arrays
_NUMERIC = {
    "bool": np.bool_,
    "int8": np.int8,
    "uint8": np.uint8,
    "byte": np.uint8,
    "char": np.uint8,
    "int16": np.int16,
    "uint16": np.uint16,
    "int32": np.int32,
    "uint32": np.uint32,
    "int64": np.int64,
    "uint64": np.uint64,
    "float32": np.float32,
    "float64": np.float64,
}
_INT = {"int8", "uint8", "byte", "char", "int16", "uint16", "int32", "uint32", "int64", "uint64"}


class TimedPubError(TwilControlError, ValueError):
    """A message sequence that cannot be published (bad field, bad time, bad file)."""


@dataclass
class TimedPubParams:
    topic: str
    type: str
    messages: list = field(default_factory=list)
    file: str = ""
    latch: bool = False


def _base_default(kind: str):
    if kind == "string":
        return ""
    if kind == "bool":
        return False
    if kind in _INT:
        return 0
    if kind in ("float32", "float64"):
        return 0.0
    if kind in ("time", "duration"):
        raise TimedPubError(f"unsupported base type {kind}")
    raise TimedPubError(f"unknown base type {kind}")


def _base_value(kind: str, value, where: str):
    if kind == "string":
        if not isinstance(value, str):
            raise TimedPubError(f"{where}: expected a string, got {value!r}")
        return value
    if kind == "bool":
        if not isinstance(value, bool):
            raise TimedPubError(f"{where}: expected true/false, got {value!r}")
        return value
    if kind in _INT:
        if isinstance(value, bool) or not isinstance(value, int):
            raise TimedPubError(f"{where}: expected an integer, got {value!r}")
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise TimedPubError(f"{where}: expected a number, got {value!r}")
    return float(value)


def build_message(typename: str, data: dict | None, where: str = "msg"):
    """A typestore message of `typename` from a dict of field values (missing fields: zero)."""
    full = messages.full_type_name(typename)
    store = typestore()
    if full not in store.fielddefs:
        msg_class(typename)  # raises the MessageTypeError with its advice
    _, fields = store.fielddefs[full]
    data = {} if data is None else data
    if not isinstance(data, dict):
        raise TimedPubError(
            f"{where}: a {messages.ros1_type_name(full)} must be a mapping of fields, got {data!r}"
        )
    allowed = [name for name, _ in fields]
    unknown = [k for k in data if k not in allowed]
    if unknown:
        raise TimedPubError(
            f"{where}: unknown field '{unknown[0]}' of {messages.ros1_type_name(full)}; "
            f"allowed fields: {', '.join(allowed)}"
        )
    values = {}
    for name, (nodetype, details) in fields:
        here = f"{where}.{name}"
        given = name in data
        value = data.get(name)
        kind = int(nodetype)
        if kind == 1:  # BASE
            base = details[0]
            values[name] = _base_value(base, value, here) if given else _base_default(base)
        elif kind == 2:  # NAME: a nested message
            values[name] = build_message(details, value if given else None, here)
        else:  # 3 ARRAY (fixed length) or 4 SEQUENCE
            (sub_type, sub_details), length = details
            items = [] if not given else value
            if not isinstance(items, list):
                raise TimedPubError(f"{here}: expected a list, got {items!r}")
            if kind == 3 and given and len(items) != length:
                raise TimedPubError(f"{here}: expected {length} values, got {len(items)}")
            if kind == 3 and not given:
                items = None
            if int(sub_type) == 1 and sub_details[0] in _NUMERIC:
                dtype = _NUMERIC[sub_details[0]]
                if items is None:
                    values[name] = np.zeros(length, dtype=dtype)
                else:
                    checked = [_base_value(sub_details[0], v, f"{here}[{i}]") for i, v in enumerate(items)]
                    values[name] = np.array(checked, dtype=dtype)
            elif int(sub_type) == 1:
                if items is None:
                    values[name] = [_base_default(sub_details[0])] * length
                else:
                    values[name] = [
                        _base_value(sub_details[0], v, f"{here}[{i}]") for i, v in enumerate(items)
                    ]
            else:
                if items is None:
                    values[name] = [build_message(sub_details, None, f"{here}[{i}]") for i in range(length)]
                else:
                    values[name] = [
                        build_message(sub_details, v, f"{here}[{i}]") for i, v in enumerate(items)
                    ]
    return msg_class(full)(**values)


class TimedPublisher(RosNode):
    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        p = self.typed_params(TimedPubParams)
        self.params = p
        where = f"node {self.fqn}"
        msg_class(p.type)  # unknown types fail here, naming the type
        if p.messages and p.file:
            raise TimedPubError(f"{where}: give 'messages' or 'file', not both")
        entries = p.messages
        if p.file:
            try:
                path = find_file(p.file, "message file")
                entries = load_yaml(path)
            except (InputPathError, YamlError) as error:
                raise TimedPubError(f"{where}: {error}") from None
            where = f"{where} (file {display_path(path)})"
            if not isinstance(entries, list):
                raise TimedPubError(f"{where}: the file must hold a list of {{time, msg}} entries")
        if not entries:
            raise TimedPubError(f"{where}: no messages to publish (give 'messages' or 'file')")
        self.schedule: list[tuple[float, dict, Any]] = []
        for i, entry in enumerate(entries):
            if not isinstance(entry, dict) or set(entry) - {"time", "msg"} or "time" not in entry:
                raise TimedPubError(
                    f"{where}: messages[{i}] must be {{time: seconds, msg: {{...}}}}, got {entry!r}"
                )
            t = entry["time"]
            if isinstance(t, bool) or not isinstance(t, (int, float)) or not (0.0 <= t < float("inf")):
                raise TimedPubError(
                    f"{where}: messages[{i}].time must be a number of seconds >= 0, got {t!r}"
                )
            data = entry.get("msg") or {}
            try:
                msg = build_message(p.type, data, f"messages[{i}].msg")
            except TimedPubError as error:
                raise TimedPubError(f"{where}: {error}") from None
            self.schedule.append((float(t), data, msg))
        self.schedule.sort(key=lambda e: e[0])  # stable: equal times keep file order
        self._has_header = any(
            name == "header" for name, _ in typestore().fielddefs[messages.full_type_name(p.type)][1]
        )
        self.publisher = self.create_publisher(p.topic, p.type, latch=p.latch)
        self.published = 0
        self._timers = []

    def on_start(self) -> None:
        t0 = self.now()
        for t in sorted({t for t, _, _ in self.schedule}):
            if t <= t0 + 1e-12:
                self._publish_due(t)
            else:
                self._timers.append(self.create_timer(t - t0, self._make_fire(t)))

    def _make_fire(self, t: float):
        def fire(event) -> None:
            self._publish_due(t)
            for timer in self._timers:
                if timer.callback is fire:
                    timer.shutdown()

        return fire

    def _publish_due(self, t: float) -> None:
        for when, data, msg in self.schedule:
            if when == t:
                if self._has_header:
                    given = data.get("header") or {}
                    msg.header = messages.header(given.get("frame_id", ""), self.now(), given.get("seq", 0))
                self.publisher.publish(msg)
                self.published += 1
