"""One launch = one Drake Diagram: the plant and scene graph of the world, the robots spawned
into it, and the systems that nodes add (hardware adapters, sensors, timers).

Building happens in two phases because a MultibodyPlant must be finalized before systems can
connect to its ports: models are added first (world, spawned robots), then `finalize()`, then
systems are added and wired, then `build()` returns the simulator. Node code never touches the
DiagramBuilder directly beyond `add_system`.
"""

from __future__ import annotations

import logging
import math
import re
from pathlib import Path
from typing import Protocol, runtime_checkable

import numpy as np
from pydrake.geometry import CollisionFilterDeclaration, GeometrySet
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlantConfig
from pydrake.multibody.tree import BodyIndex, ModelInstanceIndex
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

from twil_control.errors import InputError, TwilControlError

from ..description.gazebo_world import Normalised
from . import models
from .extent import static_extent
from .fall_monitor import floating_bases
from .floor_rest import lift_out_of_floor
from .proximity_window import ProximityWindow
from .static_world import MAX_COLLISION_GEOMETRIES, add_anchored_world, load_world, parse_world

_log = logging.getLogger(__name__)


@runtime_checkable
class PlantConnected(Protocol):
    """A system that wires its own ports to the plant once added (Simulation.add_system)."""

    def connect(self, sim: Simulation) -> None: ...


#: an SDF model or link that asks Gazebo to collide its links with each other
SDF_SELF_COLLIDE = re.compile(rb"<self_collide>\s*(1|true)\s*</self_collide>")


class SimulationError(TwilControlError, RuntimeError):
    """A model that cannot be spawned, or a build step out of order."""


#: Where the project's plant differs from Drake's MultibodyPlantConfig (whose other defaults,
#: a 1 ms step, the lagged approximation, 1 mm penetration allowance and 1e-4 stiction
#: tolerance, it keeps):
#: - point contact: the robots' wheels are spheres, and hydroelastic wheels were slower and
#:   slipped more (the figures: docs/performance.md, qbot_bench);
#: - output ports computed when read: the plant's output ports (contact results, ...) are
#:   computed from its state when read, and its step is a discrete update. Drake's default
#:   (sampled) stores them at every step as an unrestricted update, after which Drake copies the
#:   state and looks up every system's witness functions (through pybind for each Python system)
#:   at every step, which slows every launch. The motion is the same up to round-off; a
#:   ros_control cycle keeps its place before the step it drives (world/robot_hw_sim.py), and
#:   contact results mean the forces of the coming step instead of the last one's.
PROJECT_PLANT = {"contact_model": "point", "use_sampled_output_ports": False}


def plant_config(**changes) -> MultibodyPlantConfig:
    """Drake's plant config with the project's choices (PROJECT_PLANT), changed by `changes`
    (MultibodyPlantConfig's field names; an unknown one raises AttributeError)."""
    return MultibodyPlantConfig(**{**PROJECT_PLANT, **changes})


class Simulation:
    """The world being simulated and the diagram under construction."""

    def __init__(self, config: MultibodyPlantConfig | None = None) -> None:
        self.config = config if config is not None else plant_config()
        if not (self.config.time_step > 0 and math.isfinite(self.config.time_step)):
            raise SimulationError(
                f"time_step must be a positive number of seconds (got {self.config.time_step})"
            )
        self.builder = DiagramBuilder()
        self.plant, self.scene_graph = AddMultibodyPlant(self.config, self.builder)
        self.robots: dict[str, list[ModelInstanceIndex]] = {}
        self.world_files: list[Path] = []
        #: (wall s, simulated s) the run's real-time pacing counts from, set by the launch runner
        #: (it moves after a pause, so that the view's frame schedule moves with it)
        self.pace_anchor: tuple[float, float] | None = None
        self._anchored_worlds: list = []  # static_world results
        # (name, instances, root link or None: its floating base) of the models lifted out of the
        # floor at build: spawn_model's URDFs and SDFs, the world's models that are not static
        self._spawned_descriptions: list = []
        self.lifted: dict[str, float] = {}  # spawned model -> how far it was raised out of the floor
        # spawn_model's models whose links do not collide with each other, as in Gazebo
        self._without_self_collision: list[list[ModelInstanceIndex]] = []
        self.diagram = None
        self.simulator: Simulator | None = None
        self._finalized = False
        self._extent = None
        self.window: ProximityWindow | None = None  # a large world's collisions near the robots
        self._movable: list = []  # the bodies the window follows

    # -- phase 1: models --------------------------------------------------------------
    def _parser(self) -> Parser:
        parser = Parser(self.plant)
        models.register_package(parser)
        return parser

    def add_world(
        self,
        path,
        anchor_static: bool = True,
        max_collision_geometries: int = MAX_COLLISION_GEOMETRIES,
    ) -> list[ModelInstanceIndex]:
        """Load a world: a file (an SDF world is normalised first: description.gazebo_world)
        or a normalised world. With `anchor_static`, its static models become anchored geometry
        (static_world: the same scene, a cheaper plant step); returns the model instances added
        to the plant (none for an all-static world). Beyond `max_collision_geometries`
        collision geometries, the static ones collide only near the robots (static_world).
        The world's models that are not static are the simulation's models as spawned ones
        are (`robots`, by their names); its ``<gravity>`` is the plant's."""
        self._require(finalized=False, what="add a world")
        world = load_world(path)
        if anchor_static:
            anchored = add_anchored_world(self.plant, world, self._parser(), max_collision_geometries)
            self._anchored_worlds.append(anchored)
            instances = anchored.instances
        else:
            instances = parse_world(self._parser(), world)
        if isinstance(world, Normalised):
            self._take_world_models(world, instances)
            if world.gravity is not None:
                self.plant.mutable_gravity_field().set_gravity_vector(np.array(world.gravity))
            summary = world.summary()
            if summary:
                _log.info("%s", summary)
        self.world_files.append(Path(world.source if isinstance(world, Normalised) else world))
        return instances

    def _take_world_models(self, world: Normalised, instances: list[ModelInstanceIndex]) -> None:
        names = {int(i): self.plant.GetModelInstanceName(i) for i in instances}
        for model in world.models:
            if model.static:
                continue
            if model.name in self.robots:
                raise SimulationError(
                    f"{world.source}:{model.line}: a model named '{model.name}' already exists"
                )
            mine = [
                i
                for i in instances
                if names[int(i)] == model.name or names[int(i)].startswith(model.name + "::")
            ]
            if mine:
                self.robots[model.name] = mine
                self._spawned_descriptions.append((model.name, mine, None))  # lifted out of the floor

    def body(self, model: str, link: str):
        """The plant body of `link` of the simulation's model `model`; a link of a nested
        model is named ``nested::link``, as Gazebo scopes it. ValueError names the model's links."""
        instances = self.robot_instances(model)
        scope, _, name = link.rpartition("::")
        owner = f"{model}::{scope}" if scope else None
        for instance in instances:
            if owner is not None and self.plant.GetModelInstanceName(instance) != owner:
                continue
            if self.plant.HasBodyNamed(name, instance):
                return self.plant.GetBodyByName(name, instance)
        known = (
            [self.plant.get_body(k).name() for i in instances for k in self.plant.GetBodyIndices(i)]
            if self._finalized
            else []
        )
        raise InputError(
            f"model '{model}' has no link '{link}'" + (f" (links: {', '.join(known)})" if known else "")
        )

    def spawn(
        self,
        model: str | Path,
        name: str,
        x: float = 0.0,
        y: float = 0.0,
        yaw: float = 0.0,
        z: float = 0.0,
        base_link: str = "base_link",
    ) -> list[ModelInstanceIndex]:
        """Add a robot model at (x, y, yaw) on the floor (gazebo_ros spawn_model's role).

        A mobile robot's floating `base_link` gets the spawn pose as its default pose; a model
        with no floating base (a fixed arm) is left where its description welds it.
        """
        self._require(finalized=False, what="spawn a model")
        for label, value in (("x", x), ("y", y), ("yaw", yaw), ("z", z)):
            if not math.isfinite(value):
                raise SimulationError(f"spawn pose {label} of '{name}' must be finite (got {value})")
        if name in self.robots:
            raise SimulationError(f"a model named '{name}' is already spawned")
        instances = models.add_model(self.plant, model, parser=self._parser())
        self.robots[name] = instances
        welded = {int(b.index()) for b in self.plant.GetBodiesWeldedTo(self.plant.world_body())}
        for instance in instances:
            if (
                self.plant.HasBodyNamed(base_link, instance)
                and int(self.plant.GetBodyByName(base_link, instance).index()) not in welded
            ):
                # Resting on its wheels at z = 0 (models.rest_height), raised by z.
                models.set_base_pose(
                    self.plant,
                    instance,
                    x,
                    y,
                    yaw,
                    z=models.rest_height(self.plant, instance) + z,
                    base_link=base_link,
                )
        return instances

    def spawn_description(
        self,
        name: str,
        description=None,
        sdf_text: bytes | None = None,
        source: str = "",
        pose=(0.0,) * 6,
        joint_positions=None,
        base_dir: Path | None = None,
        drive_effort_limits=None,
    ) -> tuple[list[ModelInstanceIndex], list[str]]:
        """Add a user's URDF (a parsed description) as model `name` at `pose` (x, y, z, roll,
        pitch, yaw of its root link; spawn_model -urdf), or SDF text normalised for spawning
        (description.gazebo_world.normalise_model: named and posed already; -sdf). Returns the
        instances and the warnings to log (world/description.py)."""
        from .description import add_sdf, add_urdf

        self._require(finalized=False, what="spawn a model")
        if not all(math.isfinite(v) for v in pose):
            raise SimulationError(f"spawn pose of '{name}' must be finite (got {tuple(pose)})")
        if name in self.robots:
            raise SimulationError(f"a model named '{name}' is already spawned")
        if description is not None:
            instances, warnings = add_urdf(
                self.plant,
                self._parser(),
                description,
                name,
                tuple(pose),
                dict(joint_positions or {}),
                base_dir,
                drive_effort_limits,
            )
        else:
            instances, warnings = (
                add_sdf(self.plant, self._parser(), sdf_text, source, drive_effort_limits),
                [],
            )
        self.robots[name] = instances
        if description is not None:
            from ..description.drake_urdf import self_collides

            if not self_collides(description):
                self._without_self_collision.append(instances)
        elif not SDF_SELF_COLLIDE.search(sdf_text or b""):
            self._without_self_collision.append(instances)
        if description is None:
            self._spawned_descriptions.append((name, instances, None))
        elif description.root != "world":
            self._spawned_descriptions.append((name, instances, description.root))
        return instances, warnings

    def limit_efforts(self, model: str, limits: dict[str, float]) -> None:
        """The effort limits (N m) of joints of model `model` a drive plugin turns."""
        from .description import set_effort_limits

        set_effort_limits(self.plant, self.robot_instances(model), limits)

    def finalize(self) -> None:
        self._require(finalized=False, what="finalize the plant")
        self.plant.Finalize()
        self._finalized = True
        self._exclude_self_collisions()

    def _exclude_self_collisions(self) -> None:
        """Gazebo collides a model's links with each other only when the model or a link sets
        self_collide (its default is false): the links of spawn_model's models that do not are
        filtered from each other here, which also spares the contact query those pairs (a
        Husky's wheels against its chassis hulls, at every step)."""
        manager = self.scene_graph.collision_filter_manager()
        for instances in self._without_self_collision:
            frames = [
                frame
                for instance in instances
                for body in self.plant.GetBodyIndices(instance)
                if (frame := self.plant.GetBodyFrameIdIfExists(body)) is not None
            ]
            if len(frames) > 1:
                manager.Apply(CollisionFilterDeclaration().ExcludeWithin(GeometrySet(frames)))

    # -- phase 2: systems -------------------------------------------------------------
    def add_system(self, system, name: str | None = None):
        """Add a system; a PlantConnected one is then wired to the plant (its connect(sim))."""
        self._require(finalized=True, what="add a system")
        if name:
            system.set_name(name)
        self.builder.AddSystem(system)
        if isinstance(system, PlantConnected):
            system.connect(self)
        return system

    def add_visualizer(self, meshcat, publish_period: float = 1 / 32):
        """Draw the scene graph's illustration geometry in `meshcat` (Drake's MeshcatVisualizer),
        sending poses every `publish_period` s of simulated time, or (0) only when its owner
        calls ForcedPublish. Only the view asks for this."""
        from pydrake.geometry import MeshcatVisualizer, MeshcatVisualizerParams

        self._require(finalized=True, what="add a visualizer")
        params = MeshcatVisualizerParams()
        params.publish_period = publish_period
        return MeshcatVisualizer.AddToBuilder(self.builder, self.scene_graph, meshcat, params)

    @property
    def windowed_shapes(self) -> list:
        """The static shapes whose proximity role follows the robots, (GeometryId, StaticShape)
        each: what sees the whole world (the laser, the extent, the contact monitor) reads them here."""
        return [(w.gid, shape) for world in self._anchored_worlds for w, shape in world.windowed_shapes]

    @property
    def anchored_sources(self) -> dict:
        """Anchored geometry of static world models -> the (model, link) it came from."""
        return {gid: src for world in self._anchored_worlds for gid, src in world.source.items()}

    def world_extent(self):
        """The boxes of the world's static geometry, spawned robots left out (world.extent);
        computed once, after finalize()."""
        self._require(finalized=True, what="measure the world")
        if self._extent is None:
            robots = [i for instances in self.robots.values() for i in instances]
            self._extent = static_extent(
                self.plant,
                self.scene_graph,
                exclude=robots,
                extra=[(s.shape, s.X_WG) for _, s in self.windowed_shapes],
            )
        return self._extent

    def robot_instances(self, name: str) -> list[ModelInstanceIndex]:
        if name not in self.robots:
            known = ", ".join(self.robots) or "none"
            raise SimulationError(f"no spawned model named '{name}' (spawned: {known})")
        return self.robots[name]

    def build(self) -> Simulator:
        self._require(finalized=True, what="build the diagram")
        self.diagram = self.builder.Build()
        self.simulator = Simulator(self.diagram)
        self._open_window()  # before the lift: a windowed floor has no proximity role yet
        context = self.plant_context(self.simulator.get_mutable_context())
        for name, instances, root in self._spawned_descriptions:
            if root is None:  # an SDF model: its floating base, if it has one
                bases = floating_bases(self.plant, instances)
                if not bases:
                    continue
                body = bases[0]
            else:
                body = self.plant.GetBodyByName(root, instances[0])
            if body.is_floating_base_body():
                lift = lift_out_of_floor(self.plant, context, instances, body)
                if lift:
                    self.lifted[name] = lift
                    _log.info(
                        "model '%s' started %.3f m inside the floor: lifted to rest on it "
                        "(Gazebo's physics pushes it out in its first steps)",
                        name,
                        lift,
                    )
        return self.simulator

    def _open_window(self) -> None:
        shapes = [w for world in self._anchored_worlds for w, _ in world.windowed_shapes]
        if not shapes:
            return
        self.window = ProximityWindow(self.plant.get_source_id(), shapes)
        welded = {int(b.index()) for b in self.plant.GetBodiesWeldedTo(self.plant.world_body())}
        self._movable = [
            self.plant.get_body(BodyIndex(k)) for k in range(self.plant.num_bodies()) if k not in welded
        ]
        self.update_proximity_window()

    def update_proximity_window(self) -> None:
        """Give the static collision shapes near the movable bodies their proximity role (and
        take it from the far ones) in the simulator's context: a large world only, between
        slices of simulated time (world/proximity_window.py)."""
        if self.window is None or not self._movable:
            return
        root = self.simulator.get_mutable_context()
        context = self.plant_context(root)
        points = np.array(
            [self.plant.EvalBodyPoseInWorld(context, b).translation()[:2] for b in self._movable]
        )
        self.window.update(self.scene_graph, self.scene_graph.GetMyMutableContextFromRoot(root), points)

    def plant_context(self, root_context):
        return self.plant.GetMyContextFromRoot(root_context)

    def _require(self, finalized: bool, what: str) -> None:
        if self._finalized != finalized:
            when = "after" if finalized else "before"
            raise SimulationError(f"cannot {what} {when} the plant is finalized")
