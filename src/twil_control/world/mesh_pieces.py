"""A static collision mesh as convex pieces, so that it collides as Gazebo's does (its surface).

Drake's point contact sees a collision mesh as its convex hull, and TurtleBot3's hexagon wall is
one open mesh around the whole arena: its hull would fill the arena. So each connected part
becomes its hull when it is closed and convex, else one thin slab (``SLAB`` each side) per flat
convex patch of its surface. Above ``MAX_PIECES`` the mesh stays whole, with a warning:
SceneGraph's pair table grows with the square of the collision geometries (docs/robots.md).
"""

from __future__ import annotations

import logging

import numpy as np
from pydrake.geometry import Convex

from ..mapping.sections import convex_hull, polygon_area

log = logging.getLogger("twil_control.static_world")

#: Half the thickness of a slab standing for a flat patch of a mesh's surface (m): thin enough
#: that the laser sees the surface within it, thick enough that a robot cannot pass through.
SLAB = 0.005
MAX_PIECES = 500
_TOLERANCE = 1e-6


def mesh_triangles(shape) -> tuple[np.ndarray, np.ndarray]:
    """(vertices (V, 3), faces (F, 3)) of a Drake Mesh read from its file, scaled."""
    import trimesh

    mesh = trimesh.load(shape.source().path(), force="mesh", process=False)
    return np.asarray(mesh.vertices, dtype=float) * np.asarray(shape.scale3()), np.asarray(mesh.faces)


def convex_pieces(vertices: np.ndarray, faces: np.ndarray, label: str) -> list[np.ndarray] | None:
    """The pieces' points ((3, K) arrays, in the mesh frame), or None when the mesh has more than
    MAX_PIECES of them (the caller keeps its hull)."""
    points, inverse = np.unique(np.round(vertices, 9), axis=0, return_inverse=True)
    tri = inverse.reshape(-1)[faces]
    a, b, c = points[tri[:, 0]], points[tri[:, 1]], points[tri[:, 2]]
    normals = np.cross(b - a, c - a)
    area2 = np.linalg.norm(normals, axis=1)
    keep = area2 > 2 * _TOLERANCE**2
    tri, normals = tri[keep], normals[keep] / area2[keep, None]
    if len(tri) == 0:
        return []
    pieces: list[np.ndarray] = []
    for part in _components(tri, len(points), same_plane=None):
        faces_k = tri[part]
        used = np.unique(faces_k)
        if _closed(faces_k) and _convex(points[used], points[faces_k[:, 0]], normals[part]):
            pieces.append(points[used].T.copy())
            continue
        planes = _plane_keys(points[faces_k[:, 0]], normals[part])
        for patch in _components(faces_k, len(points), same_plane=planes):
            pieces += _slabs(points, faces_k[patch], normals[part][patch[0]])
        if len(pieces) > MAX_PIECES:
            log.warning(
                "%s: more than %d convex pieces; it collides as its convex hull (a concave mesh "
                "fills in): give the world a simpler collision mesh or primitive shapes",
                label,
                MAX_PIECES,
            )
            return None
    return pieces


def convex_shapes(pieces: list[np.ndarray], label: str) -> list[Convex]:
    return [Convex(piece, f"{label}_{k}") for k, piece in enumerate(pieces)]


def _components(tri: np.ndarray, n_points: int, same_plane) -> list[np.ndarray]:
    """Groups of faces joined through shared edges (and, with `same_plane`, in one plane)."""
    edges = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    face = np.tile(np.arange(len(tri)), 3)
    key = edges[:, 0] * n_points + edges[:, 1]
    order = np.argsort(key, kind="stable")
    key, face = key[order], face[order]
    pairs = np.flatnonzero(key[1:] == key[:-1])
    i, j = face[pairs], face[pairs + 1]
    if same_plane is not None:
        keep = same_plane[i] == same_plane[j]
        i, j = i[keep], j[keep]
    # imported here: scipy.sparse costs about 0.5 s of CPU to import, and only meshes need it
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    graph = coo_matrix((np.ones(len(i)), (i, j)), shape=(len(tri), len(tri)))
    count, labels = connected_components(graph, directed=False)
    return [np.flatnonzero(labels == k) for k in range(count)]


def _closed(tri: np.ndarray) -> bool:
    """Every edge is shared by exactly two faces."""
    edges = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return bool(np.all(counts == 2))


def _convex(points: np.ndarray, on_face: np.ndarray, normals: np.ndarray) -> bool:
    """Every point lies on one side of every face's plane."""
    if len(points) * len(normals) > 4_000_000:
        return False
    side = np.einsum("fk,fvk->fv", normals, points[None, :, :] - on_face[:, None, :])
    scale = max(float(np.ptp(points, axis=0).max()), 1.0)
    tol = 1e-7 * scale
    return bool(np.all((side <= tol).all(axis=1) | (side >= -tol).all(axis=1)))


def _plane_keys(on_face: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """One integer per face, equal for faces in one plane (either facing)."""
    n = (
        normals
        * np.where(
            (normals[:, 0] < -_TOLERANCE)
            | ((np.abs(normals[:, 0]) <= _TOLERANCE) & (normals[:, 1] < -_TOLERANCE))
            | (
                (np.abs(normals[:, 0]) <= _TOLERANCE)
                & (np.abs(normals[:, 1]) <= _TOLERANCE)
                & (normals[:, 2] < 0)
            ),
            -1.0,
            1.0,
        )[:, None]
    )
    d = np.einsum("fk,fk->f", n, on_face)
    keys = np.round(np.column_stack([n, d]) / 1e-6).astype(np.int64)
    _, index = np.unique(keys, axis=0, return_inverse=True)
    return index.reshape(-1)


def _slabs(points: np.ndarray, tri: np.ndarray, normal: np.ndarray) -> list[np.ndarray]:
    """A coplanar patch as one slab when it is convex, else one slab per triangle."""
    u = np.cross(normal, [1.0, 0.0, 0.0] if abs(normal[0]) < 0.9 else [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    w = np.cross(normal, u)
    origin = points[tri[0, 0]]
    used = np.unique(tri)
    flat = (points[used] - origin) @ np.column_stack([u, w])
    hull = convex_hull(flat)
    area = (
        0.5
        * np.linalg.norm(
            np.cross(points[tri[:, 1]] - points[tri[:, 0]], points[tri[:, 2]] - points[tri[:, 0]]), axis=1
        ).sum()
    )
    if len(hull) >= 3 and abs(polygon_area(hull) - area) <= 1e-6 * max(area, 1e-9):
        polygons = [origin + hull @ np.vstack([u, w])]
    else:
        polygons = [points[t] for t in tri]
    offset = SLAB * normal
    return [np.vstack([p + offset, p - offset]).T.copy() for p in polygons]
