"""Package discovery (rospack's role): where ``$(find pkg)``, ``package://pkg/...`` and
``model://name/...`` point.

The search path is ``--package-path``, ``ROS_PACKAGE_PATH``, this project, then the packages it
provides in place of ROS's (:data:`PROVIDED`), last so that a user's own package of that name
wins; directories are crawled for ``package.xml`` as rospack crawls them, and the first package
of a name wins. ``$(find xacro)`` names the installed Python xacro (docs/runtime.md).
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterable
from pathlib import Path

from twil_control import PACKAGE_ROOT
from twil_control.errors import TwilControlError

__all__ = ["PackageNotFoundError", "all_packages", "find", "resolve_url", "search_path", "set_extra_paths"]

#: Packages provided in place of ROS's, searched after every other folder.
PROVIDED = Path(__file__).resolve().parents[1] / "share"

_IGNORE_MARKERS = ("CATKIN_IGNORE", "rospack_nosubdirs", "AMENT_IGNORE", "COLCON_IGNORE")
_NAME_TAG = re.compile(r"<name>\s*([^<\s]+)\s*</name>")

_extra: list[Path] = []
_cache: dict[tuple, dict[str, Path]] = {}


class PackageNotFoundError(TwilControlError, LookupError):
    """A package (or a package:// / model:// file) that the search path does not hold."""


def set_extra_paths(paths: Iterable[str | Path]) -> None:
    """The ``--package-path`` directories, searched before ``ROS_PACKAGE_PATH``."""
    _extra[:] = [Path(p).expanduser().absolute() for p in paths]


def extra_paths() -> list[Path]:
    return list(_extra)


def search_path(environ: dict | None = None) -> list[Path]:
    """The directories crawled for packages, in priority order."""
    env = os.environ if environ is None else environ
    ros = [
        Path(p).expanduser().absolute()
        for p in env.get("ROS_PACKAGE_PATH", "").split(os.pathsep)
        if p.strip()
    ]
    paths = []
    for p in [*_extra, *ros, PACKAGE_ROOT, PROVIDED]:
        if p not in paths:
            paths.append(p)
    return paths


def _package_name(manifest: Path) -> str:
    try:
        text = manifest.read_text(encoding="utf-8", errors="replace")
    except OSError:
        return manifest.parent.name
    match = _NAME_TAG.search(text)
    return match.group(1) if match else manifest.parent.name


def _crawl(root: Path, found: dict[str, Path]) -> None:
    if not root.is_dir():
        return
    if (root / "package.xml").is_file():
        found.setdefault(_package_name(root / "package.xml"), root)
        return
    if any((root / marker).exists() for marker in _IGNORE_MARKERS):
        return
    try:
        children = sorted(p for p in root.iterdir() if p.is_dir() and not p.name.startswith("."))
    except OSError:
        return
    for child in children:
        _crawl(child, found)


def all_packages(environ: dict | None = None) -> dict[str, Path]:
    """Every package on the search path: name -> folder (the first of a name wins)."""
    paths = tuple(search_path(environ))
    if paths not in _cache:
        found: dict[str, Path] = {}
        for root in paths:
            _crawl(root, found)
        _cache[paths] = found
    return _cache[paths]


def _searched(environ: dict | None = None) -> str:
    return ", ".join(str(p) for p in search_path(environ))


def find(name: str, environ: dict | None = None) -> Path:
    """The folder of package ``name`` (``$(find name)``); PackageNotFoundError names the paths
    searched and how to add one."""
    packages = all_packages(environ)
    if name in packages:
        return packages[name]
    if name == "xacro":
        import xacro  # the registry's xacro, run in-process by the launch loader

        return Path(xacro.__file__).parent
    raise PackageNotFoundError(
        f"package {name!r} not found; searched (--package-path, then ROS_PACKAGE_PATH, then this "
        f"project and the packages it provides): {_searched(environ)}; add the folder holding it with --package-path DIR or "
        f"ROS_PACKAGE_PATH"
    )


def resolve_url(url: str, relative_to: Path | None = None, environ: dict | None = None) -> Path:
    """The file a description names: ``package://pkg/rest``, ``model://name/rest``,
    ``file:///abs`` or a path (relative paths from ``relative_to``). The file must exist."""
    if url.startswith("package://"):
        package, _, rest = url[len("package://") :].partition("/")
        path = find(package, environ) / rest
    elif url.startswith("model://"):
        from .gazebo_paths import find_model  # it reads the packages found here

        model, _, rest = url[len("model://") :].partition("/")
        path = find_model(model, environ) / rest
    elif url.startswith("file://"):
        path = Path(url[len("file://") :])
    else:
        path = Path(url).expanduser()
        if not path.is_absolute() and relative_to is not None:
            path = relative_to / path
    if not path.is_file():
        raise PackageNotFoundError(f"{url}: file not found ({path})")
    return path
