"""roslaunch's loader, for launch files in roslaunch XML or in this project's YAML (its format:
docs/launch_files.md). An XML file is read into the same tree (xml_reader.py).

One module per part: launch_file.py reads a file; scoping.py walks files, includes and groups
with the args each sees; param_elements.py sets ``param`` and ``rosparam`` values; node_element.py
builds the nodes with their remaps; recording.py reads what the launch records; scope.py reads
values and locates messages. Several files load into one plan, as ``roslaunch a.launch
b.launch`` does. Unlike roslaunch, unknown elements, attributes and command-line args are
errors, to catch the mistakes it lets through (formats.py, core/paths.py for relative files).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from pathlib import Path

from twil_control.core.paths import InputPathError, find_file
from twil_control.core.yaml_io import display_path
from twil_control.launch.launch_file import ArgDecl, declarations, read_launch
from twil_control.launch.node_element import NodeElements
from twil_control.launch.plan import LaunchError, LaunchPlan


class _Loader(NodeElements):
    """The whole loader: NodeElements derives from the other elements' handlers
    (ParamElements, RecordElements), which derive from ScopedLoader and ScopeValues."""


def load_launch(
    path: str | Path | Sequence[str | Path], arg_overrides: dict[str, str] | None = None
) -> LaunchPlan:
    """Load one launch file (YAML or roslaunch XML), or several into one plan, with everything
    they include, into a LaunchPlan.

    ``arg_overrides`` are the command line's ``name:=value`` args; with several files each goes
    to every file that declares it, and one that no file declares is an error. A relative
    path is looked up in the current directory, then in the package root.
    """
    paths = [path] if isinstance(path, (str, Path)) else list(path)
    if not paths:
        raise LaunchError("no launch file given")
    overrides = dict(arg_overrides or {})
    for name, value in overrides.items():
        if not isinstance(value, str):
            raise LaunchError(f"arg {name!r}: command-line values are strings, got {value!r}")
    files = [_launch_path(p) for p in paths]
    passed = _args_per_file(files, overrides) if len(files) > 1 else [overrides]
    loader = _Loader()
    for file, args in zip(files, passed):
        loader.load_file(file, ns="/", passed=args, inherited={}, parent=None, chain=(), included_from=None)
    record = None if loader.record_all else loader.record
    return LaunchPlan(
        args=loader.top_args,
        params=loader.params,
        nodes=loader.nodes,
        record_topics=record,
        record_format=loader.record_format,
        record_compression=loader.record_compression,
        record_output=loader.record_output,
        files=loader.files,
    )


def _args_per_file(files: list[Path], overrides: dict[str, str]) -> list[dict[str, str]]:
    """The command-line args each of several files declares; an arg none declares is an error
    listing what each file declares."""
    declared = [set(declared_args(file)) for file in files]
    unknown = [name for name in overrides if not any(name in names for names in declared)]
    if unknown:
        quoted = ", ".join(repr(name) for name in unknown)
        listed = "; ".join(
            f"{display_path(file)}: {', '.join(sorted(names)) or 'none'}"
            for file, names in zip(files, declared)
        )
        plural, them = ("s", "them") if len(unknown) > 1 else ("", "it")
        raise LaunchError(
            f"unknown arg{plural} {quoted}: no file of this launch declares {them}; declared args: {listed}"
        )
    return [{name: value for name, value in overrides.items() if name in names} for names in declared]


def parse_cli_args(argv: Iterable[str]) -> dict[str, str]:
    """Split roslaunch-style ``name:=value`` tokens into a dict (later tokens win)."""
    args: dict[str, str] = {}
    for token in argv:
        name, sep, value = token.partition(":=")
        if not sep or not name or any(ch.isspace() or ch == "=" for ch in name):
            raise LaunchError(
                f"malformed launch argument {token!r}: expected the form "
                f"name:=value (for example world:=sim/worlds/default.sdf)"
            )
        args[name] = value
    return args


def declared_args(path: str | Path) -> dict[str, ArgDecl]:
    """The args a launch file declares (at any group depth), as written."""
    launch_path = _launch_path(path)
    data, lines, _ = read_launch(launch_path, included_from=None)
    return declarations(data["launch"], ("launch",), lines)


def _launch_path(path: str | Path) -> Path:
    """A launch file on the command line, found by core.paths' rule."""
    try:
        return find_file(path, "launch file")
    except InputPathError as exc:
        raise LaunchError(str(exc)) from None
