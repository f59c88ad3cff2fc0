"""The two launch file formats, and everything in which they differ, in one place.

Both are read into one element tree and loaded with roslaunch's semantics. YAML, this project's
own format, is strict: what cannot mean anything in one process (``env``, ``machine``, ``test``,
``cwd``, ``launch-prefix``) is an error. roslaunch XML is a user's existing file: the same
features are accepted with one warning each, and every ``<param value>`` is typed as roslaunch
types it. Besides, the loader gives XML only the element forms it needs (``children``, a
``<rosparam>``'s ``text``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

#: Elements and their keys that both formats have (if/unless are allowed on all of them).
_COMMON_ELEMENTS: dict[str, tuple[str, ...]] = {
    "arg": ("name", "default", "value", "doc"),
    "param": ("name", "value", "type", "textfile", "command"),
    "rosparam": ("command", "file", "param", "ns", "subst_value"),
    "group": ("ns", "clear_params", "children"),
    "remap": ("from", "to"),
}

#: Refused in both formats, with the reason given to the user.
_REFUSED = {
    "param.binfile": "'binfile' is not supported; use 'textfile'",
    "rosparam.dump": "rosparam 'dump' is not supported: a launch only reads parameters",
}

#: What XML accepts with one warning (and ignores) and YAML refuses, with the reason.
_IN_PROCESS = {
    "env": "<env> sets environment variables for node processes; every node runs in this "
    "process and shares its environment",
    "machine": "<machine> declares a remote host; every node runs in this process",
    "test": "<test> nodes are run by rostest, not by roslaunch; write a pytest test instead",
    "node.machine": "'machine' runs a node on another host; every node runs in this process",
    "node.cwd": "'cwd' sets a node process's working directory; nodes run in this process",
    "node.launch-prefix": "'launch-prefix' wraps a node process (gdb, valgrind, xterm); nodes "
    "run in this process",
}

_NODE_KEYS = (
    "pkg",
    "type",
    "name",
    "ns",
    "args",
    "required",
    "respawn",
    "respawn_delay",
    "output",
    "clear_params",
)


@dataclass(frozen=True)
class LaunchFormat:
    """What one format allows, and how it resolves relative paths."""

    name: str
    elements: dict[str, tuple[str, ...]]  # element -> its keys (if/unless on all)
    top_level: tuple[str, ...]  # elements allowed in <launch> and <group>
    node_children: tuple[str, ...]  # elements inside a node's 'children'
    include_children: tuple[str, ...]  # elements inside an include's 'children'
    warned: dict[str, str]  # element or element.key -> reason, warned once
    refused: dict[str, str]  # element or element.key -> reason
    params_are_strings: bool  # every param value is a string to type


YAML = LaunchFormat(
    name="YAML",
    elements={
        **_COMMON_ELEMENTS,
        "rosparam": _COMMON_ELEMENTS["rosparam"] + ("value",),
        "node": (
            "pkg",
            "type",
            "name",
            "ns",
            "args",
            "params",
            "rosparam",
            "remap",
            "required",
            "respawn",
            "respawn_delay",
            "output",
            "clear_params",
        ),
        "include": ("file", "ns", "clear_params", "pass_all_args", "args"),
        "record": ("topics", "format", "compression"),
    },
    top_level=("arg", "param", "rosparam", "group", "node", "remap", "include", "record"),
    node_children=(),
    include_children=(),
    warned={},
    refused={
        **_REFUSED,
        **{key: reason + " (roslaunch XML accepts it with a warning)" for key, reason in _IN_PROCESS.items()},
    },
    params_are_strings=False,
)

XML = LaunchFormat(
    name="roslaunch XML",
    elements={
        **_COMMON_ELEMENTS,
        "param": _COMMON_ELEMENTS["param"] + ("binfile",),
        "rosparam": _COMMON_ELEMENTS["rosparam"] + ("text",),
        "node": _NODE_KEYS + ("cwd", "launch-prefix", "machine", "children"),
        "test": _NODE_KEYS
        + ("cwd", "launch-prefix", "machine", "children", "test-name", "time-limit", "retry"),
        "include": ("file", "ns", "clear_params", "pass_all_args", "children"),
        "env": ("name", "value"),
        "machine": (
            "name",
            "address",
            "env-loader",
            "ssh-port",
            "user",
            "password",
            "default",
            "timeout",
            "children",
        ),
    },
    top_level=("arg", "param", "rosparam", "group", "node", "remap", "include", "env", "machine", "test"),
    node_children=("param", "rosparam", "remap", "env"),
    include_children=("arg", "env"),
    warned={**_IN_PROCESS, "launch.deprecated": "the launch file says it is deprecated"},
    refused=dict(_REFUSED),
    params_are_strings=True,
)


def format_of(path: Path) -> LaunchFormat:
    """The format of a launch file, by its name: ``.launch`` and ``.xml`` are XML."""
    return XML if path.suffix.lower() in (".launch", ".xml") else YAML
