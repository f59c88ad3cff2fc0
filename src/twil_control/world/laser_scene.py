"""What a planar laser can see in a Drake world: SceneGraph's proximity geometry cut by a
horizontal plane (the 2D scene the ray caster and the map rasteriser work on).

`LaserScene` sorts a plant's proximity geometries once: the robot carrying the sensor is left
out (its chassis must not shadow its own laser), static geometry is posed and cut once per
height, moving geometry is re-posed at every call. Which shapes are cut and how: docs/qbot.md,
"The laser".
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
from pydrake.geometry import Box, Convex, Cylinder, Mesh, Role, Sphere

from ..mapping.sections import (
    Section,
    box_section,
    box_vertices,
    convex_hull,
    convex_section,
    cylinder_section,
    sphere_section,
)

log = logging.getLogger("twil_control.laser_scene")

SUPPORTED = (Box, Cylinder, Sphere, Convex, Mesh)


def hull_geometry(shape) -> tuple[np.ndarray, np.ndarray]:
    """(vertices (V, 3) in the geometry's frame, edges (E, 2) as vertex pairs) of the convex hull
    of a Convex or Mesh shape, as Drake's point contact sees it."""
    hull = shape.GetConvexHull()
    vertices = np.array([hull.vertex(i) for i in range(hull.num_vertices())], dtype=float)
    edges = set()
    for i in range(hull.num_elements()):
        polygon = hull.element(i)
        ring = [polygon.vertex(k) for k in range(polygon.num_vertices())]
        edges.update((min(a, b), max(a, b)) for a, b in zip(ring, ring[1:] + ring[:1]))
    return vertices, np.array(sorted(edges), dtype=np.int64).reshape(-1, 2)


def prism_footprint(world_vertices: np.ndarray) -> tuple[np.ndarray, float, float] | None:
    """(polygon, zmin, zmax) of a convex solid that is a vertical prism (every vertex on its
    bottom or top plane, the two outlines alike): its section at any height in [zmin, zmax]."""
    z = world_vertices[:, 2]
    zmin, zmax = float(z.min()), float(z.max())
    tol = 1e-9 * max(1.0, zmax - zmin)
    low, high = np.abs(z - zmin) <= tol, np.abs(z - zmax) <= tol
    if zmax - zmin <= tol or not np.all(low | high):
        return None
    bottom, top = convex_hull(world_vertices[low, :2]), convex_hull(world_vertices[high, :2])
    if len(bottom) < 3 or bottom.shape != top.shape or not np.allclose(bottom, top, atol=1e-9):
        return None
    return bottom, zmin, zmax


@dataclass
class _Primitive:
    name: str
    geometry_id: object
    shape: object
    R: np.ndarray | None = None  # world pose, for static primitives (read once)
    p: np.ndarray | None = None
    # an upright static box (its z axis exactly the world's): its section is the same polygon at
    # every height in [zmin, zmax] (the vertical edges' x, y do not depend on the height), so it
    # is cut once and re-cutting the scene only checks the height against its extent (a re-cut
    # of the house's 33 shapes took milliseconds, and the laser's height moves by more than
    # height_tolerance whenever the chassis pitches). The polygon is shared: do not modify it.
    upright: tuple[np.ndarray, float, float] | None = None  # (polygon, zmin, zmax)
    hull: tuple[np.ndarray, np.ndarray] | None = None  # a Convex or Mesh: (vertices, edges) in its frame


def cut(shape, R: np.ndarray, p: np.ndarray, height: float, into: Section, hull=None) -> None:
    """Append the section of one posed shape at `height` to `into` (nothing if missed); `hull`:
    a Convex or Mesh's hull_geometry, when already read."""
    if isinstance(shape, Box):
        poly = box_section(R, p, (shape.width(), shape.depth(), shape.height()), height)
        if poly is not None:
            into.polygons.append(poly)
    elif isinstance(shape, Cylinder):
        found = cylinder_section(R, p, shape.radius(), shape.length(), height)
        if found is not None:
            kind, value = found
            if kind == "circle":
                into.circles = np.vstack([into.circles, value])
            else:
                into.polygons.append(value)
    elif isinstance(shape, Sphere):
        circle = sphere_section(p, shape.radius(), height)
        if circle is not None:
            into.circles = np.vstack([into.circles, circle])
    elif isinstance(shape, (Convex, Mesh)):
        vertices, edges = hull_geometry(shape) if hull is None else hull
        poly = convex_section(vertices @ np.asarray(R).T + p, edges, height)
        if poly is not None:
            into.polygons.append(poly)


def warn_uncut(ignored: list[str], who: str) -> None:
    """One warning naming the geometries (``"name (Shape)"``) that `who` cannot cut."""
    if ignored:
        log.warning(
            "%s ignores %d proximity geometr%s of shapes it cannot cut (only Box, Cylinder, Sphere, "
            "Convex, Mesh): %s",
            who,
            len(ignored),
            "y" if len(ignored) == 1 else "ies",
            ", ".join(ignored),
        )


def _primitive(name: str, gid, shape) -> _Primitive:
    hull = hull_geometry(shape) if isinstance(shape, (Convex, Mesh)) else None
    return _Primitive(name, gid, shape.Clone(), hull=hull)


class LaserScene:
    """Proximity geometry of a finalized plant, sorted for cutting (see the module docstring)."""

    def __init__(self, plant, inspector, exclude=(), height_tolerance: float = 1e-3, extra=()) -> None:
        """`extra`: (GeometryId, shape) of static collision shapes registered without their
        proximity role (world/proximity_window.py), seen at all times."""
        excluded = {int(i) for i in exclude}
        welded = {int(b.index()) for b in plant.GetBodiesWeldedTo(plant.world_body())}
        world_frame = inspector.world_frame_id()
        self.static: list[_Primitive] = []
        self.dynamic: list[_Primitive] = []
        self.excluded: list[str] = []
        ignored: list[str] = []
        for gid in inspector.GetAllGeometryIds(Role.kProximity):
            name, shape, frame = inspector.GetName(gid), inspector.GetShape(gid), inspector.GetFrameId(gid)
            body = None if frame == world_frame else plant.GetBodyFromFrameId(frame)
            if body is not None and int(body.model_instance()) in excluded:
                self.excluded.append(name)
                continue
            if not isinstance(shape, SUPPORTED):
                ignored.append(f"{name} ({type(shape).__name__})")
                continue
            is_static = body is None or int(body.index()) in welded
            # a clone: the inspector's shape is a reference into the SceneGraph, whose Python
            # wrapper must not outlive the diagram (see _pose_static)
            (self.static if is_static else self.dynamic).append(_primitive(name, gid, shape))
        for gid, shape in extra:
            if isinstance(shape, SUPPORTED):
                self.static.append(_primitive(inspector.GetName(gid), gid, shape))
            else:
                ignored.append(f"{inspector.GetName(gid)} ({type(shape).__name__})")
        warn_uncut(ignored, "the laser")
        self.height_tolerance = height_tolerance
        self._static_posed = False
        self._static_cache: tuple[float, Section] | None = None
        self._static_arrays: tuple[Section, np.ndarray, np.ndarray] | None = None

    def _pose_static(self, query_object) -> None:
        for prim in self.static:
            X = query_object.GetPoseInWorld(prim.geometry_id)
            # copies: X.translation() is a view that keeps X, the query object and so the
            # context's Python wrapper alive after the diagram is gone; pybind then hands that
            # stale wrapper out for the next context made at the same address, and deletes the
            # new one (a later plant's GetPositionsAndVelocities segfaults on it)
            prim.R, prim.p = np.array(X.rotation().matrix()), np.array(X.translation())
            R = prim.R
            if isinstance(prim.shape, Box) and R[0, 2] == R[1, 2] == R[2, 0] == R[2, 1] == 0.0:
                size = (prim.shape.width(), prim.shape.depth(), prim.shape.height())
                z = box_vertices(prim.R, prim.p, size)[:, 2]
                poly = box_section(prim.R, prim.p, size, 0.5 * (z.min() + z.max()))
                if poly is not None:
                    prim.upright = (poly, float(z.min()), float(z.max()))
            elif prim.hull is not None:
                prim.upright = prism_footprint(prim.hull[0] @ R.T + prim.p)
        self._static_posed = True

    def static_section(self, query_object, height: float) -> Section:
        if not self._static_posed:
            self._pose_static(query_object)
        cached = self._static_cache
        if cached is None or abs(cached[0] - height) > self.height_tolerance:
            section = Section()
            for prim in self.static:
                if prim.upright is not None:
                    poly, zmin, zmax = prim.upright
                    if zmin <= height <= zmax:  # box_section's own test, on the vertices' heights
                        section.polygons.append(poly)
                else:
                    cut(prim.shape, prim.R, prim.p, height, section, prim.hull)
            self._static_cache = cached = (height, section)
        return cached[1]

    def dynamic_section(self, query_object, height: float) -> Section:
        section = Section()
        for prim in self.dynamic:
            X = query_object.GetPoseInWorld(prim.geometry_id)
            cut(prim.shape, X.rotation().matrix(), X.translation(), height, section, prim.hull)
        return section

    def section(self, query_object, height: float) -> Section:
        """Static and dynamic geometry cut at `height`, at the query object's poses."""
        static = self.static_section(query_object, height)
        return static.extend(self.dynamic_section(query_object, height)) if self.dynamic else static

    def arrays(self, query_object, height: float) -> tuple[np.ndarray, np.ndarray]:
        """(segments (N, 4), circles (M, 3)) of `section`, the ray caster's input; the static
        part's arrays are built once per static cut, so a scan in a static world costs no
        Python work per shape."""
        static = self.static_section(query_object, height)
        if self._static_arrays is None or self._static_arrays[0] is not static:
            self._static_arrays = (static, static.segments(), static.circles)
        _, segments, circles = self._static_arrays
        if not self.dynamic:
            return segments, circles
        moving = self.dynamic_section(query_object, height)
        return np.vstack([segments, moving.segments()]), np.vstack([circles, moving.circles])
