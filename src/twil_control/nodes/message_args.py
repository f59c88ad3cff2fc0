"""Messages from ROS's YAML command-line syntax, as ``rostopic pub`` fills them (genpy's
fill_message_args, http://wiki.ros.org/ROS/YAMLCommandLine).

The args are YAML values, one per command-line word. A single mapping sets fields by name
(fields left out are zero); otherwise the values fill every field in order, and a list does
the same for a nested message. A time field takes ``now`` (the publish time), an integer of
nanoseconds, ``{secs: S, nsecs: N}`` or ``[S, N]``; a std_msgs/Header field takes ``auto``
(stamped now). An empty value (``{data: }``) is an empty string. The result is the mapping of
fields that timed_pub.build_message checks and turns into a message.
"""

from __future__ import annotations

from typing import Any

from ..core import messages
from ..core.messages import msg_class, typestore
from ..core.ros_node import NodeArgsError
from ..errors import TwilControlError

TIME = "builtin_interfaces/msg/Time"
DURATION = "builtin_interfaces/msg/Duration"
HEADER = "std_msgs/msg/Header"
#: rosbags' stand-in field of a message without fields (std_msgs/Empty)
_PLACEHOLDER = "structure_needs_at_least_one_member"


def displays_only(node, tool: str, action: str, does: str, displays: tuple[str, ...]) -> bool:
    """Whether `node`'s command line (``tool`` ``args``) only displays (rostopic echo, rosservice
    list: nothing to do in a headless run); a command that is neither `action` nor one of
    `displays` is an error naming them."""
    command = node.args[0] if node.args else ""
    if command in displays:
        return True
    if command != action:
        raise NodeArgsError(
            f"node {node.fqn}: {tool} {command or '(no command)'}: the commands are {action}, which "
            f"{does}, and {', '.join(displays)}, which only display"
        )
    return False


class MessageArgsError(TwilControlError, ValueError):
    """Command-line values that do not fill the message type (the message names the field)."""


def _fields(full: str) -> list[tuple[str, Any]]:
    if full not in typestore().fielddefs:
        msg_class(full)  # raises the MessageTypeError with its advice
    return [(name, spec) for name, spec in typestore().fielddefs[full][1] if name != _PLACEHOLDER]


def command_line_fields(typename: str, args: list, now: float) -> dict:
    """The fields of a ``typename`` message given ``args`` (YAML values) at time ``now``."""
    full = messages.full_type_name(typename)
    value = args[0] if len(args) == 1 and isinstance(args[0], dict) else list(args)
    return _fill(full, value, now, "")


def _fill(full: str, value: Any, now: float, where: str) -> dict:
    fields = _fields(full)
    names = [name for name, _ in fields]
    shown = messages.ros1_type_name(full)
    if isinstance(value, dict):
        unknown = [key for key in value if key not in names]
        if unknown:
            raise MessageArgsError(
                f"{_at(where)}no field {unknown[0]!r} in {shown}; its fields: {', '.join(names) or 'none'}"
            )
        given = list(value.items())
    elif isinstance(value, list):
        if len(value) != len(names):
            few = "not enough" if len(value) < len(names) else "too many"
            raise MessageArgsError(
                f"{_at(where)}{few} values for {shown}: {len(value)} given, {len(names)} expected "
                f"({', '.join(names) or 'none'}), or give a mapping of fields"
            )
        given = list(zip(names, value))
    else:
        raise MessageArgsError(
            f"{_at(where)}a {shown} is a mapping of its fields or a list of their values, got {value!r}"
        )
    specs = dict(fields)
    out = {}
    for name, item in given:
        here = f"{where}.{name}" if where else name
        item = "" if item is None else item
        nodetype, details = specs[name]
        kind = int(nodetype)
        if kind == 2:  # a nested message
            out[name] = _message(details, item, now, here)
        elif kind in (3, 4):  # a fixed-length array or a sequence
            (sub_type, sub_details), _ = details
            if not isinstance(item, list):
                raise MessageArgsError(f"{here}: expected a list, got {item!r}")
            if int(sub_type) == 2:
                out[name] = [_message(sub_details, el, now, f"{here}[{i}]") for i, el in enumerate(item)]
            else:
                out[name] = item
        else:
            out[name] = item
    return out


def _at(where: str) -> str:
    return f"{where}: " if where else ""


def _message(full: str, value: Any, now: float, where: str) -> dict:
    if full in (TIME, DURATION):
        return _time(full, value, now, where)
    if isinstance(value, str):
        if value == "auto" and full == HEADER:
            return {"stamp": _time(TIME, "now", now, where)}
        keywords = "'auto'" if full == HEADER else "none"
        raise MessageArgsError(
            f"{where}: {value!r} is not a {messages.ros1_type_name(full)} (keywords it takes: {keywords})"
        )
    return _fill(full, value, now, where)


def _time(full: str, value: Any, now: float, where: str) -> dict:
    """{sec, nanosec} of a time or duration given as ROS's command line gives it."""
    ns = None
    if value == "now" and full == TIME:
        ns = int(round(now * 1e9))
    elif isinstance(value, int) and not isinstance(value, bool):
        ns = value
    elif isinstance(value, dict) and value and set(value) <= {"secs", "nsecs"}:
        secs, nsecs = value.get("secs", 0), value.get("nsecs", 0)
        if all(isinstance(v, int) and not isinstance(v, bool) for v in (secs, nsecs)):
            ns = secs * 1_000_000_000 + nsecs
    elif isinstance(value, list) and len(value) == 2 and all(type(v) is int for v in value):
        ns = value[0] * 1_000_000_000 + value[1]
    if ns is None:
        now_word = "'now', " if full == TIME else ""
        raise MessageArgsError(
            f"{where}: {value!r} is not a {'time' if full == TIME else 'duration'}; give {now_word}"
            f"integer nanoseconds, {{secs: S, nsecs: N}} or [S, N]"
        )
    return {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}
