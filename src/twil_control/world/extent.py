"""Where a world's static geometry is: an axis-aligned box around each collision shape.

What the checks at spawn and while time runs need (gazebo/spawn_model.py, world/fall_monitor.py):
the world's extent, whether anything lies under a spawn pose, and the lowest geometry. Boxes are
conservative: exact for the primitive shapes, a convex hull's vertices for meshes, an unbounded
box below a half-space's surface. The spawned robots' own geometry is not the world's.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

import numpy as np
from pydrake.geometry import Box, Capsule, Convex, Cylinder, Ellipsoid, HalfSpace, Mesh, Role, Sphere

log = logging.getLogger("twil_control.world")


def shape_box(shape, R: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """(low, high) corners enclosing `shape` at rotation R, position p; None if unknown."""
    absR = np.abs(R)
    if isinstance(shape, Box):
        half = absR @ (0.5 * np.array([shape.width(), shape.depth(), shape.height()]))
    elif isinstance(shape, Sphere):
        half = np.full(3, shape.radius())
    elif isinstance(shape, (Cylinder, Capsule)):
        axis = absR[:, 2]
        radial = np.sqrt(np.maximum(0.0, 1.0 - axis**2)) if isinstance(shape, Cylinder) else np.ones(3)
        half = 0.5 * shape.length() * axis + shape.radius() * radial
    elif isinstance(shape, Ellipsoid):
        half = np.sqrt((R**2) @ np.array([shape.a(), shape.b(), shape.c()]) ** 2)
    elif isinstance(shape, HalfSpace):
        if R[2, 2] > 1.0 - 1e-9:  # the surface is horizontal: everything below p_z
            return np.array([-math.inf, -math.inf, -math.inf]), np.array([math.inf, math.inf, p[2]])
        return np.full(3, -math.inf), np.full(3, math.inf)
    elif isinstance(shape, (Mesh, Convex)):
        hull = shape.GetConvexHull()
        vertices = np.array([hull.vertex(i) for i in range(hull.num_vertices())]) @ R.T + p
        return vertices.min(axis=0), vertices.max(axis=0)
    else:
        return None
    return p - half, p + half


@dataclass
class WorldExtent:
    """The boxes of a world's static geometry (rows of `low` and `high`)."""

    low: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    high: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))

    @property
    def empty(self) -> bool:
        return len(self.low) == 0

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(low, high) corners of the whole world (only for a world that is not empty)."""
        return self.low.min(axis=0), self.high.max(axis=0)

    def support_under(self, x: float, y: float, z: float) -> bool:
        """Some geometry lies under the point: its box covers (x, y) and reaches below z."""
        covers = (
            (self.low[:, 0] <= x)
            & (x <= self.high[:, 0])
            & (self.low[:, 1] <= y)
            & (y <= self.high[:, 1])
            & (self.low[:, 2] <= z)
        )
        return bool(covers.any())


def static_extent(plant, scene_graph, exclude=(), extra=()) -> WorldExtent:
    """The boxes of the static proximity geometry of a finalized plant, without the geometry of
    the model instances in `exclude` (the spawned robots), and of the `extra` (shape, X_WG)
    pairs (static collision shapes registered without their role: world/proximity_window.py)."""
    inspector = scene_graph.model_inspector()
    excluded = {int(i) for i in exclude}
    welded = {int(b.index()) for b in plant.GetBodiesWeldedTo(plant.world_body())}
    world_frame = inspector.world_frame_id()
    context = None
    lows, highs, unknown = [], [], []
    for gid in inspector.GetAllGeometryIds(Role.kProximity):
        frame = inspector.GetFrameId(gid)
        X_FG = inspector.GetPoseInFrame(gid)
        if frame == world_frame:
            X_WG = X_FG
        else:
            body = plant.GetBodyFromFrameId(frame)
            if int(body.index()) not in welded or int(body.model_instance()) in excluded:
                continue
            if context is None:
                context = plant.CreateDefaultContext()
            X_WG = plant.EvalBodyPoseInWorld(context, body) @ X_FG
        box = shape_box(
            inspector.GetShape(gid), np.array(X_WG.rotation().matrix()), np.array(X_WG.translation())
        )
        if box is None:
            unknown.append(inspector.GetName(gid))
            continue
        lows.append(box[0])
        highs.append(box[1])
    for shape, X_WG in extra:
        box = shape_box(shape, np.array(X_WG.rotation().matrix()), np.array(X_WG.translation()))
        if box is not None:
            lows.append(box[0])
            highs.append(box[1])
    if unknown:
        log.warning(
            "the world's extent leaves out %d geometr%s of unknown shape: %s",
            len(unknown),
            "y" if len(unknown) == 1 else "ies",
            ", ".join(unknown),
        )
    if not lows:
        return WorldExtent()
    return WorldExtent(np.array(lows), np.array(highs))
