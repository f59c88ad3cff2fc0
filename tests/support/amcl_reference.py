"""amcl's map_calc_range walked cell by cell in plain Python: the oracle the compiled ray cast
(localization.amcl_laser.calc_range, which jumps over free stretches) is tested against."""

from __future__ import annotations

import math

from twil_control.localization.amcl_map import FREE


def calc_range_reference(occ, ox, oy, res, x, y, a, max_range) -> float:
    """Bresenham from the cell of (x, y) to the cell max_range away along a; the distance (cells
    times res) to the first cell off the map or not free, else max_range."""
    h, w = occ.shape
    x0, y0 = math.floor((x - ox) / res), math.floor((y - oy) / res)
    x1 = math.floor((x + max_range * math.cos(a) - ox) / res)
    y1 = math.floor((y + max_range * math.sin(a) - oy) / res)
    steep = abs(y1 - y0) > abs(x1 - x0)
    if steep:
        x0, y0, x1, y1 = y0, x0, y1, x1
    dx, dy = abs(x1 - x0), abs(y1 - y0)
    xstep, ystep = (1 if x0 < x1 else -1), (1 if y0 < y1 else -1)
    err, cx, cy = 0, x0, y0
    while True:
        i, j = (cy, cx) if steep else (cx, cy)
        if not (0 <= i < w and 0 <= j < h) or occ[j, i] != FREE:
            return math.hypot(cx - x0, cy - y0) * res
        if cx == x1:
            return max_range
        cx += xstep
        err += dy
        if 2 * err >= dx:
            cy += ystep
            err -= dx
