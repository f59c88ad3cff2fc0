"""Sends move_base goals one after another (the original GUI's Start button, scripted) and ends
the run when every goal has a result (the runner's is_done hook).

Each goal goes when the previous one has a result, or is cancelled after ``timeout``, as an
action client's wait_for_result and cancel_goal; outcomes are logged and kept in
``self.outcomes``. Parameters: docs/launch_files.md, "The project's own publishers".
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from twil_control.errors import InputError

from ..control.transforms import quat_from_yaw
from ..core.actionlib import status_name
from ..core.messages import header, msg_class, time_msg
from ..core.params import ParamServer
from ..core.paths import InputPathError, find_file
from ..core.ros_node import RosNode
from ..core.typed_params import load_typed


@dataclass
class GoalPose:
    x: float
    y: float
    yaw: float = 0.0


@dataclass
class GoalFile:
    goals: list[GoalPose]


@dataclass
class MoveBaseGoalsParams:
    goals: str = ""
    file: str = ""
    frame_id: str = "map"
    start_delay: float = 1.0
    topic: str = "/move_base/goal"
    result_topic: str = "/move_base/result"
    timeout: float = 0.0
    cancel_topic: str = "/move_base/cancel"

    def __post_init__(self) -> None:
        if not (self.timeout >= 0 and math.isfinite(self.timeout)):
            raise InputError(f"timeout must be >= 0 s (0: none), got {self.timeout}")
        if self.goals.strip() and self.file:
            raise InputError(
                'give at most one of goals ("x y yaw; ...") and file (a YAML list of {x, y, yaw})'
            )


def parse_goals(text: str) -> list[GoalPose]:
    out = []
    for i, part in enumerate(p for p in text.split(";") if p.strip()):
        try:
            values = [float(v) for v in part.replace(",", " ").split()]
        except ValueError:
            values = []
        if len(values) not in (2, 3) or not all(math.isfinite(v) for v in values):
            raise InputError(f"goal {i + 1} ({part.strip()!r}) must be 'x y' or 'x y yaw' in numbers")
        out.append(GoalPose(*values))
    return out


class MoveBaseGoals(RosNode):
    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        p = self.params = self.typed_params(MoveBaseGoalsParams)
        if p.goals.strip():
            self.goals = parse_goals(p.goals)
        elif not p.file:
            self.goals = []  # none: move_base waits for goals from elsewhere (the view's goal panel)
        else:
            server = ParamServer()
            try:
                server.load_file(find_file(p.file, "goals file"), "/", param="goals")
            except InputPathError as error:
                raise InputError(f"node {self.fqn}: {error}") from None
            self.goals = load_typed(server, "/", GoalFile).goals
        self._pub = self.create_publisher(p.topic, "twil_control/MoveBaseActionGoal")
        self.create_subscription(p.result_topic, "twil_control/MoveBaseActionResult", self._on_result)
        self._cancel_pub = (
            self.create_publisher(p.cancel_topic, "actionlib_msgs/GoalID") if p.timeout else None
        )
        self._deadline = math.inf
        self.outcomes: list[tuple[GoalPose, int, str, float]] = []
        self._sent: str | None = None
        self._index = 0

    def on_start(self) -> None:
        self.create_timer(self.params.start_delay, self._send_first)
        if self._cancel_pub is not None:
            self.create_timer(0.1, self._check_timeout)

    def _check_timeout(self, event) -> None:
        if self._sent is not None and self.now() >= self._deadline:
            self.log.warning(
                "goal %d/%d: no result after %.1f s: cancelling it",
                self._index + 1,
                len(self.goals),
                self.params.timeout,
            )
            self._deadline = math.inf
            self._cancel_pub.publish(
                msg_class("actionlib_msgs/GoalID")(stamp=time_msg(self.now()), id=self._sent)
            )

    def _send_first(self, event) -> None:
        if not self.goals:
            self.log.info(
                "no goals given: move_base waits for goals on /move_base_simple/goal or %s; "
                "the run ends at --duration",
                self.params.topic,
            )
            return
        if self._index == 0 and self._sent is None:
            self._send()

    def _send(self) -> None:
        g = self.goals[self._index]
        gid = f"{self.fqn}/goal_{self._index + 1}"
        self._sent = gid
        q = quat_from_yaw(g.yaw)
        t = self.now()
        self._deadline = t + self.params.timeout if self.params.timeout else math.inf
        target = msg_class("geometry_msgs/PoseStamped")(
            header=header(self.params.frame_id, t),
            pose=msg_class("geometry_msgs/Pose")(
                position=msg_class("geometry_msgs/Point")(x=g.x, y=g.y, z=0.0),
                orientation=msg_class("geometry_msgs/Quaternion")(x=q[0], y=q[1], z=q[2], w=q[3]),
            ),
        )
        self.log.info("goal %d/%d: (%.2f, %.2f, %.2f)", self._index + 1, len(self.goals), g.x, g.y, g.yaw)
        self._pub.publish(
            msg_class("twil_control/MoveBaseActionGoal")(
                header=header("", t),
                goal_id=msg_class("actionlib_msgs/GoalID")(stamp=time_msg(t), id=gid),
                goal=msg_class("twil_control/MoveBaseGoal")(target_pose=target),
            )
        )

    def _on_result(self, msg) -> None:
        if self._sent is None or msg.status.goal_id.id != self._sent:
            return
        g = self.goals[self._index]
        self.outcomes.append((g, msg.status.status, msg.status.text, self.now()))
        self.log.info(
            "goal %d/%d %s at t = %.1f s: %s",
            self._index + 1,
            len(self.goals),
            status_name(msg.status.status),
            self.now(),
            msg.status.text,
        )
        self._index += 1
        self._sent = None
        if self._index < len(self.goals):
            self._send()

    def is_done(self) -> bool:
        # with no goals of its own the node never ends the run: goals come from elsewhere
        return bool(self.goals) and self._index >= len(self.goals)
