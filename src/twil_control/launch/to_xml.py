"""Write a YAML launch file as roslaunch XML that loads into the same launch plan.

    python -m twil_control.launch.to_xml launch/qbot_sim.launch.yaml > launch/qbot_sim.launch

The XML twin has the same args, params (with their types), nodes, remaps, includes (of the
included files' XML twins) and recording (a ``rosbag record`` node); the YAML file's comments
stay in the YAML file, which the twin names. tests/test_launch_xml_twins.py keeps the
shipped twins equal to their YAML files.
"""

from __future__ import annotations

import argparse
import shlex
import sys
from pathlib import Path
from typing import Any
from xml.sax.saxutils import escape, quoteattr

import yaml

from twil_control.core.yaml_io import load_yaml
from twil_control.errors import InputError
from twil_control.launch.substitutions import auto_type, has_substitution

from ..errors import exit_on_error

INDENT = "  "


def twin_name(path: str) -> str:
    """``x.launch.yaml`` -> ``x.launch`` (an include's file, or an output name)."""
    return path[: -len(".yaml")] if path.endswith(".launch.yaml") else path


def convert(path: Path) -> str:
    """The XML text of the YAML launch file at ``path``."""
    data = load_yaml(path)
    out = [
        '<?xml version="1.0"?>',
        f"<!-- The roslaunch XML twin of {path.name}, generated from it by\n"
        f"     python -m twil_control.launch.to_xml: see that file for what this launch does;\n"
        f"     its commands and args run this file the same way. -->",
        "<launch>",
    ]
    _elements(data["launch"], 1, out)
    out.append("</launch>")
    return "\n".join(out) + "\n"


def _attrs(body: dict, keys: tuple[str, ...]) -> str:
    return "".join(f" {key}={quoteattr(_text(body[key]))}" for key in keys if key in body)


def _text(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)


_CONDITIONS = ("if", "unless")


def _elements(items: list, depth: int, out: list[str]) -> None:
    pad = INDENT * depth
    for entry in items:
        ((element, body),) = entry.items()
        body = body or {}
        cond = _attrs(body, _CONDITIONS)
        if element == "arg":
            out.append(f"{pad}<arg{_attrs(body, ('name', 'default', 'value', 'doc'))}{cond}/>")
        elif element == "param":
            out.append(pad + _param(body["name"], body, cond))
        elif element == "rosparam":
            out.append(pad + _rosparam(body, cond, pad))
        elif element == "remap":
            out.append(f"{pad}<remap{_attrs(body, ('from', 'to'))}{cond}/>")
        elif element == "group":
            out.append(f"{pad}<group{_attrs(body, ('ns', 'clear_params'))}{cond}>")
            _elements(body.get("children") or [], depth + 1, out)
            out.append(f"{pad}</group>")
        elif element == "node":
            _node(body, cond, depth, out)
        elif element == "include":
            file = {"file": twin_name(str(body["file"]))}
            attrs = _attrs(file, ("file",)) + _attrs(body, ("ns", "clear_params", "pass_all_args"))
            args = body.get("args") or {}
            if not args:
                out.append(f"{pad}<include{attrs}{cond}/>")
                continue
            out.append(f"{pad}<include{attrs}{cond}>")
            for name, value in args.items():
                out.append(f"{pad}{INDENT}<arg name={quoteattr(str(name))} value={quoteattr(_text(value))}/>")
            out.append(f"{pad}</include>")
        elif element == "record":
            if "format" in body or "compression" in body:
                raise InputError(
                    "a record's format and compression have no roslaunch XML form "
                    "(rosbag record writes bags): give --bag-format on the command line"
                )
            topics = " ".join(str(t) for t in body["topics"])
            out.append(
                f'{pad}<node pkg="rosbag" type="record" name="record" args={quoteattr(topics)}{cond}/>'
            )
        else:
            raise InputError(f"no XML form for element {element!r}")


def _param(name: str, body: dict, cond: str = "") -> str:
    """One <param>, typed so that roslaunch's typing of the XML string gives the YAML value."""
    if "value" not in body:  # textfile or command: a string either way
        return f"<param name={quoteattr(name)}{_attrs(body, ('textfile', 'command', 'type'))}{cond}/>"
    value, ptype = body["value"], body.get("type")
    if ptype is None and not has_substitution(value):
        ptype = _type_for(value)
    if isinstance(value, (dict, list)):
        value = yaml.safe_dump(value, default_flow_style=True, width=10_000).strip()
    type_attr = f" type={quoteattr(ptype)}" if ptype else ""
    return f"<param name={quoteattr(name)} value={quoteattr(_text(value))}{type_attr}{cond}/>"


def _type_for(value: Any) -> str | None:
    """The type attribute that keeps a YAML value's type through roslaunch's inference."""
    if isinstance(value, (dict, list)):
        return "yaml"
    inferred = auto_type(_text(value))
    if type(inferred) is type(value) and inferred == value:
        return None
    return {str: "str", int: "int", float: "double", bool: "bool"}[type(value)]


def _rosparam(body: dict, cond: str, pad: str) -> str:
    attrs = _attrs(body, ("command", "file", "param", "ns", "subst_value")) + cond
    if "value" not in body:
        return f"<rosparam{attrs}/>"
    text = yaml.safe_dump(body["value"], default_flow_style=False, sort_keys=False).rstrip()
    inner = "\n".join(pad + INDENT + line for line in text.splitlines())
    return f"<rosparam{attrs}>\n{escape(inner)}\n{pad}</rosparam>"


def _flatten(params: dict, prefix: str = "") -> list[tuple[str, Any]]:
    """A node's nested params as (relative name, scalar or list) pairs."""
    flat = []
    for key, value in params.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            flat.extend(_flatten(value, name + "/"))
        else:
            flat.append((name, value))
    return flat


def _node(body: dict, cond: str, depth: int, out: list[str]) -> None:
    pad, inner = INDENT * depth, INDENT * (depth + 1)
    node = dict(body)
    if isinstance(node.get("args"), list):
        node["args"] = shlex.join(str(a) for a in node["args"])
    attrs = (
        _attrs(
            node,
            (
                "pkg",
                "type",
                "name",
                "ns",
                "args",
                "required",
                "respawn",
                "respawn_delay",
                "output",
                "clear_params",
            ),
        )
        + cond
    )
    children = []
    rosparams = node.get("rosparam") or []
    for entry in [rosparams] if isinstance(rosparams, dict) else rosparams:
        children.append(inner + _rosparam(entry, _attrs(entry, _CONDITIONS), inner))
    for name, value in _flatten(node.get("params") or {}):
        children.append(inner + _param(name, {"value": value}))
    remaps = node.get("remap") or []
    if isinstance(remaps, dict):
        remaps = [{"from": key, "to": value} for key, value in remaps.items()]
    for remap in remaps:
        children.append(f"{inner}<remap{_attrs(remap, ('from', 'to', 'if', 'unless'))}/>")
    if not children:
        out.append(f"{pad}<node{attrs}/>")
        return
    out.append(f"{pad}<node{attrs}>")
    out.extend(children)
    out.append(f"{pad}</node>")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m twil_control.launch.to_xml", description=(__doc__ or "").split("\n", 1)[0]
    )
    parser.add_argument("files", nargs="+", type=Path, help="YAML launch files")
    parser.add_argument(
        "--write",
        action="store_true",
        help="write each twin beside its YAML file (x.launch.yaml -> x.launch)",
    )
    opts = parser.parse_args(argv)
    return exit_on_error(lambda: _convert_all(opts))


def _convert_all(opts: argparse.Namespace) -> int:
    for path in opts.files:
        text = convert(path)
        if opts.write:
            Path(twin_name(str(path))).write_text(text, encoding="utf-8")
        else:
            sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
