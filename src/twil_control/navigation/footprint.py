"""The robot footprint: a polygon in the base frame, its inscribed and circumscribed radii (as
costmap_2d computes them), and the grid cells it covers at each heading, precomputed so that
collision checks of many poses are one numpy gather.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from twil_control.errors import TwilControlError


class FootprintError(TwilControlError, ValueError):
    """A footprint that is not a polygon of at least three finite points."""


def parse_footprint(points, padding: float = 0.0) -> np.ndarray:
    """(n, 2) array from [[x, y], ...]; `padding` grows it outwards like footprint_padding."""
    try:
        poly = np.asarray(points, dtype=float)
    except (TypeError, ValueError):
        raise FootprintError(f"footprint must be a list of [x, y] points (got {points!r})") from None
    if poly.ndim != 2 or poly.shape[1] != 2 or len(poly) < 3 or not np.isfinite(poly).all():
        raise FootprintError(f"footprint must be at least three finite [x, y] points (got {points!r})")
    if padding:
        poly = poly + padding * np.sign(poly)  # costmap_2d's padFootprint
    return poly


def radius_footprint(radius: float, n: int = 16) -> np.ndarray:
    """costmap_2d's makeFootprintFromRadius: a 16-gon for robot_radius."""
    a = np.arange(n) * 2 * np.pi / n
    return np.column_stack([radius * np.cos(a), radius * np.sin(a)])


def _point_segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    ab = b - a
    t = np.clip(np.dot(p - a, ab) / max(np.dot(ab, ab), 1e-300), 0.0, 1.0)
    return float(np.linalg.norm(a + t * ab - p))


def radii(poly: np.ndarray) -> tuple[float, float]:
    """(inscribed, circumscribed): the distance from the origin to the nearest edge and to the
    farthest vertex (costmap_2d's calculateMinAndMaxDistances)."""
    origin = np.zeros(2)
    edges = [_point_segment_distance(origin, poly[i], poly[(i + 1) % len(poly)]) for i in range(len(poly))]
    return min(edges), float(np.max(np.linalg.norm(poly, axis=1)))


def transform(poly: np.ndarray, x: float, y: float, yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return poly @ np.array([[c, s], [-s, c]]) + (x, y)


class FootprintCells:
    """Cell offsets (rows, cols relative to the centre cell) covered by the footprint at
    `bins` discrete headings (5 degrees by default: a corner of qbot's footprint moves up to
    1.6 cm within a bin, so a pose touching an obstacle can flip between free and not; the local
    planner copes with that, see local_planner's escape), at one grid resolution.

    The offsets hold the polygon's filled cells outside the inscribed disc; the disc itself is
    tested by the inflated cost of the centre cell (cost >= INSCRIBED means an obstacle lies
    within the inscribed radius), which is costmap_2d's own shortcut. Every heading's list is
    padded to one length (repeating its first cell) so a batch of poses is one array gather.
    """

    def __init__(self, poly: np.ndarray, resolution: float, bins: int = 72) -> None:
        self.poly = poly
        self.resolution = resolution
        self.bins = bins
        self.inscribed, self.circumscribed = radii(poly)
        reach = int(math.ceil(self.circumscribed / resolution)) + 2
        size = 2 * reach + 1
        jj, ii = np.meshgrid(np.arange(size) - reach, np.arange(size) - reach)
        inside_disc = np.hypot(ii, jj) * resolution < self.inscribed - resolution  # safely inside
        per_bin, outline = [], []
        for k in range(bins):
            yaw = 2 * math.pi * k / bins
            pts = transform(poly, 0.0, 0.0, yaw) / resolution + reach  # pixel coordinates
            mask = np.zeros((size, size), np.uint8)
            # fillPoly with 8 fractional bits, so the polygon is rasterised to sub-cell precision
            cv2.fillPoly(mask, [np.round(pts * 256).astype(np.int32)], 1, lineType=cv2.LINE_8, shift=8)
            cv2.polylines(mask, [np.round(pts * 256).astype(np.int32)], True, 1, lineType=cv2.LINE_8, shift=8)
            sel = (mask > 0) & ~inside_disc
            per_bin.append(np.column_stack([ii[sel], jj[sel]]))
            edge = np.zeros((size, size), np.uint8)
            cv2.polylines(edge, [np.round(pts * 256).astype(np.int32)], True, 1, lineType=cv2.LINE_8, shift=8)
            outline.append(np.column_stack([ii[edge > 0], jj[edge > 0]]))
        self.offsets = _padded(per_bin)
        # the polygon's edges alone, rasterised: the cells whose highest cost base_local_planner's
        # CostmapModel::footprintCost returns (the trajectories' occupancy cost, both ROS planners)
        self.outline = _padded(outline)

    def heading_bin(self, yaw) -> np.ndarray:
        return np.round(np.asarray(yaw) / (2 * math.pi) * self.bins).astype(np.int64) % self.bins


def _padded(per_bin: list[np.ndarray]) -> np.ndarray:
    """Per-heading cell lists as one (bins, m, 2) array, each padded by repeating its first cell."""
    width = max(len(c) for c in per_bin)
    return np.stack([np.vstack([c, np.repeat(c[:1], width - len(c), axis=0)]) for c in per_bin])
