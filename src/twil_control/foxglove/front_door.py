"""The Foxglove port: every connection's handshake is checked (access.py) before the server sees it.

The foxglove-sdk server cannot look at a handshake's headers. So it listens on a port of its own
on 127.0.0.1 and speaks only TLS there, with a certificate made for this run that no browser
trusts: a web page cannot open a WebSocket to it, even knowing the port (a program on this
machine could, as it can connect to the Foxglove port without an Origin). The port the user
names is this front door: it reads a connection's HTTP request, refuses it with a 403 and the
reason, or opens a TLS connection to the server, forwards the request and relays bytes both ways.
One asyncio loop in a thread of its own serves every connection.
"""

from __future__ import annotations

import asyncio
import datetime
import ipaddress
import logging
import socket
import ssl
import threading

log = logging.getLogger("twil_control.foxglove")

HEAD_LIMIT = 16384  # bytes of an HTTP request head; a WebSocket handshake is a few hundred
HEAD_TIMEOUT = 10.0  # seconds a connection has to send its request head
MAX_CONNECTIONS = 64
CHUNK = 1 << 16


def run_certificate() -> tuple[bytes, bytes, ssl.SSLContext]:
    """A self-signed certificate and key for 127.0.0.1 (PEM), and a client context trusting it alone."""
    from cryptography import x509
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import ec
    from cryptography.x509.oid import NameOID

    key = ec.generate_private_key(ec.SECP256R1())
    name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "twil_control foxglove")])
    now = datetime.datetime.now(datetime.UTC)
    cert = (
        x509.CertificateBuilder()
        .subject_name(name)
        .issuer_name(name)
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(now - datetime.timedelta(minutes=5))
        .not_valid_after(now + datetime.timedelta(days=30))
        .add_extension(
            x509.SubjectAlternativeName([x509.IPAddress(ipaddress.ip_address("127.0.0.1"))]),
            critical=False,
        )
        .sign(key, hashes.SHA256())
    )
    cert_pem = cert.public_bytes(serialization.Encoding.PEM)
    key_pem = key.private_bytes(
        serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8, serialization.NoEncryption()
    )
    context = ssl.create_default_context(cadata=cert_pem.decode())
    return cert_pem, key_pem, context


def parse_head(head: bytes) -> tuple[str | None, list[str], str | None]:
    """(Host, [Origin ...], why the request is not a WebSocket handshake or None)."""
    lines = head.decode("latin-1").split("\r\n")  # latin-1 decodes any byte
    request = lines[0].split(" ")
    if len(request) != 3 or not request[2].startswith("HTTP/"):
        return None, [], "the request is not HTTP"
    if request[0] != "GET":
        return None, [], f"{request[0]} requests are not served (a WebSocket handshake is a GET)"
    hosts, origins = [], []
    for line in lines[1:]:
        name, sep, value = line.partition(":")
        if not sep:
            continue
        name = name.strip().lower()
        if name == "host":
            hosts.append(value.strip())
        elif name == "origin":
            origins.append(value.strip())
    if len(hosts) > 1:
        return None, origins, "the request has more than one Host header"
    return (hosts[0] if hosts else None), origins, None


class FrontDoor:
    """Listens on (host, port); relays accepted handshakes to the TLS server on backend_port."""

    def __init__(self, host: str, port: int, access, backend_port: int, tls: ssl.SSLContext) -> None:
        self._access = access
        self._backend_port = backend_port
        self._tls = tls
        self._tasks: set[asyncio.Task] = set()
        self._reasons_logged: set[str] = set()
        self.refused = 0  # connections refused (for the log and tests)
        self.accepted = 0
        family, kind, proto, _, address = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)[0]
        sock = socket.socket(family, kind, proto)
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            sock.bind(address)
            sock.listen(128)
        except OSError:
            sock.close()
            raise
        self.port = sock.getsockname()[1]
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(
            target=self._loop.run_forever, name="foxglove-front-door", daemon=True
        )
        self._thread.start()
        started = asyncio.run_coroutine_threadsafe(
            asyncio.start_server(self._serve, sock=sock, limit=HEAD_LIMIT), self._loop
        )
        self._server = started.result(timeout=10)

    async def _serve(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        task = asyncio.current_task()
        self._tasks.add(task)
        try:
            await self._relay(reader, writer)
        except (ConnectionError, OSError, asyncio.IncompleteReadError):
            pass  # a client or the server went away: its connection ends
        finally:
            self._tasks.discard(task)
            writer.close()

    async def _relay(self, reader, writer) -> None:
        peer = writer.get_extra_info("peername")
        if len(self._tasks) > MAX_CONNECTIONS:
            return self._refuse(writer, peer, 503, f"more than {MAX_CONNECTIONS} connections at once")
        try:
            head = await asyncio.wait_for(reader.readuntil(b"\r\n\r\n"), HEAD_TIMEOUT)
        except (TimeoutError, asyncio.LimitOverrunError):
            return self._refuse(writer, peer, 400, "no complete HTTP request head in time")
        host, origins, reason = parse_head(head)
        reason = reason or self._access.refusal(host, origins)
        if reason is not None:
            return self._refuse(writer, peer, 403, reason)
        backend_reader, backend_writer = await asyncio.open_connection(
            "127.0.0.1", self._backend_port, ssl=self._tls, server_hostname="127.0.0.1", limit=CHUNK
        )
        self.accepted += 1
        backend_writer.write(head)
        await asyncio.gather(
            _pipe(reader, backend_writer), _pipe(backend_reader, writer), return_exceptions=True
        )

    def _refuse(self, writer, peer, status: int, reason: str) -> None:
        self.refused += 1
        phrase = {400: "Bad Request", 403: "Forbidden", 503: "Service Unavailable"}[status]
        body = f"Foxglove server: refused: {reason}\n".encode()
        writer.write(
            f"HTTP/1.1 {status} {phrase}\r\nContent-Type: text/plain; charset=utf-8\r\n"
            f"Content-Length: {len(body)}\r\nConnection: close\r\n\r\n".encode()
            + body
        )
        if reason not in self._reasons_logged:  # a page retrying in a loop logs its reason once
            self._reasons_logged.add(reason)
            log.warning("foxglove: refused a connection from %s: %s", _address(peer), reason)

    def close(self) -> None:
        async def stop() -> None:
            self._server.close()
            for task in list(self._tasks):
                task.cancel()
            await asyncio.gather(*self._tasks, return_exceptions=True)

        if self._loop.is_closed():
            return
        try:
            asyncio.run_coroutine_threadsafe(stop(), self._loop).result(timeout=5)
        finally:
            self._loop.call_soon_threadsafe(self._loop.stop)
            self._thread.join(timeout=5)
            if not self._thread.is_alive():
                self._loop.close()


async def _pipe(source: asyncio.StreamReader, sink: asyncio.StreamWriter) -> None:
    try:
        while data := await source.read(CHUNK):
            sink.write(data)
            await sink.drain()
    finally:
        sink.close()


def _address(peer) -> str:
    return f"{peer[0]}:{peer[1]}" if isinstance(peer, tuple) and len(peer) >= 2 else str(peer)
