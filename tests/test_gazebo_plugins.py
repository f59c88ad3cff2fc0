"""A URDF's Gazebo plugins running in the simulator node, end to end: the tiny test robot
spawned from xacro by spawn_model -urdf -param, driven by its diff-drive plugin, by
gazebo_ros_control + diff_drive_controller from its control YAML, or by the skid-steer plugin;
its laser, IMU and p3d publishing; all of it recorded."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import read_bag
from support.ros_env import use_packages

from twil_control import PACKAGE_ROOT
from twil_control.core.messages import msg_class
from twil_control.core.odometry_msg import pose_msg, twist_msg
from twil_control.launch.loader import load_launch
from twil_control.launch.runner import Launch, RunOptions, run

ROBOTS = PACKAGE_ROOT / "tests" / "data" / "robots"
LAUNCH = ROBOTS / "tiny_description" / "launch" / "tiny.launch.yaml"


@pytest.fixture(autouse=True)
def _env(monkeypatch, tmp_path_factory):
    use_packages(monkeypatch, tmp_path_factory, ROBOTS)


def _yaw(q) -> float:
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


def _run(tmp_path, duration: float, **args):
    plan = load_launch(LAUNCH, {k: str(v) for k, v in args.items()})
    result = run(plan, RunOptions(duration=duration, bag=tmp_path / "run.bag"))
    assert result.error is None
    return read_bag(result.bag)


def test_graph_puts_the_plugins_in_the_gazebo_node():
    launch = Launch(load_launch(LAUNCH))
    launch.build()
    launch.start()
    bus = launch.master.bus
    for topic in ("/odom", "/joint_states", "/scan", "/imu", "/ground_truth/odom", "/tf"):
        assert bus.publishers_of(topic) == ["/gazebo"], topic
    assert bus.subscribers_of("/cmd_vel") == ["/gazebo"]
    plant = launch.sim.plant
    context = plant.GetMyContextFromRoot(launch.simulator.get_context())
    assert plant.GetJointByName("left_wheel_joint").get_angle(context) == 0.5  # -J
    limit = plant.GetJointActuatorByName("left_wheel_motor").effort_limit()
    assert limit == 5.0  # wheelTorque
    launch.shutdown()


@pytest.mark.slow
def test_diff_drive_plugin_drives_and_sensors_publish(tmp_path):
    bag = _run(tmp_path, 2.5)
    odom = [m for _, m in bag["/odom"]]
    truth = [m for _, m in bag["/ground_truth/odom"]]
    assert len(odom) == pytest.approx(2.5 * 50, abs=2) and len(truth) == pytest.approx(2.5 * 50, abs=2)
    # 0.3 m/s for 1 s, then 1 rad/s for 1 s; the wheels ramp at 2 m/s^2 (what the ramp-up loses
    # the ramp-down gives back on the straight; the turn starts with a wheel reversing, 0.2 s)
    end = odom[-1].pose.pose
    assert end.position.x == pytest.approx(0.3, abs=0.01)
    assert 0.8 < _yaw(end.orientation) < 1.0
    # odometrySource world is the ground truth (p3d of base_link, directly above base_footprint)
    assert end.position.x == pytest.approx(
        truth[-1].pose.pose.position.x, abs=1e-5
    )  # base_link is 0.05 m above: tilt
    assert end.position.y == pytest.approx(
        truth[-1].pose.pose.position.y, abs=1e-5
    )  # base_link is 0.05 m above: tilt
    frames = {(t.header.frame_id, t.child_frame_id) for _, m in bag["/tf"] for t in m.transforms}
    assert frames == {
        ("odom", "base_footprint"),
        ("base_link", "left_wheel_link"),
        ("base_link", "right_wheel_link"),
    }
    wheels = bag["/joint_states"][0][1]
    assert list(wheels.name) == ["left_wheel_joint", "right_wheel_joint"] and wheels.position[0] == 0.5
    scans = [m for _, m in bag["/scan"]]
    assert (
        len(scans) == pytest.approx(25, abs=1)
        and len(scans[0].ranges) == 180
        and scans[0].header.frame_id == "laser_link"
    )
    assert scans[0].angle_min == pytest.approx(-1.5708) and scans[0].range_max == 5.0
    imu = [m for t, m in bag["/imu"] if t > 2.1e9]  # at rest after the turn
    accel = np.array(
        [[m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z] for m in imu]
    )
    assert len(bag["/imu"]) == pytest.approx(250, abs=2)
    assert accel[:, 2].mean() == pytest.approx(9.81, abs=0.01)  # proper acceleration at rest
    assert accel[:, 2].std() == pytest.approx(0.01, rel=0.35)  # the sensor's stddev
    assert abs(accel[:, 0].mean()) < 0.01
    # the run's log and clock are in the bag: the build-time warnings too, stamped 0
    logs = [(t, m.name, m.level, m.msg) for t, m in bag["/rosout"]]
    assert any(
        t == 0 and name == "/gazebo" and level == 4 and "libgazebo_ros_planar_move.so" in text
        for t, name, level, text in logs
    )
    clock = [m.clock.sec + m.clock.nanosec * 1e-9 for _, m in bag["/clock"]]
    assert clock[:3] == pytest.approx([0.01, 0.02, 0.03]) and len(clock) == pytest.approx(250, abs=1)


@pytest.mark.slow
def test_ros_control_plugin_runs_diff_drive_controller_from_its_yaml(tmp_path):
    bag = _run(
        tmp_path,
        2.5,
        drive="ros_control",
        ros_control="true",
        cmd_topic="/tiny/diff_drive_controller/cmd_vel",
    )
    odom = [m for _, m in bag["/tiny/diff_drive_controller/odom"]]
    truth = bag["/ground_truth/odom"][-1][1].pose.pose
    end = odom[-1].pose.pose
    assert end.position.x == pytest.approx(truth.position.x, abs=0.01)
    assert _yaw(end.orientation) == pytest.approx(_yaw(truth.orientation), abs=0.02)
    assert truth.position.x > 0.25 and _yaw(truth.orientation) > 0.8
    states = bag["/tiny/joint_states"]
    assert len(states) == pytest.approx(2.5 * 50, abs=2)
    assert odom[-1].header.frame_id == "odom" and odom[-1].child_frame_id == "base_footprint"


@pytest.mark.slow
def test_skid_steer_plugin_with_encoder_odometry(tmp_path):
    bag = _run(
        tmp_path, 1.0, drive="skid_steer", odometry_source="encoder", cmd_topic="/tiny/cmd_vel", joints=""
    )
    odom = bag["/tiny/odom"][-1][1]
    truth = bag["/ground_truth/odom"][-1][1].pose.pose
    assert truth.position.x == pytest.approx(0.3, abs=0.03)
    assert odom.pose.pose.position.x == pytest.approx(truth.position.x, abs=0.02)
    assert odom.pose.covariance[0] == 0.001 and odom.pose.covariance[35] == 0.05


def test_gazebo_services_and_model_states():
    from twil_control.core.node import ServiceError

    launch = Launch(
        load_launch(
            LAUNCH, {"cmd_sequence": str(ROBOTS / "tiny_description" / "config" / "cmd_sequence.yaml")}
        )
    )
    launch.build()
    states = []
    launch.master.bus.subscribe("/gazebo/model_states", "gazebo_msgs/ModelStates", states.append, node="/t")
    launch.start()
    call = launch.master.call_service
    launch.simulator.AdvanceTo(0.2)
    assert len(states) == 3 and list(states[-1].name) == ["tiny"]  # t = 0, 0.1, 0.2 (10 Hz)
    got = call("/gazebo/get_model_state", model_name="tiny")
    assert got.success and got.pose.position.x == pytest.approx(states[-1].pose[0].position.x)
    request = msg_class("gazebo_msgs/ModelState")(
        model_name="tiny",
        pose=pose_msg((1.0, 2.0, 0.0), (0, 0, 0, 1)),
        twist=twist_msg((0, 0, 0), (0, 0, 0)),
        reference_frame="world",
    )
    assert call("/gazebo/set_model_state", model_state=request).success
    launch.between_slices()
    pose = call("/gazebo/get_model_state", model_name="tiny").pose
    assert (pose.position.x, pose.position.y) == (1.0, 2.0)
    call("/gazebo/reset_world")
    launch.between_slices()
    pose = call("/gazebo/get_model_state", model_name="tiny").pose
    assert (pose.position.x, pose.position.y) == (0.0, 0.0)
    assert not call("/gazebo/get_model_state", model_name="nope").success
    spawned = call("/gazebo/spawn_urdf_model", model_name="x", model_xml="<robot/>")
    assert not spawned.success and "spawn_model nodes" in spawned.status_message
    with pytest.raises(ServiceError, match="pause_physics is not supported"):
        call("/gazebo/pause_physics")
    launch.shutdown()
