"""Occupied-cell precision and recall of a map against the ground truth (slam_metrics.map_score)."""
from __future__ import annotations

import numpy as np

from twil_control.mapping.slam_metrics import map_score


def _room(n=40):
    """A free square room with 2-cell-thick walls, unknown outside (int8: 100, 0, -1)."""
    g = np.full((n, n), -1, np.int8)
    g[2:-2, 2:-2] = 100
    g[4:-4, 4:-4] = 0
    return g


def test_wall_faces_found_within_one_cell_count_and_unseen_rooms_do_not():
    truth = _room()
    slam = np.full_like(truth, -1)
    slam[4:-4, 4:-4] = 0
    slam[3, 3:-3] = 100              # the inner face of the south wall, seen exactly
    slam[-3, 3:-3] = 100             # north wall: one cell into the wall, within tolerance
    slam[3:-3, 3] = 100
    slam[3:-3, -3] = 100
    slam[20, 20] = 100               # one false obstacle in the room
    s = map_score(slam, (0.0, 0.0), truth, (0.0, 0.0), 0.05)
    occupied = int((slam == 100).sum())
    assert s.slam_occupied == occupied
    np.testing.assert_allclose(s.precision, (occupied - 1) / occupied, rtol=1e-12)
    assert s.recall == 1.0
    # only the walls' inner faces are wall surface (the ring of cells 3 and 36: 4 * 34 - 4 cells);
    # the outer faces border unknown space, not free space
    assert s.true_surface_observed == 4 * 34 - 4


def test_a_map_shifted_by_two_cells_loses_precision_and_recall():
    truth = _room()
    slam = np.roll(_room(), 2, axis=1)
    s = map_score(slam, (0.0, 0.0), truth, (0.0, 0.0), 0.05)
    assert s.precision < 0.8 and s.recall < 0.8
    same = map_score(truth, (0.0, 0.0), truth, (0.0, 0.0), 0.05)
    assert same.precision == 1.0 and same.recall == 1.0
