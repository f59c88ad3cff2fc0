"""Fires the timers of ROS-role nodes as periodic events of the Drake simulation.

One periodic publish event per distinct timer period; at each event the simulated clock is
set to the event time and the due timers fire in creation order. Timers fire at multiples of
their period from t = period on (rospy.Timer's first call comes one period after creation).
A timer created while time runs (a respawned node's) joins the event of its period, if the
launch had that period at start: events cannot be declared once the diagram is built.
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
        self._groups = dict(groups)
        for period, timers in sorted(groups.items()):
            self.DeclarePeriodicPublishEvent(period, period, self._make_handler(timers))

    def add(self, timer) -> bool:
        """Fire `timer` with the others of its period; False if no event has that period."""
        group = self._groups.get(timer.period)
        if group is None:
            return False
        group.append(timer)
        return True

    def _make_handler(self, timers):
        def fire(context):
            t = context.get_time()
            self._master.clock.set(t)
            for timer in timers:
                timer.fire(t)
            return EventStatus.Succeeded()

        return fire
