"""controller_manager/spawner and controller_manager/controller_manager as nodes."""

from __future__ import annotations

import logging

import pytest
from support.ros_control_fakes import NS, make_cm, run

from twil_control.core.node import Master, NodeFailure
from twil_control.core.ros_node import NodeArgsError
from twil_control.launch import node_types
from twil_control.ros_control.nodes import ControllerManagerCli, Spawner

PARAMS = {
    "jsc": {"type": "joint_state_controller/JointStateController", "publish_rate": 50},
    "arm": {"type": "effort_controllers/JointGroupEffortController", "joints": ["j1", "j2"]},
    "bad": {"type": "nope/Nope"},
}


def states(cm):
    return {c.name: c.state for c in cm.list_controllers()}


def test_launch_node_types_resolve_to_these_classes():
    assert node_types.get("controller_manager", "spawner") is Spawner
    assert node_types.get("controller_manager", "controller_manager") is ControllerManagerCli


def test_spawner_loads_and_starts_then_shutdown_stops_and_unloads():
    master, node, hw, cm = make_cm(params=PARAMS)
    sp = Spawner(master, "spawner", namespace=NS, args=["jsc", "arm"])
    sp.on_start()
    assert states(cm) == {"jsc": "initialized", "arm": "initialized"}  # started by the first update
    run(master, hw, cm, 0.0, 2)
    assert states(cm) == {"jsc": "running", "arm": "running"}
    assert sp.started and sp.loaded == ["jsc", "arm"]
    sp.shutdown()
    assert cm.list_controllers() == []


def test_spawner_stopped_only_loads_and_shutdown_unloads():
    master, node, hw, cm = make_cm(params=PARAMS)
    sp = Spawner(master, "spawner", namespace=NS, args=["--stopped", "arm"])
    sp.on_start()
    run(master, hw, cm, 0.0, 2)
    assert states(cm) == {"arm": "initialized"}
    sp.shutdown()
    assert cm.list_controllers() == []


def test_spawner_namespace_option_finds_the_manager_elsewhere():
    master, node, hw, cm = make_cm(params=PARAMS)
    sp = Spawner(master, "spawner", namespace="/", args=["--namespace", NS, "--shutdown-timeout", "1", "jsc"])
    assert sp.service("load_controller") == f"{NS}/controller_manager/load_controller"
    sp.on_start()
    run(master, hw, cm, 0.0, 1)
    assert states(cm) == {"jsc": "running"}


def test_spawner_loads_and_starts_the_others_then_fails_with_the_reason(caplog):
    """As the ROS script, the other controllers are loaded and started; then, unlike it, the
    spawner fails (a node failure: the launch decides whether that stops it)."""
    master, node, hw, cm = make_cm(params=PARAMS)
    sp = Spawner(master, "spawner", namespace=NS, args=["bad", "jsc"])
    assert sp.required_by_default
    with caplog.at_level(logging.ERROR), pytest.raises(NodeFailure) as failure:
        sp.on_start()
    assert "Failed to load bad" in caplog.text
    assert str(failure.value).startswith(
        "Failed to load bad: Could not load controller 'bad' because controller type 'nope/Nope'"
    )  # the manager's reason
    assert sp.failed == ["bad"] and sp.loaded == ["jsc"]
    run(master, hw, cm, 0.0, 1)
    assert states(cm) == {"jsc": "running"}


def test_two_spawners_before_the_first_update_and_shutdown_before_any_update():
    master, node, hw, cm = make_cm(params=PARAMS)
    s1 = Spawner(master, "s1", namespace=NS, args=["jsc"])
    s2 = Spawner(master, "s2", namespace=NS, args=["arm"])
    s1.on_start()
    s2.on_start()
    assert s1.started and s2.started
    s2.shutdown()  # queued start then stop are performed before the unload
    s1.shutdown()
    assert cm.list_controllers() == []


def test_spawner_without_manager_fails():
    master = Master()
    sp = Spawner(master, "spawner", namespace=NS, args=["jsc"])
    with pytest.raises(
        NodeFailure,
        match="couldn't find the expected controller_manager ROS interface: "
        "service /twil/ros_control/controller_manager/load_controller "
        "is not advertised",
    ):
        sp.on_start()
    assert sp.loaded == [] and sp.failed == ["jsc"]


def test_spawner_wait_for_topic():
    master, node, hw, cm = make_cm(params=PARAMS)
    sp = Spawner(master, "spawner", namespace=NS, args=["--wait-for", "/ready", "jsc"])
    sp.on_start()
    assert cm.list_controllers() == []
    from twil_control.core.messages import msg_class

    pub = node.create_publisher("/ready", "std_msgs/Bool")
    pub.publish(msg_class("std_msgs/Bool")(data=False))
    assert cm.list_controllers() == []
    pub.publish(msg_class("std_msgs/Bool")(data=True))
    assert [c.name for c in cm.list_controllers()] == ["jsc"]


def test_spawner_needs_controller_names():
    with pytest.raises(NodeArgsError):
        Spawner(Master(), "spawner", namespace=NS, args=["--stopped"])


def cli(master, *args):
    node = ControllerManagerCli(master, f"cm_cli_{len(master.nodes)}", namespace=NS, args=list(args))
    node.on_start()
    return node


def test_controller_manager_script_commands():
    master, node, hw, cm = make_cm(params=PARAMS)
    assert cli(master, "list").output == ["No controllers are loaded in mechanism control"]
    assert cli(master, "load", "jsc").output == ["Loaded jsc"]
    assert cli(master, "spawn", "arm").output == ["Loaded arm", "Started ['arm'] successfully"]
    run(master, hw, cm, 0.0, 1)
    assert cli(master, "start", "jsc").ok
    run(master, hw, cm, 0.001, 1)
    assert cli(master, "lc").output == [
        "jsc - hardware_interface::JointStateInterface ( running )",
        "arm - hardware_interface::EffortJointInterface ( running )",
    ]
    assert cli(master, "stop", "jsc").ok
    run(master, hw, cm, 0.002, 1)
    assert cli(master, "unload", "jsc").output == ["Unloaded jsc successfully"]
    assert cli(master, "kill", "arm").output == ["Stopped ['arm'] successfully", "Unloaded arm successfully"]
    assert "effort_controllers/JointEffortController" in cli(master, "list-types").output
    bad = ControllerManagerCli(master, "cm_cli_bad", namespace=NS, args=["load", "bad"])
    with pytest.raises(
        NodeFailure,
        match="Error when loading bad: Could not load controller 'bad' because controller type 'nope/Nope'",
    ):
        bad.on_start()
    assert not bad.ok and bad.output == ["Error when loading bad"]
    assert cli(master, "reload-libraries").ok


def test_controller_manager_script_refuses_unknown_command():
    with pytest.raises(NodeArgsError, match="unknown command 'frobnicate'"):
        ControllerManagerCli(Master(), "cli", namespace=NS, args=["frobnicate"])
