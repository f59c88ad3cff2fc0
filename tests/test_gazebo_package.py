"""A Gazebo package run as its README would have it (tests/data/gazebo/rover_gazebo, this project's
own data in the form of the seed's qbot package): from the package's folder, with
GAZEBO_MODEL_PATH at its models and GAZEBO_RESOURCE_PATH at the package, its own launch files in
one command, its world given by name (world_name:=), its SDF rover (skid-steer plugin, a laser
model included and fixed by a joint) driven by a `rostopic pub`, and gmapping and move_base from
its params/ files (the global costmap in `/map`, as old files write it) reaching a goal
published once on /move_base_simple/goal. Judged against the simulator's truth
(/gazebo/model_states) and the world rasterised at the laser's height."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml
from conftest import read_bag
from support.model_truth import model_truth

from twil_control import PACKAGE_ROOT
from twil_control.bag.analyze import analyze_bag
from twil_control.core import packages
from twil_control.launch.__main__ import main

PACKAGE = PACKAGE_ROOT / "tests" / "data" / "gazebo" / "rover_gazebo"
LASER_HEIGHT = 0.13  # the lidar's ray origin above the floor (rover resting on its wheels)


@pytest.fixture(autouse=True)
def _package_folder(monkeypatch, tmp_path_factory):
    """The README's set-up: the package's folder as the working directory, its two variables."""
    monkeypatch.chdir(PACKAGE)
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(PACKAGE.parent))
    monkeypatch.setenv("GAZEBO_MODEL_PATH", str(PACKAGE / "models"))
    monkeypatch.setenv("GAZEBO_RESOURCE_PATH", str(PACKAGE))
    monkeypatch.setenv("TWIL_MESH_CACHE", str(tmp_path_factory.getbasetemp() / "meshes"))
    packages.set_extra_paths([])


@pytest.mark.slow
def test_its_gazebo_launch_and_a_rostopic_pub_drive_the_rover_which_scans_640_beams(tmp_path):
    drive = tmp_path / "drive.launch"
    drive.write_text(
        "<launch>\n  <node pkg='rostopic' type='rostopic' name='drive' args=\"pub -r 10 /rover/cmd_vel "
        "geometry_msgs/Twist '{linear: {x: 0.2}}'\"/>\n</launch>\n"
    )
    bag_path = tmp_path / "drive.bag"
    assert main(["launch/gazebo.launch", str(drive), "--duration", "3", "--bag", str(bag_path)]) == 0
    bag = read_bag(bag_path)
    truth = model_truth(bag, "rover")
    # rover_room.world puts it at (-0.5, 0.2) facing +x; the command holds from t = 0 (the
    # plugin sets wheel speeds, no ramp): along x at 0.2 m/s from there, straight
    speed, start = np.polyfit(truth[:, 0], truth[:, 1], 1)
    assert speed == pytest.approx(0.2, abs=0.005) and start == pytest.approx(-0.5, abs=0.01)
    assert np.abs(truth[:, 2] - 0.2).max() < 0.005 and np.abs(truth[:, 3]).max() < 0.01
    # the included lidar_ros model's sensor: 640 beams at 20 Hz in its plugin's frame
    scans = [m for _, m in bag["/rover/laser/scan"]]
    assert len(scans) == pytest.approx(3 * 20, abs=2)
    assert {len(s.ranges) for s in scans} == {640} and scans[0].header.frame_id == "laser"
    # the drive's odometry (the plugin's odometrySource world) is the truth at its stamps
    odom = {round(t * 1e-9, 3): m.pose.pose.position for t, m in bag["/rover/odom"]}
    at = odom[round(truth[-1, 0], 3)]
    assert (at.x, at.y) == pytest.approx(tuple(truth[-1, 1:3]), abs=1e-3)


@pytest.mark.slow
def test_its_navigation_launch_maps_the_walls_and_reaches_a_goal_behind_one(tmp_path):
    goal = (2.0, -1.0)
    bag_path = tmp_path / "nav.bag"
    command = ["launch/gazebo.launch", "launch/navigation.launch", "launch/goal.launch"]
    args = ["world_name:=rover_walls.world", f"goal_x:={goal[0]}", f"goal_y:={goal[1]}"]
    # the goal is reached 26 s in; nothing ends the run then (the goal is rviz's, no goal sender)
    assert main([*command, *args, "--duration", "40", "--bag", str(bag_path)]) == 0
    topics = ["/move_base_simple/goal", "/move_base/result", "/move_base/NavfnROS/plan", "/rover/laser/scan"]
    bag = read_bag(bag_path, [*topics, "/gazebo/model_states"])
    # move_base took the goal stamped `map` in its `/map` costmap and reached it, once
    assert len(bag["/move_base_simple/goal"]) == 1
    results = [m.status for _, m in bag["/move_base/result"]]
    assert [r.status for r in results] == [3], [r.text for r in results]  # SUCCEEDED
    assert {m.header.frame_id for _, m in bag["/move_base/NavfnROS/plan"]} == {"/map"}
    # where the rover truly stood then: within the planner file's xy_goal_tolerance + 0.05 m
    # (gmapping's map frame is the odometry's, which is the world's: the plugin's odometry is
    # the true pose); the way went round the north end of the wall between (at y = 0.4)
    tolerance = yaml.safe_load((PACKAGE / "params" / "base_local_planner.yaml").read_text())[
        "TrajectoryPlannerROS"
    ]["xy_goal_tolerance"]
    truth = model_truth(bag, "rover")
    at = truth[np.searchsorted(truth[:, 0], bag["/move_base/result"][0][0] * 1e-9) - 1]
    assert math.hypot(at[1] - goal[0], at[2] - goal[1]) < tolerance + 0.05
    crossing = truth[np.argmin(np.abs(truth[:, 1]))]  # where it passed x = 0, the wall's line
    assert crossing[2] > 0.4 + 0.2  # north of the wall's end by at least half the rover's width
    assert {len(m.ranges) for _, m in bag["/rover/laser/scan"]} == {640}
    # gmapping's last map against the world cut at the laser's height (tools.rasterize): its
    # walls where the world's are, within one cell
    from twil_control.tools.rasterize import main as rasterize

    assert (
        rasterize(["worlds/rover_walls.world", "-o", str(tmp_path / "ref"), "--height", str(LASER_HEIGHT)])
        == 0
    )
    mapping = analyze_bag(bag_path, ground_truth_map=tmp_path / "ref.yaml")["mapping"]
    assert mapping["map_precision"] > 0.9 and mapping["map_recall_observed"] > 0.95
