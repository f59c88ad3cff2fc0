"""The launch command's words as roslaunch reads them: ``name:=value`` anywhere on the line, and
the launch files named as ``PACKAGE FILE [FILE ...]`` or ``FILE [FILE ...]``.

roslaunch's rule (rlutil.resolve_launch_arguments): with two words or more, the first is tried
as a package and the second as a file in it: a path inside the package, else the one file of
that name anywhere in its folders (two of one name are an error listing them). The words after
it, or all of them when the first is no such package, are launch files, each found by
core.paths' rule (the working directory, then this package's root).
"""

from __future__ import annotations

import os
import re
from pathlib import Path

from twil_control.core import packages
from twil_control.launch.plan import LaunchError

#: what a ROS package name can be (REP 144, loosened to the names rospack accepts)
_PACKAGE_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]*")
#: ``name=value``, a launch arg missing its ':'
_MALFORMED_ARG = re.compile(r"[A-Za-z_]\w*=.*")


def split_launch_args(argv: list[str]) -> tuple[list[str], list[str]]:
    """(the ``name:=value`` words, the other words), wherever the former stand on the line, as
    roslaunch takes them: before, between or after the files and options. A word with '=' that
    names no file (``world=x.sdf``) counts as a launch arg, so that it is refused as malformed
    rather than looked for as a launch file."""
    launch_args, rest = [], []
    for word in argv:
        is_arg = not word.startswith("-") and (
            ":=" in word or (_MALFORMED_ARG.fullmatch(word) is not None and not Path(word).exists())
        )
        (launch_args if is_arg else rest).append(word)
    return launch_args, rest


def launch_files(words: list[str]) -> list[str | Path]:
    """The launch files ``words`` name: a file in a package for ``PACKAGE FILE``, then the
    other words as they are (the loader finds them)."""
    if len(words) >= 2 and _PACKAGE_NAME.fullmatch(words[0]) and not Path(words[0]).is_file():
        try:
            folder = packages.find(words[0])
        except packages.PackageNotFoundError as error:
            raise LaunchError(f"{words[0]!r} is neither a launch file nor a package: {error}") from None
        return [in_package(words[0], folder, words[1]), *words[2:]]
    return list(words)


def in_package(package: str, folder: Path, name: str) -> Path:
    """The launch file ``name`` of ``package`` (in ``folder``), as roslaunch finds it."""
    direct = folder / name
    if direct.is_file():
        return direct
    found = []
    for root, dirs, files in os.walk(folder):
        dirs[:] = sorted(d for d in dirs if not d.startswith("."))
        if Path(name).name in files and (Path(root) / Path(name).name).match(name):
            found.append(Path(root) / Path(name).name)
    if len(found) > 1:
        listed = ", ".join(str(path) for path in found)
        raise LaunchError(
            f"{len(found)} files named {name!r} in package {package!r}: {listed}; give the path of one"
        )
    if not found:
        raise LaunchError(
            f"no launch file {name!r} in package {package!r} ({folder}), and {package!r} is not a launch file"
        )
    return found[0]
