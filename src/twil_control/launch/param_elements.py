"""``param`` and ``rosparam`` elements: where each value goes, and its type.

A param is global, relative to its group's namespace, or inside a node relative to the node;
a ``~name`` param outside a node is kept for every node that follows in the same group (and
file). A YAML value keeps its YAML type; a substituted string, and every XML value (a string,
stripped), is typed as roslaunch types it (int, float, bool, else string); an explicit
``type`` converts as roslaunch's convert_value does.
"""

from __future__ import annotations

import shlex
from pathlib import Path
from typing import Any

from twil_control.core import names
from twil_control.core.params import ParamError, ParamServer
from twil_control.core.yaml_io import YamlError, display_path, parse_yaml, read_text
from twil_control.errors import InputError
from twil_control.launch.plan import LaunchError
from twil_control.launch.scope import Scope, kind, scalar_str
from twil_control.launch.scoping import ScopedLoader
from twil_control.launch.substitutions import (
    SubstitutionError,
    auto_type,
    has_substitution,
    substitute,
    to_bool,
)

PARAM_TYPES = ("str", "int", "double", "bool", "yaml")
#: roslaunch's other spellings of the param types ("auto" is no type: inferred).
_PARAM_TYPE_ALIASES = {"string": "str", "boolean": "bool", "auto": None}


class ParamElements(ScopedLoader):
    """The ``param`` and ``rosparam`` elements, into the launch's parameter server."""

    def __init__(self) -> None:
        super().__init__()
        self.params = ParamServer()

    def on_param(self, body: dict, path: tuple, scope: Scope, node: str | None = None) -> None:
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
            self.fail(scope, path, f"param {name!r} needs exactly one of 'value', 'textfile' or 'command'")
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
            self.add_file(text_path)
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

    def command_value(self, scope: Scope, body: dict, path: tuple) -> str:
        """``param command=``: a xacro command runs in process, also behind an env_run wrapper
        (description/env_run.py); anything else is refused."""
        from twil_control.description.env_run import split_env_run
        from twil_control.description.xacro_command import XacroError, is_xacro_executable, run_xacro

        command = self.text(scope, body, "command", path, "param", required=True)
        try:
            words = shlex.split(command)
        except ValueError as exc:
            self.fail(scope, path + ("command",), f"param command {command!r}: {exc}")
        env = None
        try:
            wrapped = split_env_run(words)
            if wrapped is not None:
                env, words = wrapped
            if words[:2] == ["rosrun", "xacro"]:
                words = words[2:]
            if not words or not is_xacro_executable(words[0]):
                self.fail(
                    scope,
                    path + ("command",),
                    f"param command {command!r}: 'command' runs only xacro (in-process: "
                    f"'$(find xacro)/xacro FILE name:=value ...', also xacro.py, rosrun xacro "
                    f"xacro, --inorder, and behind an env_run wrapper that sources a KEY=VALUE "
                    f"file); any other command would run a program at launch time; use "
                    f"'textfile' or a rosparam file instead",
                )
            return run_xacro(words, env)
        except XacroError as exc:
            self.fail(scope, path + ("command",), str(exc))

    def param_type(self, scope: Scope, body: dict, path: tuple) -> str | None:
        ptype = self.text(scope, body, "type", path, "param")
        if ptype is None:
            return None
        ptype = ptype.strip().lower()
        ptype = _PARAM_TYPE_ALIASES.get(ptype, ptype)
        if ptype is not None and ptype not in PARAM_TYPES:
            self.fail(scope, path + ("type",), f"param type {ptype!r} is not one of {', '.join(PARAM_TYPES)}")
        return ptype

    def param_value(self, scope: Scope, raw: Any, ptype: str | None, path: tuple, name: str) -> Any:
        """A ``param`` value typed as roslaunch types it (see the module docstring)."""
        if raw is None:
            self.fail(scope, path, f'param {name!r} has no value (null); write "" for an empty string')
        if isinstance(raw, (dict, list)):
            if ptype not in (None, "yaml"):
                self.fail(scope, path, f"param {name!r} has type {ptype} but its value is {kind(raw)}")
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

    def on_rosparam(self, body: dict, path: tuple, scope: Scope, node: str | None = None) -> None:
        command = self.text(scope, body, "command", path, "rosparam") or "load"
        if command == "dump":
            self.fail(scope, path + ("command",), scope.file.format.refused["rosparam.dump"])
        if command not in ("load", "delete"):
            self.fail(
                scope, path + ("command",), f"rosparam command must be 'load' or 'delete', got {command!r}"
            )
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
                self.fail(scope, path, "rosparam delete takes 'ns' and 'param', not 'file' or a value")
            doomed = param or target
            if self.params.has(doomed):  # like roslaunch, a missing one is not fatal
                self.params.delete(doomed)
            return
        if "file" in body and "value" in body:
            self.fail(scope, path, "rosparam load needs exactly one of 'file' or 'value'")
        if "file" in body:  # roslaunch ignores inline text when a file is given
            file = self.existing(scope, body, "file", path, "rosparam file")
            self.add_file(file)
            self.load_yaml_text(
                scope, read_text(file), file, display_path(file), target, param, subst_value, path
            )
            return
        if "text" in body:  # XML's inline YAML, padded to the launch file's lines
            self.load_yaml_text(
                scope, body["text"], scope.file.path, scope.file.label, target, param, subst_value, path
            )
            return
        if "value" not in body:
            return  # an empty rosparam loads nothing, as in roslaunch
        data = body["value"]
        if subst_value:
            data = self.sub_tree(scope, data, path + ("value",))
        self.load_params(scope, data, target, path + ("value",), param=param)

    def load_yaml_text(
        self,
        scope: Scope,
        text: str,
        file: Path,
        label: str,
        target: str,
        param: str | None,
        subst_value: bool,
        path: tuple,
    ) -> None:
        """rosparam load of YAML text (a file's, or inline), substituted if asked."""
        try:
            if subst_value:
                text = self.sub_lines(scope, text, file, path)
            data, lines = parse_yaml(text, label)
            self.params.load_data(data, target, file=label, lines=lines, param=param)
        except (YamlError, ParamError) as exc:
            raise LaunchError(f"{exc} (loaded by {self.where(scope, path)})") from None

    def sub_lines(self, scope: Scope, text: str, file: Path, path: tuple) -> str:
        """rosparam subst_value: substitute a YAML file's text, line by line for messages."""
        out = []
        for number, line in enumerate(text.splitlines(keepends=True), start=1):
            try:
                out.append(substitute(line, self.context(scope)))
            except SubstitutionError as exc:
                raise LaunchError(
                    f"{display_path(file)}:{number}: {exc} (subst_value; loaded by {self.where(scope, path)})"
                ) from None
        return "".join(out)

    def load_params(
        self, scope: Scope, data: Any, namespace: str, path: tuple, param: str | None = None
    ) -> None:
        try:
            self.params.load_data(
                data, namespace, file=scope.file.label, lines=scope.file.lines, key_path=path, param=param
            )
        except ParamError as exc:
            raise LaunchError(str(exc)) from None

    def param_name(
        self, scope: Scope, name: str, path: tuple, node: str | None, base: str | None = None
    ) -> str:
        """Resolve a param name: relative to ``base`` (the group ns, or the node's name)."""
        try:
            names.validate(name)
        except names.GraphNameError as exc:
            self.fail(scope, path, str(exc))
        base = base or node or scope.ns
        if names.is_private(name):
            if node is None:
                self.fail(
                    scope,
                    path,
                    f"private name {name!r} is only allowed inside a "
                    f"node ('~' means the node's own namespace)",
                )
            return names.join(node, name[1:])
        return names.join(base, name)


def _convert_param(value: Any, ptype: str, label: str) -> Any:
    """roslaunch's convert_value for an explicit ``type``; ValueError says why not."""
    if ptype == "str":
        return scalar_str(value)
    if ptype == "yaml":
        if not isinstance(value, str):
            return value
        try:
            return parse_yaml(value, label)[0]
        except YamlError as exc:
            raise InputError(f"its value is not valid YAML: {exc}") from None
    if ptype == "bool":
        try:
            return to_bool(value)
        except ValueError:
            raise InputError(f"its value {value!r} is not true, false, 1 or 0") from None
    if isinstance(value, bool):
        raise InputError(f"its value {value!r} is a boolean")
    try:
        if ptype == "int":
            if isinstance(value, float):
                raise ValueError
            return int(value)
        return float(value)
    except ValueError:
        expected = "an integer" if ptype == "int" else "a number"
        raise InputError(f"its value {value!r} is not {expected}") from None
