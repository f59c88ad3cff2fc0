"""move_base (node type move_base/move_base): a global costmap and planner, a local costmap and
local planner, recoveries, move_base's state machine and actionlib's interface on topics
(docs/navigation.md).

The local planner's acceleration window starts from the last command, not from odometry as ROS's
planners do: qbot's wheels do not move at small commands, so a window around the measured (zero)
velocity would keep every command at one acceleration step for ever. With
twil_control/BacksteppingLocalPlanner there is no cmd_vel: each cycle's waypoint goes to the cart
controller as its platform pose (nodes/cart_command_output.py).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from twil_control.errors import InputError

from ..control.transforms import quat_from_yaw, yaw_from_quat
from ..core.actionlib import GoalStatus
from ..core.messages import header, msg_class
from ..core.ros_node import RosNode
from ..core.tf import TfBuffer, TfError
from ..core.typed_params import load_typed
from ..navigation import costmap as cm
from ..navigation import grid_planner
from ..navigation.goals import validate_goal
from ..navigation.local_planner import TrajectoryParams
from ..navigation.ompl_planner import OmplSettings
from ..navigation.ompl_planner import Planner as OmplPlanner
from ..navigation.plans import PlanFailure, blocked_ahead, diagnose, prune, transform_path
from .costmap_ros import CostmapRos, pose2d
from .move_base_advice import advice
from .move_base_local import LOCAL_PLANNERS, LocalPlanner, TrajectoryPlannerROS
from .move_base_params import (
    GLOBAL_PLANNERS,
    GridPlannerParams,
    MoveBaseParams,
)
from .move_base_recovery import RECOVERY_BEHAVIORS, RecoveryBehavior

ACTIVE, PREEMPTED, SUCCEEDED, ABORTED, REJECTED = (
    GoalStatus.ACTIVE,
    GoalStatus.PREEMPTED,
    GoalStatus.SUCCEEDED,
    GoalStatus.ABORTED,
    GoalStatus.REJECTED,
)
PLANNING, CONTROLLING, CLEARING = "PLANNING", "CONTROLLING", "CLEARING"
STATUS_KEEP = 5.0  # s a finished goal stays in the status list (actionlib's status_list_timeout)

DEFAULT_RECOVERIES = [
    {"name": "conservative_reset", "type": "clear_costmap_recovery/ClearCostmapRecovery"},
    {"name": "rotate_recovery", "type": "rotate_recovery/RotateRecovery"},
    {"name": "aggressive_reset", "type": "clear_costmap_recovery/ClearCostmapRecovery"},
    {"name": "rotate_recovery", "type": "rotate_recovery/RotateRecovery"},
]


@dataclass
class Goal:
    id: str
    stamp: float
    pose: tuple[float, float, float]  # in the global costmap's frame
    status: GoalStatus = ACTIVE
    text: str = ""
    finished_at: float | None = None


class MoveBase(RosNode):
    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        p = self.params = self.typed_params(MoveBaseParams)
        self.tf = TfBuffer(self)
        self.global_costmap = CostmapRos(self, "global_costmap", self.tf)
        self.local_costmap = CostmapRos(self, "local_costmap", self.tf)
        # ~TrajectoryPlannerROS is also the rotate recovery's (as rotate_recovery reads it); when it
        # is not the local planner, what it holds beyond that is not read, so not warned about
        self.traj_params = self._trajectory_params()
        self.local: LocalPlanner = LOCAL_PLANNERS[p.base_local_planner].load(self)
        for message in advice(
            self, p, self.local.ns, self.local.params, (self.global_costmap.setup, self.local_costmap.setup)
        ):
            self.log.warning("%s", message)
        self.planner_kind = GLOBAL_PLANNERS[p.base_global_planner]
        planner_ns = p.base_global_planner.split("/")[1]
        if self.planner_kind == "ompl":
            self.ompl = self.typed_params(OmplSettings, "~OmplGlobalPlanner")
            self.plan_spacing = self.ompl.planning_time
            # every plan seeds OMPL from the run's seed: the same launch and --seed give the same bag
            self._ompl_rng = self.master.rng(f"{self.fqn}/ompl")
        else:
            self.grid = self.typed_params(GridPlannerParams, f"~{planner_ns}")
            self.plan_spacing = 1.0 / p.controller_frequency
        self.recoveries = self._load_recoveries()
        self._cmd_pub = self.create_publisher("cmd_vel", "geometry_msgs/Twist")
        self._plan_pub = self.create_publisher(f"~{planner_ns}/plan", "nav_msgs/Path")
        self._local_plan_pub = self.create_publisher(f"~{self.local.ns}/local_plan", "nav_msgs/Path")
        self._status_pub = self.create_publisher("~status", "actionlib_msgs/GoalStatusArray")
        self._result_pub = self.create_publisher("~result", "twil_control/MoveBaseActionResult")
        self._feedback_pub = self.create_publisher("~feedback", "twil_control/MoveBaseActionFeedback")
        self.create_subscription("move_base_simple/goal", "geometry_msgs/PoseStamped", self._on_simple_goal)
        self.create_subscription("~goal", "twil_control/MoveBaseActionGoal", self._on_action_goal)
        self.create_subscription("~cancel", "actionlib_msgs/GoalID", self._on_cancel)
        self.create_timer(1.0 / p.controller_frequency, self._cycle)
        self.create_timer(0.2, lambda e: self._publish_status())
        self.goal: Goal | None = None
        self.finished: list[Goal] = []
        self.state = PLANNING
        self.plan: np.ndarray | None = None
        self.velocity = (0.0, 0.0)
        self._goal_count = 0
        self._reset_goal_state(0.0)

    # -- parameters -------------------------------------------------------------------------
    def _trajectory_params(self) -> TrajectoryParams:
        ns = self.resolve("~TrajectoryPlannerROS")
        if LOCAL_PLANNERS[self.params.base_local_planner] is TrajectoryPlannerROS:
            return self.typed_params(TrajectoryParams, ns)
        return load_typed(self.master.params, ns, TrajectoryParams, warn=lambda message: None)

    def sim_period(self, local) -> float:
        """The period the local planner's acceleration window spans: 1 / its own
        controller_frequency, else move_base's (ROS searches the parameter upwards)."""
        return 1.0 / (local.controller_frequency or self.params.controller_frequency)

    def _load_recoveries(self) -> list[RecoveryBehavior]:
        p = self.params
        specs = DEFAULT_RECOVERIES if p.recovery_behaviors is None else p.recovery_behaviors
        out = []
        for i, spec in enumerate(specs):
            if (
                not isinstance(spec, dict)
                or set(spec) != {"name", "type"}
                or spec["type"] not in RECOVERY_BEHAVIORS
            ):
                raise InputError(
                    f"node {self.fqn}: ~recovery_behaviors[{i}] must be {{name, type}} with type one "
                    f"of {', '.join(RECOVERY_BEHAVIORS)} (got {spec!r})"
                )
            behavior = RECOVERY_BEHAVIORS[spec["type"]](self, spec["name"])
            if behavior is not None:
                out.append(behavior)
        return out

    # -- goals ------------------------------------------------------------------------------
    def _on_simple_goal(self, msg) -> None:
        self._goal_count += 1
        self._new_goal(f"{self.fqn}-{self._goal_count}-{self.now():.3f}", msg)

    def _on_action_goal(self, msg) -> None:
        gid = msg.goal_id.id or f"{self.fqn}-{self._goal_count}-{self.now():.3f}"
        self._goal_count += 1
        self._new_goal(gid, msg.goal.target_pose)

    def _on_cancel(self, msg) -> None:
        if self.goal is not None and (msg.id == "" or msg.id == self.goal.id):
            self._finish(PREEMPTED, "goal cancelled")

    def _new_goal(self, gid: str, pose_msg) -> None:
        now = self.now()
        reason = validate_goal(pose_msg)
        pose = None
        if reason is None:
            try:
                pose = self._goal_in_global_frame(pose_msg)
            except TfError as exc:
                reason = f"goal frame '{pose_msg.header.frame_id}' cannot be transformed: {exc}"
        if reason is not None:
            rejected = Goal(gid, now, (math.nan,) * 3, REJECTED, reason, now)
            self.log.warning("goal %s rejected: %s", gid, reason)
            self._publish_result(rejected)
            self.finished.append(rejected)
            self._publish_status()
            return
        if self.goal is not None:
            self._finish(PREEMPTED, f"preempted by goal {gid}", stop=False)
        self.goal = Goal(gid, now, pose)
        self.log.info("new goal %s: (%.3f, %.3f, %.3f)", gid, *pose)
        self._reset_goal_state(now)
        self._publish_status()

    def _goal_in_global_frame(self, msg) -> tuple[float, float, float]:
        p, q = msg.pose.position, msg.pose.orientation
        yaw = yaw_from_quat((q.x, q.y, q.z, q.w))
        frame = self.global_costmap.params.global_frame
        src = msg.header.frame_id or frame
        if src == frame:
            return (p.x, p.y, yaw)
        t, rq = self.tf.lookup_transform(frame, src)
        tx, ty, tyaw = pose2d(t, rq)
        c, s = math.cos(tyaw), math.sin(tyaw)
        return (tx + c * p.x - s * p.y, ty + s * p.x + c * p.y, math.remainder(yaw + tyaw, 2 * math.pi))

    def _reset_goal_state(self, now: float) -> None:
        self.state = PLANNING
        self.plan = None
        self.last_valid_plan = now
        self.last_valid_control = now
        self.next_plan_attempt = now
        self.planning_retries = 0
        self.recovery_index = 0
        self.recovery_trigger = None
        self.last_failure: PlanFailure | None = None
        for behavior in self.recoveries:
            behavior.reset()
        self.oscillation_reset = now
        self.oscillation_pose = None
        self._checked_costs = None
        self.local.reset()

    def _finish(self, status: GoalStatus, text: str, stop: bool = True) -> None:
        g = self.goal
        g.status, g.text, g.finished_at = status, text, self.now()
        log = self.log.info if status in (SUCCEEDED, PREEMPTED) else self.log.warning
        log(
            "goal %s %s: %s",
            g.id,
            status.name,
            text,
        )
        # the goal is over before anyone hears of it: a client may send the next goal from its
        # result callback (the bus delivers at once), which must not preempt this one
        self.finished.append(g)
        self.goal = None
        if stop:
            self.local.stop(self)
        self._publish_result(g)
        self._publish_status()

    # -- the control cycle ------------------------------------------------------------------
    def _cycle(self, event) -> None:
        if self.goal is None:
            return
        now = self.now()
        period = 1.0 / self.params.controller_frequency
        try:
            gpose = self.global_costmap.robot_pose()
        except TfError as exc:
            self.log_once(
                logging.WARNING,
                "no-pose",
                f"no robot pose in {self.global_costmap.params.global_frame}: {exc}",
            )
            self.local.stop(self)
            return
        self._publish_feedback(gpose)
        p = self.params
        if self.state == CONTROLLING and p.planner_frequency > 0 and now >= self.next_plan_attempt:
            self._plan(gpose, now, replanning=True)
        if self.state == CONTROLLING and p.replan_when_blocked and self._plan_blocked(gpose):
            self.log_once(
                logging.INFO,
                "replan-blocked",
                "re-planning: the global costmap blocks the plan (logged once)",
            )
            self._plan(gpose, now, replanning=True)
        if self.state == PLANNING:
            self.local.stop(self)
            if now >= self.next_plan_attempt - 1e-9:
                self._plan(gpose, now)
        if self.state == CONTROLLING:
            self._control(now, period)
        if self.state == CLEARING:
            self._clear(now, period)

    def _plan_blocked(self, gpose) -> bool:
        """Whether the plan being followed crosses a cell the global planner could not plan through,
        checked once per global costmap update (replan_when_blocked)."""
        m = self.global_costmap.costmap.master
        if self.plan is None or m.costs is self._checked_costs:
            return False
        self._checked_costs = m.costs
        if self.planner_kind == "grid":
            allow_unknown, lethal = self.grid.allow_unknown, self.grid.lethal_cost
        else:
            allow_unknown, lethal = self.ompl.allow_unknown, cm.INSCRIBED
        radius = self.global_costmap.costmap.circumscribed_radius
        return blocked_ahead(m, self.plan, gpose, radius, allow_unknown, lethal)

    def _plan(self, gpose, now: float, replanning: bool = False) -> None:
        p = self.params
        spacing = 1.0 / p.planner_frequency if replanning and p.planner_frequency > 0 else self.plan_spacing
        self.next_plan_attempt = now + spacing
        if not self.global_costmap.have_map:
            # move_base does not serve goals before the static map is there (Costmap2DROS waits for
            # it): the goal waits, and planner_patience starts when the map arrives
            self.log_once(logging.INFO, "wait-map", "waiting for the map before planning")
            self.last_valid_plan = now
            return
        if not self.global_costmap.costmap.updated:
            self.global_costmap.update()
        plan, failure = self._make_plan(gpose, self.goal.pose)
        if plan is not None:
            self.plan = plan
            self.local.new_plan()
            self.last_valid_plan = now
            self.planning_retries = 0
            self._publish_path(self._plan_pub, plan, self.global_costmap.params.global_frame)
            if self.state == PLANNING:
                self.state = CONTROLLING  # last_valid_control is not reset: patience spans re-plans
            return
        self.last_failure = failure
        self.planning_retries += 1
        if replanning:
            return  # keep following the last plan, as move_base does while a new one is sought
        out_of_patience = now > self.last_valid_plan + p.planner_patience
        out_of_retries = p.max_planning_retries >= 0 and self.planning_retries > p.max_planning_retries
        if out_of_patience or out_of_retries:
            self.state, self.recovery_trigger = CLEARING, "planning"

    def _make_plan(self, start, goal) -> tuple[np.ndarray | None, PlanFailure | None]:
        costmap = self.global_costmap.costmap
        if not costmap.updated:
            return None, PlanFailure("the global costmap has no data yet (no map received, or no robot pose)")
        m = costmap.master
        if self.planner_kind == "grid":
            # the plan first, the reason only when there is none (each is a search of the grid)
            g = self.grid
            s, t = m.world_to_cell(start[0], start[1]), m.world_to_cell(goal[0], goal[1])
            try:
                cells, _ = grid_planner.plan_cells(
                    m.costs,
                    (int(s[0]), int(s[1])),
                    (int(t[0]), int(t[1])),
                    g.cost_factor,
                    g.lethal_cost,
                    g.allow_unknown,
                )
            except grid_planner.NoPathError as exc:
                return None, diagnose(m, start, goal, g.allow_unknown) or PlanFailure(str(exc))
            x, y = m.cell_to_world(cells[:, 0], cells[:, 1])
            x[0], y[0], x[-1], y[-1] = start[0], start[1], goal[0], goal[1]
            yaw = np.arctan2(np.gradient(y), np.gradient(x)) if len(x) > 1 else np.array([goal[2]])
            yaw[-1] = goal[2]
            return np.column_stack([x, y, yaw]), None
        failure = diagnose(m, start, goal, False)
        if failure is not None:
            return None, failure
        seed = int(self._ompl_rng.integers(1, 2**31))
        result = OmplPlanner(m, costmap.cells, self.ompl, seed).solve(start, goal)
        if result.poses is None:
            return None, PlanFailure(
                f"OMPL {self.ompl.planner} found no path in {self.ompl.planning_time} s "
                f"({result.status}), though the grid connects the robot to the goal"
            )
        poses = result.poses
        poses[-1, 2] = goal[2]
        return poses, None

    def _control(self, now: float, period: float) -> None:
        p = self.params
        lc = self.local_costmap
        try:
            lpose = lc.robot_pose()
            T = pose2d(
                *self.tf.lookup_transform(lc.params.global_frame, self.global_costmap.params.global_frame)
            )
        except TfError as exc:
            self.log_once(
                logging.WARNING, "no-local-pose", f"no robot pose in {lc.params.global_frame}: {exc}"
            )
            self.local.stop(self)
            return
        if not lc.costmap.updated:
            lc.update()
        if p.oscillation_timeout > 0:
            if (
                self.oscillation_pose is None
                or math.dist(lpose[:2], self.oscillation_pose) >= p.oscillation_distance
            ):
                self.oscillation_pose, self.oscillation_reset = lpose[:2], now
                self.recovery_index = 0
            elif now > self.oscillation_reset + p.oscillation_timeout:
                self.local.stop(self)
                self.state, self.recovery_trigger = CLEARING, "oscillation"
                return
        local_plan = transform_path(self.plan, T)
        if self.local.prunes_plan():
            local_plan = prune(local_plan, lpose)
        step = self.local.compute(self, lpose, local_plan, period)
        if step.goal_reached:
            self._finish(SUCCEEDED, "goal reached")
            return
        if step.valid:
            self.last_valid_control = now
            if step.path is not None:
                self._publish_path(self._local_plan_pub, step.path, lc.params.global_frame)
            return
        self.local.stop(self)
        if now > self.last_valid_control + p.controller_patience:
            self.state, self.recovery_trigger = CLEARING, "control"
        else:
            self.state = PLANNING  # move_base re-plans when the controller finds no valid command

    def _clear(self, now: float, period: float) -> None:
        if not self.params.recovery_behavior_enabled or self.recovery_index >= len(self.recoveries):
            reasons = {
                "planning": self.last_failure.reason if self.last_failure else "no valid plan",
                "control": "the local planner found no valid command (controller_patience ran out)",
                "oscillation": "the robot oscillated (oscillation_timeout ran out)",
            }
            done = " even after the recovery behaviors" if self.params.recovery_behavior_enabled else ""
            self._finish(ABORTED, f"{reasons[self.recovery_trigger]}{done}")
            return
        if not self.recoveries[self.recovery_index].run(self, now, period):
            self._recovery_done(now)

    def _recovery_done(self, now: float) -> None:
        self.recovery_index += 1
        self.state = PLANNING
        self.next_plan_attempt = now
        self.oscillation_reset = now

    # -- output -----------------------------------------------------------------------------
    def publish_cmd(self, v: float, w: float) -> None:
        """A Twist on cmd_vel (the velocity planners and the rotate recovery)."""
        self.velocity = (v, w)
        vec = msg_class("geometry_msgs/Vector3")
        self._cmd_pub.publish(
            msg_class("geometry_msgs/Twist")(
                linear=vec(x=float(v), y=0.0, z=0.0), angular=vec(x=0.0, y=0.0, z=float(w))
            )
        )

    def _publish_path(self, pub, poses: np.ndarray, frame: str) -> None:
        pub.publish(path_msg(frame, self.now(), poses))

    def _status_msg(self, g: Goal):
        gid = msg_class("actionlib_msgs/GoalID")(stamp=header("", g.stamp).stamp, id=g.id)
        return msg_class("actionlib_msgs/GoalStatus")(goal_id=gid, status=g.status, text=g.text)

    def _publish_status(self) -> None:
        now = self.now()
        self.finished = [g for g in self.finished if now - g.finished_at <= STATUS_KEEP]
        goals = self.finished + ([self.goal] if self.goal is not None else [])
        self._status_pub.publish(
            msg_class("actionlib_msgs/GoalStatusArray")(
                header=header("", now), status_list=[self._status_msg(g) for g in goals]
            )
        )

    def _publish_result(self, g: Goal) -> None:
        self._result_pub.publish(
            msg_class("twil_control/MoveBaseActionResult")(
                header=header("", self.now()),
                status=self._status_msg(g),
                result=msg_class("twil_control/MoveBaseResult")(),
            )
        )

    def _publish_feedback(self, gpose) -> None:
        frame = self.global_costmap.params.global_frame
        self._feedback_pub.publish(
            msg_class("twil_control/MoveBaseActionFeedback")(
                header=header("", self.now()),
                status=self._status_msg(self.goal),
                feedback=msg_class("twil_control/MoveBaseFeedback")(
                    base_position=pose_stamped(frame, self.now(), gpose)
                ),
            )
        )


# -- messages ---------------------------------------------------------------------------------
def path_msg(frame: str, t: float, poses: np.ndarray):
    """nav_msgs/Path of (k, 3) poses, every pose stamped t in `frame` (one header object shared:
    messages are not mutated after publication, and one header per pose was costly)."""
    hdr = header(frame, t)
    Point, Quaternion = msg_class("geometry_msgs/Point"), msg_class("geometry_msgs/Quaternion")
    Pose, PoseStamped = msg_class("geometry_msgs/Pose"), msg_class("geometry_msgs/PoseStamped")
    half = 0.5 * np.asarray(poses[:, 2], dtype=float)
    qz, qw = np.sin(half).tolist(), np.cos(half).tolist()
    xs, ys = np.asarray(poses[:, 0], dtype=float).tolist(), np.asarray(poses[:, 1], dtype=float).tolist()
    return msg_class("nav_msgs/Path")(
        header=hdr,
        # positional fields in the messages' definition order: a plan every cycle builds thousands
        poses=[
            PoseStamped(hdr, Pose(Point(x, y, 0.0), Quaternion(0.0, 0.0, z, w)))
            for x, y, z, w in zip(xs, ys, qz, qw)
        ],
    )


def pose_stamped(frame: str, t: float, pose):
    q = quat_from_yaw(float(pose[2]))
    return msg_class("geometry_msgs/PoseStamped")(
        header=header(frame, t),
        pose=msg_class("geometry_msgs/Pose")(
            position=msg_class("geometry_msgs/Point")(x=float(pose[0]), y=float(pose[1]), z=0.0),
            orientation=msg_class("geometry_msgs/Quaternion")(x=q[0], y=q[1], z=q[2], w=q[3]),
        ),
    )
