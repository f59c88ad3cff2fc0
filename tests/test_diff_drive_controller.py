"""diff_drive_controller/DiffDriveController on a fake velocity-controlled base: wheel commands,
limits, the command timeout, NaN commands, odometry, and the wheel geometry read from the URDF."""

from __future__ import annotations

import math

import pytest
from support.ros_control_fakes import make_cm, run

from twil_control import PACKAGE_ROOT
from twil_control.core import packages
from twil_control.core.messages import msg_class
from twil_control.description.xacro_command import run_xacro
from twil_control.ros_control.controllers.diff_drive_controller import wheel_geometry_from_urdf

JOINTS = ("left_wheel_joint", "right_wheel_joint")
ROBOTS = PACKAGE_ROOT / "tests" / "data" / "robots"


def _twist(v: float, w: float):
    vec = msg_class("geometry_msgs/Vector3")
    return msg_class("geometry_msgs/Twist")(linear=vec(x=v, y=0.0, z=0.0), angular=vec(x=0.0, y=0.0, z=w))


def _controller(extra=None):
    params = {
        "ddc/type": "diff_drive_controller/DiffDriveController",
        "ddc/left_wheel": "left_wheel_joint",
        "ddc/right_wheel": ["right_wheel_joint"],
        "ddc/wheel_separation": 0.4,
        "ddc/wheel_radius": 0.1,
        **(extra or {}),
    }
    master, node, hw, cm = make_cm(JOINTS, params=params)
    assert cm.load_controller("ddc") and cm.switch_controller(["ddc"], [], 2)
    run(master, hw, cm, 0.0, 1)  # the switch: commands count from now
    odom = []
    master.bus.subscribe("/twil/ros_control/ddc/odom", "nav_msgs/Odometry", odom.append, node="/test")
    cmd = master.bus.advertise("/twil/ros_control/ddc/cmd_vel", "geometry_msgs/Twist", node="/test")
    return master, hw, cm, cmd, odom


def test_wheel_speeds_odometry_and_timeout():
    master, hw, cm, cmd, odom = _controller()
    cmd.publish(_twist(0.5, 1.0))
    t = run(master, hw, cm, 0.001, 200)
    # (v -+ w s/2) / r = (0.5 -+ 0.2) / 0.1
    assert hw.velocity.tolist() == pytest.approx([3.0, 7.0])
    cm.publish_outbox()
    last = odom[-1]
    assert last.twist.twist.linear.x == pytest.approx(0.5, rel=1e-6)
    assert last.twist.twist.angular.z == pytest.approx(1.0, rel=1e-6)
    q = last.pose.pose.orientation
    assert 2 * math.atan2(q.z, q.w) == pytest.approx(0.199, abs=2e-3)  # 1 rad/s for ~0.2 s
    assert len(odom) == pytest.approx(0.2 * 50, abs=1)  # publish_rate 50 Hz
    run(master, hw, cm, t, 600)  # past cmd_vel_timeout 0.5 s: brake
    assert hw.velocity.tolist() == [0.0, 0.0]


def test_limits_and_nan_commands(caplog):
    master, hw, cm, cmd, odom = _controller(
        {
            "ddc/linear/x/has_velocity_limits": True,
            "ddc/linear/x/max_velocity": 0.2,
            "ddc/linear/x/has_acceleration_limits": True,
            "ddc/linear/x/max_acceleration": 1.0,
        }
    )
    cmd.publish(_twist(1.0, 0.0))
    run(master, hw, cm, 0.001, 100)  # 0.1 s at 1 m/s^2
    assert hw.velocity[0] == pytest.approx(0.1 / 0.1, rel=1e-9)
    run(master, hw, cm, 0.1, 300)
    assert hw.velocity[0] == pytest.approx(0.2 / 0.1)  # velocity limit
    cmd.publish(_twist(float("nan"), 0.0))
    run(master, hw, cm, 0.4, 10)
    assert hw.velocity[0] == pytest.approx(2.0)  # the NaN was ignored
    assert "Received NaN in velocity command. Ignoring." in caplog.text


def test_wheel_separation_and_radius_from_the_urdf(monkeypatch):
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(ROBOTS))
    packages.set_extra_paths([])
    urdf = run_xacro([str(ROBOTS / "tiny_description" / "urdf" / "tiny.urdf.xacro"), "drive:=ros_control"])
    assert wheel_geometry_from_urdf(urdf, *JOINTS) == pytest.approx((0.2, 0.05))
    master, node, hw, cm = make_cm(
        JOINTS,
        params={
            "ddc/type": "diff_drive_controller/DiffDriveController",
            "ddc/left_wheel": "left_wheel_joint",
            "ddc/right_wheel": "right_wheel_joint",
            "ddc/wheel_separation_multiplier": 2.0,
        },
    )
    master.params.set("/robot_description", urdf)  # searched upwards, as ROS
    assert cm.load_controller("ddc")
    assert cm.switch_controller(["ddc"], [], 2)
    cmd = master.bus.advertise("/twil/ros_control/ddc/cmd_vel", "geometry_msgs/Twist", node="/test")
    run(master, hw, cm, 0.0, 1)
    cmd.publish(_twist(0.1, 0.0))
    run(master, hw, cm, 0.001, 1)
    assert hw.velocity.tolist() == pytest.approx([2.0, 2.0])  # 0.1 m/s / 0.05 m
