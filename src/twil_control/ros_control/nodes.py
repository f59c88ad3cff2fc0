"""The controller_manager package's scripts as nodes: ``spawner`` and ``controller_manager``.

Both talk to a controller manager only through its services, resolved as rospy would, so they
work with any manager in the graph. Unlike the ROS scripts, a controller that does not load or
start fails the node (required by default), so a launch stops instead of running without its
controller. Their arguments and the other differences: docs/ros_control.md.
"""

from __future__ import annotations

import argparse

from twil_control.core.node import ServiceError
from twil_control.core.ros_node import NodeArgsError, RosNode

from .srv import BEST_EFFORT, STRICT


def _service(node: RosNode, namespace: str | None, name: str) -> str:
    ns = (namespace or "").rstrip("/")
    return node.resolve(f"{ns}/controller_manager/{name}" if ns else f"controller_manager/{name}")


class Spawner(RosNode):
    """controller_manager/spawner."""

    required_by_default = True

    def __init__(self, master, name, namespace="/", remappings=None, args=()) -> None:
        super().__init__(master, name, namespace, remappings, args)
        parser = argparse.ArgumentParser(description="Controller spawner", add_help=False)
        parser.add_argument(
            "--stopped", action="store_true", help="loads controllers, but does not start them"
        )
        parser.add_argument("--wait-for", metavar="topic", default=None)
        parser.add_argument("--namespace", metavar="ns", default=None)
        parser.add_argument("--timeout", metavar="T", type=float, default=30.0)
        parser.add_argument("--shutdown-timeout", metavar="T", type=float, default=30.0)
        parser.add_argument("controllers", metavar="controller", nargs="+")
        self.options = self.parse_args(parser)
        self.controllers: list[str] = list(self.options.controllers)
        self.loaded: list[str] = []
        self.failed: list[str] = []
        self.started = False

    def service(self, name: str) -> str:
        return _service(self, self.options.namespace, name)

    def _call(self, name: str, *args, **request):
        return self.master.call_service(self.service(name), *args, **request)

    def on_start(self) -> None:
        if self.options.wait_for:
            self._wait_sub = self.create_subscription(self.options.wait_for, "std_msgs/Bool", self._wait_cb)
            return
        self.spawn()

    def _wait_cb(self, msg) -> None:
        if msg.data and not self.loaded and not self.failed:
            self._wait_sub.unregister()
            self.spawn()

    def spawn(self) -> None:
        """Load every controller, then start the loaded ones (unless --stopped)."""
        reasons = []
        for name in self.controllers:
            self.log.info("Loading controller: %s", name)
            try:
                response = self._call("load_controller", name)
            except ServiceError as error:
                self.failed.extend(n for n in self.controllers if n not in self.loaded)
                self.fail(
                    f"Controller Spawner couldn't find the expected controller_manager ROS interface: {error}"
                )
            if response.ok:
                self.loaded.append(name)
            else:
                self.failed.append(name)
                reasons.append(f"Failed to load {name}: {response.message}")
                self.log.error("Failed to load %s", name)
        self.log.info("Controller Spawner: Loaded controllers: %s", ", ".join(self.loaded))
        if self.loaded and not self.options.stopped:
            response = self._call(
                "switch_controller",
                start_controllers=list(self.loaded),
                stop_controllers=[],
                strictness=STRICT,
            )
            if response.ok:
                self.started = True
                self.log.info("Started controllers: %s", ", ".join(self.loaded))
            else:
                reasons.append(f"Failed to start controllers {', '.join(self.loaded)}: {response.message}")
        if reasons:
            self.fail("; ".join(reasons))

    def shutdown(self) -> None:
        if not self.loaded:
            return
        self.log.info("Shutting down spawner. Stopping and unloading controllers...")
        try:
            self._call(
                "switch_controller",
                start_controllers=[],
                stop_controllers=list(self.loaded),
                strictness=BEST_EFFORT,
            )
            for name in reversed(self.loaded):
                if not self._call("unload_controller", name).ok:
                    self.log.error("Failed to unload %s", name)
        except ServiceError as error:
            self.log.warning(
                "Controller Spawner couldn't reach controller_manager to take down controllers: %s", error
            )
        self.loaded = []


_COMMANDS = {"lc": "list", "lt": "list-types", "sp": "spawn", "kl": "kill"}
_USAGE = (
    "load <name> | unload <name> | start <name> | stop <name> | spawn <name> | kill <name> | "
    "list | list-types | reload-libraries [--restore]"
)


class ControllerManagerCli(RosNode):
    """controller_manager/controller_manager: one command of the ROS script, run at on_start()."""

    required_by_default = True

    def __init__(self, master, name, namespace="/", remappings=None, args=()) -> None:
        super().__init__(master, name, namespace, remappings, args)
        if not self.args:
            raise NodeArgsError(f"node {self.fqn}: no command given; commands: {_USAGE}")
        self.command = _COMMANDS.get(self.args[0], self.args[0])
        self.names = list(self.args[1:])
        known = ("load", "unload", "start", "stop", "spawn", "kill", "list", "list-types", "reload-libraries")
        if self.command not in known:
            raise NodeArgsError(f"node {self.fqn}: unknown command '{self.args[0]}'; commands: {_USAGE}")
        self.output: list[str] = []
        self.errors: list[str] = []  # each failed step with the manager's reason
        self.ok = True

    def _say(self, line: str) -> None:
        self.output.append(line)
        self.log.info("%s", line)

    def _call(self, name: str, *args, **request):
        return self.master.call_service(_service(self, None, name), *args, **request)

    def on_start(self) -> None:
        cmd = self.command
        if cmd == "list":
            controllers = self._call("list_controllers").controller
            if not controllers:
                self._say("No controllers are loaded in mechanism control")
            for c in controllers:
                hwi = sorted({r.hardware_interface for r in c.claimed_resources})
                self._say(f"{c.name} - {'+'.join(hwi)} ( {c.state} )")
        elif cmd == "list-types":
            for t in self._call("list_controller_types").types:
                self._say(t)
        elif cmd == "reload-libraries":
            self._reload("--restore" in self.names)
        else:
            steps = {
                "load": ["load"],
                "unload": ["unload"],
                "start": ["start"],
                "stop": ["stop"],
                "spawn": ["load", "start"],
                "kill": ["stop", "unload"],
            }[cmd]
            for step in steps:
                for name in self.names:
                    self.ok &= getattr(self, "_" + step)(name)
        if not self.ok:
            self.fail("; ".join(self.errors))

    def _step(self, response, done: str, error: str) -> bool:
        self._say(done if response.ok else error)
        if not response.ok:
            self.errors.append(f"{error}: {response.message}")
        return response.ok

    def _load(self, name: str) -> bool:
        return self._step(self._call("load_controller", name), f"Loaded {name}", f"Error when loading {name}")

    def _unload(self, name: str) -> bool:
        return self._step(
            self._call("unload_controller", name),
            f"Unloaded {name} successfully",
            f"Error when unloading {name}",
        )

    def _start(self, name: str) -> bool:
        return self._step(
            self._call("switch_controller", start_controllers=[name], stop_controllers=[], strictness=STRICT),
            f"Started {[name]} successfully",
            f"Error when starting {[name]}",
        )

    def _stop(self, name: str) -> bool:
        return self._step(
            self._call("switch_controller", start_controllers=[], stop_controllers=[name], strictness=STRICT),
            f"Stopped {[name]} successfully",
            f"Error when stopping {[name]}",
        )

    def _reload(self, restore: bool) -> None:
        before = self._call("list_controllers").controller if restore else []
        self.ok = self._call("reload_controller_libraries", force_kill=True).ok
        self._say(
            "Successfully reloaded libraries"
            if self.ok
            else "Failed to reload libraries. Do you still have controllers loaded?"
        )
        if not self.ok:
            self.errors.append(self.output[-1])
        if restore:
            for c in before:
                self._call("load_controller", c.name)
            self._call(
                "switch_controller",
                start_controllers=[c.name for c in before if c.state == "running"],
                stop_controllers=[],
                strictness=BEST_EFFORT,
            )
            self._say("Controllers restored to original state")
