"""robot_state_publisher, joint_state_publisher and /rosout, without a simulator."""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest

from twil_control import PACKAGE_ROOT
from twil_control.core import packages
from twil_control.core.messages import header, msg_class
from twil_control.core.node import Master
from twil_control.core.rosout import RosoutHandler
from twil_control.description.xacro_command import run_xacro
from twil_control.nodes.robot_state_publisher import JointStatePublisher, RobotStatePublisher

ROBOTS = PACKAGE_ROOT / "tests" / "data" / "robots"


@pytest.fixture
def master(monkeypatch):
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(ROBOTS))
    packages.set_extra_paths([])
    m = Master()
    m.params.set(
        "/robot_description", run_xacro([str(ROBOTS / "tiny_description" / "urdf" / "tiny.urdf.xacro")])
    )
    return m


def _listen(master, topic):
    got = []
    master.bus.subscribe(topic, "tf2_msgs/TFMessage", got.append, node="/test")
    return got


def _joint_states(t, names, positions):
    return msg_class("sensor_msgs/JointState")(
        header=header("", t),
        name=names,
        position=np.array(positions, dtype=float),
        velocity=np.zeros(0),
        effort=np.zeros(0),
    )


def test_fixed_joints_static_and_moving_joints_from_joint_states(master):
    static, dynamic = _listen(master, "/tf_static"), _listen(master, "/tf")
    rsp = RobotStatePublisher(master, "robot_state_publisher", "/tiny")  # finds /robot_description upwards
    rsp.on_start()
    fixed = {(t.header.frame_id, t.child_frame_id): t for t in static[-1].transforms}
    assert set(fixed) == {
        ("base_footprint", "base_link"),
        ("base_link", "laser_link"),
        ("base_link", "imu_link"),
    }
    assert fixed[("base_link", "laser_link")].transform.translation.z == pytest.approx(0.09)
    pub = master.bus.advertise("/tiny/joint_states", "sensor_msgs/JointState", node="/test")
    pub.publish(_joint_states(0.0, ["left_wheel_joint", "right_wheel_joint"], [math.pi / 2, 0.0]))
    (msg,) = dynamic
    left = next(t for t in msg.transforms if t.child_frame_id == "left_wheel_link")
    assert left.header.frame_id == "base_link"
    assert left.transform.translation.y == pytest.approx(0.1)
    q = left.transform.rotation  # a quarter turn about +y
    assert (q.x, q.y, q.z, q.w) == pytest.approx((0.0, math.sin(math.pi / 4), 0.0, math.cos(math.pi / 4)))
    pub.publish(_joint_states(0.01, ["left_wheel_joint"], [0.0]))  # within 1/50 s: throttled
    pub.publish(_joint_states(0.02, ["left_wheel_joint"], [0.0]))
    assert [m.transforms[0].header.stamp.nanosec for m in dynamic[1:]] == [20_000_000]


def test_joint_state_publisher_merges_sources_and_defaults(master):
    master.params.set("/jsp/source_list", ["/partial"])
    master.params.set("/jsp/zeros", {"right_wheel_joint": 0.25})
    jsp = JointStatePublisher(master, "jsp")
    out = []
    master.bus.subscribe("/joint_states", "sensor_msgs/JointState", out.append, node="/test")
    master.bus.advertise("/partial", "sensor_msgs/JointState", node="/test").publish(
        _joint_states(0.0, ["left_wheel_joint"], [1.5])
    )
    jsp.on_start()
    master.spin_until(0.25)
    assert len(out) == 3  # at t = 0, 0.1, 0.2 (rate 10)
    assert list(out[-1].name) == ["left_wheel_joint", "right_wheel_joint"]
    assert out[-1].position.tolist() == [1.5, 0.25]


def test_rosout_carries_every_log_line_with_its_node(master):
    handler = RosoutHandler(master).attach()
    try:
        from twil_control.core.node import Node

        node = Node(master, "talker", "/ns")
        node.create_publisher("chatter", "std_msgs/String")
        got = []
        master.bus.subscribe("/rosout", "rosgraph_msgs/Log", got.append, node="/test")
        master.clock.set(1.5)
        node.log.warning("careful: %d", 3)
        node.log.debug("not sent")  # below INFO
        logging.getLogger("twil_control.ros_control.controller").error("boom")
        assert [(m.name, m.level, m.msg) for m in got] == [
            ("/ns/talker", 4, "careful: 3"),
            ("/ros_control/controller", 8, "boom"),
        ]
        assert got[0].file.endswith("test_robot_state_publisher.py") and got[0].line > 0
        assert got[0].function == "test_rosout_carries_every_log_line_with_its_node"
        assert list(got[0].topics) == ["/ns/chatter"] and got[0].header.stamp.sec == 1
        replayed = []
        handler.replay(lambda topic, kind, msg, t: replayed.append((topic, msg.msg, t)))
        assert replayed == [("/rosout", "careful: 3", 1.5), ("/rosout", "boom", 1.5)]
    finally:
        handler.detach()
