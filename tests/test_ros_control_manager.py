"""controller_manager: load/unload/switch rules, the switch inside update(), aborts, listing."""

from __future__ import annotations

import logging

import pytest
from support.ros_control_fakes import EVENTS, NS, make_cm, run

from twil_control.ros_control import BEST_EFFORT, SERVICES, STRICT, registry
from twil_control.ros_control.srv import SwitchControllerRequest

PARAMS = {
    "a": {"type": "test_controllers/Recorder", "joints": ["j1", "j2"]},
    "b": {"type": "test_controllers/Recorder", "joints": ["j2"]},
    "c": {"type": "test_controllers/Recorder", "joints": ["j3"]},
    "jsc": {"type": "joint_state_controller/JointStateController", "publish_rate": 50},
    "bad_type": {"type": "nope/NoSuchController"},
    "no_type": {"joints": ["j1"]},
    "int_type": {"type": 3},
    "init_false": {"type": "test_controllers/InitFalse"},
    "init_raise": {"type": "test_controllers/InitRaise"},
    "raiser": {"type": "test_controllers/Raiser", "joints": ["j3"]},
    "stop_raiser": {"type": "test_controllers/StopRaiser", "joints": ["j1", "j2"]},
}


@pytest.fixture
def setup():
    EVENTS.clear()
    return make_cm(params=PARAMS, events=EVENTS)


def states(cm):
    return {c.name: c.state for c in cm.list_controllers()}


# -- load ------------------------------------------------------------------------------------
def test_load_reads_type_under_manager_namespace_and_initializes(setup):
    master, node, hw, cm = setup
    assert cm.load_controller("a")
    assert states(cm) == {"a": "initialized"}
    assert ("init", "a") in EVENTS


def test_load_refuses_duplicate_name(setup):
    *_, cm = setup
    assert cm.load_controller("a")
    assert not cm.load_controller("a")
    assert "already loaded" in cm.last_error and "'a'" in cm.last_error


def test_load_refuses_unknown_type_listing_known_types(setup):
    *_, cm = setup
    assert not cm.load_controller("bad_type")
    assert "nope/NoSuchController" in cm.last_error
    assert "effort_controllers/JointEffortController" in cm.last_error
    assert cm.list_controllers() == []


def test_load_refuses_missing_type_naming_the_parameter(setup):
    *_, cm = setup
    assert not cm.load_controller("no_type")
    assert f"{NS}/no_type/type" in cm.last_error
    assert not cm.load_controller("never_configured")
    assert f"{NS}/never_configured/type" in cm.last_error


def test_load_refuses_non_string_type(setup):
    *_, cm = setup
    assert not cm.load_controller("int_type")
    assert f"{NS}/int_type/type" in cm.last_error


def test_load_refuses_when_init_returns_false_with_the_reason(setup, caplog):
    *_, cm = setup
    with caplog.at_level(logging.ERROR):
        assert not cm.load_controller("init_false")
    assert "Initializing controller 'init_false' failed" in cm.last_error
    assert "the gains are missing" in cm.last_error
    assert "Initializing controller 'init_false' failed" in caplog.text
    assert cm.list_controllers() == []


def test_load_refuses_when_init_raises(setup):
    *_, cm = setup
    assert not cm.load_controller("init_raise")
    assert "init_raise" in cm.last_error and "RuntimeError: init exploded" in cm.last_error


def test_load_refuses_controller_whose_interface_the_hw_lacks():
    from support.ros_control_fakes import FakeHW

    from twil_control.core.node import Master, Node
    from twil_control.ros_control import ControllerManager

    master = Master()
    master.params.set(f"{NS}/v", {"type": "velocity_controllers/JointVelocityController", "joint": "j1"})
    hw = FakeHW(modes=("effort",))
    cm = ControllerManager(hw, Node(master, "cm", namespace=NS))
    assert not cm.load_controller("v")
    assert "hardware_interface::VelocityJointInterface" in cm.last_error


# -- unload ----------------------------------------------------------------------------------
def test_unload_refused_while_running_allowed_when_stopped(setup):
    master, node, hw, cm = setup
    cm.load_controller("a")
    cm.switch_controller(["a"], [], STRICT)
    run(master, hw, cm, 0.0, 1)
    assert not cm.unload_controller("a")
    assert "still running" in cm.last_error
    assert cm.switch_controller([], ["a"], STRICT)
    run(master, hw, cm, 0.001, 1)
    assert cm.unload_controller("a")
    assert cm.list_controllers() == []
    assert not cm.unload_controller("a")
    assert "no controller with this name exists" in cm.last_error


def test_unload_after_queued_stop_performs_the_stop_first(setup):
    """ROS's switch service blocks until the loop switched; a stop then unload therefore works."""
    master, node, hw, cm = setup
    cm.load_controller("a")
    cm.switch_controller(["a"], [], STRICT)
    run(master, hw, cm, 0.0, 1)
    cm.switch_controller([], ["a"], STRICT)
    assert cm.unload_controller("a")
    assert ("stopping", "a", 0.0) in EVENTS


# -- switch: STRICT / BEST_EFFORT ----------------------------------------------------------
def test_strict_refuses_unknown_names(setup):
    *_, cm = setup
    cm.load_controller("a")
    assert not cm.switch_controller(["a", "ghost"], [], STRICT)
    assert "ghost" in cm.last_error and "no controller with this name exists" in cm.last_error
    assert not cm.switch_controller([], ["ghost"], STRICT)
    assert not cm.switch_pending


def test_strict_refuses_stopping_a_controller_that_is_not_running(setup):
    *_, cm = setup
    cm.load_controller("a")
    assert not cm.switch_controller([], ["a"], STRICT)
    assert "Could not stop controller 'a' since it is not running" in cm.last_error


def test_strict_refuses_starting_a_running_controller(setup):
    master, node, hw, cm = setup
    cm.load_controller("a")
    cm.switch_controller(["a"], [], STRICT)
    run(master, hw, cm, 0.0, 1)
    assert not cm.switch_controller(["a"], [], STRICT)
    assert "Controller 'a' is already running" in cm.last_error


def test_strict_checks_against_queued_switches(setup):
    """Two spawners before the first update: the second sees the first one's start."""
    *_, cm = setup
    cm.load_controller("a")
    assert cm.switch_controller(["a"], [], STRICT)
    assert not cm.switch_controller(["a"], [], STRICT)
    assert "already running" in cm.last_error


def test_best_effort_skips_unknown_stopped_and_running(setup):
    master, node, hw, cm = setup
    for name in ("a", "c"):
        cm.load_controller(name)
    cm.switch_controller(["a"], [], STRICT)
    run(master, hw, cm, 0.0, 1)
    # a is running (start skipped), c is not running (stop skipped), ghost unknown (skipped)
    assert cm.switch_controller(["a", "ghost"], ["c", "ghost2"], BEST_EFFORT)
    assert cm.last_error == ""
    assert not cm.switch_pending
    assert cm.switch_controller(["c", "a"], ["ghost"], BEST_EFFORT)
    run(master, hw, cm, 0.001, 1)
    assert states(cm) == {"a": "running", "c": "running"}


def test_strictness_zero_is_best_effort_with_a_warning(setup, caplog):
    *_, cm = setup
    cm.load_controller("a")
    with caplog.at_level(logging.WARNING):
        assert cm.switch_controller(["a", "ghost"], [], 0)
    assert "Defaulting to ::BEST_EFFORT" in caplog.text


def test_same_controller_in_both_lists_refused_under_any_strictness(setup):
    master, node, hw, cm = setup
    cm.load_controller("a")
    cm.switch_controller(["a"], [], STRICT)
    run(master, hw, cm, 0.0, 1)
    for strictness in (BEST_EFFORT, STRICT):
        assert not cm.switch_controller(["a"], ["a"], strictness)
        assert "both the start and the stop list" in cm.last_error


# -- switch: resources ---------------------------------------------------------------------
def test_resource_conflict_refused_naming_joint_and_controllers(setup):
    master, node, hw, cm = setup
    for name in ("a", "b"):
        cm.load_controller(name)
    assert not cm.switch_controller(["a", "b"], [], STRICT)
    assert "resource conflict" in cm.last_error and "'j2'" in cm.last_error
    cm.switch_controller(["a"], [], STRICT)
    run(master, hw, cm, 0.0, 1)
    assert not cm.switch_controller(["b"], [], BEST_EFFORT)
    assert "'j2' by 'a' and 'b'" in cm.last_error


def test_conflict_ok_when_the_holder_is_in_the_stop_list(setup):
    master, node, hw, cm = setup
    for name in ("a", "b"):
        cm.load_controller(name)
    cm.switch_controller(["a"], [], STRICT)
    run(master, hw, cm, 0.0, 1)
    assert cm.switch_controller(["b"], ["a"], STRICT)
    run(master, hw, cm, 0.001, 1)
    assert states(cm) == {"a": "stopped", "b": "running"}
    assert hw.active_mode("j1") is None and hw.active_mode("j2") == "effort"


def test_joint_state_controller_never_conflicts(setup):
    master, node, hw, cm = setup
    for name in ("jsc", "a", "c"):
        cm.load_controller(name)
    assert cm.switch_controller(["jsc", "a", "c"], [], STRICT)


def test_prepare_switch_refusal_is_a_refusal(setup):
    master, node, hw, cm = setup
    cm.load_controller("a")
    hw.prepare_ok = False
    assert not cm.switch_controller(["a"], [], STRICT)
    assert "unfeasible" in cm.last_error


# -- switch timing and order ----------------------------------------------------------------
def test_switch_happens_at_next_update_stops_before_starts(setup):
    master, node, hw, cm = setup
    for name in ("a", "b"):
        cm.load_controller(name)
    cm.switch_controller(["a"], [], STRICT)
    assert states(cm)["a"] == "initialized"  # nothing until the loop runs
    run(master, hw, cm, 0.0, 2)
    EVENTS.clear()
    assert cm.switch_controller(["b"], ["a"], STRICT)
    assert states(cm) == {"a": "running", "b": "initialized"}
    assert EVENTS[0][0] == "prepare_switch" and len(EVENTS) == 1  # checked at request time only
    run(master, hw, cm, 0.002, 1)
    assert EVENTS[1:] == [
        ("do_switch", ["b"], ["a"]),
        ("stopping", "a", 0.002),
        ("starting", "b", 0.002),
        ("update", "b", 0.002),
    ]
    assert states(cm) == {"a": "stopped", "b": "running"}


def test_running_controllers_update_in_load_order(setup):
    master, node, hw, cm = setup
    for name in ("c", "a"):
        cm.load_controller(name)
    cm.switch_controller(["a", "c"], [], STRICT)
    run(master, hw, cm, 0.0, 2)
    updates = [e[1] for e in EVENTS if e[0] == "update"]
    assert updates == ["c", "a", "c", "a"]


def test_reset_controllers_restarts_running_ones(setup):
    master, node, hw, cm = setup
    cm.load_controller("a")
    cm.switch_controller(["a"], [], STRICT)
    run(master, hw, cm, 0.0, 1)
    EVENTS.clear()
    cm.update(0.001, 0.001, reset_controllers=True)
    assert [e[0] for e in EVENTS] == ["stopping", "starting", "update"]


# -- aborts --------------------------------------------------------------------------------
def test_controller_raising_in_update_is_aborted_and_others_keep_running(setup, caplog):
    master, node, hw, cm = setup
    for name in ("a", "raiser"):
        cm.load_controller(name)
    cm.switch_controller(["a", "raiser"], [], STRICT)
    with caplog.at_level(logging.ERROR):
        run(master, hw, cm, 0.0, 10)  # must not raise
    assert states(cm) == {"a": "running", "raiser": "aborted"}
    assert cm.get_controller("a").updates == 10
    assert cm.get_controller("raiser").updates == 3
    assert ("aborting", "raiser", 0.002) in EVENTS
    errors = [r.getMessage() for r in caplog.records if r.levelno >= logging.ERROR]
    assert len(errors) == 1
    assert "'raiser'" in errors[0] and "ZeroDivisionError: boom in update" in errors[0]
    assert hw.active_mode("j3") is None  # its joint is released


def test_controller_raising_in_stopping_is_aborted_without_freeing_joints_taken_over(setup):
    master, node, hw, cm = setup
    for name in ("stop_raiser", "b"):
        cm.load_controller(name)
    cm.switch_controller(["stop_raiser"], [], STRICT)
    run(master, hw, cm, 0.0, 1)
    assert cm.switch_controller(["b"], ["stop_raiser"], STRICT)
    run(master, hw, cm, 0.001, 1)
    assert states(cm) == {"stop_raiser": "aborted", "b": "running"}
    assert "raised in stopping()" in cm.last_error
    assert (hw.active_mode("j1"), hw.active_mode("j2")) == (None, "effort")


def test_aborted_controller_cannot_be_started_or_stopped_but_can_be_unloaded(setup):
    master, node, hw, cm = setup
    cm.load_controller("raiser")
    cm.switch_controller(["raiser"], [], STRICT)
    run(master, hw, cm, 0.0, 5)
    assert not cm.switch_controller(["raiser"], [], STRICT)
    assert "aborted" in cm.last_error
    assert not cm.switch_controller([], ["raiser"], STRICT)
    assert "not running" in cm.last_error
    assert cm.switch_controller(["raiser"], [], BEST_EFFORT) and not cm.switch_pending
    assert cm.unload_controller("raiser")
    assert cm.load_controller("raiser")
    assert states(cm) == {"raiser": "initialized"}


# -- listing and services ------------------------------------------------------------------
def test_list_controllers_fields(setup):
    master, node, hw, cm = setup
    for name in ("jsc", "a"):
        cm.load_controller(name)
    cm.switch_controller(["jsc"], [], STRICT)
    run(master, hw, cm, 0.0, 1)
    jsc, a = cm.list_controllers()
    assert (jsc.name, jsc.type, jsc.state) == (
        "jsc",
        "joint_state_controller/JointStateController",
        "running",
    )
    assert [(r.hardware_interface, r.resources) for r in jsc.claimed_resources] == [
        ("hardware_interface::JointStateInterface", [])
    ]
    assert (a.name, a.type, a.state) == ("a", "test_controllers/Recorder", "initialized")
    assert [(r.hardware_interface, r.resources) for r in a.claimed_resources] == [
        ("hardware_interface::EffortJointInterface", ["j1", "j2"])
    ]


def test_list_controller_types(setup):
    *_, cm = setup
    types = dict(cm.list_controller_types())
    assert types["joint_state_controller/JointStateController"] == "controller_interface::ControllerBase"
    assert "test_controllers/Recorder" in types


def test_services_are_advertised_under_namespace_controller_manager(setup):
    master, node, hw, cm = setup
    assert {f"{NS}/{s}" for s in SERVICES} <= set(master.services)
    call = master.call_service
    assert call(f"{NS}/controller_manager/load_controller", "a").ok
    assert not call(f"{NS}/controller_manager/load_controller", "a").ok
    assert not call(f"{NS}/controller_manager/switch_controller", ["ghost"], [], STRICT).ok  # positional
    assert call(
        f"{NS}/controller_manager/switch_controller",
        SwitchControllerRequest(start_controllers=["a"], strictness=STRICT),
    ).ok  # request object
    run(master, hw, cm, 0.0, 1)
    resp = call(f"{NS}/controller_manager/list_controllers")
    assert [(c.name, c.state) for c in resp.controller] == [("a", "running")]
    types = call(f"{NS}/controller_manager/list_controller_types")
    assert len(types.types) == len(types.base_classes) and "test_controllers/Recorder" in types.types
    assert not call(f"{NS}/controller_manager/unload_controller", "a").ok
    assert not call(f"{NS}/controller_manager/reload_controller_libraries", force_kill=False).ok
    assert call(f"{NS}/controller_manager/reload_controller_libraries", force_kill=True).ok
    assert cm.list_controllers() == []


def test_unloading_drops_the_controllers_subscriptions(setup):
    master, node, hw, cm = setup
    master.params.set(f"{NS}/e", {"type": "effort_controllers/JointEffortController", "joint": "j1"})
    cm.load_controller("e")
    assert master.bus.subscribers_of(f"{NS}/e/command") == [node.fqn]
    sub = cm._find("e").subscriptions[0]
    cm.unload_controller("e")
    assert not sub.active


def test_registry_types_unaffected(setup):
    assert "test_controllers/Raiser" in registry.types()
