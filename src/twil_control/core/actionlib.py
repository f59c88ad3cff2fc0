"""actionlib's goal status codes (actionlib_msgs/GoalStatus): the values go into bags as they are."""

from __future__ import annotations

from enum import IntEnum


class GoalStatus(IntEnum):
    """actionlib_msgs/GoalStatus.status; `name` is what rostopic echo shows beside the code."""

    PENDING = 0
    ACTIVE = 1
    PREEMPTED = 2
    SUCCEEDED = 3
    ABORTED = 4
    REJECTED = 5
    PREEMPTING = 6
    RECALLING = 7
    RECALLED = 8
    LOST = 9

    @property
    def is_terminal(self) -> bool:
        """The goal has its result (actionlib's terminal states)."""
        return self in TERMINAL


TERMINAL = frozenset(
    {
        GoalStatus.PREEMPTED,
        GoalStatus.SUCCEEDED,
        GoalStatus.ABORTED,
        GoalStatus.REJECTED,
        GoalStatus.RECALLED,
        GoalStatus.LOST,
    }
)


def status_name(code: int) -> str:
    """PENDING, SUCCEEDED, ... for a status code; UNKNOWN(code) for one actionlib does not define."""
    try:
        return GoalStatus(int(code)).name
    except ValueError:
        return f"UNKNOWN({code})"
