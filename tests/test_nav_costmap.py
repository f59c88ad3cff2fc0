"""costmap_2d's layers on synthetic grids: inflation against costmap_2d's cost function and
brute-force distances, the OccupancyGrid translation, obstacle marking and clearing, the rolling
window, the static layer's resampling, and the two parameter styles."""

from __future__ import annotations

import copy
import logging
import math

import numpy as np
import pytest

from twil_control.core.node import Master, Node
from twil_control.navigation import costmap as cm
from twil_control.navigation.layered_costmap import LayerConfig, LayeredCostmap, Observation, StaticMap
from twil_control.nodes.costmap_ros import load_costmap_params

pytestmark = pytest.mark.kernels

RES = 0.05
FOOTPRINT = np.array([[0.305, 0.199], [-0.305, 0.199], [-0.305, -0.199], [0.305, -0.199]])


def _brute_distance(lethal: np.ndarray, res: float) -> np.ndarray:
    rr, cc = np.nonzero(lethal)
    ii, jj = np.indices(lethal.shape)
    d2 = (ii[..., None] - rr) ** 2 + (jj[..., None] - cc) ** 2
    return np.sqrt(d2.min(axis=-1)) * res


def test_distance_transform_is_exact_euclidean_to_1e_9():
    rng = np.random.default_rng(1)
    lethal = rng.random((50, 60)) < 0.02
    assert np.abs(cm.distance_to_lethal(lethal, RES) - _brute_distance(lethal, RES)).max() < 1e-9


def test_inflated_costs_follow_costmap_2d_cost_function():
    rng = np.random.default_rng(2)
    costs = np.where(rng.random((50, 60)) < 0.01, cm.LETHAL, cm.FREE).astype(np.uint8)
    r_in, k, r_infl = 0.199, 10.0, 0.55
    out = cm.inflate(costs, RES, r_in, k, r_infl)
    d = _brute_distance(costs == cm.LETHAL, RES)
    # costmap_2d InflationLayer::computeCost, written out independently
    expect = np.zeros_like(d)
    for idx, di in np.ndenumerate(d):
        if di == 0:
            expect[idx] = 254
        elif di <= r_in:
            expect[idx] = 253
        elif di <= r_infl:
            expect[idx] = math.floor(252 * math.exp(-k * (di - r_in)))
    assert np.array_equal(out, expect.astype(np.uint8))
    # the float form before truncation matches the formula to 1e-9 at the measured distances
    ring = (d > r_in) & (d <= r_infl)
    f = 252 * np.exp(-k * (cm.distance_to_lethal(costs == cm.LETHAL, RES)[ring] - r_in))
    assert np.abs(f - 252 * np.exp(-k * (d[ring] - r_in))).max() < 1e-9
    assert ring.sum() > 100 and (out[d > r_infl] == 0).all()


@pytest.mark.parametrize("stamp_per_cell", [0.0, math.inf], ids=["distance-transform", "kernel-stamps"])
def test_inflation_by_table_equals_the_cost_of_each_cells_distance(monkeypatch, stamp_per_cell):
    """inflate() reads costs from a table by squared cell distance, through a distance transform
    or by stamping a kernel around each lethal cell: either way cell for cell the same costs
    as inflation_cost(distance_to_lethal(...)) combined by costmap_2d's rule, over random grids
    (unknown cells, grids without obstacles, resolutions whose radius is no whole cell count)."""
    monkeypatch.setattr(cm, "STAMP_PER_CELL", stamp_per_cell)
    rng = np.random.default_rng(5)
    for trial in range(60):
        h, w = rng.integers(1, 80, 2)
        r = rng.random((h, w))
        costs = np.where(r < 0.2, 50, cm.FREE).astype(np.uint8)
        costs[r < rng.random() * 0.05 * (trial % 10 != 0)] = cm.LETHAL  # every 10th: no obstacle
        costs[r > 0.85] = cm.NO_INFORMATION
        res = float(rng.choice([0.01, 0.025, 0.037, 0.05, 0.1]))
        r_in, k, r_infl = rng.uniform(0, 0.4), rng.uniform(0.5, 20), rng.uniform(0, 1.5)
        inflated = cm.inflation_cost(cm.distance_to_lethal(costs == cm.LETHAL, res), r_in, k, r_infl)
        expect = np.maximum(costs, inflated)
        unknown = costs == cm.NO_INFORMATION
        expect[unknown] = np.where(inflated[unknown] >= cm.INSCRIBED, inflated[unknown], cm.NO_INFORMATION)
        out = cm.inflate(costs, res, r_in, k, r_infl)
        assert out.dtype == np.uint8 and np.array_equal(out, expect), (trial, res, r_in, k, r_infl)


def test_unknown_cells_stay_unknown_unless_inflated_to_inscribed():
    costs = np.full((20, 20), cm.NO_INFORMATION, np.uint8)
    costs[10, 10] = cm.LETHAL
    out = cm.inflate(costs, RES, 0.2, 10.0, 0.55)
    d = _brute_distance(costs == cm.LETHAL, RES)
    assert (out[(d > 0) & (d <= 0.2)] == cm.INSCRIBED).all()
    assert (out[d > 0.2] == cm.NO_INFORMATION).all()


def test_cost_translation_to_occupancy_values():
    table = cm.cost_to_occupancy(np.arange(256, dtype=np.uint8))
    assert table[0] == 0 and table[253] == 99 and table[254] == 100 and table[255] == -1
    assert table[1] == 1 and table[252] == 1 + (97 * 251) // 251
    assert (np.diff(table[1:253].astype(int)) >= 0).all()


def test_static_layer_translation():
    occ = np.array([[0, 50, 100, -1]], np.int8)
    assert cm.occupancy_to_cost(occ).tolist() == [[0, 0, 254, 255]]
    assert cm.occupancy_to_cost(occ, track_unknown=False).tolist() == [[0, 0, 254, 0]]
    assert cm.occupancy_to_cost(occ, lethal_threshold=50).tolist() == [[0, 254, 254, 255]]


def test_obstacle_marking_and_clearing_along_rays():
    grid = cm.Costmap(100, 100, RES, 0.0, 0.0)
    grid.costs[50, 70] = cm.LETHAL  # an old obstacle at (3.525, 2.525), on the ray below
    sensor = (0.5, 2.525, 0.0)
    # one beam straight ahead (+x) hitting at 3.8 m (x 4.3), one at 90 deg hitting at 1.0 m
    ranges = np.array([3.8, 1.0])
    hits, ends = cm.scan_points(ranges, 0.0, math.pi / 2, 0.1, 10.0, sensor)
    cm.update_obstacles(grid, sensor, hits, ends, obstacle_range=3.5, raytrace_range=5.0)
    assert grid.costs[50, 70] == cm.FREE  # cleared by the ray through it
    assert grid.cost_at(4.3, 2.525) == cm.FREE  # beyond obstacle_range: not marked
    assert grid.cost_at(0.5, 3.525) == cm.LETHAL  # marked (1 m < obstacle_range)
    assert (grid.costs == cm.LETHAL).sum() == 1


def test_raytrace_range_limits_clearing():
    grid = cm.Costmap(100, 100, RES, 0.0, 0.0)
    grid.costs[50, 60:90] = cm.LETHAL
    sensor = (0.0, 2.525, 0.0)
    hits, ends = cm.scan_points(np.array([np.inf]), 0.0, 0.1, 0.1, 10.0, sensor)
    cm.update_obstacles(grid, sensor, hits, ends, obstacle_range=3.0, raytrace_range=4.0)
    cleared = np.nonzero(grid.costs[50, 60:90] == cm.FREE)[0] + 60
    assert cleared.min() == 60 and cleared.max() == 79  # up to 4.0 m = column 80, exclusive


def test_rolling_window_keeps_shared_cells_and_forgets_the_rest():
    grid = cm.Costmap(120, 120, RES, -3.0, -3.0)
    grid.costs[grid.world_to_cell(1.0, 1.0)] = cm.LETHAL
    grid.costs[grid.world_to_cell(-2.9, -2.9)] = cm.LETHAL
    grid.recenter(0.52, 0.26)
    assert np.allclose(grid.origin, [-2.5, -2.75])
    assert grid.cost_at(1.0, 1.0) == cm.LETHAL
    assert (grid.costs == cm.LETHAL).sum() == 1  # the corner cell left the window
    assert (grid.costs[-10:, :] == cm.FREE).all()  # new cells take the default


def test_layered_rolling_costmap_samples_the_static_map_through_map_to_odom():
    static = np.zeros((100, 100), np.uint8)
    static[60, 40] = cm.LETHAL  # map cell at (2.025, 3.025)
    lc = LayeredCostmap(
        FOOTPRINT, RES, LayerConfig(obstacles=False, inflation=False), 6.0, 6.0, rolling_window=True
    )
    lc.set_static_map(StaticMap(static, RES, (0.0, 0.0, 0.0)))
    # odom is map shifted by (1, 0.5) and turned 90 deg: map point p = T * odom point
    T = (1.0, 0.5, math.pi / 2)
    costs = lc.update((0.0, 0.0, 0.0), T)
    # the map cell (2.025, 3.025) in odom: R^-1 (p - t) = (2.525, -1.025)
    assert lc.master.cost_at(2.525, -1.025) == cm.LETHAL and (costs == cm.LETHAL).sum() == 1


def _load(params: dict):
    master = Master()
    master.params.set("/move_base/global_costmap", params)
    node = Node(master, "move_base")
    return load_costmap_params(node, "~global_costmap")


def test_pre_layer_and_layered_parameter_styles_give_the_same_layers():
    sensor = {
        "sensor_frame": "base_laser",
        "data_type": "LaserScan",
        "topic": "/scan",
        "marking": True,
        "clearing": True,
    }
    old = _load(
        {
            "static_map": True,
            "obstacle_range": 9.0,
            "raytrace_range": 9.5,
            "inflation_radius": 0.3,
            "observation_sources": "laser",
            "laser": sensor,
        }
    )
    new = _load(
        {
            "plugins": [
                {"name": "static", "type": "costmap_2d::StaticLayer"},
                {"name": "obstacles", "type": "costmap_2d::ObstacleLayer"},
                {"name": "inflation", "type": "costmap_2d::InflationLayer"},
            ],
            "static": {"track_unknown_space": False},
            "obstacles": {
                "obstacle_range": 9.0,
                "raytrace_range": 9.5,
                "observation_sources": "laser",
                "laser": sensor,
            },
            "inflation": {"inflation_radius": 0.3},
        }
    )
    assert old.layers == new.layers
    assert old.sources == new.sources


def test_unknown_sensor_key_is_a_warning_and_unknown_layer_type_an_error(caplog):
    # costmap_2d ignores a key it does not read (a warning here, the source keeps its default
    # topic); a layer type it cannot load stays an error
    with caplog.at_level(logging.WARNING):
        setup = _load({"observation_sources": "laser", "laser": {"topik": "/scan"}})
    assert setup.sources["laser"].topic == ""
    assert any(
        "unknown parameter '/move_base/global_costmap/laser/topik' (did you mean 'topic'?) "
        "is ignored, as costmap_2d ignores" in r.getMessage()
        for r in caplog.records
    )
    with pytest.raises(ValueError, match="costmap_2d::Nope.*allowed"):
        _load({"plugins": [{"name": "x", "type": "costmap_2d::Nope"}]})


@pytest.mark.parametrize(
    "params, message",
    [
        ({"inflation_radius": float("nan")}, r"inflation_radius must be >= 0 m .*got nan"),
        ({"inflation_radius": -0.1}, r"inflation_radius must be >= 0 m .*got -0.1"),
        ({"cost_scaling_factor": -2.0}, r"cost_scaling_factor must be a finite number >= 0 \(got -2.0\)"),
        (
            {
                "plugins": [{"name": "inflation", "type": "costmap_2d::InflationLayer"}],
                "inflation": {"cost_scaling_factor": float("inf")},
            },
            r"cost_scaling_factor must be .*got inf",
        ),
    ],
)
def test_inflation_numbers_that_make_no_costmap_are_errors_naming_the_parameter(params, message):
    with pytest.raises(ValueError, match=message):
        _load(params)


def test_an_infinite_inflation_radius_inflates_the_whole_grid():
    costs = np.zeros((30, 40), np.uint8)
    costs[3, 5] = cm.LETHAL
    out = cm.inflate(costs, RES, 0.1, 0.5, math.inf)
    d = _brute_distance(costs == cm.LETHAL, RES)
    expect = np.where(
        d == 0, cm.LETHAL, np.where(d <= 0.1, cm.INSCRIBED, np.floor(252 * np.exp(-0.5 * (d - 0.1))))
    )
    assert np.array_equal(out, expect.astype(np.uint8)) and out.min() > 0


def test_global_costmap_rebuilds_only_what_changed_with_the_same_cells_as_a_full_update(monkeypatch):
    """A global costmap's update rebuilds only the cells within the inflation radius of what the
    obstacle layer changed: after each of 40 scans from random poses (marking and clearing,
    footprint clearing, a clear_costmap reset, a new map), cell for cell the costs of an update
    that rebuilds the whole grid."""
    windows = []
    rebuild = LayeredCostmap._recomputed
    monkeypatch.setattr(LayeredCostmap, "_recomputed", lambda lc, *a: windows.append(a[1]) or rebuild(lc, *a))
    rng = np.random.default_rng(3)
    static = np.zeros((160, 200), np.uint8)
    static[40:44, 30:120] = cm.LETHAL
    config = LayerConfig(inflation_radius=0.3, cost_scaling_factor=5.0, track_unknown_space=True)
    lc = LayeredCostmap(FOOTPRINT, RES, config)
    lc.set_static_map(StaticMap(static, RES, (-1.0, -1.0, 0.0)))
    for step in range(40):
        pose = (rng.uniform(0, 8), rng.uniform(0, 6), rng.uniform(-np.pi, np.pi))
        ranges = rng.uniform(0.2, 4.0, 90)
        ranges[rng.random(90) < 0.1] = np.inf
        lc.add_observation(Observation(pose, ranges, -np.pi, 2 * np.pi / 90, 0.1, 3.5, stamp=step))
        if step == 25:
            lc.reset_beyond(pose[0], pose[1], 3.0)
        if step == 30:
            lc.set_static_map(StaticMap(static[::-1].copy(), RES, (-1.0, -1.0, 0.0)))
        full = copy.deepcopy(lc)
        full._last = None
        assert np.array_equal(lc.update(pose), full.update(pose)), step
    # every update but the first and the new map's rebuilt a part, most of them a small one
    assert len(windows) == 38
    sizes = sorted((w[0].stop - w[0].start) * (w[1].stop - w[1].start) for w in windows)
    assert sizes[len(sizes) // 2] < 0.6 * static.size
