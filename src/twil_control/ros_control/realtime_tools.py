"""realtime_tools::RealtimeBuffer (ROS 1): the slot a subscriber writes and update() reads.

In ROS the buffer hands data from the non-real-time callback thread to the real-time loop
without blocking it. Here both run in one thread, so the buffer is a plain slot; it keeps the
ROS names so controllers read like their C++ originals.
"""
from __future__ import annotations

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
