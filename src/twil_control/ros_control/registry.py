"""Controller types by name: pluginlib's role for ``controller_interface::ControllerBase``.

A type string (``effort_controllers/JointEffortController``) names a class registered in this
process (``register``, ``@controller_type``), else an installed distribution's entry point in
the group ``twil_control.controllers``, imported only when its type is asked for, as pluginlib
loads libraries lazily. ``reload()`` reads the entry points again (reload_controller_libraries).
"""

from __future__ import annotations

import importlib
import importlib.metadata
import logging
from collections.abc import Callable
from typing import TypeVar

from twil_control.errors import TwilControlError

from .controller_interface import Controller

ENTRY_POINT_GROUP = "twil_control.controllers"
BASE_CLASS = "controller_interface::ControllerBase"
_BUILTIN_MODULE = "twil_control.ros_control.controllers"

log = logging.getLogger("twil_control.ros_control.registry")
C = TypeVar("C", bound=type)


class ControllerTypeError(TwilControlError, KeyError):
    """An unknown controller type, or an entry point that does not give a Controller class."""


_registered: dict[str, type[Controller]] = {}
_entry_points: dict[str, importlib.metadata.EntryPoint] | None = None
_builtins_loaded = False
_loaded_from_entry_points: set[str] = set()


def register(type_name: str, cls: type[Controller]) -> type[Controller]:
    """Register `cls` under `type_name` ("package/Class"); registering it again is a no-op."""
    if not (isinstance(cls, type) and issubclass(cls, Controller)):
        raise ControllerTypeError(f"cannot register {cls!r} as '{type_name}': not a Controller subclass")
    if "/" not in type_name:
        raise ControllerTypeError(f"controller type '{type_name}' is not of the form package/Class")
    existing = _registered.get(type_name)
    if existing is not None and existing is not cls:
        raise ControllerTypeError(
            f"controller type '{type_name}' is already registered to {existing.__module__}.{existing.__qualname__}"
        )
    _registered[type_name] = cls
    return cls


def controller_type(type_name: str) -> Callable[[C], C]:
    """Class decorator: ``@controller_type("effort_controllers/JointEffortController")``."""

    def decorate(cls: C) -> C:
        register(type_name, cls)
        return cls

    return decorate


def _ensure_builtins() -> None:
    global _builtins_loaded
    if not _builtins_loaded:
        _builtins_loaded = True
        importlib.import_module(_BUILTIN_MODULE)


def _discover() -> dict[str, importlib.metadata.EntryPoint]:
    global _entry_points
    if _entry_points is None:
        found: dict[str, importlib.metadata.EntryPoint] = {}
        eps = importlib.metadata.entry_points(group=ENTRY_POINT_GROUP)
        for ep in sorted(eps, key=lambda e: (e.name, e.value)):
            if ep.name in found:
                log.warning(
                    "controller type '%s' is declared twice by entry points (%s and %s); using %s",
                    ep.name,
                    found[ep.name].value,
                    ep.value,
                    found[ep.name].value,
                )
                continue
            found[ep.name] = ep
        _entry_points = found
    return _entry_points


def types() -> list[str]:
    """Every known type name, sorted (list_controller_types)."""
    _ensure_builtins()
    return sorted(set(_registered) | set(_discover()))


def get(type_name: str) -> type[Controller]:
    """The class of a controller type; unknown types raise ControllerTypeError listing the known ones."""
    _ensure_builtins()
    cls = _registered.get(type_name)
    if cls is not None:
        return cls
    ep = _discover().get(type_name)
    if ep is None:
        raise ControllerTypeError(
            f"controller type '{type_name}' does not exist; known types: {', '.join(types())} "
            f"(plugins register with the entry point group '{ENTRY_POINT_GROUP}')"
        )
    try:
        cls = ep.load()
    except Exception as error:
        raise ControllerTypeError(
            f"could not load controller type '{type_name}' from entry point '{ep.value}': "
            f"{type(error).__name__}: {error}"
        ) from error
    if not (isinstance(cls, type) and issubclass(cls, Controller)):
        raise ControllerTypeError(
            f"entry point '{type_name} = {ep.value}' does not name a subclass of "
            f"twil_control.ros_control.controller_interface.Controller"
        )
    _registered[type_name] = cls
    _loaded_from_entry_points.add(type_name)
    return cls


def reload() -> None:
    """Forget entry-point types (loaded or not) and scan the entry points again."""
    global _entry_points
    for name in _loaded_from_entry_points:
        _registered.pop(name, None)
    _loaded_from_entry_points.clear()
    _entry_points = None
