"""roslaunch's scoping: files, includes and groups, the args each one sees, and every element
checked (known, with allowed keys, its if/unless) and handed to its ``on_<element>`` method.

Args are scoped per file (an included file sees only the args passed to it, or all of them
with ``pass_all_args``) and per group; an arg declared with ``value`` is fixed; an arg declared
with neither value nor default must be given; args passed to a file that it does not declare
(on the command line or by an include) are errors. XML's env, machine and test are checked and
ignored (formats.py says why).
"""

from __future__ import annotations

import difflib
import logging
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

from twil_control.core.yaml_io import display_path
from twil_control.launch.formats import LaunchFormat, format_of
from twil_control.launch.launch_file import declarations, read_launch
from twil_control.launch.plan import LaunchError
from twil_control.launch.scope import OpenFile, Scope, ScopeValues, kind
from twil_control.launch.substitutions import to_bool

log = logging.getLogger("twil_control.launch")

_CONDITIONS = ("if", "unless")

#: files a chain of includes may nest (a launch tree is a few deep; a chain deeper than this is
#: a generated or runaway file, refused with its chain before Python's recursion limit)
MAX_INCLUDE_DEPTH = 100


class ScopedLoader(ScopeValues):
    """Loads files and groups; the ``on_<element>`` methods of the other elements are the
    mixins' (param_elements.py, recording.py, node_element.py)."""

    def __init__(self) -> None:
        super().__init__()
        self.files: list[Path] = []
        self.top_args: dict[str, str] = {}
        self.warned: set[str] = set()

    # ---- files -----------------------------------------------------------------------
    def load_file(
        self,
        path: Path,
        *,
        ns: str,
        passed: dict[str, str],
        inherited: dict[str, str],
        parent: Scope | None,
        chain: tuple[Path, ...],
        included_from: str | None,
        pass_all: bool = False,
    ) -> None:
        """Load one launch file into the plan, in a fresh arg scope.

        ``passed`` are explicit args (command line, or an include's ``args``);
        ``inherited`` are args handed down by ``pass_all_args``.
        """
        data, lines, columns = read_launch(path, included_from)
        self.add_file(path)
        label = display_path(path)
        declared = declarations(data["launch"], ("launch",), lines)
        unknown = [name for name in passed if name not in declared]
        if pass_all:  # roslaunch skips the unused-args check; the extras stay usable
            passed = {name: value for name, value in passed.items() if name in declared}
        elif unknown:
            listed = ", ".join(declared) or "none"
            quoted = ", ".join(repr(name) for name in unknown)
            plural = "s" if len(unknown) > 1 else ""
            if included_from is None:
                raise LaunchError(f"unknown arg{plural} {quoted} for {label}; declared args: {listed}")
            raise LaunchError(
                f"{included_from}: include of {label} passes undeclared "
                f"arg{plural} {quoted}; declared args: {listed}"
            )
        file = OpenFile(
            path,
            label,
            lines,
            passed,
            top=included_from is None,
            chain=chain + (path.absolute(),),
            format=format_of(path),
            columns=columns,
        )
        scope = Scope(file, ns, dict(inherited), {}, parent=parent)
        if parent is not None:  # roslaunch: an included file shares its includer's ~params
            scope.private_params = parent.private_params
        for key, value in data.get("launch_attributes", {}).items():
            if key != "deprecated":
                self.fail(scope, ("launch",), f"unknown attribute {key!r} of <launch>; allowed: deprecated")
            self.warn_once(scope, ("launch",), "launch.deprecated", detail=value)
        self.elements(data["launch"], ("launch",), scope)

    def add_file(self, path: Path) -> None:
        path = path.absolute()
        if path not in self.files:
            self.files.append(path)

    # ---- element dispatch ------------------------------------------------------------
    def elements(self, items: Any, path: tuple, scope: Scope) -> None:
        """The elements of a file or group, each by its ``on_<element>`` method."""
        for element, body, epath in self.entries(items, path, scope, scope.file.format.top_level, "launch"):
            getattr(self, f"on_{element}")(body, epath, scope)

    def entries(
        self, items: Any, path: tuple, scope: Scope, allowed: tuple[str, ...], parent: str
    ) -> Iterator[tuple[str, dict, tuple]]:
        """Checked ``(element, body, path)`` of a list of elements whose if/unless hold."""
        if items is None:
            return
        if not isinstance(items, list):
            self.fail(
                scope,
                path,
                f"{path[-1]!r} must be a list of elements (like '- node: {{...}}'), got {kind(items)}",
            )
        for i, entry in enumerate(items):
            here = path + (i,)
            if not isinstance(entry, dict) or len(entry) != 1:
                got = f"keys {', '.join(map(str, entry))}" if isinstance(entry, dict) else kind(entry)
                self.fail(
                    scope,
                    here,
                    f"each entry must be a mapping with one key naming "
                    f"the element (like '- node: {{...}}'), got {got}",
                )
            ((element, body),) = entry.items()
            epath = here + (element,)
            self._check_element(scope, element, epath, allowed, parent)
            if body is None:
                body = {}
            elements = scope.file.format.elements
            if not isinstance(body, dict):
                self.fail(
                    scope,
                    epath,
                    f"{element!r} needs a mapping of its keys "
                    f"({', '.join(elements[element])}), got {kind(body)}",
                )
            self.check_keys(scope, element, body, epath)
            if self.condition(scope, body, epath):
                if element in scope.file.format.warned:
                    self.warn_once(scope, epath, element)
                yield element, body, epath

    def _check_element(
        self, scope: Scope, element: Any, path: tuple, allowed: tuple[str, ...], parent: str
    ) -> None:
        fmt = scope.file.format
        if element in allowed:
            return
        listed = ", ".join(sorted(allowed))
        if element in fmt.refused:
            self.fail(scope, path, f"element {element!r}: {fmt.refused[element]}; allowed elements: {listed}")
        where = "" if parent == "launch" else f" in {parent}"
        self.fail(
            scope,
            path,
            f"unknown element {element!r}{where}"
            f"{_did_you_mean(element, allowed)}; allowed elements: {listed}",
        )

    def check_keys(self, scope: Scope, element: str, body: dict, path: tuple) -> None:
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
            self.fail(
                scope,
                path + (key,),
                f"unknown {_key_word(fmt)} {key!r} in {element}"
                f"{_did_you_mean(key, allowed)}; allowed {_key_word(fmt)}s: "
                f"{', '.join(k for k in allowed if k not in ('children', 'text'))}",
            )

    def condition(self, scope: Scope, body: dict, path: tuple) -> bool:
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
                    self.fail(
                        scope, path + (key,), f"{key!r} must evaluate to true, false, 1 or 0, got {shown}"
                    )
        return True

    def warn_once(self, scope: Scope, path: tuple, feature: str, detail: str = "") -> None:
        """One warning per feature per launch: it is accepted, and it has no effect here."""
        if feature in self.warned:
            return
        self.warned.add(feature)
        reason = scope.file.format.warned[feature]
        shown = feature.replace(".", " ")
        log.warning(
            "%s: %s accepted and ignored: %s%s (warned once per launch)",
            self.where(scope, path),
            shown,
            reason,
            f": {detail}" if detail else "",
        )

    # ---- elements --------------------------------------------------------------------
    def on_arg(self, body: dict, path: tuple, scope: Scope) -> None:
        name = self.text(scope, body, "name", path, "arg", required=True)
        if not name or any(ch.isspace() for ch in name):
            self.fail(scope, path + ("name",), f"invalid arg name {name!r}")
        if "default" in body and "value" in body:
            self.fail(
                scope,
                path,
                f"arg {name!r} has both 'default' and 'value'; use "
                f"'default' (overridable) or 'value' (fixed)",
            )
        if name in scope.declared:
            self.fail(scope, path, f"arg {name!r} is already declared at line {scope.declared[name]}")
        line = self.line(scope.file, path)
        passed = scope.file.passed
        if "value" in body:
            if name in passed:
                how = f"{name}:={passed[name]}" if scope.file.top else "the include's args"
                self.fail(
                    scope,
                    path,
                    f"arg {name!r} is declared with 'value' (fixed) and "
                    f"cannot be overridden (by {how}); declare it with "
                    f"'default' to make it overridable",
                )
            value = self.text(scope, body, "value", path, "arg", required=True)
        elif name in passed:
            value = passed[name]
        elif name in scope.args:  # handed down by pass_all_args: it beats a default, as in roslaunch
            value = scope.args[name]
        elif "default" in body:
            value = self.text(scope, body, "default", path, "arg", required=True)
        else:
            how = f"pass it as {name}:=<value>" if scope.file.top else "pass it in the include's args"
            self.fail(
                scope,
                path,
                f"arg {name!r} is required by {scope.file.label} (declared at line {line}): {how}",
            )
        scope.declared[name] = line
        scope.args[name] = value
        if scope.file.top:
            self.top_args[name] = value

    def on_group(self, body: dict, path: tuple, scope: Scope) -> None:
        self.clear_params(scope, body, path, "group")
        child = scope.child(self.namespace(scope, body, path))
        self.elements(body.get("children"), path + ("children",), child)

    def clear_params(self, scope: Scope, body: dict, path: tuple, element: str) -> None:
        """roslaunch's clear_params: needs 'ns' on a group or include (a node's name is its
        namespace). It clears the namespace before the launch sets any parameter, so with a
        parameter server that each launch starts empty it removes nothing."""
        if self.flag(scope, body, "clear_params", path) and element != "node" and not body.get("ns"):
            self.fail(
                scope,
                path + ("clear_params",),
                f"{element} 'clear_params' needs 'ns' (roslaunch refuses to clear '/')",
            )

    def on_include(self, body: dict, path: tuple, scope: Scope) -> None:
        file = self.existing(scope, body, "file", path, "included launch file")
        ns = self.namespace(scope, body, path)
        pass_all = self.flag(scope, body, "pass_all_args", path)
        self.clear_params(scope, body, path, "include")
        raw_args = body.get("args") or {}
        if not isinstance(raw_args, dict):
            self.fail(
                scope,
                path + ("args",),
                f"include 'args' must be a mapping of arg names to values, got {kind(raw_args)}",
            )
        passed = {
            str(key): self.scalar(scope, value, path + ("args", key), f"arg {key!r}")
            for key, value in raw_args.items()
        }
        for element, child, here in self.entries(
            body.get("children"), path + ("children",), scope, scope.file.format.include_children, "include"
        ):
            if element == "arg":  # an include's <arg name value|default>: passed down
                arg = self.text(scope, child, "name", here, "arg", required=True)
                if arg in passed:
                    self.fail(scope, here, f"arg {arg!r} is passed twice to the include")
                key = "value" if "value" in child else "default"
                passed[arg] = self.text(
                    scope, child, key, here, "arg", required=True, hint="an include's arg needs 'value'"
                )
        if file.absolute() in scope.file.chain:
            loop = " -> ".join(display_path(p) for p in scope.file.chain + (file,))
            self.fail(scope, path + ("file",), f"include recursion: {loop}")
        if len(scope.file.chain) >= MAX_INCLUDE_DEPTH:
            files = [display_path(p) for p in scope.file.chain + (file,)]
            shown = files[:2] + [f"... {len(files) - 4} more ..."] + files[-2:]
            self.fail(
                scope,
                path + ("file",),
                f"includes nest more than {MAX_INCLUDE_DEPTH} files deep: {' -> '.join(shown)}",
            )
        self.load_file(
            file,
            ns=ns,
            passed=passed,
            inherited={**scope.args, **passed} if pass_all else {},
            parent=scope,
            chain=scope.file.chain,
            included_from=self.where(scope, path),
            pass_all=pass_all,
        )

    def on_env(self, body: dict, path: tuple, scope: Scope) -> None:
        self.text(scope, body, "name", path, "env", required=True)
        self.text(scope, body, "value", path, "env", required=True)

    def on_machine(self, body: dict, path: tuple, scope: Scope) -> None:
        self.text(scope, body, "name", path, "machine", required=True)

    def on_test(self, body: dict, path: tuple, scope: Scope) -> None:
        """rostest's <test>: roslaunch loads and does not run it; neither does this launcher."""
        self.text(scope, body, "test-name", path, "test", required=True)


def _key_word(fmt: LaunchFormat) -> str:
    return "attribute" if fmt.params_are_strings else "key"


def _did_you_mean(word: Any, choices: Iterable[str]) -> str:
    close = difflib.get_close_matches(str(word), list(choices), n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""
