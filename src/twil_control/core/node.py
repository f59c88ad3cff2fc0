"""Nodes and the master: the rospy-like API every ROS-role node is written against.

`Master` plays roscore (parameters, the bus, the simulated clock, every node's timers); `Node` is
what a rospy script gets from init_node. Timers fire in simulated time in a fixed order, so runs
are reproducible. A callback that raises is that node's failure (a ROS node process dying), handed
to the launch's failure handler; without one (a Master on its own, in unit tests) it propagates
(docs/runtime.md).
"""

from __future__ import annotations

import logging
import math
import zlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, TypeVar

import numpy as np

from twil_control.errors import InputError, TwilControlError

from . import names
from .bus import Bus
from .clock import SimClock
from .params import ParamError, ParamServer, param_error
from .typed_params import load_typed

T = TypeVar("T")
_MISSING = object()


@dataclass
class TimerEvent:
    """What a timer callback receives (rospy.timer.TimerEvent's fields that matter here)."""

    current_expected: float
    last_expected: float | None


class NodeFailure(TwilControlError):
    """A node ended itself with an error (RosNode.fail): the message is the reason, complete;
    no traceback is shown for it."""


class Timer:
    def __init__(self, node: Node, period: float, callback: Callable[[TimerEvent], None], index: int) -> None:
        if not (period > 0 and math.isfinite(period)):
            raise InputError(f"{node.fqn}: timer period must be a positive number of seconds (got {period})")
        self.node, self.period, self.callback, self.index = node, float(period), callback, index
        self.last_expected: float | None = None
        self.active = True
        self._next = 0.0  # when Master.spin_until fires it next (set by Node.create_timer)

    def fire(self, t: float) -> None:
        if not self.active:
            return
        try:
            self.callback(TimerEvent(t, self.last_expected))
        except Exception as error:
            self.node.master.node_failed(self.node.fqn, error)
        self.last_expected = t

    def shutdown(self) -> None:
        self.active = False


class ServiceError(TwilControlError, RuntimeError):
    """A service that is not advertised, or one advertised twice."""


def check_seed(seed: object, what: str = "--seed") -> int:
    """A run's seed: an integer >= 0, what numpy's SeedSequence takes (every random stream of a
    run is derived from it: Master.rng) and what a sweep accepts; ValueError naming `what`."""
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise InputError(f"{what} must be an integer >= 0 (got {seed!r})")
    return seed


class Master:
    """roscore's role: parameters, topics, services, clock, and the registry of nodes and timers."""

    def __init__(self, params: ParamServer | None = None, clock: SimClock | None = None) -> None:
        self.clock = clock or SimClock()
        self.params = params or ParamServer()
        self.bus = Bus(self.clock)
        self.nodes: dict[str, Node] = {}
        self.timers: list[Timer] = []
        self.services: dict[str, tuple[str, Callable]] = {}
        self.seed = 0
        #: failure_handler(node_fqn, error) decides what a node's failure does (the launch sets
        #: it); None: the error propagates to whoever drives time
        self.failure_handler: Callable[[str, BaseException], None] | None = None
        self.bus.on_callback_error = lambda failed: self.node_failed(failed.node, failed)

    def rng(self, key: str) -> np.random.Generator:
        """A random generator for one consumer (a node, a sensor), derived from the run's seed
        and a stable key, so adding a node does not change another node's random stream."""
        return np.random.default_rng([self.seed, zlib.crc32(key.encode())])

    def advertise_service(self, name: str, node: str, handler: Callable) -> None:
        if name in self.services:
            raise ServiceError(f"{node}: service {name} is already provided by {self.services[name][0]}")
        self.services[name] = (node, handler)

    def call_service(self, name: str, *args, **kwargs):
        """Call a service synchronously (rospy.ServiceProxy's role); its errors propagate."""
        if name not in self.services:
            known = ", ".join(sorted(self.services)) or "none"
            raise ServiceError(f"service {name} is not advertised (advertised: {known})")
        return self.services[name][1](*args, **kwargs)

    def register(self, node: Node) -> None:
        if node.fqn in self.nodes:
            raise InputError(f"a node named {node.fqn} already exists")
        self.nodes[node.fqn] = node

    def node_failed(self, fqn: str, error: BaseException) -> None:
        """A callback of node `fqn` raised `error` (or the node called fail())."""
        if self.failure_handler is None:
            raise error
        self.failure_handler(fqn, error)

    def stop_node(self, fqn: str) -> None:
        """Take a node out of the running graph, as its process exiting would: its timers stop,
        its subscriptions and services are withdrawn (its publishers stay advertised, silent),
        and its name is free for a new instance (respawn)."""
        for timer in self.timers:
            if timer.node.fqn == fqn:
                timer.shutdown()
        self.bus.unsubscribe_node(fqn)
        for name in [name for name, (owner, _) in self.services.items() if owner == fqn]:
            del self.services[name]
        self.nodes.pop(fqn, None)

    def spin_until(self, t_end: float) -> None:
        """Fire every timer due up to t_end in simulated time (unit tests' executor).

        Timers fire at multiples of their period after their creation, like rospy.Timer; ties
        go in creation order.
        """
        while True:
            due = [(tm._next, tm.index, tm) for tm in self.timers if tm.active]
            if not due:
                break
            t, _, timer = min(due, key=lambda d: (d[0], d[1]))
            if t > t_end + 1e-12:
                break
            self.clock.set(t)
            timer._next = t + timer.period
            timer.fire(t)
        self.clock.set(max(self.clock.now(), t_end))


class Node:
    """A ROS node: names, params, pub/sub, timers and logging in one namespace."""

    def __init__(
        self, master: Master, name: str, namespace: str = "/", remappings: dict[str, str] | None = None
    ) -> None:
        names.validate(name)
        self.master = master
        self.name = name
        self.namespace = names.canonical(namespace or "/")
        self.fqn = names.join(self.namespace, name)
        self.remappings = dict(remappings or {})
        self.log = logging.getLogger("twil_control.node" + self.fqn.replace("/", "."))
        self._logged_once: set[str] = set()
        master.register(self)

    # -- names and time ----------------------------------------------------------------
    def resolve(self, name: str) -> str:
        return names.resolve(name, self.namespace, self.name, self.remappings)

    def now(self) -> float:
        return self.master.clock.now()

    # -- parameters --------------------------------------------------------------------
    def get_param(self, name: str, default: Any = _MISSING):
        """rospy.get_param: a missing parameter without a default is an error naming it."""
        key = names.resolve(name, self.namespace, self.name)
        if default is _MISSING:
            return self.master.params.get(key)
        return self.master.params.get(key, default)

    def typed_params(self, schema: type[T], namespace: str = "~") -> T:
        """This node's parameters under `namespace`, checked against a dataclass schema (its
        warnings about parameters a ROS package ignores go to this node's log)."""
        return load_typed(
            self.master.params, names.resolve(namespace, self.namespace, self.name), schema, self.log.warning
        )

    # -- topics and timers -------------------------------------------------------------
    def create_publisher(self, topic: str, msgtype: str, *, latch: bool = False):
        return self.master.bus.advertise(self.resolve(topic), msgtype, node=self.fqn, latch=latch)

    def create_subscription(self, topic: str, msgtype: str, callback: Callable):
        return self.master.bus.subscribe(self.resolve(topic), msgtype, callback, node=self.fqn)

    def create_timer(self, period: float, callback: Callable[[TimerEvent], None]) -> Timer:
        timer = Timer(self, period, callback, len(self.master.timers))
        timer._next = self.now() + timer.period
        self.master.timers.append(timer)
        return timer

    # -- logging -----------------------------------------------------------------------
    def log_once(self, level: int, key: str, message: str) -> None:
        """Log `message` the first time `key` is seen (ROS_ERROR_ONCE's role)."""
        if key not in self._logged_once:
            self._logged_once.add(key)
            self.log.log(level, message)

    def shutdown(self) -> None:
        """Called once when the launch ends (normal end, Ctrl-C or error)."""


class NodeHandle:
    """roscpp's NodeHandle: a node's API with relative names resolved in another namespace.

    ros_control hands controllers two of these: root_nh (the controller manager's namespace)
    and controller_nh (<that namespace>/<controller name>). Publishers and subscribers belong
    to the owning node, as in roscpp.
    """

    def __init__(self, node: Node, namespace: str) -> None:
        self.node = node
        self.namespace = names.canonical(namespace)
        self.log = node.log

    def resolve(self, name: str) -> str:
        if name.startswith("~"):
            raise names.GraphNameError(
                f"private name '{name}' cannot be used with a NodeHandle "
                f"in {self.namespace}; use a relative name"
            )
        return names.resolve(name, self.namespace, None, self.node.remappings)

    def now(self) -> float:
        return self.node.now()

    def get_param(self, name: str, default: Any = _MISSING):
        key = names.resolve(name, self.namespace)
        if default is _MISSING:
            return self.node.master.params.get(key)
        return self.node.master.params.get(key, default)

    def has_param(self, name: str) -> bool:
        return self.node.master.params.has(names.resolve(name, self.namespace))

    def typed_params(self, schema: type[T], namespace: str = "") -> T:
        ns = self.namespace if not namespace else names.resolve(namespace, self.namespace)
        return load_typed(self.node.master.params, ns, schema, self.node.log.warning)

    def param_error(self, name: str, problem: str) -> ParamError:
        """ParamError for parameter `name` (relative to this handle): where it was set, its name
        and value, and `problem` ("must be ...")."""
        return param_error(self.node.master.params, names.resolve(name, self.namespace), problem)

    def create_publisher(self, topic: str, msgtype: str, *, latch: bool = False):
        return self.node.master.bus.advertise(self.resolve(topic), msgtype, node=self.node.fqn, latch=latch)

    def create_subscription(self, topic: str, msgtype: str, callback: Callable):
        return self.node.master.bus.subscribe(self.resolve(topic), msgtype, callback, node=self.node.fqn)

    def child(self, namespace: str) -> NodeHandle:
        return NodeHandle(self.node, names.resolve(namespace, self.namespace))
