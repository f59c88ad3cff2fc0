"""roslaunch's loader, for launch files in roslaunch XML or in this project's YAML.

A YAML launch file mirrors roslaunch XML element for element::

    launch:
      - arg: {name: world, default: "$(find twil_control)/sim/worlds/default.sdf"}
      - param: {name: /use_sim_time, value: true}
      - rosparam: {file: config/twil.yaml, ns: /twil/ros_control}
      - group:
          ns: twil
          if: $(arg use_arm)
          children:
            - remap: {from: cmd_vel, to: /qbot/cmd_vel}
            - node: {pkg: controller_manager, type: spawner, name: spawner,
                     args: "joint_state_controller", params: {publish_rate: 100}}
      - include: {file: launch/other.launch.yaml, ns: other, args: {world: $(arg world)}}
      - record: {topics: [/joint_states, /tf], format: mcap, compression: zstd}

and an XML file (``.launch``, ``.xml``) is read into that same tree (xml_reader.py); both
are loaded here, with roslaunch's rules: args are scoped per file (an included file sees
only the args passed to it, or all of them with ``pass_all_args``) and per group; an arg
declared with ``value`` is fixed; remaps apply to the nodes that follow them in the same
group, file, and included files; ``~name`` params outside a node go to every node that
follows in the same group (and file); a node's own params override its rosparam files;
``if``/``unless`` work on every element; node names must be unique. A ``rosbag/record`` node
is the launch's recording (what to record), as YAML's ``record`` element is.

Where the formats differ (features accepted with a warning, how values are typed) is
formats.py. Both differ from roslaunch to catch mistakes it lets through: unknown elements
and attributes are errors (with did-you-mean), command-line args the file does not declare
are errors, and an arg declared with neither value nor default must be given. Relative
``file`` paths are looked up in the working directory (as roslaunch does), then next to the
launch file, then in the package root (core/paths.py).
"""
from __future__ import annotations

import difflib
import logging
import re
import shlex
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from twil_control.bag.recorder import FORMATS as RECORD_FORMATS, MCAP_COMPRESSIONS
from twil_control.core import names
from twil_control.core.params import ParamError, ParamServer
from twil_control.core.paths import InputPathError, find_file
from twil_control.core.yaml_io import (Lines, YamlError, display_path, load_yaml_with_lines,
                                       parse_yaml, read_text)
from twil_control.launch.formats import XML, YAML, LaunchFormat, format_of
from twil_control.launch.plan import LaunchError, LaunchPlan, NodeSpec
from twil_control.launch.substitutions import (SubstitutionContext, SubstitutionError,
                                               auto_type, has_substitution, substitute,
                                               to_bool)
from twil_control.launch.xml_reader import XmlLaunchError, read_xml_launch

log = logging.getLogger("twil_control.launch")

_CONDITIONS = ("if", "unless")

PARAM_TYPES = ("str", "int", "double", "bool", "yaml")
#: roslaunch's other spellings of the param types ("auto" is no type: inferred).
_PARAM_TYPE_ALIASES = {"string": "str", "boolean": "bool", "auto": None}
OUTPUTS = ("log", "screen")


@dataclass(frozen=True)
class ArgDecl:
    """An ``arg`` element as written (before substitution), for ``--ros-args`` style help."""

    name: str
    line: int
    default: Any = None
    value: Any = None
    doc: str = ""


# --------------------------------------------------------------------------------------
# Public entry points
# --------------------------------------------------------------------------------------

def load_launch(path: str | Path, arg_overrides: dict[str, str] | None = None) -> LaunchPlan:
    """Load a launch file (YAML or roslaunch XML) and everything it includes into a LaunchPlan.

    ``arg_overrides`` are the command line's ``name:=value`` args. A relative
    ``path`` is looked up in the current directory, then in the package root.
    """
    overrides = dict(arg_overrides or {})
    for name, value in overrides.items():
        if not isinstance(value, str):
            raise LaunchError(f"arg {name!r}: command-line values are strings, got {value!r}")
    loader = _Loader()
    loader.load_file(_launch_path(path), ns="/", passed=overrides, inherited={},
                     parent=None, chain=(), included_from=None)
    record = None if loader.record_all else loader.record
    return LaunchPlan(args=loader.top_args, params=loader.params, nodes=loader.nodes,
                      record_topics=record, record_format=loader.record_format,
                      record_compression=loader.record_compression, files=loader.files)


def parse_cli_args(argv: Iterable[str]) -> dict[str, str]:
    """Split roslaunch-style ``name:=value`` tokens into a dict (later tokens win)."""
    args: dict[str, str] = {}
    for token in argv:
        name, sep, value = token.partition(":=")
        if not sep or not name or any(ch.isspace() or ch == "=" for ch in name):
            raise LaunchError(f"malformed launch argument {token!r}: expected the form "
                              f"name:=value (for example world:=sim/worlds/default.sdf)")
        args[name] = value
    return args


def declared_args(path: str | Path) -> dict[str, ArgDecl]:
    """The args a launch file declares (at any group depth), as written."""
    launch_path = _launch_path(path)
    data, lines, _ = _read_launch(launch_path, included_from=None)
    return _declarations(data["launch"], ("launch",), lines)


# --------------------------------------------------------------------------------------
# Loading
# --------------------------------------------------------------------------------------

@dataclass
class _File:
    """One launch file being read."""

    path: Path
    label: str                     # the name used in messages
    lines: Lines
    passed: dict[str, str]         # args given explicitly (command line or include args)
    top: bool                      # the file named on the command line
    chain: tuple[Path, ...]        # the include stack down to this file, for recursion
    format: LaunchFormat
    columns: dict[tuple, int] = field(default_factory=dict)   # XML: element columns


@dataclass
class _Scope:
    """roslaunch's LoaderContext: namespace, visible args, remaps and ~params at one point."""

    file: _File
    ns: str
    args: dict[str, str]
    declared: dict[str, int]       # arg name -> line of its declaration in this scope
    parent: _Scope | None = None
    remaps: list[tuple[str, str]] = field(default_factory=list)
    # ~name params outside a node: (name without '~', value, source), set on every later node
    private_params: list[tuple[str, Any, str]] = field(default_factory=list)

    def child(self, ns: str) -> _Scope:
        """A group's scope: args and ~params declared inside it do not leak out."""
        return _Scope(self.file, ns, dict(self.args), dict(self.declared), parent=self,
                      private_params=list(self.private_params))

    def remap_args(self) -> list[tuple[str, str]]:
        """Remaps in force here; an inner remap of the same 'from' replaces an outer one."""
        if self.parent is None:
            return list(self.remaps)
        own = {source for source, _ in self.remaps}
        return [r for r in self.parent.remap_args() if r[0] not in own] + self.remaps


class _Loader:
    def __init__(self) -> None:
        self.params = ParamServer()
        self.nodes: list[NodeSpec] = []
        self.node_sources: dict[str, str] = {}
        self.record: list[str] | None = None
        self.record_all = False
        self.record_format: str | None = None
        self.record_compression: str | None = None
        self.files: list[Path] = []
        self.top_args: dict[str, str] = {}
        self.anon: dict[str, str] = {}
        self.warned: set[str] = set()

    # ---- files ------------------------------------------------------------------------
    def load_file(self, path: Path, *, ns: str, passed: dict[str, str],
                  inherited: dict[str, str], parent: _Scope | None,
                  chain: tuple[Path, ...], included_from: str | None,
                  pass_all: bool = False) -> None:
        """Load one launch file into the plan, in a fresh arg scope.

        ``passed`` are explicit args (command line, or an include's ``args``);
        ``inherited`` are args handed down by ``pass_all_args``.
        """
        data, lines, columns = _read_launch(path, included_from)
        self._add_file(path)
        label = display_path(path)
        declared = _declarations(data["launch"], ("launch",), lines)
        unknown = [name for name in passed if name not in declared]
        if pass_all:  # roslaunch skips the unused-args check; the extras stay usable
            passed = {name: value for name, value in passed.items() if name in declared}
        elif unknown:
            listed = ", ".join(declared) or "none"
            quoted = ", ".join(repr(name) for name in unknown)
            plural = "s" if len(unknown) > 1 else ""
            if included_from is None:
                raise LaunchError(f"unknown arg{plural} {quoted} for {label}; declared args: "
                                  f"{listed}")
            raise LaunchError(f"{included_from}: include of {label} passes undeclared "
                              f"arg{plural} {quoted}; declared args: {listed}")
        file = _File(path, label, lines, passed, top=included_from is None,
                     chain=chain + (path.absolute(),), format=format_of(path),
                     columns=columns)
        scope = _Scope(file, ns, dict(inherited), {}, parent=parent)
        if parent is not None:  # roslaunch: an included file shares its includer's ~params
            scope.private_params = parent.private_params
        for key, value in data.get("launch_attributes", {}).items():
            if key != "deprecated":
                self.fail(scope, ("launch",), f"unknown attribute {key!r} of <launch>; "
                                              f"allowed: deprecated")
            self.warn_once(scope, ("launch",), "launch.deprecated", detail=value)
        self.elements(data["launch"], ("launch",), scope)

    def _add_file(self, path: Path) -> None:
        path = path.absolute()
        if path not in self.files:
            self.files.append(path)

    # ---- element dispatch ---------------------------------------------------------------
    def elements(self, items: Any, path: tuple, scope: _Scope) -> None:
        """The elements of a file or group, each by its ``on_<element>`` method."""
        for element, body, epath in self.entries(items, path, scope,
                                                 scope.file.format.top_level, "launch"):
            getattr(self, f"on_{element}")(body, epath, scope)

    def entries(self, items: Any, path: tuple, scope: _Scope, allowed: tuple[str, ...],
                parent: str) -> Iterator[tuple[str, dict, tuple]]:
        """Checked ``(element, body, path)`` of a list of elements whose if/unless hold."""
        if items is None:
            return
        if not isinstance(items, list):
            self.fail(scope, path, f"{path[-1]!r} must be a list of elements "
                                   f"(like '- node: {{...}}'), got {_kind(items)}")
        for i, entry in enumerate(items):
            here = path + (i,)
            if not isinstance(entry, dict) or len(entry) != 1:
                got = (f"keys {', '.join(map(str, entry))}" if isinstance(entry, dict)
                       else _kind(entry))
                self.fail(scope, here, f"each entry must be a mapping with one key naming "
                                       f"the element (like '- node: {{...}}'), got {got}")
            ((element, body),) = entry.items()
            epath = here + (element,)
            self._check_element(scope, element, epath, allowed, parent)
            if body is None:
                body = {}
            elements = scope.file.format.elements
            if not isinstance(body, dict):
                self.fail(scope, epath, f"{element!r} needs a mapping of its keys "
                                        f"({', '.join(elements[element])}), got {_kind(body)}")
            self.check_keys(scope, element, body, epath)
            if self.condition(scope, body, epath):
                if element in scope.file.format.warned:
                    self.warn_once(scope, epath, element)
                yield element, body, epath

    def _check_element(self, scope: _Scope, element: Any, path: tuple,
                       allowed: tuple[str, ...], parent: str) -> None:
        fmt = scope.file.format
        if element in allowed:
            return
        listed = ", ".join(sorted(allowed))
        if element in fmt.refused:
            self.fail(scope, path, f"element {element!r}: {fmt.refused[element]}; "
                                   f"allowed elements: {listed}")
        where = "" if parent == "launch" else f" in {parent}"
        self.fail(scope, path, f"unknown element {element!r}{where}"
                               f"{_did_you_mean(element, allowed)}; allowed elements: {listed}")

    def check_keys(self, scope: _Scope, element: str, body: dict, path: tuple) -> None:
        fmt = scope.file.format
        allowed = fmt.elements[element] + _CONDITIONS
        for key in body:
            feature = f"{element}.{key}"
            if key in allowed:
                if feature in fmt.warned:
                    self.warn_once(scope, path + (key,), feature)
                continue
            if feature in fmt.refused:
                self.fail(scope, path + (key,), f"{element}: {fmt.refused[feature]}")
            self.fail(scope, path + (key,),
                      f"unknown {_key_word(fmt)} {key!r} in {element}"
                      f"{_did_you_mean(key, allowed)}; allowed {_key_word(fmt)}s: "
                      f"{', '.join(k for k in allowed if k not in ('children', 'text'))}")

    def condition(self, scope: _Scope, body: dict, path: tuple) -> bool:
        """roslaunch's if/unless: the value must be true/false/1/0 after substitution."""
        if "if" in body and "unless" in body:
            self.fail(scope, path, "cannot set both 'if' and 'unless' on the same element")
        for key, wanted in (("if", True), ("unless", False)):
            if key in body:
                raw = body[key]
                value = self.sub(scope, raw, path + (key,)) if isinstance(raw, str) else raw
                try:
                    return to_bool(value) == wanted
                except ValueError:
                    shown = f"{value!r}" + (f" (from {raw!r})" if value != raw else "")
                    self.fail(scope, path + (key,), f"{key!r} must evaluate to true, false, "
                                                    f"1 or 0, got {shown}")
        return True

    def warn_once(self, scope: _Scope, path: tuple, feature: str, detail: str = "") -> None:
        """One warning per feature per launch: it is accepted, and it has no effect here."""
        if feature in self.warned:
            return
        self.warned.add(feature)
        reason = scope.file.format.warned[feature]
        shown = feature.replace(".", " ")
        log.warning("%s: %s accepted and ignored: %s%s (warned once per launch)",
                    self.where(scope, path), shown, reason, f": {detail}" if detail else "")

    # ---- elements -------------------------------------------------------------------------
    def on_arg(self, body: dict, path: tuple, scope: _Scope) -> None:
        name = self.text(scope, body, "name", path, "arg", required=True)
        if not name or any(ch.isspace() for ch in name):
            self.fail(scope, path + ("name",), f"invalid arg name {name!r}")
        if "default" in body and "value" in body:
            self.fail(scope, path, f"arg {name!r} has both 'default' and 'value'; use "
                                   f"'default' (overridable) or 'value' (fixed)")
        if name in scope.declared:
            self.fail(scope, path, f"arg {name!r} is already declared at line "
                                   f"{scope.declared[name]}")
        line = self.line(scope.file, path)
        passed = scope.file.passed
        if "value" in body:
            if name in passed:
                how = f"{name}:={passed[name]}" if scope.file.top else "the include's args"
                self.fail(scope, path, f"arg {name!r} is declared with 'value' (fixed) and "
                                       f"cannot be overridden (by {how}); declare it with "
                                       f"'default' to make it overridable")
            value = self.text(scope, body, "value", path, "arg")
        elif name in passed:
            value = passed[name]
        elif name in scope.args:  # handed down by pass_all_args: it beats a default, as in roslaunch
            value = scope.args[name]
        elif "default" in body:
            value = self.text(scope, body, "default", path, "arg")
        else:
            how = (f"pass it as {name}:=<value>" if scope.file.top
                   else "pass it in the include's args")
            self.fail(scope, path, f"arg {name!r} is required by {scope.file.label} "
                                   f"(declared at line {line}): {how}")
        scope.declared[name] = line
        scope.args[name] = value
        if scope.file.top:
            self.top_args[name] = value

    def on_param(self, body: dict, path: tuple, scope: _Scope, node: str | None = None) -> None:
        """A ``param``: global or relative to the group; inside a node, relative to the node;
        a ``~name`` outside a node is kept for every node that follows in this scope."""
        name = self.text(scope, body, "name", path, "param", required=True).strip()
        private_here = node is None and names.is_private(name)
        if private_here:  # set later, on each node
            full = self.param_name(scope, name, path + ("name",), node="/_")[2:]
        else:
            full = self.param_name(scope, name, path + ("name",), node=node, base=node)
        sources = [key for key in ("value", "textfile", "command", "binfile") if key in body]
        if len(sources) != 1:
            self.fail(scope, path, f"param {name!r} needs exactly one of 'value', 'textfile' "
                                   f"or 'command'")
        ptype = self.param_type(scope, body, path)
        where = self.where(scope, path)
        if "binfile" in body:
            self.fail(scope, path + ("binfile",), scope.file.format.refused["param.binfile"])
        if "textfile" in body:
            text_path = self.existing(scope, body, "textfile", path, "param textfile")
            try:
                value: Any = read_text(text_path)
            except YamlError as exc:
                self.fail(scope, path + ("textfile",), str(exc))
            self._add_file(text_path)
        elif "command" in body:
            value = self.command_value(scope, body, path)
        else:
            value = self.param_value(scope, body["value"], ptype, path + ("value",), full)
        if private_here:
            scope.private_params[:] = [p for p in scope.private_params if p[0] != name[1:]]
            scope.private_params.append((name[1:], value, where))
            return
        if "value" in body:
            self.load_params(scope, value, "/", path + ("value",), param=full)
        else:
            self.params.set(full, value, source=where)

    def command_value(self, scope: _Scope, body: dict, path: tuple) -> str:
        """``param command=``: a xacro command runs in process; anything else is refused."""
        from twil_control.description.xacro_command import (XacroError, is_xacro_executable,
                                                            run_xacro)
        command = self.text(scope, body, "command", path, "param", required=True)
        try:
            words = shlex.split(command)
        except ValueError as exc:
            self.fail(scope, path + ("command",), f"param command {command!r}: {exc}")
        if words[:2] == ["rosrun", "xacro"]:
            words = words[2:]
        if not words or not is_xacro_executable(words[0]):
            self.fail(scope, path + ("command",),
                      f"param command {command!r}: 'command' runs only xacro (in-process: "
                      f"'$(find xacro)/xacro FILE name:=value ...', also xacro.py, rosrun xacro "
                      f"xacro, --inorder); any other command would run a program at launch "
                      f"time; use 'textfile' or a rosparam file instead")
        try:
            return run_xacro(words)
        except XacroError as exc:
            self.fail(scope, path + ("command",), str(exc))

    def param_type(self, scope: _Scope, body: dict, path: tuple) -> str | None:
        ptype = self.text(scope, body, "type", path, "param")
        if ptype is None:
            return None
        ptype = ptype.strip().lower()
        ptype = _PARAM_TYPE_ALIASES.get(ptype, ptype)
        if ptype is not None and ptype not in PARAM_TYPES:
            self.fail(scope, path + ("type",), f"param type {ptype!r} is not one of "
                                               f"{', '.join(PARAM_TYPES)}")
        return ptype

    def on_rosparam(self, body: dict, path: tuple, scope: _Scope,
                    node: str | None = None) -> None:
        command = self.text(scope, body, "command", path, "rosparam") or "load"
        if command == "dump":
            self.fail(scope, path + ("command",), scope.file.format.refused["rosparam.dump"])
        if command not in ("load", "delete"):
            self.fail(scope, path + ("command",), f"rosparam command must be 'load' or "
                                                  f"'delete', got {command!r}")
        target = node or scope.ns
        ns = self.text(scope, body, "ns", path, "rosparam")
        if ns:
            target = self.param_name(scope, ns, path + ("ns",), node, base=target)
        param = self.text(scope, body, "param", path, "rosparam")
        if param:
            param = self.param_name(scope, param, path + ("param",), node, base=target)
        subst_value = self.flag(scope, body, "subst_value", path)

        if command == "delete":
            if "file" in body or "value" in body or "text" in body:
                self.fail(scope, path, "rosparam delete takes 'ns' and 'param', not "
                                       "'file' or a value")
            doomed = param or target
            if self.params.has(doomed):  # like roslaunch, a missing one is not fatal
                self.params.delete(doomed)
            return
        if "file" in body and "value" in body:
            self.fail(scope, path, "rosparam load needs exactly one of 'file' or 'value'")
        if "file" in body:  # roslaunch ignores inline text when a file is given
            file = self.existing(scope, body, "file", path, "rosparam file")
            self._add_file(file)
            self.load_yaml_text(scope, read_text(file), file, display_path(file), target,
                                param, subst_value, path)
            return
        if "text" in body:  # XML's inline YAML, padded to the launch file's lines
            self.load_yaml_text(scope, body["text"], scope.file.path, scope.file.label,
                                target, param, subst_value, path)
            return
        if "value" not in body:
            return  # an empty rosparam loads nothing, as in roslaunch
        data = body["value"]
        if subst_value:
            data = self.sub_tree(scope, data, path + ("value",))
        self.load_params(scope, data, target, path + ("value",), param=param)

    def load_yaml_text(self, scope: _Scope, text: str, file: Path, label: str, target: str,
                       param: str | None, subst_value: bool, path: tuple) -> None:
        """rosparam load of YAML text (a file's, or inline), substituted if asked."""
        try:
            if subst_value:
                text = self.sub_lines(scope, text, file, path)
            data, lines = parse_yaml(text, label)
            self.params.load_data(data, target, file=label, lines=lines, param=param)
        except (YamlError, ParamError) as exc:
            raise LaunchError(f"{exc} (loaded by {self.where(scope, path)})") from None

    def on_group(self, body: dict, path: tuple, scope: _Scope) -> None:
        self.clear_params(scope, body, path, "group")
        child = scope.child(self.namespace(scope, body, path))
        self.elements(body.get("children"), path + ("children",), child)

    def clear_params(self, scope: _Scope, body: dict, path: tuple, element: str) -> None:
        """roslaunch's clear_params: needs 'ns' on a group or include (a node's name is its
        namespace). It clears the namespace before the launch sets any parameter, so with a
        parameter server that each launch starts empty it removes nothing."""
        if self.flag(scope, body, "clear_params", path) and element != "node" \
                and not body.get("ns"):
            self.fail(scope, path + ("clear_params",), f"{element} 'clear_params' needs 'ns' "
                                                       f"(roslaunch refuses to clear '/')")

    def on_remap(self, body: dict, path: tuple, scope: _Scope) -> None:
        _add_remap(scope.remaps, self.remap_pair(scope, body, path))

    def on_env(self, body: dict, path: tuple, scope: _Scope) -> None:
        self.text(scope, body, "name", path, "env", required=True)
        self.text(scope, body, "value", path, "env", required=True)

    def on_machine(self, body: dict, path: tuple, scope: _Scope) -> None:
        self.text(scope, body, "name", path, "machine", required=True)

    def on_test(self, body: dict, path: tuple, scope: _Scope) -> None:
        """rostest's <test>: roslaunch loads and does not run it; neither does this launcher."""
        self.text(scope, body, "test-name", path, "test", required=True)

    def on_node(self, body: dict, path: tuple, scope: _Scope) -> None:
        pkg, type_, name = (self.text(scope, body, key, path, "node", required=True,
                                      hint="a node needs pkg, type and name")
                            for key in ("pkg", "type", "name"))
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
            self.fail(scope, path, f"duplicate node name {fqn!r} (first declared at "
                                   f"{self.node_sources[fqn]}); roslaunch requires unique "
                                   f"node names: change 'name' or 'ns'")
        output = self.text(scope, body, "output", path, "node") or "log"
        if output not in OUTPUTS:
            self.fail(scope, path + ("output",), f"node output must be one of "
                                                 f"{', '.join(OUTPUTS)}, got {output!r}")
        self.clear_params(scope, body, path, "node")
        remaps = scope.remap_args()
        for pair in self.node_remaps(scope, body.get("remap"), path + ("remap",)):
            _add_remap(remaps, pair)
        # roslaunch's order: the node's rosparam loads, the scope's ~params, the node's params
        params_later: list[tuple[dict, tuple]] = []
        if "rosparam" in body:
            self.node_rosparams(scope, body["rosparam"], path + ("rosparam",), fqn)
        for element, child, here in self.entries(body.get("children"), path + ("children",),
                                                 scope, scope.file.format.node_children,
                                                 "node"):
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
        self.nodes.append(NodeSpec(
            pkg=pkg, type=type_, name=name, namespace=ns,
            args=args, arg_sources=_arg_sources(body.get("args"), args),
            remappings=remappings,
            required=self.flag(scope, body, "required", path) if "required" in body else None,
            source=where, output=output, respawn=self.flag(scope, body, "respawn", path),
            respawn_delay=self.number(scope, body, "respawn_delay", path, 0.0)))

    def record_node(self, scope: _Scope, body: dict, path: tuple, ns: str) -> None:
        """``rosbag record``: what the launch records (the bag itself is --bag's)."""
        args = self.node_args(scope, body.get("args"), path + ("args",))
        topics, ignored, refused = _rosbag_record_args(args)
        if refused:
            self.fail(scope, path + ("args",), f"rosbag record option {refused!r} is not "
                                               f"supported; supported: topic names, -a/--all "
                                               f"(and -O/-o/--lz4/--bz2/-j, which are ignored)")
        if ignored:
            log.warning("%s: rosbag record %s ignored: the bag is the one --bag names",
                        self.where(scope, path), " ".join(ignored))
        if topics is None:
            self.record_all = True
            return
        self.add_record(scope, [(topic, path + ("args",)) for topic in topics], ns)

    def on_include(self, body: dict, path: tuple, scope: _Scope) -> None:
        file = self.existing(scope, body, "file", path, "included launch file")
        ns = self.namespace(scope, body, path)
        pass_all = self.flag(scope, body, "pass_all_args", path)
        self.clear_params(scope, body, path, "include")
        raw_args = body.get("args") or {}
        if not isinstance(raw_args, dict):
            self.fail(scope, path + ("args",), "include 'args' must be a mapping of arg "
                                               f"names to values, got {_kind(raw_args)}")
        passed = {str(key): self.scalar(scope, value, path + ("args", key), f"arg {key!r}")
                  for key, value in raw_args.items()}
        for element, child, here in self.entries(body.get("children"), path + ("children",),
                                                 scope, scope.file.format.include_children,
                                                 "include"):
            if element == "arg":  # an include's <arg name value|default>: passed down
                arg = self.text(scope, child, "name", here, "arg", required=True)
                if arg in passed:
                    self.fail(scope, here, f"arg {arg!r} is passed twice to the include")
                key = "value" if "value" in child else "default"
                passed[arg] = self.text(scope, child, key, here, "arg", required=True,
                                        hint="an include's arg needs 'value'")
        if file.absolute() in scope.file.chain:
            loop = " -> ".join(display_path(p) for p in scope.file.chain + (file,))
            self.fail(scope, path + ("file",), f"include recursion: {loop}")
        self.load_file(file, ns=ns, passed=passed,
                       inherited={**scope.args, **passed} if pass_all else {},
                       parent=scope, chain=scope.file.chain,
                       included_from=self.where(scope, path), pass_all=pass_all)

    def on_record(self, body: dict, path: tuple, scope: _Scope) -> None:
        if "format" in body:
            self.record_format = self.choice(scope, body["format"], path + ("format",), "record format", RECORD_FORMATS)
        if "compression" in body:
            self.record_compression = self.choice(scope, body["compression"], path + ("compression",),
                                                  "record compression (of MCAP chunks)", MCAP_COMPRESSIONS)
        if "topics" not in body and ("format" in body or "compression" in body):
            return  # options only: every topic is recorded (or the topics other records name)
        topics = body.get("topics")
        if not isinstance(topics, list):
            self.fail(scope, path + ("topics",) if "topics" in body else path,
                      f"record needs 'topics', a list of topic names, got {_kind(topics)}")
        self.add_record(scope, [(self.scalar(scope, raw, path + ("topics", i), "topic"),
                                 path + ("topics", i)) for i, raw in enumerate(topics)],
                        scope.ns)

    def add_record(self, scope: _Scope, topics: list[tuple[str, tuple]], ns: str) -> None:
        record = self.record if self.record is not None else []
        for topic, here in topics:
            try:
                resolved = names.resolve(topic, ns)
            except names.GraphNameError as exc:
                self.fail(scope, here, str(exc))
            if resolved not in record:
                record.append(resolved)
        self.record = record

    # ---- node parts -------------------------------------------------------------------------
    def node_params(self, scope: _Scope, raw: Any, path: tuple, fqn: str) -> None:
        if not isinstance(raw, dict):
            self.fail(scope, path, f"node 'params' must be a mapping of private parameter "
                                   f"names to values, got {_kind(raw)}")
        self.load_params(scope, self.sub_tree(scope, raw, path), fqn, path)

    def node_rosparams(self, scope: _Scope, raw: Any, path: tuple, fqn: str) -> None:
        entries = [(raw, path)] if isinstance(raw, dict) else (
            [(entry, path + (i,)) for i, entry in enumerate(raw)]
            if isinstance(raw, list) else None)
        if entries is None:
            self.fail(scope, path, f"node 'rosparam' must be a list of rosparam mappings, "
                                   f"got {_kind(raw)}")
        for entry, here in entries:
            if not isinstance(entry, dict):
                self.fail(scope, here, f"a node's rosparam entry must be a mapping, got "
                                       f"{_kind(entry)}")
            self.check_keys(scope, "rosparam", entry, here)
            if self.condition(scope, entry, here):
                self.on_rosparam(entry, here, scope, node=fqn)

    def node_remaps(self, scope: _Scope, raw: Any, path: tuple) -> list[tuple[str, str]]:
        """A node's remaps: a list of {from, to} or a mapping {from: to}."""
        if raw is None:
            return []
        if isinstance(raw, dict):
            return [self.remap_pair(scope, {"from": key, "to": value}, path + (key,))
                    for key, value in raw.items()]
        if not isinstance(raw, list):
            self.fail(scope, path, f"node 'remap' must be a list of {{from, to}} or a "
                                   f"mapping of from: to, got {_kind(raw)}")
        pairs = []
        for i, entry in enumerate(raw):
            here = path + (i,)
            if not isinstance(entry, dict):
                self.fail(scope, here, f"a remap must be a mapping {{from: ..., to: ...}}, "
                                       f"got {_kind(entry)}")
            self.check_keys(scope, "remap", entry, here)
            if self.condition(scope, entry, here):
                pairs.append(self.remap_pair(scope, entry, here))
        return pairs

    def node_args(self, scope: _Scope, raw: Any, path: tuple) -> list[str]:
        if raw is None:
            return []
        if isinstance(raw, list):
            return [self.scalar(scope, item, path + (i,), "node arg")
                    for i, item in enumerate(raw)]
        text = self.scalar(scope, raw, path, "node args")
        try:
            return shlex.split(text)
        except ValueError as exc:
            self.fail(scope, path, f"cannot split node args {text!r}: {exc}")

    def remap_pair(self, scope: _Scope, body: dict, path: tuple) -> tuple[str, str]:
        pair = []
        for key in ("from", "to"):
            value = self.text(scope, body, key, path, "remap", required=True)
            try:
                pair.append(names.canonical(names.validate(value)))
            except names.GraphNameError as exc:
                self.fail(scope, path, f"remap {key!r}: {exc}")
        return pair[0], pair[1]

    # ---- values ------------------------------------------------------------------------------
    def param_value(self, scope: _Scope, raw: Any, ptype: str | None, path: tuple,
                    name: str) -> Any:
        """A ``param`` value typed as roslaunch types it (see the module docstring)."""
        if raw is None:
            self.fail(scope, path, f"param {name!r} has no value (null); write \"\" for an "
                                   f"empty string")
        if isinstance(raw, (dict, list)):
            if ptype not in (None, "yaml"):
                self.fail(scope, path, f"param {name!r} has type {ptype} but its value is "
                                       f"{_kind(raw)}")
            return self.sub_tree(scope, raw, path)
        value = self.sub(scope, raw, path) if isinstance(raw, str) else raw
        if scope.file.format.params_are_strings:  # roslaunch strips an XML value, then types it
            value = value.strip()
            if ptype is None:
                return auto_type(value)
        if ptype is None:
            return auto_type(value) if has_substitution(raw) else value
        try:
            return _convert_param(value, ptype, f"{self.where(scope, path)} (param {name!r})")
        except ValueError as exc:
            self.fail(scope, path, f"param {name!r} has type {ptype} but {exc}")

    def sub_tree(self, scope: _Scope, data: Any, path: tuple) -> Any:
        """Substitute in every string of ``data``; substituted strings get auto-typed."""
        if isinstance(data, dict):
            return {key: self.sub_tree(scope, value, path + (key,)) for key, value in data.items()}
        if isinstance(data, list):
            return [self.sub_tree(scope, value, path + (i,)) for i, value in enumerate(data)]
        if has_substitution(data):
            return auto_type(self.sub(scope, data, path))
        return data

    def sub_lines(self, scope: _Scope, text: str, file: Path, path: tuple) -> str:
        """rosparam subst_value: substitute a YAML file's text, line by line for messages."""
        out = []
        for number, line in enumerate(text.splitlines(keepends=True), start=1):
            try:
                out.append(substitute(line, self.context(scope)))
            except SubstitutionError as exc:
                raise LaunchError(f"{display_path(file)}:{number}: {exc} (subst_value; "
                                  f"loaded by {self.where(scope, path)})") from None
        return "".join(out)

    def load_params(self, scope: _Scope, data: Any, namespace: str, path: tuple,
                    param: str | None = None) -> None:
        try:
            self.params.load_data(data, namespace, file=scope.file.label,
                                  lines=scope.file.lines, key_path=path, param=param)
        except ParamError as exc:
            raise LaunchError(str(exc)) from None

    def param_name(self, scope: _Scope, name: str, path: tuple, node: str | None,
                   base: str | None = None) -> str:
        """Resolve a param name: relative to ``base`` (the group ns, or the node's name)."""
        try:
            names.validate(name)
        except names.GraphNameError as exc:
            self.fail(scope, path, str(exc))
        base = base or node or scope.ns
        if names.is_private(name):
            if node is None:
                self.fail(scope, path, f"private name {name!r} is only allowed inside a "
                                       f"node ('~' means the node's own namespace)")
            return names.join(node, name[1:])
        return names.join(base, name)

    def namespace(self, scope: _Scope, body: dict, path: tuple) -> str:
        """The absolute namespace an element's ``ns`` key selects, relative to the scope's."""
        ns = self.text(scope, body, "ns", path, _element_of(path))
        if not ns:
            return scope.ns
        try:
            names.validate(ns)
        except names.GraphNameError as exc:
            self.fail(scope, path + ("ns",), str(exc))
        if names.is_private(ns):
            self.fail(scope, path + ("ns",), f"ns {ns!r} cannot be private")
        return names.join(scope.ns, ns)

    def existing(self, scope: _Scope, body: dict, key: str, path: tuple, what: str) -> Path:
        """A file path from the launch file, found by core.paths' rule (the working directory,
        next to this launch file, the package root); the match is logged at debug level."""
        value = self.text(scope, body, key, path, _element_of(path), required=True)
        try:
            found = find_file(value, what, near=scope.file.path.parent)
        except InputPathError as exc:
            self.fail(scope, path + (key,), str(exc))
        log.debug("%s: %s %r found as %s", self.where(scope, path), what, value, found)
        return found

    def text(self, scope: _Scope, body: dict, key: str, path: tuple, element: str,
             required: bool = False, hint: str = "") -> str | None:
        """The substituted string value of ``body[key]``."""
        if key not in body:
            if required:
                self.fail(scope, path, f"{element} is missing required key {key!r}"
                                       + (f"; {hint}" if hint else ""))
            return None
        return self.scalar(scope, body[key], path + (key,), f"{element} {key!r}")

    def choice(self, scope: _Scope, value: Any, path: tuple, what: str, allowed: tuple) -> str:
        text = self.scalar(scope, value, path, what)
        if text not in allowed:
            self.fail(scope, path, f"{what} '{text}' is not one of {', '.join(allowed)}")
        return text

    def scalar(self, scope: _Scope, value: Any, path: tuple, what: str) -> str:
        if value is None:
            self.fail(scope, path, f"{what} has no value (null); write \"\" for an empty string")
        if isinstance(value, (dict, list)):
            self.fail(scope, path, f"{what} must be a single value, got {_kind(value)}")
        return self.sub(scope, value, path) if isinstance(value, str) else _scalar_str(value)

    def number(self, scope: _Scope, body: dict, key: str, path: tuple, default: float) -> float:
        if key not in body:
            return default
        raw = body[key]
        value = self.sub(scope, raw, path + (key,)) if isinstance(raw, str) else raw
        try:
            number = float(value)
        except (TypeError, ValueError):
            self.fail(scope, path + (key,), f"{key!r} must be a number, got {value!r}")
        if not number >= 0 or number == float("inf"):
            self.fail(scope, path + (key,), f"{key!r} must be a finite number >= 0, got "
                                            f"{value!r}")
        return number

    def flag(self, scope: _Scope, body: dict, key: str, path: tuple) -> bool:
        raw = body.get(key, False)
        value = self.sub(scope, raw, path + (key,)) if isinstance(raw, str) else raw
        try:
            return to_bool(value)
        except ValueError as exc:
            self.fail(scope, path + (key,), f"{key!r} must be true or false: {exc}")

    def sub(self, scope: _Scope, text: str, path: tuple) -> str:
        try:
            return substitute(text, self.context(scope))
        except SubstitutionError as exc:
            self.fail(scope, path, str(exc))

    def context(self, scope: _Scope) -> SubstitutionContext:
        return SubstitutionContext(scope.args, scope.file.path, scope.file.label, self.anon)

    # ---- locations --------------------------------------------------------------------------
    @staticmethod
    def located(file: _File, path: tuple) -> tuple:
        """``path``, or the nearest enclosing path whose line is known."""
        while path and path not in file.lines:
            path = path[:-1]
        return path

    def line(self, file: _File, path: tuple) -> int:
        return file.lines.get(self.located(file, path), 1)

    def where(self, scope: _Scope, path: tuple) -> str:
        """``file:line``, and ``:column`` where the parser gave one (XML)."""
        path = self.located(scope.file, path)
        column = scope.file.columns.get(path)
        return f"{scope.file.label}:{self.line(scope.file, path)}" + (f":{column}" if column else "")

    def fail(self, scope: _Scope, path: tuple, message: str):
        raise LaunchError(f"{self.where(scope, path)}: {message}")


# --------------------------------------------------------------------------------------
# Helpers
# --------------------------------------------------------------------------------------

def _launch_path(path: str | Path) -> Path:
    """A launch file on the command line, found by core.paths' rule."""
    try:
        return find_file(path, "launch file")
    except InputPathError as exc:
        raise LaunchError(str(exc)) from None


def _read_launch(path: Path, included_from: str | None) -> tuple[dict, Lines, dict]:
    """Read a launch file into the element tree: ``{"launch": [...]}``, its lines, and its
    columns (XML only)."""
    label = display_path(path)
    suffix = f" (included from {included_from})" if included_from else ""
    if format_of(path).params_are_strings:
        try:
            return read_xml_launch(path)
        except XmlLaunchError as exc:
            raise LaunchError(f"{exc}{suffix}") from None
    try:
        data, lines = load_yaml_with_lines(path)
    except YamlError as exc:
        raise LaunchError(f"{exc}{suffix}") from None
    if not isinstance(data, dict) or "launch" not in data:
        got = "an empty file" if data is None else (
            f"keys {', '.join(map(str, data))}" if isinstance(data, dict) else _kind(data))
        raise LaunchError(f"{label}:1: a launch file is a mapping with the key 'launch' "
                          f"holding a list of elements, got {got}{suffix}")
    for key in data:
        if key != "launch":
            raise LaunchError(f"{label}:{lines.get((key,), 1)}: unknown top-level key "
                              f"{key!r}; a launch file has the single key 'launch'")
    return data, lines, {}


def _declarations(items: Any, path: tuple, lines: Lines) -> dict[str, ArgDecl]:
    """Every ``arg`` in a file as written, groups included (conditions ignored)."""
    found: dict[str, ArgDecl] = {}
    for i, entry in enumerate(items if isinstance(items, list) else []):
        if not isinstance(entry, dict) or len(entry) != 1:
            continue
        ((element, body),) = entry.items()
        if not isinstance(body, dict):
            continue
        here = path + (i, element)
        if element == "arg" and isinstance(body.get("name"), str):
            found.setdefault(body["name"], ArgDecl(
                body["name"], lines.get(here, 1), body.get("default"), body.get("value"),
                str(body.get("doc") or "")))
        elif element == "group":
            for name, decl in _declarations(body.get("children"), here + ("children",),
                                            lines).items():
                found.setdefault(name, decl)
    return found


_WHOLE_ARG = re.compile(r"\$\(arg\s+([^\s()]+)\)")


def _arg_sources(raw: Any, args: list[str]) -> dict[int, str]:
    """Which node args are, whole, the value of a launch arg (``-x $(arg x)``), so that a node
    refusing a value can name the arg the user set; {} when the split does not line up."""
    if isinstance(raw, str):   # "$(arg x)" holds a space: mark it before splitting like a shell
        try:
            raw = shlex.split(_WHOLE_ARG.sub(lambda m: f"$(arg\0{m.group(1)})", raw))
        except ValueError:
            return {}
        raw = [token.replace("\0", " ") for token in raw]
    if not isinstance(raw, list) or len(raw) != len(args):
        return {}
    return {i: m.group(1) for i, token in enumerate(raw)
            if isinstance(token, str) and (m := _WHOLE_ARG.fullmatch(token))}


def _add_remap(remaps: list[tuple[str, str]], pair: tuple[str, str]) -> None:
    """roslaunch's add_remap: a later remap of the same 'from' replaces the earlier."""
    remaps[:] = [r for r in remaps if r[0] != pair[0]] + [pair]


def _convert_param(value: Any, ptype: str, label: str) -> Any:
    """roslaunch's convert_value for an explicit ``type``; ValueError says why not."""
    if ptype == "str":
        return _scalar_str(value)
    if ptype == "yaml":
        if not isinstance(value, str):
            return value
        try:
            return parse_yaml(value, label)[0]
        except YamlError as exc:
            raise ValueError(f"its value is not valid YAML: {exc}") from None
    if ptype == "bool":
        try:
            return to_bool(value)
        except ValueError:
            raise ValueError(f"its value {value!r} is not true, false, 1 or 0") from None
    if isinstance(value, bool):
        raise ValueError(f"its value {value!r} is a boolean")
    try:
        if ptype == "int":
            if isinstance(value, float):
                raise ValueError
            return int(value)
        return float(value)
    except ValueError:
        kind = "an integer" if ptype == "int" else "a number"
        raise ValueError(f"its value {value!r} is not {kind}") from None


def _scalar_str(value: Any) -> str:
    """A YAML scalar as the string roslaunch would see in XML ("true", not "True")."""
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)


def _kind(value: Any) -> str:
    return {dict: "a mapping", list: "a list", str: "a string", bool: "a boolean",
            int: "an integer", float: "a number", type(None): "nothing"}.get(
                type(value), type(value).__name__)


def _element_of(path: tuple) -> str:
    """The element a key path points into, for messages ("node", "include", ...)."""
    return next((part for part in reversed(path) if part in XML.elements or
                 part in YAML.elements), "element")


def _key_word(fmt: LaunchFormat) -> str:
    return "attribute" if fmt.params_are_strings else "key"


#: rosbag record options: ignored (the bag is the launcher's) and taking a value.
_RECORD_IGNORED = {"-O": True, "-o": True, "--output-name": True, "--output-prefix": True,
                   "--lz4": False, "--bz2": False, "-j": False}


def _rosbag_record_args(args: list[str]) -> tuple[list[str] | None, list[str], str | None]:
    """(topics, or None for -a; options ignored; the first unsupported option) of rosbag
    record's command line."""
    topics: list[str] = []
    ignored: list[str] = []
    record_all = False
    tokens = iter(args)
    for token in tokens:
        option, _, inline = token.partition("=")
        if token in ("-a", "--all"):
            record_all = True
        elif option in _RECORD_IGNORED:
            value = inline or (next(tokens, "") if _RECORD_IGNORED[option] and not inline
                               else "")
            ignored.append(f"{option} {value}".strip())
        elif token.startswith("-"):
            return topics, ignored, token
        else:
            topics.append(token)
    return (None if record_all else topics), ignored, None


def _did_you_mean(word: Any, choices: Iterable[str]) -> str:
    close = difflib.get_close_matches(str(word), list(choices), n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""
