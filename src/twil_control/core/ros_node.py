"""The contract between the launch runner and node types.

A node type is a class constructed as ``cls(master, name, namespace, remappings, args)`` (the
rospy node after init_node, with its command-line args). The runner then calls, on every node
and in launch-file order, whichever of these hooks the class defines:

1. ``make_simulation() -> Simulation``: only the world node (gazebo's role); at most one.
2. ``build_world(sim)``: add models before the plant is finalized (spawn_model's role).
3. ``build_systems(sim)``: add Drake systems wired to the finalized plant (plugins' role).
4. ``on_start()``: the simulation is built and time is 0 (spawners load controllers here).
5. ``is_done() -> bool``: a node may end the run (e.g. all goals reached); optional.
6. ``shutdown()``: once, at the end, however the run ends.

A node fails (a ROS node process exiting with an error) when its ``on_start``, a timer or a
subscription callback raises, or when it calls ``self.fail(reason)``. What follows depends on
whether it is required (launch/supervision.py): ``required_by_default`` is the node type's
default, the launch file's ``required:`` overrides it. Errors in the constructor and the build
hooks (1-3) are errors in the launch itself: it is not started.
"""

from __future__ import annotations

import argparse
import shlex
from typing import ClassVar, NoReturn

from .node import Master, Node, NodeFailure


class NodeArgsError(ValueError):
    """A node's command-line args (the launch file's `args`) are malformed."""


class RosNode(Node):
    """Base class of node types: a Node plus the runner's hooks (all optional)."""

    #: whether the launch stops when this node fails, unless the launch file says otherwise
    #: (roslaunch's required="true"); see docs/failures.md for which types are and why
    required_by_default: ClassVar[bool] = False

    def __init__(
        self,
        master: Master,
        name: str,
        namespace: str = "/",
        remappings: dict[str, str] | None = None,
        args: list[str] | tuple = (),
    ) -> None:
        super().__init__(master, name, namespace, remappings)
        self.args = list(args)
        self.arg_sources: dict[int, str] = {}  # args[i] is launch arg NAME's value (the runner sets it)

    def launch_arg_of(self, option: str) -> str:
        """ " (launch arg NAME:=VALUE)" when the value after `option` in this node's args came
        whole from a launch arg, else "": so a refused value names what the user typed."""
        if option in self.args:
            i = self.args.index(option) + 1
            if i in self.arg_sources and i < len(self.args):
                return f" (launch arg {self.arg_sources[i]}:={self.args[i]})"
        return ""

    def fail(self, reason: str) -> NoReturn:
        """End this node with an error: `reason` (complete, no traceback) is reported, and the
        launch stops if the node is required, or goes on without it otherwise. Does not return."""
        raise NodeFailure(reason)

    def parse_args(self, parser: argparse.ArgumentParser) -> argparse.Namespace:
        """Parse self.args; errors name the node and the usage instead of exiting."""
        parser.prog = self.fqn

        def fail(message: str):
            raise NodeArgsError(
                f"node {self.fqn}: {message} (args: {shlex.join(self.args)!r}; "
                f"usage: {parser.format_usage().strip()})"
            )

        parser.error = fail  # argparse would call sys.exit
        return parser.parse_args(self.args)
