"""twist_mux (priorities, timeouts, locks, husky_control's and jackal_control's YAML), joy_node
(a Linux joystick device, or none), teleop_twist_joy and the interactive marker server, without
a simulator: messages published at simulated times on the bus."""

from __future__ import annotations

import logging
import os
import struct

import pytest
import yaml

from twil_control import PACKAGE_ROOT
from twil_control.core.messages import msg_class
from twil_control.core.node import Master
from twil_control.core.params import ParamError
from twil_control.nodes.joystick import JoyNode, TeleopTwistJoy, scale_axis
from twil_control.nodes.marker_server import MarkerServer
from twil_control.nodes.twist_mux import TwistMux

VENDOR = PACKAGE_ROOT / "tests" / "data" / "ros1" / "vendor"


def _twist(x: float, w: float = 0.0):
    vec = msg_class("geometry_msgs/Vector3")
    return msg_class("geometry_msgs/Twist")(linear=vec(x=x, y=0.0, z=0.0), angular=vec(x=0.0, y=0.0, z=w))


def _mux(config_file=VENDOR / "husky_control" / "config" / "twist_mux.yaml"):
    master = Master()
    for key, value in yaml.safe_load(config_file.read_text()).items():
        master.params.set(f"/twist_mux/{key}", value, source=f"{config_file.name}:1")
    mux = TwistMux(master, "twist_mux", "/", {"/cmd_vel_out": "/husky_velocity_controller/cmd_vel"})
    out = []
    master.bus.subscribe("/husky_velocity_controller/cmd_vel", "geometry_msgs/Twist", out.append, node="/t")
    pubs = {
        name: master.bus.advertise(topic, kind, node="/t")
        for name, topic, kind in (
            ("joy", "/joy_teleop/cmd_vel", "geometry_msgs/Twist"),
            ("marker", "/twist_marker_server/cmd_vel", "geometry_msgs/Twist"),
            ("external", "/cmd_vel", "geometry_msgs/Twist"),
            ("e_stop", "/e_stop", "std_msgs/Bool"),
        )
    }
    return master, mux, out, pubs


def _at(master, t, pub, msg):
    master.spin_until(t)
    master.clock.set(t)
    pub.publish(msg)


def test_twist_mux_forwards_the_highest_priority_input_until_it_times_out():
    master, mux, out, pubs = _mux()
    assert [(h.name, h.priority, h.timeout) for h in mux.inputs] == [
        ("joy", 10, 0.5),
        ("kb", 9, 0.5),
        ("interactive_marker", 8, 0.5),
        ("external", 1, 0.5),
    ]
    _at(master, 1.0, pubs["external"], _twist(0.3))
    _at(master, 1.1, pubs["joy"], _twist(0.0, 1.0))  # the joystick takes over
    _at(master, 1.2, pubs["external"], _twist(0.3))  # masked: joy (10) beats external (1)
    _at(master, 1.5, pubs["joy"], _twist(0.0, 1.0))
    _at(master, 1.9, pubs["external"], _twist(0.3))  # joy's last message 0.4 s ago: still masked
    _at(master, 2.01, pubs["external"], _twist(0.3))  # 0.51 s: joy has timed out
    assert [(m.linear.x, m.angular.z) for m in out] == [(0.3, 0.0), (0.0, 1.0), (0.0, 1.0), (0.3, 0.0)]


def test_twist_mux_lock_masks_the_inputs_below_its_priority():
    master, _, out, pubs = _mux()
    bool_ = msg_class("std_msgs/Bool")
    _at(master, 1.0, pubs["e_stop"], bool_(data=True))  # priority 255, timeout 0: held until false
    _at(master, 1.1, pubs["external"], _twist(0.3))
    _at(master, 1.2, pubs["joy"], _twist(0.5))
    _at(master, 30.0, pubs["marker"], _twist(0.2))  # a lock without timeout never expires
    assert out == []
    _at(master, 30.1, pubs["e_stop"], bool_(data=False))
    _at(master, 30.2, pubs["marker"], _twist(0.2))
    assert [m.linear.x for m in out] == [0.2]


def test_twist_mux_lock_with_a_timeout_engages_when_its_publisher_goes_quiet():
    master = Master()
    master.params.set("/mux/topics", [{"name": "nav", "topic": "nav_vel", "timeout": 0.5, "priority": 10}])
    master.params.set("/mux/locks", [{"name": "alive", "topic": "alive", "timeout": 1.0, "priority": 100}])
    TwistMux(master, "mux", "/")
    out = []
    master.bus.subscribe("/cmd_vel_out", "geometry_msgs/Twist", out.append, node="/t")
    nav = master.bus.advertise("/nav_vel", "geometry_msgs/Twist", node="/t")
    alive = master.bus.advertise("/alive", "std_msgs/Bool", node="/t")
    _at(master, 0.5, nav, _twist(0.1))  # the lock's publisher has not missed its 1 s yet
    _at(master, 1.5, nav, _twist(0.1))  # 1.5 s without it: the lock is engaged
    _at(master, 1.6, alive, msg_class("std_msgs/Bool")(data=False))
    _at(master, 1.7, nav, _twist(0.1))
    assert [m.linear.x for m in out] == [0.1, 0.1] and len(out) == 2


def test_twist_mux_refuses_a_topic_without_its_priority():
    master = Master()
    master.params.set(
        "/mux/topics", [{"name": "nav", "topic": "nav_vel", "timeout": 0.5}], source="mux.yaml:3"
    )
    with pytest.raises(ParamError, match=r"mux.yaml:3: parameter /mux/topics\[0\] has no priority"):
        TwistMux(master, "mux", "/")


def test_joy_node_without_a_device_warns_once_and_stays_idle(caplog, tmp_path):
    master = Master()
    master.params.set("/joy_teleop/joy_node/dev", str(tmp_path / "js0"))
    JoyNode(master, "joy_node", "/joy_teleop")
    got = []
    master.bus.subscribe("/joy_teleop/joy", "sensor_msgs/Joy", got.append, node="/t")
    with caplog.at_level(logging.INFO, logger="twil_control.node"):
        master.spin_until(5.0)
    warnings = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert warnings == [f"Couldn't open joystick {tmp_path / 'js0'}. Will retry every second."]
    assert got == []


def test_joystick_events_drive_teleop_twist_joy_with_husky_s_ps4_settings(tmp_path):
    fifo = tmp_path / "js0"
    os.mkfifo(fifo)
    master = Master()
    config = yaml.safe_load((VENDOR / "husky_control" / "config" / "teleop_ps4.yaml").read_text())
    for node, values in config.items():
        for key, value in values.items():
            master.params.set(f"/joy_teleop/{node}/{key}", value)
    master.params.set("/joy_teleop/joy_node/dev", str(fifo))
    JoyNode(master, "joy_node", "/joy_teleop")
    TeleopTwistJoy(master, "teleop_twist_joy", "/joy_teleop")
    out = []
    master.bus.subscribe("/joy_teleop/cmd_vel", "geometry_msgs/Twist", out.append, node="/t")
    master.spin_until(0.05)  # joy_node opens the device
    writer = os.open(fifo, os.O_WRONLY | os.O_NONBLOCK)
    try:
        event = struct.Struct("<IhBB")
        # left stick pushed fully forward (axis 1 at -32767: joy flips the sign) and half left,
        # with the enable button (L1, 4) held: 0.4 m/s and 1.4 * the axis rad/s
        os.write(writer, event.pack(0, 1, 0x01, 4))
        os.write(writer, event.pack(0, -32767, 0x02, 1) + event.pack(0, -16384, 0x02, 0))
        master.spin_until(0.1)
        os.write(writer, event.pack(0, 0, 0x01, 4))  # enable released: one zero twist
        master.spin_until(0.2)
        os.write(writer, event.pack(0, 0, 0x02, 1))
        master.spin_until(0.3)
    finally:
        os.close(writer)
    axis = scale_axis(-16384, 0.1)
    assert out[-2].linear.x == pytest.approx(0.4) and out[-2].angular.z == pytest.approx(1.4 * axis)
    assert (out[-1].linear.x, out[-1].angular.z) == (0.0, 0.0)
    assert sum(m.linear.x == 0.0 and m.angular.z == 0.0 for m in out) == 1  # sent once
    assert scale_axis(-32767, 0.1) == pytest.approx(1.0) and scale_axis(2000, 0.1) == 0.0


def test_marker_server_advertises_its_cmd_vel_and_stays_idle(caplog):
    master = Master()
    master.params.set("/twist_marker_server/link_name", "base_link")
    with caplog.at_level(logging.INFO, logger="twil_control.node"):
        MarkerServer(master, "twist_marker_server", "/")
        master.spin_until(2.0)
    assert master.bus.publishers_of("/twist_marker_server/cmd_vel") == ["/twist_marker_server"]
    lines = [r.getMessage() for r in caplog.records]
    assert len(lines) == 1 and "no rviz client" in lines[0]
