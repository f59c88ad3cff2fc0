"""A spawned robot that has fallen out of the world, noticed while time runs.

Gazebo lets a robot fall forever where there is no floor, while its sensors and estimators go on
as if nothing happened. A robot has left the world when its base is more than `fall_distance`
below both the world's lowest static geometry and its own spawn height (docs/failures.md). The
check reads the plant's positions at a low rate, from the world node's timer.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


def floating_bases(plant, instances) -> list:
    """The floating base bodies of the given model instances, in index order."""
    wanted = {int(i) for i in instances}
    bodies = [plant.get_body(i) for i in sorted(plant.GetFloatingBaseBodies(), key=int)]
    return [b for b in bodies if int(b.model_instance()) in wanted]


@dataclass
class _Watched:
    model: str
    body: str
    q_start: int  # the body's floating positions: qw qx qy qz x y z
    spawn_z: float
    limit: float  # below this z the robot has left the world
    reference: str  # what the limit is measured from, for the message


class FallMonitor:
    """Watches the floating base of every spawned robot (see the module docstring)."""

    def __init__(self, sim, fall_distance: float) -> None:
        self.plant = sim.plant
        self.fall_distance = fall_distance
        extent = sim.world_extent()
        lowest = math.inf if extent.empty else float(extent.low[:, 2].min())
        self.watched: list[_Watched] = []
        for model, instances in sim.robots.items():
            for body in floating_bases(self.plant, instances):
                spawn_z = float(self.plant.GetDefaultFloatingBaseBodyPose(body).translation()[2])
                if lowest <= spawn_z:
                    ground, reference = lowest, f"the world's lowest geometry (z = {lowest:.3f} m)"
                else:
                    ground, reference = spawn_z, f"its spawn height (z = {spawn_z:.3f} m)"
                self.watched.append(
                    _Watched(
                        model,
                        body.name(),
                        body.floating_positions_start(),
                        spawn_z,
                        ground - fall_distance,
                        reference,
                    )
                )

    def check(self, root_context, t: float) -> str | None:
        """None while every robot is in the world; else what happened to the first that left it."""
        q = self.plant.GetPositions(self.plant.GetMyContextFromRoot(root_context))
        for w in self.watched:
            x, y, z = (float(v) for v in q[w.q_start + 4 : w.q_start + 7])
            if z < w.limit:
                return (
                    f"robot '{w.model}' left the world at t = {t:.3f} s: its {w.body} is at (x, y, z) = "
                    f"({x:.3f}, {y:.3f}, {z:.3f}) m, more than {self.fall_distance:g} m below {w.reference}, "
                    f"with nothing under it to land on"
                )
        return None
