"""Where an element is, and its values read in its scope (roslaunch's LoaderContext).

A launch file is loaded in scopes: one per file, group and include, each with its namespace,
the args it sees, and the remaps and ``~params`` in force there. The element handlers
(scoping.py, param_elements.py, node_element.py, recording.py) read every value through
ScopeValues: substituted, checked, and any error prefixed with the file and line (and the
column in XML).
"""

from __future__ import annotations

import logging
import shlex
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal, overload

from twil_control.core import names
from twil_control.core.paths import InputPathError, find_file
from twil_control.core.yaml_io import Lines
from twil_control.launch.formats import XML, YAML, LaunchFormat
from twil_control.launch.plan import LaunchError
from twil_control.launch.substitutions import (
    SubstitutionContext,
    SubstitutionError,
    auto_type,
    has_substitution,
    substitute,
    to_bool,
)

log = logging.getLogger("twil_control.launch")


@dataclass
class OpenFile:
    """One launch file being read."""

    path: Path
    label: str  # the name used in messages
    lines: Lines
    passed: dict[str, str]  # args given explicitly (command line or include args)
    top: bool  # the file named on the command line
    chain: tuple[Path, ...]  # the include stack down to this file, for recursion
    format: LaunchFormat
    columns: dict[tuple, int] = field(default_factory=dict)  # XML: element columns


@dataclass
class Scope:
    """roslaunch's LoaderContext: namespace, visible args, remaps and ~params at one point."""

    file: OpenFile
    ns: str
    args: dict[str, str]
    declared: dict[str, int]  # arg name -> line of its declaration in this scope
    parent: Scope | None = None
    remaps: list[tuple[str, str]] = field(default_factory=list)
    # ~name params outside a node: (name without '~', value, source), set on every later node
    private_params: list[tuple[str, Any, str]] = field(default_factory=list)

    def child(self, ns: str) -> Scope:
        """A group's scope: args and ~params declared inside it do not leak out."""
        return Scope(
            self.file,
            ns,
            dict(self.args),
            dict(self.declared),
            parent=self,
            private_params=list(self.private_params),
        )

    def remap_args(self) -> list[tuple[str, str]]:
        """Remaps in force here; an inner remap of the same 'from' replaces an outer one."""
        if self.parent is None:
            return list(self.remaps)
        own = {source for source, _ in self.remaps}
        return [r for r in self.parent.remap_args() if r[0] not in own] + self.remaps


class ScopeValues:
    """Reads an element's values in its scope; every error names the file and line."""

    def __init__(self) -> None:
        self.anon: dict[str, str] = {}  # $(anon name) -> its unique name, one per launch

    # ---- values ----------------------------------------------------------------------
    def namespace(self, scope: Scope, body: dict, path: tuple) -> str:
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

    def existing(self, scope: Scope, body: dict, key: str, path: tuple, what: str) -> Path:
        """A file path from the launch file, found by core.paths' rule (the working directory,
        next to this launch file, the package root); the match is logged at debug level."""
        value = self.text(scope, body, key, path, _element_of(path), required=True)
        try:
            found = find_file(value, what, near=scope.file.path.parent)
        except InputPathError as exc:
            self.fail(scope, path + (key,), str(exc))
        log.debug("%s: %s %r found as %s", self.where(scope, path), what, value, found)
        return found

    @overload
    def text(
        self,
        scope: Scope,
        body: dict,
        key: str,
        path: tuple,
        element: str,
        required: Literal[True],
        hint: str = "",
    ) -> str: ...

    @overload
    def text(
        self,
        scope: Scope,
        body: dict,
        key: str,
        path: tuple,
        element: str,
        required: bool = False,
        hint: str = "",
    ) -> str | None: ...

    def text(
        self,
        scope: Scope,
        body: dict,
        key: str,
        path: tuple,
        element: str,
        required: bool = False,
        hint: str = "",
    ) -> str | None:
        """The substituted string value of ``body[key]``."""
        if key not in body:
            if required:
                self.fail(
                    scope, path, f"{element} is missing required key {key!r}" + (f"; {hint}" if hint else "")
                )
            return None
        return self.scalar(scope, body[key], path + (key,), f"{element} {key!r}")

    def scalar(self, scope: Scope, value: Any, path: tuple, what: str) -> str:
        if value is None:
            self.fail(scope, path, f'{what} has no value (null); write "" for an empty string')
        if isinstance(value, (dict, list)):
            self.fail(scope, path, f"{what} must be a single value, got {kind(value)}")
        return self.sub(scope, value, path) if isinstance(value, str) else scalar_str(value)

    def flag(self, scope: Scope, body: dict, key: str, path: tuple) -> bool:
        raw = body.get(key, False)
        value = self.sub(scope, raw, path + (key,)) if isinstance(raw, str) else raw
        try:
            return to_bool(value)
        except ValueError as exc:
            self.fail(scope, path + (key,), f"{key!r} must be true or false: {exc}")

    def node_args(self, scope: Scope, raw: Any, path: tuple) -> list[str]:
        if raw is None:
            return []
        if isinstance(raw, list):
            return [self.scalar(scope, item, path + (i,), "node arg") for i, item in enumerate(raw)]
        text = self.scalar(scope, raw, path, "node args")
        try:
            return shlex.split(text)
        except ValueError as exc:
            self.fail(scope, path, f"cannot split node args {text!r}: {exc}")

    def sub_tree(self, scope: Scope, data: Any, path: tuple) -> Any:
        """Substitute in every string of ``data``; substituted strings get auto-typed."""
        if isinstance(data, dict):
            return {key: self.sub_tree(scope, value, path + (key,)) for key, value in data.items()}
        if isinstance(data, list):
            return [self.sub_tree(scope, value, path + (i,)) for i, value in enumerate(data)]
        if has_substitution(data):
            return auto_type(self.sub(scope, data, path))
        return data

    def sub(self, scope: Scope, text: str, path: tuple) -> str:
        try:
            return substitute(text, self.context(scope))
        except SubstitutionError as exc:
            self.fail(scope, path, str(exc))

    def context(self, scope: Scope) -> SubstitutionContext:
        return SubstitutionContext(scope.args, scope.file.path, scope.file.label, self.anon)

    # ---- locations -------------------------------------------------------------------
    @staticmethod
    def located(file: OpenFile, path: tuple) -> tuple:
        """``path``, or the nearest enclosing path whose line is known."""
        while path and path not in file.lines:
            path = path[:-1]
        return path

    def line(self, file: OpenFile, path: tuple) -> int:
        return file.lines.get(self.located(file, path), 1)

    def where(self, scope: Scope, path: tuple) -> str:
        """``file:line``, and ``:column`` where the parser gave one (XML)."""
        path = self.located(scope.file, path)
        column = scope.file.columns.get(path)
        return f"{scope.file.label}:{self.line(scope.file, path)}" + (f":{column}" if column else "")

    def fail(self, scope: Scope, path: tuple, message: str):
        raise LaunchError(f"{self.where(scope, path)}: {message}")


def scalar_str(value: Any) -> str:
    """A YAML scalar as the string roslaunch would see in XML ("true", not "True")."""
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)


def kind(value: Any) -> str:
    """What a value is, as messages name it ("a mapping", "a list", ...)."""
    return {
        dict: "a mapping",
        list: "a list",
        str: "a string",
        bool: "a boolean",
        int: "an integer",
        float: "a number",
        type(None): "nothing",
    }.get(type(value), type(value).__name__)


def _element_of(path: tuple) -> str:
    """The element a key path points into, for messages ("node", "include", ...)."""
    return next((part for part in reversed(path) if part in XML.elements or part in YAML.elements), "element")
