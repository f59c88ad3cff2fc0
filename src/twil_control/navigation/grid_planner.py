"""navfn's role: the optimal path on the costmap grid, 8-connected and cost-aware.

A* with the octile heuristic, compiled (numba), because a Python heap loop over a house map
takes about a second. A step's cost grows with the cells' costs by `cost_factor`, as navfn's
cost term does; 0 gives the shortest 8-connected path, the reference for path lengths
(docs/navigation.md).
"""

from __future__ import annotations

import heapq
import math

import numba
import numpy as np

from twil_control.errors import TwilControlError

from .costmap import INSCRIBED, NO_INFORMATION

SQRT2 = math.sqrt(2.0)


class NoPathError(TwilControlError, RuntimeError):
    """No path between the cells (start or goal blocked, or no connection)."""


@numba.njit(cache=True)
def _step_cost(c):
    """A cell's cost term: unknown cells (passable only with allow_unknown) count as free."""
    return 0.0 if c == NO_INFORMATION else float(c)


@numba.njit(cache=True)
def _astar(passable, costs, start, goal, cost_factor):
    h, w = passable.shape
    n = h * w
    g = np.full(n, np.inf)
    parent = np.full(n, -1, np.int64)
    closed = np.zeros(n, np.bool_)
    s = start[0] * w + start[1]
    t = goal[0] * w + goal[1]
    g[s] = 0.0
    dr = np.array([-1, -1, -1, 0, 0, 1, 1, 1])
    dc = np.array([-1, 0, 1, -1, 1, -1, 0, 1])
    step = np.array([SQRT2, 1.0, SQRT2, 1.0, 1.0, SQRT2, 1.0, SQRT2])
    heap = [(0.0, s)]
    gr, gc = goal[0], goal[1]
    while len(heap) > 0:
        f, u = heapq.heappop(heap)
        if closed[u]:
            continue
        closed[u] = True
        if u == t:
            break
        ur, uc = u // w, u % w
        for k in range(8):
            vr, vc = ur + dr[k], uc + dc[k]
            if vr < 0 or vr >= h or vc < 0 or vc >= w or not passable[vr, vc]:
                continue
            if k in (0, 2, 5, 7) and not (passable[ur, vc] and passable[vr, uc]):
                continue  # no diagonal squeeze between two blocked cells
            v = vr * w + vc
            if closed[v]:
                continue
            nc = g[u] + step[k] * (
                1.0 + cost_factor * (_step_cost(costs[ur, uc]) + _step_cost(costs[vr, vc])) / 504.0
            )
            if nc < g[v]:
                g[v] = nc
                parent[v] = u
                ddr, ddc = abs(vr - gr), abs(vc - gc)
                hh = (max(ddr, ddc) - min(ddr, ddc)) + SQRT2 * min(ddr, ddc)
                heapq.heappush(heap, (nc + hh, v))
    return g[t], parent


def passable_cells(
    costs: np.ndarray, lethal_cost: int = INSCRIBED, allow_unknown: bool = False
) -> np.ndarray:
    ok = costs < lethal_cost
    if allow_unknown:
        ok |= costs == NO_INFORMATION
    return ok


def plan_cells(
    costs: np.ndarray,
    start: tuple[int, int],
    goal: tuple[int, int],
    cost_factor: float = 3.0,
    lethal_cost: int = INSCRIBED,
    allow_unknown: bool = False,
) -> tuple[np.ndarray, float]:
    """((k, 2) array of (row, col) from start to goal, path cost in cells)."""
    passable = passable_cells(costs, lethal_cost, allow_unknown)
    for label, (r, c) in (("start", start), ("goal", goal)):
        if not (0 <= r < costs.shape[0] and 0 <= c < costs.shape[1]):
            raise NoPathError(
                f"the {label} cell ({r}, {c}) is outside the {costs.shape[0]} x {costs.shape[1]} costmap"
            )
        if not passable[r, c]:
            raise NoPathError(
                f"the {label} cell ({r}, {c}) has cost {costs[r, c]} (>= {lethal_cost}: "
                f"in or too close to an obstacle)"
            )
    total, parent = _astar(
        passable,
        np.ascontiguousarray(costs, dtype=np.uint8),
        np.array(start, np.int64),
        np.array(goal, np.int64),
        float(cost_factor),
    )
    if not np.isfinite(total):
        raise NoPathError(
            f"no path from cell {tuple(start)} to cell {tuple(goal)}: they are not connected "
            f"through free cells"
        )
    w = costs.shape[1]
    chain = [goal[0] * w + goal[1]]
    while chain[-1] != start[0] * w + start[1]:
        chain.append(int(parent[chain[-1]]))
    idx = np.array(chain[::-1], np.int64)
    return np.column_stack([idx // w, idx % w]), float(total)


def path_length(points: np.ndarray) -> float:
    return float(np.sum(np.linalg.norm(np.diff(points, axis=0), axis=1))) if len(points) > 1 else 0.0
