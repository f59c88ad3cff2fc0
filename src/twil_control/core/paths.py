"""Where a file named by the user is looked for: one rule for every input path.

A path given on the command line, in a launch file or in a node parameter (a launch file, an
included file, a rosparam file, a world, a robot description, a map, a message sequence, a
reference program, a sweep's launch file) is, when relative, looked up

1. in the working directory (what a shell user expects: tab completion wrote it from there,
   and roslaunch reads relative rosparam paths from there too);
2. then in the package root (``$(find twil_control)``), so that ``config/twil.yaml`` or
   ``sim/worlds/house.sdf`` work from any directory.

``~`` is expanded. When neither holds the file, the error names every place tried. Paths
inside data files keep their format's own base (a map YAML's image is next to the YAML, as
map_server reads it).
"""
from __future__ import annotations

import os
from pathlib import Path

from twil_control import PACKAGE_ROOT


class InputPathError(FileNotFoundError):
    """A file the user named that is not where the rule looks."""

    def __str__(self) -> str:  # FileNotFoundError would print "[Errno ...]" around it
        return str(self.args[0])


def candidates(value: str | os.PathLike) -> list[Path]:
    """The places the rule looks for `value`, in order."""
    given = Path(value).expanduser()
    if given.is_absolute():
        return [given]
    here = Path.cwd() / given
    return [here] if Path.cwd() == PACKAGE_ROOT else [here, PACKAGE_ROOT / given]


def find_file(value: str | os.PathLike, what: str = "file") -> Path:
    """The first existing regular file among `candidates(value)` (absolute); InputPathError
    naming `what`, the value and every place tried when there is none."""
    tried = candidates(value)
    for path in tried:
        if path.is_file():
            return path
    if Path(value).expanduser().is_absolute():
        where = " (it is not a file)" if tried[0].exists() else ""
        raise InputPathError(f"{what} not found: {value}{where}")
    places = " and ".join(str(p) for p in tried)
    raise InputPathError(f"{what} not found: {value} (tried {places}: a relative path is looked "
                         f"up in the working directory, then in the package root)")
