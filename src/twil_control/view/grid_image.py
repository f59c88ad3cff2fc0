"""Occupancy grids as RGBA images (numpy only), with rviz's two colour schemes.

- "map": unknown (-1) grey, free (0) pale blue (rviz's white would vanish on Drake's white floor),
  occupied (100) black, in between a ramp from pale blue to black;
- "costmap": free (0) and unknown transparent, 1..98 a blue-to-red ramp, 99 (inscribed) cyan,
  100 (lethal) purple, so a costmap drawn over the map shows only its obstacles and inflation.

Rows are flipped so image row 0 is the grid's last row: an image's first row is its top, a grid's
first row is at its origin (bottom), and texture coordinate (0, 0) is the image's bottom-left.
"""

from __future__ import annotations

import numpy as np

from twil_control.errors import InputError

SCHEMES = ("map", "costmap")
FREE_RGB = (190, 215, 255)


def grid_rgba(data, width: int, height: int, scheme: str) -> np.ndarray:
    """(height, width, 4) uint8 RGBA of an OccupancyGrid's data (row-major, row 0 at the origin)."""
    if scheme not in SCHEMES:
        raise InputError(f"grid colour scheme must be one of {', '.join(SCHEMES)} (got {scheme!r})")
    cells = np.asarray(data, dtype=np.int16)
    if cells.size != width * height:
        raise InputError(f"grid data has {cells.size} cells, not width x height = {width} x {height}")
    grid = cells.reshape(height, width)[::-1]
    out = np.zeros((height, width, 4), np.uint8)
    known = (grid >= 0) & (grid <= 100)
    if scheme == "map":
        dark = 1.0 - np.clip(grid, 0, 100) / 100.0
        for channel, free in enumerate(FREE_RGB):
            out[..., channel] = np.where(known, np.round(free * dark), 128)
        out[..., 3] = 255
        return out
    ramp = known & (grid >= 1) & (grid <= 98)
    s = np.clip((grid - 1) / 97.0, 0.0, 1.0)
    out[..., 0] = np.where(ramp, 255 * s, 0)
    out[..., 2] = np.where(ramp, 255 * (1 - s), 0)
    out[..., 3] = np.where(ramp, 160, 0)
    out[grid == 99] = (0, 255, 255, 200)
    out[grid == 100] = (160, 0, 200, 220)
    return out
