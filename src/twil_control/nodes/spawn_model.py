"""gazebo_ros spawn_model's role: puts a robot description into the world at a pose.

Args as the ROS script takes them: ``-file PATH -model NAME -x X -y Y -z Z -Y YAW``. PATH is a
URDF, SDF or Drake model-directives file, or a model name known to world.models (twil,
twil_wam, wam_fixed, qbot).
"""
from __future__ import annotations

import argparse
import math

from .base import RosNode


class SpawnModel(RosNode):
    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        parser = argparse.ArgumentParser(add_help=False)
        parser.add_argument("-file", required=True)
        parser.add_argument("-model", required=True)
        for axis in ("x", "y", "z", "Y"):
            parser.add_argument(f"-{axis}", type=float, default=0.0)
        self.spec = self.parse_args(parser)
        for label in ("x", "y", "z", "Y"):
            value = getattr(self.spec, label)
            if not math.isfinite(value):
                raise ValueError(f"node {self.fqn}: spawn pose -{label} must be finite (got {value})")

    def build_world(self, sim) -> None:
        s = self.spec
        sim.spawn(s.file, s.model, x=s.x, y=s.y, yaw=s.Y, z=s.z)
