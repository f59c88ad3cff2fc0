"""run.py's arithmetic: the optimal path's length from BARN's path files, the navigation metric,
and the out.txt line that report_test.py reads.

The metric is 1_success * optimal_time / clip(actual_time, 2 optimal_time, 8 optimal_time),
with optimal_time the path's length at 2 m/s; the path is the path file's cells (world
coordinates through path_coord_to_gazebo_coord) between the initial position and the goal.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

RADIUS = 0.075  # BARN's cell half-size (m)


def path_coord_to_gazebo_coord(x: float, y: float) -> tuple[float, float]:
    """A path file's (row, column) cell as world (x, y), as run.py converts it."""
    r_shift = -RADIUS - (30 * RADIUS * 2)
    c_shift = RADIUS + 5
    return x * (RADIUS * 2) + r_shift, y * (RADIUS * 2) + c_shift


def path_length(path_file: Path, init: tuple[float, float], goal: tuple[float, float]) -> float:
    """Length (m) of init -> the path file's cells -> goal."""
    cells = np.load(path_file)
    points = [init, *(path_coord_to_gazebo_coord(*c) for c in cells), goal]
    return sum(math.dist(a, b) for a, b in zip(points[:-1], points[1:]))


def nav_metric(success: bool, actual_time: float, optimal_time: float) -> float:
    return int(success) * optimal_time / float(np.clip(actual_time, 2 * optimal_time, 8 * optimal_time))


def out_line(
    world_idx: int, success: bool, collided: bool, time: float, metric: float, time_limit: float = 100.0
) -> str:
    """The line run.py appends to its --out file: world, success, collided, timed out, time, metric."""
    return f"{world_idx:d} {int(success)} {int(collided)} {int(time >= time_limit)} {time:.4f} {metric:.4f}\n"
