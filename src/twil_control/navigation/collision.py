"""Footprint collision tests on one costmap snapshot, compiled with numba (the planners' hot
path: OMPL calls back once per motion, the local planner checks thousands of poses a cycle, and
numpy's per-call overhead on small arrays was most of their time).

A pose is free when the centre cell's inflated cost is below INSCRIBED (no obstacle within the
inscribed radius: costmap_2d's shortcut for the disc) and no cell under the footprint polygon
at its heading is LETHAL (or unknown, unless unknown space is allowed). Poses whose cell is
farther from every blocked cell than the footprint reaches (in rows or columns) skip the polygon
test, and a trajectory's successive poses in one cell at one heading bin are tested once.
"""

from __future__ import annotations

import math

import cv2
import numba
import numpy as np

from . import costmap as cm
from .footprint import FootprintCells


@numba.njit(cache=True)
def _pose_free(
    x,
    y,
    yaw,
    heading_only_disc,
    costs,
    blocked,
    near,
    offsets,
    row_len,
    pad,
    h,
    w,
    ox,
    oy,
    res,
    allow_unknown,
):
    """One pose free: the centre's inflated cost below INSCRIBED (the inscribed disc is clear)
    and, unless the pose is farther than the circumscribed radius from every blocked cell or
    heading_only_disc is set, no blocked cell under the footprint at that heading."""
    c = min(max(int(math.floor((x - ox) / res)), -1), w) + pad
    r = min(max(int(math.floor((y - oy) / res)), -1), h) + pad
    i = r * row_len + c
    v = costs[i]
    if not (v < 253 or (allow_unknown and v == 255)):
        return False
    if heading_only_disc or not near[i]:
        return True
    bins = offsets.shape[0]
    b = int(round(yaw / (2.0 * math.pi) * bins)) % bins
    for j in range(offsets.shape[1]):
        if blocked[i + offsets[b, j]]:
            return False
    return True


@numba.njit(cache=True)
def _poses_free(xs, ys, yaws, costs, blocked, near, offsets, row_len, pad, h, w, ox, oy, res, allow_unknown):
    """Every pose free (_pose_free). Compiled: OMPL calls this once per motion, and numpy's
    per-call overhead on the dozens of small array operations a motion needs was most of the
    planning time."""
    for k in range(xs.shape[0]):
        if not _pose_free(
            xs[k],
            ys[k],
            yaws[k],
            False,
            costs,
            blocked,
            near,
            offsets,
            row_len,
            pad,
            h,
            w,
            ox,
            oy,
            res,
            allow_unknown,
        ):
            return False
    return True


@numba.njit(cache=True)
def _segment_free(
    xa,
    ya,
    yawa,
    xb,
    yb,
    yawb,
    use_heading,
    radius,
    costs,
    blocked,
    near,
    offsets,
    row_len,
    pad,
    h,
    w,
    ox,
    oy,
    res,
    allow_unknown,
):
    """The motion from a to b sampled every half cell (yaw along the segment's heading, or
    interpolated on the shorter arc), every sample free (see _poses_free)."""
    d = math.hypot(xb - xa, yb - ya)
    if use_heading:
        yawa = math.atan2(yb - ya, xb - xa)
        dyaw = 0.0
    else:
        dyaw = (yawb - yawa + math.pi) % (2.0 * math.pi) - math.pi
    n = max(2, int(math.ceil(max(d, abs(dyaw) * radius) / (0.5 * res))) + 1)
    xs = np.empty(n)
    ys = np.empty(n)
    yaws = np.empty(n)
    for k in range(n):
        s = k / (n - 1)
        xs[k] = xa + s * (xb - xa)
        ys[k] = ya + s * (yb - ya)
        yaws[k] = yawa + s * dyaw
    return _poses_free(
        xs, ys, yaws, costs, blocked, near, offsets, row_len, pad, h, w, ox, oy, res, allow_unknown
    )


@numba.njit(cache=True)
def _trajectories(
    poses, costs, blocked, near, offsets, outline, row_len, pad, h, w, ox, oy, res, allow_unknown
):
    """Per trajectory: every pose free, and the highest cost met by its centre cells and its
    footprint's outline (unknown counts 0), as base_local_planner's occ_cost takes
    max(footprintCost, centre cost) along a trajectory (dwa_local_planner's ObstacleCostFunction
    the same)."""
    n, k = poses.shape[0], poses.shape[1]
    ok = np.ones(n, np.bool_)
    occ = np.zeros(n)
    bins = outline.shape[0]
    for i in range(n):
        last_centre, last_bin = -1, -1
        for j in range(k):
            x, y = poses[i, j, 0], poses[i, j, 1]
            c = min(max(int(math.floor((x - ox) / res)), -1), w) + pad
            r = min(max(int(math.floor((y - oy) / res)), -1), h) + pad
            centre = r * row_len + c
            b = int(round(poses[i, j, 2] / (2.0 * math.pi) * bins)) % bins
            if centre == last_centre and b == last_bin:
                continue  # the same cells as the pose before (a cell holds several steps)
            last_centre, last_bin = centre, b
            if not _pose_free(
                x,
                y,
                poses[i, j, 2],
                False,
                costs,
                blocked,
                near,
                offsets,
                row_len,
                pad,
                h,
                w,
                ox,
                oy,
                res,
                allow_unknown,
            ):
                ok[i] = False
                break
            v = costs[centre]
            if v != 255 and v > occ[i]:
                occ[i] = v
            for m in range(outline.shape[1]):
                v = costs[centre + outline[b, m]]
                if v != 255 and v > occ[i]:
                    occ[i] = v
    return ok, occ


@numba.njit(cache=True)
def _edge_cost(x0, y0, x1, y1, costs, row_len, pad):
    """Highest cost on the cells of the line from cell (x0, y0) to (x1, y1), -1.0 at a LETHAL or
    unknown one: base_local_planner's CostmapModel::lineCost over its LineIterator (Bresenham,
    the error starting at half the major span; both ends included)."""
    dx, dy = abs(x1 - x0), abs(y1 - y0)
    sx = 1 if x1 >= x0 else -1
    sy = 1 if y1 >= y0 else -1
    major_x = dx >= dy
    den = dx if major_x else dy
    add = dy if major_x else dx
    err = den // 2
    x, y = x0, y0
    best = 0.0
    for _ in range(den + 1):
        v = costs[(y + pad) * row_len + x + pad]
        if v >= 254:  # LETHAL, or NO_INFORMATION
            return -1.0
        if v > best:
            best = v
        err += add
        if err >= den:
            err -= den
            if major_x:
                y += sy
            else:
                x += sx
        if major_x:
            x += sx
        else:
            y += sy
    return best


@numba.njit(cache=True)
def _corner_cells(x, y, yaw, poly, h, w, ox, oy, res, cols, rows):
    """The cells of the polygon's corners at (x, y, yaw) into cols and rows; False when a corner
    lies off the grid (CostmapModel::footprintCost's worldToMap failing)."""
    c, s = math.cos(yaw), math.sin(yaw)
    for k in range(poly.shape[0]):
        cx = (x + poly[k, 0] * c - poly[k, 1] * s - ox) / res
        cy = (y + poly[k, 0] * s + poly[k, 1] * c - oy) / res
        if cx < 0.0 or cy < 0.0 or cx >= w or cy >= h:
            return False
        cols[k], rows[k] = int(cx), int(cy)
    return True


@numba.njit(cache=True)
def _outline_cost(cols, rows, costs, row_len, pad):
    """base_local_planner's CostmapModel::footprintCost of a polygon whose corners lie in cells
    (cols, rows): the highest cost on its rasterised edges, -1.0 when one of their cells is
    LETHAL or unknown. The cells inside the polygon are not looked at, as upstream."""
    n = cols.shape[0]
    best = 0.0
    for k in range(n):
        j = (k + 1) % n
        v = _edge_cost(cols[k], rows[k], cols[j], rows[j], costs, row_len, pad)
        if v < 0.0:
            return -1.0
        if v > best:
            best = v
    return best


@numba.njit(cache=True)
def _trajectories_outline(poses, poly, costs, row_len, pad, h, w, ox, oy, res):
    """Per trajectory, as TrajectoryPlanner's generateTrajectory (and dwa_local_planner's
    ObstacleCostFunction) judge every point: legal while the centre is on the grid and the
    footprint's edges meet no LETHAL or unknown cell; and the highest of the edges' and the
    centre cells' costs (unknown centre counts 0, as in _trajectories). A pose whose centre and
    corner cells are those of the pose before it adds nothing and is skipped (at the planners'
    fine steps most are: a cell holds several steps)."""
    n, k = poses.shape[0], poses.shape[1]
    m = poly.shape[0]
    ok = np.ones(n, np.bool_)
    occ = np.zeros(n)
    cols, rows = np.empty(m, np.int64), np.empty(m, np.int64)
    last_cols, last_rows = np.empty(m, np.int64), np.empty(m, np.int64)
    for i in range(n):
        last_centre = -1
        for j in range(k):
            x, y, yaw = poses[i, j, 0], poses[i, j, 1], poses[i, j, 2]
            cx, cy = (x - ox) / res, (y - oy) / res
            if cx < 0.0 or cy < 0.0 or cx >= w or cy >= h:
                ok[i] = False
                break
            if not _corner_cells(x, y, yaw, poly, h, w, ox, oy, res, cols, rows):
                ok[i] = False
                break
            centre = (int(cy) + pad) * row_len + int(cx) + pad
            if centre == last_centre:
                same = True
                for q in range(m):
                    if cols[q] != last_cols[q] or rows[q] != last_rows[q]:
                        same = False
                        break
                if same:
                    continue
            last_centre = centre
            last_cols[:] = cols
            last_rows[:] = rows
            f = _outline_cost(cols, rows, costs, row_len, pad)
            if f < 0.0:
                ok[i] = False
                break
            v = costs[centre]
            if v == 255:
                v = 0
            occ[i] = max(occ[i], f, v)
    return ok, occ


@numba.njit(cache=True)
def _segment_mean_cost(xa, ya, xb, yb, n, costs, row_len, pad, h, w, ox, oy, res):
    """Mean cell cost at n >= 2 evenly spaced points from a to b, ends included (the points
    of np.linspace(0, 1, n), bit for bit; unknown counts 0)."""
    total = 0.0
    step = 1.0 / (n - 1)
    for k in range(n):
        s = k * step if k < n - 1 else 1.0
        c = min(max(int(math.floor((xa + s * (xb - xa) - ox) / res)), -1), w) + pad
        r = min(max(int(math.floor((ya + s * (yb - ya) - oy) / res)), -1), h) + pad
        v = costs[r * row_len + c]
        total += 0.0 if v == 255 else v
    return total / n


class GridChecker:
    """Collision tests of poses and segments against one costmap snapshot.

    The grid is padded with a border of blocked cells (outside the map is not free) and
    flattened, so a pose's footprint cells are one gather of precomputed flat offsets. Poses
    farther than the footprint reaches from every blocked cell (a dilation of the blocked cells)
    are free at any heading and skip the footprint test; most samples are such poses.
    """

    def __init__(self, costmap: cm.Costmap, cells: FootprintCells, allow_unknown: bool = False) -> None:
        self.costmap = costmap
        self.cells = cells
        self.allow_unknown = allow_unknown
        pad = int(np.abs(cells.offsets).max()) + 1
        costs = costmap.costs
        border = cm.NO_INFORMATION if allow_unknown else cm.LETHAL
        padded = np.pad(costs, pad, constant_values=border)
        self._pad, self._w = pad, padded.shape[1]
        self._costs = padded.ravel()
        blocked = padded == cm.LETHAL
        if not allow_unknown:
            blocked |= padded == cm.NO_INFORMATION
        self._blocked = blocked.ravel()
        # a footprint cell lies at most `reach` rows and columns from the centre cell: a centre
        # farther than that from every blocked cell is free at any heading (a square dilation, a
        # few times cheaper than a distance transform)
        reach = int(np.abs(cells.offsets).max())
        kernel = np.ones((2 * reach + 1, 2 * reach + 1), np.uint8)
        self._near = cv2.dilate(blocked.view(np.uint8), kernel).view(np.bool_).ravel()
        self._offsets = cells.offsets[..., 0] * self._w + cells.offsets[..., 1]  # (bins, m) flat
        self._outline = cells.outline[..., 0] * self._w + cells.outline[..., 1]
        self._polygon = np.ascontiguousarray(cells.poly, dtype=np.float64)  # trajectories_outline's
        self._origin_x, self._origin_y = float(costmap.origin[0]), float(costmap.origin[1])
        self._rows, self._cols = costs.shape

    def warm_up(self) -> None:
        """Run every compiled test once (numba compiles, or loads its cache, on the first call:
        about a second, which must not be charged to a planner's time budget)."""
        x, y = self.costmap.cell_to_world(0, 0)
        self.pose_free(x, y, 0.0)
        self.segment_free((x, y), (x, y), 0.0, 0.1)
        self.segment_free((x, y), (x, y))
        self.trajectories(np.array([[[x, y, 0.0]]]))
        self.segment_mean_cost(x, y, x, y, 2)

    def flat_index(self, x, y) -> np.ndarray:
        r, c = self.costmap.world_to_cell(np.atleast_1d(x), np.atleast_1d(y))
        h, w = self.costmap.shape
        r = np.clip(r, -1, h) + self._pad  # one cell outside stays in the blocked border
        c = np.clip(c, -1, w) + self._pad
        return r * self._w + c

    def poses_valid(self, x, y, yaw) -> np.ndarray:
        """Per pose: inscribed disc clear (centre cost < INSCRIBED) and no LETHAL (or, unless
        allowed, unknown) cell under the footprint polygon at that heading."""
        idx = self.flat_index(x, y)
        centre = self._costs[idx]
        ok = centre < cm.INSCRIBED
        if self.allow_unknown:
            ok |= centre == cm.NO_INFORMATION
        check = ok & self._near[idx]
        if check.any():
            yaw = np.broadcast_to(np.asarray(yaw, dtype=float), idx.shape)[check]
            cells = idx[check][:, None] + self._offsets[self.cells.heading_bin(yaw)]
            ok[check] = ~self._blocked[cells].any(axis=1)
        return ok

    def all_free(self, x: np.ndarray, y: np.ndarray, yaw: np.ndarray) -> bool:
        """poses_valid(x, y, yaw).all(), compiled (the planners' hot path)."""
        h, w = self.costmap.shape
        return bool(
            _poses_free(
                x,
                y,
                yaw,
                self._costs,
                self._blocked,
                self._near,
                self._offsets,
                self._w,
                self._pad,
                h,
                w,
                self.costmap.origin[0],
                self.costmap.origin[1],
                self.costmap.resolution,
                self.allow_unknown,
            )
        )

    def segment_samples(self, a, b, yaw_a=None, yaw_b=None):
        """Samples every half cell from a to b (inclusive); yaw interpolated along the shorter arc,
        or the segment's heading when no yaws are given."""
        d = math.hypot(b[0] - a[0], b[1] - a[1])
        dyaw = 0.0 if yaw_a is None else math.remainder(yaw_b - yaw_a, 2 * math.pi)
        n = max(
            2,
            int(math.ceil(max(d, abs(dyaw) * self.cells.circumscribed) / (0.5 * self.costmap.resolution)))
            + 1,
        )
        s = np.linspace(0.0, 1.0, n)
        x = a[0] + s * (b[0] - a[0])
        y = a[1] + s * (b[1] - a[1])
        yaw = (math.atan2(b[1] - a[1], b[0] - a[0]) if yaw_a is None else yaw_a + s * dyaw) * np.ones(n)
        return x, y, yaw

    def pose_free(self, x: float, y: float, yaw: float | None) -> bool:
        """One pose free; yaw None tests the inscribed disc only (R^2 states)."""
        h, w = self.costmap.shape
        return bool(
            _pose_free(
                float(x),
                float(y),
                0.0 if yaw is None else float(yaw),
                yaw is None,
                self._costs,
                self._blocked,
                self._near,
                self._offsets,
                self._w,
                self._pad,
                h,
                w,
                self.costmap.origin[0],
                self.costmap.origin[1],
                self.costmap.resolution,
                self.allow_unknown,
            )
        )

    def segment_free(self, a, b, yaw_a=None, yaw_b=None) -> bool:
        """Every half-cell sample of the motion a -> b free (compiled)."""
        h, w = self.costmap.shape
        heading = yaw_a is None
        return bool(
            _segment_free(
                float(a[0]),
                float(a[1]),
                0.0 if heading else float(yaw_a),
                float(b[0]),
                float(b[1]),
                0.0 if heading else float(yaw_b),
                heading,
                self.cells.circumscribed,
                self._costs,
                self._blocked,
                self._near,
                self._offsets,
                self._w,
                self._pad,
                h,
                w,
                self.costmap.origin[0],
                self.costmap.origin[1],
                self.costmap.resolution,
                self.allow_unknown,
            )
        )

    def trajectories(self, poses: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """For trajectories (n, k, 3): (every pose free, highest cost met by the centre and the
        footprint's outline), compiled."""
        h, w = self.costmap.shape
        return _trajectories(
            np.ascontiguousarray(poses, dtype=np.float64),
            self._costs,
            self._blocked,
            self._near,
            self._offsets,
            self._outline,
            self._w,
            self._pad,
            h,
            w,
            self.costmap.origin[0],
            self.costmap.origin[1],
            self.costmap.resolution,
            self.allow_unknown,
        )

    def trajectories_outline(self, poses: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """For trajectories (n, k, 3), as upstream's local planners judge them: (every pose's
        footprint edges clear, highest cost met by the edges and the centre), compiled. Unlike
        trajectories(), cells inside the polygon are not checked and the centre may lie within
        the inscribed radius of an obstacle (CostmapModel::footprintCost)."""
        h, w = self.costmap.shape
        return _trajectories_outline(
            np.ascontiguousarray(poses, dtype=np.float64),
            self._polygon,
            self._costs,
            self._w,
            self._pad,
            h,
            w,
            self.costmap.origin[0],
            self.costmap.origin[1],
            self.costmap.resolution,
        )

    def segment_mean_cost(self, xa: float, ya: float, xb: float, yb: float, n: int) -> float:
        """Mean cost of n >= 2 evenly spaced points along a segment, compiled: OMPL's optimising
        planners ask it of every candidate edge (RRT*: about 200,000 times a second)."""
        return _segment_mean_cost(
            xa,
            ya,
            xb,
            yb,
            n,
            self._costs,
            self._w,
            self._pad,
            self._rows,
            self._cols,
            self._origin_x,
            self._origin_y,
            self.costmap.resolution,
        )
