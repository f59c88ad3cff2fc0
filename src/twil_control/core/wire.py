"""The ROS 1 wire bytes of published messages, serialised once for every consumer.

The bag recorder and the Foxglove bridge both send what was published as ROS 1 bytes, and
both do it between the simulation's time slices. Whichever asks first serialises a message
(core.messages.serialize); the other gets the same bytes object. Only the current slice's
messages are kept: the cache empties itself when the simulated clock has moved on, so it
holds at most one slice of messages, whoever forgets to clear it.

A message is known by identity, which is sound because a published message is not modified
afterwards (ROS's intra-process rule, which the recorder already relies on) and the cache
holds the message itself, so its id cannot be reused while its entry lives.
"""

from __future__ import annotations

from . import messages
from .clock import SimClock


class WireCache:
    def __init__(self, clock: SimClock) -> None:
        self._clock = clock
        self._t = None
        self._bytes: dict[int, tuple[object, bytes]] = {}

    def serialize(self, msg) -> bytes:
        now = self._clock.now()
        if now != self._t:
            self._bytes.clear()
            self._t = now
        hit = self._bytes.get(id(msg))
        if hit is not None and hit[0] is msg:
            return hit[1]
        data = messages.serialize(msg)
        self._bytes[id(msg)] = (msg, data)
        return data

    def __len__(self) -> int:
        return len(self._bytes)
