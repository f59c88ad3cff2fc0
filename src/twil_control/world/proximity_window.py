"""Static collision geometry handed to SceneGraph only near the robots, for worlds too large for
its pair table (quadratic in the collision geometries: docs/inputs.md, "Large worlds").

Beyond `max_collision_geometries`, static collision shapes are registered without a proximity
role; the window gives the role, in the simulator's context, to those within `radius` of a
movable body and takes it back beyond `radius + margin`, between slices of simulated time. It
depends only on the state at the slice boundaries, so the same seed gives the same run.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pydrake.geometry import ProximityProperties, Role

#: m around a movable body's origin within which static collision geometry has its role
RADIUS = 2.0
#: m further before the role is taken back (no flicker at the edge)
MARGIN = 0.5


@dataclass
class WindowedShape:
    """A static collision geometry registered without its proximity role."""

    gid: object  # GeometryId
    low: np.ndarray  # its footprint's corners in the world's x-y plane
    high: np.ndarray
    proximity: ProximityProperties  # the role it gets near a robot


class ProximityWindow:
    """Which windowed shapes have their proximity role, and the changes that keep it current."""

    def __init__(
        self, source_id, shapes: list[WindowedShape], radius: float = RADIUS, margin: float = MARGIN
    ) -> None:
        self.source_id = source_id
        self.shapes = shapes
        self.radius, self.margin = radius, margin
        self._low = np.array([s.low for s in shapes]).reshape(-1, 2)
        self._high = np.array([s.high for s in shapes]).reshape(-1, 2)
        self.active = np.zeros(len(shapes), dtype=bool)

    def distances(self, points: np.ndarray) -> np.ndarray:
        """Each shape's footprint distance to the nearest of `points` (k x 2)."""
        best = np.full(len(self.shapes), np.inf)
        for p in np.asarray(points, float).reshape(-1, 2):
            gap = np.maximum(np.maximum(self._low - p, p - self._high), 0.0)
            best = np.minimum(best, np.hypot(gap[:, 0], gap[:, 1]))
        return best

    def update(self, scene_graph, scene_graph_context, points: np.ndarray) -> tuple[int, int]:
        """Give the role to the shapes within radius of `points`, take it from those beyond
        radius + margin; returns (given, taken)."""
        d = self.distances(points)
        give = np.flatnonzero((d <= self.radius) & ~self.active)
        take = np.flatnonzero((d > self.radius + self.margin) & self.active)
        for i in give:
            shape = self.shapes[i]
            scene_graph.AssignRole(scene_graph_context, self.source_id, shape.gid, shape.proximity)
        for i in take:
            scene_graph.RemoveRole(scene_graph_context, self.source_id, self.shapes[i].gid, Role.kProximity)
        self.active[give] = True
        self.active[take] = False
        return len(give), len(take)
