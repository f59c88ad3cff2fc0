"""Where Gazebo looks for models and worlds (gzserver with gazebo_ros's paths plugin).

Model folders: ``GAZEBO_MODEL_PATH``, the packages' ``gazebo_model_path`` exports, then this
project's stock models; resource folders (worlds, media) likewise, with ``GAZEBO_RESOURCE_PATH``
and ``gazebo_media_path``. There is no online model database to fall back on, so a missing model
names every folder searched (docs/robots.md, "Worlds and SDF models").
"""

from __future__ import annotations

import os
import re
from pathlib import Path

from twil_control import PACKAGE_ROOT

from . import packages

__all__ = [
    "STOCK",
    "ModelNotFoundError",
    "WorldNotFoundError",
    "find_model",
    "model_folders",
    "resolve_world",
    "resource_folders",
]

#: Gazebo's stock worlds and models, as this project provides them.
STOCK: Path = Path(__file__).resolve().parents[1] / "share" / "gazebo"

_EXPORT = re.compile(r"<gazebo_ros\b([^>]*)/?>", re.S)
_ATTRIBUTE = re.compile(r"""(gazebo_model_path|gazebo_media_path)\s*=\s*["']([^"']*)["']""")


class ModelNotFoundError(packages.PackageNotFoundError):
    """A ``model://`` name that no model folder holds."""


class WorldNotFoundError(packages.PackageNotFoundError):
    """A world name that neither the working directory nor a resource folder holds."""


def _env_list(name: str, environ: dict | None) -> list[Path]:
    env = os.environ if environ is None else environ
    return [Path(p).expanduser().absolute() for p in env.get(name, "").split(os.pathsep) if p.strip()]


def package_exports(environ: dict | None = None) -> dict[str, list[Path]]:
    """``{"gazebo_model_path": [...], "gazebo_media_path": [...]}`` over every package, in the
    packages' search order."""
    found: dict[str, list[Path]] = {"gazebo_model_path": [], "gazebo_media_path": []}
    for folder in packages.all_packages(environ).values():
        try:
            text = (folder / "package.xml").read_text(encoding="utf-8", errors="replace")
        except OSError:
            continue
        for tag in _EXPORT.finditer(text):
            for key, value in _ATTRIBUTE.findall(tag.group(1)):
                path = Path(value.replace("${prefix}", str(folder))).expanduser()
                found[key].append(path if path.is_absolute() else folder / path)
    return found


def _unique(paths: list[Path]) -> list[Path]:
    return list(dict.fromkeys(paths))


def model_folders(environ: dict | None = None) -> list[Path]:
    """The folders model names are looked up in, in Gazebo's order (module docstring)."""
    exported = package_exports(environ)["gazebo_model_path"]
    return _unique([*_env_list("GAZEBO_MODEL_PATH", environ), *exported, STOCK / "models"])


def resource_folders(environ: dict | None = None) -> list[Path]:
    """The folders world names (and media) are looked up in, in Gazebo's order."""
    exported = package_exports(environ)["gazebo_media_path"]
    return _unique([*_env_list("GAZEBO_RESOURCE_PATH", environ), *exported, STOCK])


def find_model(name: str, environ: dict | None = None) -> Path:
    """The folder of model ``name`` (it holds ``model.config``); ModelNotFoundError names the
    model and every folder searched."""
    folders = model_folders(environ)
    for root in folders:
        if (root / name / "model.config").is_file():
            return root / name
    searched = ", ".join(str(f) for f in folders)
    raise ModelNotFoundError(
        f"model {name!r} not found: no folder {name}/ holding a model.config in {searched} "
        f"(GAZEBO_MODEL_PATH, then the gazebo_model_path exports of the ROS packages, then the stock "
        f"models); Gazebo's online model database is not reachable here, so every model must be "
        f"on disk: add its parent folder to GAZEBO_MODEL_PATH"
    )


def resolve_world(name: str | os.PathLike, environ: dict | None = None) -> Path:
    """The world file ``name`` names, as gzserver resolves it: as given (absolute, or from the
    working directory), then under each resource folder and its ``worlds/``, then the project
    root (``sim/worlds/house.sdf`` from anywhere). WorldNotFoundError names every place tried."""
    given = Path(name).expanduser()
    tried = [given if given.is_absolute() else Path.cwd() / given]
    if not given.is_absolute():
        for root in resource_folders(environ):
            tried += [root / given, root / "worlds" / given]
        tried.append(PACKAGE_ROOT / given)
    tried = _unique(tried)
    for path in tried:
        if path.exists() and not path.is_dir():  # a file, or a stream such as /dev/stdin
            return path
    raise WorldNotFoundError(
        f"world file not found: {name} (tried {', '.join(str(p) for p in tried)}: as given, then "
        f"under each GAZEBO_RESOURCE_PATH entry, each package's gazebo_media_path export and the "
        f"stock worlds, and their worlds/ folders)"
    )
