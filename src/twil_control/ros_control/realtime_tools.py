"""realtime_tools (ROS 1): RealtimeBuffer and RealtimePublisher.

The callbacks and the real-time loop run in one thread here, so the buffer is a plain slot that
keeps ROS's names. The publisher puts its message in the controller manager's outbox, delivered
after write() at the same simulated time, so publishing stays out of the read -> update ->
write cycle as in ROS (docs/ros_control.md).
"""

from __future__ import annotations

from collections import deque
from typing import Generic, TypeVar

T = TypeVar("T")


class RealtimeBuffer(Generic[T]):
    def __init__(self, value: T) -> None:
        self._value = value

    def write_from_non_rt(self, value: T) -> None:
        """writeFromNonRT: a subscriber callback stores a new command."""
        self._value = value

    def init_rt(self, value: T) -> None:
        """initRT: set from the real-time side (starting())."""
        self._value = value

    def read_from_rt(self) -> T:
        """readFromRT: the latest value, for update()."""
        return self._value


class PublishSchedule:
    """When a controller publishing at ``rate`` Hz from a faster loop is due: the first update
    after :meth:`start` is, the next exactly 1/rate later (advanced by 1/rate, never reset to
    the time, so no drift), due when ``time >= due - period/2`` (so 100 Hz from 1 kHz gives
    exactly 100 messages a second); a loop that fell behind restarts the schedule at the
    current time instead of bursting."""

    def __init__(self, rate: float) -> None:
        self.interval = 1.0 / rate
        self.due = 0.0

    def start(self, time: float) -> None:
        self.due = time

    def is_due(self, time: float, period: float) -> bool:
        if time < self.due - 0.5 * period:
            return False
        self.due += self.interval
        if self.due + 0.5 * period <= time:
            self.due = time + self.interval
        return True


class RealtimePublisher:
    """realtime_tools::RealtimePublisher over a bus Publisher and an outbox (a deque of
    (publisher, message) the owner drains with :func:`publish_outbox`)."""

    def __init__(self, publisher, outbox: deque) -> None:
        self.publisher = publisher
        self._outbox = outbox

    @property
    def topic(self) -> str:
        return self.publisher.topic

    def publish(self, msg) -> None:
        """unlockAndPublish: hand the filled message to the non-real-time side."""
        self._outbox.append((self.publisher, None, msg))

    def publish_built(self, build, *data) -> None:
        """Hand over the message's data; the non-real-time side builds the message with
        build(*data) and publishes it. ROS fills a preallocated msg_ in the loop; in Python,
        building the message object inside the cycle costs several times more than copying its
        data. `data` must not be modified afterwards (pass copies)."""
        self._outbox.append((self.publisher, build, data))


def publish_outbox(outbox: deque) -> None:
    """The non-real-time publishing thread's work: deliver every queued message, in order."""
    while outbox:
        publisher, build, payload = outbox.popleft()
        publisher.publish(payload if build is None else build(*payload))
