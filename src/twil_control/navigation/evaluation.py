"""Navigation evaluation, pure: the costmap move_base builds from a map, seeded random goals the
robot can reach from a start, and the grid optimum a driven path is compared with.

Goals are drawn from cells whose inflated cost is FREE (farther than inflation_radius from every
obstacle: where a user would click), whose footprint is free at the goal's heading, that the
grid connects to the start through cells below INSCRIBED, and that lie at least
`min_separation` from the previous goal (so every goal is a real drive).
"""

from __future__ import annotations

import math

import numpy as np

from twil_control.errors import InputError

from . import costmap as cm
from . import grid_planner as gp
from .collision import GridChecker
from .footprint import FootprintCells


def costmap_from_occupancy(
    data: np.ndarray,
    resolution: float,
    origin,
    cells: FootprintCells,
    inflation_radius: float,
    cost_scaling_factor: float,
) -> cm.Costmap:
    """The global costmap of a static map (unknown as free, as track_unknown_space false)."""
    m = cm.Costmap(data.shape[1], data.shape[0], resolution, origin[0], origin[1])
    m.costs = cm.inflate(
        cm.occupancy_to_cost(data, track_unknown=False),
        resolution,
        cells.inscribed,
        cost_scaling_factor,
        inflation_radius,
    )
    return m


def reachable(m: cm.Costmap, start_xy) -> np.ndarray:
    """Cells the grid connects to the start's cell through cells below INSCRIBED (8-connected)."""
    import cv2

    passable = (m.costs < cm.INSCRIBED).astype(np.uint8)
    _, labels = cv2.connectedComponents(passable, connectivity=8)
    r, c = m.world_to_cell(start_xy[0], start_xy[1])
    if not (m.inside(r, c) and passable[r, c]):
        raise InputError(f"the start ({start_xy[0]:.2f}, {start_xy[1]:.2f}) is not in free space")
    return labels == labels[r, c]


def sample_goals(
    m: cm.Costmap, cells: FootprintCells, start, n: int, rng: np.random.Generator, min_separation: float = 2.0
) -> list[tuple[float, float, float]]:
    """n goals (x, y, yaw), each reachable and min_separation from the one before (the first from
    `start`), yaw uniform in [-pi, pi) rounded to 0.01 rad, x and y to 0.01 m."""
    checker = GridChecker(m, cells)
    candidates = np.argwhere(reachable(m, start[:2]) & (m.costs == cm.FREE))
    goals, prev = [], (float(start[0]), float(start[1]))
    for _ in range(200 * n):
        if len(goals) == n:
            break
        r, c = candidates[rng.integers(len(candidates))]
        x, y = (round(float(v), 2) for v in m.cell_to_world(r, c))
        yaw = round(float(rng.uniform(-math.pi, math.pi)), 2)
        if math.dist((x, y), prev) < min_separation or not checker.pose_free(x, y, yaw):
            continue
        goals.append((x, y, yaw))
        prev = (x, y)
    if len(goals) < n:
        raise InputError(f"found only {len(goals)} of {n} goals {min_separation} m apart")
    return goals


def grid_optimum(m: cm.Costmap, a, b) -> float:
    """Length (m) of the shortest 8-connected path between the cells of a and b through cells
    below INSCRIBED (no cost term: navfn's optimum, the reference for path lengths). Raises
    grid_planner.NoPathError when they are not connected."""
    ra, ca = (int(v) for v in m.world_to_cell(a[0], a[1]))
    rb, cb = (int(v) for v in m.world_to_cell(b[0], b[1]))
    return gp.plan_cells(m.costs, (ra, ca), (rb, cb), cost_factor=0.0)[1] * m.resolution
