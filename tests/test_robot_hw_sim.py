"""The Drake hardware adapter (gazebo_ros_control's DefaultRobotHWSim role), on the fixed WAM:
effort limits from the description, NaN/inf refused, and velocity/position commands through a
PID or Drake's implicit joint PD, chosen by config."""

from __future__ import annotations

import logging
import math
import textwrap

import numpy as np
import pytest

from twil_control.core.messages import msg_class
from twil_control.launch.loader import load_launch
from twil_control.launch.runner import Launch

JOINT4 = "wam_joint_4"


OTHERS = ["wam_joint_1", "wam_joint_2", "wam_joint_3", "wam_joint_5", "wam_joint_6", "wam_joint_7"]


def _launch(tmp_path, joint4: str, controller: str, hold_others: bool = False):
    """The WAM welded in an empty world; joint 4 configured by `joint4`, driven by `controller`.
    The other joints are idle in effort mode (the arm sags under gravity), or, with
    `hold_others`, held where they start by a group position controller through Drake's
    implicit PD."""
    other = (
        "{interfaces: [position], implicit_pd: {p: 2000.0, d: 100.0}}"
        if hold_others
        else "{interfaces: [effort]}"
    )
    joints = "\n".join(f"    {j}: {other}" for j in OTHERS)
    hold = (
        f"hold: {{type: position_controllers/JointGroupPositionController, joints: {OTHERS}}}"
        if hold_others
        else ""
    )
    (tmp_path / "hw.yaml").write_text(
        f"gazebo_ros_control:\n  model: wam\n  joints:\n{joints}\n    {JOINT4}: {joint4}\n"
        f"j4_controller: {controller}\n{hold}\n"
    )
    (tmp_path / "hw.launch.yaml").write_text(
        textwrap.dedent(f"""
        launch:
          - rosparam: {{file: "{tmp_path / "hw.yaml"}", ns: /wam}}
          - node: {{pkg: twil_control, type: drake_world, name: world,
                   params: {{world: "$(find twil_control)/sim/worlds/default.sdf"}}}}
          - node: {{pkg: gazebo_ros, type: spawn_model, name: spawn, args: "-file wam_fixed -model wam"}}
          - node: {{pkg: twil_control, type: robot_hw_sim, name: gazebo_ros_control, ns: /wam}}
          - node: {{pkg: controller_manager, type: spawner, name: spawner, ns: /wam,
                   args: "j4_controller{" hold" if hold_others else ""}"}}
    """)
    )
    launch = Launch(load_launch(tmp_path / "hw.launch.yaml"))
    launch.build()
    launch.start()
    hw_node = next(n for n in launch.nodes if getattr(n, "hw", None) is not None)
    command = launch.master.bus.advertise("/wam/j4_controller/command", "std_msgs/Float64")
    return launch, hw_node, lambda v: command.publish(msg_class("std_msgs/Float64")(data=v))


def _joint4(launch, hw_node):
    plant = launch.sim.plant
    ctx = plant.GetMyContextFromRoot(launch.simulator.get_context())
    joint = plant.GetJointByName(JOINT4)
    return (
        joint.get_angle(ctx),
        joint.get_angular_rate(ctx),
        hw_node.hw.effort[hw_node.hw.joint_index(JOINT4)],
    )


def test_effort_commands_are_clipped_to_the_description_limit(tmp_path):
    launch, hw_node, send = _launch(
        tmp_path,
        "{interfaces: [effort]}",
        f"{{type: effort_controllers/JointEffortController, joint: {JOINT4}}}",
    )
    launch.simulator.AdvanceTo(0.01)
    send(1000.0)
    launch.simulator.AdvanceTo(0.02)
    limit = launch.sim.plant.GetJointActuatorByName(JOINT4).effort_limit()
    assert limit == pytest.approx(28.8)
    assert _joint4(launch, hw_node)[2] == pytest.approx(limit)
    send(-1000.0)
    launch.simulator.AdvanceTo(0.03)
    assert _joint4(launch, hw_node)[2] == pytest.approx(-limit)


def test_non_finite_commands_never_reach_the_plant(tmp_path, caplog):
    launch, hw_node, send = _launch(
        tmp_path,
        "{interfaces: [effort]}",
        f"{{type: effort_controllers/JointEffortController, joint: {JOINT4}}}",
    )
    launch.simulator.AdvanceTo(0.01)
    send(5.0)
    launch.simulator.AdvanceTo(0.02)
    assert _joint4(launch, hw_node)[2] == pytest.approx(5.0)
    # Bypass the controller's own NaN filter: write NaN straight into the command interface.
    hw = hw_node.hw
    with caplog.at_level(logging.ERROR):
        for bad in (math.nan, math.inf):
            hw.command("effort")[hw.joint_index(JOINT4)] = bad
            hw.write(0.0, 0.001)
            assert hw.effort[hw.joint_index(JOINT4)] == 0.0
            assert np.isfinite(hw.actuation).all()
    refusals = [r for r in caplog.records if "non-finite" in r.getMessage() and JOINT4 in r.getMessage()]
    assert len(refusals) == 1  # logged once per joint


# An explicit PID's gain is bounded by the 1 ms loop (p = 200 on this light distal inertia is
# unstable, as it would be on the real robot); Drake's implicit PD takes any gain.
@pytest.mark.parametrize(
    "gains", ["pid: {p: 20.0, i: 400.0, d: 0.0, i_clamp: 30.0}", "implicit_pd: {p: 0.0, d: 200.0}"]
)
def test_velocity_commands_track_through_pid_or_implicit_pd(tmp_path, gains):
    launch, hw_node, send = _launch(
        tmp_path,
        f"{{interfaces: [velocity], {gains}}}",
        f"{{type: velocity_controllers/JointVelocityController, joint: {JOINT4}}}",
    )
    launch.simulator.AdvanceTo(0.01)
    send(0.5)
    launch.simulator.AdvanceTo(1.0)
    _, rate, _ = _joint4(launch, hw_node)
    assert rate == pytest.approx(0.5, abs=0.05)


# The rest of the arm is held: left idle it swings under gravity and shakes joint 4, whose error
# at any one instant then depends on where the swing is (up to 0.47 rad between 1 s and 2 s).
@pytest.mark.parametrize(
    "gains", ["pid: {p: 2000.0, i: 0.0, d: 100.0}", "implicit_pd: {p: 2000.0, d: 100.0}"]
)
def test_position_commands_converge_through_pid_or_implicit_pd(tmp_path, gains):
    launch, hw_node, send = _launch(
        tmp_path,
        f"{{interfaces: [position], {gains}}}",
        f"{{type: position_controllers/JointPositionController, joint: {JOINT4}}}",
        hold_others=True,
    )
    launch.simulator.AdvanceTo(0.01)
    send(1.0)
    settled = []
    for t in np.arange(1.5, 2.0001, 0.05):  # settled: within 0.01 rad and still for the last 0.5 s
        launch.simulator.AdvanceTo(t)
        angle, rate, _ = _joint4(launch, hw_node)
        settled.append(abs(angle - 1.0) < 0.01 and abs(rate) < 0.01)
    assert all(settled), settled


def test_velocity_interface_without_gains_is_a_config_error(tmp_path):
    with pytest.raises(ValueError, match="no 'pid' or 'implicit_pd' gains"):
        _launch(
            tmp_path,
            "{interfaces: [velocity]}",
            f"{{type: velocity_controllers/JointVelocityController, joint: {JOINT4}}}",
        )
