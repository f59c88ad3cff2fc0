"""The Rao-Blackwellised particle filter of gmapping (Grisetti et al.): each particle carries
a pose and its own map; odometry proposes, scan matching corrects, the scan's likelihood in
the particle's map weighs, and the particles are resampled when the weights degenerate.

The steps of a processed scan, when a scan is processed and why the motion noise depends on the
scan rate: docs/slam.md, "How the filter works". Each particle's trajectory is kept in a shared
tree, so the published map is rebuilt from the best particle's path, as slam_gmapping does.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from numba import njit

from twil_control.errors import TwilControlError

from . import matcher
from .gmapping_params import GMappingParams
from .grid import ParticleMaps
from .motion import relative_motion, sample_motion, wrap_angle
from .occupancy import occupancy_from_counts, trace_scan


@njit(cache=True)
def _world_bounds(poses, ex, ey, sx, sy):
    """(xmin, ymin, xmax, ymax) of the sensor and the robot-frame points (ex, ey) seen from
    every pose (80 particles x 640 beams: compiled, as numpy's temporaries cost a millisecond)."""
    x0 = y0 = math.inf
    x1 = y1 = -math.inf
    for k in range(poses.shape[0]):
        c, s = math.cos(poses[k, 2]), math.sin(poses[k, 2])
        for i in range(ex.shape[0] + 1):
            px, py = (ex[i], ey[i]) if i < ex.shape[0] else (sx, sy)
            wx = poses[k, 0] + c * px - s * py
            wy = poses[k, 1] + s * px + c * py
            x0, x1 = min(x0, wx), max(x1, wx)
            y0, y1 = min(y0, wy), max(y1, wy)
    return x0, y0, x1, y1


class ScanSizeError(TwilControlError, ValueError):
    """A scan with a different number of ranges than the filter was built for."""


@dataclass
class ScanGeometry:
    """Where the beams point: directions in the robot (base) frame and the sensor's position."""

    angles: np.ndarray  # beam directions in the base frame (rad), one per range
    sensor_x: float = 0.0
    sensor_y: float = 0.0


@dataclass
class _Beams:
    ex: np.ndarray  # robot-frame endpoints of every usable beam (cut at maxUrange)
    ey: np.ndarray
    is_hit: np.ndarray  # a real return within maxUrange (the rest only clear space)
    mx: np.ndarray  # the matcher's beams: endpoints and unit directions
    my: np.ndarray
    mdx: np.ndarray
    mdy: np.ndarray


@dataclass
class Grid:
    """An occupancy grid: data[row, col] (row = y), origin = world (x, y) of cell (0, 0)'s corner."""

    data: np.ndarray
    origin_x: float
    origin_y: float
    resolution: float


class GMapping:
    """The filter. `process(odom_pose, ranges, t)` returns True when the scan was used."""

    def __init__(
        self, params: GMappingParams, geometry: ScanGeometry, rng: np.random.Generator, parallel: bool = False
    ) -> None:
        self.p = params
        self.geometry = geometry
        self.rng = rng
        m = matcher.matcher_for(params.kernelSize)
        self._match = m.match_parallel if parallel else m.match_serial
        n = params.particles
        self.n_beams = len(geometry.angles)
        self._cos = np.cos(np.asarray(geometry.angles, float))
        self._sin = np.sin(np.asarray(geometry.angles, float))
        self.maps = ParticleMaps(
            n, params.xmin, params.ymin, params.xmax, params.ymax, params.delta, params.kernelSize
        )
        self.poses = np.zeros((n, 3))
        self.log_weights = np.zeros(n)  # since the last resampling
        self.weight_sums = np.zeros(n)  # along the whole path (picks the best particle)
        self.weights = np.full(n, 1.0 / n)
        self.neff = float(n)
        self.entropy = float(np.log(n))
        self.resample_count = 0
        self.count = 0  # processed scans
        # trajectory tree
        self._node_parent = np.zeros(1024, np.int64)
        self._node_pose = np.zeros((1024, 3))
        self._node_scan = np.zeros(1024, np.int64)
        self._n_nodes = 0
        self.node = np.full(n, -1, np.int64)
        self.scans: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        self.scan_times: list[float] = []
        self.odom_at_scan: list[np.ndarray] = []
        # gating state
        self._last_odom: np.ndarray | None = None
        self._update_odom: np.ndarray | None = None
        self._linear = 0.0
        self._angular = 0.0
        self._last_update_time = 0.0
        self.last_process_seconds = 0.0
        # wall seconds of the last processed scan's phases: scan matching of every particle,
        # registration of the scan into every map (with the tiles copied on write), resampling
        # (the index arrays only), and the rest (beams, weights, the trajectory tree, growth)
        self.last_phase_seconds = dict(match=0.0, register=0.0, resample=0.0, other=0.0)
        self._counts_cache: dict | None = None  # the counts of the last path traced (counts())

    # -- the filter ----------------------------------------------------------------------
    def process(self, odom_pose, ranges, t: float) -> bool:
        odom = np.asarray(odom_pose, float)
        ranges = np.asarray(ranges, float)
        if ranges.shape != (self.n_beams,):
            raise ScanSizeError(f"scan has {ranges.size} ranges; this filter was set up for {self.n_beams}")
        p = self.p
        if self._last_odom is not None:
            step = relative_motion(odom, self._last_odom)
            self._linear += float(np.hypot(step[0], step[1]))
            self._angular += abs(float(step[2]))
            self.poses = sample_motion(
                self.poses, odom, self._last_odom, p.srr, p.srt, p.str, p.stt, self.rng
            )
        self._last_odom = odom
        if self.count and not self._due(t):
            return False
        start = time.perf_counter()
        match = resample = 0.0
        beams = self._beams(ranges)
        if self.count == 0:
            self.poses[:] = odom
        else:
            self._grow(beams)
            m = self.maps
            t0 = time.perf_counter()
            self.poses, _, liks = self._match(
                m.tiles,
                m.cells,
                m.ox,
                m.oy,
                m.delta,
                self.poses,
                beams.mx,
                beams.my,
                beams.mdx,
                beams.mdy,
                p.sigma,
                p.lsigma,
                p.lstep,
                p.astep,
                p.iterations,
                p.minimumScore,
            )
            match = time.perf_counter() - t0
            self.poses[:, 2] = wrap_angle(self.poses[:, 2])
            self.log_weights += liks
            self.weight_sums += liks
            self._normalise()
        self._grow(beams)
        self._record(beams, odom, t)
        if self.count and self.neff < self.p.resampleThreshold * self.p.particles:
            t0 = time.perf_counter()
            self._resample()
            resample = time.perf_counter() - t0
        hits = beams.is_hit
        t0 = time.perf_counter()
        self.maps.register_all(np.arange(self.p.particles), self.poses, beams.ex[hits], beams.ey[hits])
        end = time.perf_counter()
        self.count += 1
        self._update_odom = odom
        self._linear = self._angular = 0.0
        self._last_update_time = t
        self.last_process_seconds = end - start
        self.last_phase_seconds = dict(
            match=match, register=end - t0, resample=resample, other=(t0 - start) - match - resample
        )
        return True

    def _due(self, t: float) -> bool:
        p = self.p
        return (
            self._linear >= p.linearUpdate
            or self._angular >= p.angularUpdate
            or (p.temporalUpdate >= 0 and t - self._last_update_time > p.temporalUpdate)
        )

    def _beams(self, ranges: np.ndarray) -> _Beams:
        p, g = self.p, self.geometry
        with np.errstate(invalid="ignore"):
            valid = np.isfinite(ranges) & (ranges > 0) & (ranges <= p.maxRange)
            is_hit = valid & (ranges < p.maxUrange)
        r = np.where(valid, np.minimum(ranges, p.maxUrange), 0.0)
        ex = g.sensor_x + r * self._cos
        ey = g.sensor_y + r * self._sin
        # the matcher's beams in scan order: neighbouring beams read neighbouring cells (an
        # interleaved order let the matcher drop hopeless moves a little sooner, but cost more
        # in cache misses than it saved)
        use = np.flatnonzero(is_hit & (np.arange(self.n_beams) % (p.lskip + 1) == 0))
        return _Beams(ex[valid], ey[valid], is_hit[valid], ex[use], ey[use], self._cos[use], self._sin[use])

    def _grow(self, beams: _Beams) -> None:
        """Make the grid hold every particle's beams (and the kernel around them)."""
        x0, y0, x1, y1 = _world_bounds(
            self.poses, beams.ex, beams.ey, self.geometry.sensor_x, self.geometry.sensor_y
        )
        margin = (self.p.kernelSize + 2) * self.p.delta
        self.maps.ensure_inside(x0 - margin, y0 - margin, x1 + margin, y1 + margin)

    def _normalise(self) -> None:
        n = self.p.particles
        gain = 1.0 / (self.p.ogain * n)
        w = np.exp(gain * (self.log_weights - self.log_weights.max()))
        w /= w.sum()
        self.weights = w
        self.neff = float(1.0 / np.sum(w * w))
        nz = w[w > 0]
        self.entropy = float(-np.sum(nz * np.log(nz)))

    def _resample(self) -> None:
        """Systematic (low-variance) resampling: one random offset, n evenly spaced pointers."""
        n = self.p.particles
        pointers = (self.rng.random() + np.arange(n)) / n
        idx = np.minimum(np.searchsorted(np.cumsum(self.weights), pointers), n - 1)
        self.poses = self.poses[idx].copy()
        self.weight_sums = self.weight_sums[idx].copy()
        self.node = self.node[idx].copy()
        self.log_weights = np.zeros(n)
        self.weights = np.full(n, 1.0 / n)
        self.maps.resample(idx)
        self.resample_count += 1

    def _record(self, beams: _Beams, odom: np.ndarray, t: float) -> None:
        """Store the scan and add one trajectory node per particle."""
        k = len(self.scans)
        self.scans.append((beams.ex.astype(np.float32), beams.ey.astype(np.float32), beams.is_hit.copy()))
        self.scan_times.append(float(t))
        self.odom_at_scan.append(odom.copy())
        n = self.p.particles
        while self._n_nodes + n > len(self._node_parent):
            self._node_parent = np.concatenate([self._node_parent, np.zeros_like(self._node_parent)])
            self._node_pose = np.concatenate([self._node_pose, np.zeros_like(self._node_pose)])
            self._node_scan = np.concatenate([self._node_scan, np.zeros_like(self._node_scan)])
        ids = np.arange(self._n_nodes, self._n_nodes + n)
        self._node_parent[ids] = self.node
        self._node_pose[ids] = self.poses
        self._node_scan[ids] = k
        self._n_nodes += n
        self.node = ids

    # -- results -------------------------------------------------------------------------
    def best_particle(self) -> int:
        """gmapping's choice: the particle with the highest accumulated log likelihood."""
        return int(np.argmax(self.weight_sums))

    def best_pose(self) -> np.ndarray:
        return self.poses[self.best_particle()].copy()

    def map_to_odom(self) -> np.ndarray:
        """(x, y, theta) of the odom frame in the map frame: best pose * odom pose^-1."""
        if self._update_odom is None:
            return np.zeros(3)
        pose, odom = self.best_pose(), self._update_odom
        th = wrap_angle(pose[2] - odom[2])
        c, s = np.cos(th), np.sin(th)
        return np.array([pose[0] - (c * odom[0] - s * odom[1]), pose[1] - (s * odom[0] + c * odom[1]), th])

    def trajectory(self, particle: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(scan indices, poses (k, 3)) of a particle's path over the processed scans, oldest first."""
        node = self.node[self.best_particle() if particle is None else particle]
        scans, poses = [], []
        while node >= 0:
            scans.append(self._node_scan[node])
            poses.append(self._node_pose[node])
            node = self._node_parent[node]
        return np.array(scans[::-1], np.int64), np.array(poses[::-1]).reshape(-1, 3)

    def _path_nodes(self, particle: int | None = None) -> np.ndarray:
        """Trajectory node ids of a particle's path, oldest first."""
        node = self.node[self.best_particle() if particle is None else particle]
        out = []
        while node >= 0:
            out.append(node)
            node = self._node_parent[node]
        return np.array(out[::-1], np.int64)

    def counts(self, particle: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(hits, visits) of every processed scan ray-traced along a particle's path.

        The counts of the path asked for last are kept: a new path is traced only from where
        it leaves that one (the scans after the common ancestor are taken out, the new ones
        added), which gives the same integers as tracing the whole path again, in a
        millisecond instead of one per processed scan."""
        m = self.maps
        rows, cols = m.shape_cells
        path = self._path_nodes(particle)
        cache = self._counts_cache
        if cache is not None and (cache["shape"] != (rows, cols) or cache["origin"] != (m.ox, m.oy)):
            cache = self._regrid_counts(cache, rows, cols)
        if cache is None:
            cache = dict(
                path=np.zeros(0, np.int64),
                hits=np.zeros((rows, cols), np.int32),
                visits=np.zeros((rows, cols), np.int32),
                outside=0,
            )
        old = cache["path"]
        n = min(len(old), len(path))
        common = int(np.argmin(old[:n] == path[:n])) if n and not np.array_equal(old[:n], path[:n]) else n
        for node, weight in [(k, -1) for k in old[common:][::-1]] + [(k, 1) for k in path[common:]]:
            cache["outside"] += weight * self._trace_node(cache["hits"], cache["visits"], node, weight)
        cache.update(path=path, shape=(rows, cols), origin=(m.ox, m.oy))
        self._counts_cache = cache
        return cache["hits"].copy(), cache["visits"].copy()

    def _trace_node(self, hits, visits, node: int, weight: int) -> int:
        g, m = self.geometry, self.maps
        ex, ey, is_hit = self.scans[self._node_scan[node]]
        x, y, th = self._node_pose[node]
        return trace_scan(
            hits, visits, m.ox, m.oy, m.delta, x, y, th, g.sensor_x, g.sensor_y, ex, ey, is_hit, weight
        )

    def _regrid_counts(self, cache: dict, rows: int, cols: int) -> dict | None:
        """The kept counts moved onto the grown grid (it grows by whole cells on each side);
        None (trace anew) if a traced beam had left the old grid, which the new one may hold."""
        if cache["outside"]:
            return None
        m = self.maps
        left = int(round((cache["origin"][0] - m.ox) / m.delta))
        bottom = int(round((cache["origin"][1] - m.oy) / m.delta))
        old_rows, old_cols = cache["shape"]
        for key in ("hits", "visits"):
            grown = np.zeros((rows, cols), np.int32)
            grown[bottom : bottom + old_rows, left : left + old_cols] = cache[key]
            cache[key] = grown
        return cache

    def occupancy(self, particle: int | None = None) -> Grid:
        hits, visits = self.counts(particle)
        m = self.maps
        return Grid(occupancy_from_counts(hits, visits, self.p.occ_thresh), m.ox, m.oy, m.delta)
