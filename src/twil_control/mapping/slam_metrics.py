"""SLAM accuracy figures: the relation-based error of Kummerle et al. (2009) and the absolute
trajectory error after a best rigid alignment. Poses are (n, 3) arrays of (x, y, theta), the
estimate and the reference row for row.

The relation error compares relative motions, so drift accumulated before a pair does not count;
loop-closing pairs (far apart in time, close in space) show an estimate that failed to close a
loop even when every consecutive relation is good (docs/slam.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from twil_control.errors import InputError

from .gmapping.motion import relative_motion, wrap_angle


@dataclass
class RelationError:
    pairs: int
    trans_mean: float  # m
    trans_std: float
    rot_mean: float  # deg
    rot_std: float


def relation_errors(est: np.ndarray, ref: np.ndarray, pairs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(translational m, rotational rad) errors of the relations (i, j) in `pairs` (k, 2)."""
    est, ref, pairs = np.asarray(est, float), np.asarray(ref, float), np.asarray(pairs, np.int64)
    if est.shape != ref.shape or est.ndim != 2 or est.shape[1] != 3:
        raise InputError(f"estimate {est.shape} and reference {ref.shape} must both be (n, 3)")
    i, j = pairs[:, 0], pairs[:, 1]
    d_est = relative_motion(est[j], est[i])
    d_ref = relative_motion(ref[j], ref[i])
    trans = np.hypot(d_est[:, 0] - d_ref[:, 0], d_est[:, 1] - d_ref[:, 1])
    rot = np.abs(wrap_angle(d_est[:, 2] - d_ref[:, 2]))
    return trans, rot


def consecutive_pairs(n: int) -> np.ndarray:
    return np.stack([np.arange(n - 1), np.arange(1, n)], axis=1)


def loop_pairs(ref: np.ndarray, min_gap: int = 50, radius: float = 1.0) -> np.ndarray:
    """Pairs (i, j), j - i >= min_gap, whose reference positions are within `radius` m."""
    ref = np.asarray(ref, float)
    d = np.hypot(ref[:, None, 0] - ref[None, :, 0], ref[:, None, 1] - ref[None, :, 1])
    i, j = np.nonzero(d <= radius)
    keep = j - i >= min_gap
    return np.stack([i[keep], j[keep]], axis=1)


def summarise(est: np.ndarray, ref: np.ndarray, pairs: np.ndarray) -> RelationError:
    if len(pairs) == 0:
        return RelationError(0, float("nan"), float("nan"), float("nan"), float("nan"))
    trans, rot = relation_errors(est, ref, pairs)
    rot = np.degrees(rot)
    return RelationError(
        len(pairs), float(trans.mean()), float(trans.std()), float(rot.mean()), float(rot.std())
    )


def align_rigid(est_xy: np.ndarray, ref_xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(R 2x2, t) minimising sum |R est + t - ref|^2 (Kabsch/Umeyama without scale)."""
    est_xy, ref_xy = np.asarray(est_xy, float), np.asarray(ref_xy, float)
    me, mr = est_xy.mean(0), ref_xy.mean(0)
    u, _, vt = np.linalg.svd((ref_xy - mr).T @ (est_xy - me))
    d = np.sign(np.linalg.det(u @ vt))
    rot = u @ np.diag([1.0, d]) @ vt
    return rot, mr - rot @ me


def ate_rmse(est: np.ndarray, ref: np.ndarray) -> float:
    """Root mean square position error (m) after the best rigid alignment of est onto ref."""
    est, ref = np.asarray(est, float), np.asarray(ref, float)
    rot, t = align_rigid(est[:, :2], ref[:, :2])
    err = est[:, :2] @ rot.T + t - ref[:, :2]
    return float(np.sqrt(np.mean(np.sum(err * err, axis=1))))


@dataclass
class SlamReport:
    consecutive: RelationError
    loops: RelationError
    ate_rmse: float


def evaluate(est: np.ndarray, ref: np.ndarray, min_gap: int = 50, radius: float = 1.0) -> SlamReport:
    """Consecutive and loop-closing relation errors and ATE RMSE of one trajectory."""
    return SlamReport(
        summarise(est, ref, consecutive_pairs(len(ref))),
        summarise(est, ref, loop_pairs(ref, min_gap, radius)),
        ate_rmse(est, ref),
    )


# -- maps ------------------------------------------------------------------------------------


@dataclass
class MapScore:
    precision: float  # SLAM occupied cells with a true occupied cell within tolerance
    recall: float  # observed true wall surface cells with a SLAM occupied cell within tolerance
    slam_occupied: int
    true_surface_observed: int


def _dilate(mask: np.ndarray, cells: int) -> np.ndarray:
    """Chebyshev dilation by `cells` (a (2 cells + 1)^2 square), in numpy."""
    out = mask.copy()
    padded = np.pad(mask, cells)
    h, w = mask.shape
    for dy in range(2 * cells + 1):
        for dx in range(2 * cells + 1):
            out |= padded[dy : dy + h, dx : dx + w]
    return out


def _on_grid(
    data: np.ndarray, origin, resolution: float, x: np.ndarray, y: np.ndarray, outside: int = -1
) -> np.ndarray:
    """Values of grid `data` at world points (x, y) (cell lookup; `outside` beyond it)."""
    col = np.floor((x - origin[0]) / resolution).astype(np.int64)
    row = np.floor((y - origin[1]) / resolution).astype(np.int64)
    ok = (row >= 0) & (row < data.shape[0]) & (col >= 0) & (col < data.shape[1])
    out = np.full(x.shape, outside, data.dtype)
    out[ok] = data[row[ok], col[ok]]
    return out


@njit(cache=True)
def _first_hits(occupied, ox, oy, resolution, px, py, max_range, n_rays, out):
    """Mark in `out` the first occupied cell along each of n_rays rays (evenly spread over 360
    deg) from every point (px, py), up to max_range (exact cell traversal, Amanatides-Woo)."""
    rows, cols = occupied.shape
    for k in range(px.shape[0]):
        x0, y0 = (px[k] - ox) / resolution, (py[k] - oy) / resolution
        for r in range(n_rays):
            a = 2.0 * np.pi * r / n_rays
            dx, dy = np.cos(a), np.sin(a)
            cx, cy = int(np.floor(x0)), int(np.floor(y0))
            sx = 1 if dx > 0 else -1
            sy = 1 if dy > 0 else -1
            tdx = abs(1.0 / dx) if dx != 0 else 1e300
            tdy = abs(1.0 / dy) if dy != 0 else 1e300
            tx = ((cx + 1 - x0) if dx > 0 else (x0 - cx)) * tdx
            ty = ((cy + 1 - y0) if dy > 0 else (y0 - cy)) * tdy
            limit = max_range / resolution
            while True:
                if not (0 <= cx < cols and 0 <= cy < rows):
                    break
                if occupied[cy, cx]:
                    out[cy, cx] = True
                    break
                if tx < ty:
                    if tx > limit:
                        break
                    tx += tdx
                    cx += sx
                else:
                    if ty > limit:
                        break
                    ty += tdy
                    cy += sy


def visible_cells(
    truth: np.ndarray, truth_origin, resolution: float, positions: np.ndarray, max_range: float
) -> np.ndarray:
    """Occupied cells of `truth` in line of sight of any of the (k, 2) sensor positions within
    max_range: the first occupied cell along rays spread finely enough (a quarter cell apart at
    max_range) that every cell face a laser could hit from there is found."""
    occupied = np.ascontiguousarray(np.asarray(truth) == 100)
    positions = np.asarray(positions, float).reshape(-1, 2)
    n_rays = int(np.ceil(2.0 * np.pi * max_range / (0.25 * resolution)))
    out = np.zeros(occupied.shape, np.bool_)
    _first_hits(
        occupied,
        float(truth_origin[0]),
        float(truth_origin[1]),
        float(resolution),
        np.ascontiguousarray(positions[:, 0]),
        np.ascontiguousarray(positions[:, 1]),
        float(max_range),
        n_rays,
        out,
    )
    return out


def map_score(
    slam: np.ndarray,
    slam_origin,
    truth: np.ndarray,
    truth_origin,
    resolution: float,
    tolerance: int = 1,
    visible: np.ndarray | None = None,
) -> MapScore:
    """Occupied-cell precision and recall of a SLAM grid against a ground-truth grid of the same
    resolution (int8: 100 occupied, 0 free, -1 unknown; origins = world (x, y) of cell (0, 0)'s
    corner), with `tolerance` cells of slack (Chebyshev).

    Precision counts every occupied SLAM cell. Recall counts the true cells a laser can see and
    the robot could have seen: occupied cells next to true free space (a wall's faces, not its
    inside) that the SLAM map observed, i.e. with a known SLAM cell within the tolerance (rooms
    never entered or seen through a door do not count against the map). `visible` (a mask on the
    truth grid, e.g. visible_cells from the sensor's path) further keeps only the faces in line
    of sight of the path: a slot too narrow to look into, or the far side of a pillar, is next
    to observed cells but no beam can reach it."""
    slam, truth = np.asarray(slam), np.asarray(truth)
    # precision: SLAM occupied cells, looked up in the dilated truth
    rows, cols = np.nonzero(slam == 100)
    x = slam_origin[0] + (cols + 0.5) * resolution
    y = slam_origin[1] + (rows + 0.5) * resolution
    near_truth = _dilate(truth == 100, tolerance).astype(np.int8)
    precision = (
        float(_on_grid(near_truth, truth_origin, resolution, x, y, 0).mean()) if len(x) else float("nan")
    )
    # recall: the truth's wall faces that the SLAM map observed
    surface = (truth == 100) & _dilate(truth == 0, 1)
    if visible is not None:
        surface &= np.asarray(visible, bool)
    rows, cols = np.nonzero(surface)
    x = truth_origin[0] + (cols + 0.5) * resolution
    y = truth_origin[1] + (rows + 0.5) * resolution
    known = _on_grid(_dilate(slam >= 0, tolerance).astype(np.int8), slam_origin, resolution, x, y, 0) == 1
    hit = _on_grid(_dilate(slam == 100, tolerance).astype(np.int8), slam_origin, resolution, x, y, 0) == 1
    recall = float(hit[known].mean()) if known.any() else float("nan")
    return MapScore(precision, recall, int((slam == 100).sum()), int(known.sum()))
