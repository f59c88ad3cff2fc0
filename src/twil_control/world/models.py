"""Robot and world descriptions shipped in sim/, and one loader for all of them (Drake only).

Every file loads offline: model directives refer to files as ``package://twil_control/...``,
and :func:`register_package` maps every package core.packages finds. The short names of
:data:`MODELS`, their frames, masses and the reasons for each choice: sim/README.md.
"""

from __future__ import annotations

from pathlib import Path

from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.parsing import LoadModelDirectives, Parser, ProcessModelDirectives
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import ModelInstanceIndex

from twil_control import PACKAGE_ROOT
from twil_control.core import packages
from twil_control.core.paths import InputPathError, find_file
from twil_control.core.yaml_io import YamlError
from twil_control.core.yaml_io import load_yaml as check_yaml
from twil_control.errors import TwilControlError

__all__ = [
    "MODELS",
    "ModelError",
    "PACKAGE_NAME",
    "REST_HEIGHT",
    "SIM_DIR",
    "add_model",
    "register_package",
    "resolve",
    "rest_height",
    "set_base_pose",
]

#: The ROS package name used in ``package://`` URLs.
PACKAGE_NAME = "twil_control"

#: Robot descriptions and worlds: ``$(find twil_control)/sim``.
SIM_DIR: Path = PACKAGE_ROOT / "sim"

#: Short model names -> description files.
MODELS: dict[str, Path] = {
    "twil": SIM_DIR / "robots" / "twil" / "twil.urdf",
    "wam": SIM_DIR / "robots" / "wam" / "wam.urdf",
    "wam_fixed": SIM_DIR / "robots" / "wam" / "wam_fixed.dmd.yaml",
    "twil_wam": SIM_DIR / "robots" / "twil_wam.dmd.yaml",
    "qbot": SIM_DIR / "robots" / "qbot" / "qbot.urdf",
    "default_world": SIM_DIR / "worlds" / "default.sdf",
}

#: Height of a mobile robot's ``base_link`` above the floor when it rests on its wheels, keyed by
#: the model instance name (the URDF's ``<robot name>``): the wheel radius for both robots, whose
#: base_link origins lie on the wheel axes' height. Spawning at z = 0 would sink the wheels.
REST_HEIGHT: dict[str, float] = {
    "twil": 0.075,
    "qbot": 0.055,
}


class ModelError(TwilControlError, ValueError):
    """A model file that does not exist or that Drake cannot parse."""


def register_package(parser: Parser) -> Parser:
    """Map every package of the search path (core.packages: ``--package-path``,
    ``ROS_PACKAGE_PATH`` and twil_control itself) in ``parser``'s package map; return it."""
    package_map = parser.package_map()
    for name, folder in packages.all_packages().items():
        if not package_map.Contains(name):
            package_map.Add(name, str(folder))
    return parser


def _known() -> str:
    return ", ".join(MODELS)


def resolve(name_or_path: str | Path, what: str = "model file") -> Path:
    """The file a short name (``"twil"``), a ``package://twil_control/...`` URL or a path names
    (a relative path: core.paths' rule, the working directory then the package root).

    Raises :class:`ModelError` when the file does not exist.
    """
    if isinstance(name_or_path, str) and name_or_path in MODELS:
        path = MODELS[name_or_path]
    elif isinstance(name_or_path, str) and name_or_path.startswith(("package://", "model://")):
        try:
            path = packages.resolve_url(name_or_path)
        except packages.PackageNotFoundError as error:
            raise ModelError(f"model file not found: {error}; known models: {_known()}") from None
    else:
        try:
            return find_file(name_or_path, what)
        except InputPathError as error:
            raise ModelError(f"{error}; known models: {_known()}") from None
    if not path.is_file():
        raise ModelError(f"model file not found: {path}; known models: {_known()}")
    return path


def add_model(
    plant: MultibodyPlant,
    name_or_path: str | Path,
    parser: Parser | None = None,
    model_name_prefix: str = "",
) -> list[ModelInstanceIndex]:
    """Add a URDF, SDF (robot or world) or model-directives file to ``plant`` (not finalized).

    ``name_or_path`` is a short name from :data:`MODELS`, a ``package://twil_control/...`` URL or
    a file path. ``parser`` (optional) is used as given, with the twil_control package
    registered; otherwise a new one is made with ``model_name_prefix`` (scoped name ``prefix::``,
    to add a second copy of a model). Returns the model instances added, in file order.

    Raises :class:`ModelError` naming the file when it is missing or fails to parse.
    """
    path = resolve(name_or_path)
    if parser is None:
        parser = Parser(plant, model_name_prefix) if model_name_prefix else Parser(plant)
    elif model_name_prefix:
        raise ModelError(f"{path}: give model_name_prefix or a parser, not both")
    register_package(parser)
    try:
        if path.name.endswith((".dmd.yaml", ".dmd.yml")):
            check_yaml(path)  # Drake's reader would expand an alias bomb; ours refuses it first
            directives = LoadModelDirectives(str(path))
            infos = ProcessModelDirectives(directives, parser)
            return [info.model_instance for info in infos]
        return list(parser.AddModels(str(path)))
    except RuntimeError as error:  # Drake's parser diagnostics
        raise ModelError(f"failed to parse model file {path}: {error}") from error
    except YamlError as error:
        raise ModelError(f"failed to parse model file {path}: {error}") from None


def rest_height(plant: MultibodyPlant, instance: ModelInstanceIndex) -> float:
    """Height of the instance's ``base_link`` above the floor at rest (0 if not a known robot)."""
    name = plant.GetModelInstanceName(instance).split("::")[-1]
    return REST_HEIGHT.get(name, 0.0)


def set_base_pose(
    plant: MultibodyPlant,
    instance: ModelInstanceIndex,
    x: float = 0.0,
    y: float = 0.0,
    yaw: float = 0.0,
    z: float | None = None,
    base_link: str = "base_link",
) -> RigidTransform:
    """Set the default pose of a free-floating ``base_link`` to (x, y, yaw), resting on z = 0.

    ``z`` defaults to :func:`rest_height`. Works before or after ``Finalize()``. Returns the pose.
    """
    body = plant.GetBodyByName(base_link, instance)
    if z is None:
        z = rest_height(plant, instance)
    pose = RigidTransform(RotationMatrix.MakeZRotation(yaw), [x, y, z])
    plant.SetDefaultFloatingBaseBodyPose(body, pose)
    return pose
