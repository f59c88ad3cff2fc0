"""Simulated time (ROS's use_sim_time): every node reads the simulator's clock.

The simulator advances the clock; nodes only read it. Times are float seconds internally and
turned into ROS Time messages at the edges (core.messages.time_msg).
"""

from __future__ import annotations


class SimClock:
    """The current simulated time, set by whoever drives the simulation."""

    def __init__(self, t: float = 0.0) -> None:
        self._t = float(t)

    def now(self) -> float:
        return self._t

    def set(self, t: float) -> None:
        if t < self._t - 1e-12:
            raise ValueError(f"simulated time cannot go backwards ({t} < {self._t})")
        self._t = float(t)

    def advance_to(self, t: float) -> None:
        """Set the time to t unless it is already later (an event stamped earlier than the
        last one set, which runs after it)."""
        if t > self._t:
            self._t = float(t)
