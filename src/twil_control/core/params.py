"""The parameter server (rosmaster's role) and typed parameter schemas.

ParamServer keeps ROS's parameter tree: global names, namespaces as nested
mappings, and rosparam's merge semantics (setting a mapping updates a namespace
key by key instead of replacing it). Unlike rosmaster it remembers where each
value came from (``config/x.yaml:12``), so that a node reading its parameters can
point at the line to fix.

load_typed reads one namespace into a dataclass, refusing unknown keys and values
of the wrong type or out of range (fields declared with core.param_rules.param): in
ROS a misspelt parameter is silently ignored and the node runs with its default,
which is the bug this module exists to prevent.
"""
from __future__ import annotations

import copy
import dataclasses
import difflib
import math
import re
import types
import typing
from collections.abc import Callable
from pathlib import Path
from typing import Any, Literal, TypeVar, Union

from twil_control.core import names
from twil_control.core.param_rules import rule_of
from twil_control.core.yaml_io import Lines, display_path, load_yaml_with_lines

T = TypeVar("T")


class _Missing:
    def __repr__(self) -> str:
        return "MISSING"


#: Sentinel for "no default given" in ParamServer.get.
MISSING: Any = _Missing()

_SCALARS = (bool, int, float, str)


class ParamError(ValueError):
    """A parameter that is missing, misnamed, mistyped or out of range."""


class ParamNotFoundError(ParamError, KeyError):
    """A parameter that is not set (also a KeyError, like a missing dict key)."""

    def __str__(self) -> str:  # KeyError would print the message quoted
        return str(self.args[0])


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

    # ---- writing --------------------------------------------------------------------
    def set(self, name: str, value: Any, source: str | None = None) -> None:
        """Set ``name``; a mapping value is merged into the namespace, like ``rosparam set``."""
        self._set(_global(name), value, lambda _rel: source, ())

    def load_data(self, data: Any, namespace: str = "/", *, file: str,
                  lines: Lines | None = None, key_path: tuple = (),
                  param: str | None = None) -> None:
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

        namespace = _global(namespace)
        if param is not None:
            self._set(_global(names.join(namespace, param)), data, source, ())
        elif data is None:  # an empty file loads nothing, as with rosparam
            return
        elif not isinstance(data, dict):
            raise ParamError(
                f"{source(())}: parameters loaded into namespace {namespace!r} must be a "
                f"mapping of names to values, got {_kind(data)} (give a 'param' name to "
                f"store a single value)")
        else:
            self._set(namespace, data, source, ())

    def load_file(self, path: str | Path, namespace: str = "/",
                  param: str | None = None) -> None:
        """``rosparam load path namespace``: raises YamlError/ParamError naming file:line."""
        data, lines = load_yaml_with_lines(path)
        self.load_data(data, namespace, file=display_path(path), lines=lines, param=param)

    def delete(self, name: str) -> None:
        """Delete a parameter or a whole namespace; ``/`` clears the server."""
        name = _global(name)
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
        value = self._lookup(_global(name))
        if value is MISSING:
            if default is MISSING:
                raise ParamNotFoundError(self._not_found(_global(name)))
            return default
        return copy.deepcopy(value)

    def has(self, name: str) -> bool:
        return self._lookup(_global(name)) is not MISSING

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
            raise ParamError(f"{_global(namespace)!r} is a parameter, not a namespace")
        return value

    def source_of(self, name: str) -> str | None:
        """Where ``name`` was set ("config/x.yaml:12", "command line", ...), if known.

        For a namespace set key by key, the source of its first parameter.
        """
        name = _global(name)
        if name in self._sources:
            return self._sources[name]
        prefix = name.rstrip("/") + "/"
        under = sorted(key for key in self._sources if key.startswith(prefix))
        return self._sources[under[0]] if under else None

    def files_under(self, namespace: str) -> list[str]:
        """The distinct files (without line numbers) that set parameters in ``namespace``."""
        namespace = _global(namespace)
        prefix = namespace.rstrip("/") + "/"
        files: list[str] = []
        for key in sorted(self._sources):
            if key == namespace or key.startswith(prefix):
                file = re.sub(r":\d+$", "", self._sources[key])
                if file not in files:
                    files.append(file)
        return files

    # ---- internals ------------------------------------------------------------------
    def _set(self, name: str, value: Any, source: Callable[[tuple], str | None],
             rel: tuple) -> None:
        if isinstance(value, dict):
            self._namespace(name)
            self._record(name, source(rel))
            for key, item in value.items():
                self._set(self._child(name, key, source, rel), item, source, rel + (key,))
            return
        if name == "/":
            raise ParamError(f"{_where(source(rel))}cannot set the root namespace '/' to "
                             f"{_kind(value)}; only a mapping can be set at '/'")
        checked = _checked_value(value, name, source(rel))
        parent = self._namespace(names.namespace_of(name))
        self._forget(name)  # a namespace replaced by a value loses its old sources
        parent[names.basename(name)] = checked
        self._record(name, source(rel))

    @staticmethod
    def _child(name: str, key: Any, source: Callable[[tuple], str | None],
               rel: tuple) -> str:
        """The full name of ``key`` in namespace ``name``, with rosparam's ns_join."""
        where = _where(source(rel + (key,)) if isinstance(key, str) else source(rel))
        if not isinstance(key, str):
            raise ParamError(f"{where}parameter names must be strings, got {key!r} "
                             f"under {name!r}")
        if names.is_private(key):
            raise ParamError(f"{where}private name {key!r} is not allowed in a parameter "
                             f"mapping (under {name!r}); drop the '~'")
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
            return (f"parameter {name!r} is not set; {parent!r} has: "
                    f"{', '.join(sorted(siblings))}")
        return f"parameter {name!r} is not set"


def _global(name: str) -> str:
    """Validate a parameter name for the server: it must be global."""
    try:
        names.validate(name)
    except names.GraphNameError as exc:
        raise ParamError(str(exc)) from None
    if not names.is_global(name):
        raise ParamError(f"parameter name {name!r} must be global (start with '/'); "
                         f"resolve it in the node's namespace first")
    return names.canonical(name)


def _tokens(name: str) -> list[str]:
    return [token for token in name.split("/") if token]


def _where(source: str | None) -> str:
    return f"{source}: " if source else ""


def param_error(server: ParamServer, name: str, problem: str) -> ParamError:
    """A ParamError for parameter `name` (global): where it was set, its name, its value and
    `problem` ("must be ..."), for checks a schema cannot make alone (a list's length against
    the number of joints)."""
    name = _global(name)
    value = server.get(name, MISSING)
    got = "" if value is MISSING else f" (got {value!r})"
    return ParamError(f"{_where(server.source_of(name))}parameter {name!r} {problem}{got}")


def _kind(value: Any) -> str:
    return {dict: "a mapping", list: "a list", str: "a string", bool: "a boolean",
            int: "an integer", float: "a number", type(None): "null"}.get(
                type(value), f"a {type(value).__name__}")


def _checked_value(value: Any, name: str, source: str | None) -> Any:
    """A copy of ``value`` if the ROS parameter server can hold it, else ParamError."""
    if isinstance(value, _SCALARS):
        return value
    if isinstance(value, (list, tuple)):
        return [_checked_value(item, f"{name}[{i}]", source) for i, item in enumerate(value)]
    if isinstance(value, dict):  # a mapping inside a list (a struct in XML-RPC terms)
        return {str(key): _checked_value(item, f"{name}/{key}", source)
                for key, item in value.items()}
    if value is None:
        raise ParamError(f"{_where(source)}parameter {name!r} has no value (YAML null, or an "
                         f"empty 'key:'); the ROS parameter server cannot store null")
    raise ParamError(f"{_where(source)}parameter {name!r} has unsupported type "
                     f"{type(value).__name__} ({value!r}); allowed: bool, int, float, str, "
                     f"lists and mappings of those")


# --------------------------------------------------------------------------------------
# Typed schemas
# --------------------------------------------------------------------------------------

def schema_keys(schema: type) -> tuple[str, ...]:
    """The parameter names a schema dataclass accepts (its init fields, in order)."""
    return tuple(f.name for f in dataclasses.fields(schema) if f.init)


def load_typed(server: ParamServer, namespace: str, schema: type[T]) -> T:
    """Read the parameters under ``namespace`` into an instance of dataclass ``schema``.

    Field names are the ROS parameter names. Every key under the namespace must be a
    field, every value must match the field's annotation, and every field without a
    default must be set; errors name the file and line the parameter came from. A
    ``ValueError`` raised by the schema's ``__post_init__`` (range checks) becomes a
    ParamError naming the namespace and its source.
    """
    namespace = _global(namespace)
    raw = server.get(namespace, {})
    if not isinstance(raw, dict):
        raise ParamError(f"{_where(server.source_of(namespace))}parameter {namespace!r} "
                         f"must be a namespace holding {', '.join(schema_keys(schema))} "
                         f"(got {raw!r})")
    return _build(schema, raw, namespace, server)


def _build(schema: type[T], raw: dict, namespace: str, server: ParamServer) -> T:
    if not dataclasses.is_dataclass(schema):
        raise TypeError(f"load_typed needs a dataclass schema, got {schema!r}")
    hints = typing.get_type_hints(schema)
    fields = {f.name: f for f in dataclasses.fields(schema) if f.init}
    allowed = ", ".join(sorted(fields))
    for key in raw:
        if key not in fields:
            full = names.join(namespace, key)
            close = difflib.get_close_matches(key, list(fields), n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise ParamError(f"{_where(server.source_of(full))}unknown parameter "
                             f"{full!r}{hint}; allowed: {allowed}")
    values: dict[str, Any] = {}
    missing: list[str] = []
    for key, field in fields.items():
        full = names.join(namespace, key)
        if key in raw:
            values[key] = _convert(raw[key], hints[key], full, server)
            rule = rule_of(field)
            problem = rule.problem(values[key]) if rule is not None else None
            if problem is not None:
                raise ParamError(f"{_where(server.source_of(full))}parameter {full!r} {problem} "
                                 f"(got {raw[key]!r})")
        elif field.default is dataclasses.MISSING and field.default_factory is dataclasses.MISSING:
            missing.append(full)
    if missing:
        files = server.files_under(namespace)
        origin = (f"parameters under {namespace!r} were loaded from {', '.join(files)}"
                  if files else f"no parameters are set under {namespace!r}")
        plural = "s" if len(missing) > 1 else ""
        raise ParamError(f"missing required parameter{plural} "
                         f"{', '.join(repr(m) for m in missing)} for {schema.__name__}; "
                         f"{origin}")
    try:
        return schema(**values)
    except ParamError:
        raise
    except ValueError as exc:
        raise ParamError(f"{_where(server.source_of(namespace))}invalid parameters in "
                         f"{namespace!r} ({schema.__name__}): {exc}") from None


def _convert(value: Any, annotation: Any, name: str, server: ParamServer) -> Any:
    """Check ``value`` against ``annotation``; ``name`` is the parameter, for messages."""
    origin, args = typing.get_origin(annotation), typing.get_args(annotation)

    def wrong() -> ParamError:
        source = server.source_of(name.split("[")[0])  # list items share their key's line
        return ParamError(f"{_where(source)}parameter {name!r} must be "
                          f"{describe(annotation)} (got {value!r}){_hint(value, annotation)}")

    if annotation is Any:
        return value
    if origin in (Union, types.UnionType):
        if value is None and type(None) in args:
            return None
        options = [a for a in args if a is not type(None)]
        if len(options) == 1:  # Optional[T]: T's own message
            return _convert(value, options[0], name, server)
        for option in options:  # the first that fits
            try:
                return _convert(value, option, name, server)
            except ParamError:
                pass
        raise wrong()
    if origin is Literal:
        if any(type(value) is type(choice) and value == choice for choice in args):
            return value
        raise wrong()
    if annotation is bool:
        if isinstance(value, bool):
            return value
        raise wrong()
    if annotation is int:
        if isinstance(value, int) and not isinstance(value, bool):
            return value
        raise wrong()
    if annotation is float:
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return float(value)
        raise wrong()
    if annotation is str:
        if isinstance(value, str):
            return value
        raise wrong()
    if annotation in (list, tuple, dict):
        if isinstance(value, annotation if annotation is not tuple else list):
            return annotation(value)
        raise wrong()
    if origin is list:
        if not isinstance(value, list):
            raise wrong()
        return [_convert(item, args[0], f"{name}[{i}]", server) for i, item in enumerate(value)]
    if origin is tuple:
        if not isinstance(value, list):
            raise wrong()
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_convert(item, args[0], f"{name}[{i}]", server)
                         for i, item in enumerate(value))
        if len(value) != len(args):
            raise wrong()
        return tuple(_convert(item, arg, f"{name}[{i}]", server)
                     for i, (item, arg) in enumerate(zip(value, args)))
    if origin is dict:
        if not isinstance(value, dict):
            raise wrong()
        return {key: _convert(item, args[1], names.join(name, key), server)
                for key, item in value.items()}
    if dataclasses.is_dataclass(annotation):
        if not isinstance(value, dict):
            raise wrong()
        return _build(annotation, value, name, server)
    raise TypeError(f"unsupported annotation {annotation!r} for parameter {name!r}")


def describe(annotation: Any) -> str:
    """A phrase for what an annotation accepts: 'a number', 'one of 'a', 'b''."""
    origin, args = typing.get_origin(annotation), typing.get_args(annotation)
    if origin in (Union, types.UnionType):
        return " or ".join(describe(a) for a in args if a is not type(None))
    if origin is Literal:
        return "one of " + ", ".join(repr(a) for a in args)
    if origin is list or (origin is tuple and len(args) == 2 and args[1] is Ellipsis):
        return f"a list of {_plural(args[0])}"
    if origin is tuple:
        return f"a list of {len(args)} items ({', '.join(describe(a) for a in args)})"
    if origin is dict:
        return f"a mapping of names to {_plural(args[1])}"
    if dataclasses.is_dataclass(annotation):
        return f"a mapping with keys {', '.join(schema_keys(annotation))}"
    simple = {bool: "a boolean (true or false)", int: "an integer", float: "a number",
              str: "a string", list: "a list", tuple: "a list", dict: "a mapping",
              Any: "any value"}
    return simple.get(annotation, repr(annotation))


def _plural(annotation: Any) -> str:
    simple = {bool: "booleans", int: "integers", float: "numbers", str: "strings"}
    return simple.get(annotation, f"items that are each {describe(annotation)}")


def _hint(value: Any, annotation: Any) -> str:
    """Explain the usual YAML surprises behind a type error."""
    wants_number = annotation in (int, float)
    if wants_number and isinstance(value, str):
        try:
            if not math.isfinite(float(value)):   # "nan", "inf": no number to suggest
                return ""
        except ValueError:
            return ""
        return ("; YAML read it as a string: quote-free numbers need a '.' before an "
                "exponent (write 1.0e-3, not 1e-3)")
    if wants_number and isinstance(value, bool):
        return "; booleans are not numbers"
    if annotation is int and isinstance(value, float):
        return "; write it without a decimal point, or declare the parameter as float"
    return ""
