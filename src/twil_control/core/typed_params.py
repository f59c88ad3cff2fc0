"""Typed parameter schemas: load_typed reads one namespace of the parameter server into a dataclass.

Values of the wrong type and values out of range (fields declared with core.param_rules.param)
are refused with the file:line where the parameter was set. An unknown key follows the schema's
policy: this project's own nodes and controllers refuse it (a misspelt gain must not leave a
robot running on its default), while a schema standing for someone else's ROS package (its
class attribute ``ros_package`` names the package) warns once, naming the file:line and the
nearest allowed name, and goes on, as that package would ignore it: a ROS user's file that ran
for years, typo included, runs here too.
"""

from __future__ import annotations

import dataclasses
import difflib
import logging
import math
import types
import typing
from collections.abc import Callable
from typing import Any, Literal, TypeVar, Union

from twil_control.core import names
from twil_control.core.param_rules import rule_of
from twil_control.core.params import MISSING, ParamError, ParamServer, global_name, source_prefix

T = TypeVar("T")

#: Where load_typed's warnings go when the caller gives no logger (a node passes its own).
_log = logging.getLogger("twil_control.params")


def schema_keys(schema: type) -> tuple[str, ...]:
    """The parameter names a schema dataclass accepts (its init fields, in order)."""
    return tuple(f.name for f in dataclasses.fields(schema) if f.init)


def _no_effect(key: str, value: Any, full: str, server: ParamServer, schema: type, warn: Warn) -> None:
    """One warning for a parameter the schema's package reads but the simulation does not honour:
    the schema's ``no_effect`` maps its name to why, or to (a value that needs no warning, why)."""
    entry = getattr(schema, "no_effect", {}).get(key)
    if entry is None or full in server.warned:
        return
    fine, why = entry if isinstance(entry, tuple) else (MISSING, entry)
    if value == fine:
        return
    server.warned.add(full)
    warn(f"{source_prefix(server.source_of(full))}parameter {full!r} = {value!r} has no effect here: {why}")


def _renamed(schema: type, raw: dict, namespace: str, server: ParamServer, warn: Warn) -> dict:
    """`raw` with the schema's old parameter names (its ``renamed``: old -> new) read as the new
    ones when those are not set, each warned about once, as nav_core's warnRenamedParameter does;
    file:line stay the old name's."""
    renamed = getattr(schema, "renamed", {})
    if not any(old in raw for old in renamed):
        return raw
    raw = dict(raw)
    for old, new in renamed.items():
        if old not in raw:
            continue
        value = raw.pop(old)
        full = names.join(namespace, old)
        if full not in server.warned:
            server.warned.add(full)
            used = "ignored: the new name is set too" if new in raw else "its value is used"
            warn(
                f"{source_prefix(server.source_of(full))}parameter {full!r} has been renamed to {new!r} ({used})"
            )
        if new not in raw:
            raw[new] = value
            server.alias(names.join(namespace, new), full)
    return raw


def package_of(schema: type) -> str | None:
    """The ROS package a schema stands for (its ``ros_package`` class attribute, e.g.
    ``ros_package: ClassVar[str] = "move_base"``), or None: a schema of this project's own."""
    return getattr(schema, "ros_package", None)


Warn = Callable[[str], None]


def load_typed(server: ParamServer, namespace: str, schema: type[T], warn: Warn | None = None) -> T:
    """Read the parameters under ``namespace`` into an instance of dataclass ``schema``.

    Field names are the ROS parameter names. Every value must match the field's annotation,
    and every field without a default must be set; errors name the file and line the
    parameter came from. A key that is no field is an error, or, for a schema with a
    ``ros_package``, a warning (through ``warn``, once per parameter and server) and ignored;
    a key in the schema's ``no_effect`` (read by the package, not honoured here) warns once, an
    old name in its ``renamed`` is read as the new one with a warning, and a key matching its
    ``dynamic_keys`` (a compiled pattern) is left to the caller. A
    ``ValueError`` raised by the schema's ``__post_init__`` (range checks) becomes a
    ParamError naming the namespace and its source.
    """
    namespace = global_name(namespace)
    raw = server.get(namespace, {})
    if not isinstance(raw, dict):
        raise ParamError(
            f"{source_prefix(server.source_of(namespace))}parameter {namespace!r} "
            f"must be a namespace holding {', '.join(schema_keys(schema))} "
            f"(got {raw!r})"
        )
    return _build(schema, raw, namespace, server, warn or _log.warning)


def _unknown(key: str, fields: dict, namespace: str, server: ParamServer, schema: type, warn: Warn) -> None:
    """An unknown key under `namespace`: ParamError, or one warning if the schema has a ros_package."""
    full = names.join(namespace, key)
    close = closest(key, list(fields))
    hint = f" (did you mean {close!r}?)" if close else ""
    allowed = ", ".join(sorted(fields))
    where = source_prefix(server.source_of(full))
    package = package_of(schema)
    if package is None:
        raise ParamError(f"{where}unknown parameter {full!r}{hint}; allowed: {allowed}")
    if full not in server.warned:
        server.warned.add(full)
        warn(
            f"{where}unknown parameter {full!r}{hint} is ignored, as {package} ignores "
            f"parameters it does not read; allowed: {allowed}"
        )


def closest(name: str, allowed: list[str]) -> str | None:
    """The allowed name `name` most likely misspells, if any; case is ignored first
    (maxURange -> maxUrange), then difflib's closest match."""
    folded = {a.lower(): a for a in allowed}
    if name.lower() in folded:
        return folded[name.lower()]
    close = difflib.get_close_matches(name.lower(), list(folded), n=1)
    return folded[close[0]] if close else None


def _build(schema: type[T], raw: dict, namespace: str, server: ParamServer, warn: Warn) -> T:
    if not dataclasses.is_dataclass(schema):
        raise TypeError(f"load_typed needs a dataclass schema, got {schema!r}")
    hints = typing.get_type_hints(schema)
    fields = {f.name: f for f in dataclasses.fields(schema) if f.init}
    raw = _renamed(schema, raw, namespace, server, warn)
    dynamic = getattr(schema, "dynamic_keys", None)  # keys the node reads itself (sensor0, ...)
    for key in raw:
        if key not in fields and not (dynamic is not None and dynamic.match(key)):
            _unknown(key, fields, namespace, server, schema, warn)
    values: dict[str, Any] = {}
    missing: list[str] = []
    for key, field in fields.items():
        full = names.join(namespace, key)
        if key in raw:
            values[key] = _convert(raw[key], hints[key], full, server, warn)
            _no_effect(key, values[key], full, server, schema, warn)
            rule = rule_of(field)
            problem = rule.problem(values[key]) if rule is not None else None
            if problem is not None:
                raise ParamError(
                    f"{source_prefix(server.source_of(full))}parameter {full!r} {problem} (got {raw[key]!r})"
                )
        elif field.default is dataclasses.MISSING and field.default_factory is dataclasses.MISSING:
            missing.append(full)
    if missing:
        files = server.files_under(namespace)
        origin = (
            f"parameters under {namespace!r} were loaded from {', '.join(files)}"
            if files
            else f"no parameters are set under {namespace!r}"
        )
        plural = "s" if len(missing) > 1 else ""
        raise ParamError(
            f"missing required parameter{plural} "
            f"{', '.join(repr(m) for m in missing)} for {schema.__name__}; "
            f"{origin}"
        )
    try:
        return schema(**values)
    except ParamError:
        raise
    except ValueError as exc:
        raise ParamError(
            f"{source_prefix(server.source_of(namespace))}invalid parameters in "
            f"{namespace!r} ({schema.__name__}): {exc}"
        ) from None


def _convert(value: Any, annotation: Any, name: str, server: ParamServer, warn: Warn) -> Any:
    """Check ``value`` against ``annotation``; ``name`` is the parameter, for messages."""
    if annotation is Any:
        return value
    converted = _converter_for(annotation, name)(value, annotation, name, server, warn)
    if converted is _NO_FIT:
        source = server.source_of(name.split("[")[0])  # list items share their key's line
        raise ParamError(
            f"{source_prefix(source)}parameter {name!r} must be "
            f"{describe(annotation)} (got {value!r}){_hint(value, annotation)}"
        )
    return converted


#: A converter's answer for a value its annotation does not accept (_convert words the error).
_NO_FIT = object()
_SCALARS = (bool, int, float, str)
_BARE_CONTAINERS = (list, tuple, dict)


def _converter_for(annotation: Any, name: str) -> Callable[[Any, Any, str, ParamServer, Warn], Any]:
    origin = typing.get_origin(annotation)
    if origin in (Union, types.UnionType):
        return _convert_union
    if origin is Literal:
        return _convert_literal
    if annotation in _SCALARS:
        return _convert_scalar
    if annotation in _BARE_CONTAINERS:
        return _convert_bare_container
    if origin is list:
        return _convert_list
    if origin is tuple:
        return _convert_tuple
    if origin is dict:
        return _convert_dict
    if isinstance(annotation, type) and dataclasses.is_dataclass(annotation):
        return _convert_dataclass
    raise TypeError(f"unsupported annotation {annotation!r} for parameter {name!r}")


def _convert_union(value: Any, annotation: Any, name: str, server: ParamServer, warn: Warn) -> Any:
    args = typing.get_args(annotation)
    if value is None and type(None) in args:
        return None
    options = [a for a in args if a is not type(None)]
    if len(options) == 1:  # Optional[T]: T's own message
        return _convert(value, options[0], name, server, warn)
    for option in options:  # the first that fits
        try:
            return _convert(value, option, name, server, warn)
        except ParamError:
            pass
    return _NO_FIT


def _convert_literal(value: Any, annotation: Any, name: str, server: ParamServer, warn: Warn) -> Any:
    choices = typing.get_args(annotation)
    return value if any(type(value) is type(c) and value == c for c in choices) else _NO_FIT


def _convert_scalar(value: Any, annotation: Any, name: str, server: ParamServer, warn: Warn) -> Any:
    """bool, int, float (an int is taken as a float) or str; a YAML boolean is never a number."""
    accepted = (int, float) if annotation is float else annotation
    if not isinstance(value, accepted) or (isinstance(value, bool) and annotation is not bool):
        return _NO_FIT
    return float(value) if annotation is float else value


def _convert_bare_container(value: Any, annotation: Any, name: str, server: ParamServer, warn: Warn) -> Any:
    """A bare list, tuple (a YAML list) or dict, its items unchecked."""
    return annotation(value) if isinstance(value, list if annotation is tuple else annotation) else _NO_FIT


def _convert_list(value: Any, annotation: Any, name: str, server: ParamServer, warn: Warn) -> Any:
    if not isinstance(value, list):
        return _NO_FIT
    (item_type,) = typing.get_args(annotation)
    return [_convert(item, item_type, f"{name}[{i}]", server, warn) for i, item in enumerate(value)]


def _convert_tuple(value: Any, annotation: Any, name: str, server: ParamServer, warn: Warn) -> Any:
    """tuple[T, ...] takes a list of any length, tuple[A, B] a list of exactly two."""
    args = typing.get_args(annotation)
    if not isinstance(value, list):
        return _NO_FIT
    if len(args) == 2 and args[1] is Ellipsis:
        args = (args[0],) * len(value)
    elif len(value) != len(args):
        return _NO_FIT
    return tuple(
        _convert(item, arg, f"{name}[{i}]", server, warn) for i, (item, arg) in enumerate(zip(value, args))
    )


def _convert_dict(value: Any, annotation: Any, name: str, server: ParamServer, warn: Warn) -> Any:
    if not isinstance(value, dict):
        return _NO_FIT
    item_type = typing.get_args(annotation)[1]
    return {
        key: _convert(item, item_type, names.join(name, key), server, warn) for key, item in value.items()
    }


def _convert_dataclass(value: Any, annotation: Any, name: str, server: ParamServer, warn: Warn) -> Any:
    return _build(annotation, value, name, server, warn) if isinstance(value, dict) else _NO_FIT


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
    if isinstance(annotation, type) and dataclasses.is_dataclass(annotation):
        return f"a mapping with keys {', '.join(schema_keys(annotation))}"
    simple = {
        bool: "a boolean (true or false)",
        int: "an integer",
        float: "a number",
        str: "a string",
        list: "a list",
        tuple: "a list",
        dict: "a mapping",
        Any: "any value",
    }
    return simple.get(annotation, repr(annotation))


def _plural(annotation: Any) -> str:
    simple = {bool: "booleans", int: "integers", float: "numbers", str: "strings"}
    return simple.get(annotation, f"items that are each {describe(annotation)}")


def _hint(value: Any, annotation: Any) -> str:
    """Explain the usual YAML surprises behind a type error."""
    wants_number = annotation in (int, float)
    if wants_number and isinstance(value, str):
        try:
            if not math.isfinite(float(value)):  # "nan", "inf": no number to suggest
                return ""
        except ValueError:
            return ""
        return (
            "; YAML read it as a string: quote-free numbers need a '.' before an "
            "exponent (write 1.0e-3, not 1e-3)"
        )
    if wants_number and isinstance(value, bool):
        return "; booleans are not numbers"
    if annotation is int and isinstance(value, float):
        return "; write it without a decimal point, or declare the parameter as float"
    return ""
