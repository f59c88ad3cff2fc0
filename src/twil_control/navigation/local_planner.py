"""base_local_planner's TrajectoryPlanner, vectorised, and what dwa_local_planner's DWAPlanner
(navigation/dwa_planner.py) shares with it: sample (v, w) within what the accelerations allow,
roll every sample out at once, drop trajectories whose footprint meets an obstacle, and score
the rest, ties going to the first sample in TrajectoryPlanner's order. The cost, the order and
min_vel_theta's sign: docs/navigation.md, "How the pieces decide".
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numba
import numpy as np

from twil_control.errors import TwilControlError

from . import costmap as cm
from .collision import GridChecker
from .footprint import FootprintCells

UNREACHABLE = 1e9
NOT_HOLONOMIC = "the simulated bases are not holonomic: no lateral (y) velocity is ever sampled"
NO_CLOUDS = (
    "no point clouds are published (the chosen trajectory is on local_plan in the planner's namespace)"
)


class LocalPlannerError(TwilControlError, ValueError):
    """Parameters a local planner cannot work with."""


#: footprint_check (a parameter of this package, not of the ROS planners): "outline" tests a pose
#: as upstream's CostmapModel::footprintCost, only the cells on the footprint's edges, so the
#: centre may come within the inscribed radius of an obstacle and an obstacle wholly inside the
#: footprint goes unseen; "filled" tests every cell under the polygon and the inscribed disc
#: (the centre's inflated cost below INSCRIBED), which is stricter by up to a cell to each side
FOOTPRINT_CHECKS = ("outline", "filled")


def check_footprint_check(value: str) -> None:
    if value not in FOOTPRINT_CHECKS:
        raise LocalPlannerError(
            f"footprint_check must be one of {', '.join(FOOTPRINT_CHECKS)} (got {value!r})"
        )


@dataclass
class TrajectoryParams:
    """TrajectoryPlannerROS's parameter names and defaults."""

    ros_package: ClassVar[str] = "base_local_planner"
    no_effect: ClassVar[dict] = {
        "holonomic_robot": (False, NOT_HOLONOMIC),
        "y_vels": NOT_HOLONOMIC,
        "heading_scoring": (False, "trajectories are scored by their end point's distance to the path"),
        "heading_scoring_timestep": "heading_scoring is not simulated here",
        "simple_attractor": (False, "the path and goal distances are the grid's, as without it"),
        "publish_cost_grid_pc": (False, NO_CLOUDS),
    }

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
    y_vels: list[float] | None = None
    sim_time: float = 1.0
    sim_granularity: float = 0.025
    angular_sim_granularity: float = 0.025
    vx_samples: int = 3
    vtheta_samples: int = 20
    # the control period the acceleration window spans (dwa) is 1 / this; unset: move_base's
    controller_frequency: float | None = None
    pdist_scale: float = 0.6
    gdist_scale: float = 0.8
    occdist_scale: float = 0.01
    meter_scoring: bool = False
    heading_lookahead: float = 0.325
    heading_scoring: bool = False
    heading_scoring_timestep: float = 0.8
    simple_attractor: bool = False
    xy_goal_tolerance: float = 0.1
    yaw_goal_tolerance: float = 0.05
    latch_xy_goal_tolerance: bool = False
    prune_plan: bool = True
    dwa: bool = True
    oscillation_reset_dist: float = 0.05
    publish_cost_grid_pc: bool = False
    # Not in TrajectoryPlanner: when the plan's direction heading_lookahead ahead differs from the
    # robot's heading by more than this (rad), rotate in place towards it before driving. For
    # skid-steer robots whose arcs barely turn (qbot); 0 keeps TrajectoryPlanner's behaviour.
    rotate_to_heading_threshold: float = 0.0
    # Not in TrajectoryPlanner: how a pose's footprint is tested (FOOTPRINT_CHECKS)
    footprint_check: str = "outline"
    global_frame_id: str = ""  # the local costmap's frame; accepted for compatibility

    def __post_init__(self) -> None:
        if self.min_vel_theta > self.max_vel_theta:
            raise LocalPlannerError(
                f"min_vel_theta ({self.min_vel_theta}) must be <= max_vel_theta ({self.max_vel_theta})"
            )
        if self.max_vel_theta <= 0:
            raise LocalPlannerError(f"max_vel_theta must be > 0 (got {self.max_vel_theta})")
        if not (0 <= self.min_vel_x <= self.max_vel_x) or self.max_vel_x <= 0:
            raise LocalPlannerError(
                f"need 0 <= min_vel_x <= max_vel_x and max_vel_x > 0 (got {self.min_vel_x}, {self.max_vel_x})"
            )
        for name in (
            "acc_lim_x",
            "acc_lim_theta",
            "sim_time",
            "sim_granularity",
            "angular_sim_granularity",
            "xy_goal_tolerance",
            "yaw_goal_tolerance",
        ):
            if not getattr(self, name) > 0:
                raise LocalPlannerError(f"{name} must be > 0 (got {getattr(self, name)})")
        if self.vx_samples < 1 or self.vtheta_samples < 1:
            raise LocalPlannerError(
                f"vx_samples and vtheta_samples must be >= 1 (got {self.vx_samples}, {self.vtheta_samples})"
            )
        if self.min_in_place_vel_theta < 0 or self.min_in_place_vel_theta > self.max_vel_theta:
            raise LocalPlannerError(
                f"min_in_place_vel_theta must be in [0, max_vel_theta] (got {self.min_in_place_vel_theta})"
            )
        if self.controller_frequency is not None and not self.controller_frequency > 0:
            raise LocalPlannerError(f"controller_frequency must be > 0 Hz (got {self.controller_frequency})")
        check_footprint_check(self.footprint_check)

    @property
    def turn_limits(self) -> tuple[float, float]:
        """The rotational velocities allowed, (most negative, most positive)."""
        return self.min_vel_theta, self.max_vel_theta

    @property
    def min_turn_in_place(self) -> float:
        return self.min_in_place_vel_theta


@numba.njit(cache=True)
def _grid_search(free, seeds_r, seeds_c):
    """4-connected breadth-first distances (cells) from the start cells through free cells (on the
    flat grid: the first visit of a cell is its distance). A start cell is 0 whatever its cost
    (MapGrid seeds the plan's cells so), only its neighbours must be free."""
    h, w = free.shape
    n = h * w
    flat = free.ravel()
    dist = np.full(n, 1e9)
    queue = np.empty(n, np.int64)
    head, tail = 0, 0
    for k in range(seeds_r.shape[0]):
        r, c = seeds_r[k], seeds_c[k]
        if 0 <= r < h and 0 <= c < w:
            i = r * w + c
            if dist[i] > 0:
                dist[i] = 0.0
                queue[tail] = i
                tail += 1
    while head < tail:
        u = queue[head]
        head += 1
        d = dist[u] + 1.0
        col = u % w
        for v, inside in ((u + w, u < n - w), (u - w, u >= w), (u + 1, col < w - 1), (u - 1, col > 0)):
            if inside and flat[v] and dist[v] > d:
                dist[v] = d
                queue[tail] = v
                tail += 1
    return dist.reshape(h, w)


def free_cells(costmap: cm.Costmap) -> np.ndarray:
    """Cells the grid searches pass through: below INSCRIBED. Unknown cells are obstacles, as
    MapGrid's updatePathCell has them (LETHAL, INSCRIBED and NO_INFORMATION stop the search)."""
    return costmap.costs < cm.INSCRIBED


def distances_from(costmap: cm.Costmap, x, y, free: np.ndarray | None = None) -> np.ndarray:
    """4-connected grid distances (cells) from the cells of points (x, y) through free cells;
    UNREACHABLE where no free path leads (points outside the grid start nothing)."""
    r, c = costmap.world_to_cell(np.atleast_1d(x), np.atleast_1d(y))
    return _grid_search(free_cells(costmap) if free is None else free, r.astype(np.int64), c.astype(np.int64))


def densify(plan_xy: np.ndarray, step: float) -> np.ndarray:
    """The plan with points added evenly, at most `step` apart, along every segment longer than a
    cell's diagonal (MapGrid's adjustPlanResolution, for sparse plans such as OMPL's). Unlike
    it, a diagonal step between neighbouring cells gets no midpoint: on the grid planner's
    cell-centre paths that point lies on a cell corner, its cell a matter of rounding."""
    if len(plan_xy) < 2:
        return plan_xy
    seg = np.hypot(*np.diff(plan_xy, axis=0).T)
    parts = np.where(seg > step * math.sqrt(2) * (1 + 1e-9), np.ceil(seg / step), 1).astype(np.int64)
    if (parts == 1).all():
        return plan_xy
    s = np.concatenate([np.arange(k) / k for k in parts] + [[0.0]])
    start = np.concatenate([np.repeat(np.arange(len(seg)), parts), [len(seg) - 1]])
    nxt = np.minimum(start + 1, len(plan_xy) - 1)
    s[-1] = 1.0
    return plan_xy[start] + s[:, None] * (plan_xy[nxt] - plan_xy[start])


def distance_maps(costmap: cm.Costmap, plan_xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(path distance map, goal distance map, the local goal (x, y)), as MapGrid's setTargetCells
    and setLocalGoal make them: the plan (filled in, densify) from its first point on a
    known cell of the costmap up to where it first leaves the costmap or meets an unknown cell;
    the local goal is that stretch's last point."""
    plan_xy = densify(plan_xy, costmap.resolution)
    r, c = costmap.world_to_cell(plan_xy[:, 0], plan_xy[:, 1])
    usable = costmap.inside(r, c)
    rc, cc = np.clip(r, 0, costmap.shape[0] - 1), np.clip(c, 0, costmap.shape[1] - 1)
    usable &= costmap.costs[rc, cc] != cm.NO_INFORMATION
    if not usable.any():
        raise LocalPlannerError("no part of the global plan lies on known cells of the local costmap")
    first = int(np.argmax(usable))
    stop = np.where(~usable[first:])[0]
    end = first + (int(stop[0]) if len(stop) else len(usable) - first) - 1
    free = free_cells(costmap)
    path = _grid_search(free, r[first : end + 1], c[first : end + 1])
    goal = _grid_search(free, r[end : end + 1], c[end : end + 1])
    return path, goal, plan_xy[end]


@numba.njit(cache=True)
def _reachable_along(traj, path_map, goal_map, ox, oy, res, limit):
    """Per trajectory (n, k, 3): every pose's cell on the grid with path and goal distances below
    `limit`."""
    h, w = path_map.shape
    n, k = traj.shape[0], traj.shape[1]
    ok = np.ones(n, np.bool_)
    for i in range(n):
        for j in range(k):
            col = int(math.floor((traj[i, j, 0] - ox) / res))
            row = int(math.floor((traj[i, j, 1] - oy) / res))
            if (
                not (0 <= row < h and 0 <= col < w)
                or path_map[row, col] >= limit
                or goal_map[row, col] >= limit
            ):
                ok[i] = False
                break
    return ok


def reachable_along(costmap: cm.Costmap, traj: np.ndarray, path_map, goal_map) -> np.ndarray:
    """Per trajectory (n, k, 3): no pose on a cell the path or the goal cannot be reached from
    (an obstacle, unknown, cut off), which makes a trajectory illegal in TrajectoryPlanner's
    generateTrajectory and in DWAPlanner's path and goal critics, at every point, not only at
    the end."""
    return _reachable_along(
        np.ascontiguousarray(traj, dtype=np.float64),
        path_map,
        goal_map,
        float(costmap.origin[0]),
        float(costmap.origin[1]),
        costmap.resolution,
        UNREACHABLE,
    )


def map_values(
    costmap: cm.Costmap, grid: np.ndarray, x: np.ndarray, y: np.ndarray, outside: float = UNREACHABLE
) -> np.ndarray:
    """grid's values at points (x, y); `outside` for points off the grid."""
    r, c = costmap.world_to_cell(x, y)
    inside = costmap.inside(r, c)
    rc, cc = np.clip(r, 0, costmap.shape[0] - 1), np.clip(c, 0, costmap.shape[1] - 1)
    return np.where(inside, grid[rc, cc], outside)


def velocity_window(
    p: TrajectoryParams, vx: float, vth: float, period: float, vx_cap: float = math.inf
) -> tuple[float, float, float, float]:
    """(vx_min, vx_max, vth_min, vth_max) reachable within `period` under the acceleration limits,
    max_vel_x lowered to vx_cap, as createTrajectories has them: vx_max never below min_vel_x,
    but it may lie below vx_min (decelerating towards the goal: the samples then run downwards)."""
    vx_max = max(min(p.max_vel_x, vx_cap, vx + p.acc_lim_x * period), p.min_vel_x)
    vx_min = max(p.min_vel_x, vx - p.acc_lim_x * period)
    vth_max = min(p.max_vel_theta, vth + p.acc_lim_theta * period)
    vth_min = max(p.min_vel_theta, vth - p.acc_lim_theta * period)
    return vx_min, vx_max, vth_min, max(vth_min, vth_max)


def sample_velocities(
    p: TrajectoryParams,
    vx: float,
    vth: float,
    period: float,
    escaping: bool = False,
    goal_dist: float = math.inf,
) -> np.ndarray:
    """(n, 2) candidate (v, w) in TrajectoryPlanner's createTrajectories order: for each of
    vx_samples speeds of the window (slowest first) the straight line, then vtheta_samples - 1
    rates from the window's most negative, dvtheta apart (the window's top rate is not among
    them, as upstream); then the rotations in place: the window's vtheta_samples rates, those
    within dvtheta of zero left out, the rest raised to at least min_in_place_vel_theta (alone
    when escaping). max_vel_x is capped at goal_dist / sim_time, the final goal's distance, as
    upstream slows down towards it. Backing out is not among them (TrajectoryPlanner.choose)."""
    vx_min, vx_max, th_min, th_max = velocity_window(p, vx, vth, period, goal_dist / p.sim_time)
    vxs = np.linspace(vx_min, vx_max, p.vx_samples)
    ths = np.linspace(th_min, th_max, p.vtheta_samples)
    dth = (th_max - th_min) / (p.vtheta_samples - 1) if p.vtheta_samples > 1 else 0.0
    per_vx = np.concatenate([[0.0], ths[:-1] if p.vtheta_samples > 1 else ths])
    grid = np.column_stack([np.repeat(vxs, len(per_vx)), np.tile(per_vx, len(vxs))])
    if escaping:
        grid = grid[:0]
    # in place: raised to at least min_in_place_vel_theta (the rollout still ramps to them at
    # acc_lim_theta), without the right turns that a min_vel_theta of 0 forbids
    turning = ths[np.abs(ths) > dth]
    rot = np.unique(
        np.where(
            turning >= 0,
            np.maximum(turning, p.min_in_place_vel_theta),
            np.minimum(turning, -p.min_in_place_vel_theta),
        )
    )
    rot = rot[(rot != 0) & (rot >= p.min_vel_theta) & (rot <= p.max_vel_theta)]
    return np.vstack([grid, np.column_stack([np.zeros(len(rot)), rot])])


@numba.njit(cache=True)
def _rollout(x0, y0, th0, v0, w0, samples, k, dt, acc_x, acc_th):
    n = samples.shape[0]
    out = np.empty((n, k, 3))
    for i in range(n):
        x, y, th = x0, y0, th0
        for j in range(k):
            t = dt * (j + 1)
            # from the current velocity towards the sample, at most acc * t away (inf: the sample)
            v = v0 + min(max(samples[i, 0] - v0, -acc_x * t), acc_x * t)
            w = w0 + min(max(samples[i, 1] - w0, -acc_th * t), acc_th * t)
            x += v * math.cos(th) * dt
            y += v * math.sin(th) * dt
            th += w * dt
            out[i, j, 0], out[i, j, 1], out[i, j, 2] = x, y, th
    return out


def rollout(
    pose,
    v0,
    samples: np.ndarray,
    sim_time: float,
    sim_granularity: float,
    angular_sim_granularity: float,
    acc_x: float = math.inf,
    acc_th: float = math.inf,
) -> np.ndarray:
    """Poses (n, k, 3) of every sample over sim_time, the velocity ramping from the current one (v0)
    towards each sample at the acceleration limits (TrajectoryPlanner's computeNewVelocity), or
    at the sample throughout with infinite limits (DWAPlanner's use_dwa); k from sim_granularity
    / angular_sim_granularity, the largest any sample needs. Compiled: the numpy version spent
    most of a cycle on temporaries."""
    reach = max(
        np.abs(samples[:, 0]).max() * sim_time / sim_granularity,
        np.abs(samples[:, 1]).max() * sim_time / angular_sim_granularity,
    )
    k = max(2, int(math.ceil(reach)))
    return _rollout(
        float(pose[0]),
        float(pose[1]),
        float(pose[2]),
        float(v0[0]),
        float(v0[1]),
        np.ascontiguousarray(samples, dtype=np.float64),
        k,
        sim_time / k,
        acc_x,
        acc_th,
    )


@dataclass
class Choice:
    cmd: tuple[float, float]  # (v, w) to command, (0, 0) when nothing is valid
    valid: bool
    cost: float
    trajectory: np.ndarray | None  # (k, 3) poses of the chosen sample


class Oscillation:
    """The oscillation flags of both ROS planners: once the robot reverses its direction of
    rotation while translating at most `slow` m/s (and, when `forward` is tracked, its direction
    of travel), only the new direction is allowed until it has moved `reset_dist` or turned
    `reset_angle` since. DWAPlanner's critic refuses any trajectory in the other direction;
    TrajectoryPlanner, which judges forward motion apart, only rotations in place
    (``in_place_only``)."""

    def __init__(
        self,
        reset_dist: float,
        reset_angle: float = math.inf,
        slow: float = 0.0,
        forward: bool = True,
        in_place_only: bool = False,
    ) -> None:
        self.reset_dist, self.reset_angle, self.slow = reset_dist, reset_angle, slow
        self.axes = ("forward", "turn") if forward else ("turn",)
        self.in_place_only = in_place_only
        self.reset()

    def reset(self) -> None:
        self.last: dict[str, int] = {}  # axis -> sign of the last command
        self.only: dict[str, int] = {}  # axis -> the one sign allowed
        self.since: tuple | None = None

    def allowed(self, samples: np.ndarray) -> np.ndarray:
        ok = np.ones(len(samples), bool)
        for axis, sign in self.only.items():
            refused = np.sign(samples[:, 0 if axis == "forward" else 1]) == -sign
            if self.in_place_only:
                refused &= samples[:, 0] == 0
            ok &= ~refused
        return ok

    def update(self, pose, cmd: tuple[float, float]) -> None:
        """Record the chosen command at `pose`; lift the restrictions once the robot moved enough."""
        v, w = cmd
        values = {"forward": v, "turn": w if abs(v) <= self.slow else 0.0}
        flipped = False
        for axis in self.axes:
            sign = int(np.sign(values[axis]))
            if sign == 0:
                continue
            if self.last.get(axis) == -sign:
                self.only[axis] = sign
                flipped = True
            self.last[axis] = sign
        if flipped:
            self.since = tuple(pose)
        elif self.only and self.since is not None:
            moved = math.hypot(pose[0] - self.since[0], pose[1] - self.since[1])
            turned = abs(math.remainder(pose[2] - self.since[2], 2 * math.pi))
            if moved > self.reset_dist or turned > self.reset_angle:
                self.reset()


class InPlaceFlags:
    """TrajectoryPlanner's rotating_left/right and stuck_left/right: a second in-place rotation
    to one side in a row marks that side stuck, after which rotations to the other side are
    refused (upstream's pairing: stuck_right refuses left turns, stuck_left right turns), so the
    robot keeps turning one way; all flags drop once it is oscillation_reset_dist from where it
    last rotated."""

    def __init__(self, reset_dist: float) -> None:
        self.reset_dist = reset_dist
        self.reset()

    def reset(self) -> None:
        self.rotating_left = self.rotating_right = False
        self.stuck_left = self.stuck_right = False
        self.since: tuple | None = None

    def refuses(self, w: float) -> bool:
        return (w < 0 and self.stuck_left) or (w > 0 and self.stuck_right)

    def chose(self, pose, v: float, w: float) -> None:
        """Record the command chosen at `pose`; (0, 0) when no forward or in-place sample was
        chosen (backing out, or nothing valid): then only the reset by distance applies."""
        if not v > 0 and w != 0:
            if w < 0:
                self.stuck_right |= self.rotating_right
                self.rotating_right = True
            else:
                self.stuck_left |= self.rotating_left
                self.rotating_left = True
            self.since = tuple(pose)
        if self.since is not None:
            if math.hypot(pose[0] - self.since[0], pose[1] - self.since[1]) > self.reset_dist:
                self.reset()


class SamplingPlanner:
    """What TrajectoryPlanner and DWAPlanner share: the collision checker of the local costmap,
    and the in-place rotation towards a heading. ``sim_period`` is the control period the
    acceleration window spans (1 / controller_frequency)."""

    def __init__(self, params, cells: FootprintCells, sim_period: float) -> None:
        self.p = params
        self.cells = cells
        self.sim_period = sim_period
        self._checker: GridChecker | None = None

    #: rotate in place towards the plan beyond this heading error (rad); 0: never
    align_threshold = 0.0

    def new_plan(self) -> None:
        """A new global plan arrived (move_base's setPlan)."""

    def reset(self) -> None:
        """A new goal: forget what the planner kept of the last one."""
        self.new_plan()

    def checker(self, costmap: cm.Costmap) -> GridChecker:
        """The collision checker of this costmap snapshot, rebuilt only when the grid changed (the
        local costmap updates at 5 Hz, the controller runs at 20 Hz)."""
        c = self._checker
        if (
            c is None
            or c.costmap.costs is not costmap.costs
            or not np.array_equal(c.costmap.origin, costmap.origin)
        ):
            snapshot = cm.Costmap(1, 1, costmap.resolution, *costmap.origin)
            snapshot.costs = costmap.costs
            # unknown under the footprint makes a pose illegal (CostmapModel's footprintCost < 0)
            self._checker = c = GridChecker(snapshot, self.cells, allow_unknown=False)
        return c

    def footprint_ok(self, costmap: cm.Costmap, poses: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Per trajectory (n, k, 3): (every pose free, highest centre or outline cost along it),
        as the footprint_check parameter tests a pose."""
        if self.p.footprint_check == "outline":
            return self.checker(costmap).trajectories_outline(poses)
        return self.checker(costmap).trajectories(poses)

    #: whether the robot's own pose is judged with every trajectory (upstream's rollouts start there)
    judges_own_pose = True

    def legal(
        self, costmap: cm.Costmap, pose, traj: np.ndarray, path_map, goal_map
    ) -> tuple[np.ndarray, np.ndarray]:
        """Per trajectory (n, k, 3) from `pose`: (legal, highest cost met along it). Legal as
        upstream's rollouts judge every point: the footprint clear as footprint_check tests it (on
        the grid) and the path and the goal reachable from the point's cell; with
        judges_own_pose, from the robot's own pose on, so that a robot whose own footprint is not
        clear has no legal trajectory."""
        clear, occ = self.footprint_ok(costmap, traj)
        ok = clear & reachable_along(costmap, traj, path_map, goal_map)
        if self.judges_own_pose:
            here = np.asarray(pose, dtype=float)[None, None]
            if not (
                self.footprint_ok(costmap, here)[0][0]
                and reachable_along(costmap, here, path_map, goal_map)[0]
            ):
                ok[:] = False
        return ok, occ

    def rotate_towards(self, yaw: float, target_yaw: float, w0: float, period: float) -> float:
        """An in-place rotation command towards target_yaw: fast enough to turn (the planner's
        minimum in-place rate), slow enough to stop on it (sqrt(2 a |error|)), within the
        acceleration window and the rotational limits."""
        p = self.p
        lo, hi = p.turn_limits
        err = math.remainder(target_yaw - yaw, 2 * math.pi)
        speed = min(max(abs(lo), hi), math.sqrt(2 * p.acc_lim_theta * abs(err)))
        speed = max(speed, p.min_turn_in_place)
        w = math.copysign(speed, err)
        w = min(max(w, w0 - p.acc_lim_theta * period), w0 + p.acc_lim_theta * period)
        return min(max(w, lo), hi)


class TrajectoryPlanner(SamplingPlanner):
    def __init__(self, params: TrajectoryParams, cells: FootprintCells, sim_period: float) -> None:
        super().__init__(params, cells, sim_period)
        # reset by distance only (not by a new plan, unlike DWAPlanner's oscillation flags)
        self.flags = InPlaceFlags(params.oscillation_reset_dist)
        # TrajectoryPlanner's escaping_: the pose where the robot started backing out, or None
        self.escape_from: tuple | None = None

    @property
    def align_threshold(self) -> float:
        return self.p.rotate_to_heading_threshold

    def reset(self) -> None:
        self.new_plan()
        self.escape_from = None
        self.flags.reset()

    def _end_escape(self, pose) -> None:
        """Leave the escape once the robot is escape_reset_dist from where it began or has turned
        escape_reset_theta (TrajectoryPlanner checks this at the end of every cycle, so the next
        cycle samples forward motion again)."""
        e = self.escape_from
        if e is not None and (
            math.hypot(pose[0] - e[0], pose[1] - e[1]) > self.p.escape_reset_dist
            or abs(math.remainder(pose[2] - e[2], 2 * math.pi)) > self.p.escape_reset_theta
        ):
            self.escape_from = None

    def choose(
        self, costmap: cm.Costmap, pose, velocity, plan_xy: np.ndarray, period: float, escaping: bool = False
    ) -> Choice:
        """TrajectoryPlanner's createTrajectories: the best legal forward sample (not while
        escaping); then the rotations in place in their order, each legal one at most as costly
        as the best so far taken when the point heading_lookahead ahead of its end is nearer the
        local goal (goal distance map) than the last taken, unless the stuck flags refuse its
        side. When none is legal, the robot backs out at escape_vel (negative; 0 disables it):
        after that only rotations and backing out are tried until it has moved
        escape_reset_dist or turned escape_reset_theta."""
        p = self.p
        escaping = escaping or self.escape_from is not None
        path_map, goal_map, _ = distance_maps(costmap, plan_xy)
        # dwa: the window one control period allows; trajectory rollout (dwa false): what sim_time
        # allows, the rollout ramping to each sample at the acceleration limits
        window = self.sim_period if p.dwa else p.sim_time
        goal_dist = math.hypot(plan_xy[-1, 0] - pose[0], plan_xy[-1, 1] - pose[1])
        samples = sample_velocities(p, velocity[0], velocity[1], window, escaping, goal_dist)
        if p.escape_vel < 0:
            # backing out is scored apart, and taken only when nothing else is legal
            samples = np.vstack([samples, [[p.escape_vel, 0.0]]])
        traj = rollout(
            pose,
            velocity,
            samples,
            p.sim_time,
            p.sim_granularity,
            p.angular_sim_granularity,
            p.acc_lim_x,
            p.acc_lim_theta,
        )
        ok, occ = self.legal(costmap, pose, traj, path_map, goal_map)
        end = traj[:, -1, :]
        pdist = map_values(costmap, path_map, end[:, 0], end[:, 1])
        gdist = map_values(costmap, goal_map, end[:, 0], end[:, 1])
        # meter_scoring multiplies all three weights by the resolution (TrajectoryPlannerROS's
        # initialize), the occupancy weight too
        scale = costmap.resolution if p.meter_scoring else 1.0
        cost = (p.pdist_scale * pdist + p.gdist_scale * gdist + p.occdist_scale * occ) * scale
        best = self._best(costmap, goal_map, samples, traj, ok, cost)
        if best is None:
            self.flags.chose(pose, 0.0, 0.0)
            back = self._back_out(costmap, pose, samples, traj, ok, path_map, goal_map)
            self._end_escape(pose)
            if back is None:
                return Choice((0.0, 0.0), False, math.inf, None)
            best, cost_best = back, float(cost[back]) if ok[back] else 1.0
        else:
            self.flags.chose(pose, float(samples[best, 0]), float(samples[best, 1]))
            self._end_escape(pose)
            cost_best = float(cost[best])
        # command the first period of the ramp towards the chosen sample, so that every command
        # is within the acceleration limits of the previous velocity, in-place rotations raised
        # to min_in_place_vel_theta included
        v = velocity[0] + np.clip(samples[best, 0] - velocity[0], -p.acc_lim_x * period, p.acc_lim_x * period)
        w = velocity[1] + np.clip(
            samples[best, 1] - velocity[1], -p.acc_lim_theta * period, p.acc_lim_theta * period
        )
        return Choice((float(v), float(w)), True, cost_best, traj[best])

    def _back_out(self, costmap, pose, samples, traj, ok, path_map, goal_map) -> int | None:
        """The backing-out sample's index when TrajectoryPlanner would drive it, or None.
        createTrajectories' last resort, as upstream: the escape_vel trajectory is taken whatever
        its footprint meets (an illegal one scored 1.0), but not when, walking it from the
        current pose, a point the path or the goal cannot be reached from comes before any
        footprint collision (generateTrajectory's -2, against -1 for a collision). Taking it
        starts the escape."""
        if not self.p.escape_vel < 0:
            return None
        k = len(samples) - 1
        if not ok[k]:
            points = np.vstack([np.asarray(pose, dtype=float)[None], traj[k]])
            blocked = ~self.footprint_ok(costmap, points[:, None])[0]
            cut_off = ~reachable_along(costmap, points[:, None], path_map, goal_map)
            first_blocked = int(np.argmax(blocked)) if blocked.any() else len(points)
            if cut_off.any() and int(np.argmax(cut_off)) < first_blocked:
                return None
        if self.escape_from is None:
            self.escape_from = tuple(float(v) for v in pose)
        return k

    def _best(self, costmap, goal_map, samples, traj, ok, cost) -> int | None:
        """The index createTrajectories returns before backing out (None: nothing valid)."""
        forward = np.nonzero(ok & (samples[:, 0] > 0))[0]
        best = int(forward[np.argmin(cost[forward])]) if len(forward) else None  # first of equals
        turns = np.nonzero(ok & (samples[:, 0] == 0) & (samples[:, 1] != 0))[0]
        if not len(turns):
            return best
        end = traj[turns, -1, :]
        ax = end[:, 0] + self.p.heading_lookahead * np.cos(end[:, 2])
        ay = end[:, 1] + self.p.heading_lookahead * np.sin(end[:, 2])
        r, c = costmap.world_to_cell(ax, ay)
        inside = costmap.inside(r, c)
        ahead = map_values(costmap, goal_map, ax, ay)
        heading_dist = math.inf
        for i, k in enumerate(turns):
            if best is not None and cost[k] > cost[best]:
                continue
            if inside[i] and ahead[i] < heading_dist and not self.flags.refuses(samples[k, 1]):
                best, heading_dist = int(k), float(ahead[i])
        return best


@dataclass
class ControlState:
    """What the controller remembers between cycles for one goal."""

    xy_latched: bool = False
    aligning: bool = False  # rotating in place towards the plan (rotate_to_heading_threshold)


@dataclass
class ControlOutput:
    cmd: tuple[float, float]
    valid: bool  # False: no collision-free command (move_base counts controller patience)
    goal_reached: bool
    trajectory: np.ndarray | None = None


class LocalController:
    """computeVelocityCommands + isGoalReached of TrajectoryPlannerROS and DWAPlannerROS around a
    SamplingPlanner: the goal tolerances (with the xy latch), the final rotation to the goal's
    yaw, and otherwise the planner's sampled trajectories."""

    def __init__(self, planner: SamplingPlanner) -> None:
        self.planner = planner
        self.p = planner.p
        self.state = ControlState()

    def reset(self) -> None:
        self.state = ControlState()
        self.planner.reset()

    def compute(
        self, costmap: cm.Costmap, pose, velocity, plan: np.ndarray, period: float, escaping: bool = False
    ) -> ControlOutput:
        """pose (x, y, yaw) and plan (k, 3) in the costmap's frame; velocity (v, w) the last command."""
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
        if self.planner.align_threshold > 0 and not escaping:
            out = self._align(costmap, pose, velocity, plan, period)
            if out is not None:
                return out
        choice = self.planner.choose(costmap, pose, velocity, plan[:, :2], period, escaping)
        return ControlOutput(choice.cmd, choice.valid, False, choice.trajectory)

    def _align(
        self, costmap: cm.Costmap, pose, velocity, plan: np.ndarray, period: float
    ) -> ControlOutput | None:
        """Rotate in place towards the plan's direction when it is off by more than the planner's
        align_threshold (None: aligned, or the rotation would collide)."""
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
        limit = self.planner.align_threshold * (0.5 if self.state.aligning else 1.0)
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
