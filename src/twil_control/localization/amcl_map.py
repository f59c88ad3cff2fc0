"""amcl's view of an occupancy grid: each cell free, unknown or occupied, the free cells that
global localisation and recovery draw particles from, and the distance from each cell to the
nearest occupied one (the likelihood field's "cspace"). Cells are where nav_msgs/OccupancyGrid
puts them, not half a cell off as in amcl; the distance is exact (docs/localization.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from twil_control.errors import TwilControlError

from ..navigation.costmap import distance_to_lethal

FREE, UNKNOWN, OCCUPIED = -1, 0, 1  # amcl's occ_state


class AmclMapError(TwilControlError, ValueError):
    """A grid amcl cannot localise in (empty, or a resolution that is not a positive number)."""


@dataclass
class AmclMap:
    occ_state: np.ndarray  # (height, width) int8: FREE, UNKNOWN or OCCUPIED
    resolution: float
    origin_x: float = 0.0
    origin_y: float = 0.0
    free_cells: np.ndarray = field(init=False)  # (n, 2) int64 (column i, row j) of free cells
    _fields: dict = field(init=False, default_factory=dict)  # distance fields, computed once each

    def __post_init__(self) -> None:
        if self.occ_state.ndim != 2 or self.occ_state.size == 0:
            raise AmclMapError(f"the map holds no cells (shape {self.occ_state.shape})")
        if not (math.isfinite(self.resolution) and self.resolution > 0):
            raise AmclMapError(f"map resolution must be a positive number of m/cell (got {self.resolution})")
        self.occ_state = np.ascontiguousarray(self.occ_state, dtype=np.int8)
        rows, cols = np.nonzero(self.occ_state == FREE)
        self.free_cells = np.column_stack([cols, rows]).astype(np.int64)

    @classmethod
    def from_occupancy(cls, data, resolution: float, origin_x: float = 0.0, origin_y: float = 0.0) -> AmclMap:
        """From OccupancyGrid values (height, width): 0 free, 100 occupied, anything else unknown
        (amcl's convertMap)."""
        data = np.asarray(data)
        state = np.full(data.shape, UNKNOWN, np.int8)
        state[data == 0] = FREE
        state[data == 100] = OCCUPIED
        return cls(state, float(resolution), float(origin_x), float(origin_y))

    @property
    def height(self) -> int:
        return self.occ_state.shape[0]

    @property
    def width(self) -> int:
        return self.occ_state.shape[1]

    def distance_field(self, max_occ_dist: float) -> np.ndarray:
        """Distance (m) from each cell to the nearest occupied cell, cut off at max_occ_dist
        (docs/localization.md); computed once per max_occ_dist."""
        key = float(max_occ_dist)
        if key not in self._fields:
            exact = distance_to_lethal(self.occ_state == OCCUPIED, self.resolution)
            cells = exact / self.resolution
            radius = int(max_occ_dist / self.resolution)  # amcl's cell_radius_ (truncated)
            self._fields[key] = np.where(cells > radius + 1e-9, key, exact)
        return self._fields[key]

    def clearance(self) -> np.ndarray:
        """int32 (height, width): each free cell's chessboard distance (in cells) to the nearest
        cell that is not free or lies off the map, 0 on cells that are not free; computed once.
        The beam model's ray casting jumps over free stretches with it."""
        if "clearance" not in self._fields:
            free = np.pad(self.occ_state == FREE, 1).astype(np.uint8)  # off the map: not free
            d = cv2.distanceTransform(free, cv2.DIST_C, 3)[1:-1, 1:-1]
            self._fields["clearance"] = np.ascontiguousarray(np.rint(d).astype(np.int32))
        return self._fields["clearance"]

    def random_free_poses(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """`n` poses (x, y, yaw): a free cell's centre drawn uniformly among the free cells and a
        heading uniform in [-pi, pi) (amcl's uniformPoseGenerator). A map with no free cell
        gives poses at its origin."""
        out = np.empty((n, 3))
        if n == 0:
            return out
        if len(self.free_cells) == 0:
            out[:, :2] = self.origin_x, self.origin_y
        else:
            cells = self.free_cells[rng.integers(0, len(self.free_cells), n)]
            out[:, 0] = self.origin_x + (cells[:, 0] + 0.5) * self.resolution
            out[:, 1] = self.origin_y + (cells[:, 1] + 0.5) * self.resolution
        out[:, 2] = rng.random(n) * 2.0 * math.pi - math.pi
        return out
