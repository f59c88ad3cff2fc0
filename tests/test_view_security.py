"""The goal panel is a door into the robot: only the operator's own page may use it (token,
Host, Origin, JSON only), and a malformed request is a 400 with its reason, never a traceback
or an unbounded read (view/guard.py, view/panel_server.py)."""

from __future__ import annotations

import http.client
import json
import socket

import pytest

from twil_control.view import panel_server as server_module
from twil_control.view.guard import Guard, Refused
from twil_control.view.panel_server import PanelServer

GOAL = json.dumps({"x": 1, "y": 2, "ori": 0}).encode()


@pytest.fixture
def panel():
    s = PanelServer("http://127.0.0.1:7000", "127.0.0.1", 0)
    yield s
    s.close()


def _request(
    panel: PanelServer, method: str, path: str, body: bytes | None = None, **headers: str
) -> tuple[int, dict, dict]:
    """(status, JSON body or {}, response headers); headers given as Content_Type=... etc."""
    host, port = panel._httpd.server_address[:2]
    conn = http.client.HTTPConnection(host, port, timeout=10)
    names = {k.replace("_", "-"): v for k, v in headers.items()}
    conn.putrequest(method, path, skip_host="Host" in names, skip_accept_encoding=True)
    for name, value in names.items():
        conn.putheader(name, value)
    if body is not None and "Content-Length" not in names:
        conn.putheader("Content-Length", str(len(body)))
    conn.endheaders(body)
    response = conn.getresponse()
    raw = response.read()
    conn.close()
    try:
        data = json.loads(raw) if raw else {}
    except ValueError:
        data = {"text": raw.decode()}
    return response.status, data, dict(response.getheaders())


def _auth(panel: PanelServer) -> dict:
    return {"Authorization": f"token {panel.token}", "Content_Type": "application/json"}


# ---- who may use it ------------------------------------------------------------------------


def test_without_the_token_nothing_is_served_and_nothing_is_queued(panel):
    for method, path, body in (
        ("GET", "/", None),
        ("GET", "/api/state", None),
        ("POST", "/api/goal", GOAL),
        ("POST", "/api/cancel", b"{}"),
        ("POST", "/api/controller", b'{"enable": false}'),
    ):
        status, data, _ = _request(panel, method, path, body, Content_Type="application/json")
        assert status == 403 and "?token=" in data["error"], (method, path)
    status, _, _ = _request(panel, "POST", "/api/goal?token=wrong", GOAL, Content_Type="application/json")
    assert status == 403
    assert panel.pending() == []


def test_the_token_url_sets_a_strict_cookie_that_then_opens_the_page_and_the_api(panel):
    assert len(panel.token) >= 32 and panel.url.endswith(f"/?token={panel.token}")
    status, _, headers = _request(panel, "GET", f"/?token={panel.token}")
    assert status == 302 and headers["Location"] == "/"
    cookie = headers["Set-Cookie"]
    assert cookie.startswith(f"{panel.guard.cookie}={panel.token};")
    assert "HttpOnly" in cookie and "SameSite=Strict" in cookie
    jar = cookie.split(";")[0]
    status, data, headers = _request(panel, "GET", "/", Cookie=jar)
    assert status == 200 and headers["Content-Type"].startswith("text/html")
    assert _request(panel, "POST", "/api/goal", GOAL, Cookie=jar, Content_Type="application/json")[0] == 202
    assert [a.kind for a in panel.pending()] == ["goal"]


def test_a_foreign_host_is_refused_even_with_the_token(panel):  # DNS rebinding
    port = panel._httpd.server_address[1]
    status, data, _ = _request(panel, "POST", "/api/goal", GOAL, Host=f"evil.example:{port}", **_auth(panel))
    assert status == 403 and "Host 'evil.example:" in data["error"]
    for host in (f"localhost:{port}", f"127.0.0.1:{port}", f"[::1]:{port}"):
        assert _request(panel, "GET", "/api/state", Host=host, **_auth(panel))[0] == 200, host
    assert [a.kind for a in panel.pending()] == []


def test_another_sites_page_cannot_post_even_with_the_cookie(panel):
    port = panel._httpd.server_address[1]
    status, data, _ = _request(panel, "POST", "/api/goal", GOAL, Origin="http://evil.example", **_auth(panel))
    assert status == 403 and "another site (http://evil.example)" in data["error"]
    status, _, _ = _request(
        panel, "POST", "/api/goal", GOAL, Origin=f"http://127.0.0.1:{port}", **_auth(panel)
    )
    assert status == 202
    assert len(panel.pending()) == 1


@pytest.mark.parametrize(
    "ctype", ["text/plain", "application/x-www-form-urlencoded", "multipart/form-data; boundary=x"]
)
def test_only_json_bodies_are_accepted(panel, ctype):  # what a page can send without a preflight
    headers = {**_auth(panel), "Content_Type": ctype}
    status, data, _ = _request(panel, "POST", "/api/goal", GOAL, **headers)
    assert status == 415 and "application/json" in data["error"]
    assert panel.pending() == []


def test_the_bind_address_decides_which_host_names_are_accepted():
    lan = Guard("t", "192.168.1.5", 8800)
    lan.check_host("192.168.1.5:8800")
    lan.check_host("localhost:8800")
    with pytest.raises(Refused):
        lan.check_host("attacker.example:8800")
    Guard("t", "0.0.0.0", 8800).check_host("any.name:8800")  # every interface: the token guards it


# ---- malformed requests ----------------------------------------------------------------------


@pytest.mark.parametrize(
    "length, status, reason",
    [
        ("-1", 400, "Content-Length must be a byte count (got '-1')"),
        ("abc", 400, "Content-Length must be a byte count (got 'abc')"),
        ("300000000", 413, "request body of 300000000 bytes is too large (max 4096)"),
    ],
)
def test_a_bad_content_length_is_a_400_and_the_body_is_not_read(panel, capfd, length, status, reason):
    host, port = panel._httpd.server_address[:2]
    with socket.create_connection((host, port), timeout=10) as sock:
        head = (
            f"POST /api/goal HTTP/1.1\r\nHost: {host}:{port}\r\nContent-Type: application/json\r\n"
            f"Authorization: token {panel.token}\r\nContent-Length: {length}\r\n\r\n"
        )
        sock.sendall(head.encode())  # and no body: the answer must not wait for one
        reply = b""
        while chunk := sock.recv(65536):  # the server answers and closes
            reply += chunk
    head, _, body = reply.partition(b"\r\n\r\n")
    assert head.startswith(f"HTTP/1.0 {status}".encode())
    assert json.loads(body) == {"error": reason}
    assert panel.pending() == []
    assert "Traceback" not in capfd.readouterr().err


@pytest.mark.parametrize(
    "body, reason",
    [
        (b"[" * 2000 + b"]" * 2000, "request body is JSON nested too deep"),
        (b'{"x": 1' + b"0" * 4000 + b', "y": 0, "ori": 0}', "X must be a number in [-20, 20] m"),
        (b'{"x": 1, "y": "\xff", "ori": 0}', "request body is not UTF-8 text"),
    ],
)
def test_hostile_json_is_a_400_with_its_reason_and_no_traceback(panel, capfd, body, reason):
    status, data, _ = _request(panel, "POST", "/api/goal", body, **_auth(panel))
    assert status == 400 and data["error"].startswith(reason)
    assert panel.pending() == []
    assert "Traceback" not in capfd.readouterr().err


def test_a_body_that_never_arrives_times_out(monkeypatch, capfd):
    monkeypatch.setattr(server_module, "REQUEST_TIMEOUT", 0.5)
    slow = PanelServer("http://127.0.0.1:7000", "127.0.0.1", 0)
    try:
        host, port = slow._httpd.server_address[:2]
        with socket.create_connection((host, port), timeout=10) as sock:
            sock.sendall(
                f"POST /api/cancel HTTP/1.1\r\nHost: {host}:{port}\r\nContent-Type: "
                f"application/json\r\nAuthorization: token {slow.token}\r\n"
                f"Content-Length: 100\r\n\r\n{{".encode()
            )
            reply = b""
            while chunk := sock.recv(65536):  # until the server closes
                reply += chunk
        assert reply.startswith(b"HTTP/1.0 408") and b"did not arrive within 0.5 s" in reply
        assert slow.pending() == []
    finally:
        slow.close()
    assert "Traceback" not in capfd.readouterr().err
