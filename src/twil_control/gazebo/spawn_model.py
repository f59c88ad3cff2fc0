"""gazebo_ros spawn_model's role: puts a robot description into the world at a pose.

The ROS script's arguments (-urdf/-sdf, -param/-file, -model, the pose, -J ...); the
description's Gazebo plugins and sensors load into /gazebo, as gazebo_ros does (docs/robots.md,
"Spawning"). Once the world is built a floating model's pose is checked against the world's
extent: far outside it is refused (a typo, or a pose for another world), nothing under it is
warned about (it will fall), and -z is free, since dropping a robot is a legitimate start
(docs/failures.md).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from twil_control.errors import InputError

from ..core.ros_node import RosNode
from ..core.yaml_io import display_path

_POSE = ("x", "y", "z", "R", "P", "Y")

#: m: how far outside the box around the world's geometry a model may be spawned
SPAWN_MARGIN = 1.0


class SpawnModel(RosNode):
    required_by_default = True

    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        parser = argparse.ArgumentParser(add_help=False, allow_abbrev=False)
        kind = parser.add_mutually_exclusive_group()
        kind.add_argument("-urdf", action="store_true")
        kind.add_argument("-sdf", action="store_true")
        source = parser.add_mutually_exclusive_group()
        source.add_argument("-file")
        source.add_argument("-param")
        parser.add_argument("-model", required=True)
        for axis in _POSE:
            parser.add_argument(f"-{axis}", type=float, default=0.0)
        parser.add_argument("-J", nargs=2, action="append", default=[], metavar=("JOINT", "VALUE"))
        parser.add_argument("-robot_namespace", default=None)
        parser.add_argument("-unpause", action="store_true")
        parser.add_argument("-wait", default=None)
        parser.add_argument("-reference_frame", default="world")
        parser.add_argument("-gazebo_namespace", default="/gazebo")
        parser.add_argument("-package_to_model", action="store_true")
        self.spec = s = self.parse_args(parser)
        if s.file is None and s.param is None:
            raise InputError(f"node {self.fqn}: give the description with -file PATH or -param NAME")
        if s.param is not None and not (s.urdf or s.sdf):
            raise InputError(f"node {self.fqn}: -param {s.param} needs -urdf or -sdf")
        if s.reference_frame not in ("world", ""):
            raise InputError(
                f"node {self.fqn}: -reference_frame {s.reference_frame}: only the world frame is supported"
            )
        for label in _POSE:
            value = getattr(s, label)
            if not math.isfinite(value):
                raise InputError(f"node {self.fqn}: spawn pose -{label} must be finite (got {value})")
        self.joint_positions = {}
        for joint, value in s.J:
            try:
                self.joint_positions[joint] = float(value)
            except ValueError:
                raise InputError(
                    f"node {self.fqn}: -J {joint} {value}: the value must be a number (rad or m)"
                ) from None
        self.text, self.label, self.base_dir = self._read()
        self.description = None
        self.sdf = None
        if s.urdf:
            from ..description.urdf import parse_urdf

            self.description = parse_urdf(self.text, self.label)
        elif s.sdf:
            from ..description.gazebo_world import normalise_model
            from ..description.urdf import DescriptionError

            pose = tuple(getattr(s, axis) for axis in _POSE)
            try:
                self.sdf = normalise_model(self.text, self.label, self.base_dir, s.model, pose)
            except DescriptionError as error:
                raise InputError(f"node {self.fqn}: {error}") from None
            self.description = self.sdf.models[0].robot  # None: a model without plugins

    def _read(self) -> tuple[str | None, str, Path | None]:
        """The description's text (None for the short names of shipped models), its label for
        messages and the folder relative mesh paths resolve from."""
        s = self.spec
        if s.param is not None:
            text = self.get_param(s.param)
            if not isinstance(text, str) or not text.strip():
                raise InputError(
                    f"node {self.fqn}: parameter {self.resolve(s.param)} does not hold "
                    f"a robot description (got {type(text).__name__})"
                )
            return text, f"parameter {self.resolve(s.param)}", None
        if not (s.urdf or s.sdf):
            return None, s.file, None
        path = Path(s.file).expanduser()
        if not path.is_file():
            raise InputError(f"node {self.fqn}: -file {s.file}: file not found")
        return path.read_text(), str(path), path.parent

    def build_world(self, sim) -> None:
        s = self.spec
        if self.text is None:  # a shipped model by short name or path
            sim.spawn(s.file, s.model, x=s.x, y=s.y, yaw=s.Y, z=s.z)
            return
        from .plugins import host_of

        host = host_of(self.master)
        pose = tuple(getattr(s, axis) for axis in _POSE)
        limits = host.drive_effort_limits(self.description) if self.description else {}
        _, warnings = sim.spawn_description(
            s.model,
            description=None if s.sdf else self.description,
            sdf_text=self.sdf.text if s.sdf else None,
            source=self.label,
            pose=pose,
            joint_positions=self.joint_positions,
            base_dir=self.base_dir,
            drive_effort_limits=limits,
        )
        if self.sdf is not None and self.sdf.summary():
            self.log.info("%s", self.sdf.summary())
        for warning in warnings:
            self.log.warning("%s", warning)
        if self.description is not None:
            host.load_plugins(sim, s.model, self.description, s.robot_namespace)

    def build_systems(self, sim) -> None:
        from ..world.fall_monitor import floating_bases

        bases = floating_bases(sim.plant, sim.robot_instances(self.spec.model))
        if not bases:  # welded where its description says: the pose is not used
            return
        s, extent = self.spec, sim.world_extent()
        world = ", ".join(display_path(p) for p in sim.world_files) or "(no world file)"
        if not extent.empty:
            low, high = extent.bounds()
            for option, value, axis in (("x", s.x, 0), ("y", s.y, 1)):
                if not low[axis] - SPAWN_MARGIN <= value <= high[axis] + SPAWN_MARGIN:
                    raise InputError(
                        f"node {self.fqn}: spawn_model -{option} {value:g}{self.launch_arg_of('-' + option)} "
                        f"puts '{s.model}' outside the world "
                        f"{world}, whose geometry spans x [{low[0]:g}, {high[0]:g}] m and y [{low[1]:g}, "
                        f"{high[1]:g}] m; a model may be spawned at most {SPAWN_MARGIN:g} m outside it"
                    )
        z = float(sim.plant.GetDefaultFloatingBaseBodyPose(bases[0]).translation()[2])
        if extent.empty or not extent.support_under(s.x, s.y, z):
            self.log.warning(
                "no geometry of the world %s lies under '%s' spawned at (x, y) = (%g, %g): it will "
                "fall, and the run stops once it has left the world",
                world,
                s.model,
                s.x,
                s.y,
            )
