"""dwa_local_planner's DWAPlanner: the dynamic-window variant of the trajectory rollout planner
(navigation/local_planner.py), with DWAPlannerROS's parameter names.

Velocities are sampled within what the acceleration limits reach in one control period, rolled
out at constant velocity, and scored by DWAPlanner's critics (path, goal, obstacle, twirling,
oscillation), ties going to the first sample in its generator's order. The sampling and the
cost: docs/navigation.md. vy is always 0: the robots simulated here are not holonomic.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from . import costmap as cm
from .footprint import FootprintCells
from .local_planner import (
    NO_CLOUDS,
    NOT_HOLONOMIC,
    UNREACHABLE,
    Choice,
    LocalPlannerError,
    Oscillation,
    SamplingPlanner,
    check_footprint_check,
    distance_maps,
    distances_from,
    free_cells,
    map_values,
    rollout,
)

AT_GOAL = "at the goal the robot decelerates while it turns to the goal's yaw, without waiting to stop"
SCALING = "the footprint is checked at its own size at every speed"


@dataclass
class DWAParams:
    """DWAPlannerROS's parameters: names and defaults of dwa_local_planner's DWAPlanner.cfg (with
    base_local_planner's generic local planner limits) and DWAPlannerROS."""

    ros_package: ClassVar[str] = "dwa_local_planner"
    #: the names before ROS Melodic, read (with a warning) when the new one is not set
    renamed: ClassVar[dict] = {
        "max_trans_vel": "max_vel_trans",
        "min_trans_vel": "min_vel_trans",
        "max_rot_vel": "max_vel_theta",
        "min_rot_vel": "min_vel_theta",
        "acc_limit_trans": "acc_lim_trans",
        "rot_stopped_vel": "theta_stopped_vel",
    }
    no_effect: ClassVar[dict] = {
        "max_vel_y": (0.0, NOT_HOLONOMIC),
        "min_vel_y": (0.0, NOT_HOLONOMIC),
        "acc_lim_trans": "translation is bounded by acc_lim_x alone",
        "trans_stopped_vel": AT_GOAL,
        "theta_stopped_vel": AT_GOAL,
        "stop_time_buffer": "a trajectory is valid when its whole rollout is free, with no time kept to stop",
        "scaling_speed": SCALING,
        "max_scaling_factor": SCALING,
        "sum_scores": (False, "the obstacle term is the highest cost met along a trajectory"),
        "publish_traj_pc": (False, NO_CLOUDS),
        "publish_cost_grid_pc": (False, NO_CLOUDS),
        "publish_cost_grid": (False, NO_CLOUDS),
        "restore_defaults": (False, "dynamic_reconfigure is not served"),
        "odom_topic": ("odom", "the current velocity is move_base's last command, not odometry"),
    }

    max_vel_trans: float = 0.55
    min_vel_trans: float = 0.1
    max_vel_x: float = 0.55
    min_vel_x: float = 0.0
    max_vel_y: float = 0.1
    min_vel_y: float = -0.1
    max_vel_theta: float = 1.0
    min_vel_theta: float = 0.4
    acc_lim_x: float = 2.5
    acc_lim_y: float = 2.5
    acc_lim_theta: float = 3.2
    acc_lim_trans: float = 0.1
    prune_plan: bool = False
    xy_goal_tolerance: float = 0.1
    yaw_goal_tolerance: float = 0.1
    latch_xy_goal_tolerance: bool = False
    trans_stopped_vel: float = 0.1
    theta_stopped_vel: float = 0.1
    sim_time: float = 1.7
    sim_granularity: float = 0.025
    angular_sim_granularity: float = 0.1
    path_distance_bias: float = 32.0
    goal_distance_bias: float = 24.0
    occdist_scale: float = 0.01
    twirling_scale: float = 0.0
    stop_time_buffer: float = 0.2
    oscillation_reset_dist: float = 0.05
    oscillation_reset_angle: float = 0.2
    forward_point_distance: float = 0.325
    scaling_speed: float = 0.25
    max_scaling_factor: float = 0.2
    vx_samples: int = 3
    vy_samples: int = 10
    vth_samples: int = 20
    use_dwa: bool = True
    restore_defaults: bool = False
    # searched upwards from DWAPlannerROS's namespace as in ROS: unset here, move_base's
    controller_frequency: float | None = None
    cheat_factor: float = 1.0
    sum_scores: bool = False
    publish_traj_pc: bool = False
    publish_cost_grid_pc: bool = False
    publish_cost_grid: bool = False
    global_frame_id: str = "odom"
    odom_topic: str = "odom"
    # Not in DWAPlanner: how a pose's footprint is tested (local_planner.FOOTPRINT_CHECKS)
    footprint_check: str = "outline"

    def __post_init__(self) -> None:
        for name in (
            "max_vel_trans",
            "min_vel_trans",
            "max_vel_theta",
            "min_vel_theta",
            "acc_lim_x",
            "acc_lim_y",
            "acc_lim_theta",
            "xy_goal_tolerance",
            "yaw_goal_tolerance",
            "forward_point_distance",
            "oscillation_reset_dist",
            "oscillation_reset_angle",
            "path_distance_bias",
            "goal_distance_bias",
            "occdist_scale",
            "twirling_scale",
        ):
            if not getattr(self, name) >= 0:
                raise LocalPlannerError(f"{name} must be >= 0 (got {getattr(self, name)})")
        for name in (
            "sim_time",
            "sim_granularity",
            "angular_sim_granularity",
            "max_vel_theta",
            "acc_lim_x",
            "acc_lim_theta",
        ):
            if not getattr(self, name) > 0:
                raise LocalPlannerError(f"{name} must be > 0 (got {getattr(self, name)})")
        if self.min_vel_x > self.max_vel_x:
            raise LocalPlannerError(f"min_vel_x ({self.min_vel_x}) must be <= max_vel_x ({self.max_vel_x})")
        if self.min_vel_theta > self.max_vel_theta:
            raise LocalPlannerError(
                f"min_vel_theta ({self.min_vel_theta}, the slowest rotation) must be <= "
                f"max_vel_theta ({self.max_vel_theta})"
            )
        if self.controller_frequency is not None and not self.controller_frequency > 0:
            raise LocalPlannerError(f"controller_frequency must be > 0 Hz (got {self.controller_frequency})")
        check_footprint_check(self.footprint_check)

    @property
    def turn_limits(self) -> tuple[float, float]:
        """The rotational velocities allowed, (most negative, most positive)."""
        return -self.max_vel_theta, self.max_vel_theta

    @property
    def min_turn_in_place(self) -> float:
        return self.min_vel_theta


def velocity_samples(lo: float, hi: float, n: int) -> np.ndarray:
    """VelocityIterator's samples: lo alone if lo >= hi, else max(2, n) evenly spaced from lo to
    hi, with 0 inserted between a negative and a positive sample."""
    if lo >= hi:
        return np.array([lo])
    values = np.linspace(lo, hi, max(2, n))
    values[np.abs(values) < 1e-9] = 0.0  # a sample that is 0 but for rounding
    k = np.searchsorted(values, 0.0)
    if 0 < k < len(values) and values[k - 1] < 0 < values[k]:
        values = np.insert(values, k, 0.0)
    return values


def dwa_samples(p: DWAParams, vx: float, vth: float, window: float) -> np.ndarray:
    """(n, 2) (vx, vth) samples of the velocities reachable within `window` s, in the generator's
    order (vx outer), those that neither move nor turn fast enough or translate too fast dropped."""
    vxs = velocity_samples(
        max(p.min_vel_x, vx - p.acc_lim_x * window), min(p.max_vel_x, vx + p.acc_lim_x * window), p.vx_samples
    )
    ths = velocity_samples(
        max(-p.max_vel_theta, vth - p.acc_lim_theta * window),
        min(p.max_vel_theta, vth + p.acc_lim_theta * window),
        p.vth_samples,
    )
    grid = np.column_stack([np.repeat(vxs, len(ths)), np.tile(ths, len(vxs))])
    eps = 1e-4
    still = (np.abs(grid[:, 0]) + eps < p.min_vel_trans) & (np.abs(grid[:, 1]) + eps < p.min_vel_theta)
    too_fast = np.abs(grid[:, 0]) - eps > p.max_vel_trans
    return grid[~still & ~too_fast]


class DWAPlanner(SamplingPlanner):
    @property
    def judges_own_pose(self) -> bool:
        """Upstream judges the robot's own pose (its rollouts' first point) by the footprint's
        outline; with the filled test a robot brushing an obstacle would have no trajectory at
        all, and DWAPlanner has no escape, so then the own pose is not judged."""
        return self.p.footprint_check == "outline"

    def __init__(self, params: DWAParams, cells: FootprintCells, sim_period: float) -> None:
        super().__init__(params, cells, sim_period)
        self.oscillation = Oscillation(
            params.oscillation_reset_dist, params.oscillation_reset_angle, params.min_vel_trans
        )

    def new_plan(self) -> None:
        self.oscillation.reset()

    def samples(self, velocity) -> np.ndarray:
        p = self.p
        return dwa_samples(p, velocity[0], velocity[1], self.sim_period if p.use_dwa else p.sim_time)

    def choose(
        self, costmap: cm.Costmap, pose, velocity, plan_xy: np.ndarray, period: float, escaping: bool = False
    ) -> Choice:
        """The best sample's velocity, commanded as it is (it lies in the window); no escape."""
        p = self.p
        samples = self.samples(velocity)
        if not len(samples):
            return Choice((0.0, 0.0), False, math.inf, None)
        acc = (math.inf, math.inf) if p.use_dwa else (p.acc_lim_x, p.acc_lim_theta)
        traj = rollout(
            pose, velocity, samples, p.sim_time, p.sim_granularity, p.angular_sim_granularity, *acc
        )
        maps = distance_maps(costmap, plan_xy)
        # ObstacleCostFunction and the path and goal critics judge every point of a trajectory
        legal, occ = self.legal(costmap, pose, traj, maps[0], maps[1])
        grid_cost, valid = self.grid_terms(costmap, pose, maps, traj)
        cost = grid_cost + p.occdist_scale * occ + p.twirling_scale * np.abs(samples[:, 1])
        cost = np.where(legal & valid & self.oscillation.allowed(samples), cost, np.inf)
        best = int(np.argmin(cost))  # the first of equal costs, in the generator's order
        if not np.isfinite(cost[best]):
            return Choice((0.0, 0.0), False, math.inf, None)
        cmd = (float(samples[best, 0]), float(samples[best, 1]))
        self.oscillation.update(pose, cmd)
        return Choice(cmd, True, float(cost[best]), traj[best])

    def grid_terms(
        self, costmap: cm.Costmap, pose, maps: tuple, traj: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """(the path and goal terms of every trajectory, whether they leave it valid), from the
        path and goal distance maps and the local goal (distance_maps)."""
        p = self.p
        free = free_cells(costmap)
        path_map, goal_map, goal = maps
        end = traj[:, -1, :]
        nose_x = end[:, 0] + p.forward_point_distance * np.cos(end[:, 2])
        nose_y = end[:, 1] + p.forward_point_distance * np.sin(end[:, 2])
        path_end = map_values(costmap, path_map, end[:, 0], end[:, 1])
        goal_end = map_values(costmap, goal_map, end[:, 0], end[:, 1])
        # the local goal pushed forward along the robot -> goal direction, for the nose to reach
        # (the goal itself if that leaves the grid)
        heading = math.atan2(goal[1] - pose[1], goal[0] - pose[0])
        front = (
            goal[0] + p.forward_point_distance * math.cos(heading),
            goal[1] + p.forward_point_distance * math.sin(heading),
        )
        if not costmap.inside(*costmap.world_to_cell(*front)):
            front = tuple(goal)
        front_map = distances_from(costmap, *front, free=free)
        # a nose cell no free path connects costs more than any connected one (the grid's cell
        # count + 1) without invalidating the trajectory; a nose off the grid invalidates it
        unreachable = costmap.costs.size + 1.0
        nose_path = np.minimum(map_values(costmap, path_map, nose_x, nose_y, outside=math.inf), unreachable)
        nose_goal = np.minimum(map_values(costmap, front_map, nose_x, nose_y, outside=math.inf), unreachable)
        valid = (
            (path_end < UNREACHABLE)
            & (goal_end < UNREACHABLE)
            & np.isfinite(nose_path)
            & np.isfinite(nose_goal)
        )
        # keeping the nose on the path near the goal destabilises the approach: off within reach
        near = (
            math.hypot(goal[0] - pose[0], goal[1] - pose[1]) ** 2
            <= p.forward_point_distance**2 * p.cheat_factor
        )
        align = np.zeros(len(end)) if near else np.where(valid, nose_path, 0.0)
        res = costmap.resolution
        cost = p.path_distance_bias * res * (
            np.where(valid, path_end, 0.0) + align
        ) + p.goal_distance_bias * res * (np.where(valid, goal_end, 0.0) + np.where(valid, nose_goal, 0.0))
        return cost, valid
