"""``play``: replay a bag onto the in-process topic bus (rosbag play's role).

Messages go out in time order, the bus's clock set to each one's bag time, paced at `rate` times
wall time (0: as fast as possible); latched topics are advertised latched. Whatever subscribes
before ``run()`` (a test, the Meshcat view) receives them as from a running launch. Only types
whose definition the typestore knows are published; the others are listed in ``skipped``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

from ..core import messages
from ..core.bus import Bus
from .bag_errors import BagError
from .reader import Bag


@dataclass
class PlayStats:
    messages: int = 0
    per_topic: dict[str, int] = field(default_factory=dict)
    bag_start: float = 0.0  # s, bag time of the first message played
    bag_end: float = 0.0  # s, bag time of the last
    wall: float = 0.0  # s
    skipped: dict[str, str] = field(default_factory=dict)  # topic -> why it was not played


class Player:
    """Replays a bag onto a bus; subscribe to ``player.bus`` before ``run``."""

    def __init__(
        self,
        bag: Bag,
        bus: Bus | None = None,
        rate: float = 1.0,
        start: float = 0.0,
        duration: float | None = None,
        topics: list[str] | None = None,
        sleep=time.sleep,
        monotonic=time.monotonic,
    ) -> None:
        if not (rate >= 0 and math.isfinite(rate)):
            raise BagError(f"--rate must be >= 0 (got {rate}); 0 plays as fast as possible")
        if not (start >= 0 and math.isfinite(start)):
            raise BagError(f"--start must be >= 0 seconds from the bag's start (got {start})")
        if duration is not None and not (duration > 0 and math.isfinite(duration)):
            raise BagError(f"--duration must be a positive number of seconds (got {duration})")
        self.bag, self.rate = bag, rate
        self.bus = bus or Bus()
        self._sleep, self._monotonic = sleep, monotonic
        self.start_ns = bag.start_ns + int(round(start * 1e9))
        self.stop_ns = None if duration is None else self.start_ns + int(round(duration * 1e9))
        self.stats = PlayStats()
        self.topics: list[str] = []
        self._pubs = {}
        for name in topics or list(bag.topics):
            t = bag.topic(name)
            why = self._why_not(t)
            if why:
                self.stats.skipped[name] = why
                continue
            self.topics.append(name)
            self._pubs[name] = self.bus.advertise(name, t.msgtype, node="/play", latch=t.latching)

    @staticmethod
    def _why_not(t) -> str | None:
        store = messages.typestore()
        if t.msgtype not in store.types:
            return f"type {t.ros1_type} is not in this package's typestore"
        if store.generate_msgdef(t.msgtype)[1] != t.md5sum:
            return f"the bag's definition of {t.ros1_type} differs from this package's (md5sum)"
        return None

    def run(self) -> PlayStats:
        store = messages.typestore()
        clock = self.bus.clock
        wall0 = self._monotonic()
        first = None
        for topic, t_ns, raw in self.bag.raw_messages(self.topics, self.start_ns, self.stop_ns):
            index = self.stats.per_topic.get(topic, 0)
            if first is None:
                first = t_ns
                self.stats.bag_start = t_ns * 1e-9
            if self.rate > 0:
                ahead = wall0 + (t_ns - first) * 1e-9 / self.rate - self._monotonic()
                if ahead > 0:
                    self._sleep(ahead)
            t = t_ns * 1e-9
            if t > clock.now():
                clock.set(t)
            self._pubs[topic].publish(self.bag.deserialize(topic, raw, index, t_ns, store))
            self.stats.messages += 1
            self.stats.per_topic[topic] = self.stats.per_topic.get(topic, 0) + 1
            self.stats.bag_end = t
        self.stats.wall = self._monotonic() - wall0
        return self.stats
