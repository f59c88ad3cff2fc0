"""amcl's laser models (AMCLLaser): each particle's weight multiplied by the likelihood of a scan.

`likelihood_field` (amcl's ad-hoc 1 + sum pz^3), `likelihood_field_prob` (a product, with beam
skipping) and `beam` (ray cast in the map), each with amcl's choice of beams and its handling of
readings out of range (docs/localization.md). The likelihood fields are tabulated per cell once
per map, so a beam costs a rotation and one lookup; the kernels are compiled with numba.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from twil_control.errors import InputError

from .amcl_map import AmclMap

MODELS = ("likelihood_field", "likelihood_field_prob", "beam")
FLT_MAX = float(np.finfo(np.float32).max)


@dataclass(frozen=True)
class LaserModelParams:
    model: str = "likelihood_field"
    max_beams: int = 30
    z_hit: float = 0.95
    z_short: float = 0.1
    z_max: float = 0.05
    z_rand: float = 0.05
    sigma_hit: float = 0.2
    lambda_short: float = 0.1
    likelihood_max_dist: float = 2.0
    do_beamskip: bool = False
    beam_skip_distance: float = 0.5
    beam_skip_threshold: float = 0.3
    beam_skip_error_threshold: float = 0.9


@dataclass(frozen=True)
class LaserData:
    ranges: np.ndarray  # prepared observed ranges (prepare_ranges), float64
    bearings: np.ndarray  # beam angles in the robot's frame
    range_max: float
    laser_x: float = 0.0  # the laser's position on the robot
    laser_y: float = 0.0


def prepare_ranges(ranges, range_min: float, range_max: float) -> np.ndarray:
    """amcl_node's reading of a LaserScan's ranges (float32 comparisons, as there): <= range_min
    -> range_max ("amcl has no concept of min range"), > range_max -> FLT_MAX, NaN kept."""
    r = np.asarray(ranges, dtype=np.float32)
    with np.errstate(invalid="ignore"):
        out = np.where(r <= np.float32(range_min), range_max, np.where(r > np.float32(range_max), FLT_MAX, r))
    return out.astype(np.float64)


def beam_step(model: str, count: int, max_beams: int) -> int:
    """One beam in this many (amcl's per-model subsampling; at least 1)."""
    if model == "likelihood_field_prob":
        return max(int(math.ceil(count / max_beams)), 1)
    return max((count - 1) // (max_beams - 1), 1)


class LaserModel:
    """The laser model of one map and parameter set, with its tabulated fields."""

    def __init__(self, params: LaserModelParams, grid: AmclMap) -> None:
        if params.model not in MODELS:
            raise InputError(f"laser model {params.model!r} is not one of {', '.join(MODELS)}")
        self.p, self.map = params, grid
        self._tables: dict[float, tuple[np.ndarray, float]] = {}

    def likelihood_table(self, range_max: float) -> tuple[np.ndarray, float]:
        """(per-cell table, off-map value): pz^3 (likelihood_field) or log pz (_prob)."""
        table = self._tables.get(range_max)
        if table is None:
            p = self.p
            dist = self.map.distance_field(p.likelihood_max_dist)
            denom = 2.0 * p.sigma_hit * p.sigma_hit
            rand = p.z_rand * (1.0 / range_max)
            pz = p.z_hit * np.exp(-(dist * dist) / denom) + rand
            off = p.z_hit * math.exp(-(p.likelihood_max_dist**2) / denom) + rand
            if p.model == "likelihood_field":
                table = (np.ascontiguousarray(pz**3), off**3)
            else:
                with np.errstate(divide="ignore"):
                    table = (np.ascontiguousarray(np.log(pz)), math.log(off) if off > 0 else -math.inf)
            self._tables[range_max] = table
        return table

    def weigh(self, poses: np.ndarray, weights: np.ndarray, data: LaserData, converged: bool) -> float:
        """Multiply `weights` (in place) by each pose's scan likelihood; the new total weight."""
        p = self.p
        count = len(data.ranges)
        step = beam_step(p.model, count, p.max_beams)
        idx = np.arange(0, count, step)
        r, b = data.ranges[idx], data.bearings[idx]
        m = self.map
        if p.model == "beam":
            return _beam_model(
                poses, weights, data.laser_x, data.laser_y, r, b, data.range_max, m.clearance(),
                m.origin_x, m.origin_y, m.resolution, p.z_hit, p.z_short, p.z_max, p.z_rand,
                p.sigma_hit, p.lambda_short,
            )  # fmt: skip
        table, off = self.likelihood_table(data.range_max)
        with np.errstate(invalid="ignore"):
            used = (r < data.range_max) & ~np.isnan(r)  # max-range readings and NaN are skipped
        ex, ey = r * np.cos(b), r * np.sin(b)
        args = (
            poses,
            weights,
            data.laser_x,
            data.laser_y,
            table,
            off,
            m.origin_x,
            m.origin_y,
            1.0 / m.resolution,
        )
        if p.model == "likelihood_field":
            return _likelihood_field(*args, ex[used], ey[used], False)
        if not (p.do_beamskip and converged):
            return _likelihood_field(*args, ex[used], ey[used], True)
        dist = m.distance_field(p.likelihood_max_dist)
        return _likelihood_field_beamskip(
            *args, ex, ey, used, dist, p.max_beams, p.beam_skip_distance, p.beam_skip_threshold,
            p.beam_skip_error_threshold,
        )  # fmt: skip


@njit(cache=True)
def _cell(hx, hy, ox, oy, inv_res, w, h):
    """Flat index of the cell holding (hx, hy), or -1 off the map."""
    u = (hx - ox) * inv_res
    v = (hy - oy) * inv_res
    if u >= 0.0 and v >= 0.0 and u < w and v < h:
        return int(v) * w + int(u)
    return -1


@njit(cache=True)
def _likelihood_field(poses, weights, lx, ly, table, off, ox, oy, inv_res, ex, ey, logs):
    h, w = table.shape
    flat = table.ravel()
    total = 0.0
    for j in range(poses.shape[0]):
        c, s = math.cos(poses[j, 2]), math.sin(poses[j, 2])
        px = poses[j, 0] + c * lx - s * ly
        py = poses[j, 1] + s * lx + c * ly
        acc = 0.0
        for k in range(ex.shape[0]):
            cell = _cell(px + c * ex[k] - s * ey[k], py + s * ex[k] + c * ey[k], ox, oy, inv_res, w, h)
            acc += flat[cell] if cell >= 0 else off
        weights[j] *= math.exp(acc) if logs else 1.0 + acc
        total += weights[j]
    return total


@njit(cache=True)
def _likelihood_field_beamskip(
    poses,
    weights,
    lx,
    ly,
    table,
    off,
    ox,
    oy,
    inv_res,
    ex,
    ey,
    used,
    dist,
    max_beams,
    skip_dist,
    threshold,
    error_threshold,
):
    h, w = table.shape
    flat, dflat = table.ravel(), dist.ravel()
    n, nb = poses.shape[0], ex.shape[0]
    logs = np.zeros((n, max_beams))
    counts = np.zeros(max_beams)
    for j in range(n):
        c, s = math.cos(poses[j, 2]), math.sin(poses[j, 2])
        px = poses[j, 0] + c * lx - s * ly
        py = poses[j, 1] + s * lx + c * ly
        for k in range(min(nb, max_beams)):
            if not used[k]:
                continue
            cell = _cell(px + c * ex[k] - s * ey[k], py + s * ex[k] + c * ey[k], ox, oy, inv_res, w, h)
            if cell >= 0:
                if dflat[cell] < skip_dist:
                    counts[k] += 1.0
                logs[j, k] = flat[cell]
            else:
                logs[j, k] = off
    keep = counts / n > threshold
    skipped = max_beams - int(keep.sum())
    if skipped >= max_beams * error_threshold:  # most beams disagree: the filter may be lost
        keep[:] = True
    total = 0.0
    for j in range(n):
        acc = 0.0
        for k in range(max_beams):
            if keep[k]:
                acc += logs[j, k]
        weights[j] *= math.exp(acc)
        total += weights[j]
    return total


@njit(cache=True)
def calc_range(clear, ox, oy, res, x, y, a, max_range):
    """The range the map gives from (x, y) along heading a: Bresenham from the start cell to the
    cell max_range away, stopping at the first cell off the map or not free (amcl's
    map_calc_range: unknown counts as an obstacle); the cell distance in metres, or max_range.
    `clear` is AmclMap.clearance()."""
    x0 = int(math.floor((x - ox) / res))
    y0 = int(math.floor((y - oy) / res))
    x1 = int(math.floor((x + max_range * math.cos(a) - ox) / res))
    y1 = int(math.floor((y + max_range * math.sin(a) - oy) / res))
    return _walk(clear, x0, y0, x1, y1, res, max_range)


@njit(cache=True)
def _walk(clear, x0, y0, x1, y1, res, max_range):
    """calc_range's walk from cell (x0, y0) to (x1, y1). Bresenham moves one cell a step along its
    major axis and at most one across, so from a cell whose clearance (chessboard distance to the
    nearest cell to stop at) is c, the next c - 1 cells are free: the walk jumps over them, the
    error term advanced in closed form, and lands where the step-by-step walk would (the oracle,
    tests/support/amcl_reference.py, walks cell by cell)."""
    h, w = clear.shape
    steep = abs(y1 - y0) > abs(x1 - x0)
    if steep:
        x0, y0, x1, y1 = y0, x0, y1, x1
    dx, dy = abs(x1 - x0), abs(y1 - y0)
    xstep = 1 if x0 < x1 else -1
    ystep = 1 if y0 < y1 else -1
    err = 0
    cx, cy = x0, y0
    while True:
        i, j = (cy, cx) if steep else (cx, cy)
        c = clear[j, i] if (0 <= i < w and 0 <= j < h) else 0
        if c <= 0:
            return math.sqrt((cx - x0) ** 2 + (cy - y0) ** 2) * res
        if cx == x1:
            return max_range
        k = min(c - 1, abs(x1 - cx))
        if k <= 1:  # one step: err += dy; if 2 err >= dx: cy += ystep, err -= dx
            cx += xstep
            err += dy
            if 2 * err >= dx:
                cy += ystep
                err -= dx
        else:  # k steps at once (2 err stays in [-dx, dx), so the count of cy steps is this floor)
            total = err + k * dy
            m = (2 * total + dx) // (2 * dx)
            cx += xstep * k
            cy += ystep * m
            err = total - m * dx


@njit(cache=True)
def _beam_model(
    poses,
    weights,
    lx,
    ly,
    ranges,
    bearings,
    range_max,
    clear,
    ox,
    oy,
    res,
    z_hit,
    z_short,
    z_max,
    z_rand,
    sigma_hit,
    lambda_short,
):
    denom = 2.0 * sigma_hit * sigma_hit
    cb, sb = np.cos(bearings), np.sin(bearings)
    # the terms that depend on the reading alone: short (when the map says farther), max, random
    short = z_short * lambda_short * np.exp(-lambda_short * ranges)
    fixed = np.where(ranges == range_max, z_max, 0.0) + np.where(ranges < range_max, z_rand / range_max, 0.0)
    inv = 1.0 / res
    total = 0.0
    for j in range(poses.shape[0]):
        c, s = math.cos(poses[j, 2]), math.sin(poses[j, 2])
        px = poses[j, 0] + c * lx - s * ly
        py = poses[j, 1] + s * lx + c * ly
        x0 = int(math.floor((px - ox) * inv))
        y0 = int(math.floor((py - oy) * inv))
        p = 1.0
        for k in range(ranges.shape[0]):
            obs = ranges[k]
            if obs != obs:  # NaN: no reading (amcl's beam model would turn the weight into NaN)
                continue
            # the beam's heading from the particle's and the bearing's cosines and sines
            x1 = int(math.floor((px + range_max * (c * cb[k] - s * sb[k]) - ox) * inv))
            y1 = int(math.floor((py + range_max * (s * cb[k] + c * sb[k]) - oy) * inv))
            expected = _walk(clear, x0, y0, x1, y1, res, range_max)
            z = obs - expected
            pz = z_hit * math.exp(-(z * z) / denom) + fixed[k]
            if z < 0:
                pz += short[k]
            p += pz * pz * pz
        weights[j] *= p
        total += weights[j]
    return total
