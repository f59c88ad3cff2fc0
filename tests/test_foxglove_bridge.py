"""The Foxglove bridge on a bus without a simulation: a protocol client (tests/support/foxglove_client.py)
against the real server, ticked by hand as the runner ticks it between time slices.

What is checked: channels in ROS 1 encoding with the full ros1msg definitions; messages with
their simulated publish time and the bytes the recorder writes, serialised once for both;
nothing done for the bus while no client subscribes; latched topics sent again to a late
subscriber; clients' goals and velocity commands checked before they reach the bus (refusals
answered with a status message); services and parameters; a warning when not on loopback.
"""

from __future__ import annotations

import logging
import math
import time

import numpy as np
import pytest
from rosbags.rosbag1 import Reader
from support.foxglove_client import FoxgloveClient, schema_store

from twil_control.bag.recorder import BagRecorder
from twil_control.core import messages
from twil_control.core.node import Master
from twil_control.foxglove import client_input
from twil_control.foxglove.bridge import FoxgloveBridge, FoxgloveOptions, is_loopback
from twil_control.launch.__main__ import _port_optional
from twil_control.launch.loader import load_launch
from twil_control.ros_control import srv

M = messages.msg_class
EVERYTHING = ("clientPublish", "services", "parameters", "parametersSubscribe", "time")


def joint_state(t: float, q: float):
    # numeric arrays as numpy arrays, as the typestore's classes (rosbags' serializer) take them
    return M("sensor_msgs/JointState")(
        header=messages.header("", t),
        name=["a", "b"],
        position=np.array([q, -q]),
        velocity=np.array([0.0, 1.0]),
        effort=np.zeros(0),
    )


def pose_stamped(x: float, y: float, q=(0.0, 0.0, 0.0, 1.0)):
    return M("geometry_msgs/PoseStamped")(
        header=messages.header("map", 0.0),
        pose=M("geometry_msgs/Pose")(
            position=M("geometry_msgs/Point")(x=x, y=y, z=0.0),
            orientation=M("geometry_msgs/Quaternion")(x=q[0], y=q[1], z=q[2], w=q[3]),
        ),
    )


def twist(vx: float, wz: float):
    V = M("geometry_msgs/Vector3")
    return M("geometry_msgs/Twist")(linear=V(x=vx, y=0.0, z=0.0), angular=V(x=0.0, y=0.0, z=wz))


class Graph:
    """A master with a few topics, the bridge and a connected client."""

    def __init__(self, options: FoxgloveOptions | None = None) -> None:
        self.master = m = Master()
        bus = m.bus
        self.js = bus.advertise("/joint_states", "sensor_msgs/JointState", node="/drv")
        self.tf_static = bus.advertise("/tf_static", "tf2_msgs/TFMessage", node="/st", latch=True)
        self.goals, self.twists = [], []
        bus.subscribe(
            "/move_base_simple/goal", "geometry_msgs/PoseStamped", self.goals.append, node="/move_base"
        )
        bus.subscribe("/cmd_vel", "geometry_msgs/Twist", self.twists.append, node="/base")
        self.switches = []

        def switch(*args, **kwargs):
            req = srv.request(srv.SwitchControllerRequest, args, kwargs)
            self.switches.append(req)
            return srv.SwitchControllerResponse(ok=req.stop_controllers == ["arm"])

        m.advertise_service("/r/controller_manager/switch_controller", "/r", switch)
        m.advertise_service(
            "/r/controller_manager/list_controllers",
            "/r",
            lambda *a, **k: srv.ListControllersResponse(
                [
                    srv.ControllerState(
                        "arm",
                        "running",
                        "effort_controllers/X",
                        [srv.InterfaceResources("hardware_interface::EffortJointInterface", ["j1", "j2"])],
                    )
                ]
            ),
        )
        self.global_calls = []  # amcl's std_srvs/Empty service, called with no arguments
        m.advertise_service("/global_localization", "/amcl", lambda: self.global_calls.append(1) or object())
        m.params.set("/robot_description", "<robot name='r'/>")
        m.params.set("/r/arm/gains", [25.0, 10.0])
        # every capability on unless the test says otherwise: these tests are about what a client
        # may send once it is allowed to (tests/test_foxglove_access.py: who is allowed)
        self.bridge = FoxgloveBridge(m, options or FoxgloveOptions(port=0, capabilities=EVERYTHING))
        self.client = FoxgloveClient(f"ws://127.0.0.1:{self.bridge.port}")
        can_call = self.bridge.access.has("services")
        self.client.wait(
            lambda: "/joint_states" in self.client.channels and (self.client.services or not can_call),
            what="channels",
        )

    def step(self, dt: float = 0.05) -> None:
        """One time slice: time moves on, the recorder would flush, the bridge ticks."""
        self.master.clock.set(self.master.clock.now() + dt)
        self.bridge.tick()

    def tick_until(self, predicate, what: str, timeout: float = 20.0) -> None:
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            self.step()
            with self.client.lock:
                if predicate():
                    return
            time.sleep(0.01)
        raise TimeoutError(f"waited {timeout} s for {what}")

    def close(self) -> None:
        self.client.close()
        self.bridge.close()


@pytest.fixture
def graph():
    g = Graph()
    yield g
    g.close()


def test_every_topic_is_a_ros1_channel_with_the_definition_rosbag_stores(graph):
    c = graph.client
    assert {"clientPublish", "services", "parameters", "time"} <= set(c.server_info["capabilities"])
    assert c.server_info["supportedEncodings"] == ["ros1"]
    for topic, typ in [
        ("/joint_states", "sensor_msgs/JointState"),
        ("/tf_static", "tf2_msgs/TFMessage"),
        ("/move_base_simple/goal", "geometry_msgs/PoseStamped"),
        ("/clock", "rosgraph_msgs/Clock"),
    ]:
        ch = c.channels[topic]
        assert (ch["encoding"], ch["schemaEncoding"], ch["schemaName"]) == ("ros1", "ros1msg", typ)
        assert ch["schema"] == messages.definition(typ)[0]
    assert "MSG: std_msgs/Header" in c.channels["/joint_states"]["schema"]  # the concatenated definitions


def test_messages_carry_the_recorders_bytes_serialised_once_and_their_simulated_time(
    graph, tmp_path, monkeypatch
):
    c = graph.client
    recorder = BagRecorder(tmp_path / "run.bag", graph.master.bus)
    c.subscribe(["/joint_states"])
    graph.tick_until(lambda: graph.bridge._listening, "the subscription")
    calls = []
    real = messages.serialize
    monkeypatch.setattr(messages, "serialize", lambda msg: calls.append(msg) or real(msg))
    stamps = []
    for k in range(5):
        t = graph.master.clock.now() + 0.01
        graph.master.clock.set(t)
        graph.js.publish(joint_state(t, 0.1 * k))
        stamps.append(int(round(t * 1e9)))
    graph.master.clock.set(graph.master.clock.now() + 0.01)
    recorder.flush()  # the runner's order: the recorder, then the bridge
    graph.bridge.tick()
    assert len(calls) == 5  # one serialisation per message, for both
    c.wait(lambda: len(c.messages.get("/joint_states", [])) == 5, what="5 messages")
    recorder.close()
    with Reader(tmp_path / "run.bag") as bag:
        in_bag = [(t, bytes(raw)) for conn, t, raw in bag.messages() if conn.topic == "/joint_states"]
    assert c.messages["/joint_states"] == in_bag
    assert [t for t, _ in in_bag] == stamps
    store, name = schema_store("sensor_msgs/JointState", c.channels["/joint_states"]["schema"])
    decoded = store.deserialize_ros1(c.messages["/joint_states"][3][1], name)
    assert list(decoded.name) == ["a", "b"] and decoded.position[1] == pytest.approx(-0.3)


def test_without_a_subscriber_the_bridge_is_not_on_the_bus(graph, monkeypatch):
    calls = []
    real = messages.serialize
    monkeypatch.setattr(messages, "serialize", lambda msg: calls.append(msg) or real(msg))
    listeners = list(graph.master.bus._listeners)
    for _ in range(20):
        graph.js.publish(joint_state(graph.master.clock.now(), 0.0))
        graph.step()
    assert graph.master.bus._listeners == listeners == []
    assert calls == [msg for msg in calls if msg.__msgtype__ == "rosgraph_msgs/msg/Clock"] == []
    graph.client.subscribe(["/joint_states"])
    graph.tick_until(lambda: graph.bridge._listening, "the subscription")
    assert graph.master.bus._listeners == [graph.bridge._on_message]
    graph.client.ws.send('{"op": "unsubscribe", "subscriptionIds": [1]}')
    graph.tick_until(lambda: not graph.bridge._listening, "the unsubscription")
    assert graph.master.bus._listeners == []


def test_a_latched_topic_is_sent_again_to_a_late_subscriber(graph):
    tf = M("tf2_msgs/TFMessage")(transforms=[])
    graph.tf_static.publish(tf)
    for _ in range(3):
        graph.step()
    graph.client.subscribe(["/tf_static"])
    graph.tick_until(lambda: "/tf_static" in graph.client.messages, "the latched message")
    ((stamp, data),) = graph.client.messages["/tf_static"]
    assert data == messages.serialize(tf)
    assert stamp > 0  # delivered now, as the recorder stamps latched messages when it starts


def test_the_clock_is_sent_as_time_and_on_clock(graph):
    graph.client.subscribe(["/clock"])
    graph.tick_until(lambda: len(graph.client.messages.get("/clock", [])) >= 3, "/clock")
    c = graph.client
    with c.lock:
        times, clocks = list(c.times), list(c.messages["/clock"])
    assert times == sorted(times) and len(set(times)) == len(times)
    store, name = schema_store("rosgraph_msgs/Clock", c.channels["/clock"]["schema"])
    for stamp, data in clocks:
        clock = store.deserialize_ros1(data, name).clock
        assert clock.sec * 10**9 + clock.nanosec == stamp
    assert clocks[-1][0] in times


def test_the_simulators_own_clock_is_forwarded_not_doubled(graph):
    """With /clock on the bus (the simulator publishes it), the client gets exactly those
    messages, not the bridge's own besides."""
    pub = graph.master.bus.advertise("/clock", "rosgraph_msgs/Clock", node="/gazebo")
    graph.client.subscribe(["/clock"])
    graph.tick_until(lambda: graph.bridge._listening, "the subscription")
    sent = []
    for _ in range(6):  # the simulator's clock at 100 Hz, the bridge's tick every 0.03 s
        for _ in range(3):
            t = graph.master.clock.now() + 0.01
            graph.master.clock.set(t)
            pub.publish(messages.msg_class("rosgraph_msgs/Clock")(clock=messages.time_msg(t)))
            sent.append(int(round(t * 1e9)))
        graph.bridge.tick()
    c = graph.client
    c.wait(lambda: len(c.messages.get("/clock", [])) >= len(sent), what="the clocks")
    time.sleep(0.2)
    with c.lock:
        stamps = [stamp for stamp, _ in c.messages["/clock"]]
    assert stamps == sent


def _publish(graph, topic: str, schema: str, msg, encoding: str = "ros1") -> None:
    cid = graph.client.advertise(topic, schema, encoding)
    time.sleep(0.05)  # the advertisement first
    graph.client.publish(cid, messages.serialize(msg) if msg is not None else b"\x01\x02")


def test_a_clients_goal_and_velocity_command_reach_the_bus(graph):
    _publish(graph, "/move_base_simple/goal", "geometry_msgs/PoseStamped", pose_stamped(1.5, -2.0))
    _publish(graph, "/cmd_vel", "geometry_msgs/Twist", twist(0.3, -0.5))
    graph.tick_until(lambda: graph.goals and graph.twists, "the goal and the command")
    assert graph.goals[0].pose.position.x == 1.5 and graph.twists[0].angular.z == -0.5
    assert graph.master.bus.publishers_of("/move_base_simple/goal") == ["/foxglove_bridge"]
    assert graph.bridge.refused == 0


@pytest.mark.parametrize(
    "topic,schema,msg,why",
    [
        (
            "/move_base_simple/goal",
            "geometry_msgs/PoseStamped",
            pose_stamped(25.0, 0.0),
            "goal X = 25 m is out of range: allowed [-20, 20] m",
        ),
        (
            "/move_base_simple/goal",
            "geometry_msgs/PoseStamped",
            pose_stamped(0.0, -20.5),
            "goal Y = -20.5 m is out of range",
        ),
        (
            "/move_base_simple/goal",
            "geometry_msgs/PoseStamped",
            pose_stamped(math.nan, 0.0),
            "NaN or infinite",
        ),
        (
            "/move_base_simple/goal",
            "geometry_msgs/PoseStamped",
            pose_stamped(1.0, 0.0, (0.0, 0.0, 0.0, 0.0)),
            "zero quaternion",
        ),
        (
            "/move_base_simple/goal",
            "geometry_msgs/PoseStamped",
            pose_stamped(1.0, 0.0, (0.0, 0.0, 0.5, 0.5)),
            "not normalised",
        ),
        ("/cmd_vel", "geometry_msgs/Twist", twist(math.inf, 0.0), "NaN or infinite values"),
        ("/cmd_vel", "geometry_msgs/Twist", twist(0.0, math.nan), "NaN or infinite values"),
        (
            "/joint_states",
            "sensor_msgs/JointState",
            joint_state(0.0, 1.0),
            "sensor_msgs/JointState is not accepted",
        ),
        ("/no_such_topic", "geometry_msgs/Twist", twist(0.1, 0.0), "no such topic"),
        (
            "/cmd_vel",
            "geometry_msgs/PoseStamped",
            pose_stamped(1.0, 0.0),
            "/cmd_vel carries geometry_msgs/Twist",
        ),
        ("/cmd_vel", "geometry_msgs/Twist", None, "bytes that are not a ROS 1 geometry_msgs/Twist"),
    ],
)
def test_a_refused_client_message_never_reaches_the_bus_and_is_answered(graph, topic, schema, msg, why):
    _publish(graph, topic, schema, msg)
    graph.tick_until(lambda: graph.client.statuses, "the refusal")
    (status,) = graph.client.statuses
    assert status["level"] == 2 and why in status["message"], status
    assert graph.goals == graph.twists == []
    assert graph.bridge.refused == 1


def test_a_client_must_publish_ros1(graph):
    _publish(graph, "/cmd_vel", "geometry_msgs/Twist", twist(0.1, 0.0), encoding="json")
    graph.tick_until(lambda: graph.client.statuses, "the refusal")
    assert "encoding 'json' is not accepted" in graph.client.statuses[0]["message"]
    assert graph.twists == []


def _request(c, name: str, **fields) -> bytes:
    half = c.services[name]["request"]
    store, typ = schema_store(half["schemaName"], half["schema"])
    return bytes(store.serialize_ros1(store.types[typ](**fields), typ))


def test_switch_controller_and_list_controllers_are_services_in_ros1(graph):
    c = graph.client
    name = "/r/controller_manager/switch_controller"
    assert c.services[name]["type"] == "controller_manager_msgs/SwitchController"
    ok = c.call_service(
        name,
        _request(
            c,
            name,
            start_controllers=[],
            stop_controllers=["arm"],
            strictness=2,
            start_asap=False,
            timeout=0.0,
        ),
    )
    refused = c.call_service(
        name,
        _request(
            c, name, start_controllers=["x"], stop_controllers=[], strictness=1, start_asap=True, timeout=1.5
        ),
    )
    listed = c.call_service("/r/controller_manager/list_controllers", b"")
    graph.tick_until(lambda: {ok, refused, listed} <= set(c.responses), "three responses")
    assert c.responses[ok] == ("ros1", b"\x01") and c.responses[refused] == ("ros1", b"\x00")
    # the SDK may hand the two calls to the graph in either order
    assert srv.SwitchControllerRequest(["x"], [], 1, True, 1.5) in graph.switches
    assert len(graph.switches) == 2
    half = c.services["/r/controller_manager/list_controllers"]["response"]
    store, typ = schema_store(half["schemaName"], half["schema"])
    (state,) = store.deserialize_ros1(c.responses[listed][1], typ).controller
    assert (state.name, state.state, state.claimed_resources[0].resources) == ("arm", "running", ["j1", "j2"])


def test_amcl_s_global_localization_is_a_std_srvs_empty_service(graph):
    c = graph.client
    assert c.services["/global_localization"]["type"] == "std_srvs/Empty"
    call = c.call_service("/global_localization", b"")
    graph.tick_until(lambda: call in c.responses, "the response")
    assert c.responses[call] == ("ros1", b"") and graph.global_calls == [1]


def test_a_garbled_service_request_fails_with_a_reason(graph):
    c = graph.client
    call = c.call_service("/r/controller_manager/switch_controller", b"\x05\x00")
    graph.tick_until(lambda: call in c.failures, "the failure")
    assert "not a ROS 1 encoded controller_manager_msgs/SwitchControllerRequest" in c.failures[call]
    assert graph.switches == []


def test_parameters_are_served_read_only(graph):
    c = graph.client
    c.get_parameters(["/robot_description", "/r/arm/gains", "/missing"], "q")
    c.get_parameters([], "all")
    c._send({"op": "setParameters", "parameters": [{"name": "/robot_description", "value": "x"}], "id": "s"})
    c.wait(lambda: len(c.parameter_values) == 3 and c.statuses, what="the parameters")
    by_id = {p["id"]: {q["name"]: q for q in p["parameters"]} for p in c.parameter_values}
    assert by_id["q"]["/robot_description"]["value"] == "<robot name='r'/>"
    assert by_id["q"]["/r/arm/gains"] == {"name": "/r/arm/gains", "value": [25, 10], "type": "float64_array"}
    assert "/missing" not in by_id["q"] and set(by_id["q"]) <= set(by_id["all"])
    assert by_id["s"]["/robot_description"]["value"] == "<robot name='r'/>"
    assert "read-only" in c.statuses[0]["message"]
    assert graph.master.params.get("/robot_description") == "<robot name='r'/>"


def test_subscribed_parameters_are_sent_and_sent_again_when_they_change(graph, caplog):
    c = graph.client
    assert "parametersSubscribe" in c.server_info["capabilities"]
    with caplog.at_level(logging.WARNING):
        c._send({"op": "subscribeParameterUpdates", "parameterNames": ["/r/arm/gains", "/missing"]})
        graph.tick_until(lambda: c.parameter_values, "the subscribed values")
        graph.master.params.set("/r/arm/gains", [30.0, 10.0])
        graph.tick_until(lambda: len(c.parameter_values) == 2, "the changed value")
        for _ in range(5):  # unchanged: nothing more is sent
            graph.step()
    sent = [[(p["name"], p["value"]) for p in v["parameters"]] for v in c.parameter_values]
    assert sent == [[("/r/arm/gains", [25, 10])], [("/r/arm/gains", [30, 10])]]
    assert not [r for r in caplog.records if "on_parameters_subscribe" in r.getMessage()]
    c._send({"op": "unsubscribeParameterUpdates", "parameterNames": ["/r/arm/gains"]})
    time.sleep(0.2)
    graph.master.params.set("/r/arm/gains", [1.0, 1.0])
    for _ in range(5):
        graph.step()
    assert len(c.parameter_values) == 2


def test_serving_beyond_this_machine_is_warned(caplog):
    assert is_loopback("127.0.0.1") and is_loopback("::1") and is_loopback("localhost")
    assert not is_loopback("0.0.0.0") and not is_loopback("192.168.1.4")
    with caplog.at_level(logging.WARNING, logger="twil_control.foxglove"):
        bridge = FoxgloveBridge(Master(), FoxgloveOptions(host="0.0.0.0", port=0))
        bridge.close()
        loop = FoxgloveBridge(Master(), FoxgloveOptions(port=0))
        loop.close()
    warnings = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert len(warnings) == 1 and "serving on 0.0.0.0, not this machine only" in warnings[0]


def test_the_port_is_optional_before_a_launch_argument():
    assert _port_optional(["f.yaml", "--foxglove", "goal:=1 2 0"]) == [
        "f.yaml",
        "--foxglove=8765",
        "goal:=1 2 0",
    ]
    assert _port_optional(["f.yaml", "--foxglove"]) == ["f.yaml", "--foxglove=8765"]
    assert _port_optional(["--foxglove", "0", "f.yaml"]) == ["--foxglove", "0", "f.yaml"]


def test_client_topics_are_checked_before_decoding():
    types = {"/goal": "geometry_msgs/PoseStamped"}
    assert client_input.check_topic("/goal", "geometry_msgs/PoseStamped", "ros1", types) is None
    assert "not accepted" in client_input.check_topic("/goal", "", "ros1", types)


def test_a_port_in_use_stops_the_launch_before_its_bag_is_opened(tmp_path):
    import socket

    from twil_control.foxglove.bridge import FoxgloveError
    from twil_control.launch.runner import RunOptions, run

    f = tmp_path / "tf.launch.yaml"
    f.write_text(
        "launch:\n  - node: {pkg: tf, type: static_transform_publisher, name: tf, "
        "args: '0 0 1 0 0 0 base_link laser 100'}\n"
    )
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        with pytest.raises(
            FoxgloveError, match=f"127.0.0.1:{port}: .*Address already in use.*--foxglove PORT"
        ):
            run(
                load_launch(f),
                RunOptions(duration=0.2, bag=tmp_path / "run.bag", foxglove=FoxgloveOptions(port=port)),
            )
    assert list(tmp_path.iterdir()) == [f]


def test_a_launch_without_a_world_runs_with_the_bridge(tmp_path):
    from twil_control.launch.runner import RunOptions, run

    f = tmp_path / "tf.launch.yaml"
    f.write_text(
        "launch:\n  - node: {pkg: tf, type: static_transform_publisher, name: tf, "
        "args: '0 0 1 0 0 0 base_link laser 100'}\n"
    )
    result = run(
        load_launch(f), RunOptions(duration=0.2, bag=tmp_path / "run.bag", foxglove=FoxgloveOptions(port=0))
    )
    assert result.error is None and result.bag == tmp_path / "run.bag"
