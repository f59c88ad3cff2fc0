"""Who may use the goal panel, and what a request may look like (the rules, free of HTTP code).

The panel drives a robot, so it is guarded the way Jupyter guards a notebook server: a random
token (then an HttpOnly, SameSite=Strict cookie), a ``Host`` that names this machine (against DNS
rebinding), an ``Origin`` that is the panel's own and JSON POSTs only (against pages in other
tabs), and bounded bodies. Each rule and the attack it stops: docs/view.md.
"""

from __future__ import annotations

import hmac
import json
import re
import secrets
from urllib.parse import parse_qs, urlsplit

MAX_BODY = 4096  # bytes; a goal is a few dozen

LOOPBACK = ("localhost", "127.0.0.1", "::1")
WILDCARD = ("", "0.0.0.0", "::")


class Refused(Exception):
    """A request the panel does not serve: an HTTP status and the reason, for the client."""

    def __init__(self, status: int, reason: str) -> None:
        super().__init__(reason)
        self.status = status
        self.reason = reason


def new_token() -> str:
    return secrets.token_urlsafe(24)


def host_name(header: str | None) -> str:
    """The host part of a ``Host`` header or an origin's netloc (``[::1]:8800`` -> ``::1``)."""
    text = (header or "").strip().lower()
    if text.startswith("["):
        return text[1 : text.find("]")] if "]" in text else text
    return text.rsplit(":", 1)[0] if text.count(":") == 1 else text


class Guard:
    """The checks for one panel: its token, the address it is bound to, its cookie's name."""

    def __init__(self, token: str, bind_host: str, port: int) -> None:
        self.token = token
        self.bind_host = host_name(bind_host)
        self.cookie = f"twil_view_token_{port}"

    def check_host(self, host: str | None) -> None:
        if self.bind_host in WILDCARD:
            return
        name = host_name(host)
        if name not in LOOPBACK and name != self.bind_host:
            raise Refused(
                403,
                f"Host {host!r} is not this machine's (allowed: localhost, 127.0.0.1, "
                f"[::1] or the --view-host address)",
            )

    def token_in(self, path: str, headers) -> str | None:
        """The token a request carries: in the query, the Authorization header or the cookie."""
        query = parse_qs(urlsplit(path).query).get("token")
        if query:
            return query[0]
        auth = headers.get("Authorization") or ""
        if auth.lower().startswith("token "):
            return auth[6:].strip()
        for part in (headers.get("Cookie") or "").split(";"):
            name, _, value = part.strip().partition("=")
            if name == self.cookie:
                return value
        return None

    def check_token(self, path: str, headers) -> None:
        given = self.token_in(path, headers)
        if given is None or not hmac.compare_digest(given.encode(), self.token.encode()):
            raise Refused(
                403,
                "open the panel with the URL printed at start (it ends in "
                "?token=...); this request has no valid token",
            )

    def check_origin(self, headers) -> None:
        origin = headers.get("Origin")
        if origin is None:  # not sent by a browser for this request (a script, a same-origin GET)
            return
        parts = urlsplit(origin)
        own = (headers.get("Host") or "").strip().lower()
        if parts.scheme != "http" or parts.netloc.lower() != own:
            raise Refused(403, f"requests from another site ({origin}) are refused")

    def cookie_header(self) -> str:
        return f"{self.cookie}={self.token}; Path=/; HttpOnly; SameSite=Strict"


def check_json_type(headers) -> None:
    ctype = headers.get_content_type() if headers.get("Content-Type") else ""
    if ctype != "application/json":
        raise Refused(
            415,
            f"the body must be JSON sent as Content-Type: application/json "
            f"(got {headers.get('Content-Type') or 'none'})",
        )


def body_length(headers) -> int:
    """The Content-Length of a POST: a decimal integer in [0, MAX_BODY] (0 when absent)."""
    if headers.get("Transfer-Encoding"):
        raise Refused(411, "chunked bodies are not accepted: send a Content-Length")
    text = headers.get("Content-Length")
    if text is None:
        return 0
    if not re.fullmatch(r"[0-9]{1,10}", text.strip()):
        raise Refused(400, f"Content-Length must be a byte count (got {text!r})")
    length = int(text)
    if length > MAX_BODY:
        raise Refused(413, f"request body of {length} bytes is too large (max {MAX_BODY})")
    return length


def parse_body(raw: bytes):
    """The JSON value of a body (an empty body is ``{}``)."""
    try:
        return json.loads(raw or b"{}")
    except RecursionError:
        raise Refused(400, "request body is JSON nested too deep") from None
    except UnicodeDecodeError as exc:
        raise Refused(400, f"request body is not UTF-8 text ({exc.reason})") from None
    except ValueError as exc:  # json.JSONDecodeError, and integers too long to convert
        raise Refused(400, f"request body is not JSON: {exc}") from None
