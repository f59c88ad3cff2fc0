"""The topic bus: in-process publish/subscribe with ROS 1 topic semantics.

Delivery is synchronous and deterministic (listeners first, then subscribers in order; a message
published inside a callback is queued, so delivery is FIFO however deep callbacks nest): the same
launch, arguments and seed give the same message sequence. A topic has one type, an error where
ROS 1 would only warn, and latched publishers keep their last message (docs/runtime.md).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from twil_control.errors import TwilControlError

from .clock import SimClock
from .messages import full_type_name, msg_class, ros1_type_name
from .wire import WireCache


class BusError(TwilControlError, RuntimeError):
    """A topic used with conflicting types, or a message of the wrong type."""


class CallbackError(RuntimeError):
    """A subscriber's callback raised; names the node and topic. The cause is chained."""

    def __init__(self, node: str, topic: str, error: BaseException) -> None:
        super().__init__(
            f"node {node or '(anonymous)'}: callback on {topic} raised {type(error).__name__}: {error}"
        )
        self.node = node
        self.topic = topic


Listener = Callable[[str, str, Any, float], None]


@dataclass
class _Topic:
    msgtype: str
    publishers: list[Publisher] = field(default_factory=list)
    subscriptions: list[Subscription] = field(default_factory=list)
    latched: Any = None
    latched_by: Publisher | None = None  # the publisher of `latched`


class Publisher:
    def __init__(self, bus: Bus, topic: str, msgtype: str, node: str, latch: bool) -> None:
        self.bus, self.topic, self.msgtype, self.node, self.latch = bus, topic, msgtype, node, latch
        self._cls = msg_class(msgtype)

    def publish(self, msg) -> None:
        if type(msg) is not self._cls:
            raise BusError(
                f"{self.node}: publishing {type(msg).__name__} on {self.topic}, "
                f"which carries {ros1_type_name(self.msgtype)}"
            )
        self.bus._enqueue(self, msg)

    def get_num_connections(self) -> int:
        return len(self.bus._topics[self.topic].subscriptions)

    def unregister(self) -> None:
        """Withdraw this publisher (rospy's Publisher.unregister, or its process ending): its
        latched message is no longer handed to subscribers that connect later."""
        entry = self.bus._topics[self.topic]
        if self in entry.publishers:
            entry.publishers.remove(self)
        if entry.latched_by is self:
            entry.latched, entry.latched_by = None, None


class Subscription:
    def __init__(self, topic: str, msgtype: str, callback: Callable, node: str) -> None:
        self.topic, self.msgtype, self.callback, self.node = topic, msgtype, callback, node
        self.active = True

    def unregister(self) -> None:
        self.active = False


class Bus:
    """The topic registry and message dispatcher (the role of roscore plus the transport)."""

    def __init__(self, clock: SimClock | None = None) -> None:
        self.clock = clock or SimClock()
        self._topics: dict[str, _Topic] = {}
        self._listeners: list[Listener] = []
        self._queue: deque = deque()
        self._delivering = False
        #: the published messages' ROS 1 bytes, serialised once for the recorder and the bridge
        self.wire = WireCache(self.clock)
        self.on_callback_error: Callable[[CallbackError], None] | None = None

    # -- graph -------------------------------------------------------------------------
    def _topic(self, topic: str, msgtype: str, who: str) -> _Topic:
        full = full_type_name(msgtype)
        msg_class(full)  # unknown types fail here, naming the type
        entry = self._topics.get(topic)
        if entry is None:
            entry = self._topics[topic] = _Topic(full)
        elif entry.msgtype != full:
            raise BusError(
                f"{who}: topic {topic} carries {ros1_type_name(entry.msgtype)}, not {ros1_type_name(full)}"
            )
        return entry

    def advertise(self, topic: str, msgtype: str, *, node: str = "", latch: bool = False) -> Publisher:
        entry = self._topic(topic, msgtype, node)
        pub = Publisher(self, topic, entry.msgtype, node, latch)
        entry.publishers.append(pub)
        return pub

    def subscribe(self, topic: str, msgtype: str, callback: Callable, *, node: str = "") -> Subscription:
        entry = self._topic(topic, msgtype, node)
        sub = Subscription(topic, entry.msgtype, callback, node)
        entry.subscriptions.append(sub)
        if entry.latched is not None:
            self._queue.append((None, sub, entry.latched))
            self._drain()
        return sub

    def unsubscribe_node(self, node: str) -> None:
        """Unregister every subscription of `node` (a node that stopped)."""
        for entry in self._topics.values():
            for sub in entry.subscriptions:
                if sub.node == node:
                    sub.unregister()

    def add_listener(self, listener: Listener) -> None:
        """Call listener(topic, msgtype, msg, time) for every message on every topic."""
        self._listeners.append(listener)

    def remove_listener(self, listener: Listener) -> None:
        """Stop calling listener (from the thread that publishes, between deliveries)."""
        self._listeners.remove(listener)

    def topic_count(self) -> int:
        """How many topics have a publisher or subscriber (grows as nodes advertise)."""
        return len(self._topics)

    def topic_types(self) -> dict[str, str]:
        """{topic: ROS 1 type name} for every topic with a publisher or subscriber."""
        return {t: ros1_type_name(e.msgtype) for t, e in sorted(self._topics.items())}

    def latched_messages(self) -> list[tuple[str, str, Any]]:
        """(topic, type, last message) of every latched topic, for late listeners."""
        return [(t, e.msgtype, e.latched) for t, e in sorted(self._topics.items()) if e.latched is not None]

    def is_latched(self, topic: str) -> bool:
        entry = self._topics.get(topic)
        return bool(entry) and any(p.latch for p in entry.publishers)

    def publishers_of(self, topic: str) -> list[str]:
        return sorted({p.node for p in self._topics[topic].publishers}) if topic in self._topics else []

    def subscribers_of(self, topic: str) -> list[str]:
        return sorted({s.node for s in self._topics[topic].subscriptions}) if topic in self._topics else []

    # -- delivery ----------------------------------------------------------------------
    def _enqueue(self, pub: Publisher, msg) -> None:
        self._queue.append((pub, None, msg))
        self._drain()

    def _drain(self) -> None:
        if self._delivering:
            return  # the outer drain loop delivers it, after the message in hand
        self._delivering = True
        try:
            while self._queue:
                pub, only_sub, msg = self._queue.popleft()
                if only_sub is not None:  # a latched message for one late subscriber
                    self._call(only_sub, msg)
                    continue
                entry = self._topics[pub.topic]
                if pub.latch:
                    entry.latched, entry.latched_by = msg, pub
                t = self.clock.now()
                for listener in self._listeners:
                    listener(pub.topic, entry.msgtype, msg, t)
                for sub in list(entry.subscriptions):
                    self._call(sub, msg)
        except BaseException:
            self._queue.clear()
            raise
        finally:
            self._delivering = False

    def _call(self, sub: Subscription, msg) -> None:
        if not sub.active:
            return
        try:
            sub.callback(msg)
        except CallbackError:
            raise
        except Exception as error:
            failed = CallbackError(sub.node, sub.topic, error)
            if self.on_callback_error is None:
                raise failed from error
            failed.__cause__ = error
            self.on_callback_error(failed)
