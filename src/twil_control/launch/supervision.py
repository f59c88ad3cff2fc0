"""What a node's failure does to the launch: roslaunch's process monitor for in-process nodes.

A required node's failure ends the launch (`RequiredNodeFailed` unwinds to the runner, which
closes the bag); any other node is taken out of the graph and the launch goes on, or it is
respawned from its NodeSpec. Every failure is kept, so a launch that went on without a node
exits 1 and never looks like one that went right (docs/failures.md). Respawn needs a node whose
work is only on the ROS side: build hooks cannot run again once time runs.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ..core.bus import CallbackError
from ..core.node import Master, NodeFailure
from ..core.ros_node import RosNode
from ..errors import InputError, TwilControlError
from .plan import NodeSpec

log = logging.getLogger("twil_control.launch")


@dataclass
class Failure:
    """One node failure: which node, why, when (simulated s), and what it did to the launch."""

    node: str
    reason: str
    time: float
    required: bool
    error: BaseException

    def __str__(self) -> str:
        kind = "required node" if self.required else "node"
        return f"{kind} {self.node} failed at t = {self.time:.3f} s: {self.reason}"


class RequiredNodeFailed(BaseException):
    """A required node failed: unwinds the simulation up to the runner. A BaseException, like
    KeyboardInterrupt, so that no node's ``except Exception`` swallows it on the way."""

    def __init__(self, failure: Failure) -> None:
        super().__init__(str(failure))
        self.failure = failure


def cause_of(error: BaseException) -> BaseException:
    """What a node raised: a subscription callback's error is wrapped in CallbackError."""
    cause = error.__cause__ if isinstance(error, CallbackError) else error
    return cause if cause is not None else error


def is_bug(error: BaseException) -> bool:
    """Whether a node's failure is a bug (any exception but a TwilControlError, such as a
    node's own ``fail(reason)``): its traceback is shown."""
    return not isinstance(cause_of(error), TwilControlError)


def reason_of(error: BaseException) -> str:
    """The failure's text: a node's own reason as it gave it, otherwise the exception."""
    cause = cause_of(error)
    if isinstance(cause, NodeFailure):
        return str(cause)
    if isinstance(error, CallbackError):
        return str(error)
    return f"{type(error).__name__}: {error}"


def is_required(spec: NodeSpec | None, node: RosNode) -> bool:
    """The launch file's ``required:`` if given, else the node type's default."""
    if spec is not None and spec.required is not None:
        return spec.required
    return node.required_by_default


class Supervisor:
    """Applies required/respawn to the nodes of one launch (see the module docstring)."""

    def __init__(
        self,
        master: Master,
        nodes: list,
        specs: dict[str, NodeSpec],
        construct: Callable[[NodeSpec], RosNode],
    ) -> None:
        self.master = master
        self.nodes = nodes  # the launch's list: a respawned node replaces its entry
        self.specs = specs  # fqn -> NodeSpec (nodes the runner adds have none)
        self.construct = construct
        self.failures: list[Failure] = []
        #: how a respawned node's timers fire: None = Master.spin_until (no simulated world), else
        #: the simulation's world.ros_timers.RosTimers (set by the runner; False: it has none)
        self.timer_events: Any = None
        self._respawns: list[tuple[float, NodeSpec]] = []
        self._stopped: set[str] = set()
        master.failure_handler = self.on_failure
        for node in nodes:
            spec = specs.get(node.fqn)
            if spec is not None and spec.respawn:
                self._check_respawnable(spec, node)

    def _check_respawnable(self, spec: NodeSpec, node: RosNode) -> None:
        if is_required(spec, node):
            raise InputError(
                f"{spec.source}: node {spec.fqn} is both required and respawn: a required "
                f"node's failure ends the launch, so it is never respawned; choose one"
            )
        hooks = node.build_hooks()
        if hooks:
            raise InputError(
                f"{spec.source}: node {spec.fqn} ({spec.pkg}/{spec.type}) cannot respawn: it "
                f"adds models or systems to the simulated world ({', '.join(hooks)}), which "
                f"cannot be rebuilt while time runs; remove respawn"
            )

    # -- failures ------------------------------------------------------------------------
    def on_failure(self, fqn: str, error: BaseException) -> None:
        if fqn in self._stopped:  # a callback of a node already taken out, still on the stack
            log.debug("node %s, already stopped, raised again", fqn, exc_info=error)
            return
        node = next((n for n in self.nodes if n.fqn == fqn), None)
        spec = self.specs.get(fqn)
        required = is_required(spec, node) if node is not None else True  # not a node of ours
        failure = Failure(fqn, reason_of(error), self.master.clock.now(), required, error)
        self.failures.append(failure)
        if required:
            raise RequiredNodeFailed(failure) from error
        respawn = spec is not None and spec.respawn
        log.error(
            "%s; the node is not required: the launch goes on %s",
            failure,
            "and respawns it" if respawn else "without it",
        )
        if is_bug(error):
            log.error("node %s failed on a bug", fqn, exc_info=cause_of(error))
        self.master.stop_node(fqn)
        self._stopped.add(fqn)
        if spec is not None and spec.respawn:
            self._respawns.append((failure.time + spec.respawn_delay, spec))

    def start(self, node: RosNode) -> None:
        """Run a node's on_start as a failure of that node if it raises."""
        try:
            node.on_start()
        except Exception as error:
            self.master.node_failed(node.fqn, error)

    # -- respawn -------------------------------------------------------------------------
    def respawn_due(self, now: float) -> None:
        """Restart the failed nodes whose respawn time has come (between time slices)."""
        if not self._respawns:
            return
        due = [(t, spec) for t, spec in self._respawns if t <= now + 1e-12]
        self._respawns = [(t, spec) for t, spec in self._respawns if t > now + 1e-12]
        for _, spec in due:
            self._respawn(spec)

    def _respawn(self, spec: NodeSpec) -> None:
        index = next(i for i, n in enumerate(self.nodes) if n.fqn == spec.fqn)
        old = self.nodes[index]
        try:
            old.shutdown()
        except Exception:
            log.exception("node %s failed to shut down before its respawn", spec.fqn)
        first_timer = len(self.master.timers)
        try:
            node = self.construct(spec)
        except Exception as error:  # its parameters were fine at start: something changed them
            log.error("node %s cannot be respawned: %s", spec.fqn, reason_of(error))
            return
        self.nodes[index] = node
        self._stopped.discard(spec.fqn)
        for timer in self.master.timers[first_timer:]:
            if self.timer_events is None:  # no simulated world: Master.spin_until fires every timer
                continue
            if self.timer_events is False or not self.timer_events.add(timer):
                log.error(
                    "node %s cannot be respawned: its timer of period %g s is not one the launch "
                    "started with, so the simulation has no event for it",
                    spec.fqn,
                    timer.period,
                )
                self.master.stop_node(spec.fqn)
                self._stopped.add(spec.fqn)
                return
        log.warning("respawned node %s at t = %.3f s", spec.fqn, self.master.clock.now())
        self.start(node)
