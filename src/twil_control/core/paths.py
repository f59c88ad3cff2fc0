"""Where a file named by the user is looked for: one rule for every input path.

A relative path is looked up in the working directory (what a shell user expects, and where
roslaunch reads relative rosparam paths), then, for a path written in a launch file, next to that
file (so a user's launch file finds its own files wherever it is started from), then in the
package root. The error names every place tried. Paths inside data files keep their format's own
base (docs/inputs.md).
"""

from __future__ import annotations

import os
from pathlib import Path

from twil_control import PACKAGE_ROOT
from twil_control.errors import TwilControlError


class InputPathError(TwilControlError, FileNotFoundError):
    """A file the user named that is not where the rule looks."""


def candidates(value: str | os.PathLike, near: Path | None = None) -> list[Path]:
    """The places the rule looks for `value`, in order; `near` is the directory of the launch
    file that names it, if any."""
    given = Path(value).expanduser()
    if given.is_absolute():
        return [given]
    bases = [Path.cwd()] + ([near.absolute()] if near is not None else []) + [PACKAGE_ROOT]
    return [base / given for base in dict.fromkeys(bases)]


def find_file(value: str | os.PathLike, what: str = "file", near: Path | None = None) -> Path:
    """The first existing regular file among `candidates(value, near)` (absolute);
    InputPathError naming `what`, the value and every place tried when there is none."""
    tried = candidates(value, near)
    for path in tried:
        if path.is_file():
            return path
    if Path(value).expanduser().is_absolute():
        where = " (it is not a file)" if tried[0].exists() else ""
        raise InputPathError(f"{what} not found: {value}{where}")
    places = ", ".join(str(p) for p in tried)
    near_note = ", then next to the launch file" if near is not None else ""
    raise InputPathError(
        f"{what} not found: {value} (tried {places}: a relative path is looked "
        f"up in the working directory{near_note}, then in the package root)"
    )
