"""Who may connect to the Foxglove port, and what a connected client may do (rules, no sockets).

A WebSocket handshake is checked as the view's panel checks a request: ``Host`` against DNS
rebinding, ``Origin`` (which pages cannot change) against other pages. What a connected client
may do is foxglove_bridge's ``capabilities``, publishing and service calls off unless asked for
and limited by whitelists matched as foxglove_bridge matches them (docs/foxglove.md).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from urllib.parse import urlsplit

from ..errors import TwilControlError
from ..view.guard import LOOPBACK, WILDCARD, host_name

#: origins a connection may come from without --foxglove-origin: the Foxglove web app (and its
#: former Studio address) and Lichtblick's hosted web app. Desktop apps and command-line clients
#: send no Origin, which is always accepted; `file://` (any local HTML file a browser opens) is
#: only accepted when --foxglove-origin names it.
DEFAULT_ORIGINS = (
    "https://app.foxglove.dev",
    "https://studio.foxglove.dev",
    "https://lichtblick-suite.github.io",
)

#: foxglove_bridge's capability names this server offers
CAPABILITIES = ("clientPublish", "parameters", "parametersSubscribe", "services", "time")
#: on unless --foxglove-capabilities says otherwise: watching, never driving
DEFAULT_CAPABILITIES = ("parameters", "parametersSubscribe", "time")


class FoxgloveAccessError(TwilControlError, ValueError):
    """An option of the Foxglove server that cannot be used (an origin, a capability, a regex)."""


def normal_origin(text: str) -> str:
    """An origin as browsers send it: ``scheme://host[:port]``, lower case, no path."""
    text = text.strip()
    if text.lower() == "file://":
        return "file://"
    parts = urlsplit(text)
    if parts.scheme not in ("http", "https") or not parts.netloc or parts.path not in ("", "/"):
        raise FoxgloveAccessError(
            f"--foxglove-origin {text!r} is not an origin; give scheme://host[:port] with http or "
            "https (e.g. http://localhost:8080 for a Lichtblick served on this machine), or file://"
        )
    if parts.query or parts.fragment:
        raise FoxgloveAccessError(f"--foxglove-origin {text!r}: an origin has no query or fragment")
    return f"{parts.scheme}://{parts.netloc.lower()}"


def _patterns(option: str, texts) -> tuple[re.Pattern, ...]:
    out = []
    for text in texts:
        try:
            out.append(re.compile(text))
        except re.error as error:
            raise FoxgloveAccessError(f"{option} {text!r} is not a regular expression ({error})") from None
    return tuple(out)


@dataclass(frozen=True)
class Access:
    """The checks of one server: where it is bound, the origins and capabilities it allows."""

    bind_host: str = "127.0.0.1"
    origins: tuple[str, ...] = ()  # added to DEFAULT_ORIGINS
    capabilities: tuple[str, ...] = DEFAULT_CAPABILITIES
    client_topic_whitelist: tuple[str, ...] = (".*",)
    service_whitelist: tuple[str, ...] = (".*",)
    _topic_res: tuple = field(default=(), init=False, repr=False, compare=False)
    _service_res: tuple = field(default=(), init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        unknown = [c for c in self.capabilities if c not in CAPABILITIES]
        if unknown:
            raise FoxgloveAccessError(
                f"--foxglove-capabilities: unknown {', '.join(unknown)}; allowed: {', '.join(CAPABILITIES)}"
            )
        object.__setattr__(self, "origins", tuple(normal_origin(o) for o in self.origins))
        object.__setattr__(
            self, "_topic_res", _patterns("--foxglove-client-topic-whitelist", self.client_topic_whitelist)
        )
        object.__setattr__(
            self, "_service_res", _patterns("--foxglove-service-whitelist", self.service_whitelist)
        )

    # -- the handshake ---------------------------------------------------------------------
    def refusal(self, host: str | None, origins: list[str]) -> str | None:
        """Why a handshake with these ``Host`` and ``Origin`` headers is refused (None: accept)."""
        bind = host_name(self.bind_host)
        if host is None:
            return "the request has no Host header"
        if bind not in WILDCARD:
            name = host_name(host)
            if name not in LOOPBACK and name != bind:
                return (
                    f"Host {host!r} is not this machine's (allowed: localhost, 127.0.0.1, [::1] "
                    "or the --foxglove-host address)"
                )
        if len(origins) > 1:
            return "the request has more than one Origin header"
        if origins:
            origin = origins[0].strip()
            allowed = DEFAULT_ORIGINS + self.origins
            if not self._own_origin(origin, host) and origin.lower().rstrip("/") not in (
                o.rstrip("/") for o in allowed
            ):
                return (
                    f"connections from the page {origin!r} are refused (allowed: no Origin, "
                    f"{', '.join(allowed)}; add one with --foxglove-origin)"
                )
        return None

    def _own_origin(self, origin: str, host: str) -> bool:
        """The server's own origin on a loopback name or the bound address (what a script's
        WebSocket library sends by default): the port serves no page that could carry it."""
        parts = urlsplit(origin.lower())
        name = host_name(parts.netloc)
        bind = host_name(self.bind_host)
        return (
            parts.scheme in ("http", "https")
            and parts.netloc == host.strip().lower()
            and (name in LOOPBACK or (name == bind and bind not in WILDCARD))
        )

    # -- what a client may do ----------------------------------------------------------------
    def has(self, capability: str) -> bool:
        return capability in self.capabilities

    def may_publish(self, topic: str) -> str | None:
        """Why a client may not publish on ``topic`` (None: it may)."""
        if not self.has("clientPublish"):
            return (
                f"{topic}: client publishing is off; start the launch with "
                "--foxglove-capabilities clientPublish,... to allow it"
            )
        if not any(p.fullmatch(topic) for p in self._topic_res):
            return f"{topic} does not match --foxglove-client-topic-whitelist"
        return None

    def may_call(self, service: str) -> bool:
        return self.has("services") and any(p.fullmatch(service) for p in self._service_res)
