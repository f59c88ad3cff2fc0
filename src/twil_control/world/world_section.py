"""An SDF world's static geometry cut at a height, through Drake (the map rasteriser's input).

The world is parsed by Drake into a MultibodyPlant + SceneGraph and cut by the same
`LaserScene` the simulated laser uses, so the ground-truth map and the laser see the same
shapes. Only static geometry is kept (anchored, or welded to the world): free bodies have no
fixed place on a map.
"""
from __future__ import annotations

from pathlib import Path

from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlantConfig
from pydrake.systems.framework import DiagramBuilder

from ..mapping.sections import Section
from . import models
from .laser_scene import LaserScene


def world_section(world: str | Path, height: float) -> Section:
    """The static shapes of `world` (an SDF/URDF path or a short model name) at z = height."""
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlant(MultibodyPlantConfig(time_step=0.001), builder)
    models.add_model(plant, world)
    plant.Finalize()
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    query = scene_graph.get_query_output_port().Eval(scene_graph.GetMyContextFromRoot(context))
    scene = LaserScene(plant, scene_graph.model_inspector())
    return scene.static_section(query, height)
