"""navfn's role: the optimal path on the costmap grid, 8-connected and cost-aware.

A* with the octile heuristic, compiled (numba), because a Python heap loop over a house map
takes about a second. A step's cost grows with the cells' costs by `cost_factor`, as navfn's
cost term does; 0 gives the shortest 8-connected path, the reference for path lengths
(docs/navigation.md).
"""

from __future__ import annotations

import math
import threading

import numba
import numpy as np

from twil_control.errors import TwilControlError

from .costmap import INSCRIBED, NO_INFORMATION

SQRT2 = math.sqrt(2.0)


class NoPathError(TwilControlError, RuntimeError):
    """No path between the cells (start or goal blocked, or no connection)."""


@numba.njit(cache=True)
def _heap_push(keys, vals, size, f, v):
    """Push (f, v) on the binary min-heap held in keys/vals[:size] (grown by the caller); pairs are
    ordered as tuples are, f first and the cell index on ties, so cells pop in heapq's order."""
    i = size
    while i > 0:
        p = (i - 1) >> 1
        if keys[p] < f or (keys[p] == f and vals[p] < v):
            break
        keys[i], vals[i] = keys[p], vals[p]
        i = p
    keys[i], vals[i] = f, v


@numba.njit(cache=True)
def _heap_pop(keys, vals, size):
    """Remove the smallest pair of keys/vals[:size] (size > 0) and return its cell index."""
    top = vals[0]
    size -= 1
    f, v = keys[size], vals[size]
    i = 0
    while True:
        c = 2 * i + 1
        if c >= size:
            break
        if c + 1 < size and (keys[c + 1] < keys[c] or (keys[c + 1] == keys[c] and vals[c + 1] < vals[c])):
            c += 1
        if f < keys[c] or (f == keys[c] and v < vals[c]):
            break
        keys[i], vals[i] = keys[c], vals[c]
        i = c
    keys[i], vals[i] = f, v
    return top


@numba.njit(cache=True)
def _passable(c, lethal_cost, allow_unknown):
    return c < lethal_cost or (allow_unknown and c == NO_INFORMATION)


@numba.njit(cache=True)
def _step_cost(c):
    """A cell's cost term: unknown cells (passable only with allow_unknown) count as free."""
    return 0.0 if c == NO_INFORMATION else float(c)


@numba.njit(cache=True)
def _grow(a, n):
    out = np.empty(2 * a.shape[0], a.dtype)
    out[:n] = a[:n]
    return out


@numba.njit(cache=True)
def _astar(costs, lethal_cost, allow_unknown, start, goal, cost_factor, g, parent, closed):
    """(path cost, flat cell indices from start to goal; empty when not connected). g, parent and
    closed are work arrays of one entry per cell, inf, -1 and 0 on entry and again on return: only
    the cells the search reached are reset, not the whole grid."""
    h, w = costs.shape
    s = start[0] * w + start[1]
    t = goal[0] * w + goal[1]
    dr = np.array([-1, -1, -1, 0, 0, 1, 1, 1])
    dc = np.array([-1, 0, 1, -1, 1, -1, 0, 1])
    step = np.array([SQRT2, 1.0, SQRT2, 1.0, 1.0, SQRT2, 1.0, SQRT2])
    keys = np.empty(1024)
    vals = np.empty(1024, np.int64)
    touched = np.empty(1024, np.int64)
    size, n_touched = 0, 0
    g[s] = 0.0
    touched[0] = s
    n_touched = 1
    _heap_push(keys, vals, size, 0.0, s)
    size = 1
    gr, gc = goal[0], goal[1]
    while size > 0:
        u = _heap_pop(keys, vals, size)
        size -= 1
        if closed[u]:
            continue
        closed[u] = 1
        if u == t:
            break
        ur, uc = u // w, u % w
        for k in range(8):
            vr, vc = ur + dr[k], uc + dc[k]
            v = vr * w + vc
            if not _can_step(costs, ur, uc, vr, vc, lethal_cost, allow_unknown) or closed[v]:
                continue
            nc = g[u] + step[k] * (
                1.0 + cost_factor * (_step_cost(costs[ur, uc]) + _step_cost(costs[vr, vc])) / 504.0
            )
            if nc < g[v]:
                if g[v] == np.inf:
                    if n_touched == touched.shape[0]:
                        touched = _grow(touched, n_touched)
                    touched[n_touched] = v
                    n_touched += 1
                g[v] = nc
                parent[v] = u
                ddr, ddc = abs(vr - gr), abs(vc - gc)
                hh = (max(ddr, ddc) - min(ddr, ddc)) + SQRT2 * min(ddr, ddc)
                if size == keys.shape[0]:
                    keys = _grow(keys, size)
                    vals = _grow(vals, size)
                _heap_push(keys, vals, size, nc + hh, v)
                size += 1
    total = g[t]
    path = _walk_back(parent, s, t) if total < np.inf else np.empty(0, np.int64)
    for i in range(n_touched):
        v = touched[i]
        g[v] = np.inf
        parent[v] = -1
        closed[v] = 0
    return total, path


@numba.njit(cache=True)
def _can_step(costs, ur, uc, vr, vc, lethal_cost, allow_unknown):
    """Whether the search may step from cell (ur, uc) to its neighbour (vr, vc): inside the grid,
    passable, and a diagonal step not squeezed between two blocked cells."""
    h, w = costs.shape
    if vr < 0 or vr >= h or vc < 0 or vc >= w or not _passable(costs[vr, vc], lethal_cost, allow_unknown):
        return False
    if ur == vr or uc == vc:
        return True
    return _passable(costs[ur, vc], lethal_cost, allow_unknown) and _passable(
        costs[vr, uc], lethal_cost, allow_unknown
    )


@numba.njit(cache=True)
def _walk_back(parent, s, t):
    """The flat cell indices from s to t along the parent links."""
    n, u = 1, t
    while u != s:
        u = parent[u]
        n += 1
    path = np.empty(n, np.int64)
    u = t
    for i in range(n - 1, -1, -1):
        path[i] = u
        u = parent[u]
    return path


class _WorkArrays(threading.local):
    """Per thread, the search's per-cell arrays of the last grid size (allocating and filling
    them for a 40 m x 40 m costmap cost more than many searches do)."""

    shape: tuple[int, int] | None = None
    arrays: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None

    def get(self, shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        if self.shape != shape or self.arrays is None:
            n = shape[0] * shape[1]
            self.shape = shape
            self.arrays = (np.full(n, np.inf), np.full(n, -1, np.int64), np.zeros(n, np.uint8))
        return self.arrays


_WORK = _WorkArrays()


def plan_cells(
    costs: np.ndarray,
    start: tuple[int, int],
    goal: tuple[int, int],
    cost_factor: float = 3.0,
    lethal_cost: int = INSCRIBED,
    allow_unknown: bool = False,
) -> tuple[np.ndarray, float]:
    """((k, 2) array of (row, col) from start to goal, path cost in cells)."""
    for label, (r, c) in (("start", start), ("goal", goal)):
        if not (0 <= r < costs.shape[0] and 0 <= c < costs.shape[1]):
            raise NoPathError(
                f"the {label} cell ({r}, {c}) is outside the {costs.shape[0]} x {costs.shape[1]} costmap"
            )
        if not (costs[r, c] < lethal_cost or (allow_unknown and costs[r, c] == NO_INFORMATION)):
            raise NoPathError(
                f"the {label} cell ({r}, {c}) has cost {costs[r, c]} (>= {lethal_cost}: "
                f"in or too close to an obstacle)"
            )
    total, idx = _astar(
        np.ascontiguousarray(costs, dtype=np.uint8),
        int(lethal_cost),
        bool(allow_unknown),
        np.array(start, np.int64),
        np.array(goal, np.int64),
        float(cost_factor),
        *_WORK.get(costs.shape),
    )
    if not np.isfinite(total):
        raise NoPathError(
            f"no path from cell {tuple(start)} to cell {tuple(goal)}: they are not connected "
            f"through free cells"
        )
    w = costs.shape[1]
    return np.column_stack([idx // w, idx % w]), float(total)


def path_length(points: np.ndarray) -> float:
    return float(np.sum(np.linalg.norm(np.diff(points, axis=0), axis=1))) if len(points) > 1 else 0.0
