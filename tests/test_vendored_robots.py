"""Public ROS 1 robots run as a new user would run them: TurtleBot3 burger and Husky from their
own packages (vendored unchanged under tests/data/ros1/vendor, found through ROS_PACKAGE_PATH),
brought up by roslaunch XML files in the house world (tests/data/ros1/tryout). The TurtleBot3
drives a cmd_vel sequence and scans, and maps and navigates with its own gmapping and move_base
parameter files (DWAPlannerROS); the Husky drives through husky_control's diff_drive_controller.
Motion is judged against the simulator's ground truth (/gazebo/model_states)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml
from conftest import read_bag
from support.model_truth import model_truth, yaw
from support.ros_env import use_packages

from twil_control import PACKAGE_ROOT
from twil_control.core import packages
from twil_control.description.urdf import parse_urdf
from twil_control.description.xacro_command import run_xacro
from twil_control.launch.loader import load_launch
from twil_control.launch.runner import RunOptions, run

ROS1 = PACKAGE_ROOT / "tests" / "data" / "ros1"
VENDOR = ROS1 / "vendor"
TRYOUT = ROS1 / "tryout"


@pytest.fixture(autouse=True)
def _env(monkeypatch, tmp_path_factory):
    use_packages(monkeypatch, tmp_path_factory, VENDOR, ROS1 / "stubs")


def _run(tmp_path, launch: str, duration: float, topics=None, **args) -> dict:
    """The bag of a tryout launch's run: every topic, or only `topics`."""
    plan = load_launch(TRYOUT / launch, {k: str(v) for k, v in args.items()})
    result = run(plan, RunOptions(duration=duration, bag=tmp_path / "run.bag"))
    assert result.error is None and not result.failures
    return read_bag(result.bag, topics)


def _links(package: str, xacro: str, *args: str) -> set[str]:
    return set(parse_urdf(run_xacro([str(packages.find(package) / xacro), *args])).links)


def _tf_children(bag: dict) -> set[str]:
    return {
        t.child_frame_id
        for topic in ("/tf", "/tf_static")
        for _, m in bag.get(topic, [])
        for t in m.transforms
    }


def _sequence_end(name: str) -> float:
    return yaml.safe_load((TRYOUT / name).read_text())["segments"][-1]["time"]


@pytest.mark.slow
def test_turtlebot3_drives_its_cmd_vel_sequence_scans_and_records_its_links(tmp_path):
    bag = _run(tmp_path, "tb3_house.launch", 7.0)
    truth = model_truth(bag, "turtlebot3_burger")
    # the sequence: 0.8 rad/s for pi/2 rad, then 0.15 m/s for 4 s (0.6 m); at 10 Hz a command
    # lasts up to 0.1 s longer than its segment, and the plugin's wheelAcceleration ramps it, so
    # the heading within 0.15 rad (0.12 measured), the distance within 0.05 m, travelled straight
    end = truth[-1]
    assert end[3] == pytest.approx(math.pi / 2, abs=0.15)
    assert math.hypot(end[1], end[2]) == pytest.approx(0.6, abs=0.05)
    assert math.atan2(end[2], end[1]) == pytest.approx(end[3], abs=0.03)
    after = truth[truth[:, 0] > _sequence_end("tb3_cmd_sequence.yaml") + 0.5]
    assert np.ptp(after[:, 1:3], axis=0).max() < 0.005  # stopped
    # its LDS: 360 rays at 5 Hz, every finite range inside [range_min, range_max], walls in view
    scans = [m for _, m in bag["/scan"]]
    assert len(scans) == pytest.approx(7 * 5, abs=2)
    scan = scans[-1]
    assert scan.header.frame_id == "base_scan" and len(scan.ranges) == 360
    assert (scan.range_min, scan.range_max) == pytest.approx((0.12, 3.5))
    ranges = np.array([r for m in scans for r in m.ranges])
    finite = ranges[np.isfinite(ranges)]
    assert len(finite) > 0.5 * len(ranges)
    assert finite.min() >= scan.range_min and finite.max() <= scan.range_max
    # every link of the description in tf, and the simulator's clock and the nodes' log recorded
    links = _links("turtlebot3_description", "urdf/turtlebot3_burger.urdf.xacro")
    root = "base_footprint"
    assert links - {root} <= _tf_children(bag) and root in links
    clock = [m.clock.sec + m.clock.nanosec * 1e-9 for _, m in bag["/clock"]]
    assert len(clock) == pytest.approx(7 * 100, abs=2) and clock[-1] == pytest.approx(7.0, abs=0.011)
    assert {m.name for _, m in bag["/rosout"]} >= {"/spawn_urdf", "/gazebo"}


@pytest.mark.slow
def test_husky_drives_forward_through_its_diff_drive_controller(tmp_path):
    bag = _run(tmp_path, "husky_house.launch", 5.0)
    truth = model_truth(bag, "husky")
    # 0.5 m/s for 2 s north from t = 1 s; control.yaml limits acceleration to 3 m/s^2 (the ramps
    # cost and return about 0.04 m): 1 m within 0.05 m, straight, and so says the wheel odometry.
    # spawn_model puts base_link at z = 0, the wheels 0.13 m into the floor: it is lifted to rest
    # on them before time starts (else the wheels slip while the floor pushes them out: 0.80 m)
    start, end = truth[0], truth[-1]
    assert start[3] == pytest.approx(math.pi / 2, abs=1e-3)
    assert end[2] - start[2] == pytest.approx(1.0, abs=0.05)
    assert abs(end[1] - start[1]) < 0.02 and abs(math.remainder(end[3] - math.pi / 2, math.tau)) < 0.02
    odom = [m for _, m in bag["/husky_velocity_controller/odom"]]
    assert odom[-1].pose.pose.position.x == pytest.approx(end[2] - start[2], abs=0.02)
    base = [m.pose[list(m.name).index("husky::base_link")].position.z for _, m in bag["/gazebo/link_states"]]
    assert min(base) == pytest.approx(0.1323, abs=0.003)  # wheel radius - wheel offset
    after = truth[truth[:, 0] > _sequence_end("husky_cmd_sequence.yaml") + 1.0]
    assert np.ptp(after[:, 1:3], axis=0).max() < 0.01  # stopped
    # the joint states of control.yaml's joint_state_controller, every link in tf
    names = set(bag["/joint_states"][-1][1].name)
    assert names == {"front_left_wheel", "front_right_wheel", "rear_left_wheel", "rear_right_wheel"}
    links = _links("husky_description", "urdf/husky.urdf.xacro", "robot_namespace:=/")
    assert links - {"base_link"} <= _tf_children(bag)
    assert len(bag["/clock"]) > 0 and "/rosout" in bag


@pytest.mark.slow
def test_turtlebot3_maps_and_reaches_a_goal_with_its_own_navigation_files(tmp_path):
    goal = (1.2, 0.0, 0.0)
    topics = ["/move_base/result", "/gazebo/model_states", "/move_base/DWAPlannerROS/local_plan", "/cmd_vel"]
    bag = _run(tmp_path, "tb3_nav.launch", 25.0, topics, goal=" ".join(map(str, goal)))
    results = [m for _, m in bag["/move_base/result"]]
    assert [r.status.status for r in results] == [3], [r.status.text for r in results]  # SUCCEEDED
    # gmapping's map frame starts at the spawn pose, which is the world's origin: the goal is
    # where the robot truly stands, within the file's xy_goal_tolerance + 0.05 m (the map's drift)
    tolerance = yaml.safe_load(
        (VENDOR / "turtlebot3_navigation/param/dwa_local_planner_params_burger.yaml").read_text()
    )["DWAPlannerROS"]["xy_goal_tolerance"]
    truth = model_truth(bag, "turtlebot3_burger")
    at = truth[np.searchsorted(truth[:, 0], bag["/move_base/result"][0][0] * 1e-9) - 1]
    assert math.hypot(at[1] - goal[0], at[2] - goal[1]) < tolerance + 0.05
    # the local planner was dwa_local_planner's, with the file's limits
    plans = bag["/move_base/DWAPlannerROS/local_plan"]
    assert plans
    speeds = [m.linear.x for _, m in bag["/cmd_vel"]]
    assert max(speeds) <= 0.22 + 1e-9 and max(speeds) > 0.1


def _heading_errors(bag: dict, model: str, topic: str) -> np.ndarray:
    """|heading of `topic`'s odometry - the true heading change since the start| over the run."""
    truth = model_truth(bag, model)
    true_yaw = np.unwrap(truth[:, 3])
    rows = np.array([(t * 1e-9, yaw(m.pose.pose.orientation)) for t, m in bag[topic]])
    start = true_yaw[0]
    expected = np.interp(rows[:, 0], truth[:, 0], true_yaw) - start
    return np.abs(np.remainder(rows[:, 1] - expected + math.pi, math.tau) - math.pi)


@pytest.mark.slow
def test_husky_control_launch_runs_whole_and_its_ekf_keeps_the_heading_on_a_square(tmp_path):
    # husky_gazebo's spawn_husky.launch as it is: control.launch (EKF, twist_mux, marker server)
    # and teleop.launch (joy_node without a device: one warning); the square goes in on /cmd_vel,
    # twist_mux's lowest-priority input, and reaches the velocity controller through it
    topics = ["/gazebo/model_states", "/odometry/filtered", "/rosout"]
    topics += ["/husky_velocity_controller/odom", "/husky_velocity_controller/cmd_vel"]
    bag = _run(tmp_path, "husky_control.launch", 27.0, topics)
    ekf = _heading_errors(bag, "husky", "/odometry/filtered")
    wheels = _heading_errors(bag, "husky", "/husky_velocity_controller/odom")
    message = f"heading error: odometry/filtered {ekf.max():.3f} rad, wheel odometry {wheels.max():.3f} rad"
    assert ekf.max() < 0.1, message  # measured 0.025
    assert wheels.max() > 0.15, message  # the skid-steered wheels slip in the turns: 0.225 measured
    assert len(bag["/odometry/filtered"]) == pytest.approx(27 * 50, abs=2)
    muxed = [m for _, m in bag["/husky_velocity_controller/cmd_vel"]]
    assert {round(m.linear.x, 3) for m in muxed} == {0.0, 0.4} and {round(m.angular.z, 3) for m in muxed} == {
        0.0,
        -0.5,
    }
    logs = [m.msg for _, m in bag["/rosout"]]
    assert sum("Couldn't open joystick" in line for line in logs) == 1


@pytest.mark.slow
def test_jackal_spawns_through_env_run_and_twist_mux_lets_the_higher_priority_command_through(tmp_path):
    topics = ["/gazebo/model_states", "/jackal_velocity_controller/cmd_vel", "/odometry/filtered"]
    bag = _run(tmp_path, "jackal_world.launch", 7.0, topics)
    truth = model_truth(bag, "jackal")

    def at(t):
        return truth[np.searchsorted(truth[:, 0], t)]

    # rostopic pub -r 20: 0.3 m/s east from the start; bt_joy (priority 9) turns in place from
    # 2.5 s to 4 s
    assert at(2.5)[1] - at(1.0)[1] == pytest.approx(0.3 * 1.5, abs=0.06)
    during = truth[(truth[:, 0] > 2.7) & (truth[:, 0] < 4.0)]
    assert np.ptp(during[:, 1]) < 0.05 and np.ptp(during[:, 2]) < 0.05  # turning, not driving
    assert at(4.5)[3] - at(2.5)[3] == pytest.approx(1.5, abs=0.25)
    # 0.5 s after the override stops (its twist_mux timeout) the external command drives again
    assert math.hypot(at(6.0)[1] - at(4.6)[1], at(6.0)[2] - at(4.6)[2]) == pytest.approx(0.3 * 1.4, abs=0.08)
    muxed = [(t * 1e-9, m) for t, m in bag["/jackal_velocity_controller/cmd_vel"]]
    assert all(m.angular.z == 1.0 for t, m in muxed if 2.55 < t < 4.0)
    assert all(m.linear.x == 0.3 for t, m in muxed if 4.55 < t < 6.0)
    assert not any(m.linear.x for t, m in muxed if 4.05 < t < 4.45)  # bt_joy not yet timed out
    # the EKF (melodic-devel's: the IMU's absolute yaw) keeps the true heading
    assert _heading_errors(bag, "jackal", "/odometry/filtered").max() < 0.1


@pytest.mark.slow
def test_husky_navigates_with_husky_navigation_s_gmapping_demo(tmp_path, monkeypatch):
    # the LMS1xx on, as Clearpath's instructions export it; three goals in the part of the house
    # the laser maps from the spawn point, each given 60 s, each sent from where the previous one
    # left the Husky
    monkeypatch.setenv("HUSKY_LMS1XX_ENABLED", "1")
    goals = [(1.0, 1.5, 0.0), (0.3, 2.0, 1.57), (0.0, 0.0, 0.0)]
    topics = ["/move_base/result", "/gazebo/model_states", "/front/scan"]
    text = "; ".join(" ".join(map(str, g)) for g in goals)
    bag = _run(tmp_path, "husky_nav.launch", 150.0, topics, goals=text)
    results = [(t * 1e-9, m.status.status, m.status.text) for t, m in bag["/move_base/result"]]
    assert [r[1] for r in results] == [3, 3, 3], results  # SUCCEEDED each
    truth = model_truth(bag, "husky")
    assert truth[-1, 0] < results[-1][0] + 0.5  # the goal sender ended the run at the last result
    for (x, y, _), (t, _, _) in zip(goals, results):
        at = truth[np.searchsorted(truth[:, 0], t) - 1]
        # gmapping's map frame is the spawn pose, the world's origin: the goal is where the
        # Husky truly stands, within planner.yaml's xy_goal_tolerance (0.2 m) + 0.1 m of map drift
        assert math.hypot(at[1] - x, at[2] - y) < 0.3, (x, y, at)
    scans = bag["/front/scan"]
    assert len(scans[-1][1].ranges) == 720  # the real lms1xx package's sensor
