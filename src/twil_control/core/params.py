"""The parameter server (rosmaster's role).

ParamServer keeps ROS's parameter tree: global names, namespaces as nested
mappings, and rosparam's merge semantics (setting a mapping updates a namespace
key by key instead of replacing it). Unlike rosmaster it remembers where each
value came from (``config/x.yaml:12``), so that a node reading its parameters can
point at the line to fix (core.typed_params reads a namespace into a typed schema).
"""

from __future__ import annotations

import copy
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

from twil_control.core import names
from twil_control.core.yaml_io import Lines, display_path, load_yaml_with_lines
from twil_control.errors import TwilControlError


class _Missing:
    def __repr__(self) -> str:
        return "MISSING"


#: Sentinel for "no default given" in ParamServer.get.
MISSING: Any = _Missing()

_SCALARS = (bool, int, float, str)
#: a key that is a valid ROS base name as it is (the common case, joined without more checks)
_PLAIN_KEY = re.compile(r"[A-Za-z][A-Za-z0-9_]*")


class ParamError(TwilControlError, ValueError):
    """A parameter that is missing, misnamed, mistyped or out of range."""


class ParamNotFoundError(ParamError, KeyError):
    """A parameter that is not set (also a KeyError, like a missing dict key)."""


# --------------------------------------------------------------------------------------
# The parameter server
# --------------------------------------------------------------------------------------


class ParamServer:
    """A hierarchical parameter store keyed by global graph names.

    Values are what XML-RPC can carry: bool, int, float, str, lists of those (and of
    mappings), and mappings, which are namespaces. ``None`` is refused, as rosmaster
    refuses it, so an empty ``key:`` in YAML is reported instead of stored.
    """

    def __init__(self) -> None:
        self._root: dict[str, Any] = {}
        self._sources: dict[str, str] = {}
        self.warned: set[str] = set()  # parameters load_typed has warned about (once each)

    # ---- writing --------------------------------------------------------------------
    def set(self, name: str, value: Any, source: str | None = None) -> None:
        """Set ``name``; a mapping value is merged into the namespace, like ``rosparam set``."""
        self._set(global_name(name), value, lambda _rel: source, ())

    def load_data(
        self,
        data: Any,
        namespace: str = "/",
        *,
        file: str,
        lines: Lines | None = None,
        key_path: tuple = (),
        param: str | None = None,
    ) -> None:
        """Load parsed YAML like ``rosparam load``, recording ``file:line`` per key.

        ``data`` goes under ``namespace`` (a mapping is required then), or, when
        ``param`` is given, is set as the value of ``namespace/param``. ``lines`` and
        ``key_path`` locate the data inside ``file`` (see yaml_io.Lines).
        """
        lines = lines or {}

        def source(rel: tuple) -> str:
            path = key_path + rel
            while path and path not in lines:
                path = path[:-1]
            return f"{file}:{lines.get(path, 1)}"

        namespace = global_name(namespace)
        if param is not None:
            self._set(global_name(names.join(namespace, param)), data, source, ())
        elif data is None:  # an empty file loads nothing, as with rosparam
            return
        elif not isinstance(data, dict):
            raise ParamError(
                f"{source(())}: parameters loaded into namespace {namespace!r} must be a "
                f"mapping of names to values, got {_kind(data)} (give a 'param' name to "
                f"store a single value)"
            )
        else:
            self._set(namespace, data, source, ())

    def load_file(self, path: str | Path, namespace: str = "/", param: str | None = None) -> None:
        """``rosparam load path namespace``: raises YamlError/ParamError naming file:line."""
        data, lines = load_yaml_with_lines(path)
        self.load_data(data, namespace, file=display_path(path), lines=lines, param=param)

    def delete(self, name: str) -> None:
        """Delete a parameter or a whole namespace; ``/`` clears the server."""
        name = global_name(name)
        if name == "/":
            self._root.clear()
            self._sources.clear()
            return
        parent = self._lookup(names.namespace_of(name))
        key = names.basename(name)
        if not isinstance(parent, dict) or key not in parent:
            raise ParamNotFoundError(self._not_found(name))
        del parent[key]
        self._forget(name)

    # ---- reading --------------------------------------------------------------------
    def get(self, name: str, default: Any = MISSING) -> Any:
        """The value of ``name`` (a namespace gives a nested dict copy)."""
        value = self._lookup(global_name(name))
        if value is MISSING:
            if default is MISSING:
                raise ParamNotFoundError(self._not_found(global_name(name)))
            return default
        return copy.deepcopy(value)

    def has(self, name: str) -> bool:
        return self._lookup(global_name(name)) is not MISSING

    def names(self) -> list[str]:
        """Every leaf parameter, sorted (namespaces are not listed themselves)."""
        found: list[str] = []

        def walk(prefix: str, tree: dict) -> None:
            for key, value in tree.items():
                full = names.join(prefix, key)
                if isinstance(value, dict):
                    walk(full, value)
                else:
                    found.append(full)

        walk("/", self._root)
        return sorted(found)

    def dump(self, namespace: str = "/") -> dict:
        """A copy of a namespace as a nested dict (``rosparam dump``)."""
        value = self.get(namespace)
        if not isinstance(value, dict):
            raise ParamError(f"{global_name(namespace)!r} is a parameter, not a namespace")
        return value

    def source_of(self, name: str) -> str | None:
        """Where ``name`` was set ("config/x.yaml:12", "command line", ...), if known.

        For a namespace set key by key, the source of its first parameter.
        """
        name = global_name(name)
        if name in self._sources:
            return self._sources[name]
        prefix = name.rstrip("/") + "/"
        under = sorted(key for key in self._sources if key.startswith(prefix))
        return self._sources[under[0]] if under else None

    def alias(self, name: str, source_name: str) -> None:
        """Report `name`'s source as `source_name`'s (a renamed parameter read under its new name)."""
        source = self.source_of(source_name)
        if source is not None and global_name(name) not in self._sources:
            self._sources[global_name(name)] = source

    def files_under(self, namespace: str) -> list[str]:
        """The distinct files (without line numbers) that set parameters in ``namespace``."""
        namespace = global_name(namespace)
        prefix = namespace.rstrip("/") + "/"
        files: list[str] = []
        for key in sorted(self._sources):
            if key == namespace or key.startswith(prefix):
                file = re.sub(r":\d+$", "", self._sources[key])
                if file not in files:
                    files.append(file)
        return files

    # ---- internals ------------------------------------------------------------------
    def _set(self, name: str, value: Any, source: Callable[[tuple], str | None], rel: tuple) -> None:
        if isinstance(value, dict):
            namespace = self._namespace(name)
            self._record(name, source(rel))
            for key, item in value.items():
                child = self._child(name, key, source, rel)
                if isinstance(item, dict) or "/" in key:  # a mapping, a global or a nested name
                    self._set(child, item, source, rel + (key,))
                else:  # straight into the namespace's dict: no walk from the root per key
                    self._set_value(namespace, key, child, item, source(rel + (key,)))
            return
        if name == "/":
            raise ParamError(
                f"{source_prefix(source(rel))}cannot set the root namespace '/' to "
                f"{_kind(value)}; only a mapping can be set at '/'"
            )
        parent = self._namespace(names.namespace_of(name))
        self._set_value(parent, names.basename(name), name, value, source(rel))

    def _set_value(self, parent: dict, key: str, name: str, value: Any, source: str | None) -> None:
        """Set the non-mapping `value` as `key` of the namespace dict `parent` (full name `name`)."""
        checked = _checked_value(value, name, source)
        if isinstance(parent.get(key), dict):
            self._forget(name)  # a namespace replaced by a value loses its old sources (a scan, rare)
        else:
            self._sources.pop(name, None)  # one key: no scan, so loading n keys is linear
        parent[key] = checked
        self._record(name, source)

    @staticmethod
    def _child(name: str, key: Any, source: Callable[[tuple], str | None], rel: tuple) -> str:
        """The full name of ``key`` in namespace ``name``, with rosparam's ns_join."""
        if isinstance(key, str) and _PLAIN_KEY.fullmatch(key):  # most keys: no checks to make
            return f"{name}/{key}" if name != "/" else f"/{key}"
        where = source_prefix(source(rel + (key,)) if isinstance(key, str) else source(rel))
        if not isinstance(key, str):
            raise ParamError(f"{where}parameter names must be strings, got {key!r} under {name!r}")
        if names.is_private(key):
            raise ParamError(
                f"{where}private name {key!r} is not allowed in a parameter "
                f"mapping (under {name!r}); drop the '~'"
            )
        try:
            names.validate(key)
        except names.GraphNameError as exc:
            raise ParamError(f"{where}{exc}") from None
        return names.join(name, key)

    def _namespace(self, name: str) -> dict:
        """The dict of namespace ``name``, created as needed.

        A value in the way becomes an empty namespace, as in rosmaster's set_param.
        """
        tree, path = self._root, "/"
        for token in _tokens(name):
            path = names.join(path, token)
            if not isinstance(tree.get(token), dict):
                self._sources.pop(path, None)
                tree[token] = {}
            tree = tree[token]
        return tree

    def _lookup(self, name: str) -> Any:
        tree: Any = self._root
        for token in _tokens(name):
            if not isinstance(tree, dict) or token not in tree:
                return MISSING
            tree = tree[token]
        return tree

    def _record(self, name: str, source: str | None) -> None:
        if source is not None:
            self._sources[name] = source

    def _forget(self, name: str) -> None:
        prefix = name.rstrip("/") + "/"
        for key in [k for k in self._sources if k == name or k.startswith(prefix)]:
            del self._sources[key]

    def _not_found(self, name: str) -> str:
        parent = names.namespace_of(name)
        siblings = self._lookup(parent)
        if isinstance(siblings, dict) and siblings:
            return f"parameter {name!r} is not set; {parent!r} has: {', '.join(sorted(siblings))}"
        return f"parameter {name!r} is not set"


def global_name(name: str) -> str:
    """A parameter name checked for the server: valid and global; canonical."""
    try:
        names.validate(name)
    except names.GraphNameError as exc:
        raise ParamError(str(exc)) from None
    if not names.is_global(name):
        raise ParamError(
            f"parameter name {name!r} must be global (start with '/'); "
            f"resolve it in the node's namespace first"
        )
    return names.canonical(name)


def _tokens(name: str) -> list[str]:
    return [token for token in name.split("/") if token]


def source_prefix(source: str | None) -> str:
    """ "file:line: " of a parameter's source, for messages ("" when unknown)."""
    return f"{source}: " if source else ""


def param_error(server: ParamServer, name: str, problem: str) -> ParamError:
    """A ParamError for parameter `name` (global): where it was set, its name, its value and
    `problem` ("must be ..."), for checks a schema cannot make alone (a list's length against
    the number of joints)."""
    name = global_name(name)
    value = server.get(name, MISSING)
    got = "" if value is MISSING else f" (got {value!r})"
    return ParamError(f"{source_prefix(server.source_of(name))}parameter {name!r} {problem}{got}")


def _kind(value: Any) -> str:
    return {
        dict: "a mapping",
        list: "a list",
        str: "a string",
        bool: "a boolean",
        int: "an integer",
        float: "a number",
        type(None): "null",
    }.get(type(value), f"a {type(value).__name__}")


def _checked_value(value: Any, name: str, source: str | None) -> Any:
    """A copy of ``value`` if the ROS parameter server can hold it, else ParamError."""
    if isinstance(value, _SCALARS):
        return value
    if isinstance(value, (list, tuple)):
        return [_checked_value(item, f"{name}[{i}]", source) for i, item in enumerate(value)]
    if isinstance(value, dict):  # a mapping inside a list (a struct in XML-RPC terms)
        return {str(key): _checked_value(item, f"{name}/{key}", source) for key, item in value.items()}
    if value is None:
        raise ParamError(
            f"{source_prefix(source)}parameter {name!r} has no value (YAML null, or an "
            f"empty 'key:'); the ROS parameter server cannot store null"
        )
    raise ParamError(
        f"{source_prefix(source)}parameter {name!r} has unsupported type "
        f"{type(value).__name__} ({value!r}); allowed: bool, int, float, str, "
        f"lists and mappings of those"
    )
