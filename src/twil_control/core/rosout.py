"""/rosout: every log line of the launch's nodes as a rosgraph_msgs/Log, as rosconsole sends it.

A logging handler publishes each record at INFO or above from its node, stamped with simulated
time. Lines logged while the launch is built, before the recorder subscribes, are kept and
published again (:meth:`RosoutHandler.replay`), so the bag holds them too (docs/runtime.md).
"""

from __future__ import annotations

import logging

from .bus import Publisher
from .messages import header, msg_class

__all__ = ["RosoutHandler", "LEVELS"]

#: Python level -> rosgraph_msgs/Log level
LEVELS = ((logging.CRITICAL, 16), (logging.ERROR, 8), (logging.WARNING, 4), (logging.INFO, 2), (0, 1))
_NODE_PREFIX = "twil_control.node"


def node_of(logger_name: str) -> str:
    if logger_name.startswith(_NODE_PREFIX):
        return logger_name[len(_NODE_PREFIX) :].replace(".", "/") or "/"
    return "/" + logger_name.removeprefix("twil_control.").replace(".", "/")


class RosoutHandler(logging.Handler):
    """Publishes log records on the master's bus as /rosout; attach() / detach() around a run."""

    def __init__(self, master, level: int = logging.INFO) -> None:
        super().__init__(level)
        self.master = master
        self._publishers: dict[str, Publisher] = {}
        self._busy = False
        self._backlog: list | None = []  # kept until replay(): the lines before recording
        self._msg = msg_class("rosgraph_msgs/Log")
        self._seq = 0

    def attach(self) -> RosoutHandler:
        logging.getLogger("twil_control").addHandler(self)
        return self

    def detach(self) -> None:
        logging.getLogger("twil_control").removeHandler(self)

    def emit(self, record: logging.LogRecord) -> None:
        if self._busy:  # a /rosout subscriber that logs must not recurse
            return
        self._busy = True
        try:
            node = node_of(record.name)
            level = next(code for threshold, code in LEVELS if record.levelno >= threshold)
            bus = self.master.bus
            topics = sorted(t for t in bus.topic_types() if node in bus.publishers_of(t))
            msg = self._msg(
                header=header("", self.master.clock.now(), self._seq),
                level=level,
                name=node,
                msg=record.getMessage(),
                file=record.pathname,
                function=record.funcName,
                line=record.lineno,
                topics=topics,
            )
            self._seq += 1
            if self._backlog is not None:
                self._backlog.append((node, msg))
            self._publisher(node).publish(msg)
        except Exception:  # logging must never break a run
            self.handleError(record)
        finally:
            self._busy = False

    def _publisher(self, node: str):
        if node not in self._publishers:
            self._publishers[node] = self.master.bus.advertise("/rosout", "rosgraph_msgs/Log", node=node)
        return self._publishers[node]

    def replay(self, write) -> None:
        """Hand the lines logged so far to ``write(topic, msgtype, msg, t)`` (the bag recorder's
        listener) and stop keeping them."""
        for _, msg in self._backlog or []:
            write(
                "/rosout",
                "rosgraph_msgs/msg/Log",
                msg,
                msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9,
            )
        self._backlog = None
