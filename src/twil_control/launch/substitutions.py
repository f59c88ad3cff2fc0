"""roslaunch substitution args: ``$(find pkg)``, ``$(arg x)``, ``$(env X)`` and friends.

roslaunch's syntax and meaning, with two differences: ``$(eval ...)`` is evaluated on a
whitelisted syntax tree (eval_expr.py), never by Python's eval; ``$(anon name)`` is
deterministic (``name_1``, ``name_2``, ... in order of first use), because a launch must give the
same run and the same bag every time. Errors carry no location: the loader adds the file and line.
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from twil_control.core import packages
from twil_control.errors import InputError
from twil_control.launch.eval_expr import EvalError, evaluate
from twil_control.launch.plan import LaunchError

SUPPORTED = (
    "$(find pkg)",
    "$(arg name)",
    "$(env NAME)",
    "$(optenv NAME [default])",
    "$(dirname)",
    "$(anon name)",
    "$(eval expression)",
)

#: A decimal number with an exponent and no '.', which YAML 1.1 and roslaunch's auto typing
#: leave a string.
_EXPONENT = re.compile(r"[-+]?[0-9]+[eE][-+]?[0-9]+")


class SubstitutionError(LaunchError):
    """A substitution that cannot be resolved (message without file/line)."""


@dataclass
class SubstitutionContext:
    """What a substitution may refer to, at one point of one launch file."""

    args: Mapping[str, str]  # args visible here: name -> value
    launch_file: Path  # for $(dirname) and messages
    file_label: str = ""  # how the file is named in messages
    anon: dict[str, str] = field(default_factory=dict)  # shared by the whole launch
    environ: Mapping[str, str] = field(default_factory=lambda: os.environ)


def has_substitution(value: Any) -> bool:
    return isinstance(value, str) and "$(" in value


def find_package(name: str) -> Path:
    """The directory of package ``name`` (``$(find name)``), from core.packages
    (ROS_PACKAGE_PATH, --package-path, this project, and xacro); SubstitutionError if unknown."""
    try:
        return packages.find(name)
    except packages.PackageNotFoundError as exc:
        raise SubstitutionError(f"$(find {name}): {exc}") from None


def substitute(text: str, ctx: SubstitutionContext) -> str:
    """Replace every ``$(...)`` in ``text``, left to right (no nesting, as roslaunch).

    ``$(eval ...)`` must be the whole of ``text``, as in roslaunch.
    """
    stripped = text.strip()
    if stripped.startswith("$(eval ") and stripped.endswith(")"):
        return _eval(stripped[len("$(eval ") : -1], ctx)
    if "$(eval " in text or "$(eval)" in text:
        raise SubstitutionError(f"$(eval ...) must be the whole value, as in roslaunch: {text!r}")
    out: list[str] = []
    pos = 0
    while (start := text.find("$(", pos)) >= 0:
        end = text.find(")", start)
        if end < 0:
            raise SubstitutionError(f"unterminated substitution in {text!r}: '$(' without ')'")
        inner = text[start + 2 : end]
        if "$(" in inner:
            raise SubstitutionError(f"nested substitutions are not supported: {text!r}")
        out.append(text[pos:start])
        out.append(_resolve(inner, ctx))
        pos = end + 1
    out.append(text[pos:])
    return "".join(out)


def _resolve(inner: str, ctx: SubstitutionContext) -> str:
    words = inner.split()
    command = words.pop(0) if words else ""
    shown = f"$({inner})"
    if command == "find":
        return str(find_package(_one(words, shown, "a package name")))
    if command == "arg":
        return _arg(_one(words, shown, "an arg name"), ctx, shown)
    if command == "env":
        return _env(_one(words, shown, "an environment variable name"), ctx, shown)
    if command == "optenv":
        if not words:
            raise SubstitutionError(f"{shown}: expected $(optenv NAME [default])")
        return ctx.environ.get(words[0], " ".join(words[1:]))
    if command == "dirname":
        if words:
            raise SubstitutionError(f"{shown}: $(dirname) takes no arguments")
        return _dirname(ctx)
    if command == "anon":
        return _anon(_one(words, shown, "a base name"), ctx)
    raise SubstitutionError(f"unknown substitution {shown}; supported: {', '.join(SUPPORTED)}")


def _arg(name: str, ctx: SubstitutionContext, shown: str) -> str:
    if name not in ctx.args:
        declared = ", ".join(ctx.args) or "none"
        raise SubstitutionError(
            f"{shown}: arg {name!r} is not declared in {ctx.file_label or ctx.launch_file}"
            f"; declared args: {declared}"
        )
    return ctx.args[name]


def _env(name: str, ctx: SubstitutionContext, shown: str) -> str:
    if name not in ctx.environ:
        raise SubstitutionError(
            f"{shown}: environment variable {name!r} is not set (use $(optenv {name} "
            f"default) to fall back to a default)"
        )
    return ctx.environ[name]


def _dirname(ctx: SubstitutionContext) -> str:
    return str(Path(ctx.launch_file).absolute().parent)


def _anon(name: str, ctx: SubstitutionContext) -> str:
    if name not in ctx.anon:
        ctx.anon[name] = f"{name}_{len(ctx.anon) + 1}"
    return ctx.anon[name]


def _eval(expression: str, ctx: SubstitutionContext) -> str:
    """``$(eval expression)`` as roslaunch gives it: the value's str()."""
    shown = f"$(eval {expression})"

    def arg_value(name: str) -> Any:
        if name not in ctx.args:
            raise KeyError(name)
        return auto_type(ctx.args[name])

    functions = {
        "arg": lambda name: auto_type(_arg(name, ctx, f"{shown}: arg({name!r})")),
        "env": lambda name: _env(name, ctx, f"{shown}: env({name!r})"),
        "optenv": lambda name, default="": ctx.environ.get(name, default),
        "find": lambda name: str(find_package(name)),
        "anon": lambda name: _anon(name, ctx),
        "dirname": lambda: _dirname(ctx),
    }
    try:
        return str(evaluate(expression, arg_value, functions))
    except EvalError as exc:
        raise SubstitutionError(str(exc)) from None


def _one(words: list[str], shown: str, what: str) -> str:
    if len(words) != 1:
        raise SubstitutionError(f"{shown}: expected exactly one argument, {what}")
    return words[0]


def auto_type(text: str) -> bool | int | float | str:
    """roslaunch's ``type="auto"`` for a ``<param value=...>`` string.

    roslaunch's convert_value: a value with '.' tries float, otherwise int; then
    'true'/'false' in any case are booleans; anything else stays a string. One addition:
    a number written with an exponent and no '.' (``1e-3``, ``2E6``) is a float, where
    roslaunch keeps the string "1e-3" that a double parameter then cannot read (an arg is
    text, typed by what it is put into; here the node's schema would refuse the string).
    """
    try:
        return float(text) if "." in text else int(text)
    except ValueError:
        pass
    if _EXPONENT.fullmatch(text.strip()):
        return float(text)
    if text.strip().lower() in ("true", "false"):
        return text.strip().lower() == "true"
    return text


def to_bool(value: Any) -> bool:
    """roslaunch's boolean: true/false/1/0 (any case) or a YAML boolean, else ValueError."""
    if isinstance(value, bool):
        return value
    if isinstance(value, int) and value in (0, 1):
        return bool(value)
    if isinstance(value, str) and value.strip().lower() in ("true", "1", "false", "0"):
        return value.strip().lower() in ("true", "1")
    raise InputError(f"expected true, false, 1 or 0, got {value!r}")
