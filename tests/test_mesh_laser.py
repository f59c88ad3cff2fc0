"""The laser sees meshes and the robot collides with them as Gazebo's does, in TurtleBot3's world
(vendored turtlebot3_gazebo: a hexagon wall and five pillars that are DAE meshes, nine
cylinders): static meshes as convex pieces that follow their surface (world/mesh_pieces.py),
cut by the laser (world/laser_scene.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh
from support.ros_env import use_packages

from twil_control import PACKAGE_ROOT
from twil_control.description import meshes
from twil_control.mapping import raycast
from twil_control.world.laser_scene import LaserScene
from twil_control.world.mesh_pieces import SLAB
from twil_control.world.simulation import Simulation

VENDOR = PACKAGE_ROOT / "tests" / "data" / "ros1" / "vendor"
TB3 = VENDOR / "turtlebot3_gazebo"
WORLD = TB3 / "worlds" / "turtlebot3_world.world"
MESHES = TB3 / "models" / "turtlebot3_world" / "meshes"
HEIGHT = 0.135  # the qbot's scan plane

#: turtlebot3_world's model (models/turtlebot3_world/model.sdf): mesh, scale, x, y, z, yaw
MESH_POSES = [
    ("hexagon.dae", 0.8, 3.5, 0.0, -0.5, 0.0),
    ("hexagon.dae", 0.55, 1.8, 2.7, 0.0, 0.0),
    ("hexagon.dae", 0.55, 1.8, -2.7, 0.0, 0.0),
    ("hexagon.dae", 0.55, -1.8, 2.7, 0.0, 0.0),
    ("hexagon.dae", 0.55, -1.8, -2.7, 0.0, 0.0),
    ("wall.dae", 0.25, 0.0, 0.0, -0.3, -1.5708),
]
CYLINDERS = [(x, y) for x in (-1.1, 0.0, 1.1) for y in (-1.1, 0.0, 1.1)]  # radius 0.15, 0 .. 0.5 m


@pytest.fixture(autouse=True)
def _env(monkeypatch, tmp_path_factory):
    use_packages(monkeypatch, tmp_path_factory, VENDOR, without_gazebo_paths=True)


def _reference_segments(height: float = HEIGHT) -> tuple[np.ndarray, np.ndarray]:
    """The world's mesh triangles cut at `height`, read here with trimesh from the DAE files (in
    metres, as their <unit meter="0.0254"/> says): segments (N, 4) and their unit normals (N, 2)."""
    segments, normals = [], []
    for name, scale, x, y, z, yaw in MESH_POSES:
        mesh = trimesh.load(MESHES / name, force="mesh", process=False)
        mesh.convert_units("meters")
        c, s = math.cos(yaw), math.sin(yaw)
        v = np.asarray(mesh.vertices) * scale
        v = np.column_stack([c * v[:, 0] - s * v[:, 1] + x, s * v[:, 0] + c * v[:, 1] + y, v[:, 2] + z])
        for a, b, cc in v[np.asarray(mesh.faces)]:
            points = []
            for p, q in ((a, b), (b, cc), (cc, a)):
                if (p[2] - height) * (q[2] - height) < 0:
                    t = (height - p[2]) / (q[2] - p[2])
                    points.append(p[:2] + t * (q[:2] - p[:2]))
            if len(points) == 2:
                n = np.cross(b - a, cc - a)[:2]
                segments.append([*points[0], *points[1]])
                normals.append(n / np.linalg.norm(n))
    return np.array(segments), np.array(normals)


def _reference_ranges(x, y, angles, segments, normals):
    """(range, kind, cos of incidence) per beam: kind 0 nothing, 1 a mesh, 2 a cylinder."""
    d = np.column_stack([np.cos(angles), np.sin(angles)])
    out = np.full(len(angles), np.inf)
    kind = np.zeros(len(angles), dtype=int)
    cosine = np.ones(len(angles))
    p, e = segments[:, :2] - [x, y], segments[:, 2:] - segments[:, :2]
    for k, (dx, dy) in enumerate(d):
        denom = dx * e[:, 1] - dy * e[:, 0]
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (p[:, 0] * e[:, 1] - p[:, 1] * e[:, 0]) / denom
            u = (p[:, 0] * dy - p[:, 1] * dx) / denom
        hit = (t > 0) & (u >= 0) & (u <= 1)
        if hit.any():
            j = np.flatnonzero(hit)[np.argmin(t[hit])]
            out[k], kind[k], cosine[k] = t[j], 1, abs(normals[j] @ [dx, dy])
        for cx, cy in CYLINDERS:
            f = np.array([x - cx, y - cy])
            b, c = f @ [dx, dy], f @ f - 0.15**2
            if b * b - c >= 0 and -b - math.sqrt(b * b - c) > 0 and -b - math.sqrt(b * b - c) < out[k]:
                out[k], kind[k] = -b - math.sqrt(b * b - c), 2
    return out, kind, cosine


def _distance_to(points: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """Each point's distance to the nearest segment."""
    a, b = segments[None, :, :2], segments[None, :, 2:]
    p = points[:, None, :]
    t = np.clip(((p - a) * (b - a)).sum(-1) / ((b - a) ** 2).sum(-1), 0.0, 1.0)
    return np.linalg.norm(a + t[..., None] * (b - a) - p, axis=-1).min(axis=1)


def _world_with_qbot(x: float = -2.0, y: float = -0.5, yaw: float = 0.0) -> Simulation:
    sim = Simulation()
    sim.add_world(WORLD)
    sim.spawn("qbot", "qbot", x=x, y=y, yaw=yaw)
    sim.finalize()
    sim.build()
    return sim


def test_a_dae_mesh_is_converted_in_metres_as_its_unit_says():
    wall = trimesh.load(meshes.convert(MESHES / "wall.dae", (0.25, 0.25, 0.25)), force="mesh")
    # the outer hexagon's vertex at 519.615 inches, the wall 200 inches high, scaled by 0.25
    np.testing.assert_allclose(
        wall.bounds[1], [450 * 0.0254 / 4, 519.615 * 0.0254 / 4, 200 * 0.0254 / 4], rtol=1e-6
    )


def test_the_laser_sees_the_hexagon_wall_and_the_pillars_within_the_slab_of_their_surface():
    sim = _world_with_qbot()
    root = sim.simulator.get_context()
    query = sim.scene_graph.get_query_output_port().Eval(sim.scene_graph.GetMyContextFromRoot(root))
    scene = LaserScene(sim.plant, sim.scene_graph.model_inspector(), sim.robot_instances("qbot"))
    segments, circles = scene.arrays(query, HEIGHT)
    reference, normals = _reference_segments()
    angles = np.linspace(-math.pi, math.pi, 640, endpoint=False)
    counts = np.zeros(3, dtype=int)
    for x, y in ((-2.0, -0.5), (0.55, 1.9), (2.3, -0.4), (-0.55, -2.2)):
        ranges = raycast.cast(x, y, 0.0, -math.pi, 2 * math.pi / 640, 640, segments, circles)
        expected, kind, cosine = _reference_ranges(x, y, angles, reference, normals)
        assert np.isfinite(ranges).all() and (kind > 0).all()  # the wall closes the arena
        counts += np.bincount(kind, minlength=3)
        exact = kind == 2
        np.testing.assert_allclose(ranges[exact], expected[exact], atol=1e-6)  # cylinders
        # a mesh is seen on its slab's near face: never beyond the surface, and every return
        # within SLAB of it (on a flat face, exactly SLAB nearer along its normal)
        mesh = kind == 1
        assert (ranges[mesh] <= expected[mesh] + 1e-6).all()
        hits = np.column_stack([x + ranges * np.cos(angles), y + ranges * np.sin(angles)])[mesh]
        assert _distance_to(hits, reference).max() <= SLAB + 1e-6
        flat = (expected - ranges)[mesh] * cosine[mesh]
        assert np.median(flat) == pytest.approx(SLAB, abs=1e-6)
    assert counts[1] > 1500 and counts[2] > 150  # mesh walls and pillars, and cylinders, were seen


def test_the_robot_rests_inside_the_hexagon_wall_and_stops_at_it():
    sim = _world_with_qbot(x=-2.0, y=0.0, yaw=math.pi)  # facing the wall's corner at x = -2.93
    plant = sim.plant
    context = sim.plant_context(sim.simulator.get_mutable_context())
    base = plant.GetBodyByName("base_link")
    sim.simulator.AdvanceTo(0.5)
    start = plant.EvalBodyPoseInWorld(context, base).translation().copy()
    assert start[2] == pytest.approx(0.055, abs=0.002)  # on the ground, not thrown out of a hull
    plant.get_actuation_input_port().FixValue(context, np.full(4, 0.3))  # N m on every wheel
    sim.simulator.AdvanceTo(3.5)
    end = plant.EvalBodyPoseInWorld(context, base).translation()
    # the front wheels (spheres of 0.055 m, 0.25 m ahead and 0.18 m aside of base_link) stop
    # against the two wall faces that meet at the inner corner x = -2.9331 (120 degrees apart,
    # each 30 degrees off the robot's heading), the slab's 5 mm included
    corner = -461.88 * 0.0254 * 0.25
    stop = corner + (0.055 + SLAB + 0.18 * math.sin(math.radians(30))) / math.cos(math.radians(30)) + 0.25
    assert end[0] == pytest.approx(stop, abs=0.003)  # -2.510; a hull would have thrown it out
    assert abs(end[1]) < 0.01 and end[2] == pytest.approx(0.055, abs=0.002)


@pytest.mark.slow
def test_turtlebot3_world_launch_as_it_is_the_burger_sees_the_hexagon_and_the_pillars(tmp_path, monkeypatch):
    from conftest import read_bag

    from twil_control.launch.loader import load_launch
    from twil_control.launch.runner import RunOptions, run

    monkeypatch.setenv("TURTLEBOT3_MODEL", "burger")
    plan = load_launch(TB3 / "launch" / "turtlebot3_world.launch")
    result = run(plan, RunOptions(duration=1.0, bag=tmp_path / "tb3.bag"))
    assert result.error is None
    bag = read_bag(result.bag)
    odom = bag["/odom"][-1][1].pose.pose.position
    assert (odom.x, odom.y) == (
        pytest.approx(-2.0, abs=1e-3),
        pytest.approx(-0.5, abs=1e-3),
    )  # its spawn pose
    # the LDS (base_scan: 0.032 m behind base_link, 0.182 m above the ground) at rest there
    x, y = -2.0 - 0.032, -0.5
    reference, normals = _reference_segments(height=0.182)
    scans = [m for _, m in bag["/scan"]]
    assert len(scans) == 5 and all(len(s.ranges) == 360 for s in scans)  # 5 Hz, 360 beams
    angles = scans[0].angle_min + scans[0].angle_increment * np.arange(360)
    expected, kind, _ = _reference_ranges(x, y, angles, reference, normals)
    seen = (expected < 3.5) & (kind > 0)  # range_max 3.5 m: the far wall is out of reach
    assert seen.sum() > 300 and (kind[seen] == 1).sum() > 200 and (kind[seen] == 2).sum() > 10
    errors = np.concatenate([np.asarray(s.ranges)[seen] - expected[seen] for s in scans])
    # Gaussian noise of stddev 0.01 m, readings rounded to 0.015 m, the slab's 5 mm
    assert np.median(np.abs(errors)) < 0.012 and np.mean(np.abs(errors) < 0.045) > 0.99
