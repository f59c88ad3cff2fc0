"""roslaunch's loader, for launch files in roslaunch XML or in this project's YAML.

A YAML launch file mirrors roslaunch XML element for element::

    launch:
      - arg: {name: world, default: "$(find twil_control)/sim/worlds/default.sdf"}
      - param: {name: /use_sim_time, value: true}
      - rosparam: {file: config/twil.yaml, ns: /twil/ros_control}
      - group:
          ns: twil
          if: $(arg use_arm)
          children:
            - remap: {from: cmd_vel, to: /qbot/cmd_vel}
            - node: {pkg: controller_manager, type: spawner, name: spawner,
                     args: "joint_state_controller", params: {publish_rate: 100}}
      - include: {file: launch/other.launch.yaml, ns: other, args: {world: $(arg world)}}
      - record: {topics: [/joint_states, /tf], format: mcap, compression: zstd}

and an XML file (``.launch``, ``.xml``) is read into that same tree (xml_reader.py); both
are loaded with roslaunch's rules, one module per part: launch_file.py reads a file;
scoping.py walks files, includes and groups with the args each sees (``if``/``unless`` work on
every element); param_elements.py sets ``param`` and ``rosparam`` values, typed as roslaunch
types them; node_element.py builds the nodes with their remaps; recording.py reads what the
launch records (YAML's ``record`` element, or a ``rosbag/record`` node); scope.py reads
every value in its scope, and locates every message.

Several files load into one plan, as ``roslaunch a.launch b.launch`` does: in the order given,
with one namespace of node names (two nodes of one name are an error naming both files) and
one parameter server; a command-line arg goes to every file that declares it.

Where the formats differ (features accepted with a warning, how values are typed) is
formats.py. Both differ from roslaunch to catch mistakes it lets through: unknown elements
and attributes are errors (with did-you-mean), command-line args the file does not declare
are errors, and an arg declared with neither value nor default must be given. Relative
``file`` paths are looked up in the working directory (as roslaunch does), then next to the
launch file, then in the package root (core/paths.py).
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
