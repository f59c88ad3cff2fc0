"""A large world's visuals as merged meshes (world/merged_visuals.py): each shape's surface
closed, wound outwards, of the shape's volume and extent; the OBJ text holds them all."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from pydrake.geometry import Box, Cylinder, Rgba, Sphere
from pydrake.math import RigidTransform, RollPitchYaw

from twil_control.world import merged_visuals
from twil_control.world.extent import shape_box
from twil_control.world.merged_visuals import SEGMENTS, merged_meshes, obj_text, shape_triangles

POSE = RigidTransform(RollPitchYaw(0.3, -0.2, 1.1), [4.0, -2.0, 0.7])
N = SEGMENTS


def _volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    """Signed volume enclosed by triangles (positive when they are wound outwards)."""
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def _edges_pair_up(faces: np.ndarray) -> bool:
    """Closed and consistently wound: every directed edge appears once, its reverse once."""
    edges = [(int(f[k]), int(f[(k + 1) % 3])) for f in faces for k in range(3)]
    return len(set(edges)) == len(edges) and all((b, a) in set(edges) for a, b in edges)


@pytest.mark.parametrize(
    "shape, volume, tolerance",
    [
        (Box(0.5, 0.6, 1.0), 0.3, 1e-12),
        # the inscribed polygon's area times the length
        (Cylinder(0.25, 1.5), 0.5 * N * 0.25**2 * math.sin(2 * math.pi / N) * 1.5, 1e-12),
        (Sphere(0.4), 4.0 / 3.0 * math.pi * 0.4**3, 0.03),  # a polyhedron inside the sphere
    ],
)
def test_each_shape_is_a_closed_outward_surface_of_its_volume(shape, volume, tolerance):
    vertices, faces = shape_triangles(shape, POSE)
    assert _edges_pair_up(faces)
    assert _volume(vertices, faces) == pytest.approx(volume, rel=tolerance)
    # every vertex on the surface: inside the shape's own box at its pose, and, for the round
    # ones, at the radius from the axis or centre
    local = (vertices - POSE.translation()) @ np.asarray(POSE.rotation().matrix())
    if isinstance(shape, Sphere):
        np.testing.assert_allclose(np.linalg.norm(local, axis=1), 0.4, atol=1e-12)
    if isinstance(shape, Cylinder):
        side = np.abs(np.abs(local[:, 2]) - 0.75) > 1e-12
        assert not side.any()  # every vertex on a cap's plane
        radial = np.hypot(local[:, 0], local[:, 1])
        assert np.all((np.abs(radial - 0.25) < 1e-12) | (radial < 1e-12))


@pytest.mark.parametrize("shape", [Box(0.5, 0.6, 1.0), Cylinder(0.25, 1.5), Sphere(0.4)])
def test_an_upright_shape_spans_the_box_the_world_extent_gives_it(shape):
    X = RigidTransform(RollPitchYaw(0.0, 0.0, 0.0), [4.0, -2.0, 0.7])
    vertices, _ = shape_triangles(shape, X)
    low, high = shape_box(shape, np.eye(3), X.translation())
    np.testing.assert_allclose(vertices.min(axis=0), low, atol=1e-12)
    np.testing.assert_allclose(vertices.max(axis=0), high, atol=1e-12)


def test_the_obj_text_holds_every_shape_with_its_own_vertices():
    pieces = [
        shape_triangles(Box(1, 2, 3), POSE),
        shape_triangles(Cylinder(0.5, 2.0), RigidTransform([9, 0, 0])),
    ]
    lines = obj_text(pieces).splitlines()
    vertices = np.array([[float(x) for x in ln.split()[1:]] for ln in lines if ln.startswith("v ")])
    faces = np.array([[int(i) - 1 for i in ln.split()[1:]] for ln in lines if ln.startswith("f ")])
    assert len(vertices) == 8 + 2 * N + 2 and len(faces) == 12 + 4 * N
    assert _edges_pair_up(faces)
    total = sum(_volume(v, f) for v, f in pieces)
    assert _volume(vertices, faces) == pytest.approx(total, rel=1e-6)  # 6 decimals written


def test_visuals_are_merged_a_batch_at_a_time_one_mesh_per_colour(monkeypatch):
    monkeypatch.setattr(merged_visuals, "BATCH", 3)
    red, grey = Rgba(1, 0, 0, 1), Rgba(0.5, 0.5, 0.5, 1)
    visuals = [
        SimpleNamespace(shape=Box(1, 1, 1), X_WG=RigidTransform([2.0 * i, 0, 0]), diffuse=c)
        for i, c in enumerate([red, grey, red, red, red, grey, grey])
    ]
    meshes = merged_meshes(visuals, "w.sdf::visuals")
    assert [(name, rgba) for name, _, rgba in meshes] == [
        ("w.sdf::visuals_0_0", tuple(red.rgba)),
        ("w.sdf::visuals_0_1", tuple(grey.rgba)),
        ("w.sdf::visuals_1_0", tuple(red.rgba)),
        ("w.sdf::visuals_1_1", tuple(grey.rgba)),
        ("w.sdf::visuals_2_0", tuple(grey.rgba)),
    ]
    hull = meshes[0][1].GetConvexHull()  # boxes 0 and 2, 1 x 1 x 1 at x = 0 and x = 4
    corners = np.array([hull.vertex(i) for i in range(hull.num_vertices())])
    np.testing.assert_allclose([corners.min(axis=0), corners.max(axis=0)], [[-0.5] * 3, [4.5, 0.5, 0.5]])
