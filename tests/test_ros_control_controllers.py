"""Standard controllers: joint_state_controller rate and fields, forward command controllers,
effort_controllers/JointPositionController, NaN commands."""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest
from support.ros_control_fakes import NS, make_cm, run

from twil_control.core.messages import msg_class, to_sec
from twil_control.ros_control import STRICT

Float64 = msg_class("std_msgs/Float64")
Float64MultiArray = msg_class("std_msgs/Float64MultiArray")
Layout = msg_class("std_msgs/MultiArrayLayout")


def multi(values):
    return Float64MultiArray(layout=Layout(dim=[], data_offset=0), data=np.array(values, dtype=float))


def spawn(params, *names):
    master, node, hw, cm = make_cm(params=params)
    for name in names:
        assert cm.load_controller(name), cm.last_error
    assert cm.switch_controller(list(names), [], STRICT), cm.last_error
    return master, node, hw, cm


def collect(master, topic, msgtype):
    got = []
    master.bus.subscribe(topic, msgtype, got.append)
    return got


# -- joint_state_controller ---------------------------------------------------------------
def test_jsc_publishes_exactly_publish_rate_messages_per_simulated_second():
    params = {
        "jsc": {
            "type": "joint_state_controller/JointStateController",
            "publish_rate": 100,
            "topic": "/joint_states",
        }
    }
    master, node, hw, cm = spawn(params, "jsc")
    got = collect(master, "/joint_states", "sensor_msgs/JointState")
    run(master, hw, cm, 0.0, 1000)  # updates at t = 0.000 ... 0.999
    assert len(got) == 100
    stamps = np.array([to_sec(m.header.stamp) for m in got])
    np.testing.assert_allclose(np.diff(stamps), 0.01, atol=1e-9)
    run(master, hw, cm, 1.0, 9000)  # no drift over 10 s
    assert len(got) == 1000


@pytest.mark.parametrize("rate, expected", [(50, 50), (30, 30), (1000, 1000), (2000, 1000)])
def test_jsc_rate_at_1khz(rate, expected):
    params = {"jsc": {"type": "joint_state_controller/JointStateController", "publish_rate": rate}}
    master, node, hw, cm = spawn(params, "jsc")
    got = collect(master, f"{NS}/joint_states", "sensor_msgs/JointState")
    run(master, hw, cm, 0.0, 1000)
    assert abs(len(got) - expected) <= 1


def test_jsc_default_topic_is_joint_states_in_the_root_namespace_with_all_joints_in_hw_order():
    params = {"jsc": {"type": "joint_state_controller/JointStateController", "publish_rate": 100}}
    master, node, hw, cm = spawn(params, "jsc")
    got = collect(master, f"{NS}/joint_states", "sensor_msgs/JointState")
    hw.position[:] = [0.1, 0.2, 0.3]
    hw.velocity[:] = [1.0, 2.0, 3.0]
    cm.update(0.0, 0.001)
    (m,) = got
    assert m.name == ["j1", "j2", "j3"]
    assert len(m.position) == len(m.velocity) == len(m.effort) == 3
    np.testing.assert_array_equal(m.position, [0.1, 0.2, 0.3])
    np.testing.assert_array_equal(m.velocity, [1.0, 2.0, 3.0])
    assert to_sec(m.header.stamp) == 0.0


def test_jsc_joints_subset_and_order():
    params = {
        "jsc": {
            "type": "joint_state_controller/JointStateController",
            "publish_rate": 100,
            "joints": ["j3", "j1"],
        }
    }
    master, node, hw, cm = spawn(params, "jsc")
    got = collect(master, f"{NS}/joint_states", "sensor_msgs/JointState")
    hw.position[:] = [0.1, 0.2, 0.3]
    cm.update(0.0, 0.001)
    assert got[0].name == ["j3", "j1"]
    np.testing.assert_array_equal(got[0].position, [0.3, 0.1])


def test_jsc_requires_publish_rate_naming_the_parameter():
    params = {"jsc": {"type": "joint_state_controller/JointStateController"}}
    master, node, hw, cm = make_cm(params=params)
    assert not cm.load_controller("jsc")
    assert f"{NS}/jsc/publish_rate" in cm.last_error


def test_jsc_refuses_an_unknown_joint_and_warns_about_a_misspelt_parameter(caplog):
    params = {
        "jsc": {"type": "joint_state_controller/JointStateController", "publish_rate": 10, "joints": ["j9"]},
        "jsc2": {"type": "joint_state_controller/JointStateController", "publish_rate": 10, "publish_rat": 5},
    }
    master, node, hw, cm = make_cm(params=params)
    assert not cm.load_controller("jsc")
    assert "j9" in cm.last_error
    # joint_state_controller ignores a parameter it does not read, and so does its replica
    with caplog.at_level(logging.WARNING):
        assert cm.load_controller("jsc2")
    warned = [r.getMessage() for r in caplog.records if "publish_rat'" in r.getMessage()]
    assert len(warned) == 1 and "(did you mean 'publish_rate'?) is ignored" in warned[0]


# -- forward command controllers ------------------------------------------------------------
def test_effort_controller_forwards_command_topic_to_effort_interface():
    params = {"e": {"type": "effort_controllers/JointEffortController", "joint": "j2"}}
    master, node, hw, cm = spawn(params, "e")
    pub = node.create_publisher(f"{NS}/e/command", "std_msgs/Float64")
    t = run(master, hw, cm, 0.0, 1)
    assert hw.command("effort")[1] == 0.0  # starting() holds zero effort
    pub.publish(Float64(data=2.0))
    run(master, hw, cm, t, 1000)
    assert hw.command("effort")[1] == 2.0
    assert hw.active_mode("j2") == "effort"
    assert hw.velocity[1] == pytest.approx(2.0, rel=1e-9)  # unit inertia, 1 s at 2 N m


def test_velocity_controller_forwards_to_velocity_interface():
    params = {"v": {"type": "velocity_controllers/JointVelocityController", "joint": "j1"}}
    master, node, hw, cm = spawn(params, "v")
    pub = node.create_publisher(f"{NS}/v/command", "std_msgs/Float64")
    pub.publish(Float64(data=0.5))  # before starting(): starting() resets the command to 0, as in ROS
    t = run(master, hw, cm, 0.0, 1)
    assert hw.command("velocity")[0] == 0.0
    pub.publish(Float64(data=0.5))
    run(master, hw, cm, t, 1000)
    assert hw.active_mode("j1") == "velocity"
    assert hw.position[0] == pytest.approx(0.5, abs=1e-9)


def test_position_controller_holds_current_position_when_started():
    params = {"p": {"type": "position_controllers/JointPositionController", "joint": "j3"}}
    master, node, hw, cm = spawn(params, "p")
    hw.position[2] = 0.7
    run(master, hw, cm, 0.0, 10)
    assert hw.position[2] == pytest.approx(0.7)
    node.create_publisher(f"{NS}/p/command", "std_msgs/Float64").publish(Float64(data=-0.2))
    run(master, hw, cm, 0.01, 1)
    assert hw.position[2] == -0.2


def test_group_controllers_write_joints_in_param_order_and_refuse_wrong_length(caplog):
    params = {
        "g": {"type": "effort_controllers/JointGroupEffortController", "joints": ["j3", "j1"]},
        "gv": {"type": "velocity_controllers/JointGroupVelocityController", "joints": ["j2"]},
    }
    master, node, hw, cm = spawn(params, "g", "gv")
    pub = node.create_publisher(f"{NS}/g/command", "std_msgs/Float64MultiArray")
    run(master, hw, cm, 0.0, 1)
    pub.publish(multi([3.0, 1.0]))
    run(master, hw, cm, 0.001, 1)
    np.testing.assert_array_equal(hw.command("effort")[[0, 2]], [1.0, 3.0])
    with caplog.at_level(logging.ERROR):
        pub.publish(multi([1.0, 2.0, 3.0]))
    assert "Dimension of command (3) does not match number of joints (2)" in caplog.text
    run(master, hw, cm, 0.002, 1)
    np.testing.assert_array_equal(hw.command("effort")[[0, 2]], [1.0, 3.0])
    claimed = {c.name: c.claimed_resources[0].resources for c in cm.list_controllers()}
    assert claimed == {"g": ["j1", "j3"], "gv": ["j2"]}


def test_group_position_controller_holds_positions():
    params = {"gp": {"type": "position_controllers/JointGroupPositionController", "joints": ["j1", "j2"]}}
    master, node, hw, cm = spawn(params, "gp")
    hw.position[:] = [0.4, -0.4, 9.0]
    run(master, hw, cm, 0.0, 5)
    np.testing.assert_allclose(hw.position[:2], [0.4, -0.4])


def test_group_controller_claims_seven_effort_joints_like_a_wam_controller():
    joints = [f"wam_joint_{i}" for i in range(1, 8)]
    master, node, hw, cm = make_cm(
        joints=joints,
        params={
            "arm": {"type": "effort_controllers/JointGroupEffortController", "joints": joints},
            "j4": {"type": "effort_controllers/JointEffortController", "joint": "wam_joint_4"},
        },
    )
    assert cm.load_controller("arm") and cm.load_controller("j4")
    (arm, j4) = cm.list_controllers()
    assert arm.claimed_resources[0].resources == sorted(joints)
    assert cm.switch_controller(["arm"], [], STRICT)
    assert not cm.switch_controller(["j4"], [], STRICT)  # wam_joint_4 is the arm's


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_commands_are_ignored_keeping_the_previous_one_logged_once_per_burst(bad, caplog):
    params = {
        "e": {"type": "effort_controllers/JointEffortController", "joint": "j1"},
        "g": {"type": "velocity_controllers/JointGroupVelocityController", "joints": ["j2", "j3"]},
    }
    master, node, hw, cm = spawn(params, "e", "g")
    pe = node.create_publisher(f"{NS}/e/command", "std_msgs/Float64")
    pg = node.create_publisher(f"{NS}/g/command", "std_msgs/Float64MultiArray")
    run(master, hw, cm, 0.0, 1)
    pe.publish(Float64(data=1.5))
    pg.publish(multi([0.1, 0.2]))
    with caplog.at_level(logging.ERROR):
        for _ in range(5):
            pe.publish(Float64(data=bad))
            pg.publish(multi([bad, 0.0]))
    run(master, hw, cm, 0.0, 1)
    assert hw.command("effort")[0] == 1.5
    np.testing.assert_array_equal(hw.command("velocity")[1:], [0.1, 0.2])
    errors = [r.getMessage() for r in caplog.records if r.levelno >= logging.ERROR]
    assert len(errors) == 2 and "e:" in errors[0] and "g:" in errors[1]
    pe.publish(Float64(data=1.0))  # a good command ends the burst
    with caplog.at_level(logging.ERROR):
        pe.publish(Float64(data=bad))
    assert len([r for r in caplog.records if r.levelno >= logging.ERROR]) == 3


def test_forward_controller_refuses_missing_joint_param_and_unknown_joint():
    params = {
        "e": {"type": "effort_controllers/JointEffortController"},
        "f": {"type": "effort_controllers/JointEffortController", "joint": "nope"},
        "g": {"type": "effort_controllers/JointGroupEffortController", "joints": []},
    }
    master, node, hw, cm = make_cm(params=params)
    assert not cm.load_controller("e")
    assert f"{NS}/e/joint" in cm.last_error
    assert not cm.load_controller("f")
    assert "nope" in cm.last_error and "EffortJointInterface" in cm.last_error
    assert not cm.load_controller("g")
    assert "List of joint names is empty" in cm.last_error


# -- effort_controllers/JointPositionController --------------------------------------------
def test_effort_position_controller_tracks_a_step_with_pid():
    params = {
        "pc": {
            "type": "effort_controllers/JointPositionController",
            "joint": "j1",
            "pid": {"p": 100.0, "d": 20.0, "i": 0.0},
        }
    }
    master, node, hw, cm = spawn(params, "pc")
    hw.position[0] = 0.3
    t = run(master, hw, cm, 0.0, 100)
    assert hw.position[0] == pytest.approx(0.3, abs=1e-12)  # holds the pose it started at
    node.create_publisher(f"{NS}/pc/command", "std_msgs/Float64").publish(Float64(data=1.3))
    run(master, hw, cm, t, 3000)
    # critically damped (wn = 10, zeta = 1) unit-inertia joint: error after 3 s is e^-30 (1 + 30)
    assert hw.position[0] == pytest.approx(1.3, abs=1e-3)
    assert hw.active_mode("j1") == "effort"


def test_effort_position_controller_requires_pid_p():
    params = {"pc": {"type": "effort_controllers/JointPositionController", "joint": "j1", "pid": {"d": 1.0}}}
    master, node, hw, cm = make_cm(params=params)
    assert not cm.load_controller("pc")
    assert f"{NS}/pc/pid/p" in cm.last_error
