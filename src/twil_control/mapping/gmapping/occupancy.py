"""The published map: every processed scan of one particle's trajectory ray-traced into visit
and hit counts (what slam_gmapping's updateMap does for the best particle), then thresholded
into an occupancy grid (-1 unknown, 0 free, 100 occupied). The counts are integers, so a scan
traced with weight -1 is taken out exactly: the filter keeps the last path's counts and only
traces where the new path differs (filter.GMapping.counts)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)  # slam_gmapping's worker builds /map beside the simulation
def trace_scan(hits, visits, ox, oy, delta, x, y, th, sx, sy, ex, ey, is_hit, weight=1):
    """Ray-trace one scan: sensor at robot-frame (sx, sy), endpoints (ex, ey); cells on each
    beam get `weight` visits, the endpoint cell of a real return (is_hit) gets a visit and a
    hit; the endpoint cell of a beam cut at maxUrange is left alone (gmapping's registerScan).
    Returns the number of cells that fell outside the grid (skipped)."""
    c, s = math.cos(th), math.sin(th)
    inv = 1.0 / delta
    rows, cols = hits.shape
    x0 = int(math.floor((x + c * sx - s * sy - ox) * inv))
    y0 = int(math.floor((y + s * sx + c * sy - oy) * inv))
    outside = 0
    for i in range(ex.shape[0]):
        x1 = int(math.floor((x + c * ex[i] - s * ey[i] - ox) * inv))
        y1 = int(math.floor((y + s * ex[i] + c * ey[i] - oy) * inv))
        # Bresenham from (x0, y0) to (x1, y1); every cell but the last is free
        ddx, ddy = abs(x1 - x0), -abs(y1 - y0)
        stx = 1 if x0 < x1 else -1
        sty = 1 if y0 < y1 else -1
        err = ddx + ddy
        cx, cy = x0, y0
        while cx != x1 or cy != y1:
            if 0 <= cx < cols and 0 <= cy < rows:
                visits[cy, cx] += weight
            else:
                outside += 1
            e2 = 2 * err
            if e2 >= ddy:
                err += ddy
                cx += stx
            if e2 <= ddx:
                err += ddx
                cy += sty
        if is_hit[i]:
            if 0 <= x1 < cols and 0 <= y1 < rows:
                visits[y1, x1] += weight
                hits[y1, x1] += weight
            else:
                outside += 1
    return outside


def occupancy_from_counts(hits: np.ndarray, visits: np.ndarray, occ_thresh: float) -> np.ndarray:
    """int8 grid: -1 where never visited, 100 where hits/visits > occ_thresh, else 0."""
    grid = np.full(hits.shape, -1, np.int8)
    seen = visits > 0
    occ = np.zeros(hits.shape)
    occ[seen] = hits[seen] / visits[seen]
    grid[seen] = 0
    grid[seen & (occ > occ_thresh)] = 100
    return grid
