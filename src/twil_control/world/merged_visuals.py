"""A large world's static visuals drawn as a few triangle meshes instead of thousands of
geometries.

SceneGraph checks each new geometry's name against every geometry of its frame, and anchored
geometry is all in the world frame, so N visuals cost N^2; frames of their own would cost every
step instead. Above `MERGE_ABOVE` static visuals, boxes, cylinders and spheres become one mesh
per colour per `BATCH` shapes, anchored in the world frame: the same surfaces and colours, a few
registrations (docs/inputs.md, "Large worlds").
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
from pydrake.common import MemoryFile
from pydrake.geometry import Box, Cylinder, InMemoryMesh, Mesh, Sphere
from pydrake.math import RigidTransform

from ..mapping.sections import box_vertices

#: static visuals in a world beyond which its boxes, cylinders and spheres are merged
MERGE_ABOVE = 500
#: shapes per mesh: a mesh of 500 boxes is 4,000 vertices, a few hundred kB of OBJ text
BATCH = 500
#: sides of a cylinder's polygon, and of a sphere's parallels (half as many meridian steps)
SEGMENTS = 24

MERGEABLE = (Box, Cylinder, Sphere)

# A box's 12 triangles wound outwards, on the corners in box_vertices' order (x, then y, then z
# from - to +).
_BOX_FACES = np.array(
    [
        [0, 1, 3],
        [0, 3, 2],
        [4, 6, 7],
        [4, 7, 5],
        [0, 4, 5],
        [0, 5, 1],
        [2, 3, 7],
        [2, 7, 6],
        [0, 2, 6],
        [0, 6, 4],
        [1, 5, 7],
        [1, 7, 3],
    ]
)


def _cylinder(n: int) -> tuple[np.ndarray, np.ndarray]:
    """A unit-radius, unit-length cylinder about z: two rings of n and the caps' centres."""
    a = 2.0 * np.pi * np.arange(n) / n
    ring = np.column_stack([np.cos(a), np.sin(a)])
    vertices = np.vstack(
        [
            np.column_stack([ring, np.full(n, -0.5)]),
            np.column_stack([ring, np.full(n, 0.5)]),
            [[0.0, 0.0, -0.5], [0.0, 0.0, 0.5]],
        ]
    )
    i, j = np.arange(n), (np.arange(n) + 1) % n
    sides = np.vstack([np.column_stack([i, j, j + n]), np.column_stack([i, j + n, i + n])])
    caps = np.vstack(
        [np.column_stack([np.full(n, 2 * n), j, i]), np.column_stack([np.full(n, 2 * n + 1), i + n, j + n])]
    )
    return vertices, np.vstack([sides, caps])


def _sphere(n: int) -> tuple[np.ndarray, np.ndarray]:
    """A unit sphere: n/2 - 1 parallels of n points between the poles."""
    rows = n // 2
    polar = np.pi * np.arange(1, rows) / rows
    a = 2.0 * np.pi * np.arange(n) / n
    ring = np.column_stack(
        [
            np.outer(np.sin(polar), np.cos(a)).ravel(),
            np.outer(np.sin(polar), np.sin(a)).ravel(),
            np.repeat(np.cos(polar), n),
        ]
    )
    north, south = (rows - 1) * n, (rows - 1) * n + 1
    vertices = np.vstack([ring, [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]])
    i, j = np.arange(n), (np.arange(n) + 1) % n
    faces = [
        np.column_stack([np.full(n, north), i, j]),
        np.column_stack([np.full(n, south), (rows - 2) * n + j, (rows - 2) * n + i]),
    ]
    for r in range(rows - 2):
        top, low = r * n, (r + 1) * n
        faces += [np.column_stack([top + i, low + j, top + j]), np.column_stack([top + i, low + i, low + j])]
    return vertices, np.vstack(faces)


_UNIT = {Cylinder: _cylinder(SEGMENTS), Sphere: _sphere(SEGMENTS)}


def shape_triangles(shape, X_WG: RigidTransform) -> tuple[np.ndarray, np.ndarray]:
    """A box's, cylinder's or sphere's surface in the world: vertices (n x 3) and triangles
    (m x 3 vertex indices), wound outwards."""
    R, p = np.asarray(X_WG.rotation().matrix()), np.asarray(X_WG.translation())
    if isinstance(shape, Box):
        return box_vertices(R, p, (shape.width(), shape.depth(), shape.height())), _BOX_FACES
    vertices, faces = _UNIT[type(shape)]
    if isinstance(shape, Cylinder):
        scale = np.array([shape.radius(), shape.radius(), shape.length()])
    else:
        scale = np.full(3, shape.radius())
    return (vertices * scale) @ R.T + p, faces


def obj_text(pieces: Iterable[tuple[np.ndarray, np.ndarray]]) -> str:
    """Wavefront OBJ of several surfaces in one mesh (no normals: viewers shade each triangle
    flat, as the shapes' faces are)."""
    lines, offset = [], 1
    for vertices, faces in pieces:
        lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in vertices.tolist()]
        lines += [f"f {a} {b} {c}" for a, b, c in (faces + offset).tolist()]
        offset += len(vertices)
    return "\n".join(lines) + "\n"


def merged_meshes(visuals: list, name: str) -> list[tuple[str, Mesh, tuple]]:
    """(name, mesh, rgba) for `visuals` (objects with .shape, .X_WG, .diffuse; mergeable
    shapes only), grouped `BATCH` at a time in their order, one mesh per colour in a batch."""
    out = []
    for start in range(0, len(visuals), BATCH):
        by_colour: dict[tuple, list] = {}
        for v in visuals[start : start + BATCH]:
            by_colour.setdefault(tuple(v.diffuse.rgba), []).append(v)
        for k, (rgba, group) in enumerate(by_colour.items()):
            label = f"{name}_{start // BATCH}_{k}"
            text = obj_text(shape_triangles(v.shape, v.X_WG) for v in group)
            out.append((label, Mesh(InMemoryMesh(mesh_file=MemoryFile(text, ".obj", label))), rgba))
    return out
