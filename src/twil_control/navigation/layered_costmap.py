"""costmap_2d's LayeredCostmap: a master grid built from a static layer, an obstacle layer and
an inflation layer, either fixed in the map frame (global) or a rolling window that follows the
robot (local).

The update order is costmap_2d's: move the window, then each layer writes into the master by
maximum (static, then obstacles), then the inflation layer inflates the lethal cells. As
costmap_2d bounds each update, only the cells within the inflation radius of what the obstacle
layer changed are rebuilt, unless the window or the static layer moved.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import costmap as cm
from .footprint import FootprintCells, transform


@dataclass
class StaticMap:
    """An OccupancyGrid already translated to costs (costmap.occupancy_to_cost)."""

    costs: np.ndarray
    resolution: float
    origin: tuple[float, float, float]  # x, y, yaw of cell (0, 0)'s corner in the map frame


@dataclass
class Observation:
    """One laser scan in the costmap's frame: sensor pose (x, y, yaw) and the scan's data."""

    sensor_pose: tuple[float, float, float]
    ranges: np.ndarray
    angle_min: float
    angle_increment: float
    range_min: float
    range_max: float
    marking: bool = True
    clearing: bool = True
    obstacle_range: float | None = None  # None: the layer's
    raytrace_range: float | None = None
    source: str = ""  # the observation source it came from
    stamp: float = 0.0  # s
    keep_time: float = 0.0  # the source's observation_persistence (s)


@dataclass
class LayerConfig:
    static: bool = True
    obstacles: bool = True
    inflation: bool = True
    obstacle_range: float = 2.5
    raytrace_range: float = 3.0
    inflation_radius: float = 0.55
    cost_scaling_factor: float = 10.0
    footprint_clearing: bool = True
    track_unknown_space: bool = False
    lethal_cost_threshold: int = 100


@dataclass
class _LastUpdate:
    """What the last update combined and made: a later update rebuilds only the cells the
    changes since reach."""

    static: np.ndarray | None
    obstacles: np.ndarray | None  # a copy of the obstacle layer
    master: np.ndarray


UNCHANGED = (slice(0, 0), slice(0, 0))


def _bounds(changed: np.ndarray):
    """((first, last) row, (first, last) column) of the True cells, (None, None) if there are none."""
    rows = np.flatnonzero(changed.any(axis=1))
    if rows.size == 0:
        return None, None
    cols = np.flatnonzero(changed[rows[0] : rows[-1] + 1].any(axis=0))
    return (int(rows[0]), int(rows[-1])), (int(cols[0]), int(cols[-1]))


def _grown(rows, cols, margin: int, shape) -> tuple[slice, slice]:
    """The slices of rows rows[0]..rows[1] and columns cols[0]..cols[1] grown by margin cells on
    every side, within a grid of `shape`."""
    h, w = shape
    return (
        slice(max(rows[0] - margin, 0), min(rows[1] + margin + 1, h)),
        slice(max(cols[0] - margin, 0), min(cols[1] + margin + 1, w)),
    )


class LayeredCostmap:
    def __init__(
        self,
        footprint: np.ndarray,
        resolution: float,
        config: LayerConfig,
        width_m: float = 10.0,
        height_m: float = 10.0,
        rolling_window: bool = False,
        origin: tuple[float, float] = (0.0, 0.0),
    ) -> None:
        self.config = config
        self.rolling_window = rolling_window
        self.footprint = footprint
        self.cells = FootprintCells(footprint, resolution)
        w, h = max(1, int(round(width_m / resolution))), max(1, int(round(height_m / resolution)))
        unknown = cm.NO_INFORMATION if config.track_unknown_space else cm.FREE
        self.master = cm.Costmap(w, h, resolution, *origin, default=unknown)
        self.obstacles = cm.Costmap(w, h, resolution, *origin, default=unknown)
        self.static_layer: np.ndarray | None = None
        self.static_map: StaticMap | None = None
        self._static_cache: tuple | None = None
        # per observation source, its buffer (ObservationBuffer's role): the newest scan, or the
        # scans of the last observation_persistence seconds; every update applies all of them
        self.observations: dict[str, list[Observation]] = {}
        self.updated = False
        self._last: _LastUpdate | None = None

    @property
    def inscribed_radius(self) -> float:
        return self.cells.inscribed

    @property
    def circumscribed_radius(self) -> float:
        return self.cells.circumscribed

    # -- inputs -------------------------------------------------------------------------
    def set_static_map(self, static: StaticMap) -> None:
        """A new map. A global (non-rolling) costmap takes the map's size and origin, as
        costmap_2d's static layer resizes the master grid; obstacle data is kept where the
        old and new grids overlap."""
        self.static_map = static
        if self.rolling_window:
            return
        h, w = static.costs.shape
        res = self.master.resolution
        if not math.isclose(static.resolution, res, rel_tol=1e-6) or static.origin[2] != 0.0:
            # costmap_2d keeps the costmap's resolution: resample the map onto it
            w = int(round(w * static.resolution / res))
            h = int(round(h * static.resolution / res))
        old = self.obstacles
        self.master = cm.Costmap(w, h, res, static.origin[0], static.origin[1], default=old.default)
        self.obstacles = cm.Costmap(w, h, res, static.origin[0], static.origin[1], default=old.default)
        # carry obstacles over where the grids overlap (same resolution, shifted origin)
        shift = np.round((old.origin - self.obstacles.origin) / res).astype(int)
        oh, ow = old.shape
        r0, c0 = shift[1], shift[0]
        rs, cs = max(0, r0), max(0, c0)
        re, ce = min(h, r0 + oh), min(w, c0 + ow)
        if rs < re and cs < ce:
            self.obstacles.costs[rs:re, cs:ce] = old.costs[rs - r0 : re - r0, cs - c0 : ce - c0]

    def add_observation(self, obs: Observation) -> None:
        """Buffer a scan as costmap_2d's ObservationBuffer does: with keep_time 0 only the newest
        scan of its source is kept, otherwise those no older than keep_time before it."""
        buf = self.observations.setdefault(obs.source, [])
        buf.append(obs)
        buf[:] = [o for o in buf if o.stamp >= obs.stamp - obs.keep_time] if obs.keep_time > 0 else buf[-1:]

    # -- update -------------------------------------------------------------------------
    def update(self, robot_pose, T_map_costmap=(0.0, 0.0, 0.0)) -> np.ndarray:
        """Update the master grid for the robot at `robot_pose` (x, y, yaw in the costmap
        frame). T_map_costmap is the pose of the costmap frame in the static map's frame."""
        c = self.config
        x, y, yaw = robot_pose
        if self.rolling_window:
            self.master.recenter(x, y)
            self.obstacles.recenter(x, y)
        if c.obstacles:
            for obs in (o for buf in self.observations.values() for o in buf):
                hits, ends = cm.scan_points(
                    obs.ranges,
                    obs.angle_min,
                    obs.angle_increment,
                    obs.range_min,
                    obs.range_max,
                    obs.sensor_pose,
                )
                cm.update_obstacles(
                    self.obstacles,
                    obs.sensor_pose,
                    hits,
                    ends,
                    c.obstacle_range if obs.obstacle_range is None else obs.obstacle_range,
                    c.raytrace_range if obs.raytrace_range is None else obs.raytrace_range,
                    clearing=obs.clearing,
                    marking=obs.marking,
                )
            if c.footprint_clearing:
                self._clear_footprint(x, y, yaw)
        static = self._static_layer(T_map_costmap) if c.static and self.static_map is not None else None
        window = self._changed_window(static)
        if window is None:
            base = self._combined(static, (slice(None), slice(None)))
            if c.inflation:
                base = cm.inflate(
                    base,
                    self.master.resolution,
                    self.inscribed_radius,
                    c.cost_scaling_factor,
                    c.inflation_radius,
                )
        else:
            base = self._last.master.copy()  # every update is a new grid (readers compare identity)
            if window != UNCHANGED:
                base[window] = self._recomputed(static, window)
        self.master.costs = base
        self._last = _LastUpdate(static, self.obstacles.costs.copy() if c.obstacles else None, base)
        self.updated = True
        return base

    def _static_layer(self, T_map_costmap) -> np.ndarray:
        """The static map resampled on the master grid, cached until the map, the window or the
        map -> costmap transform moves (a global costmap: once per map)."""
        s = self.static_map
        key = (id(s), tuple(self.master.origin), self.master.shape, tuple(np.round(T_map_costmap, 6)))
        if self._static_cache is None or self._static_cache[0] != key:
            layer = cm.sample_static(
                self.master, s.costs, s.resolution, np.array(s.origin[:2]), s.origin[2], T_map_costmap
            )
            if not self.config.track_unknown_space:
                layer[layer == cm.NO_INFORMATION] = cm.FREE
            self._static_cache = (key, layer)
        return self._static_cache[1]

    def _combined(self, static: np.ndarray | None, region) -> np.ndarray:
        """The static layer (or the default) and the obstacle layer combined by maximum over a
        region of the grid (a pair of slices), before inflation."""
        base = (
            static[region].copy()
            if static is not None
            else np.full(self.obstacles.costs[region].shape, self.master.default, np.uint8)
        )
        if self.config.obstacles:
            obst = self.obstacles.costs[region]
            known = obst != cm.NO_INFORMATION
            base = np.where(known & ((base == cm.NO_INFORMATION) | (obst > base)), obst, base)
        return base

    def _changed_window(self, static: np.ndarray | None):
        """The master cells the layers' changes since the last update can reach (a pair of
        slices; UNCHANGED when nothing changed), None when the whole grid must be built (a first
        update, a moved window or static layer, an infinite inflation radius). Inflation reaches
        inflation_radius from a changed cell, as costmap_2d's updateBounds grows its bounds."""
        last, c = self._last, self.config
        if (
            last is None
            or last.master is not self.master.costs
            or last.static is not static
            or (c.inflation and not math.isfinite(c.inflation_radius))
        ):
            return None
        if not c.obstacles:
            return UNCHANGED
        rows, cols = _bounds(self.obstacles.costs != last.obstacles)
        if rows is None:
            return UNCHANGED
        margin = self._margin()
        return _grown(rows, cols, margin, self.master.shape)

    def _margin(self) -> int:
        c = self.config
        return int(math.ceil(c.inflation_radius / self.master.resolution)) + 1 if c.inflation else 0

    def _recomputed(self, static: np.ndarray | None, window) -> np.ndarray:
        """The master's cells in `window`, from the layers within one inflation reach around it
        (every lethal cell that inflates a cell of the window lies there)."""
        c = self.config
        margin = self._margin()
        rows, cols = window
        source = _grown((rows.start, rows.stop - 1), (cols.start, cols.stop - 1), margin, self.master.shape)
        base = self._combined(static, source)
        if c.inflation:
            base = cm.inflate(
                base, self.master.resolution, self.inscribed_radius, c.cost_scaling_factor, c.inflation_radius
            )
        return base[
            rows.start - source[0].start : rows.stop - source[0].start,
            cols.start - source[1].start : cols.stop - source[1].start,
        ]

    def _clear_footprint(self, x: float, y: float, yaw: float) -> None:
        import cv2

        o = self.obstacles
        pts = (transform(self.footprint, x, y, yaw) - o.origin) / o.resolution - 0.5
        fixed = np.round(pts * 16).astype(np.int32)  # 4 fractional bits
        # rasterised in the polygon's bounding box of cells, not the whole grid
        h, w = o.shape
        c0, r0 = np.maximum(np.floor(pts.min(axis=0)).astype(int) - 1, 0)
        c1, r1 = np.minimum(np.ceil(pts.max(axis=0)).astype(int) + 2, (w, h))
        if c0 >= c1 or r0 >= r1:
            return
        mask = np.zeros((r1 - r0, c1 - c0), np.uint8)
        cv2.fillPoly(mask, [fixed - np.array([c0, r0], np.int32) * 16], 1, shift=4)
        window = o.costs[r0:r1, c0:c1]
        window[(mask > 0) & (window == cm.LETHAL)] = cm.FREE

    def reset_beyond(self, x: float, y: float, reset_distance: float) -> None:
        """clear_costmap_recovery: forget obstacle-layer data outside the square of side
        reset_distance centred on the robot (the static layer is kept)."""
        self.obstacles.clear_outside_window(x, y, reset_distance)
