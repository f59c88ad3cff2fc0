"""Who may connect to the Foxglove port, and what a client may do there (foxglove/access.py,
foxglove/front_door.py): a web page of another site never gets a WebSocket, whatever its Host
and Origin headers; the Foxglove and Lichtblick apps and command-line clients do; publishing and
service calls are off unless asked for, and then limited to their whitelists; the SDK's own port
cannot be reached without TLS.
"""

from __future__ import annotations

import socket
import time

import pytest
import websocket
from support.foxglove_client import SUBPROTOCOLS, FoxgloveClient
from test_foxglove_bridge import EVERYTHING, Graph, joint_state, pose_stamped, twist

from twil_control.core import messages
from twil_control.core.node import Master
from twil_control.foxglove.access import Access, FoxgloveAccessError
from twil_control.foxglove.bridge import FoxgloveBridge, FoxgloveOptions

SWITCH = "/r/controller_manager/switch_controller"


def _handshake(port: int, **headers) -> tuple[int, str]:
    """The status and body of a WebSocket handshake sent with exactly these headers."""
    lines = [
        "GET / HTTP/1.1",
        "Upgrade: websocket",
        "Connection: Upgrade",
        "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==",
        "Sec-WebSocket-Version: 13",
        f"Sec-WebSocket-Protocol: {SUBPROTOCOLS[1]}",
    ] + [f"{name.replace('_', '-')}: {value}" for name, value in headers.items()]
    with socket.create_connection(("127.0.0.1", port), timeout=10) as s:
        s.sendall(("\r\n".join(lines) + "\r\n\r\n").encode())
        data = b""
        while b"\r\n\r\n" not in data:
            more = s.recv(4096)
            if not more:
                break
            data += more
        if data.startswith(b"HTTP/1.1 403"):
            while chunk := s.recv(4096):
                data += chunk
    status = int(data.split(b" ", 2)[1])
    return status, data.decode("latin-1")


@pytest.fixture
def wide_open():
    """A bridge with every capability on: only the handshake checks stand between a page and the robot."""
    g = Graph(FoxgloveOptions(port=0, capabilities=EVERYTHING))
    yield g
    g.close()


@pytest.mark.parametrize(
    "headers,why",
    [
        ({"Host": "127.0.0.1", "Origin": "https://evil.example.com"}, "the page 'https://evil.example.com'"),
        ({"Host": "127.0.0.1", "Origin": "null"}, "the page 'null'"),
        ({"Host": "evil.example.com:8765"}, "Host 'evil.example.com:8765' is not this machine's"),
        ({"Host": "evil.example.com", "Origin": "http://evil.example.com"}, "is not this machine's"),
        ({"Host": "localhost", "Origin": "https://app.foxglove.dev.evil.com"}, "refused"),
        ({"Origin": "https://app.foxglove.dev"}, "no Host header"),
        (
            {"Host": "127.0.0.1", "Origin": "https://app.foxglove.dev", "origin": "null"},
            "more than one Origin",
        ),
    ],
)
def test_a_foreign_page_gets_no_websocket_so_no_publish_and_no_call(wide_open, headers, why):
    g = wide_open
    status, body = _handshake(g.bridge.port, **headers)
    assert status == 403 and why in body, body
    # the same refusal through a real WebSocket client, then what the graph saw: nothing
    with pytest.raises(websocket.WebSocketBadStatusException):
        websocket.create_connection(
            f"ws://127.0.0.1:{g.bridge.port}",
            subprotocols=SUBPROTOCOLS,
            origin="https://evil.example.com",
            timeout=10,
        )
    for _ in range(5):
        g.step()
    assert g.goals == g.twists == g.switches == []
    assert g.bridge.front.refused == 2 and g.bridge.front.accepted == 1  # the fixture's own client


@pytest.mark.parametrize("origin", ["https://app.foxglove.dev", "https://lichtblick-suite.github.io", None])
def test_the_foxglove_and_lichtblick_apps_connect_and_drive_when_allowed(wide_open, origin):
    g = wide_open
    client = FoxgloveClient(f"ws://localhost:{g.bridge.port}", origin=origin)
    try:
        client.wait(lambda: "/joint_states" in client.channels and SWITCH in client.services)
        cid = client.advertise("/cmd_vel", "geometry_msgs/Twist")
        time.sleep(0.05)
        client.publish(cid, messages.serialize(twist(0.2, 0.0)))
        g.tick_until(lambda: g.twists, "the command")
        assert g.twists[0].linear.x == 0.2
    finally:
        client.close()


def test_an_added_origin_is_accepted_and_no_other(wide_open):
    # a page opened from a file (file://) is refused by default, like any other page
    assert _handshake(wide_open.bridge.port, Host="localhost", Origin="file://")[0] == 403
    g = Graph(FoxgloveOptions(port=0, origins=("http://localhost:8080", "file://")))
    try:
        assert _handshake(g.bridge.port, Host="localhost", Origin="http://localhost:8080")[0] == 101
        assert _handshake(g.bridge.port, Host="localhost", Origin="file://")[0] == 101
        assert _handshake(g.bridge.port, Host="localhost", Origin="http://localhost:8081")[0] == 403
    finally:
        g.close()
    with pytest.raises(FoxgloveAccessError, match="--foxglove-origin 'localhost:8080' is not an origin"):
        Access(origins=("localhost:8080",))


def test_by_default_a_client_watches_and_neither_publishes_nor_calls():
    g = Graph(FoxgloveOptions(port=0, origins=()))
    try:
        c = g.client
        assert SWITCH not in c.services and c.services == {}
        assert {"clientPublish", "services"}.isdisjoint(c.server_info["capabilities"])
        cid = c.advertise("/move_base_simple/goal", "geometry_msgs/PoseStamped")
        time.sleep(0.05)
        c.publish(cid, messages.serialize(pose_stamped(1.0, 1.0)))
        c.subscribe(["/joint_states"])  # watching still works

        def published() -> bool:  # until the subscription has reached the bridge
            g.js.publish(joint_state(0.0, 0.5))
            return bool(c.messages.get("/joint_states"))

        g.tick_until(published, "a message")
        for _ in range(5):
            g.step()
        assert g.goals == [] and g.switches == []
    finally:
        g.close()


def test_whitelists_limit_topics_and_services():
    g = Graph(
        FoxgloveOptions(
            port=0,
            capabilities=EVERYTHING,
            client_topic_whitelist=("/move_base_simple/goal",),
            service_whitelist=(".*/list_controllers",),
        )
    )
    try:
        c = g.client
        assert set(c.services) == {"/r/controller_manager/list_controllers"}
        cid = c.advertise("/cmd_vel", "geometry_msgs/Twist")
        time.sleep(0.05)
        c.publish(cid, messages.serialize(twist(0.5, 0.0)))
        g.tick_until(lambda: c.statuses, "the refusal")
        assert "/cmd_vel does not match --foxglove-client-topic-whitelist" in c.statuses[0]["message"]
        assert g.twists == []
    finally:
        g.close()
    with pytest.raises(FoxgloveAccessError, match="unknown assets; allowed: clientPublish"):
        Access(capabilities=("assets",))
    with pytest.raises(FoxgloveAccessError, match="--foxglove-service-whitelist '\\(' is not a regular"):
        Access(service_whitelist=("(",))


def test_the_sdk_port_speaks_tls_only_so_a_page_cannot_reach_it(wide_open):
    port = wide_open.bridge.server.port
    assert port != wide_open.bridge.port
    with pytest.raises((websocket.WebSocketException, OSError)):
        websocket.create_connection(
            f"ws://127.0.0.1:{port}", subprotocols=SUBPROTOCOLS, origin="https://evil.example.com", timeout=5
        )
    assert wide_open.goals == wide_open.twists == []


def test_the_warning_about_serving_the_network_names_the_real_port(caplog):
    with caplog.at_level("WARNING", logger="twil_control.foxglove"):
        bridge = FoxgloveBridge(Master(), FoxgloveOptions(host="0.0.0.0", port=0))
        bridge.close()
    (warning,) = [r.getMessage() for r in caplog.records if r.levelno >= 30]
    assert f"port {bridge.port} " in warning and bridge.port != 0 and "port 0" not in warning
