"""A navigation launch watched and driven live by a Foxglove protocol client (tests/support/foxglove_client.py),
checked against the bag of the same run: what the client received is what the bag holds, byte for
byte and stamp for stamp, decodable from the advertised schemas alone; a goal sent through
clientPublish (switched on with --foxglove-capabilities) is taken by move_base; an out-of-range
goal is refused and never reaches the bus; a page of another site gets no connection.
"""

from __future__ import annotations

import re
import subprocess
import sys
import threading
from pathlib import Path
from types import SimpleNamespace

import pytest
import websocket
from rosbags.rosbag1 import Reader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from support.foxglove_client import FoxgloveClient, schema_store

from twil_control import PACKAGE_ROOT
from twil_control.core import messages

pytestmark = pytest.mark.slow

SUBSCRIBED = ["/joint_states", "/tf", "/map", "/tf_static", "/move_base/status", "/clock"]
GOAL = (1.0, 0.5)
SIM_SECONDS = 5.0
GOAL_AT = 1.0  # simulated seconds


def pose_stamped(x: float, y: float) -> bytes:
    M = messages.msg_class
    return messages.serialize(
        M("geometry_msgs/PoseStamped")(
            header=messages.header("map", 0.0),
            pose=M("geometry_msgs/Pose")(
                position=M("geometry_msgs/Point")(x=x, y=y, z=0.0),
                orientation=M("geometry_msgs/Quaternion")(x=0.0, y=0.0, z=0.0, w=1.0),
            ),
        )
    )


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("foxglove")
    bag = tmp / "run.bag"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "twil_control.launch",
            str(PACKAGE_ROOT / "launch/qbot_navigation.launch.yaml"),
            "--foxglove",
            "0",
            "--foxglove-capabilities",
            "clientPublish,services,parameters,time",
            "--realtime",
            "1",
            "--duration",
            str(SIM_SECONDS),
            "--bag",
            str(bag),
        ],
        cwd=tmp,
        stderr=subprocess.PIPE,
        stdout=subprocess.DEVNULL,
        text=True,
    )
    log: list[str] = []
    port = None
    for line in proc.stderr:
        log.append(line)
        m = re.search(r"foxglove: serving ws://127\.0\.0\.1:(\d+)", line)
        if m:
            port = int(m.group(1))
            break
    drain = threading.Thread(target=lambda: log.extend(proc.stderr), daemon=True)
    drain.start()
    assert port is not None, "".join(log)
    # a page of another site is turned away at the handshake; the Lichtblick web app is let in
    with pytest.raises(websocket.WebSocketBadStatusException, match="403"):
        FoxgloveClient(f"ws://127.0.0.1:{port}", origin="https://evil.example.com")
    c = FoxgloveClient(f"ws://127.0.0.1:{port}", origin="https://lichtblick-suite.github.io")
    try:
        c.wait(lambda: set(SUBSCRIBED) <= set(c.channels) and c.services, what="the channels")
        c.subscribe(SUBSCRIBED)
        c.wait(lambda: c.times and c.times[-1] >= GOAL_AT * 1e9, what="simulated time")
        goal_channel = c.advertise("/move_base_simple/goal", "geometry_msgs/PoseStamped")
        c.wait(lambda: c.times[-1] >= (GOAL_AT + 0.2) * 1e9, what="the advertisement")
        c.publish(goal_channel, pose_stamped(*GOAL))
        c.publish(goal_channel, pose_stamped(25.0, 0.0))
        listed = c.call_service("/qbot/controller_manager/list_controllers", b"")
        c.wait(lambda: c.statuses and listed in c.responses, what="the refusal and the service's response")
        assert proc.wait(timeout=600) == 0, "".join(log)
    finally:
        proc.kill()
        c.close()
    drain.join(timeout=10)
    return SimpleNamespace(client=c, bag=bag, log="".join(log), listed=listed)


def bag_messages(path: Path) -> tuple[dict, dict]:
    """({topic: [(t, bytes)]}, {topic: connection}) read by rosbags' ROS 1 reader."""
    out, conns = {}, {}
    with Reader(path) as reader:
        for conn in reader.connections:
            conns[conn.topic] = conn
        for conn, t, raw in reader.messages():
            out.setdefault(conn.topic, []).append((t, bytes(raw)))
    return out, conns


def test_the_client_receives_the_bags_messages_with_their_stamps(run):
    in_bag, conns = bag_messages(run.bag)
    got = run.client.messages
    for topic in ("/joint_states", "/tf"):
        received = got[topic]
        first, last = received[0][0], received[-1][0]
        assert len(received) > 100
        # nothing dropped, added or changed between the client's first and last stamps (a stamp on
        # a time slice's edge is published in two slices: the subscription may begin between them)
        inner = [(t, raw) for t, raw in received if first < t < last]
        assert inner == [(t, raw) for t, raw in in_bag[topic] if first < t < last], topic
        assert set(received) <= set(in_bag[topic])
    for topic in ("/joint_states", "/tf", "/map", "/tf_static"):
        assert run.client.channels[topic]["schema"] == conns[topic].msgdef.data


def test_messages_decode_from_the_advertised_schemas_alone(run):
    in_bag, conns = bag_messages(run.bag)
    for topic in ("/joint_states", "/tf"):
        ch = run.client.channels[topic]
        store, name = schema_store(ch["schemaName"], ch["schema"])
        bag_store = get_typestore(Stores.EMPTY)
        bag_store.register(get_types_from_msg(conns[topic].msgdef.data, conns[topic].msgtype))
        for _, raw in run.client.messages[topic][::25]:
            mine, theirs = (
                store.deserialize_ros1(raw, name),
                bag_store.deserialize_ros1(raw, conns[topic].msgtype),
            )
            if topic == "/tf":
                assert [t.child_frame_id for t in mine.transforms] == [
                    t.child_frame_id for t in theirs.transforms
                ]
                assert [t.transform.translation.x for t in mine.transforms] == [
                    t.transform.translation.x for t in theirs.transforms
                ]
            else:
                assert list(mine.name) == list(theirs.name) and list(mine.position) == list(theirs.position)


def test_latched_topics_reach_a_subscriber_that_came_late(run):
    in_bag, _ = bag_messages(run.bag)
    ((_, tf_static),) = run.client.messages["/tf_static"]  # published at time 0, before the client
    assert tf_static == in_bag["/tf_static"][0][1]
    bag_maps = {raw for _, raw in in_bag["/map"]}
    assert run.client.messages["/map"] and all(raw in bag_maps for _, raw in run.client.messages["/map"])


def test_a_goal_sent_by_the_client_is_taken_by_move_base(run):
    in_bag, conns = bag_messages(run.bag)
    ((t_goal, goal),) = in_bag["/move_base_simple/goal"]  # the refused one is not there
    assert goal == pose_stamped(*GOAL)
    assert "/move_base: new goal" in run.log and f"({GOAL[0]:.3f}, {GOAL[1]:.3f}, 0.000)" in run.log
    ch = run.client.channels["/move_base/status"]
    store, name = schema_store(ch["schemaName"], ch["schema"])
    active = [
        t
        for t, raw in run.client.messages["/move_base/status"]
        if t >= t_goal and any(s.status == 1 for s in store.deserialize_ros1(raw, name).status_list)
    ]
    assert active, "the client saw no ACTIVE goal after sending one"


def test_an_out_of_range_goal_is_refused_with_a_status_message(run):
    (status,) = run.client.statuses
    assert status["level"] == 2
    assert "goal X = 25 m is out of range: allowed [-20, 20] m" in status["message"]


def test_the_controller_manager_answers_through_the_services_capability(run):
    c = run.client
    half = c.services["/qbot/controller_manager/list_controllers"]["response"]
    store, name = schema_store(half["schemaName"], half["schema"])
    states = {s.name: s.state for s in store.deserialize_ros1(c.responses[run.listed][1], name).controller}
    assert states == {"joint_state_controller": "running", "skid_steer_drive_controller": "running"}


# -- the layouts in foxglove/ ---------------------------------------------------------------------
def layout_references(path: Path) -> tuple[dict[str, set[str]], set[str]]:
    """({topic: {field paths}}, {services}) a Foxglove layout file refers to."""
    import json

    config = json.loads(path.read_text())["configById"]
    topics: dict[str, set[str]] = {}

    def add(path_text: str) -> None:
        topic, _, field = path_text.partition(".")
        topics.setdefault(topic, set()).update({field} if field else set())

    services = set()
    for panel_id, cfg in config.items():
        kind = panel_id.split("!")[0]
        if kind == "3D":
            for topic in cfg["topics"]:
                add(topic)
            add(cfg["publish"]["poseTopic"])
        elif kind == "Plot":
            for series in cfg["paths"]:
                add(series["value"])
        elif kind == "RawMessages":
            add(cfg["topicPath"])
        elif kind == "CallService":
            services.add(cfg["serviceName"])
    return topics, services


def resolve_field(store, msgtype: str, field: str) -> None:
    """Walk a field path (a.b[0].c) through a typestore's definitions; KeyError if one is missing."""
    for name in re.sub(r"\[\d+\]", "", field).split("."):
        if msgtype is None:
            raise KeyError(f"{field}: {name} is below a number or string")
        node, detail = dict(store.fielddefs[msgtype][1])[name]
        while isinstance(detail, tuple) and isinstance(detail[0], tuple):  # arrays and sequences
            detail = detail[0][1]
        msgtype = detail if isinstance(detail, str) else None


def check_layout(path: Path, channels: dict[str, dict], services: set[str]) -> None:
    topics, called = layout_references(path)
    assert called <= services, called - services
    for topic, fields in topics.items():
        assert topic in channels, f"{path.name}: {topic} is not a topic of the launch"
        store, name = schema_store(channels[topic]["schemaName"], channels[topic]["schema"])
        for field in fields:
            resolve_field(store, name, field)


def test_the_qbot_layout_shows_topics_and_fields_the_launch_has(run):
    check_layout(
        PACKAGE_ROOT / "foxglove/qbot_navigation.json", run.client.channels, set(run.client.services)
    )


def test_the_twil_layout_shows_topics_and_fields_the_launch_has(run):
    """The TWIL layout's move_base topics are the navigation stack's (the same node as qbot's);
    its controller's topics and services are the cart launch's, which twil_navigation includes."""
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "twil_control.launch",
            str(PACKAGE_ROOT / "launch/twil_cart_linearizing.launch.yaml"),
            "--graph",
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    graph = re.findall(r"^  (/\S+) \[(\S+)\]$", out.stdout, re.M)
    served = set(re.findall(r"^  (/\S+) \(/", out.stdout, re.M))
    channels = dict(run.client.channels)
    for topic, typ in graph:
        channels[topic] = {"schemaName": typ, "schema": messages.definition(typ)[0]}
    check_layout(PACKAGE_ROOT / "foxglove/twil_navigation.json", channels, served | set(run.client.services))
