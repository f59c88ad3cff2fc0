"""The launch's topic bus, live over the Foxglove WebSocket protocol (foxglove_bridge's role).

Served by foxglove-sdk, whose server runs in its own threads outside Python's GIL; its callbacks
only record what a client asked, and ``tick``, between time slices in the simulation's thread,
does the work. Each topic is a channel in ROS 1 encoding with the bytes the bag recorder writes
(serialised once for both). While no client subscribes the bridge is no listener of the bus. The
port the user names is foxglove/front_door.py's, which checks each handshake first
(docs/foxglove.md).
"""

from __future__ import annotations

import ipaddress
import logging
import threading
from collections import deque
from concurrent.futures import Future
from concurrent.futures import TimeoutError as FutureTimeout
from dataclasses import dataclass

from twil_control.errors import InputError, TwilControlError

from ..core import messages
from ..core.node import Master
from . import DEFAULT_PORT, client_input
from .access import DEFAULT_CAPABILITIES, Access
from .front_door import FrontDoor, run_certificate
from .services import EMPTY, ControllerManagerServices

log = logging.getLogger("twil_control.foxglove")

#: node name of the bridge as a publisher of clients' messages on the bus
NODE = "/foxglove_bridge"
#: wall seconds a service call waits for the simulation's next tick
SERVICE_TIMEOUT = 10.0
CLOCK_TOPIC = "/clock"


class FoxgloveError(TwilControlError, RuntimeError):
    """The server cannot start (a port in use, an address this machine does not have)."""


@dataclass
class FoxgloveOptions:
    host: str = "127.0.0.1"  # address the server binds to (default: this machine only)
    port: int = DEFAULT_PORT  # 0: any free port (the bound one is logged)
    origins: tuple[str, ...] = ()  # Origins accepted beyond access.DEFAULT_ORIGINS
    capabilities: tuple[str, ...] = DEFAULT_CAPABILITIES  # foxglove_bridge's names
    client_topic_whitelist: tuple[str, ...] = (".*",)
    service_whitelist: tuple[str, ...] = (".*",)

    def access(self) -> Access:
        return Access(
            self.host, self.origins, self.capabilities, self.client_topic_whitelist, self.service_whitelist
        )


def is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


class _SdkLogFilter(logging.Filter):
    """The server's own log: its warnings, and clients coming and going, marked as the bridge's
    (its start and shutdown lines would read as the launch's)."""

    def filter(self, record: logging.LogRecord) -> bool:
        text = record.getMessage()
        if record.levelno < logging.WARNING and not text.startswith(
            ("Registered client", "Unregistered client")
        ):
            return False
        record.msg, record.args = f"foxglove: {text}", None
        return True


def _quiet_sdk_log() -> None:
    server_log = logging.getLogger("foxglove.websocket.server")
    if not any(isinstance(f, _SdkLogFilter) for f in server_log.filters):
        server_log.addFilter(_SdkLogFilter())
    logging.getLogger("foxglove.runtime").setLevel(logging.WARNING)


def _ns(t: float) -> int:
    return int(round(t * 1e9))


class FoxgloveBridge:
    def __init__(
        self, master: Master, options: FoxgloveOptions | None = None, name: str = "twil_control"
    ) -> None:
        from foxglove.websocket import Capability

        import foxglove

        self._fg = foxglove
        _quiet_sdk_log()
        self.options = o = options or FoxgloveOptions()
        if not 0 <= o.port <= 65535:
            raise InputError(f"Foxglove port must be in 0..65535 (got {o.port}); 0 picks a free port")
        self._master = master
        self._bus = master.bus
        self._context = foxglove.Context()  # this bridge's channels only
        self._lock = threading.Lock()
        self._channels: dict[str, object] = {}  # topic -> Channel
        self._topic_of: dict[int, str] = {}  # channel id -> topic
        self._subscribers: dict[str, int] = {}  # topic -> subscriptions over all clients
        self._changed = False  # subscriptions changed since the last tick
        self._resend: set[str] = set()  # latched topics to send again at the next tick
        self._inbox: deque = deque()  # clients' messages and service calls
        self._client_channels: dict[tuple[int, int], object] = {}
        self._publishers: dict[str, object] = {}
        self._wanted: frozenset[str] = frozenset()  # topics some client subscribes to (the bus's)
        self._wanted_clock = False
        self._pending: list[tuple[str, float, object]] = []
        self._listening = False
        self._closed = False
        self.topic_types: dict[str, str] = {}
        self.refused = 0  # client messages refused (for the log and tests)
        self.access = access = o.access()
        names = [n for n in master.services if access.may_call(n)]
        self._services = ControllerManagerServices(names)
        self._param_subscriptions: dict[str, object] = {}  # name -> value last sent
        self._param_lock = threading.Lock()
        self._clock_channel = self._channel(CLOCK_TOPIC, "rosgraph_msgs/Clock")
        self._advertise_new_topics()
        wanted = {
            "clientPublish": Capability.ClientPublish,
            "services": Capability.Services,
            "parameters": Capability.Parameters,
            "parametersSubscribe": Capability.Parameters,
            "time": Capability.Time,
        }
        capabilities = []
        for c in access.capabilities:  # the SDK's Capability is not hashable
            if wanted[c] not in capabilities:
                capabilities.append(wanted[c])
        cert, key, tls = run_certificate()
        try:  # the SDK's server: TLS on a loopback port of its own, reached through the front door
            self.server = foxglove.start_server(
                name=name,
                host="127.0.0.1",
                port=0,
                context=self._context,
                capabilities=capabilities,
                supported_encodings=["ros1"],
                server_listener=_Listener(self),
                services=[self._service(spec) for spec in self._services.specs],
                tls_cert=cert,
                tls_key=key,
            )
        except RuntimeError as error:
            raise FoxgloveError(f"Foxglove server on 127.0.0.1: {error}") from None
        try:
            self.front = FrontDoor(o.host, o.port, access, self.server.port, tls)
        except OSError as error:
            self.server.stop()
            raise FoxgloveError(
                f"Foxglove server on {o.host}:{o.port}: {error}; choose another port with "
                "--foxglove PORT (0: any free port) or another --foxglove-host"
            ) from None
        self.port = self.front.port
        if not is_loopback(o.host):
            log.warning(
                "foxglove: serving on %s, not this machine only: anyone who reaches port %d can "
                "watch the run%s",
                o.host,
                self.port,
                _driving(access),
            )
        log.info(
            "foxglove: serving ws://%s:%d (Foxglove: Open connection > Foxglove WebSocket)", o.host, self.port
        )

    # -- channels ------------------------------------------------------------------------------
    def _channel(self, topic: str, ros1_type: str):
        definition, _ = messages.definition(ros1_type)
        schema = self._fg.Schema(name=ros1_type, encoding="ros1msg", data=definition.encode())
        channel = self._fg.Channel(topic, schema=schema, message_encoding="ros1", context=self._context)
        with self._lock:
            self._channels[topic] = channel
            self._topic_of[channel.id()] = topic
        return channel

    def _advertise_new_topics(self) -> None:
        if self._bus.topic_count() == len(self.topic_types):
            return
        types = self._bus.topic_types()
        for topic, typ in types.items():
            if topic not in self._channels:
                self._channel(topic, typ)
        self.topic_types = types

    def _service(self, spec):
        fg = self._fg

        def half(typ: str):
            return fg.MessageSchema(
                encoding="ros1",
                schema=fg.Schema(
                    name=messages.ros1_type_name(typ),
                    encoding="ros1msg",
                    data=self._services.schema_text(typ).encode(),
                ),
            )

        def handler(request) -> bytes:  # the server's thread: decode, then wait for the tick
            req = self._services.decode(spec, request.payload)
            done: Future = Future()
            if self._closed:
                raise RuntimeError(f"{spec.name}: the run is over")
            self._inbox.append(("service", spec, req, done))
            try:
                response = done.result(timeout=SERVICE_TIMEOUT)
            except FutureTimeout:
                raise RuntimeError(
                    f"{spec.name}: no answer within {SERVICE_TIMEOUT:g} s (is the simulation paused?)"
                ) from None
            return self._services.encode(spec, response)

        return fg.Service(
            spec.name,
            schema=fg.ServiceSchema(
                spec.srv_type, request=half(spec.request_type), response=half(spec.response_type)
            ),
            handler=handler,
        )

    # -- the server's callbacks (its threads) ------------------------------------------------------
    def _subscribed(self, channel_id: int, delta: int) -> None:
        with self._lock:
            topic = self._topic_of.get(channel_id)
            if topic is None:
                return
            self._subscribers[topic] = max(0, self._subscribers.get(topic, 0) + delta)
            self._changed = True
            if delta > 0 and topic != CLOCK_TOPIC and self._bus.is_latched(topic):
                self._resend.add(topic)

    def _client_advertised(self, client_id: int, channel) -> None:
        with self._lock:
            self._client_channels[(client_id, channel.id)] = channel
        log.debug(
            "foxglove: client %d advertises %s (%s, %s)",
            client_id,
            channel.topic,
            channel.schema_name,
            channel.encoding,
        )

    def _client_unadvertised(self, client_id: int, channel_id: int) -> None:
        with self._lock:
            self._client_channels.pop((client_id, channel_id), None)

    def _client_message(self, client_id: int, channel_id: int, data: bytes) -> None:
        with self._lock:
            channel = self._client_channels.get((client_id, channel_id))
        self._inbox.append(("publish", client_id, channel, bytes(data)))

    def _parameters_subscribed(self, names: list[str], subscribe: bool) -> None:
        with self._param_lock:
            for name in names:
                if subscribe:
                    self._param_subscriptions.setdefault(name, _UNSENT)
                else:
                    self._param_subscriptions.pop(name, None)

    def _send_changed_parameters(self) -> None:
        """Subscribed parameters whose value is new since they were last sent (the simulation's thread)."""
        params = self._master.params
        changed = []
        with self._param_lock:
            for name, sent in self._param_subscriptions.items():
                value = params.get(name, None) if params.has(name) else None
                if value is not None and (sent is _UNSENT or value != sent):
                    self._param_subscriptions[name] = value
                    changed.append(_parameter(self._fg, name, value))
        if changed:
            self.server.publish_parameter_values(changed)

    def parameters(self, names: list[str]) -> list:
        """The named parameters (all of them when none is named) as the protocol's Parameters."""
        params = self._master.params
        wanted = names or params.names()
        out = []
        for name in wanted:
            if params.has(name):
                out.append(_parameter(self._fg, name, params.get(name)))
        return out

    # -- the simulation's thread -------------------------------------------------------------------
    def _on_message(self, topic: str, msgtype: str, msg, t: float) -> None:
        if topic in self._wanted:
            self._pending.append((topic, t, msg))

    def tick(self) -> None:
        """Between time slices: send, publish the clients' messages, make their calls."""
        if self._closed:
            return
        self._advertise_new_topics()
        if self._changed:
            self._update_subscriptions()
        now = self._bus.clock.now()
        if self._resend:
            self._send_latched(now)
        if self._pending:
            wire = self._bus.wire
            channels = self._channels
            for topic, t, msg in self._pending:
                channels[topic].log(wire.serialize(msg), log_time=_ns(t))
            self._pending.clear()
        while self._inbox:
            self._handle(self._inbox.popleft())
        if self._param_subscriptions:
            self._send_changed_parameters()
        stamp = _ns(now)
        if self.access.has("time"):
            self.server.broadcast_time(stamp)
        if self._wanted_clock:
            clock = messages.msg_class("rosgraph_msgs/Clock")(clock=messages.time_msg(now))
            self._clock_channel.log(messages.serialize(clock), log_time=stamp)

    def _update_subscriptions(self) -> None:
        with self._lock:
            self._changed = False
            wanted = frozenset(t for t, n in self._subscribers.items() if n > 0)
        # the simulator's own /clock is forwarded as any topic (the bag's bytes); a launch without
        # one (no world) gets the bridge's, one message per tick
        own_clock = CLOCK_TOPIC not in self._bus.topic_types()
        self._wanted_clock = own_clock and CLOCK_TOPIC in wanted
        self._wanted = wanted - {CLOCK_TOPIC} if own_clock else wanted
        self._pending = [p for p in self._pending if p[0] in self._wanted]
        if self._wanted and not self._listening:
            self._bus.add_listener(self._on_message)
            self._listening = True
        elif not self._wanted and self._listening:
            self._bus.remove_listener(self._on_message)
            self._listening = False

    def _send_latched(self, now: float) -> None:
        with self._lock:
            topics, self._resend = self._resend, set()
        for topic, _, msg in self._bus.latched_messages():
            if topic in topics:
                self._channels[topic].log(self._bus.wire.serialize(msg), log_time=_ns(now))

    def _handle(self, item) -> None:
        if item[0] == "service":
            _, spec, request, done = item
            try:
                args = () if request is EMPTY else (request,)
                done.set_result(self._master.call_service(spec.name, *args))
            except Exception as error:  # the caller gets the error; the run goes on
                done.set_exception(error)
            return
        _, client_id, channel, data = item
        if channel is None:
            return self._refuse(client_id, "a message on a channel it has not advertised")
        reason = self.access.may_publish(channel.topic) or client_input.check_topic(
            channel.topic, channel.schema_name, channel.encoding, self.topic_types
        )
        msg = None
        if reason is None:
            try:
                msg = client_input.decode(data, channel.schema_name)
            except ValueError as error:
                reason = f"{channel.topic}: {error}"
        if reason is None:
            reason = client_input.check_message(channel.schema_name, msg)
            reason = reason and f"{channel.topic}: {reason}"
        if reason is not None:
            return self._refuse(client_id, reason)
        pub = self._publishers.get(channel.topic)
        if pub is None:
            pub = self._publishers[channel.topic] = self._bus.advertise(
                channel.topic, channel.schema_name, node=NODE
            )
        pub.publish(msg)
        log.info("foxglove: client %d published on %s (%s)", client_id, channel.topic, channel.schema_name)

    def _refuse(self, client_id: int, reason: str) -> None:
        self.refused += 1
        text = f"refused: {reason}"
        log.warning("foxglove: client %d: %s", client_id, text)
        self.server.publish_status(text, self._fg.StatusLevel.Error)

    def close(self) -> None:
        """Stop serving; service calls still waiting fail. Safe to call twice."""
        if self._closed:
            return
        self._closed = True
        if self._listening:
            self._bus.remove_listener(self._on_message)
            self._listening = False
        while self._inbox:
            item = self._inbox.popleft()
            if item[0] == "service":
                item[3].set_exception(RuntimeError(f"{item[1].name}: the run is over"))
        self.front.close()
        self.server.stop()


_UNSENT = object()


def _driving(access: Access) -> str:
    """What a client may do beyond watching, for the warning about serving the network."""
    can = [
        what
        for cap, what in (("clientPublish", "publish on topics"), ("services", "call services"))
        if access.has(cap)
    ]
    return f" and {' and '.join(can)} (--foxglove-capabilities)" if can else ""


def _parameter(fg, name: str, value):
    """A protocol Parameter of a parameter server value (floats kept as floats)."""
    if isinstance(value, float):
        return fg.Parameter(name, value=value, type=fg.ParameterType.Float64)
    if isinstance(value, list) and value and all(isinstance(v, float) for v in value):
        return fg.Parameter(name, value=value, type=fg.ParameterType.Float64Array)
    try:
        return fg.Parameter(name, value=value)
    except (TypeError, ValueError, OverflowError):  # a value the protocol has no type for
        return fg.Parameter(name, value=str(value))


class _Listener:
    """The server's callbacks, handed to the bridge (the foxglove ServerListener protocol)."""

    def __init__(self, bridge: FoxgloveBridge) -> None:
        self._bridge = bridge

    def on_subscribe(self, client, channel) -> None:
        self._bridge._subscribed(channel.id, +1)

    def on_unsubscribe(self, client, channel) -> None:
        self._bridge._subscribed(channel.id, -1)

    def on_client_advertise(self, client, channel) -> None:
        self._bridge._client_advertised(client.id, channel)

    def on_parameters_subscribe(self, param_names) -> None:
        self._bridge._parameters_subscribed(list(param_names), True)

    def on_parameters_unsubscribe(self, param_names) -> None:
        self._bridge._parameters_subscribed(list(param_names), False)

    def on_client_unadvertise(self, client, client_channel_id) -> None:
        self._bridge._client_unadvertised(client.id, client_channel_id)

    def on_message_data(self, client, client_channel_id, data) -> None:
        self._bridge._client_message(client.id, client_channel_id, data)

    def on_get_parameters(self, client, param_names, request_id=None) -> list:
        return self._bridge.parameters(list(param_names))

    def on_set_parameters(self, client, parameters, request_id=None) -> list:
        names = [p.name for p in parameters]
        self._bridge.server.publish_status(
            f"parameters are read-only while a launch runs (asked to set {', '.join(names)})",
            self._bridge._fg.StatusLevel.Warning,
        )
        return self._bridge.parameters(names)
