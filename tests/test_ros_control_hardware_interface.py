"""hardware_interface replica: handles, interfaces, claims, switching modes, finite commands."""

from __future__ import annotations

import math

import numpy as np
import pytest

from twil_control.ros_control import (
    EFFORT_JOINT_INTERFACE,
    JOINT_STATE_INTERFACE,
    POSITION_JOINT_INTERFACE,
    VELOCITY_JOINT_INTERFACE,
    ControllerInfo,
    HardwareInterfaceError,
    InterfaceResources,
    JointHandle,
    JointStateHandle,
    RobotHW,
)


def hw():
    return RobotHW(
        ["base_l", "base_r", "arm"],
        {
            "base_l": ["velocity"],
            "base_r": ["hardware_interface/VelocityJointInterface"],
            "arm": ["effort", "hardware_interface::PositionJointInterface"],
        },
    )


def test_interface_type_names_are_the_ones_ros_prints():
    assert JOINT_STATE_INTERFACE == "hardware_interface::JointStateInterface"
    assert EFFORT_JOINT_INTERFACE == "hardware_interface::EffortJointInterface"
    assert VELOCITY_JOINT_INTERFACE == "hardware_interface::VelocityJointInterface"
    assert POSITION_JOINT_INTERFACE == "hardware_interface::PositionJointInterface"
    assert hw().interface_types() == [
        JOINT_STATE_INTERFACE,
        EFFORT_JOINT_INTERFACE,
        VELOCITY_JOINT_INTERFACE,
        POSITION_JOINT_INTERFACE,
    ]
    assert RobotHW(["a"], {"a": ["EffortJointInterface"]}).interface_types() == [
        JOINT_STATE_INTERFACE,
        EFFORT_JOINT_INTERFACE,
    ]


def test_handles_see_the_arrays_read_fills_in_place():
    h = hw()
    state = h.get_handle(JOINT_STATE_INTERFACE, "arm")
    cmd = h.get_handle(EFFORT_JOINT_INTERFACE, "arm")
    assert isinstance(state, JointStateHandle) and not isinstance(state, JointHandle)
    h.position[:] = [1.0, 2.0, 3.0]
    h.velocity[2] = -1.0
    h.effort[2] = 7.0
    assert (state.position, state.velocity, state.effort) == (3.0, -1.0, 7.0)
    assert (cmd.get_position(), cmd.get_name()) == (3.0, "arm")
    cmd.set_command(4.5)
    assert h.command("effort")[2] == 4.5 and cmd.command == cmd.get_command() == 4.5
    cmd.command = -1.0
    assert h.commands[EFFORT_JOINT_INTERFACE][2] == -1.0
    assert not hasattr(state, "set_command")


def test_get_handle_errors_name_joint_interface_and_what_exists():
    h = hw()
    with pytest.raises(HardwareInterfaceError) as info:
        h.get_handle(EFFORT_JOINT_INTERFACE, "base_l")
    msg = str(info.value)
    assert "'base_l'" in msg and EFFORT_JOINT_INTERFACE in msg and "velocity" in msg and "arm" in msg
    with pytest.raises(HardwareInterfaceError, match="could not find joint 'elbow'.*base_l, base_r, arm"):
        h.get_handle(JOINT_STATE_INTERFACE, "elbow")
    with pytest.raises(HardwareInterfaceError, match="unknown interface type 'foo'"):
        h.get_handle("foo", "arm")
    only_effort = RobotHW(["a"], {"a": ["effort"]})
    with pytest.raises(HardwareInterfaceError, match="no joint of this RobotHW has that interface"):
        only_effort.get_handle(VELOCITY_JOINT_INTERFACE, "a")
    with pytest.raises(HardwareInterfaceError, match="unknown command interface 'torque'"):
        RobotHW(["a"], {"a": ["torque"]})
    with pytest.raises(HardwareInterfaceError, match="unknown joint 'b'"):
        RobotHW(["a"], {"b": ["effort"]})


def test_only_command_interfaces_claim_joints():
    h = hw()
    h.clear_claims()
    h.get_handle(JOINT_STATE_INTERFACE, "base_l")
    h.get_handle(VELOCITY_JOINT_INTERFACE, "base_r")
    h.get_handle(VELOCITY_JOINT_INTERFACE, "base_l")
    assert h.get_claims() == {VELOCITY_JOINT_INTERFACE: ["base_l", "base_r"]}


def test_do_switch_sets_and_clears_active_modes_stops_first():
    h = hw()
    arm_effort = ControllerInfo("ct", "t", [InterfaceResources(EFFORT_JOINT_INTERFACE, ["arm"])])
    arm_position = ControllerInfo("pos", "t", [InterfaceResources(POSITION_JOINT_INTERFACE, ["arm"])])
    base = ControllerInfo(
        "base",
        "t",
        [
            InterfaceResources(VELOCITY_JOINT_INTERFACE, ["base_l", "base_r"]),
            InterfaceResources(JOINT_STATE_INTERFACE, []),
        ],
    )
    assert h.active_mode("arm") is None
    assert h.prepare_switch([arm_effort, base], [])
    h.do_switch([arm_effort, base], [])
    assert [h.active_mode(j) for j in h.joint_names] == ["velocity", "velocity", "effort"]
    h.do_switch([arm_position], [arm_effort])
    assert h.active_mode("arm") == "position"
    h.do_switch([], [base])
    assert h.active_mode("base_l") is None
    bad = ControllerInfo("bad", "t", [InterfaceResources(EFFORT_JOINT_INTERFACE, ["base_l"])])
    assert not h.prepare_switch([bad], [])


def test_check_for_conflict():
    h = hw()
    a = ControllerInfo("a", "t", [InterfaceResources(EFFORT_JOINT_INTERFACE, ["arm"])])
    b = ControllerInfo("b", "t", [InterfaceResources(POSITION_JOINT_INTERFACE, ["arm"])])
    jsc = ControllerInfo("jsc", "t", [InterfaceResources(JOINT_STATE_INTERFACE, [])])
    multi = ControllerInfo(
        "m",
        "t",
        [
            InterfaceResources(EFFORT_JOINT_INTERFACE, ["arm"]),
            InterfaceResources(POSITION_JOINT_INTERFACE, ["arm"]),
        ],
    )
    assert h.check_for_conflict([a, b])
    assert not h.check_for_conflict([a, jsc])
    assert not h.check_for_conflict([multi, jsc])


def test_finite_commands_replace_non_finite_with_zero_and_name_the_joints():
    h = hw()
    h.command("velocity")[:] = [math.nan, 1.0, math.inf]
    values, bad = h.finite_commands(VELOCITY_JOINT_INTERFACE)
    np.testing.assert_array_equal(values, [0.0, 1.0, 0.0])
    assert bad == ["base_l", "arm"]
    assert math.isnan(h.command("velocity")[0])  # the command array itself is untouched
    assert h.finite_commands("effort")[1] == []


def test_base_read_write_are_noops_and_joint_lists():
    h = hw()
    h.read(0.0, 0.001)
    h.write(0.0, 0.001)
    assert h.joints_of(VELOCITY_JOINT_INTERFACE) == ["base_l", "base_r"]
    assert h.joints_of(JOINT_STATE_INTERFACE) == ["base_l", "base_r", "arm"]
    assert h.supported_modes("arm") == ["effort", "position"]
    with pytest.raises(HardwareInterfaceError, match="duplicate"):
        RobotHW(["a", "a"])
