"""The contract between the launch runner and node types.

A node type is a RosNode subclass constructed as ``cls(master, name, namespace, remappings,
args)``. The runner calls the hooks below on every node in launch-file order (make_simulation,
build_world, build_systems, on_start, between_slices/is_done, shutdown); each is a no-op here and
a node type overrides the ones it needs. Their order and what a failure in each means:
docs/runtime.md.
"""

from __future__ import annotations

import argparse
import shlex
from typing import Any, ClassVar, NoReturn

from twil_control.errors import TwilControlError

from .node import Master, Node, NodeFailure


class NodeArgsError(TwilControlError, ValueError):
    """A node's command-line args (the launch file's `args`) are malformed."""


class RosNode(Node):
    """Base class of node types: a Node plus the runner's hooks (no-ops unless overridden)."""

    #: whether the launch stops when this node fails, unless the launch file says otherwise
    #: (roslaunch's required="true"); see docs/failures.md for which types are and why
    required_by_default: ClassVar[bool] = False

    # -- the runner's hooks (the simulation is world.simulation.Simulation; core sees no Drake) --
    def make_simulation(self) -> Any:
        """The simulated world, made by the one node that simulates it (see `simulates`)."""
        raise NotImplementedError(f"node {self.fqn} simulates no world")

    def build_world(self, sim: Any) -> None:
        """Add models to the simulation before its plant is finalized."""

    def build_systems(self, sim: Any) -> None:
        """Add Drake systems wired to the finalized plant."""

    def on_start(self) -> None:
        """The simulation is built and time is 0."""

    def between_slices(self) -> None:
        """Between two slices of simulated time (the simulator's context may change here)."""

    def is_done(self) -> bool:
        """Whether this node has done its work, which ends the run."""
        return False

    @classmethod
    def simulates(cls) -> bool:
        """Whether this node type makes the simulated world (overrides make_simulation)."""
        return cls.make_simulation is not RosNode.make_simulation

    @classmethod
    def build_hooks(cls) -> list[str]:
        """The build hooks this node type overrides: a node with any adds to the simulated
        world, so it needs one and cannot be rebuilt while time runs (respawned)."""
        own = {
            "make_simulation": cls.make_simulation is not RosNode.make_simulation,
            "build_world": cls.build_world is not RosNode.build_world,
            "build_systems": cls.build_systems is not RosNode.build_systems,
        }
        return [name for name, overridden in own.items() if overridden]

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
