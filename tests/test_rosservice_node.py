"""`rosservice call` as a launch node, as users put it in launch files (amcl's global_localization
from a terminal, scripted): called once when time starts, or with --wait once the service is
advertised; its YAML arguments; a missing service fails the node; list/info/... only display.
No world is simulated: the runs take a fraction of a second."""

from __future__ import annotations

import shlex

import pytest

from twil_control.core.node import Master, ServiceError
from twil_control.core.ros_node import NodeArgsError
from twil_control.launch import node_types


def _node(master: Master, args: str, name: str = "call", namespace: str = "/"):
    cls = node_types.get("rosservice", "rosservice")
    return cls(master, name, namespace, {}, shlex.split(args))


def _served(master: Master, name: str) -> list:
    calls = []
    master.advertise_service(
        name, "/server", lambda *a, **kw: calls.append((master.clock.now(), a, kw)) or "ok"
    )
    return calls


def test_call_calls_the_service_once_when_time_starts_with_no_request_fields():
    master = Master()
    calls = _served(master, "/global_localization")
    node = _node(master, "call /global_localization")
    node.on_start()
    master.spin_until(2.0)
    assert calls == [(0.0, (), {})] and node.response == "ok"


def test_wait_calls_as_soon_as_the_service_is_advertised():
    master = Master()
    node = _node(master, "call --wait global_localization", namespace="/robot")
    node.on_start()
    master.spin_until(0.35)
    calls = _served(master, "/robot/global_localization")  # resolved in the node's namespace
    master.spin_until(2.0)
    assert calls == [(pytest.approx(0.4), (), {})] and node.called


def test_yaml_arguments_are_the_requests_fields_by_name_or_in_order():
    master = Master()
    named, ordered = _served(master, "/set_pose"), _served(master, "/switch")
    _node(master, "call /set_pose '{x: 1.5, frame: map}'", "a").on_start()
    _node(master, "call /switch '[arm]' '[]' 2", "b").on_start()
    assert named == [(0.0, (), {"x": 1.5, "frame": "map"})]
    assert ordered == [(0.0, (["arm"], [], 2), {})]


def test_a_service_nobody_advertises_fails_the_node_as_rosservice_exits_with_an_error():
    master = Master()
    _served(master, "/other")
    with pytest.raises(ServiceError, match=r"/global_localization is not advertised \(advertised: /other\)"):
        _node(master, "call /global_localization").on_start()


def test_list_and_info_only_display_and_other_commands_are_refused():
    master = Master()
    assert _node(master, "list", "l").displays_only and _node(master, "info /x", "i").displays_only
    with pytest.raises(NodeArgsError, match="the commands are call"):
        _node(master, "ping /x", "p")
    with pytest.raises(NodeArgsError, match="give the service"):
        _node(master, "call --wait", "w")
