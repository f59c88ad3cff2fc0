"""The TWIL platform's local planner for move_base (twil_control/BacksteppingLocalPlanner): no
velocity sampling, but a reference pose for the cart_linearizing_controller, whose backstepping
law (the paper's (37)-(52)) drives the platform to it.

The reference is a waypoint `lookahead` ahead on the plan, headed against the path by default,
because the law approaches its reference rear first (alpha = 0 is its stable configuration).
The law drives along a curve, so the line to the waypoint must stay clear of the inscribed zone.
The reasoning and the parameters: docs/navigation.md. Pure: numpy only; poses (x, y, yaw) and
plans (k, 3) in the local costmap's frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from twil_control.errors import TwilControlError

from . import costmap as cm

SAMPLE = 0.025  # m between the resampled plan's points
HEADING_SPAN = 0.25  # m: the path's heading is taken over +-HEADING_SPAN (grid paths zigzag by cells)


class BacksteppingPlannerError(TwilControlError, ValueError):
    """Parameters the waypoint follower cannot work with."""


@dataclass
class BacksteppingPlannerParams:
    """~BacksteppingLocalPlanner's parameters (names in base_local_planner's style)."""

    # the cart controller's namespace: commands go to <controller>/command, the arm's joint names
    # are read from <controller>/arm_joints
    controller: str = "/twil/ros_control/cart_linearizing_controller"
    # the frame of the controller's pose_source: odom for odometry (its odometry starts where
    # wheel_odometry's does), the simulator's world (= map under fake_localization) for ground_truth
    command_frame: str = "odom"
    joint_states: str = "/joint_states"
    lookahead: float = 0.6
    min_lookahead: float = 0.15
    xy_goal_tolerance: float = 0.1
    yaw_goal_tolerance: float = 0.1
    latch_xy_goal_tolerance: bool = False
    # waypoints headed against the path (the law's stable approach, see the module's docstring);
    # false: along it (for a law that approaches its reference driving forwards)
    backwards: bool = True

    def __post_init__(self) -> None:
        for name in ("lookahead", "min_lookahead", "xy_goal_tolerance", "yaw_goal_tolerance"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise BacksteppingPlannerError(
                    f"{name} must be a finite number > 0 m (rad for yaw) (got {value!r})"
                )
        if self.min_lookahead > self.lookahead:
            raise BacksteppingPlannerError(
                f"min_lookahead ({self.min_lookahead}) must be <= lookahead ({self.lookahead})"
            )


@dataclass
class Reference:
    pose: tuple[float, float, float] | None  # the reference for the controller (None: no valid one)
    goal_reached: bool
    final: bool = False  # the reference is the goal pose itself


def resample(plan: np.ndarray, step: float = SAMPLE) -> tuple[np.ndarray, np.ndarray]:
    """(points (n, 2), their arc lengths (n,)) of the plan's polyline every `step` metres."""
    xy = np.asarray(plan[:, :2], dtype=float)
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
    if s[-1] <= 0.0:
        return xy[:1], s[:1]
    q = np.append(np.arange(0.0, s[-1], step), s[-1])
    return np.column_stack([np.interp(q, s, xy[:, 0]), np.interp(q, s, xy[:, 1])]), q


def path_heading(points: np.ndarray, arc: np.ndarray, i: int) -> float:
    """Direction of the path at point i, over +-HEADING_SPAN of arc length."""
    a = int(np.searchsorted(arc, arc[i] - HEADING_SPAN))
    b = min(len(arc) - 1, int(np.searchsorted(arc, arc[i] + HEADING_SPAN)))
    a = min(a, b - 1) if b > 0 else 0
    d = points[b] - points[a]
    return math.atan2(d[1], d[0])


def segment_free(costmap: cm.Costmap, a, b) -> bool:
    """No cell on the segment a -> b (sampled at half the resolution) at or above INSCRIBED
    (unknown cells count as free, as in the local planner's checker), except a leading run of
    INSCRIBED cells: a robot already that close to an obstacle may leave (escape) along it; no
    LETHAL cell anywhere; cells outside the costmap are not free."""
    n = max(2, int(math.ceil(math.dist(a, b) / (0.5 * costmap.resolution))) + 1)
    t = np.linspace(0.0, 1.0, n)
    r, c = costmap.world_to_cell(a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]))
    if not costmap.inside(r, c).all():
        return False
    cost = costmap.costs[r, c]
    blocked = (cost >= cm.INSCRIBED) & (cost != cm.NO_INFORMATION)
    if (cost == cm.LETHAL).any():
        return False
    first_free = int(np.argmin(blocked)) if not blocked.all() else len(blocked)
    return not blocked[first_free:].any()


class WaypointFollower:
    """Picks the controller's reference each cycle and decides when the goal is reached."""

    def __init__(self, params: BacksteppingPlannerParams) -> None:
        self.p = params
        self.xy_latched = False

    def reset(self) -> None:
        self.xy_latched = False

    def goal_reached(self, pose, goal) -> bool:
        p = self.p
        if math.hypot(goal[0] - pose[0], goal[1] - pose[1]) <= p.xy_goal_tolerance:
            self.xy_latched = self.xy_latched or p.latch_xy_goal_tolerance
            xy_ok = True
        else:
            xy_ok = self.xy_latched
        return xy_ok and abs(math.remainder(goal[2] - pose[2], 2 * math.pi)) <= p.yaw_goal_tolerance

    def compute(self, costmap: cm.Costmap, pose, plan: np.ndarray) -> Reference:
        """The reference for this cycle; `plan` (k, 3) ends at the goal (whose yaw is the goal's);
        the part before its point nearest the robot is ignored."""
        goal = tuple(float(v) for v in plan[-1])
        if self.goal_reached(pose, goal):
            return Reference(None, True, True)
        points, arc = resample(plan)
        dist = np.hypot(points[:, 0] - pose[0], points[:, 1] - pose[1])
        nearest = int(np.argmin(dist))  # the plan from its point nearest the robot on
        beyond = nearest + np.nonzero(dist[nearest:] >= self.p.lookahead)[0]
        if len(beyond):
            end, final = int(beyond[0]), False
        else:
            end, final = len(points) - 1, True
        # from the waypoint back towards the robot, the farthest one the segment reaches freely
        for i in range(end, nearest - 1, -2):
            if dist[i] < self.p.min_lookahead and not (final and i == len(points) - 1):
                break
            if segment_free(costmap, pose[:2], points[i]):
                if final and i == len(points) - 1:
                    return Reference(goal, False, True)
                x, y = points[i]
                heading = path_heading(points, arc, i) + (math.pi if self.p.backwards else 0.0)
                return Reference((float(x), float(y), math.remainder(heading, 2 * math.pi)), False)
        return Reference(None, False)
