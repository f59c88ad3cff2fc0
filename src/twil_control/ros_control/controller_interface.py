"""controller_interface (ROS 1): the Controller base class and its lifecycle.

ControllerBase with Controller<T> and MultiInterfaceController<T...> folded in: a controller
declares the hardware interfaces it needs, claims joints by getting command handles in init(),
and moves through ROS's states (a StrEnum of ROS's strings). docs/ros_control.md has the rules.
"""

from __future__ import annotations

import logging
from collections import deque
from collections.abc import Callable
from enum import StrEnum
from typing import ClassVar

from twil_control.core import names
from twil_control.core.node import Node, NodeHandle

from .hardware_interface import InterfaceResources, RobotHW
from .realtime_tools import RealtimePublisher


class ControllerLifecycle(StrEnum):
    """A controller's state as list_controllers shows it (the values go into bags as they are)."""

    CONSTRUCTED = "constructed"  # before init succeeds; never listed
    INITIALIZED = "initialized"
    RUNNING = "running"
    STOPPED = "stopped"
    WAITING = "waiting"
    ABORTED = "aborted"


CONSTRUCTED = ControllerLifecycle.CONSTRUCTED
INITIALIZED = ControllerLifecycle.INITIALIZED
RUNNING = ControllerLifecycle.RUNNING
STOPPED = ControllerLifecycle.STOPPED
WAITING = ControllerLifecycle.WAITING
ABORTED = ControllerLifecycle.ABORTED
STATES = (INITIALIZED, RUNNING, STOPPED, WAITING, ABORTED)


class ControllerNodeHandle(NodeHandle):
    """A NodeHandle that remembers its subscriptions, so unloading a controller drops them
    (in ROS, destroying the controller shuts its subscribers down)."""

    def __init__(self, node: Node, namespace: str, subscriptions: list, outbox: deque) -> None:
        super().__init__(node, namespace)
        self._subscriptions = subscriptions
        self._outbox = outbox

    def create_realtime_publisher(self, topic: str, msgtype: str) -> RealtimePublisher:
        """A publisher for update(): the message goes out after the real-time cycle."""
        return RealtimePublisher(self.create_publisher(topic, msgtype), self._outbox)

    def create_subscription(self, topic: str, msgtype: str, callback: Callable):
        sub = super().create_subscription(topic, msgtype, callback)
        self._subscriptions.append(sub)
        return sub

    def child(self, namespace: str) -> ControllerNodeHandle:
        return ControllerNodeHandle(
            self.node, names.resolve(namespace, self.namespace), self._subscriptions, self._outbox
        )


class Controller:
    """Base of every controller plugin. Subclass, set ``hardware_interfaces``, override init/update.

    In ``init`` return ``self.fail("reason")`` to refuse loading: the reason is logged at ERROR
    and the controller manager reports it with "Initializing controller '<name>' failed".
    """

    #: interface type names this controller needs (Controller<T> / MultiInterfaceController<T...>)
    hardware_interfaces: ClassVar[tuple[str, ...]] = ()

    def __init__(self) -> None:
        self.state: ControllerLifecycle = CONSTRUCTED
        self.name: str = ""
        self.init_error: str = ""
        self.log: logging.Logger = logging.getLogger("twil_control.ros_control.controller")
        self._claims: dict[str, list[str]] = {}

    # -- to override ---------------------------------------------------------------------
    def init(self, hw: RobotHW, root_nh: ControllerNodeHandle, controller_nh: ControllerNodeHandle) -> bool:
        return True

    def starting(self, time: float) -> None:
        """Called in the real-time loop just before the first update()."""

    def update(self, time: float, period: float) -> None:
        raise NotImplementedError(f"{type(self).__name__} does not implement update()")

    def stopping(self, time: float) -> None:
        """Called in the real-time loop after the last update()."""

    def waiting(self, time: float) -> None:
        """Called while a start waits for the hardware to switch (unused: switches are immediate)."""

    def aborting(self, time: float) -> None:
        """Called when the controller is aborted (its update raised, or its start failed)."""

    def claimed_resources(self) -> list[InterfaceResources]:
        """ControllerInfo.claimed_resources: one entry per declared interface, joints sorted.

        Interfaces the controller took handles from without declaring them are listed after.
        """
        ifaces = list(self.hardware_interfaces) + [
            i for i in self._claims if i not in self.hardware_interfaces
        ]
        return [InterfaceResources(i, list(self._claims.get(i, []))) for i in ifaces]

    # -- helpers -------------------------------------------------------------------------
    def fail(self, reason: str) -> bool:
        """Log `reason` at ERROR, remember it, and return False (for ``return self.fail(...)``)."""
        self.init_error = reason
        self.log.error("%s", reason)
        return False

    # -- ControllerBase requests (called by the controller manager) -----------------------
    def init_request(
        self, hw: RobotHW, root_nh: ControllerNodeHandle, controller_nh: ControllerNodeHandle
    ) -> bool:
        """ControllerBase::initRequest: run init() while recording the joints it claims."""
        if self.state != CONSTRUCTED:
            return self.fail(f"controller '{self.name}' has already been initialized")
        hw.clear_claims()
        ok = self.init(hw, root_nh, controller_nh)
        self._claims = hw.get_claims()
        hw.clear_claims()
        if ok is not True:  # None (forgotten return) counts as failure, as a C++ bool would not
            if ok is None:
                return self.fail(f"{type(self).__name__}.init() returned None instead of True/False")
            return False
        self.state = INITIALIZED
        return True

    def start_request(self, time: float) -> bool:
        """ControllerBase::startRequest: start from initialized, stopped, waiting (or running)."""
        if self.state in (RUNNING, INITIALIZED, STOPPED, WAITING):
            self.starting(time)
            self.state = RUNNING
            return True
        return False

    def stop_request(self, time: float) -> bool:
        if self.state == RUNNING:
            self.stopping(time)
            self.state = STOPPED
            return True
        return False

    def wait_request(self, time: float) -> bool:
        if self.state in (INITIALIZED, STOPPED):
            self.waiting(time)
            self.state = WAITING
            return True
        return False

    def abort_request(self, time: float) -> bool:
        """Mark the controller aborted (terminal: unload and load it again to use it)."""
        self.state = ABORTED
        self.aborting(time)
        return True

    def update_request(self, time: float, period: float) -> None:
        if self.state == RUNNING:
            self.update(time, period)

    def is_running(self) -> bool:
        return self.state == RUNNING

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.name!r} {self.state}>"
