"""Occupied-cell precision and recall of a map against the ground truth (slam_metrics.map_score)."""

from __future__ import annotations

import numpy as np
import pytest

from twil_control.mapping.slam_metrics import map_score, visible_cells

pytestmark = pytest.mark.kernels


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
    slam[3, 3:-3] = 100  # the inner face of the south wall, seen exactly
    slam[-3, 3:-3] = 100  # north wall: one cell into the wall, within tolerance
    slam[3:-3, 3] = 100
    slam[3:-3, -3] = 100
    slam[20, 20] = 100  # one false obstacle in the room
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


def test_visible_cells_are_the_faces_in_line_of_sight_within_range():
    truth = _room()  # 0.05 m cells, free inside cells 4..35
    truth[18:22, 18:22] = 100  # a pillar in the middle
    eye = np.array([[0.5 * 0.05 + 8 * 0.05, 20.5 * 0.05]])  # west of the pillar, on its axis
    vis = visible_cells(truth, (0.0, 0.0), 0.05, eye, max_range=5.0)
    assert vis[18:22, 18].all() and not vis[18:22, 19:22].any()  # the near face only
    assert (
        not vis[19:21, 36].any() and vis[4:8, 36].all()
    )  # east wall: hidden behind the pillar, seen past it
    assert vis[4:36, 3].all()  # the west wall, in plain sight
    short = visible_cells(truth, (0.0, 0.0), 0.05, eye, max_range=0.3)  # 6 cells
    assert short[20, 3] and not short[18:22, 18].any()  # the pillar is 10 cells away
    # a face hidden from the path does not count against the recall
    slam = truth.copy()
    slam[18:22, 21] = 0  # the pillar's far face missing
    assert map_score(slam, (0.0, 0.0), truth, (0.0, 0.0), 0.05, tolerance=0).recall < 1.0
    assert map_score(slam, (0.0, 0.0), truth, (0.0, 0.0), 0.05, tolerance=0, visible=vis).recall == 1.0
