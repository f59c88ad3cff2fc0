"""One launch file read into the element tree the loader walks, and the args it declares.

An XML file (``.launch``, ``.xml``) is read by xml_reader.py into the tree a YAML file is: a
mapping whose single key ``launch`` holds the list of elements.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from twil_control.core.yaml_io import Lines, YamlError, display_path, load_yaml_with_lines
from twil_control.launch.formats import format_of
from twil_control.launch.plan import LaunchError
from twil_control.launch.scope import kind
from twil_control.launch.xml_reader import XmlLaunchError, read_xml_launch


@dataclass(frozen=True)
class ArgDecl:
    """An ``arg`` element as written (before substitution), for ``--ros-args`` style help."""

    name: str
    line: int
    default: Any = None
    value: Any = None
    doc: str = ""


def read_launch(path: Path, included_from: str | None) -> tuple[dict, Lines, dict]:
    """Read a launch file into the element tree: ``{"launch": [...]}``, its lines, and its
    columns (XML only)."""
    label = display_path(path)
    suffix = f" (included from {included_from})" if included_from else ""
    if format_of(path).params_are_strings:
        try:
            return read_xml_launch(path)
        except XmlLaunchError as exc:
            raise LaunchError(f"{exc}{suffix}") from None
    try:
        data, lines = load_yaml_with_lines(path)
    except YamlError as exc:
        raise LaunchError(f"{exc}{suffix}") from None
    if not isinstance(data, dict) or "launch" not in data:
        got = (
            "an empty file"
            if data is None
            else (f"keys {', '.join(map(str, data))}" if isinstance(data, dict) else kind(data))
        )
        raise LaunchError(
            f"{label}:1: a launch file is a mapping with the key 'launch' "
            f"holding a list of elements, got {got}{suffix}"
        )
    for key in data:
        if key != "launch":
            raise LaunchError(
                f"{label}:{lines.get((key,), 1)}: unknown top-level key "
                f"{key!r}; a launch file has the single key 'launch'"
            )
    return data, lines, {}


def declarations(items: Any, path: tuple, lines: Lines) -> dict[str, ArgDecl]:
    """Every ``arg`` in a file as written, groups included (conditions ignored)."""
    found: dict[str, ArgDecl] = {}
    for i, entry in enumerate(items if isinstance(items, list) else []):
        if not isinstance(entry, dict) or len(entry) != 1:
            continue
        ((element, body),) = entry.items()
        if not isinstance(body, dict):
            continue
        here = path + (i, element)
        if element == "arg" and isinstance(body.get("name"), str):
            found.setdefault(
                body["name"],
                ArgDecl(
                    body["name"],
                    lines.get(here, 1),
                    body.get("default"),
                    body.get("value"),
                    str(body.get("doc") or ""),
                ),
            )
        elif element == "group":
            for name, decl in declarations(body.get("children"), here + ("children",), lines).items():
                found.setdefault(name, decl)
    return found
