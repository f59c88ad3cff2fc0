"""Synthetic occupancy grids for tests and benchmarks (OccupancyGrid values: 0 free, 100
occupied, -1 unknown), with walls drawn as filled rectangles in metres."""

from __future__ import annotations

import numpy as np


def _box(grid: np.ndarray, res: float, x0: float, y0: float, x1: float, y1: float, value: int = 100) -> None:
    c0, c1 = int(round(x0 / res)), int(round(x1 / res))
    r0, r1 = int(round(y0 / res)), int(round(y1 / res))
    grid[max(r0, 0) : max(r1, 0), max(c0, 0) : max(c1, 0)] = value


def house(resolution: float = 0.05) -> np.ndarray:
    """A 12 m x 9 m house: outer walls, four rooms and a hall joined by 0.9 m doors, furniture.
    Cell (0, 0) is at (0, 0); row = y."""
    w, h, t = 12.0, 9.0, 0.1
    g = np.zeros((int(round(h / resolution)), int(round(w / resolution))), np.int8)
    for box in ((0, 0, w, t), (0, h - t, w, h), (0, 0, t, h), (w - t, 0, w, h)):
        _box(g, resolution, *box)
    # a hall along y in [4, 5]; rooms below and above, split at x = 6
    _box(g, resolution, 0, 4.0, 2.0, 4.0 + t)
    _box(g, resolution, 2.9, 4.0, 8.0, 4.0 + t)
    _box(g, resolution, 8.9, 4.0, w, 4.0 + t)
    _box(g, resolution, 0, 5.0, 4.0, 5.0 + t)
    _box(g, resolution, 4.9, 5.0, 9.5, 5.0 + t)
    _box(g, resolution, 10.4, 5.0, w, 5.0 + t)
    _box(g, resolution, 6.0, 0, 6.0 + t, 4.0)
    _box(g, resolution, 6.0, 5.0, 6.0 + t, h)
    # furniture
    _box(g, resolution, 1.0, 1.0, 2.5, 2.0)  # bed
    _box(g, resolution, 8.0, 1.5, 9.0, 2.5)  # table
    _box(g, resolution, 2.0, 6.5, 3.0, 8.0)  # sofa
    _box(g, resolution, 9.0, 6.0, 10.5, 7.0)  # desk
    return g


def maze(cells: int = 8, cell_size: int = 10, seed: int = 0) -> np.ndarray:
    """A perfect maze (one path between any two cells) by randomised depth-first search, as a
    grid of (cells * cell_size + 1)^2 pixels with 1-pixel walls: 100 wall, 0 free."""
    rng = np.random.default_rng(seed)
    n = cells * cell_size + 1
    g = np.full((n, n), 100, np.int8)
    seen = np.zeros((cells, cells), bool)
    stack = [(0, 0)]
    seen[0, 0] = True

    def carve(r, c):
        g[r * cell_size + 1 : (r + 1) * cell_size, c * cell_size + 1 : (c + 1) * cell_size] = 0

    carve(0, 0)
    while stack:
        r, c = stack[-1]
        nbrs = [
            (r + dr, c + dc)
            for dr, dc in ((1, 0), (-1, 0), (0, 1), (0, -1))
            if 0 <= r + dr < cells and 0 <= c + dc < cells and not seen[r + dr, c + dc]
        ]
        if not nbrs:
            stack.pop()
            continue
        nr, nc = nbrs[rng.integers(len(nbrs))]
        seen[nr, nc] = True
        carve(nr, nc)
        # open the wall between the two cells
        if nr != r:
            wr = max(r, nr) * cell_size
            g[wr, c * cell_size + 1 : (c + 1) * cell_size] = 0
        else:
            wc = max(c, nc) * cell_size
            g[r * cell_size + 1 : (r + 1) * cell_size, wc] = 0
        stack.append((nr, nc))
    return g
