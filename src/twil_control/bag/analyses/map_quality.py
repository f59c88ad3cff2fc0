"""Occupancy-grid comparison: precision and recall of occupied cells within a tolerance.

Pure (numpy, scipy.ndimage). A cell is occupied at >= `occupied` (65, as map_server's default
occupied_thresh reads a grid), -1 unknown; `recall_observed` counts only reference cells the map
has observed, so unexplored parts of the world do not count against it (docs/analyze.md).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from ..signals import compose, inverse

OCCUPIED = 65


def cell_centres(mask: np.ndarray, resolution: float, origin) -> np.ndarray:
    """(K, 2) frame coordinates of the centres of the cells where mask is set."""
    r, c = np.nonzero(mask)
    local = np.stack([(c + 0.5) * resolution, (r + 0.5) * resolution, np.zeros(len(r))], axis=-1)
    return compose(np.asarray(origin, float), local)[:, :2]


def near(points, mask: np.ndarray, resolution: float, origin, tol: int) -> np.ndarray:
    """For each point (frame coordinates): is a set cell of mask within tol cells of its cell?"""
    if len(points) == 0:
        return np.zeros(0, bool)
    grown = (
        ndimage.binary_dilation(mask, structure=np.ones((2 * tol + 1, 2 * tol + 1), bool)) if tol else mask
    )
    pts = np.concatenate([np.asarray(points, float), np.zeros((len(points), 1))], axis=1)
    local = compose(inverse(np.asarray(origin, float)), pts)
    col = np.floor(local[:, 0] / resolution).astype(int)
    row = np.floor(local[:, 1] / resolution).astype(int)
    inside = (row >= 0) & (row < mask.shape[0]) & (col >= 0) & (col < mask.shape[1])
    out = np.zeros(len(points), bool)
    out[inside] = grown[row[inside], col[inside]]
    return out


def compare_grids(
    map_data,
    map_res,
    map_origin,
    ref_data,
    ref_res,
    ref_origin,
    T_ref_map=(0, 0, 0),
    tol: int = 1,
    occupied: int = OCCUPIED,
) -> dict:
    """Precision and recall of the map's occupied cells against a reference grid.

    T_ref_map: pose of the map's frame in the reference's frame (planar)."""
    map_data, ref_data = np.asarray(map_data), np.asarray(ref_data)
    map_occ, ref_occ = map_data >= occupied, ref_data >= occupied
    map_origin_in_ref = compose(np.asarray(T_ref_map, float), np.asarray(map_origin, float))
    map_pts = cell_centres(map_occ, map_res, map_origin_in_ref)
    ref_pts = cell_centres(ref_occ, ref_res, ref_origin)
    tp_map = near(map_pts, ref_occ, ref_res, ref_origin, tol)
    found = near(ref_pts, map_occ, map_res, map_origin_in_ref, tol)
    observed = near(ref_pts, map_data >= 0, map_res, map_origin_in_ref, tol)
    return {
        "map_occupied_cells": int(map_occ.sum()),
        "reference_occupied_cells": int(ref_occ.sum()),
        "precision": float(tp_map.mean()) if len(tp_map) else None,
        "recall": float(found.mean()) if len(found) else None,
        "recall_observed": float(found[observed].mean()) if observed.any() else None,
        "tolerance_cells": tol,
    }


def distance_field(data, resolution: float, occupied: int = OCCUPIED) -> np.ndarray:
    """Distance (m) from each cell centre to the nearest occupied cell centre."""
    occ = np.asarray(data) >= occupied
    if not occ.any():
        return np.full(occ.shape, np.inf)
    return ndimage.distance_transform_edt(~occ) * resolution


def sample(field: np.ndarray, resolution: float, origin, points) -> np.ndarray:
    """Values of a grid field at points (frame coordinates); NaN outside the grid."""
    pts = np.concatenate([np.asarray(points, float), np.zeros((len(points), 1))], axis=1)
    local = compose(inverse(np.asarray(origin, float)), pts)
    col = np.floor(local[:, 0] / resolution).astype(int)
    row = np.floor(local[:, 1] / resolution).astype(int)
    inside = (row >= 0) & (row < field.shape[0]) & (col >= 0) & (col < field.shape[1])
    out = np.full(len(points), np.nan)
    out[inside] = field[row[inside], col[inside]]
    return out
