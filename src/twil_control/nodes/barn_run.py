"""One BARN trial (node type twil_control/barn_run), the ROS side of the-barn-challenge's run.py
(its node ``gym``) on simulated time: reset the robot, send move_base its goal, watch it.

1. Every ``reset_period`` s (run.py: a 1 s sleep) ``/gazebo/set_model_state`` puts ``model`` at
   (``init_x``, ``init_y``, yaw ``init_yaw``), until the robot is within 0.1 m of it and
   ``/collision`` (std_msgs/Bool) said nothing since the previous look.
2. A move_base goal (``goal_x``, ``goal_y``) in ``goal_frame``, orientation (0, 0, 0, 1), on
   ``/move_base/goal``.
3. The trial starts at the first look (every 0.01 s) that finds the robot 0.1 m or more from
   its initial position; every 0.1 s ``/gazebo/get_model_state`` gives its position. It ends
   when the robot is within ``success_radius`` of init + goal (succeeded), ``/collision`` said
   true since the previous look (collided), or ``time_limit`` s have passed (timeout).
run.py waits for the first motion forever; here a robot that has not moved ``time_limit`` s
after the goal ends the trial as a timeout. ``self.result`` holds the outcome (BarnResult).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from ..core.messages import header, msg_class, time_msg
from ..core.ros_node import RosNode

RESET, WAIT_MOTION, NAVIGATE, DONE = "reset", "wait_motion", "navigate", "done"
MOVED = 0.1  # m from the initial position: reset done (below), trial started (at or above)


@dataclass
class BarnRunParams:
    model: str = "jackal"
    init_x: float = -2.25
    init_y: float = 3.0
    init_yaw: float = 1.57
    goal_x: float = 0.0  # relative to the initial position (the goal in goal_frame)
    goal_y: float = 10.0
    goal_frame: str = "odom"
    success_radius: float = 1.0
    time_limit: float = 100.0
    reset_period: float = 1.0
    look_period: float = 0.1
    motion_period: float = 0.01

    def __post_init__(self) -> None:
        for name in ("success_radius", "time_limit", "reset_period", "look_period", "motion_period"):
            value = getattr(self, name)
            if not (value > 0 and math.isfinite(value)):
                raise ValueError(f"{name} must be a positive number (got {value})")


@dataclass
class BarnResult:
    status: str  # succeeded, collided or timeout
    time: float  # s from the first motion to the end (run.py's curr_time - start_time)
    start: float  # simulated time of the first motion
    end_position: tuple[float, float]
    resets: int  # set_model_state calls before the goal

    @property
    def success(self) -> bool:
        return self.status == "succeeded"

    @property
    def collided(self) -> bool:
        return self.status == "collided"

    @property
    def timeout(self) -> bool:
        return self.status == "timeout"


class BarnRun(RosNode):
    required_by_default = True

    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        p = self.params = self.typed_params(BarnRunParams)
        self.init = (p.init_x, p.init_y)
        self.goal = (p.init_x + p.goal_x, p.init_y + p.goal_y)
        self._goal_pub = self.create_publisher("/move_base/goal", "twil_control/MoveBaseActionGoal")
        self.create_subscription("/collision", "std_msgs/Bool", self._on_collision)
        self._collisions = 0
        self.phase = RESET
        self.resets = 0
        self.result: BarnResult | None = None
        self.position = self.init
        self._goal_time = 0.0
        self._start = 0.0
        # Called with (time since start, x, y) at every look (run.py's print).
        self.on_look: Callable[[float, float, float], None] | None = None
        # Called once, at the first timer event (time has started).
        self.on_start_hook: Callable[[], None] | None = None

    # -- run.py's GazeboSimulation ---------------------------------------------------------------
    def _on_collision(self, msg) -> None:
        if msg.data:
            self._collisions += 1

    def hard_collision(self) -> bool:
        """Whether /collision said true since the previous call."""
        collided, self._collisions = self._collisions > 0, 0
        return collided

    def _model_position(self) -> tuple[float, float]:
        state = self.master.call_service("/gazebo/get_model_state", self.params.model, "world")
        if not state.success:
            self.fail(f"/gazebo/get_model_state: {state.status_message}")
        self.position = (state.pose.position.x, state.pose.position.y)
        return self.position

    def _reset(self) -> None:
        p = self.params
        state = msg_class("gazebo_msgs/ModelState")(
            model_name=p.model,
            pose=msg_class("geometry_msgs/Pose")(
                position=msg_class("geometry_msgs/Point")(x=p.init_x, y=p.init_y, z=0.0),
                orientation=msg_class("geometry_msgs/Quaternion")(
                    x=0.0, y=0.0, z=math.sin(p.init_yaw / 2), w=math.cos(p.init_yaw / 2)
                ),
            ),
            twist=msg_class("geometry_msgs/Twist")(
                linear=msg_class("geometry_msgs/Vector3")(x=0.0, y=0.0, z=0.0),
                angular=msg_class("geometry_msgs/Vector3")(x=0.0, y=0.0, z=0.0),
            ),
            reference_frame="world",
        )
        response = self.master.call_service("/gazebo/set_model_state", model_state=state)
        if not response.success:
            self.fail(f"/gazebo/set_model_state: {response.status_message}")
        self.resets += 1

    # -- the trial -------------------------------------------------------------------------------
    def on_start(self) -> None:
        # every timer now: timers created while time runs join only periods that exist at start
        p = self.params
        self._reset()
        self.create_timer(p.reset_period, self._reset_step)
        self.create_timer(p.motion_period, self._motion_step)
        self.create_timer(p.look_period, self._look)

    def _reset_step(self, event) -> None:
        if self.phase != RESET:
            return
        position = self._model_position()
        if math.dist(position, self.init) > MOVED or self.hard_collision():
            self._reset()
            return
        self.phase = WAIT_MOTION
        self._send_goal()
        self._goal_time = self.now()

    def _send_goal(self) -> None:
        p, t = self.params, self.now()
        target = msg_class("geometry_msgs/PoseStamped")(
            header=header(p.goal_frame, t),
            pose=msg_class("geometry_msgs/Pose")(
                position=msg_class("geometry_msgs/Point")(x=p.goal_x, y=p.goal_y, z=0.0),
                orientation=msg_class("geometry_msgs/Quaternion")(x=0.0, y=0.0, z=0.0, w=1.0),
            ),
        )
        self._goal_pub.publish(
            msg_class("twil_control/MoveBaseActionGoal")(
                header=header("", t),
                goal_id=msg_class("actionlib_msgs/GoalID")(stamp=time_msg(t), id=f"{self.fqn}/barn_goal"),
                goal=msg_class("twil_control/MoveBaseGoal")(target_pose=target),
            )
        )
        self.log.info("goal (%.2f, %.2f) in %s sent at t = %.2f s", p.goal_x, p.goal_y, p.goal_frame, t)

    def _motion_step(self, event) -> None:
        if self.on_start_hook is not None:
            self.on_start_hook()
            self.on_start_hook = None
        if self.phase != WAIT_MOTION:
            return
        t = self.now()
        if math.dist(self._model_position(), self.init) >= MOVED:
            self.phase = NAVIGATE
            self._start = t
        elif t - self._goal_time >= self.params.time_limit:
            self.log.warning("the robot did not move within %.0f s of the goal", self.params.time_limit)
            self._finish("timeout", self._goal_time, t)

    def _look(self, event) -> None:
        if self.phase != NAVIGATE:
            return
        t = self.now()
        position = self._model_position()
        collided = self.hard_collision()
        if self.on_look is not None:
            self.on_look(t - self._start, *position)
        if collided:
            self._finish("collided", self._start, t)
        elif math.dist(position, self.goal) <= self.params.success_radius:
            self._finish("succeeded", self._start, t)
        elif t - self._start >= self.params.time_limit:
            self._finish("timeout", self._start, t)

    def _finish(self, status: str, start: float, t: float) -> None:
        self.phase = DONE
        self.result = BarnResult(status, t - start, start, self.position, self.resets)
        self.log.info("trial %s after %.2f s at (%.2f, %.2f)", status, t - start, *self.position)

    def is_done(self) -> bool:
        return self.phase == DONE
