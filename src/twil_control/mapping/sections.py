"""Horizontal cross-sections of 3D primitives: what a planar laser (or a map) sees at a height.

Pure numpy. Boxes give convex polygons, spheres and upright cylinders circles, and a tilted
cylinder a 32-sided inscribed prism (docs/slam.md). `Section` gathers a scene's polygons
(counter-clockwise) and circles; `Section.segments()` gives the edges in the ray caster's form.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import product

import numpy as np

#: Sides of the prism a tilted cylinder is cut as.
PRISM_SIDES = 32
_UPRIGHT_TOL = 1e-6
_AREA_EPS = 1e-12


@dataclass
class Section:
    """2D shapes of a scene cut at one height (world x, y in metres)."""

    polygons: list[np.ndarray] = field(default_factory=list)  # each (K, 2), convex, CCW
    circles: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))  # (M, 3): cx, cy, r

    def segments(self) -> np.ndarray:
        """Every polygon edge as a row [x0, y0, x1, y1]; (0, 4) when there are none."""
        if not self.polygons:
            return np.zeros((0, 4))
        return np.concatenate([np.hstack([p, np.roll(p, -1, axis=0)]) for p in self.polygons])

    def extend(self, other: Section) -> Section:
        """A new Section holding the shapes of both."""
        return Section(self.polygons + other.polygons, np.vstack([self.circles, other.circles]))

    def bounds(self) -> tuple[float, float, float, float] | None:
        """(xmin, ymin, xmax, ymax) of every shape, or None for an empty section."""
        pts = [p for p in self.polygons]
        c = self.circles
        if len(c):
            pts.append(np.column_stack([c[:, 0] - c[:, 2], c[:, 1] - c[:, 2]]))
            pts.append(np.column_stack([c[:, 0] + c[:, 2], c[:, 1] + c[:, 2]]))
        if not pts:
            return None
        allp = np.vstack(pts)
        return (*allp.min(axis=0), *allp.max(axis=0))

    def __len__(self) -> int:
        return len(self.polygons) + len(self.circles)


def convex_hull(points: np.ndarray) -> np.ndarray:
    """Counter-clockwise convex hull of 2D points (monotone chain), duplicates and collinear
    points removed; fewer than 3 points come back as they are (deduplicated)."""
    pts = np.unique(np.round(np.asarray(points, dtype=float), 12), axis=0)  # sorted by x, then y
    if len(pts) < 3:
        return pts

    def half(seq):
        chain: list[np.ndarray] = []
        for p in seq:
            while len(chain) >= 2 and _cross(chain[-2], chain[-1], p) <= 0:
                chain.pop()
            chain.append(p)
        return chain

    lower, upper = half(pts), half(pts[::-1])
    return np.array(lower[:-1] + upper[:-1])


def _cross(o, a, b) -> float:
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def polygon_area(poly: np.ndarray) -> float:
    """Signed area (positive for counter-clockwise vertices), shoelace formula."""
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def convex_section(vertices: np.ndarray, edges: np.ndarray, height: float) -> np.ndarray | None:
    """The polygon where the plane z = height cuts a convex polyhedron, given its vertices (V, 3)
    and edges (E, 2) as vertex-index pairs; None when the plane misses it or only touches it."""
    a, b = vertices[edges[:, 0]], vertices[edges[:, 1]]
    da, db = a[:, 2] - height, b[:, 2] - height
    crossing = (da * db <= 0) & (da != db)
    s = da[crossing] / (da[crossing] - db[crossing])
    points = a[crossing, :2] + s[:, None] * (b[crossing, :2] - a[crossing, :2])
    on_plane = vertices[vertices[:, 2] == height, :2]
    hull = convex_hull(np.vstack([points, on_plane])) if len(points) + len(on_plane) else None
    if hull is None or len(hull) < 3 or polygon_area(hull) <= _AREA_EPS:
        return None
    return hull


_BOX_CORNERS = np.array(list(product((-1, 1), repeat=3)), dtype=float)  # 8 sign triples
_BOX_EDGES = np.array(
    [
        (i, j)
        for i in range(8)
        for j in range(i + 1, 8)
        if np.count_nonzero(_BOX_CORNERS[i] != _BOX_CORNERS[j]) == 1
    ]
)


def box_vertices(R: np.ndarray, p: np.ndarray, size) -> np.ndarray:
    """The 8 corners (8, 3) of a box of full `size` (x, y, z) centred at p with orientation R."""
    half = 0.5 * np.asarray(size, dtype=float)
    return p + (_BOX_CORNERS * half) @ np.asarray(R).T


def box_section(R: np.ndarray, p: np.ndarray, size, height: float) -> np.ndarray | None:
    """Section of a box of full `size` (x, y, z) centred at p with orientation R."""
    R = np.asarray(R)
    if R[0, 2] == R[1, 2] == R[2, 0] == R[2, 1] == 0.0:
        return _upright_box_section(R, p, size, height)
    return convex_section(box_vertices(R, p, size), _BOX_EDGES, height)


def _upright_box_section(R: np.ndarray, p: np.ndarray, size, height: float) -> np.ndarray | None:
    """A box with a vertical axis: every cut between its faces (both included) is its
    footprint, the polygon convex_section gives (the same vertices, rounded and ordered as
    convex_hull orders them) without a hull per box (worlds of thousands of boxes)."""
    half = 0.5 * np.asarray(size, dtype=float)
    top, bottom = p[2] + half[2] * R[2, 2], p[2] - half[2] * R[2, 2]  # as box_vertices rounds them
    if not min(top, bottom) <= height <= max(top, bottom) or half[0] * half[1] * 4.0 <= _AREA_EPS:
        return None
    poly = np.round(p[:2] + (_SQUARE * half[:2]) @ R[:2, :2].T, 12)
    if R[0, 0] * R[1, 1] - R[0, 1] * R[1, 0] < 0:  # an upside-down box mirrors its footprint
        poly = poly[::-1]
    first = min(range(4), key=lambda k: (poly[k, 0], poly[k, 1]))
    return np.roll(poly, -first, axis=0)


_SQUARE = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])  # counter-clockwise


def sphere_section(p: np.ndarray, radius: float, height: float) -> np.ndarray | None:
    """(cx, cy, r) of the circle where z = height cuts a sphere, or None."""
    dz = height - p[2]
    if abs(dz) >= radius:
        return None
    return np.array([p[0], p[1], np.sqrt(radius * radius - dz * dz)])


def _prism(R, p, radius, length, sides=PRISM_SIDES):
    phi = 2 * np.pi * np.arange(sides) / sides
    ring = np.column_stack([radius * np.cos(phi), radius * np.sin(phi)])
    local = np.vstack([np.column_stack([ring, np.full(sides, z)]) for z in (-length / 2, length / 2)])
    vertices = p + local @ np.asarray(R).T
    k = np.arange(sides)
    edges = np.vstack(
        [
            np.column_stack([k, (k + 1) % sides]),  # bottom ring
            np.column_stack([k + sides, (k + 1) % sides + sides]),  # top ring
            np.column_stack([k, k + sides]),
        ]
    )  # sides
    return vertices, edges


def cylinder_section(
    R: np.ndarray, p: np.ndarray, radius: float, length: float, height: float
) -> tuple[str, np.ndarray] | None:
    """Section of a cylinder (axis = R's z column, centred at p): ("circle", (cx, cy, r)) when
    it is upright, ("polygon", vertices) when tilted (cut as an inscribed prism), or None."""
    axis = np.asarray(R)[:, 2]
    if abs(abs(axis[2]) - 1.0) <= _UPRIGHT_TOL:
        if abs(height - p[2]) > length / 2:
            return None
        return "circle", np.array([p[0], p[1], radius])
    poly = convex_section(*_prism(R, p, radius, length), height)
    return None if poly is None else ("polygon", poly)
