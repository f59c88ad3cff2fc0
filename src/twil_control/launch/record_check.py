"""Recording nothing is a warning: the topics a launch's ``record`` names, checked at both ends.

At start (once every node is built, when recording starts) each named topic that no node
publishes is a warning, with the published topics nearest in name; at the end each named
topic that got no message is a warning, naming its publishers if it had any. A launch that
records every topic (no ``record`` element) has nothing to check: topics that stay silent in a
run (a cancel topic, a goal topic nobody used) are normal there.
"""

from __future__ import annotations

import difflib
import logging

from ..core.bus import Bus

log = logging.getLogger("twil_control.launch")


class RecordCheck:
    def __init__(self, bus: Bus, topics: list[str] | None) -> None:
        self.bus = bus
        self.topics = list(topics or [])
        self._waiting = set(self.topics) - {topic for topic, _, _ in bus.latched_messages()}
        if not self._waiting:
            return
        bus.add_listener(self._on_message)
        published = [t for t in bus.topic_types() if bus.publishers_of(t)]
        for topic in self.topics:
            if not bus.publishers_of(topic):
                close = difflib.get_close_matches(topic, published, n=3)
                hint = f" (published topics near it: {', '.join(close)})" if close else ""
                log.warning("record: no node publishes %s, so the bag will hold nothing of it%s", topic, hint)

    def _on_message(self, topic: str, msgtype: str, msg, t: float) -> None:
        self._waiting.discard(topic)

    def finish(self) -> None:
        """Warn about every named topic that got no message (call once recording has ended)."""
        for topic in self.topics:
            if topic in self._waiting:
                publishers = self.bus.publishers_of(topic)
                by = f" (published by {', '.join(publishers)}, which sent nothing)" if publishers else ""
                log.warning("record: %s got no message during the run%s", topic, by)
