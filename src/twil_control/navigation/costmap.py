"""costmap_2d's grid and layers (static, obstacle, inflation), vectorised.

Costs are uint8 with costmap_2d's values (FREE 0, INSCRIBED 253, LETHAL 254, NO_INFORMATION
255), cells in the OccupancyGrid's row-major layout, and the layers combine as costmap_2d's
default plugins do. The layers' rules: docs/navigation.md, "How the pieces decide".
"""

from __future__ import annotations

import functools
import math

import cv2
import numba
import numpy as np

from twil_control.errors import InputError

FREE = 0
INSCRIBED = 253
LETHAL = 254
NO_INFORMATION = 255


def inflation_cost(
    distance: np.ndarray, inscribed_radius: float, cost_scaling_factor: float, inflation_radius: float
) -> np.ndarray:
    """costmap_2d InflationLayer::computeCost of a distance (m) to the nearest lethal cell,
    as uint8: LETHAL at 0, INSCRIBED within the inscribed radius, then
    (INSCRIBED - 1) exp(-k (d - r_inscribed)) truncated, and FREE beyond inflation_radius."""
    d = np.asarray(distance, dtype=float)
    cost = np.zeros(d.shape, np.uint8)
    near = d <= inflation_radius  # the exponential only where it matters (a few % of a map)
    dn = d[near]
    decay = np.floor((INSCRIBED - 1) * np.exp(-cost_scaling_factor * (dn - inscribed_radius)))
    cost[near] = np.where(dn == 0.0, LETHAL, np.where(dn <= inscribed_radius, INSCRIBED, decay))
    return cost


def check_inflation(inflation_radius: float, cost_scaling_factor: float) -> None:
    """ValueError for inflation numbers that make no costmap: a NaN or negative radius inflates
    nothing sensible, a negative factor makes costs above INSCRIBED (they wrap round in uint8),
    and an infinite or NaN one makes NaN costs. A radius of .inf inflates the whole grid."""
    if not inflation_radius >= 0:
        raise InputError(f"inflation_radius must be >= 0 m (.inf: everywhere) (got {inflation_radius})")
    if not (cost_scaling_factor >= 0 and math.isfinite(cost_scaling_factor)):
        raise InputError(f"cost_scaling_factor must be a finite number >= 0 (got {cost_scaling_factor})")


def _cell_distances(lethal: np.ndarray) -> np.ndarray:
    """OpenCV's precise L2 distance (cells, float32) from each cell to the nearest lethal one;
    at least one cell must be lethal."""
    free = np.logical_not(lethal).astype(np.uint8, copy=False)
    return cv2.distanceTransform(free, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)


def distance_to_lethal(lethal: np.ndarray, resolution: float) -> np.ndarray:
    """Exact Euclidean distance (m) from each cell centre to the nearest lethal cell centre.

    OpenCV's precise L2 transform returns float32; squared cell distances are integers, so
    rounding d^2 recovers the exact value in float64."""
    if not lethal.any():
        return np.full(lethal.shape, np.inf)
    return np.sqrt(np.round(_cell_distances(lethal).astype(np.float64) ** 2)) * resolution


def inflate(
    costs: np.ndarray,
    resolution: float,
    inscribed_radius: float,
    cost_scaling_factor: float,
    inflation_radius: float,
) -> np.ndarray:
    """The costs after the inflation layer: max(layer costs, inflated), unknown kept unknown
    unless the inflated cost is at least INSCRIBED (costmap_2d's updateCosts).

    The same values as inflation_cost(distance_to_lethal(...)) (tested), found faster: a cell's
    squared distance in cells is an integer, so costs come from a table of inflation_cost over the
    squared distances up to the inflation radius (beyond it, FREE). With few lethal cells for the
    radius (a laser's obstacles) that table, as a kernel of cells, is stamped around each lethal
    cell (costmap_2d's cached kernels); otherwise OpenCV's distance transform gives each cell its
    squared distance."""
    check_inflation(inflation_radius, cost_scaling_factor)
    lethal = costs == LETHAL
    window = _inflation_window(lethal, inflation_radius, resolution)
    if window is not None and window != (slice(None), slice(None)):
        # inflated costs are FREE beyond inflation_radius of every lethal cell, and FREE leaves
        # a cost as it is: only the lethal cells' bounding box grown by the radius can change (a
        # gmapping map of 200 m x 200 m holds a house in a corner of its 16 million cells)
        out = costs.copy()
        out[window] = inflate(
            costs[window], resolution, inscribed_radius, cost_scaling_factor, inflation_radius
        )
        return out
    if lethal.any():
        # squared cell distances from 0 to top: sqrt(top) cells lie beyond inflation_radius, or
        # beyond the grid's diagonal (a radius of .inf)
        top = int(min(inflation_radius / resolution, math.hypot(*costs.shape)) ** 2) + 2
        key = (top, resolution, inscribed_radius, cost_scaling_factor, inflation_radius)
        table = _cost_table(*key)
        rows, cols = np.nonzero(lethal)
        if len(rows) * math.pi * top <= STAMP_PER_CELL * lethal.size:
            inflated = _stamp(rows, cols, lethal.shape, *_kernel(*key))
        else:
            d_cells = _cell_distances(lethal)
            np.minimum(d_cells, np.float32(math.sqrt(top)), out=d_cells)
            inflated = table[np.rint(np.square(d_cells, dtype=np.float64)).astype(np.intp)]
    else:
        inflated = np.zeros(costs.shape, np.uint8)  # no obstacle: nothing to inflate
    out = np.maximum(costs, inflated)  # NO_INFORMATION (255) stays, except under INSCRIBED or more
    unknown = costs == NO_INFORMATION
    if unknown.any():
        out = np.where(unknown & (inflated >= INSCRIBED), inflated, out)
    return out


#: stamping the inflation kernel around every lethal cell beats the distance transform up to
#: about this many kernel cells per grid cell
STAMP_PER_CELL = 4


@functools.lru_cache(maxsize=8)
def _cost_table(
    top: int, resolution: float, inscribed_radius: float, cost_scaling_factor: float, inflation_radius: float
) -> np.ndarray:
    """inflation_cost at the squared cell distances 0..top (read-only: it is shared)."""
    table = inflation_cost(
        np.sqrt(np.arange(top + 1, dtype=float)) * resolution,
        inscribed_radius,
        cost_scaling_factor,
        inflation_radius,
    )
    table.setflags(write=False)
    return table


@functools.lru_cache(maxsize=8)
def _kernel(*table_key) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(rows, cols, costs) of the cells around a lethal cell that inflation raises above FREE,
    for the table _cost_table(*table_key)."""
    table = _cost_table(*table_key)
    reach = math.isqrt(len(table) - 1)
    dr, dc = np.mgrid[-reach : reach + 1, -reach : reach + 1]
    d2 = dr * dr + dc * dc
    keep = d2 < len(table)
    cost = np.zeros(d2.shape, np.uint8)
    cost[keep] = table[d2[keep]]
    keep &= cost > FREE
    out = dr[keep].astype(np.int64), dc[keep].astype(np.int64), cost[keep]
    for array in out:
        array.setflags(write=False)
    return out


@numba.njit(cache=True)
def _stamp(rows, cols, shape, k_rows, k_cols, k_costs):
    """The highest kernel cost over every lethal cell's kernel: inflation costs fall with
    distance, so this is the cost of the nearest lethal cell's distance, as a distance transform
    would give it, in time proportional to the lethal cells."""
    h, w = shape
    out = np.zeros((h, w), np.uint8)
    for i in range(rows.shape[0]):
        for k in range(k_rows.shape[0]):
            r, c = rows[i] + k_rows[k], cols[i] + k_cols[k]
            if 0 <= r < h and 0 <= c < w and k_costs[k] > out[r, c]:
                out[r, c] = k_costs[k]
    return out


def _inflation_window(lethal: np.ndarray, inflation_radius: float, resolution: float):
    """The rows and columns within inflation_radius of a lethal cell (a pair of slices), None when
    no cell is lethal; the whole grid for an infinite radius."""
    rows = np.flatnonzero(lethal.any(axis=1))
    if rows.size == 0:
        return None
    if not math.isfinite(inflation_radius):
        return slice(None), slice(None)
    cols = np.flatnonzero(lethal[rows[0] : rows[-1] + 1].any(axis=0))
    margin = int(math.ceil(inflation_radius / resolution)) + 1
    h, w = lethal.shape
    r0, r1 = max(rows[0] - margin, 0), min(rows[-1] + margin + 1, h)
    c0, c1 = max(cols[0] - margin, 0), min(cols[-1] + margin + 1, w)
    if r0 == 0 and c0 == 0 and r1 == h and c1 == w:
        return slice(None), slice(None)
    return slice(r0, r1), slice(c0, c1)


def occupancy_to_cost(
    data: np.ndarray,
    lethal_threshold: int = 100,
    track_unknown: bool = True,
    trinary: bool = True,
    unknown_value: int = -1,
) -> np.ndarray:
    """StaticLayer::interpretValue for an OccupancyGrid's int8 values: each of the 256 values
    translated once, then looked up (a 16-million-cell gmapping map in one pass)."""
    v = np.arange(-128, 128, dtype=np.int16)
    if trinary:
        cost = np.where(v >= lethal_threshold, LETHAL, FREE)
    else:
        cost = np.clip(np.round(v / lethal_threshold * LETHAL), 0, LETHAL)
    cost = np.where(v == unknown_value, NO_INFORMATION if track_unknown else FREE, cost).astype(np.uint8)
    table = np.roll(cost, -128)  # indexed by the value's byte: 0..127, then -128..-1
    return table[np.asarray(data, dtype=np.int8).view(np.uint8)]


def _translation_table() -> np.ndarray:
    """costmap_2d's Costmap2DPublisher table: cost -> OccupancyGrid value."""
    t = np.zeros(256, np.int8)
    t[1:253] = 1 + (97 * (np.arange(1, 253) - 1)) // 251
    t[INSCRIBED], t[LETHAL], t[NO_INFORMATION] = 99, 100, -1
    return t


_TABLE = _translation_table()


def cost_to_occupancy(costs: np.ndarray) -> np.ndarray:
    """OccupancyGrid values of uint8 costs (OpenCV's table look-up: a 40 m x 40 m costmap
    published five times a second)."""
    costs = np.asarray(costs, dtype=np.uint8)
    return cv2.LUT(costs, _TABLE).reshape(costs.shape) if costs.size else _TABLE[costs]


class Costmap:
    """A cost grid with its origin (x, y of the corner of cell (0, 0)) and resolution (m)."""

    def __init__(
        self,
        width: int,
        height: int,
        resolution: float,
        origin_x: float,
        origin_y: float,
        default: int = FREE,
    ) -> None:
        if width < 1 or height < 1 or not resolution > 0:
            raise InputError(
                f"costmap needs a positive size and resolution (got {width} x {height} "
                f"cells at {resolution} m)"
            )
        self.resolution = float(resolution)
        self.origin = np.array([origin_x, origin_y], dtype=float)
        self.default = default
        self.costs = np.full((height, width), default, np.uint8)

    @property
    def shape(self) -> tuple[int, int]:
        return self.costs.shape

    def world_to_cell(self, x, y) -> tuple[np.ndarray, np.ndarray]:
        """(row, col) integer indices (may be outside the grid)."""
        col = np.floor((np.asarray(x) - self.origin[0]) / self.resolution).astype(np.int64)
        row = np.floor((np.asarray(y) - self.origin[1]) / self.resolution).astype(np.int64)
        return row, col

    def cell_to_world(self, row, col) -> tuple[np.ndarray, np.ndarray]:
        """Cell centres."""
        return (
            self.origin[0] + (np.asarray(col) + 0.5) * self.resolution,
            self.origin[1] + (np.asarray(row) + 0.5) * self.resolution,
        )

    def inside(self, row, col) -> np.ndarray:
        h, w = self.shape
        return (row >= 0) & (row < h) & (col >= 0) & (col < w)

    def cost_at(self, x, y, outside: int = NO_INFORMATION) -> np.ndarray:
        row, col = self.world_to_cell(x, y)
        ok = self.inside(row, col)
        return np.where(
            ok, self.costs[np.clip(row, 0, self.shape[0] - 1), np.clip(col, 0, self.shape[1] - 1)], outside
        )

    def copy(self) -> Costmap:
        other = Costmap(self.shape[1], self.shape[0], self.resolution, *self.origin, default=self.default)
        other.costs = self.costs.copy()
        return other

    def recenter(self, x: float, y: float) -> None:
        """Rolling window: move the grid so that (x, y) is at its centre, keeping the cells the
        old and new windows share (costmap_2d's updateOrigin); new cells take the default."""
        h, w = self.shape
        new_origin = np.array([x - w * self.resolution / 2, y - h * self.resolution / 2])
        shift = np.floor((new_origin - self.origin) / self.resolution).astype(int)  # (dcol, drow)
        if not shift.any():
            return
        dc, dr = int(shift[0]), int(shift[1])
        old = self.costs
        self.costs = np.full_like(old, self.default)
        r0, r1 = max(0, dr), min(h, h + dr)
        c0, c1 = max(0, dc), min(w, w + dc)
        if r0 < r1 and c0 < c1:
            self.costs[r0 - dr : r1 - dr, c0 - dc : c1 - dc] = old[r0:r1, c0:c1]
        self.origin = self.origin + shift * self.resolution

    def clear_outside_window(self, x: float, y: float, size: float, keep: np.ndarray | None = None) -> None:
        """Reset every cell outside the size x size square centred on (x, y) to the default (or the
        `keep` layer's value): clear_costmap_recovery's reset of a layer."""
        xs, ys = self.cell_to_world(np.arange(self.shape[0])[:, None], np.arange(self.shape[1])[None, :])
        outside = (np.abs(xs - x) > size / 2) | (np.abs(ys - y) > size / 2)
        self.costs[outside] = self.default if keep is None else keep[outside]


def sample_static(
    costmap: Costmap,
    static_costs: np.ndarray,
    static_resolution: float,
    static_origin: np.ndarray,
    static_yaw: float,
    T_static_costmap,
) -> np.ndarray:
    """The static layer resampled at the costmap's cell centres.

    T_static_costmap = (tx, ty, yaw) is the pose of the costmap's frame in the static map's frame
    (identity for a global costmap in the map frame; map -> odom inverse for a rolling window in
    odom). Cells that fall outside the static map are NO_INFORMATION."""
    shifted = _aligned_offset(costmap, static_resolution, static_origin, static_yaw, T_static_costmap)
    if shifted is not None:  # a global costmap on its map's own grid: the cells, copied
        return _paste(static_costs, *shifted, costmap.shape)
    rows, cols = np.indices(costmap.shape)
    x, y = costmap.cell_to_world(rows, cols)
    tx, ty, yaw = T_static_costmap
    c, s = math.cos(yaw), math.sin(yaw)
    mx, my = tx + c * x - s * y, ty + s * x + c * y
    # into the map image frame (its origin pose may carry a yaw)
    cm, sm = math.cos(static_yaw), math.sin(static_yaw)
    dx, dy = mx - static_origin[0], my - static_origin[1]
    u, v = cm * dx + sm * dy, -sm * dx + cm * dy
    col = np.floor(u / static_resolution).astype(np.int64)
    row = np.floor(v / static_resolution).astype(np.int64)
    h, w = static_costs.shape
    ok = (row >= 0) & (row < h) & (col >= 0) & (col < w)
    return np.where(ok, static_costs[np.clip(row, 0, h - 1), np.clip(col, 0, w - 1)], NO_INFORMATION).astype(
        np.uint8
    )


def _aligned_offset(costmap: Costmap, resolution: float, origin, yaw: float, T) -> tuple[int, int] | None:
    """(row, col) of the costmap's cell (0, 0) in the static map, when both grids are the same
    cells (same resolution, no rotation, origins a whole number of cells apart); else None."""
    tx, ty, t_yaw = T
    if yaw != 0.0 or t_yaw != 0.0 or abs(costmap.resolution - resolution) > 1e-12 * resolution:
        return None
    offset = (np.array([tx, ty]) + costmap.origin - np.asarray(origin, dtype=float)) / resolution
    whole = np.round(offset)
    if np.abs(offset - whole).max() > 1e-6:
        return None
    return int(whole[1]), int(whole[0])


def _paste(static_costs: np.ndarray, row0: int, col0: int, shape: tuple[int, int]) -> np.ndarray:
    out = np.full(shape, NO_INFORMATION, np.uint8)
    h, w = static_costs.shape
    r0, r1 = max(row0, 0), min(row0 + shape[0], h)
    c0, c1 = max(col0, 0), min(col0 + shape[1], w)
    if r0 < r1 and c0 < c1:
        out[r0 - row0 : r1 - row0, c0 - col0 : c1 - col0] = static_costs[r0:r1, c0:c1]
    return out


def scan_points(
    ranges: np.ndarray,
    angle_min: float,
    angle_increment: float,
    range_min: float,
    range_max: float,
    sensor_pose,
) -> tuple[np.ndarray, np.ndarray]:
    """Laser returns as world points: (hit points (n, 2) of finite in-range returns,
    ray ends (m, 2) for clearing, with max-range / inf returns as rays to range_max)."""
    r = np.asarray(ranges, dtype=float)
    a = angle_min + angle_increment * np.arange(len(r)) + sensor_pose[2]
    hit = np.isfinite(r) & (r >= range_min) & (r < range_max)
    free_ray = ~hit & ~np.isnan(r) & (r >= range_min)  # inf / max range: the ray is free
    rr = np.where(hit, r, range_max)
    pts = np.column_stack([sensor_pose[0] + rr * np.cos(a), sensor_pose[1] + rr * np.sin(a)])
    return pts[hit], pts[hit | free_ray]


@numba.njit(cache=True)
def _clear_rays(costs, x0, y0, ends, ox, oy, res, free):
    """Set the cells along each ray from (x0, y0) to ends[i] to `free`, excluding the end cell
    (it holds the obstacle): integer Bresenham from cell to cell, stopping at the grid's edge
    (costmap_2d's raytraceLine). Compiled: a scan is 640 rays of up to 190 cells."""
    h, w = costs.shape
    c0 = int(math.floor((x0 - ox) / res))
    r0 = int(math.floor((y0 - oy) / res))
    for i in range(ends.shape[0]):
        c1 = int(math.floor((ends[i, 0] - ox) / res))
        r1 = int(math.floor((ends[i, 1] - oy) / res))
        dc, dr = abs(c1 - c0), abs(r1 - r0)
        sc = 1 if c1 > c0 else -1
        sr = 1 if r1 > r0 else -1
        err = dc - dr
        c, r = c0, r0
        for _ in range(dc + dr + 1):
            if c == c1 and r == r1:
                break
            if r < 0 or r >= h or c < 0 or c >= w:
                if (c < 0 and sc < 0) or (c >= w and sc > 0) or (r < 0 and sr < 0) or (r >= h and sr > 0):
                    break  # left the grid for good
            else:
                costs[r, c] = free
            e2 = 2 * err
            if e2 > -dr and e2 < dc:  # a diagonal step (8-connected)
                err += dc - dr
                c += sc
                r += sr
            elif e2 > -dr:
                err -= dr
                c += sc
            else:
                err += dc
                r += sr


def update_obstacles(
    obstacles: Costmap,
    origin,
    hits: np.ndarray,
    ray_ends: np.ndarray,
    obstacle_range: float,
    raytrace_range: float,
    clearing: bool = True,
    marking: bool = True,
) -> None:
    """ObstacleLayer: clear the cells along every ray (truncated to raytrace_range), then mark
    the hits closer than obstacle_range as LETHAL."""
    o = np.asarray(origin[:2], dtype=float)
    if clearing and len(ray_ends):
        d = ray_ends - o
        n = np.linalg.norm(d, axis=1, keepdims=True)
        ends = o + d * np.minimum(1.0, raytrace_range / np.maximum(n, 1e-12))
        _clear_rays(
            obstacles.costs,
            float(o[0]),
            float(o[1]),
            np.ascontiguousarray(ends),
            float(obstacles.origin[0]),
            float(obstacles.origin[1]),
            obstacles.resolution,
            FREE,
        )
    if marking and len(hits):
        near = np.linalg.norm(hits - o, axis=1) <= obstacle_range
        r, c = obstacles.world_to_cell(hits[near, 0], hits[near, 1])
        ok = obstacles.inside(r, c)
        obstacles.costs[r[ok], c[ok]] = LETHAL
