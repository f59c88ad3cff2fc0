"""The costmap's shortcuts for large maps give the same cells as the general computation: the
static layer copied when the costmap is on its map's grid, inflation only around the lethal
cells, StaticLayer's translation by table. (husky_navigation's gmapping.launch makes a 200 m x
200 m map at 0.05 m, 16 million cells, with a house in a corner of it.)"""

from __future__ import annotations

import math

import numpy as np
import pytest

from twil_control.navigation import costmap as cm

pytestmark = pytest.mark.kernels


def _reference_occupancy_to_cost(v, lethal_threshold, track_unknown, trinary, unknown_value):
    v = np.asarray(v).astype(np.int16)
    cost = (
        np.where(v >= lethal_threshold, cm.LETHAL, cm.FREE)
        if trinary
        else (np.clip(np.round(v / lethal_threshold * cm.LETHAL), 0, cm.LETHAL))
    )
    return np.where(v == unknown_value, cm.NO_INFORMATION if track_unknown else cm.FREE, cost).astype(
        np.uint8
    )


@pytest.mark.parametrize("trinary", [True, False])
@pytest.mark.parametrize("track_unknown", [True, False])
def test_occupancy_to_cost_by_table_is_static_layer_s_translation(trinary, track_unknown):
    values = np.arange(-128, 128, dtype=np.int8).reshape(16, 16)
    for threshold, unknown in ((100, -1), (65, 255 - 256), (50, 0)):
        got = cm.occupancy_to_cost(values, threshold, track_unknown, trinary, unknown)
        assert np.array_equal(
            got, _reference_occupancy_to_cost(values, threshold, track_unknown, trinary, unknown)
        )


def _house_in_a_big_map(rng) -> np.ndarray:
    costs = np.full((600, 700), cm.NO_INFORMATION, np.uint8)
    room = costs[400:520, 80:230]
    room[:] = cm.FREE
    room[rng.random(room.shape) < 0.02] = cm.LETHAL
    room[0, :] = room[-1, :] = room[:, 0] = cm.LETHAL
    return costs


@pytest.mark.parametrize("radius", [0.0, 0.55, 1.0, math.inf])
def test_inflation_around_the_lethal_cells_equals_inflation_of_the_whole_grid(radius):
    costs = _house_in_a_big_map(np.random.default_rng(1))
    got = cm.inflate(costs, 0.05, 0.35, 3.0, radius)
    distance = cm.distance_to_lethal(costs == cm.LETHAL, 0.05)
    inflated = cm.inflation_cost(distance, 0.35, 3.0, radius)
    expected = np.maximum(costs, inflated)
    unknown = costs == cm.NO_INFORMATION
    expected = np.where(unknown & (inflated >= cm.INSCRIBED), inflated, expected)
    assert np.array_equal(got, expected)
    assert np.array_equal(
        cm.inflate(np.zeros((50, 60), np.uint8), 0.05, 0.3, 3.0, radius), np.zeros((50, 60))
    )


@pytest.mark.parametrize(("origin", "shape"), [((0.0, 0.0), (600, 700)), ((-2.5, 3.0), (200, 900))])
def test_a_costmap_on_its_map_s_grid_copies_the_cells(origin, shape):
    rng = np.random.default_rng(2)
    static = rng.integers(0, 256, (600, 700)).astype(np.uint8)
    map_origin = np.array([-10.0, -12.5])
    costmap = cm.Costmap(shape[1], shape[0], 0.05, map_origin[0] + origin[0], map_origin[1] + origin[1])
    fast = cm.sample_static(costmap, static, 0.05, map_origin, 0.0, (0.0, 0.0, 0.0))
    # the general resampling, made to take its own path by a transform of 1e-9 rad
    general = cm.sample_static(costmap, static, 0.05, map_origin, 0.0, (0.0, 0.0, 1e-9))
    assert np.array_equal(fast, general)
