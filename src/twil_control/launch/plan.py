"""What a launch file amounts to once loaded: parameters, nodes and what to record.

The loader (loader.py) produces a LaunchPlan; the runner turns it into a running
graph. Keeping the plan as plain data means a launch file can be checked, printed
and tested without starting anything, like ``roslaunch --nodes`` / ``--dump-params``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

from twil_control.core import names
from twil_control.core.params import ParamServer
from twil_control.errors import TwilControlError


class LaunchError(TwilControlError, ValueError):
    """A launch file that cannot be loaded; the message names the file and line."""


@dataclass
class NodeSpec:
    """One ``node`` element, fully resolved."""

    pkg: str
    type: str
    name: str
    namespace: str  # absolute and canonical, e.g. "/twil/ros_control"
    args: list[str]  # the node's 'args', split like a shell would
    remappings: dict[str, str]  # resolved from-name -> resolved to-name
    required: bool | None = None  # roslaunch's required: its failure ends the launch; None = the
    # node type's default (launch/supervision.py)
    source: str = ""  # "file:line" of the node element
    output: str = "log"  # roslaunch's output="screen" | "log"
    respawn: bool = False  # restart it after a failure (not with required)
    respawn_delay: float = 0.0  # simulated s between the failure and the restart
    arg_sources: dict[int, str] = field(default_factory=dict)  # args[i] is launch arg NAME's value

    @property
    def fqn(self) -> str:
        """The node's fully qualified name, e.g. "/twil/controller_spawner"."""
        return names.node_fqn(self.namespace, self.name)


@dataclass(frozen=True)
class RecordOutput:
    """A ``rosbag record`` node's ``-O NAME`` or ``-o PREFIX``: where the run's bag goes."""

    name: str  # as written, ".bag" or ".mcap" included or not
    prefix: bool  # -o: NAME_<local date and time>.<format>, as rosbag names it
    source: str  # "file:line" of the node

    @property
    def option(self) -> str:
        return f"{'-o' if self.prefix else '-O'} {self.name}"

    def suffix_format(self) -> str | None:
        """The format the name's own suffix asks for, as --bag's does, or None."""
        for fmt in ("bag", "mcap"):
            if self.name.endswith(f".{fmt}"):
                return fmt
        return None

    def path(self, fmt: str) -> Path:
        """The bag's path in format ``fmt``: rosbag record's rule (the suffix dropped, the date
        joined with '_' for -o, the format's suffix added), relative to the working directory."""
        stem = self.name
        own = self.suffix_format()
        if own is not None:
            stem = stem[: -len(own) - 1]
        parts = [stem] if stem else []
        if self.prefix:
            parts.append(time.strftime("%Y-%m-%d-%H-%M-%S"))
        return Path("_".join(parts) + f".{fmt}").expanduser()


@dataclass
class LaunchPlan:
    """Everything a launch file (and what it includes) asks for."""

    args: dict[str, str]  # the top-level file's final arg values
    params: ParamServer  # all parameters, each with the file:line that set it
    nodes: list[NodeSpec]  # in file order, includes expanded in place
    record_topics: list[str] | None = None  # None: record every topic
    record_format: str | None = None  # "bag" or "mcap"; None: the command line's (default bag)
    record_compression: str | None = None  # MCAP chunks: "zstd", "lz4" or "none"; None: zstd
    record_output: RecordOutput | None = None  # a rosbag record node's -O/-o; None: --bag's or the default
    files: list[Path] = field(default_factory=list)  # every file read, in order

    def node(self, fqn: str) -> NodeSpec:
        """The node with fully qualified name ``fqn`` (KeyError naming the known ones)."""
        for spec in self.nodes:
            if spec.fqn == fqn:
                return spec
        known = ", ".join(spec.fqn for spec in self.nodes) or "none"
        raise KeyError(f"no node {fqn!r} in the launch plan; nodes: {known}")
