"""base_local_planner's TrajectoryPlanner, vectorised: sample (v, w) within what the
accelerations allow in one control period, roll every sample out at once, drop trajectories
whose footprint meets an obstacle, and score the rest as TrajectoryPlanner does:

    cost = pdist_scale * path_dist + gdist_scale * goal_dist + occdist_scale * occ_cost

path_dist / goal_dist: the end point's distance (cells, or metres with meter_scoring) to the
nearest plan cell / to the local goal, from a 4-connected grid search through free cells
(MapGrid's role); occ_cost: the highest centre cost met along the trajectory.

In TrajectoryPlanner min_vel_theta is the most *negative* rotational velocity (default -1.0);
a positive value forbids turning right, as it does in ROS (move_base warns about it at load).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from . import costmap as cm
from .collision import GridChecker
from .footprint import FootprintCells

UNREACHABLE = 1e9


class LocalPlannerError(ValueError):
    """Parameters TrajectoryPlanner cannot work with."""


@dataclass
class TrajectoryParams:
    """TrajectoryPlannerROS's parameter names and defaults."""

    max_vel_x: float = 0.5
    min_vel_x: float = 0.1
    max_vel_theta: float = 1.0
    min_vel_theta: float = -1.0
    min_in_place_vel_theta: float = 0.4
    acc_lim_x: float = 2.5
    acc_lim_y: float = 2.5
    acc_lim_theta: float = 3.2
    escape_vel: float = -0.1
    escape_reset_dist: float = 0.10
    escape_reset_theta: float = 0.785
    holonomic_robot: bool = True
    sim_time: float = 1.0
    sim_granularity: float = 0.025
    angular_sim_granularity: float = 0.025
    vx_samples: int = 3
    vtheta_samples: int = 20
    pdist_scale: float = 0.6
    gdist_scale: float = 0.8
    occdist_scale: float = 0.01
    meter_scoring: bool = False
    heading_lookahead: float = 0.325
    heading_scoring: bool = False
    xy_goal_tolerance: float = 0.1
    yaw_goal_tolerance: float = 0.05
    latch_xy_goal_tolerance: bool = False
    prune_plan: bool = True
    dwa: bool = True
    # Not in TrajectoryPlanner: when the plan's direction heading_lookahead ahead differs from the
    # robot's heading by more than this (rad), rotate in place towards it before driving. For
    # skid-steer robots whose arcs barely turn (qbot); 0 keeps TrajectoryPlanner's behaviour.
    rotate_to_heading_threshold: float = 0.0
    global_frame_id: str = ""  # the local costmap's frame; accepted for compatibility

    def __post_init__(self) -> None:
        if self.min_vel_theta > self.max_vel_theta:
            raise LocalPlannerError(f"min_vel_theta ({self.min_vel_theta}) must be <= max_vel_theta "
                                    f"({self.max_vel_theta})")
        if self.max_vel_theta <= 0:
            raise LocalPlannerError(f"max_vel_theta must be > 0 (got {self.max_vel_theta})")
        if not (0 <= self.min_vel_x <= self.max_vel_x) or self.max_vel_x <= 0:
            raise LocalPlannerError(f"need 0 <= min_vel_x <= max_vel_x and max_vel_x > 0 "
                                    f"(got {self.min_vel_x}, {self.max_vel_x})")
        for name in ("acc_lim_x", "acc_lim_theta", "sim_time", "sim_granularity", "angular_sim_granularity",
                     "xy_goal_tolerance", "yaw_goal_tolerance"):
            if not getattr(self, name) > 0:
                raise LocalPlannerError(f"{name} must be > 0 (got {getattr(self, name)})")
        if self.vx_samples < 1 or self.vtheta_samples < 1:
            raise LocalPlannerError(f"vx_samples and vtheta_samples must be >= 1 "
                                    f"(got {self.vx_samples}, {self.vtheta_samples})")
        if self.min_in_place_vel_theta < 0 or self.min_in_place_vel_theta > self.max_vel_theta:
            raise LocalPlannerError(f"min_in_place_vel_theta must be in [0, max_vel_theta] "
                                    f"(got {self.min_in_place_vel_theta})")


@numba.njit(cache=True)
def _grid_search(free, seeds_r, seeds_c):
    """4-connected breadth-first distances (cells) from the seed cells through free cells."""
    h, w = free.shape
    dist = np.full((h, w), 1e9)
    queue = np.empty(h * w, np.int64)
    head, tail = 0, 0
    for k in range(seeds_r.shape[0]):
        r, c = seeds_r[k], seeds_c[k]
        if 0 <= r < h and 0 <= c < w and dist[r, c] > 0 and free[r, c]:
            dist[r, c] = 0.0
            queue[tail] = r * w + c
            tail += 1
    while head < tail:
        u = queue[head]
        head += 1
        ur, uc = u // w, u % w
        for dr, dc in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            vr, vc = ur + dr, uc + dc
            if 0 <= vr < h and 0 <= vc < w and free[vr, vc] and dist[vr, vc] > dist[ur, uc] + 1:
                dist[vr, vc] = dist[ur, uc] + 1
                queue[tail] = vr * w + vc
                tail += 1
    return dist


def distance_maps(costmap: cm.Costmap, plan_xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(path distance map, goal distance map, the local goal (x, y)) for the part of the plan
    inside the costmap; the local goal is the last plan point inside it."""
    free = costmap.costs < cm.INSCRIBED
    free |= costmap.costs == cm.NO_INFORMATION
    r, c = costmap.world_to_cell(plan_xy[:, 0], plan_xy[:, 1])
    inside = costmap.inside(r, c)
    if not inside.any():
        raise LocalPlannerError("no part of the global plan lies in the local costmap")
    last = np.where(inside)[0]
    # the plan up to where it first leaves the window
    leave = np.where(~inside[last[0]:])[0]
    end = last[0] + (leave[0] if len(leave) else len(inside) - last[0]) - 1
    rr, cc = r[last[0]:end + 1], c[last[0]:end + 1]
    path = _grid_search(free, rr.astype(np.int64), cc.astype(np.int64))
    goal = _grid_search(free, rr[-1:].astype(np.int64), cc[-1:].astype(np.int64))
    return path, goal, plan_xy[end]


def velocity_window(p: TrajectoryParams, vx: float, vth: float, period: float) -> tuple[float, float, float, float]:
    """(vx_min, vx_max, vth_min, vth_max) reachable within `period` under the acceleration limits."""
    vx_max = min(p.max_vel_x, vx + p.acc_lim_x * period)
    vx_min = max(p.min_vel_x, vx - p.acc_lim_x * period)
    vth_max = min(p.max_vel_theta, vth + p.acc_lim_theta * period)
    vth_min = max(p.min_vel_theta, vth - p.acc_lim_theta * period)
    return vx_min, max(vx_min, vx_max), vth_min, max(vth_min, vth_max)


def sample_velocities(p: TrajectoryParams, vx: float, vth: float, period: float, escaping: bool = False) -> np.ndarray:
    """(n, 2) candidate (v, w): the vx_samples x vtheta_samples grid of the window, plus rotations in
    place at least min_in_place_vel_theta fast (bounded by what acc_lim_theta allows), plus the
    escape velocity when backing out."""
    vx_min, vx_max, th_min, th_max = velocity_window(p, vx, vth, period)
    vxs = np.linspace(vx_min, vx_max, p.vx_samples)
    ths = np.linspace(th_min, th_max, p.vtheta_samples)
    grid = np.stack(np.meshgrid(vxs, ths, indexing="ij"), axis=-1).reshape(-1, 2)
    if escaping:
        grid = grid[:0]
    # in place: the window's rates raised to at least min_in_place_vel_theta (as TrajectoryPlanner
    # does; the rollout still ramps to them at acc_lim_theta), without the right turns that a
    # min_vel_theta of 0 forbids
    rot = np.unique(np.where(ths >= 0, np.maximum(ths, p.min_in_place_vel_theta),
                             np.minimum(ths, -p.min_in_place_vel_theta)))
    rot = rot[(rot != 0) & (rot >= p.min_vel_theta) & (rot <= p.max_vel_theta)]
    extra = [np.column_stack([np.zeros(len(rot)), rot])]
    if escaping or vx_min <= 0 <= vx_max:
        extra.append(np.array([[max(p.escape_vel, vx - p.acc_lim_x * period), 0.0]]))
    return np.vstack([grid] + extra)


@numba.njit(cache=True)
def _rollout(x0, y0, th0, v0, w0, samples, k, dt, acc_x, acc_th):
    n = samples.shape[0]
    out = np.empty((n, k, 3))
    for i in range(n):
        x, y, th = x0, y0, th0
        for j in range(k):
            t = dt * (j + 1)
            v = samples[i, 0] + min(max(v0 - samples[i, 0], -acc_x * t), acc_x * t)
            w = samples[i, 1] + min(max(w0 - samples[i, 1], -acc_th * t), acc_th * t)
            x += v * math.cos(th) * dt
            y += v * math.sin(th) * dt
            th += w * dt
            out[i, j, 0], out[i, j, 1], out[i, j, 2] = x, y, th
    return out


def rollout(pose, v0, samples: np.ndarray, p: TrajectoryParams) -> np.ndarray:
    """Poses (n, k, 3) of every sample over sim_time, velocities ramping from the current (v0)
    towards each sample at the acceleration limits (TrajectoryPlanner's computeNewVelocity);
    k from sim_granularity / angular_sim_granularity, the largest any sample needs. Compiled:
    the numpy version cost about 1 ms a cycle in temporaries."""
    reach = max(np.abs(samples[:, 0]).max() * p.sim_time / p.sim_granularity,
                np.abs(samples[:, 1]).max() * p.sim_time / p.angular_sim_granularity)
    k = max(2, int(math.ceil(reach)))
    return _rollout(float(pose[0]), float(pose[1]), float(pose[2]), float(v0[0]), float(v0[1]),
                    np.ascontiguousarray(samples, dtype=np.float64), k, p.sim_time / k, p.acc_lim_x, p.acc_lim_theta)


@dataclass
class Choice:
    cmd: tuple[float, float]          # (v, w) to command, (0, 0) when nothing is valid
    valid: bool
    cost: float
    trajectory: np.ndarray | None     # (k, 3) poses of the chosen sample


class TrajectoryPlanner:
    def __init__(self, params: TrajectoryParams, cells: FootprintCells) -> None:
        self.p = params
        self.cells = cells
        self._checker: GridChecker | None = None

    def checker(self, costmap: cm.Costmap) -> GridChecker:
        """The collision checker of this costmap snapshot, rebuilt only when the grid changed (the
        local costmap updates at 5 Hz, the controller runs at 20 Hz)."""
        c = self._checker
        if c is None or c.costmap.costs is not costmap.costs or not np.array_equal(c.costmap.origin, costmap.origin):
            snapshot = cm.Costmap(1, 1, costmap.resolution, *costmap.origin)
            snapshot.costs = costmap.costs
            self._checker = c = GridChecker(snapshot, self.cells, allow_unknown=True)
        return c

    def footprint_ok(self, costmap: cm.Costmap, poses: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Per trajectory (n, k, 3): (every pose free, highest centre cost along it)."""
        return self.checker(costmap).trajectories(poses)

    def choose(self, costmap: cm.Costmap, pose, velocity, path_map: np.ndarray, goal_map: np.ndarray,
               period: float, escaping: bool = False) -> Choice:
        p = self.p
        # dwa: the window one control period allows; trajectory rollout (dwa false): what sim_time
        # allows, the rollout ramping to each sample at the acceleration limits
        window = period if p.dwa else p.sim_time
        samples = sample_velocities(p, velocity[0], velocity[1], window, escaping)
        traj = rollout(pose, velocity, samples, p)
        ok, occ = self.footprint_ok(costmap, traj)
        if not ok.any() and not self.footprint_ok(costmap, np.array([[pose]], dtype=float))[0][0]:
            # the robot already touches an obstacle (it never follows a rollout exactly): judge the
            # trajectories from escape_reset_dist / escape_reset_theta away from where it is
            moved = (np.hypot(traj[..., 0] - pose[0], traj[..., 1] - pose[1]) >= p.escape_reset_dist) | \
                    (np.abs(traj[..., 2] - pose[2]) >= p.escape_reset_theta)
            first = np.argmax(moved, axis=1)
            tail_ok = np.array([self.footprint_ok(costmap, traj[i:i + 1, f:])[0][0] if moved[i, f] else False
                                for i, f in enumerate(first)])
            ok = tail_ok
        end = traj[:, -1, :]
        r, c = costmap.world_to_cell(end[:, 0], end[:, 1])
        inside = costmap.inside(r, c)
        rc, cc = np.clip(r, 0, costmap.shape[0] - 1), np.clip(c, 0, costmap.shape[1] - 1)
        pdist = np.where(inside, path_map[rc, cc], UNREACHABLE)
        gdist = np.where(inside, goal_map[rc, cc], UNREACHABLE)
        ok &= (pdist < UNREACHABLE) & (gdist < UNREACHABLE)
        scale = costmap.resolution if p.meter_scoring else 1.0
        cost = p.pdist_scale * pdist * scale + p.gdist_scale * gdist * scale + p.occdist_scale * occ
        if not escaping:
            # backing up is for escapes only (TrajectoryPlanner tries it when nothing else is valid)
            ok &= samples[:, 0] >= 0
        if not ok.any():
            return Choice((0.0, 0.0), False, math.inf, None)
        cost = np.where(ok, cost, np.inf)
        best = int(np.argmin(cost))
        # command the first period of the ramp towards the chosen sample, so that every command
        # is within the acceleration limits of the previous velocity, in-place rotations raised
        # to min_in_place_vel_theta included
        v = velocity[0] + np.clip(samples[best, 0] - velocity[0], -p.acc_lim_x * period, p.acc_lim_x * period)
        w = velocity[1] + np.clip(samples[best, 1] - velocity[1], -p.acc_lim_theta * period, p.acc_lim_theta * period)
        return Choice((float(v), float(w)), True, float(cost[best]), traj[best])

    def rotate_towards(self, yaw: float, target_yaw: float, w0: float, period: float) -> float:
        """An in-place rotation command towards target_yaw: fast enough to turn
        (min_in_place_vel_theta), slow enough to stop on it (sqrt(2 a |error|)), within the
        acceleration window."""
        p = self.p
        err = math.remainder(target_yaw - yaw, 2 * math.pi)
        speed = min(p.max_vel_theta, math.sqrt(2 * p.acc_lim_theta * abs(err)))
        speed = max(speed, p.min_in_place_vel_theta)
        w = math.copysign(speed, err)
        w = min(max(w, w0 - p.acc_lim_theta * period), w0 + p.acc_lim_theta * period)
        return min(max(w, p.min_vel_theta), p.max_vel_theta)


@dataclass
class ControlState:
    """What the controller remembers between cycles for one goal."""

    xy_latched: bool = False
    aligning: bool = False   # rotating in place towards the plan (rotate_to_heading_threshold)


@dataclass
class ControlOutput:
    cmd: tuple[float, float]
    valid: bool            # False: no collision-free command (move_base counts controller patience)
    goal_reached: bool
    trajectory: np.ndarray | None = None


class LocalController:
    """TrajectoryPlannerROS.computeVelocityCommands + isGoalReached: the goal tolerances (with the
    xy latch), the final rotation to the goal's yaw, and otherwise the sampled trajectories."""

    def __init__(self, params: TrajectoryParams, cells: FootprintCells) -> None:
        self.p = params
        self.planner = TrajectoryPlanner(params, cells)
        self.state = ControlState()

    def reset(self) -> None:
        self.state = ControlState()

    def compute(self, costmap: cm.Costmap, pose, velocity, plan: np.ndarray, period: float,
                escaping: bool = False) -> ControlOutput:
        """pose (x, y, yaw) and plan (k, 3) in the costmap's frame; velocity (v, w) measured."""
        p = self.p
        gx, gy, gyaw = plan[-1]
        dist = math.hypot(gx - pose[0], gy - pose[1])
        if dist <= p.xy_goal_tolerance and p.latch_xy_goal_tolerance:
            self.state.xy_latched = True
        if dist <= p.xy_goal_tolerance or self.state.xy_latched:
            err = abs(math.remainder(gyaw - pose[2], 2 * math.pi))
            if err <= p.yaw_goal_tolerance:
                return ControlOutput((0.0, 0.0), True, True)
            w = self.planner.rotate_towards(pose[2], gyaw, velocity[1], period)
            # decelerate any forward motion first, then rotate
            v = max(0.0, velocity[0] - p.acc_lim_x * period)
            traj = self._turn(pose, gyaw)
            ok, _ = self.planner.footprint_ok(costmap, traj)
            return ControlOutput((v, w) if ok[0] else (0.0, 0.0), bool(ok[0]), False, traj[0])
        if p.rotate_to_heading_threshold > 0 and not escaping:
            out = self._align(costmap, pose, velocity, plan, period)
            if out is not None:
                return out
        path_map, goal_map, _ = distance_maps(costmap, plan[:, :2])
        choice = self.planner.choose(costmap, pose, velocity, path_map, goal_map, period, escaping)
        return ControlOutput(choice.cmd, choice.valid, False, choice.trajectory)

    def _align(self, costmap: cm.Costmap, pose, velocity, plan: np.ndarray, period: float) -> ControlOutput | None:
        """Rotate in place towards the plan's direction when it is off by more than
        rotate_to_heading_threshold (None: aligned, or the rotation would collide)."""
        p = self.p
        d = np.hypot(plan[:, 0] - pose[0], plan[:, 1] - pose[1])
        nearest = int(np.argmin(d))
        ahead = nearest + np.nonzero(d[nearest:] >= max(p.heading_lookahead, costmap.resolution))[0]
        if not len(ahead):
            return None
        tx, ty = plan[ahead[0], :2]
        target = math.atan2(ty - pose[1], tx - pose[0])
        err = abs(math.remainder(target - pose[2], 2 * math.pi))
        # hysteresis: start beyond the threshold, stop within half of it
        limit = p.rotate_to_heading_threshold * (0.5 if self.state.aligning else 1.0)
        self.state.aligning = err > limit
        if not self.state.aligning:
            return None
        w = self.planner.rotate_towards(pose[2], target, velocity[1], period)
        v = max(0.0, velocity[0] - p.acc_lim_x * period)
        traj = self._turn(pose, target)
        ok, _ = self.planner.footprint_ok(costmap, traj)
        return ControlOutput((v, w), True, False, traj[0]) if ok[0] else None

    def _turn(self, pose, target_yaw: float) -> np.ndarray:
        """(1, k, 3) poses of an in-place turn from the robot's heading to target_yaw (what must be
        free to turn there; a 1 s rollout at the turn rate would test angles beyond the target)."""
        err = math.remainder(target_yaw - pose[2], 2 * math.pi)
        k = max(2, int(math.ceil(abs(err) / self.p.angular_sim_granularity)) + 1)
        yaw = pose[2] + np.linspace(0.0, err, k)
        return np.column_stack([np.full(k, pose[0]), np.full(k, pose[1]), yaw])[None]
