"""``node`` elements and the remaps they take, into the plan's NodeSpecs.

Node names must be unique. Remaps apply to the nodes that follow them in the same group, file,
and included files; a node's own remaps come last. A node's parameters are set in roslaunch's
order: its rosparam loads, the scope's ``~params``, its own params.
"""

from __future__ import annotations

import re
import shlex
from typing import Any

from twil_control.core import names
from twil_control.launch.param_elements import ParamElements
from twil_control.launch.plan import NodeSpec
from twil_control.launch.recording import RecordElements
from twil_control.launch.scope import Scope, kind

OUTPUTS = ("log", "screen")


class NodeElements(ParamElements, RecordElements):
    """The ``node`` and ``remap`` elements (a ``rosbag record`` node is recording.py's)."""

    def __init__(self) -> None:
        super().__init__()
        self.nodes: list[NodeSpec] = []
        self.node_sources: dict[str, str] = {}  # node name -> where it is declared

    def on_node(self, body: dict, path: tuple, scope: Scope) -> None:
        pkg, type_, name = (
            self.text(scope, body, key, path, "node", required=True, hint="a node needs pkg, type and name")
            for key in ("pkg", "type", "name")
        )
        try:
            names.validate_base(name)
        except names.GraphNameError as exc:
            self.fail(scope, path + ("name",), str(exc))
        ns = self.namespace(scope, body, path)
        if (pkg, type_) == ("rosbag", "record"):
            self.record_node(scope, body, path, ns)
            return
        fqn = names.node_fqn(ns, name)
        where = self.where(scope, path)
        if fqn in self.node_sources:
            self.fail(
                scope,
                path,
                f"duplicate node name {fqn!r} (first declared at "
                f"{self.node_sources[fqn]}); roslaunch requires unique "
                f"node names: change 'name' or 'ns'",
            )
        output = self.text(scope, body, "output", path, "node") or "log"
        if output not in OUTPUTS:
            self.fail(
                scope, path + ("output",), f"node output must be one of {', '.join(OUTPUTS)}, got {output!r}"
            )
        self.clear_params(scope, body, path, "node")
        remaps = scope.remap_args()
        for pair in self.node_remaps(scope, body.get("remap"), path + ("remap",)):
            _add_remap(remaps, pair)
        # roslaunch's order: the node's rosparam loads, the scope's ~params, the node's params
        params_later: list[tuple[dict, tuple]] = []
        if "rosparam" in body:
            self.node_rosparams(scope, body["rosparam"], path + ("rosparam",), fqn)
        for element, child, here in self.entries(
            body.get("children"), path + ("children",), scope, scope.file.format.node_children, "node"
        ):
            if element == "remap":
                _add_remap(remaps, self.remap_pair(scope, child, here))
            elif element == "rosparam":
                self.on_rosparam(child, here, scope, node=fqn)
            elif element == "param":
                params_later.append((child, here))
        for key, value, source in scope.private_params:
            self.params.set(names.join(fqn, key), value, source=source)
        if "params" in body:
            self.node_params(scope, body["params"], path + ("params",), fqn)
        for child, here in params_later:
            self.on_param(child, here, scope, node=fqn)
        try:
            remappings = names.resolve_remappings(dict(remaps), ns, name)
        except names.GraphNameError as exc:
            self.fail(scope, path, f"node {fqn!r}: {exc}")
        self.node_sources[fqn] = where
        args = self.node_args(scope, body.get("args"), path + ("args",))
        self.nodes.append(
            NodeSpec(
                pkg=pkg,
                type=type_,
                name=name,
                namespace=ns,
                args=args,
                arg_sources=_arg_sources(body.get("args"), args),
                remappings=remappings,
                required=self.flag(scope, body, "required", path) if "required" in body else None,
                source=where,
                output=output,
                respawn=self.flag(scope, body, "respawn", path),
                respawn_delay=self.number(scope, body, "respawn_delay", path, 0.0),
            )
        )

    def number(self, scope: Scope, body: dict, key: str, path: tuple, default: float) -> float:
        if key not in body:
            return default
        raw = body[key]
        value = self.sub(scope, raw, path + (key,)) if isinstance(raw, str) else raw
        try:
            number = float(value)
        except (TypeError, ValueError):
            self.fail(scope, path + (key,), f"{key!r} must be a number, got {value!r}")
        if not number >= 0 or number == float("inf"):
            self.fail(scope, path + (key,), f"{key!r} must be a finite number >= 0, got {value!r}")
        return number

    def node_params(self, scope: Scope, raw: Any, path: tuple, fqn: str) -> None:
        if not isinstance(raw, dict):
            self.fail(
                scope,
                path,
                f"node 'params' must be a mapping of private parameter names to values, got {kind(raw)}",
            )
        self.load_params(scope, self.sub_tree(scope, raw, path), fqn, path)

    def node_rosparams(self, scope: Scope, raw: Any, path: tuple, fqn: str) -> None:
        entries = (
            [(raw, path)]
            if isinstance(raw, dict)
            else ([(entry, path + (i,)) for i, entry in enumerate(raw)] if isinstance(raw, list) else None)
        )
        if entries is None:
            self.fail(scope, path, f"node 'rosparam' must be a list of rosparam mappings, got {kind(raw)}")
        for entry, here in entries:
            if not isinstance(entry, dict):
                self.fail(scope, here, f"a node's rosparam entry must be a mapping, got {kind(entry)}")
            self.check_keys(scope, "rosparam", entry, here)
            if self.condition(scope, entry, here):
                self.on_rosparam(entry, here, scope, node=fqn)

    def node_remaps(self, scope: Scope, raw: Any, path: tuple) -> list[tuple[str, str]]:
        """A node's remaps: a list of {from, to} or a mapping {from: to}."""
        if raw is None:
            return []
        if isinstance(raw, dict):
            return [
                self.remap_pair(scope, {"from": key, "to": value}, path + (key,))
                for key, value in raw.items()
            ]
        if not isinstance(raw, list):
            self.fail(
                scope,
                path,
                f"node 'remap' must be a list of {{from, to}} or a mapping of from: to, got {kind(raw)}",
            )
        pairs = []
        for i, entry in enumerate(raw):
            here = path + (i,)
            if not isinstance(entry, dict):
                self.fail(scope, here, f"a remap must be a mapping {{from: ..., to: ...}}, got {kind(entry)}")
            self.check_keys(scope, "remap", entry, here)
            if self.condition(scope, entry, here):
                pairs.append(self.remap_pair(scope, entry, here))
        return pairs

    def on_remap(self, body: dict, path: tuple, scope: Scope) -> None:
        _add_remap(scope.remaps, self.remap_pair(scope, body, path))

    def remap_pair(self, scope: Scope, body: dict, path: tuple) -> tuple[str, str]:
        pair = []
        for key in ("from", "to"):
            value = self.text(scope, body, key, path, "remap", required=True)
            try:
                pair.append(names.canonical(names.validate(value)))
            except names.GraphNameError as exc:
                self.fail(scope, path, f"remap {key!r}: {exc}")
        return pair[0], pair[1]


_WHOLE_ARG = re.compile(r"\$\(arg\s+([^\s()]+)\)")


def _arg_sources(raw: Any, args: list[str]) -> dict[int, str]:
    """Which node args are, whole, the value of a launch arg (``-x $(arg x)``), so that a node
    refusing a value can name the arg the user set; {} when the split does not line up."""
    if isinstance(raw, str):  # "$(arg x)" holds a space: mark it before splitting like a shell
        try:
            raw = shlex.split(_WHOLE_ARG.sub(lambda m: f"$(arg\0{m.group(1)})", raw))
        except ValueError:
            return {}
        raw = [token.replace("\0", " ") for token in raw]
    if not isinstance(raw, list) or len(raw) != len(args):
        return {}
    return {
        i: m.group(1)
        for i, token in enumerate(raw)
        if isinstance(token, str) and (m := _WHOLE_ARG.fullmatch(token))
    }


def _add_remap(remaps: list[tuple[str, str]], pair: tuple[str, str]) -> None:
    """roslaunch's add_remap: a later remap of the same 'from' replaces the earlier."""
    remaps[:] = [r for r in remaps if r[0] != pair[0]] + [pair]
