"""Controller type registry: built-in types, the decorator, and entry-point plugins."""

from __future__ import annotations

import importlib.metadata
import sys

import pytest
from support.ros_control_fakes import NS, PluginController, make_cm

from twil_control.ros_control import Controller, ControllerTypeError, registry

GROUP = registry.ENTRY_POINT_GROUP


@pytest.fixture
def entry_points(monkeypatch):
    """Install a fake set of entry points; returns the list to fill."""
    eps: list[importlib.metadata.EntryPoint] = []

    def fake(**kwargs):
        assert kwargs == {"group": GROUP}
        return list(eps)

    monkeypatch.setattr(importlib.metadata, "entry_points", fake)
    registry.reload()
    yield eps
    monkeypatch.undo()
    registry.reload()


def ep(name, value):
    return importlib.metadata.EntryPoint(name, value, GROUP)


def test_builtin_types_are_known_by_their_ros_names():
    assert {
        "joint_state_controller/JointStateController",
        "effort_controllers/JointEffortController",
        "effort_controllers/JointGroupEffortController",
        "effort_controllers/JointPositionController",
        "velocity_controllers/JointVelocityController",
        "velocity_controllers/JointGroupVelocityController",
        "position_controllers/JointPositionController",
        "position_controllers/JointGroupPositionController",
    } <= set(registry.types())
    assert registry.types() == sorted(registry.types())


def test_unknown_type_lists_known_types():
    with pytest.raises(ControllerTypeError) as info:
        registry.get("foo/Bar")
    assert "foo/Bar" in str(info.value) and "joint_state_controller/JointStateController" in str(info.value)


def test_decorator_registers_and_conflicting_registration_is_refused():
    @registry.controller_type("test_registry/Deco")
    class Deco(Controller):
        pass

    assert registry.get("test_registry/Deco") is Deco
    registry.register("test_registry/Deco", Deco)  # same class again: no-op
    with pytest.raises(ControllerTypeError, match="already registered"):
        registry.register("test_registry/Deco", PluginController)
    with pytest.raises(ControllerTypeError, match="not a Controller"):
        registry.register("test_registry/Bad", int)


def test_entry_point_types_are_listed_without_importing_them(entry_points):
    entry_points.append(ep("ext_controllers/Lazy", "twil_test_not_imported_module:Thing"))
    assert "ext_controllers/Lazy" in registry.types()
    assert "twil_test_not_imported_module" not in sys.modules
    with pytest.raises(ControllerTypeError, match="twil_test_not_imported_module:Thing"):
        registry.get("ext_controllers/Lazy")


def test_entry_point_type_loads_and_the_manager_uses_it(entry_points):
    entry_points.append(ep("ext_controllers/Plugin", "support.ros_control_fakes:PluginController"))
    assert registry.get("ext_controllers/Plugin") is PluginController
    master, node, hw, cm = make_cm(params={"x": {"type": "ext_controllers/Plugin", "joints": ["j1"]}})
    assert ("ext_controllers/Plugin", "controller_interface::ControllerBase") in cm.list_controller_types()
    assert cm.load_controller("x"), cm.last_error
    assert cm.list_controllers()[0].type == "ext_controllers/Plugin"
    resp = master.call_service(f"{NS}/controller_manager/list_controller_types")
    assert "ext_controllers/Plugin" in resp.types


def test_duplicate_entry_points_resolve_deterministically(entry_points):
    entry_points.extend(
        [
            ep("ext_controllers/Dup", "support.ros_control_fakes:PluginController"),
            ep("ext_controllers/Dup", "support.ros_control_fakes:Recorder"),
        ]
    )
    first = registry.get("ext_controllers/Dup")
    registry.reload()
    entry_points.reverse()
    assert registry.get("ext_controllers/Dup") is first  # sorted by (name, value), not by discovery order


def test_entry_point_that_is_not_a_controller_is_refused(entry_points):
    entry_points.append(ep("ext_controllers/NotOne", "support.ros_control_fakes:NotAController"))
    with pytest.raises(ControllerTypeError, match="does not name a subclass"):
        registry.get("ext_controllers/NotOne")


def test_reload_forgets_entry_point_types(entry_points):
    entry_points.append(ep("ext_controllers/Plugin", "support.ros_control_fakes:PluginController"))
    registry.get("ext_controllers/Plugin")
    entry_points.clear()
    registry.reload()
    assert "ext_controllers/Plugin" not in registry.types()
    assert "joint_state_controller/JointStateController" in registry.types()
