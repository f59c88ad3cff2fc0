"""A Foxglove WebSocket protocol client for the tests, written from the protocol's spec
(foxglove/ws-protocol, docs/spec.md) on websocket-client: what Foxglove's app does when it
connects, subscribes, publishes and calls services. Messages are decoded with rosbags from
the schemas the server advertises, not with the project's own types.
"""

from __future__ import annotations

import itertools
import json
import struct
import threading
import time

import websocket
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

#: the protocol's subprotocol names; the server picks the one it speaks
SUBPROTOCOLS = ["foxglove.websocket.v1", "foxglove.sdk.v1"]


#: what FoxgloveClient's origin means by default: websocket-client's own Origin (the server's address)
LIBRARY_ORIGIN = object()


class FoxgloveClient:
    def __init__(self, url: str, timeout: float = 30.0, origin=LIBRARY_ORIGIN) -> None:
        """origin: the Origin header a browser page would send; None sends none (a desktop client)."""
        kwargs = {} if origin is LIBRARY_ORIGIN else {"origin": origin, "suppress_origin": origin is None}
        self.ws = websocket.create_connection(url, subprotocols=SUBPROTOCOLS, timeout=timeout, **kwargs)
        self.subprotocol = self.ws.getsubprotocol()
        self.lock = threading.Lock()
        self.server_info: dict | None = None
        self.channels: dict[str, dict] = {}  # topic -> advertised channel
        self.services: dict[str, dict] = {}  # name -> advertised service
        self.statuses: list[dict] = []
        self.parameter_values: list[dict] = []
        self.times: list[int] = []
        self.messages: dict[str, list[tuple[int, bytes]]] = {}  # topic -> [(timestamp, payload)]
        self.responses: dict[int, tuple[str, bytes]] = {}  # call id -> (encoding, payload)
        self.failures: dict[int, str] = {}
        self._sub_topic: dict[int, str] = {}
        self._ids = itertools.count(1)
        self._closed = False
        self._thread = threading.Thread(target=self._read, daemon=True)
        self._thread.start()

    # -- receiving ---------------------------------------------------------------------------
    def _read(self) -> None:
        while not self._closed:
            try:
                opcode, data = self.ws.recv_data()
            except (websocket.WebSocketException, OSError):
                return
            if opcode == websocket.ABNF.OPCODE_TEXT:
                self._on_json(json.loads(data))
            elif opcode == websocket.ABNF.OPCODE_BINARY:
                self._on_binary(data)

    def _on_json(self, msg: dict) -> None:
        with self.lock:
            op = msg["op"]
            if op == "serverInfo":
                self.server_info = msg
            elif op == "advertise":
                for ch in msg["channels"]:
                    self.channels[ch["topic"]] = ch
            elif op == "advertiseServices":
                for s in msg["services"]:
                    self.services[s["name"]] = s
            elif op == "status":
                self.statuses.append(msg)
            elif op == "parameterValues":
                self.parameter_values.append(msg)
            elif op == "serviceCallFailure":
                self.failures[msg["callId"]] = msg["message"]

    def _on_binary(self, data: bytes) -> None:
        op = data[0]
        with self.lock:
            if op == 0x01:  # message data: subscription id, timestamp, payload
                sub, stamp = struct.unpack_from("<IQ", data, 1)
                self.messages.setdefault(self._sub_topic[sub], []).append((stamp, bytes(data[13:])))
            elif op == 0x02:  # time
                self.times.append(struct.unpack_from("<Q", data, 1)[0])
            elif op == 0x03:  # service call response: service id, call id, encoding, payload
                _, call, n = struct.unpack_from("<III", data, 1)
                self.responses[call] = (data[13 : 13 + n].decode(), bytes(data[13 + n :]))

    def wait(self, predicate, timeout: float = 60.0, what: str = "the server") -> None:
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            with self.lock:
                if predicate():
                    return
            time.sleep(0.02)
        raise TimeoutError(f"waited {timeout} s for {what}")

    # -- requests ----------------------------------------------------------------------------
    def _send(self, obj: dict) -> None:
        self.ws.send(json.dumps(obj))

    def subscribe(self, topics: list[str]) -> None:
        subs = []
        with self.lock:
            for topic in topics:
                sid = next(self._ids)
                self._sub_topic[sid] = topic
                subs.append({"id": sid, "channelId": self.channels[topic]["id"]})
        self._send({"op": "subscribe", "subscriptions": subs})

    def advertise(self, topic: str, schema_name: str, encoding: str = "ros1") -> int:
        cid = next(self._ids)
        self._send(
            {
                "op": "advertise",
                "channels": [{"id": cid, "topic": topic, "encoding": encoding, "schemaName": schema_name}],
            }
        )
        return cid

    def publish(self, channel_id: int, payload: bytes) -> None:
        self.ws.send_binary(b"\x01" + struct.pack("<I", channel_id) + payload)

    def call_service(self, name: str, payload: bytes, encoding: str = "ros1") -> int:
        call = next(self._ids)
        head = struct.pack("<III", self.services[name]["id"], call, len(encoding)) + encoding.encode()
        self.ws.send_binary(b"\x02" + head + payload)
        return call

    def get_parameters(self, names: list[str], request_id: str) -> None:
        self._send({"op": "getParameters", "parameterNames": names, "id": request_id})

    def close(self) -> None:
        self._closed = True
        try:
            self.ws.close()
        except (websocket.WebSocketException, OSError):
            pass


def schema_store(schema_name: str, schema: str):
    """A rosbags typestore holding the advertised schema (a ros1msg definition, with the
    definitions it uses after '=====' lines, as rosbag stores them)."""
    name = schema_name if schema_name.count("/") == 2 else schema_name.replace("/", "/msg/", 1)
    store = get_typestore(Stores.EMPTY)
    store.register(get_types_from_msg(schema, name))
    return store, name
