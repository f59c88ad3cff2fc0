"""The goal panel's web server: a page (the panel next to the Meshcat view in an iframe) and a
small JSON API, served by the standard library in a daemon thread.

The server never touches the topic bus or Meshcat (neither is thread-safe): POSTs are validated
here (view/panel.py) and queued as `Action`s that the view node applies in the simulation
thread between steps; GET /api/state returns the last snapshot that thread published.

API (all JSON):
- GET  /api/state        -> the snapshot (goal status, controllers, last action's outcome, time)
- POST /api/goal         {"x": .., "y": .., "ori": ..} -> 202 {"queued": id} | 400 {"error": why}
- POST /api/cancel       {} -> 202
- POST /api/controller   {"enable": true|false} -> 202 | 400
"""
from __future__ import annotations

import itertools
import json
import logging
import queue
import threading
from dataclasses import dataclass
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

from .page import render_page
from .panel import PanelInputError, parse_enable, parse_goal_form

log = logging.getLogger("twil_control.view")

MAX_BODY = 4096  # bytes; a goal is a few dozen


@dataclass(frozen=True)
class Action:
    id: int
    kind: str            # "goal", "cancel", "controller"
    payload: object      # GoalForm, None, or bool


class PanelServer:
    """Serves the panel on host:port (port 0: any free port) until close()."""

    def __init__(self, meshcat_url: str, host: str = "127.0.0.1", port: int = 0, title: str = "twil_control") -> None:
        self.actions: queue.Queue[Action] = queue.Queue()
        self._ids = itertools.count(1)
        self._lock = threading.Lock()
        self._state_text = json.dumps({"time": 0.0, "status": None, "controllers": [], "last_action": None})
        self._page = render_page(meshcat_url, title).encode()
        self._httpd = ThreadingHTTPServer((host, port), self._handler_class())
        self._httpd.daemon_threads = True
        self._thread = threading.Thread(target=self._httpd.serve_forever, name="view-panel", daemon=True)
        self._thread.start()

    @property
    def url(self) -> str:
        host, port = self._httpd.server_address[:2]
        return f"http://{host}:{port}/"

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
    def _handler_class(self):
        server = self

        class Handler(BaseHTTPRequestHandler):
            def log_message(self, fmt, *args):  # keep the run's log clean
                log.debug("panel %s - " + fmt, self.client_address[0], *args)

            def _send(self, code: int, body: bytes, ctype: str = "application/json") -> None:
                self.send_response(code)
                self.send_header("Content-Type", ctype)
                self.send_header("Content-Length", str(len(body)))
                self.send_header("Cache-Control", "no-store")
                self.end_headers()
                self.wfile.write(body)

            def _json(self, code: int, obj) -> None:
                self._send(code, json.dumps(obj).encode())

            def do_GET(self):
                if self.path in ("/", "/index.html"):
                    self._send(200, server._page, "text/html; charset=utf-8")
                elif self.path == "/api/state":
                    self._send(200, server.state_text().encode())
                else:
                    self._json(404, {"error": f"no such page {self.path} (pages: /, /api/state)"})

            def do_POST(self):
                routes = {"/api/goal": self._goal, "/api/cancel": self._cancel, "/api/controller": self._controller}
                if self.path not in routes:
                    self._json(404, {"error": f"no such action {self.path} (actions: {', '.join(routes)})"})
                    return
                try:
                    length = int(self.headers.get("Content-Length") or 0)
                    if length > MAX_BODY:
                        raise PanelInputError(f"request body of {length} bytes is too large (max {MAX_BODY})")
                    raw = self.rfile.read(length) if length else b"{}"
                    try:
                        data = json.loads(raw or b"{}")
                    except json.JSONDecodeError as exc:
                        raise PanelInputError(f"request body is not JSON: {exc}") from None
                    action = routes[self.path](data)
                except PanelInputError as exc:
                    self._json(400, {"error": str(exc)})
                    return
                self._json(202, {"queued": action.id})

            def _goal(self, data):
                return server.submit("goal", parse_goal_form(data))

            def _cancel(self, data):
                if data not in ({}, None):
                    raise PanelInputError(f"cancel takes no arguments (got {data!r})")
                return server.submit("cancel", None)

            def _controller(self, data):
                return server.submit("controller", parse_enable(data))

        return Handler
