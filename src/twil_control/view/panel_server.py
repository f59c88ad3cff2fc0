"""The goal panel's web server: a page (the panel beside the Meshcat view) and a small JSON API,
served by the standard library in a daemon thread.

The server never touches the topic bus or Meshcat (neither is thread-safe): POSTs are validated
here and queued as `Action`s that the view node applies in the simulation thread between steps.
Every request passes view/guard.py's checks first; a refusal is an HTTP error with its reason as
JSON, never a traceback. The API: docs/view.md.
"""

from __future__ import annotations

import itertools
import json
import logging
import queue
import threading
from dataclasses import dataclass
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from urllib.parse import urlsplit

from .guard import Guard, Refused, body_length, check_json_type, new_token, parse_body
from .page import render_page
from .panel import PanelInputError, parse_enable, parse_goal_form

log = logging.getLogger("twil_control.view")

#: Seconds a client may take to send a request's line, headers or body (a stalled client would
#: otherwise hold its thread for ever).
REQUEST_TIMEOUT = 10.0


@dataclass(frozen=True)
class Action:
    id: int
    kind: str  # "goal", "initialpose", "cancel", "controller"
    payload: object  # GoalForm, None, or bool


class PanelServer:
    """Serves the panel on host:port (port 0: any free port) until close()."""

    def __init__(
        self,
        meshcat_url: str,
        host: str = "127.0.0.1",
        port: int = 0,
        title: str = "twil_control",
        token: str | None = None,
    ) -> None:
        self.actions: queue.Queue[Action] = queue.Queue()
        self._ids = itertools.count(1)
        self._lock = threading.Lock()
        self._state_text = json.dumps({"time": 0.0, "status": None, "controllers": [], "last_action": None})
        self._page = render_page(meshcat_url, title).encode()
        self._httpd = _Server((host, port), self._handler_class())
        self._httpd.daemon_threads = True
        self.token = token or new_token()
        self.guard = Guard(self.token, host, self._httpd.server_address[1])
        self._thread = threading.Thread(target=self._httpd.serve_forever, name="view-panel", daemon=True)
        self._thread.start()

    @property
    def base_url(self) -> str:
        host, port = self._httpd.server_address[:2]
        return f"http://{host}:{port}/"

    @property
    def url(self) -> str:
        """The URL to open: with the token (the first visit turns it into a cookie)."""
        return f"{self.base_url}?token={self.token}"

    def set_state(self, state: dict) -> None:
        """Publish a snapshot for GET /api/state (called from the simulation thread)."""
        text = json.dumps(state)
        with self._lock:
            self._state_text = text

    def state_text(self) -> str:
        with self._lock:
            return self._state_text

    def pending(self) -> list[Action]:
        """Every queued action, oldest first (called from the simulation thread)."""
        out = []
        while True:
            try:
                out.append(self.actions.get_nowait())
            except queue.Empty:
                return out

    def submit(self, kind: str, payload) -> Action:
        action = Action(next(self._ids), kind, payload)
        self.actions.put(action)
        return action

    def close(self) -> None:
        self._httpd.shutdown()
        self._httpd.server_close()
        self._thread.join(timeout=5)

    # -- HTTP -----------------------------------------------------------------------------
    def _handler_class(self) -> type[BaseHTTPRequestHandler]:
        # the timeout is read when the server is built (a test shortens it)
        return type("PanelHandler", (_PanelHandler,), {"panel": self, "timeout": REQUEST_TIMEOUT})


class _PanelHandler(BaseHTTPRequestHandler):
    """One request to the panel; `panel` is the PanelServer it serves (set by
    PanelServer._handler_class)."""

    panel: PanelServer

    def log_message(self, fmt, *args):  # keep the run's log clean
        log.debug("panel %s - " + fmt, self.client_address[0], *args)

    def _send(
        self, code: int, body: bytes, ctype: str = "application/json", headers: dict | None = None
    ) -> None:
        self.send_response(code)
        self.send_header("Content-Type", ctype)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        for name, value in (headers or {}).items():
            self.send_header(name, value)
        self.end_headers()
        self.wfile.write(body)

    def _json(self, code: int, obj) -> None:
        self._send(code, json.dumps(obj).encode())

    def _guarded(self, serve) -> None:
        """Run `serve` after the checks every request passes; refusals are answered
        with their reason, and anything unexpected with a 500 (logged, no traceback)."""
        try:
            self.panel.guard.check_host(self.headers.get("Host"))
            self.panel.guard.check_origin(self.headers)
            serve()
        except Refused as refused:
            self.close_connection = True  # a body may be left unread: never parse it as a request
            self._json(refused.status, {"error": refused.reason})
        except Exception as exc:  # a bug must not kill the thread with a traceback on stderr
            log.warning(
                "panel: %s %s failed: %s: %s",
                self.command,
                urlsplit(self.path).path,
                type(exc).__name__,
                exc,
            )  # the path without its query: no token in logs
            self.close_connection = True
            self._json(500, {"error": f"internal error: {type(exc).__name__}"})

    def do_GET(self):
        self._guarded(self._get)

    def do_POST(self):
        self._guarded(self._post)

    def _get(self):
        path = urlsplit(self.path).path
        self.panel.guard.check_token(self.path, self.headers)
        if path in ("/", "/index.html"):
            if urlsplit(self.path).query:  # the token URL: keep the token as a cookie
                self._send(
                    302,
                    b"",
                    "text/plain",
                    {"Location": "/", "Set-Cookie": self.panel.guard.cookie_header()},
                )
            else:
                self._send(200, self.panel._page, "text/html; charset=utf-8")
        elif path == "/api/state":
            self._send(200, self.panel.state_text().encode())
        else:
            self._json(404, {"error": f"no such page {path} (pages: /, /api/state)"})

    def _post(self):
        routes = {
            "/api/goal": self._goal,
            "/api/initialpose": self._initialpose,
            "/api/cancel": self._cancel,
            "/api/controller": self._controller,
        }
        self.panel.guard.check_token(self.path, self.headers)
        path = urlsplit(self.path).path
        if path not in routes:
            raise Refused(404, f"no such action {path} (actions: {', '.join(routes)})")
        check_json_type(self.headers)
        length = body_length(self.headers)
        try:
            raw = self.rfile.read(length) if length else b""
        except TimeoutError:
            self.close_connection = True
            raise Refused(408, f"the request body did not arrive within {REQUEST_TIMEOUT:g} s") from None
        try:
            action = routes[path](parse_body(raw))
        except PanelInputError as exc:
            raise Refused(400, str(exc)) from None
        self._json(202, {"queued": action.id})

    def _goal(self, data):
        return self.panel.submit("goal", parse_goal_form(data))

    def _initialpose(self, data):
        return self.panel.submit("initialpose", parse_goal_form(data))

    def _cancel(self, data):
        if data not in ({}, None):
            raise PanelInputError(f"cancel takes no arguments (got {data!r})")
        return self.panel.submit("cancel", None)

    def _controller(self, data):
        return self.panel.submit("controller", parse_enable(data))


class _Server(ThreadingHTTPServer):
    def handle_error(self, request, client_address) -> None:
        """A connection that broke (a reset, a timeout while reading headers): one debug line,
        not socketserver's traceback on stderr."""
        import sys

        log.debug("panel: connection from %s ended: %s", client_address[0], sys.exc_info()[1])
