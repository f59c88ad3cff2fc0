"""Global planners on synthetic maps: grid A* against SciPy's Dijkstra on the same graph (a
maze and a cost-weighted map), OMPL paths collision-free pose by pose (footprint polygon against
lethal cells, tested with matplotlib's point-in-polygon, independent of the planner's own
checker), and OMPL's path length against the grid optimum."""

from __future__ import annotations

import math

import numpy as np
import pytest
from matplotlib.path import Path as MplPath
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from twil_control.navigation import costmap as cm
from twil_control.navigation import grid_planner as gp
from twil_control.navigation import ompl_planner as op
from twil_control.navigation import synthetic_maps
from twil_control.navigation.footprint import FootprintCells, parse_footprint, radii, transform

pytestmark = pytest.mark.kernels

RES = 0.05
FOOTPRINT = parse_footprint([[0.305, 0.199], [-0.305, 0.199], [-0.305, -0.199], [0.305, -0.199]])


def _scipy_cost(costs, start, goal, cost_factor, lethal=cm.INSCRIBED):
    """The same 8-connected graph (no corner cutting) solved by SciPy's Dijkstra."""
    h, w = costs.shape
    ok = costs < lethal
    rows, cols, wts = [], [], []
    for dr, dc in ((0, 1), (1, 0), (1, 1), (1, -1), (0, -1), (-1, 0), (-1, -1), (-1, 1)):
        r0, c0 = np.nonzero(ok)
        r1, c1 = r0 + dr, c0 + dc
        inb = (r1 >= 0) & (r1 < h) & (c1 >= 0) & (c1 < w)
        r0, c0, r1, c1 = r0[inb], c0[inb], r1[inb], c1[inb]
        good = ok[r1, c1]
        if dr and dc:
            good &= ok[r0, c1] & ok[r1, c0]
        r0, c0, r1, c1 = r0[good], c0[good], r1[good], c1[good]
        step = math.sqrt(2) if dr and dc else 1.0
        rows.append(r0 * w + c0)
        cols.append(r1 * w + c1)
        wts.append(step * (1 + cost_factor * (costs[r0, c0].astype(float) + costs[r1, c1]) / 504.0))
    g = coo_matrix(
        (np.concatenate(wts), (np.concatenate(rows), np.concatenate(cols))), shape=(h * w, h * w)
    ).tocsr()
    return dijkstra(g, indices=start[0] * w + start[1])[goal[0] * w + goal[1]]


def test_astar_is_optimal_on_a_maze():
    occ = synthetic_maps.maze(8, 10, seed=3)
    costs = cm.occupancy_to_cost(occ)
    start, goal = (5, 5), (75, 75)
    cells, total = gp.plan_cells(costs, start, goal, cost_factor=0.0)
    assert abs(total - _scipy_cost(costs, start, goal, 0.0)) < 1e-9
    assert tuple(cells[0]) == start and tuple(cells[-1]) == goal
    steps = np.abs(np.diff(cells, axis=0))
    assert steps.max() == 1 and (costs[cells[:, 0], cells[:, 1]] < cm.INSCRIBED).all()
    assert total > 2.5 * 70 * math.sqrt(2)  # the maze forces a detour (the diagonal is 99 cells)


def test_astar_is_optimal_with_cost_weighting():
    costs = cm.inflate(cm.occupancy_to_cost(synthetic_maps.house(0.1)), 0.1, 0.2, 3.0, 1.0)
    start, goal = (30, 40), (80, 100)
    _, total = gp.plan_cells(costs, start, goal, cost_factor=3.0)
    assert abs(total - _scipy_cost(costs, start, goal, 3.0)) < 1e-9


def test_astar_reports_blocked_and_disconnected_cells():
    costs = np.zeros((20, 20), np.uint8)
    costs[:, 10] = cm.LETHAL
    with pytest.raises(gp.NoPathError, match="not connected"):
        gp.plan_cells(costs, (5, 5), (5, 15))
    with pytest.raises(gp.NoPathError, match="goal cell .* has cost 254"):
        gp.plan_cells(costs, (5, 5), (5, 10))


def _house():
    occ = synthetic_maps.house(RES)
    costs = cm.inflate(cm.occupancy_to_cost(occ), RES, radii(FOOTPRINT)[0], 10.0, 0.55)
    m = cm.Costmap(occ.shape[1], occ.shape[0], RES, 0.0, 0.0)
    m.costs = costs
    return m


def _collision_free(m: cm.Costmap, poses: np.ndarray) -> np.ndarray:
    """Independent check: no lethal cell centre inside the footprint polygon at any pose."""
    rr, cc = np.nonzero(m.costs == cm.LETHAL)
    xs, ys = m.cell_to_world(rr, cc)
    pts = np.column_stack([xs, ys])
    free = []
    for x, y, yaw in poses:
        near = np.hypot(pts[:, 0] - x, pts[:, 1] - y) < 0.5
        free.append(not MplPath(transform(FOOTPRINT, x, y, yaw)).contains_points(pts[near]).any())
    return np.array(free)


START, GOAL = (1.0, 3.0, 0.0), (10.5, 8.0, 0.0)


def _grid_optimum(m):
    s, g = m.world_to_cell(START[0], START[1]), m.world_to_cell(GOAL[0], GOAL[1])
    return gp.plan_cells(m.costs, (int(s[0]), int(s[1])), (int(g[0]), int(g[1])), cost_factor=0.0)[1] * RES


@pytest.mark.parametrize("space", ["R2", "SE2"])
def test_ompl_paths_are_collision_free_pose_by_pose(space):
    m = _house()
    cells = FootprintCells(FOOTPRINT, RES)
    result = op.plan(
        m,
        cells,
        START,
        GOAL,
        op.OmplSettings(planner="RRTConnect", state_space=space, planning_time=600.0),
        seed=1,
    )
    assert result.poses is not None, result.status
    assert (
        np.hypot(*(result.poses[0, :2] - START[:2])) < 1e-9
        and np.hypot(*(result.poses[-1, :2] - GOAL[:2])) < 1e-9
    )
    assert np.abs(np.diff(result.poses[:, :2], axis=0)).max() <= 0.05 + 1e-9
    assert _collision_free(m, result.poses).all()


# iteration budgets (not time: the result must not depend on the machine's speed) at which the
# seeded planners have converged on this problem
ITERATIONS = {"RRTstar": 8000, "InformedRRTstar": 8000, "BITstar": 4000}


@pytest.mark.parametrize("planner", list(ITERATIONS))
def test_optimising_planners_come_within_15_percent_of_the_grid_optimum(planner):
    m = _house()
    cells = FootprintCells(FOOTPRINT, RES)
    settings = op.OmplSettings(
        planner=planner, objective="length", planning_time=600.0, max_iterations=ITERATIONS[planner]
    )
    result = op.plan(m, cells, START, GOAL, settings, seed=7)
    assert result.poses is not None, result.status
    ratio = result.length / _grid_optimum(m)
    # any-angle paths may be shorter than the 8-connected optimum (by up to 8 %), never much longer
    assert 0.92 < ratio < 1.15, ratio
    assert _collision_free(m, result.poses).all()


def test_seeded_ompl_plans_are_reproducible_and_seeds_matter():
    m = _house()
    cells = FootprintCells(FOOTPRINT, RES)
    settings = op.OmplSettings(planner="RRTConnect", planning_time=600.0, simplify=False)
    a, b, c = (op.plan(m, cells, START, GOAL, settings, seed=s) for s in (3, 3, 4))
    assert a.poses is not None and b.poses is not None and c.poses is not None
    np.testing.assert_array_equal(a.poses, b.poses)
    assert a.poses.shape != c.poses.shape or not np.array_equal(a.poses, c.poses)


def test_max_iterations_is_refused_for_prm_star():
    with pytest.raises(op.OmplPlannerError, match="PRMstar cannot use max_iterations"):
        op.OmplSettings(planner="PRMstar", objective="length", max_iterations=100)


def test_prm_star_refuses_the_python_cost_objective_and_unknown_planners_are_named():
    with pytest.raises(op.OmplPlannerError, match="PRMstar needs objective 'length'"):
        op.OmplSettings(planner="PRMstar", objective="length_and_cost")
    with pytest.raises(op.OmplPlannerError, match="RRTConect.*allowed: RRTConnect"):
        op.OmplSettings(planner="RRTConect")


def test_ompl_reports_no_path_to_a_walled_off_half():
    m = _house()
    m.costs[:, 120] = cm.LETHAL  # a wall at x = 6.0 across the whole house, hall included
    cells = FootprintCells(FOOTPRINT, RES)
    result = op.plan(m, cells, START, GOAL, op.OmplSettings(planner="RRTConnect", planning_time=0.3), seed=1)
    assert result.poses is None and math.isinf(result.length)


@pytest.mark.parametrize("objective", ["length", "length_and_cost"])
def test_a_planner_is_freed_once_dropped(objective):
    # OMPL keeps the validity checker and the motion validator in C++, out of the garbage
    # collector's sight: a callback leading back to the Planner made a cycle that was never
    # freed, so move_base leaked a Planner (with its costmap snapshot) at every planning call
    import gc
    import weakref

    m = _house()
    planner = op.Planner(
        m,
        FootprintCells(FOOTPRINT, RES),
        op.OmplSettings(planner="RRTConnect", objective=objective, planning_time=600.0),
        seed=1,
    )
    assert planner.solve(START, GOAL).poses is not None
    alive = weakref.ref(planner)
    del planner
    gc.collect()
    assert alive() is None


def test_segment_mean_cost_equals_the_mean_over_linspace_points_bit_for_bit():
    # the cost objective's per-edge mean, compiled (RRT* asks it of every candidate edge),
    # against the definition: costs at np.linspace(0, 1, n) along the segment, unknown as 0,
    # points outside the map on the padded border; random segments, some leaving the map
    from twil_control.navigation.collision import GridChecker

    m = _house()
    m.costs[40:60, 40:60] = cm.NO_INFORMATION
    checker = GridChecker(m, FootprintCells(FOOTPRINT, RES), allow_unknown=True)
    h, w = m.shape
    rng = np.random.default_rng(3)
    lo, hi = np.array(m.origin) - 1.0, np.array(m.origin) + np.array([w, h]) * RES + 1.0
    for _ in range(300):
        (xa, ya), (xb, yb) = rng.uniform(lo, hi), rng.uniform(lo, hi)
        n = max(2, int(math.hypot(xb - xa, yb - ya) / RES) + 1)
        s = np.linspace(0.0, 1.0, n)
        c = np.clip(np.floor((xa + s * (xb - xa) - m.origin[0]) / RES).astype(int), -1, w)
        r = np.clip(np.floor((ya + s * (yb - ya) - m.origin[1]) / RES).astype(int), -1, h)
        inside = (c >= 0) & (c < w) & (r >= 0) & (r < h)
        values = np.full(n, float(cm.NO_INFORMATION))  # the border the checker pads with
        values[inside] = m.costs[r[inside], c[inside]]
        values[values == cm.NO_INFORMATION] = 0.0
        assert checker.segment_mean_cost(xa, ya, xb, yb, n) == values.mean()


def test_informed_planners_with_the_python_objective_warn_once_in_python_not_per_plan(caplog, capfd):
    # the Python cost objective has no cost-to-go heuristic, so InformedRRT* samples uniformly:
    # said once, in the log, instead of OMPL's two stderr lines at every plan
    import logging

    op._uninformed_warned.discard("InformedRRTstar")
    m = _house()
    cells = FootprintCells(FOOTPRINT, RES)
    settings = op.OmplSettings(planner="InformedRRTstar", planning_time=0.2)
    capfd.readouterr()
    with caplog.at_level(logging.WARNING, logger=op.__name__):
        for seed in (1, 2):
            op.plan(m, cells, START, GOAL, settings, seed=seed)
    warned = [r.getMessage() for r in caplog.records if "samples uniformly" in r.getMessage()]
    assert len(warned) == 1 and "InformedRRTstar" in warned[0]
    assert "RejectionInfSampler" not in capfd.readouterr().err
    from ompl import util as ou

    assert ou.getLogLevel() == ou.LOG_WARN  # OMPL's level is back for other plans
