"""The ROS 1 wire bytes of published messages, serialised once for every consumer.

The bag recorder and the Foxglove bridge both send published messages as ROS 1 bytes between
time slices; whichever asks first serialises, the other gets the same bytes. A message is known
by identity, sound because a published message is never changed (ROS's intra-process rule) and
the cache holds it, so its id is not reused. The cache empties itself when the clock moves on.
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
