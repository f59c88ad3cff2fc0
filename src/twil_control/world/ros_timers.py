"""Fires the timers of ROS-role nodes as periodic events of the Drake simulation.

One periodic publish event per distinct timer period; at each event the simulated clock is
set to the event time and the due timers fire in creation order. Timers fire at multiples of
their period from t = period on (rospy.Timer's first call comes one period after creation).
"""
from __future__ import annotations

from collections import defaultdict

from pydrake.systems.framework import EventStatus, LeafSystem

from ..core.node import Master


class RosTimers(LeafSystem):
    def __init__(self, master: Master) -> None:
        super().__init__()
        self._master = master
        groups: dict[float, list] = defaultdict(list)
        for timer in master.timers:
            groups[timer.period].append(timer)
        for period, timers in sorted(groups.items()):
            self.DeclarePeriodicPublishEvent(period, period, self._make_handler(timers))

    def _make_handler(self, timers):
        def fire(context):
            t = context.get_time()
            self._master.clock.set(t)
            for timer in timers:
                timer.fire(t)
            return EventStatus.Succeeded()
        return fire
