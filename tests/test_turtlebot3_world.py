"""TurtleBot3 in turtlebot3_world as its e-manual runs it, from the packages' own launch files
(noetic branches, vendored unchanged under tests/data/ros1/vendor) with the user's side in
tests/data/ros1/tryout: SLAM (turtlebot3_world.launch + turtlebot3_slam.launch with gmapping, a
timed cmd_vel sequence driving the burger, map_saver) and navigation on the package's saved map
(turtlebot3_navigation.launch: map_server, amcl.launch, move_base.launch; a 2D Pose Estimate on
/initialpose and 2D Nav Goals on /move_base_simple/goal). Judged against the simulator's truth
(/gazebo/model_states) and the world cut at the laser's height (tools.rasterize)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import read_bag
from support.model_truth import model_truth
from support.model_truth import yaw as heading
from support.ros_env import use_packages

from twil_control import PACKAGE_ROOT
from twil_control.bag.analyses.map_quality import compare_grids
from twil_control.bag.analyze import analyze_bag
from twil_control.launch.__main__ import main
from twil_control.mapping.map_io import read_map

ROS1 = PACKAGE_ROOT / "tests" / "data" / "ros1"
VENDOR = ROS1 / "vendor"
TRYOUT = ROS1 / "tryout"
WORLD_LAUNCH = VENDOR / "turtlebot3_gazebo" / "launch" / "turtlebot3_world.launch"
#: the burger's LDS above the floor: base_link 0.010 m over base_footprint, base_scan 0.172 m over it
SCAN_HEIGHT = 0.182
SCAN_X = -0.032  # base_scan ahead of base_footprint
PILLARS = [(x, y) for x in (-1.1, 0.0, 1.1) for y in (-1.1, 0.0, 1.1)]
PILLAR_RADIUS = 0.15


@pytest.fixture(autouse=True)
def _env(monkeypatch, tmp_path_factory):
    monkeypatch.setenv("TURTLEBOT3_MODEL", "burger")
    use_packages(monkeypatch, tmp_path_factory, VENDOR, without_gazebo_paths=True)


def _at(truth: np.ndarray, t: float) -> np.ndarray:
    """The true (x, y, yaw) at time t, interpolated (yaw unwrapped)."""
    yaw = np.unwrap(truth[:, 3])
    return np.array(
        [np.interp(t, truth[:, 0], truth[:, k]) for k in (1, 2)] + [np.interp(t, truth[:, 0], yaw)]
    )


def _world_map(tmp_path):
    from twil_control.tools.rasterize import main as rasterize

    world = VENDOR / "turtlebot3_gazebo" / "worlds" / "turtlebot3_world.world"
    assert rasterize([str(world), "-o", str(tmp_path / "world"), "--height", str(SCAN_HEIGHT)]) == 0
    return read_map(tmp_path / "world.yaml")


def _near_pillars(points: np.ndarray, tolerance: float) -> np.ndarray:
    """Per pillar, how many of the points lie within `tolerance` of its surface."""
    d = np.hypot(
        points[:, None, 0] - np.array(PILLARS)[None, :, 0], points[:, None, 1] - np.array(PILLARS)[None, :, 1]
    )
    return (np.abs(d - PILLAR_RADIUS) < tolerance).sum(axis=0)


@pytest.mark.slow
def test_slam_with_gmapping_maps_the_pillars_and_the_hexagon_wall(tmp_path):
    bag_path, saved = tmp_path / "slam.bag", tmp_path / "tb3_map"
    files = [str(WORLD_LAUNCH), str(VENDOR / "turtlebot3_slam/launch/turtlebot3_slam.launch")]
    files.append(str(TRYOUT / "tb3_world_drive.launch"))
    args = ["slam_methods:=gmapping", "open_rviz:=false", f"map_file:={saved}"]
    assert main([*files, *args, "--duration", "17", "--bag", str(bag_path)]) == 0
    bag = read_bag(bag_path, ["/gazebo/model_states", "/scan"])
    truth = model_truth(bag, "turtlebot3_burger")
    # spawned where turtlebot3_world.launch puts it, (-2, -0.5) facing +x; driven east from
    # t = 0 (tb3_world_cmd_sequence.yaml), the plugin's wheelAcceleration ramping it up to
    # 0.2 m/s: at the first sample (0.1 s) under 0.015 m on, then straight at 0.2 m/s
    assert truth[0, 0] == pytest.approx(0.1) and truth[0, 1] - (-2.0) == pytest.approx(0.0075, abs=0.0075)
    driving = truth[(truth[:, 0] > 2.0) & (truth[:, 0] < 15.0)]
    assert np.polyfit(driving[:, 0], driving[:, 1], 1)[0] == pytest.approx(0.2, abs=0.005)
    assert np.abs(truth[truth[:, 0] < 15.0, 2] + 0.5).max() < 0.01 and np.abs(driving[:, 3]).max() < 0.02
    # its scans, put in the world by the true pose: every pillar seen, every return on the
    # world's surfaces (the pillars, the hexagon wall) within a cell
    world = _world_map(tmp_path)
    points = []
    for t, m in bag["/scan"]:
        x, y, yaw = _at(truth, t * 1e-9)
        r = np.array(m.ranges)
        a = m.angle_min + m.angle_increment * np.arange(len(r))
        keep = np.isfinite(r)
        sx, sy = x + SCAN_X * math.cos(yaw), y + SCAN_X * math.sin(yaw)
        points.append(
            np.column_stack([sx + r[keep] * np.cos(yaw + a[keep]), sy + r[keep] * np.sin(yaw + a[keep])])
        )
    points = np.concatenate(points)
    assert _near_pillars(points, 0.05).min() > 200  # 389 to 1660 measured
    on_world = compare_grids(
        *_points_grid(points, world.resolution), world.data, world.resolution, world.origin
    )
    assert on_world["precision"] > 0.99  # 1.0 measured
    # gmapping's last map (bag analyze's map quality against the world: its occupied cells on
    # the world's within a cell, 0.998 measured, and of the world's cells it observed, those it
    # holds, 0.948), each pillar in it, and the map map_saver wrote against the map the package
    # ships of this world (maps/map.pgm, made by gmapping in Gazebo): its cells on the package
    # map's (0.998), and the package map's hexagon wall in it (0.86 of its cells)
    quality = analyze_bag(bag_path, ground_truth_map=tmp_path / "world.yaml")["mapping"]
    assert quality["map_precision"] > 0.97 and quality["map_recall_observed"] > 0.9
    mine = read_map(saved.with_suffix(".yaml"))
    assert _near_pillars(_cell_centres(mine), 0.08).min() >= 10  # 13 to 20 cells measured
    package_map = read_map(VENDOR / "turtlebot3_navigation/maps/map.yaml")
    against_package = compare_grids(
        mine.data, mine.resolution, mine.origin, package_map.data, package_map.resolution, package_map.origin
    )
    assert against_package["precision"] > 0.97
    wall = _largest_part(package_map)
    wall_found = compare_grids(
        wall, package_map.resolution, package_map.origin, mine.data, mine.resolution, mine.origin
    )
    assert wall_found["precision"] > 0.75


def _largest_part(m) -> np.ndarray:
    """The grid with only its largest connected set of occupied cells (in turtlebot3_world's
    map, the hexagon wall) occupied, the rest unknown."""
    from scipy import ndimage

    occupied = np.asarray(m.data) >= 65
    labels, n = ndimage.label(occupied, structure=np.ones((3, 3)))
    largest = 1 + int(np.argmax(ndimage.sum(occupied, labels, range(1, n + 1))))
    return np.where(labels == largest, 100, -1).astype(np.int8)


def _cell_centres(m) -> np.ndarray:
    rows, cols = np.nonzero(np.asarray(m.data) >= 65)
    return np.column_stack(
        [m.origin[0] + (cols + 0.5) * m.resolution, m.origin[1] + (rows + 0.5) * m.resolution]
    )


def _points_grid(points: np.ndarray, resolution: float):
    """An occupancy grid of points (100 where a point falls, unknown elsewhere) on a grid
    covering them, for compare_grids."""
    x0, y0 = np.floor(points.min(axis=0) / resolution) * resolution - resolution
    cols = np.floor((points[:, 0] - x0) / resolution).astype(int)
    rows = np.floor((points[:, 1] - y0) / resolution).astype(int)
    grid = np.full((rows.max() + 2, cols.max() + 2), -1, np.int8)
    grid[rows, cols] = 100
    return grid, resolution, (x0, y0, 0.0)


@pytest.mark.slow
def test_the_e_manual_navigation_reaches_five_goals_round_the_pillars_with_amcl_on_the_truth(tmp_path):
    bag_path = tmp_path / "nav.bag"
    files = [str(WORLD_LAUNCH), str(VENDOR / "turtlebot3_navigation/launch/turtlebot3_navigation.launch")]
    files.append(str(TRYOUT / "tb3_world_goals.launch"))  # the pose estimate, then five goals
    args = ["open_rviz:=false"]
    assert main([*files, *args, "--duration", "150", "--bag", str(bag_path)]) == 0
    topics = ["/gazebo/model_states", "/move_base/result", "/move_base_simple/goal", "/amcl_pose"]
    bag = read_bag(bag_path, topics)
    truth = model_truth(bag, "turtlebot3_burger")
    # every goal SUCCEEDED, the run ending with the last (the goal sender's work done)
    results = bag["/move_base/result"]
    assert [m.status.status for _, m in results] == [3] * 5, [m.status.text for _, m in results]
    assert truth[-1, 0] < 150.0
    goals = [m.pose.position for _, m in bag["/move_base_simple/goal"]]
    assert len(goals) == 5
    for goal, (t, _) in zip(goals, results):
        # where the burger truly stood: within DWAPlannerROS's xy_goal_tolerance (0.05 m) of the
        # goal as amcl saw it, plus amcl's error there
        x, y, _ = _at(truth, t * 1e-9)
        assert math.hypot(x - goal.x, y - goal.y) < 0.05 + 0.05
    # amcl: the pose estimate put it where it spawned; once converged (its first pose within
    # 0.1 m and 0.1 rad of the truth), every pose it published within 0.15 m and 0.1 rad
    poses = [(m.header.stamp.sec + m.header.stamp.nanosec * 1e-9, m.pose.pose) for _, m in bag["/amcl_pose"]]
    assert len(poses) > 30  # 66 measured
    errors = []
    for t, pose in poses:
        x, y, yaw = _at(truth, t)
        dyaw = abs(math.remainder(heading(pose.orientation) - yaw, math.tau))
        errors.append((math.hypot(pose.position.x - x, pose.position.y - y), dyaw))
    errors = np.array(errors)
    converged = np.nonzero((errors[:, 0] < 0.1) & (errors[:, 1] < 0.1))[0][0]
    assert poses[converged][0] < 5.0
    assert errors[converged:, 0].max() < 0.15 and errors[converged:, 1].max() < 0.1
