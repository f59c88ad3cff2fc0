"""A world file's static models as anchored geometry (cheaper physics, the same scene).

Drake welds each link of an SDF ``<static>`` model to the world with its own body and weld
mobilizer, and every plant step computes those bodies' kinematics and inertias like any other
body's (the house world has 33 of them against the qbot's 7 bodies). Registering a static link's shapes directly on the world body gives SceneGraph the same
geometry at the same poses, with the same contact properties and colours (all an SDF world's
visual carries), and the tree nothing to compute.

`add_anchored_world` parses the file into a scratch plant, and when every body it holds is
welded to the world, registers each of their geometries on the target plant's world body,
named ``<model>::<geometry>`` (unique, and readable in Meshcat and in warnings). A world with
any moving body (a free box, a door on a hinge) is parsed into the plant as it is, unchanged.

`AnchoredWorld.source` maps each anchored geometry to the ``(model, link)`` it came from, so that
whoever names what the robot touched (the contact monitor) still says ``wall_north::wall_north_link``
and not ``world``.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from pydrake.geometry import Rgba
from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlant, MultibodyPlantConfig
from pydrake.multibody.tree import BodyIndex, ModelInstanceIndex
from pydrake.systems.framework import DiagramBuilder

from . import models

#: Drake's colour for a visual whose description gives none
DEFAULT_DIFFUSE = Rgba(0.9, 0.9, 0.9, 1.0)


@dataclass
class AnchoredWorld:
    """What `add_anchored_world` did: the model instances it added to the plant (none when the
    world was anchored) and, for anchored geometry, where each geometry came from."""

    instances: list[ModelInstanceIndex] = field(default_factory=list)
    source: dict = field(default_factory=dict)   # GeometryId -> (model name, link name)
    # the scratch diagram the world was parsed into, kept for as long as this result: nothing
    # registered in the plant refers to it (properties and shapes are copied), but pydrake
    # objects that did are only safe to drop in an order Python does not promise at a return
    scratch: object = None


def _scratch(path: str | Path):
    """The world parsed alone: (diagram, plant, scene graph); keep the diagram while using them."""
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlant(MultibodyPlantConfig(time_step=0.0), builder)
    models.add_model(plant, path)
    plant.Finalize()
    return builder.Build(), plant, scene_graph


def add_anchored_world(plant: MultibodyPlant, path: str | Path, parser) -> AnchoredWorld:
    """Add the world file `path` to `plant` (not finalized): as anchored geometry when all of its
    bodies are static, otherwise parsed as it is with `parser`."""
    diagram, scratch, scene_graph = _scratch(path)
    bodies = [scratch.get_body(BodyIndex(i)) for i in range(1, scratch.num_bodies())]
    welded = {int(b.index()) for b in scratch.GetBodiesWeldedTo(scratch.world_body())}
    if any(int(b.index()) not in welded for b in bodies):
        return AnchoredWorld(instances=models.add_model(plant, path, parser=parser))
    context = scratch.GetMyContextFromRoot(diagram.CreateDefaultContext())
    inspector = scene_graph.model_inspector()
    world = plant.world_body()
    result = AnchoredWorld(scratch=diagram)
    for body in bodies:
        model = scratch.GetModelInstanceName(body.model_instance())
        X_WB = scratch.EvalBodyPoseInWorld(context, body)
        for gid in inspector.GetGeometries(scratch.GetBodyFrameIdOrThrow(body.index())):
            name = f"{model}::{inspector.GetName(gid)}"
            X_WG = X_WB @ inspector.GetPoseInFrame(gid)
            shape = inspector.GetShape(gid).Clone()
            proximity = inspector.GetProximityProperties(gid)
            if proximity is not None:
                new = plant.RegisterCollisionGeometry(world, X_WG, shape, name, proximity)
            else:   # a visual: its colour is all an SDF world's visual carries
                # (registered through the colour overload, which copies everything it is given,
                # rather than handing a GeometryInstance over to C++)
                illustration = inspector.GetIllustrationProperties(gid)
                diffuse = DEFAULT_DIFFUSE if illustration is None else \
                    illustration.GetPropertyOrDefault("phong", "diffuse", DEFAULT_DIFFUSE)
                new = plant.RegisterVisualGeometry(world, X_WG, shape, name, diffuse.rgba)
            result.source[new] = (model, body.name())
    return result
