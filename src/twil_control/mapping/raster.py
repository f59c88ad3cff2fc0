"""Rasterise a 2D scene (mapping.sections.Section) into an occupancy grid (pure numpy).

A cell is occupied (100) when its centre lies inside a shape, or when a shape's outline passes
through the cell's interior (outlines sampled every resolution / 4), so a wall thinner than a
cell still shows;
every other cell is free (0). This is the ground-truth map SLAM results are compared with.
"""

from __future__ import annotations

import math

import numpy as np

from twil_control.errors import InputError

from .map_io import FREE, OCCUPIED, OccupancyMap
from .sections import Section


def default_extent(
    section: Section, resolution: float, margin: float = 0.5
) -> tuple[tuple[float, float], tuple[float, float]]:
    """((x0, y0), (width, height)): the shapes' bounding box grown by `margin` on each side,
    snapped outwards to multiples of `resolution`."""
    bounds = section.bounds()
    if bounds is None:
        raise InputError(
            "the section holds no shapes: nothing to rasterise (is the height "
            "above every obstacle, or below the floor?)"
        )
    xmin, ymin, xmax, ymax = bounds
    x0 = math.floor((xmin - margin) / resolution) * resolution
    y0 = math.floor((ymin - margin) / resolution) * resolution
    x1 = math.ceil((xmax + margin) / resolution) * resolution
    y1 = math.ceil((ymax + margin) / resolution) * resolution
    return (x0, y0), (x1 - x0, y1 - y0)


#: Outline samples are taken between sample points (never at a vertex) and moved this fraction
#: of a cell into the shape, so an outline lying exactly on a cell border (a wall face on the
#: grid) does not mark the cell outside it.
_NUDGE = 1e-6


def _mark_points(grid, points, x0, y0, res) -> None:
    cols = np.floor((points[:, 0] - x0) / res).astype(np.int64)
    rows = np.floor((points[:, 1] - y0) / res).astype(np.int64)
    inside = (rows >= 0) & (rows < grid.shape[0]) & (cols >= 0) & (cols < grid.shape[1])
    grid[rows[inside], cols[inside]] = OCCUPIED


def _window(lo, hi, start, res, n):
    """Index range [i0, i1) of the cells whose centres may lie in [lo, hi]."""
    i0 = max(int(math.floor((lo - start) / res - 0.5)), 0)
    i1 = min(int(math.ceil((hi - start) / res - 0.5)) + 1, n)
    return i0, i1


def rasterize(
    section: Section, resolution: float, origin: tuple[float, float], size: tuple[float, float]
) -> OccupancyMap:
    """Occupancy grid of `section`: cell (0, 0)'s corner at `origin`, `size` (w, h) in metres."""
    if not (resolution > 0 and math.isfinite(resolution)):
        raise InputError(f"resolution must be > 0 m per cell (got {resolution})")
    width, height = int(round(size[0] / resolution)), int(round(size[1] / resolution))
    if width < 1 or height < 1:
        raise InputError(
            f"the map must be at least one cell wide and high (size {size} at resolution {resolution})"
        )
    x0, y0 = map(float, origin)
    res = resolution
    grid = np.full((height, width), FREE, dtype=np.int8)
    step = res / 4
    for poly in section.polygons:
        c0, c1 = _window(poly[:, 0].min(), poly[:, 0].max(), x0, res, width)
        r0, r1 = _window(poly[:, 1].min(), poly[:, 1].max(), y0, res, height)
        if c0 < c1 and r0 < r1:
            cx = x0 + (np.arange(c0, c1) + 0.5) * res
            cy = y0 + (np.arange(r0, r1) + 0.5) * res
            X, Y = np.meshgrid(cx, cy)
            inside = np.ones(X.shape, dtype=bool)
            for a, b in zip(poly, np.roll(poly, -1, axis=0)):  # left of every CCW edge
                inside &= (b[0] - a[0]) * (Y - a[1]) - (b[1] - a[1]) * (X - a[0]) >= 0
            grid[r0:r1, c0:c1][inside] = OCCUPIED
        for a, b in zip(poly, np.roll(poly, -1, axis=0)):
            length = float(np.hypot(*(b - a)))
            n = max(int(math.ceil(length / step)), 1)
            s = ((np.arange(n) + 0.5) / n)[:, None]
            inward = np.array([a[1] - b[1], b[0] - a[0]]) / length * _NUDGE * res
            _mark_points(grid, a + s * (b - a) + inward, x0, y0, res)
    for cx_, cy_, r in section.circles:
        c0, c1 = _window(cx_ - r, cx_ + r, x0, res, width)
        r0, r1 = _window(cy_ - r, cy_ + r, y0, res, height)
        if c0 < c1 and r0 < r1:
            X, Y = np.meshgrid(x0 + (np.arange(c0, c1) + 0.5) * res, y0 + (np.arange(r0, r1) + 0.5) * res)
            grid[r0:r1, c0:c1][(X - cx_) ** 2 + (Y - cy_) ** 2 <= r * r] = OCCUPIED
        n = max(int(math.ceil(2 * math.pi * r / step)), 8)
        phi = (np.arange(n) + 0.5) * (2 * math.pi / n)
        inner = r - _NUDGE * res
        _mark_points(
            grid, np.column_stack([cx_ + inner * np.cos(phi), cy_ + inner * np.sin(phi)]), x0, y0, res
        )
    return OccupancyMap(grid, res, (x0, y0, 0.0))
