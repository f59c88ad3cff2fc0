"""twist_mux's role: several geometry_msgs/Twist inputs, one output, by priority.

Parameters as twist_mux reads them (husky_control's and jackal_control's YAML). An input's message
goes out when it is the highest-priority input neither timed out nor below an engaged lock (ties:
the first listed; priority 0 never wins, as twist_mux's strict comparison from 0 has it). Nothing
is published by time alone: when every input stops the output stops, and the controller's own
cmd_vel_timeout brings the robot to rest. No /diagnostics (docs/ros1.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..core.params import ParamError, source_prefix
from ..core.ros_node import RosNode


@dataclass
class Handle:
    name: str
    topic: str
    timeout: float
    priority: int
    stamp: float = 0.0
    value: object = None

    def expired(self, now: float) -> bool:
        return self.timeout > 0.0 and now - self.stamp > self.timeout


def _handles(node: RosNode, key: str) -> list[Handle]:
    """twist_mux's ~topics or ~locks: a list of mappings with name, topic, timeout, priority."""
    full = node.resolve(f"~{key}")
    server = node.master.params
    raw = server.get(full, [])
    where = source_prefix(server.source_of(full))
    if not isinstance(raw, list):
        raise ParamError(f"{where}parameter {full!r} must be a list of {{name, topic, timeout, priority}}")
    out = []
    for i, item in enumerate(raw):
        what = f"{where}parameter {full}[{i}]"
        if not isinstance(item, dict):
            raise ParamError(
                f"{what} must be a mapping with name, topic, timeout and priority (got {item!r})"
            )
        missing = [m for m in ("name", "topic", "timeout", "priority") if m not in item]
        if missing:
            raise ParamError(
                f"{what} has no {', '.join(missing)} (twist_mux needs name, topic, timeout, priority)"
            )
        timeout, priority = item["timeout"], item["priority"]
        if isinstance(timeout, bool) or not isinstance(timeout, (int, float)) or not math.isfinite(timeout):
            raise ParamError(f"{what}: timeout must be a number of seconds (got {timeout!r})")
        if isinstance(priority, bool) or not isinstance(priority, int):
            raise ParamError(f"{what}: priority must be an integer in [0, 255] (got {priority!r})")
        if not isinstance(item["name"], str) or not isinstance(item["topic"], str):
            raise ParamError(f"{what}: name and topic must be strings")
        out.append(Handle(item["name"], item["topic"], float(timeout), min(max(priority, 0), 255)))
        extra = sorted(set(item) - {"name", "topic", "timeout", "priority"})
        if extra:
            node.log.warning(
                "%s: %s ignored, as twist_mux reads only name, topic, timeout, priority", what, extra
            )
    return out


class TwistMux(RosNode):
    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        self.inputs = _handles(self, "topics")
        self.locks = _handles(self, "locks")
        self._pub = self.create_publisher("cmd_vel_out", "geometry_msgs/Twist")
        for handle in self.inputs:
            self._announce(handle)
            self.create_subscription(
                handle.topic, "geometry_msgs/Twist", lambda m, h=handle: self._on_twist(h, m)
            )
        for handle in self.locks:
            self._announce(handle)
            self.create_subscription(handle.topic, "std_msgs/Bool", lambda m, h=handle: self._on_lock(h, m))

    def _announce(self, h: Handle) -> None:
        timeout = f"{h.timeout:f}s" if h.timeout else "None"
        self.log.info(
            "Topic handler '%s' subscribed to topic '%s': timeout = %s, priority = %d",
            h.name,
            self.resolve(h.topic),
            timeout,
            h.priority,
        )

    def lock_priority(self, now: float) -> int:
        """The highest priority of the engaged locks (0: none)."""
        engaged = [h.priority for h in self.locks if h.expired(now) or (h.value is not None and h.value.data)]
        return max(engaged, default=0)

    def selected(self, now: float) -> Handle | None:
        """The input whose messages go out now: the first of the highest priority not masked."""
        lock = self.lock_priority(now)
        best, priority = None, 0
        for h in self.inputs:
            if not h.expired(now) and h.priority >= lock and h.priority > priority:
                best, priority = h, h.priority
        return best

    def _on_twist(self, h: Handle, msg) -> None:
        now = self.now()
        h.stamp, h.value = now, msg
        if self.selected(now) is h:
            self._pub.publish(msg)

    def _on_lock(self, h: Handle, msg) -> None:
        h.stamp, h.value = self.now(), msg
