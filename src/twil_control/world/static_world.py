"""A world file's static models as anchored geometry (cheaper physics, the same scene).

Drake welds each link of a ``<static>`` model to the world with a body of its own, whose
kinematics every step computes; the same shapes registered on the world body give SceneGraph the
same scene with nothing to compute. Models are read a few hundred at a time (world/sdf_models.py);
three limits of Drake 1.51 are met here rather than as a crash: quadratic pair tables (the
proximity window), quadratic name checks (merged visuals) and meshes as hulls (mesh pieces), as
docs/inputs.md and docs/robots.md say. `AnchoredWorld.source` keeps each geometry's model and
link, so the contact monitor names what the robot touched.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from pydrake.geometry import (
    GeometryInstance,
    Mesh,
    PerceptionProperties,
    ProximityProperties,
    Rgba,
    SceneGraph,
)
from pydrake.math import RigidTransform
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import BodyIndex, ModelInstanceIndex

from ..core import gazebo_paths
from ..description.gazebo_world import Normalised, normalise
from ..description.urdf import DescriptionError
from . import models
from .extent import shape_box
from .merged_visuals import MERGE_ABOVE, MERGEABLE, merged_meshes
from .mesh_pieces import convex_pieces, convex_shapes, mesh_triangles
from .proximity_window import WindowedShape
from .sdf_models import MAX_COLLISION_GEOMETRIES, ModelText, SplitWorld, WorldScan, scan_world

log = logging.getLogger("twil_control.static_world")

#: Drake's colour for a visual whose description gives none
DEFAULT_DIFFUSE = Rgba(0.9, 0.9, 0.9, 1.0)

#: Static models per scratch plant: small enough that Drake's per-model cost (which grows with
#: the plant) stays small, large enough to spread the cost of a plant (the performance page).
PIECE_MODELS = 200

#: Files Drake reads as they are (no Gazebo world in them): URDF and model directives.
NOT_SDF = (".urdf", ".dmd.yaml", ".dmd.yml")


class WorldTooLargeError(models.ModelError):
    """A world with more collision geometries than SceneGraph's pair table can hold here."""


def load_world(world: str | Path | Normalised) -> Normalised | Path:
    """The world as Drake should read it: an SDF world (any suffix) normalised
    (description.gazebo_world), a URDF or model-directives file as its path. ModelError names
    the file when it is missing or cannot be read."""
    if isinstance(world, Normalised):
        return world
    try:
        file = models.resolve(world, "world file")
    except models.ModelError as error:
        try:  # a name as gzserver finds it (worlds/empty.world)
            file = gazebo_paths.resolve_world(world)
        except gazebo_paths.WorldNotFoundError:
            raise error from None
    if file.name.endswith(NOT_SDF):
        return file
    try:
        return normalise(file)
    except DescriptionError as error:
        raise models.ModelError(str(error)) from None


@dataclass
class StaticShape:
    """One geometry of a body welded to the world, posed in the world frame; plain copies that
    outlive the scratch plant it was read from."""

    model: str
    link: str
    name: str  # as the scratch plant names it (see scoped_name)
    X_WG: RigidTransform
    shape: object  # a pydrake Shape (owned copy)
    proximity: ProximityProperties | None  # a collision geometry's properties, or None
    diffuse: Rgba | None = None  # a visual's colour

    @property
    def scoped_name(self) -> str:
        """``model::geometry``, as Drake names a parsed model's geometry (its parser has
        already scoped most names with their model)."""
        return self.name if self.name.startswith(f"{self.model}::") else f"{self.model}::{self.name}"


@dataclass
class AnchoredWorld:
    """What `add_anchored_world` did: the model instances it added to the plant (none when the
    world was anchored) and, for anchored geometry, where each geometry came from."""

    instances: list[ModelInstanceIndex] = field(default_factory=list)
    source: dict = field(default_factory=dict)  # GeometryId -> (model name, link name)
    windowed: bool = False  # collision shapes get their proximity role only near the robots
    windowed_shapes: list[tuple[WindowedShape, StaticShape]] = field(default_factory=list)
    world: Normalised | None = None  # the normalised world (None for URDF and directives)

    def register(self, plant: MultibodyPlant, s: StaticShape) -> None:
        """Register one shape on the world body, remembering where it came from."""
        name = s.scoped_name
        footprint = (
            shape_box(s.shape, np.array(s.X_WG.rotation().matrix()), np.array(s.X_WG.translation()))
            if self.windowed and s.proximity is not None
            else None
        )
        if footprint is not None:
            # no proximity role yet (world/proximity_window.py); a perception role only, so
            # that the plant knows the geometry and adds no illustration role (which it does
            # to an instance without roles): the scene does not draw it twice
            instance = GeometryInstance(s.X_WG, s.shape, name)
            instance.set_perception_properties(PerceptionProperties())
            new = plant.RegisterVisualGeometry(plant.world_body(), instance)
            low, high = footprint
            self.windowed_shapes.append((WindowedShape(new, low[:2], high[:2], s.proximity), s))
        elif s.proximity is not None:
            new = plant.RegisterCollisionGeometry(plant.world_body(), s.X_WG, s.shape, name, s.proximity)
        else:  # the colour overload copies everything it is given (no GeometryInstance to C++)
            new = plant.RegisterVisualGeometry(plant.world_body(), s.X_WG, s.shape, name, s.diffuse.rgba)
        self.source[new] = (s.model, s.link)


def _label(world: Normalised | Path) -> str:
    return world.source if isinstance(world, Normalised) else str(world)


def add_anchored_world(
    plant: MultibodyPlant,
    world: str | Path | Normalised,
    parser: Parser,
    max_collision_geometries: int = MAX_COLLISION_GEOMETRIES,
) -> AnchoredWorld:
    """Add the world (a file, or a normalised world) to `plant` (not finalized): its static
    models as anchored geometry, the others parsed with `parser`."""
    world = load_world(world)
    label = _label(world)
    if not isinstance(world, Normalised):
        return _add_whole(plant, world, label, None, parser)
    scan = scan_world(world.text)
    if scan.split is None:
        _check_size(label, scan, max_collision_geometries)
        return _add_whole(plant, world, label, scan, parser)
    if len(scan.split.models) > PIECE_MODELS:
        log.info(
            "reading %s: %d models, %d collision geometries", label, len(scan.split.models), scan.collisions
        )
    split = scan.split
    moving = [m for m in split.models if not m.static]
    result = AnchoredWorld(windowed=scan.collisions > max_collision_geometries, world=world)
    if result.windowed:
        log.info(
            "%s: %d collision geometries, more than max_collision_geometries (%d): static ones "
            "collide only near the robots (world/proximity_window.py)",
            label,
            scan.collisions,
            max_collision_geometries,
        )
    _anchor(plant, result, label, static_shapes(label, split))
    if moving:
        result.instances = _parse_piece(parser, label, split, moving)
    return result


def world_shapes(world: str | Path | Normalised) -> list[StaticShape]:
    """Every geometry of the world that is fixed in it: its static models' and that of the
    other models' links welded to the world, static meshes as their convex pieces (no limit on
    their number: no SceneGraph holds them all)."""
    world = load_world(world)
    label = _label(world)
    if not isinstance(world, Normalised):
        return _split_meshes(_scratch_shapes(lambda p: _parse_file(p, world))[0])
    scan = scan_world(world.text)
    if scan.split is None:
        return _split_meshes(_scratch_shapes(lambda p: _parse_text(p, label, world.text))[0])
    shapes = static_shapes(label, scan.split)
    moving = [m for m in scan.split.models if not m.static]
    if moving:
        shapes += _scratch_shapes(lambda p: _parse_piece(p, label, scan.split, moving))[0]
    return _split_meshes(shapes)


def static_shapes(label: str, split: SplitWorld) -> list[StaticShape]:
    """The geometry of a split world's static models, read piece by piece."""
    shapes: list[StaticShape] = []
    for piece in _pieces([m for m in split.models if m.static]):
        shapes += _scratch_shapes(lambda p: _parse_piece(p, label, split, piece))[0]
    return shapes


def _pieces(static: list[ModelText]) -> list[list[ModelText]]:
    """Groups of at most PIECE_MODELS models in file order."""
    return [static[i : i + PIECE_MODELS] for i in range(0, len(static), PIECE_MODELS)]


def _split_meshes(shapes: list[StaticShape]) -> list[StaticShape]:
    """Static collision meshes as their convex pieces (world/mesh_pieces.py), each named
    ``<geometry>_<k>``; every other shape as it is."""
    out: list[StaticShape] = []
    for s in shapes:
        if s.proximity is None or not isinstance(s.shape, Mesh):
            out.append(s)
            continue
        pieces = convex_pieces(*mesh_triangles(s.shape), f"collision mesh {s.scoped_name}")
        if pieces is None:
            out.append(s)
            continue
        for k, shape in enumerate(convex_shapes(pieces, s.name)):
            out.append(StaticShape(s.model, s.link, f"{s.name}_{k}", s.X_WG, shape, s.proximity))
    return out


def _scratch_shapes(parse) -> tuple[list[StaticShape], bool]:
    """Parse into a scratch plant (no diagram: nothing here needs one) and copy out the geometry
    of every body welded to the world; also whether every body is welded."""
    scratch = MultibodyPlant(0.0)
    scene_graph = SceneGraph()
    scratch.RegisterAsSourceForSceneGraph(scene_graph)
    parser = models.register_package(Parser(scratch))
    parse(parser)
    scratch.Finalize()
    context = scratch.CreateDefaultContext()
    inspector = scene_graph.model_inspector()
    welded = {int(b.index()) for b in scratch.GetBodiesWeldedTo(scratch.world_body())}
    shapes: list[StaticShape] = []
    all_welded = True
    for i in range(1, scratch.num_bodies()):
        body = scratch.get_body(BodyIndex(i))
        if i not in welded:
            all_welded = False
            continue
        model = scratch.GetModelInstanceName(body.model_instance())
        X_WB = scratch.EvalBodyPoseInWorld(context, body)
        for gid in inspector.GetGeometries(scratch.GetBodyFrameIdOrThrow(body.index())):
            proximity = inspector.GetProximityProperties(gid)
            diffuse = None
            if proximity is None:  # a visual: its colour is all an SDF world's visual carries
                illustration = inspector.GetIllustrationProperties(gid)
                diffuse = (
                    DEFAULT_DIFFUSE
                    if illustration is None
                    else illustration.GetPropertyOrDefault("phong", "diffuse", DEFAULT_DIFFUSE)
                )
                diffuse = Rgba(*diffuse.rgba)
            else:
                proximity = ProximityProperties(proximity)
            shapes.append(
                StaticShape(
                    model,
                    body.name(),
                    inspector.GetName(gid),
                    X_WB @ inspector.GetPoseInFrame(gid),
                    inspector.GetShape(gid).Clone(),
                    proximity,
                    diffuse,
                )
            )
    return shapes, all_welded


def _merge_visuals(plant: MultibodyPlant, label: str, shapes: list[StaticShape]) -> list[StaticShape]:
    """Register the boxes, cylinders and spheres among the visuals as merged meshes (named
    ``<world file>::visuals_<batch>_<colour>``, sourced to no single model); the other shapes
    are left to register one by one."""
    merge = [s for s in shapes if s.proximity is None and isinstance(s.shape, MERGEABLE)]
    meshes = merged_meshes(merge, f"{Path(label).name}::visuals")
    for name, mesh, rgba in meshes:
        plant.RegisterVisualGeometry(plant.world_body(), RigidTransform(), mesh, name, np.array(rgba))
    log.info(
        "%s: %d static visuals drawn as %d meshes (world/merged_visuals.py)", label, len(merge), len(meshes)
    )
    merged = {id(s) for s in merge}
    return [s for s in shapes if id(s) not in merged]


def _anchor(plant: MultibodyPlant, result: AnchoredWorld, label: str, shapes: list[StaticShape]) -> None:
    shapes = _split_meshes(shapes)
    if sum(s.proximity is None for s in shapes) > MERGE_ABOVE:
        shapes = _merge_visuals(plant, label, shapes)
    for s in shapes:
        result.register(plant, s)


def _add_whole(
    plant: MultibodyPlant, world: Normalised | Path, label: str, scan: WorldScan | None, parser: Parser
) -> AnchoredWorld:
    """A world read in one scratch plant: anchored if all of it is static, else parsed as is."""
    text = world.text if isinstance(world, Normalised) else None
    read = (lambda p: _parse_text(p, label, text)) if text is not None else (lambda p: _parse_file(p, world))
    shapes, all_welded = _scratch_shapes(read)
    normalised = world if isinstance(world, Normalised) else None
    if not all_welded:
        return AnchoredWorld(instances=read(parser), world=normalised)
    result = AnchoredWorld(world=normalised)
    _anchor(plant, result, label, shapes)
    return result


def _check_size(label: str, scan: WorldScan, limit: int) -> None:
    if scan.collisions > limit:
        raise WorldTooLargeError(
            f"{label}: {scan.collisions:,} <collision> elements, more than "
            f"max_collision_geometries ({limit:,}), in a world that is read whole ({scan.why_whole}): "
            f"Drake 1.51's SceneGraph keeps an entry for every pair of collision geometries, so "
            f"time and memory grow with the square (3,000 took 17 s and 1.7 GB here), and only the "
            f"static models of a world read in pieces can collide near the robots alone; merge "
            f"small shapes, drop collisions the robot cannot reach, or raise the world node's "
            f"max_collision_geometries if the machine has the memory"
        )


def parse_world(parser: Parser, world: str | Path | Normalised) -> list[ModelInstanceIndex]:
    """The whole world parsed into the parser's plant as it is, nothing anchored."""
    world = load_world(world)
    if isinstance(world, Normalised):
        return _parse_text(parser, world.source, world.text)
    return _parse_file(parser, world)


def _parse_file(parser: Parser, file: Path) -> list[ModelInstanceIndex]:
    """A URDF or model-directives world, as models.add_model reads it."""
    return models.add_model(parser.plant(), file, parser=parser)


def _parse_text(parser: Parser, label: str, text: bytes) -> list[ModelInstanceIndex]:
    """SDF text; Drake's messages about it name `label` (its lines are the file's)."""
    drake_log = logging.getLogger("drake")
    rename = _NameTheFile(label)
    drake_log.addFilter(rename)
    try:
        return list(parser.AddModelsFromString(text.decode("utf-8"), "sdf"))
    except (RuntimeError, UnicodeDecodeError) as error:
        raise models.ModelError(f"failed to parse model file {label}: {rename.fix(str(error))}") from error
    finally:
        drake_log.removeFilter(rename)


def _parse_piece(
    parser: Parser, label: str, split: SplitWorld, piece: list[ModelText]
) -> list[ModelInstanceIndex]:
    """Parse some of a split world's models (the piece keeps every model on its line)."""
    return _parse_text(parser, label, split.text(piece))


class _NameTheFile(logging.Filter):
    """Drake calls a model parsed from a string "<literal-string>.sdf" (its warnings) or
    "<data-string>" (SDFormat's errors); say which file it is."""

    def __init__(self, file: str) -> None:
        super().__init__()
        self.file = file

    def fix(self, text: str) -> str:
        return text.replace("<literal-string>.sdf", self.file).replace("<data-string>", self.file)

    def filter(self, record: logging.LogRecord) -> bool:
        text = record.getMessage()
        if "<literal-string>" in text or "<data-string>" in text:
            record.msg, record.args = self.fix(text), ()
        return True
