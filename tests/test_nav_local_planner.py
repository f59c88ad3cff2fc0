"""TrajectoryPlanner: a positive min_vel_theta as ROS takes it, acceleration limits on every command, reaching a
goal in a kinematic rollout on a free grid and past an obstacle, stopping when boxed in."""

from __future__ import annotations

import math

import numpy as np
import pytest

from twil_control.navigation import costmap as cm
from twil_control.navigation import local_planner as lp
from twil_control.navigation.dwa_planner import DWAParams, DWAPlanner
from twil_control.navigation.footprint import FootprintCells, parse_footprint

pytestmark = pytest.mark.kernels

RES = 0.05
FOOTPRINT = parse_footprint([[0.305, 0.199], [-0.305, 0.199], [-0.305, -0.199], [0.305, -0.199]])


def _params(**kw):
    base = dict(
        max_vel_x=0.45,
        min_vel_x=0.1,
        max_vel_theta=2.0,
        min_vel_theta=-2.0,
        min_in_place_vel_theta=1.0,
        acc_lim_theta=3.2,
        acc_lim_x=2.5,
        xy_goal_tolerance=0.2,
        yaw_goal_tolerance=0.2,
        latch_xy_goal_tolerance=True,
        holonomic_robot=False,
        dwa=False,
    )
    base.update(kw)
    return lp.TrajectoryParams(**base)


def _controller(p, period=0.05):
    return lp.LocalController(lp.TrajectoryPlanner(p, FootprintCells(FOOTPRINT, RES), period))


def test_a_positive_min_vel_theta_forbids_right_turns_as_in_ros():
    # the original qbot file's 0.5: valid ROS, so accepted (move_base warns), and used as
    # TrajectoryPlanner uses it: rotational velocities are sampled in [0.5, max_vel_theta]
    p = _params(min_vel_theta=0.5, rotate_to_heading_threshold=0.3)
    ctl = _controller(p)
    pose, vel, period = np.zeros(3), np.zeros(2), 0.05
    s = np.linspace(0, 1, 100)
    plan = np.column_stack([2.0 * s, -2.0 * s, np.full(100, -math.pi / 2)])  # a goal on the right
    turns = []
    for _ in range(200):
        m = cm.Costmap(120, 120, RES, pose[0] - 3, pose[1] - 3)
        v, w = ctl.compute(m, pose, vel, plan, period).cmd
        turns.append(w)
        pose = pose + np.array([v * math.cos(pose[2]) * period, v * math.sin(pose[2]) * period, w * period])
        vel = np.array([v, w])
    assert min(turns) >= 0.0 and max(turns) >= 0.5  # never right, left to turn at all
    with pytest.raises(lp.LocalPlannerError, match=r"min_vel_theta \(2.5\) must be <= max_vel_theta"):
        lp.TrajectoryParams(min_vel_theta=2.5, max_vel_theta=2.0)


def _drive(pose, goal_xy_yaw, obstacles=(), steps=800, period=0.05, **kw):
    """Closed loop: local costmap (rolling 6 m window, inflated) around a unicycle robot."""
    p = _params(**kw)
    ctl = _controller(p)
    pose, vel = np.array(pose, float), np.zeros(2)
    gx, gy, gyaw = goal_xy_yaw
    n = 100
    s = np.linspace(0, 1, n)
    plan = np.column_stack([pose[0] + s * (gx - pose[0]), pose[1] + s * (gy - pose[1]), np.full(n, gyaw)])
    if obstacles:  # a detour plan around the obstacle: via the waypoint given last
        wx, wy = obstacles[-1]
        a = np.column_stack([pose[0] + s * (wx - pose[0]), pose[1] + s * (wy - pose[1])])
        b = np.column_stack([wx + s * (gx - wx), wy + s * (gy - wy)])
        xy = np.vstack([a, b])
        plan = np.column_stack([xy, np.full(len(xy), gyaw)])
    accel_ok = True
    for k in range(steps):
        m = cm.Costmap(120, 120, RES, pose[0] - 3, pose[1] - 3)
        for x0, y0, x1, y1 in obstacles[:-1]:
            r0, c0 = m.world_to_cell(x0, y0)
            r1, c1 = m.world_to_cell(x1, y1)
            m.costs[max(r0, 0) : max(r1, 0), max(c0, 0) : max(c1, 0)] = cm.LETHAL
        m.costs = cm.inflate(m.costs, RES, 0.199, 10.0, 0.55)
        out = ctl.compute(m, pose, vel, plan, period)
        if out.goal_reached:
            return k * period, pose, accel_ok, out
        v, w = out.cmd
        accel_ok &= (
            abs(v - vel[0]) <= p.acc_lim_x * period + 1e-9
            and abs(w - vel[1]) <= p.acc_lim_theta * period + 1e-9
        )
        accel_ok &= p.min_vel_theta - 1e-9 <= w <= p.max_vel_theta + 1e-9 and v <= p.max_vel_x + 1e-9
        pose = pose + np.array([v * math.cos(pose[2]) * period, v * math.sin(pose[2]) * period, w * period])
        vel = np.array([v, w])
    return None, pose, accel_ok, out


def test_reaches_a_goal_behind_it_on_a_free_grid_within_the_acceleration_limits():
    t, pose, accel_ok, out = _drive((0.0, 0.0, math.pi), (3.0, 1.0, math.pi / 2))
    assert t is not None, pose
    assert math.hypot(pose[0] - 3.0, pose[1] - 1.0) <= 0.2 + 1e-9
    assert abs(math.remainder(pose[2] - math.pi / 2, 2 * math.pi)) <= 0.2 + 1e-9
    assert accel_ok and out.cmd == (0.0, 0.0)


def test_goes_around_an_obstacle_following_the_plan():
    box = (1.2, -0.4, 1.8, 0.4)  # a 0.6 x 0.8 m box on the straight line
    t, pose, accel_ok, _ = _drive((0.0, 0.0, 0.0), (3.0, 0.0, 0.0), obstacles=(box, (1.5, 1.0)))
    assert t is not None and accel_ok


def test_boxed_in_robot_without_an_escape_velocity_gets_no_valid_command():
    # escape_vel 0: no backing out (with a negative one it backs out, tests/test_nav_escape.py)
    p = _params(escape_vel=0.0)
    ctl = _controller(p)
    m = cm.Costmap(120, 120, RES, -3, -3)
    r, c = np.indices(m.shape)
    x, y = m.cell_to_world(r, c)
    m.costs[(np.abs(x) < 0.45) & (np.abs(y) < 0.3) & ~((np.abs(x) < 0.4) & (np.abs(y) < 0.25))] = cm.LETHAL
    plan = np.column_stack([np.linspace(0, 2, 50), np.zeros(50), np.zeros(50)])
    out = ctl.compute(m, (0.0, 0.0, 0.0), (0.0, 0.0), plan, 0.05)
    assert not out.valid and out.cmd == (0.0, 0.0)


def test_rotate_to_heading_turns_in_place_until_aligned_then_drives():
    """With rotate_to_heading_threshold the robot never drives while its heading is off the plan by
    more than the threshold (a skid-steer robot's arcs barely turn)."""
    p = _params(rotate_to_heading_threshold=0.3)
    ctl = _controller(p)
    m = cm.Costmap(120, 120, RES, -3, -3)
    plan = np.column_stack([np.zeros(60), np.linspace(0, 2.5, 60), np.full(60, math.pi / 2)])
    pose, vel = np.array([0.0, 0.0, 0.0]), np.zeros(2)
    for _ in range(100):
        out = ctl.compute(m, pose, vel, plan, 0.05)
        v, w = out.cmd
        if abs(math.remainder(math.pi / 2 - pose[2], 2 * math.pi)) > 0.3 + 0.2:
            assert v == 0.0
        pose = pose + np.array([v * math.cos(pose[2]) * 0.05, v * math.sin(pose[2]) * 0.05, w * 0.05])
        vel = np.array([v, w])
    assert abs(math.remainder(math.pi / 2 - pose[2], 2 * math.pi)) <= 0.3 + 0.2 and pose[1] > 0.3


def test_rollouts_ramp_from_the_current_velocity_to_the_sample():
    # from rest towards 0.2 m/s at 1 m/s^2: 0.2 s of ramp, then 0.8 s at 0.2 m/s: 0.02 + 0.16 m
    traj = lp.rollout(
        (0.0, 0.0, 0.0),
        (0.0, 0.0),
        np.array([[0.2, 0.0], [0.0, 0.5]]),
        1.0,
        0.005,
        0.005,
        acc_x=1.0,
        acc_th=1.0,
    )
    assert traj[0, -1, 0] == pytest.approx(0.18, abs=0.002)
    assert traj[1, -1, 2] == pytest.approx(0.5 - 0.125, abs=0.003)  # 0.5 s of ramp to 0.5 rad/s
    # at constant velocity (DWAPlanner's use_dwa): the sample throughout
    traj = lp.rollout((0.0, 0.0, 0.0), (0.1, 0.0), np.array([[0.2, 0.0]]), 1.0, 0.005, 0.005)
    assert traj[0, -1, 0] == pytest.approx(0.2, abs=1e-9)


def test_samples_are_scored_straight_line_first_for_each_speed_as_trajectory_planner_orders_them():
    p = _params(vx_samples=3, vtheta_samples=5, dwa=True)
    s = lp.sample_velocities(p, 0.2, -1.0, 0.05)
    per_vx = p.vtheta_samples  # the straight line, then vtheta_samples - 1 rates, as upstream
    _, _, th_min, th_max = lp.velocity_window(p, 0.2, -1.0, 0.05)
    for k in range(p.vx_samples):
        block = s[k * per_vx : (k + 1) * per_vx]
        assert block[0, 1] == 0.0 and np.all(block[:, 0] == block[0, 0])  # the straight line first
        assert np.all(np.diff(block[1:, 1]) > 0)  # then from the most negative
        assert block[1, 1] == pytest.approx(th_min) and block[-1, 1] < th_max  # the top rate left out


def test_forward_speed_is_capped_by_the_final_goals_distance_over_sim_time_as_upstream():
    p = _params(vx_samples=3, vtheta_samples=5, dwa=True, min_vel_x=0.1, max_vel_x=0.5, sim_time=2.0)
    s = lp.sample_velocities(p, 0.2, 0.0, 0.05, goal_dist=0.4)
    assert s[:, 0].max() == pytest.approx(0.2)  # 0.4 m / 2 s
    s = lp.sample_velocities(p, 0.2, 0.0, 0.05, goal_dist=0.05)
    assert s[s[:, 0] > 0, 0].max() == pytest.approx(0.1)  # never below min_vel_x
    s = lp.sample_velocities(p, 0.5, 0.0, 0.05, goal_dist=0.4)  # faster than the cap: slow down
    assert s[s[:, 0] > 0, 0].max() == pytest.approx(0.375) and s[s[:, 0] > 0, 0].min() == pytest.approx(0.2)


def test_in_place_rotation_turns_towards_the_goal_side_by_the_heading_lookahead():
    """Among valid rotations in place (nothing forward valid), TrajectoryPlanner takes the one whose
    end, heading_lookahead ahead, is nearest the local goal: a goal on the robot's left turns it
    left, one on its right turns it right, though the most negative rate always comes first."""
    for side in (1.0, -1.0):
        p = _params(dwa=True, escape_vel=0.0, sim_time=1.0, heading_lookahead=0.325)
        planner = lp.TrajectoryPlanner(p, FootprintCells(FOOTPRINT, RES), 0.05)
        m = cm.Costmap(120, 120, RES, -3.0, -3.0)
        r, c = m.world_to_cell(np.array([0.45]), np.array([0.0]))
        m.costs[:, c[0] : c[0] + 2] = cm.LETHAL  # a wall 0.45 m ahead: nothing forward is valid
        s = np.linspace(0, 1, 40)
        plan = np.column_stack([np.zeros(40), side * 2.0 * s])  # the goal 2 m to one side
        choice = planner.choose(m, (0.0, 0.0, 0.0), (0.0, 0.0), plan, 0.05)
        assert choice.valid and choice.cmd[0] == 0.0
        assert np.sign(choice.cmd[1]) == side


def test_two_rotations_to_one_side_in_a_row_refuse_the_other_side_until_the_robot_moves():
    flags = lp.InPlaceFlags(0.05)
    flags.chose((0.0, 0.0, 0.0), 0.0, -0.5)
    assert not flags.refuses(0.5)
    flags.chose((0.0, 0.0, 0.1), 0.0, -0.5)
    assert flags.refuses(0.5) and not flags.refuses(-0.5)  # upstream: stuck_right refuses left turns
    flags.chose((0.01, 0.0, 0.2), 0.2, 0.0)
    assert flags.refuses(0.5)  # moved 1 cm: still
    flags.chose((0.1, 0.0, 0.2), 0.2, 0.0)
    assert not flags.refuses(0.5)  # moved beyond oscillation_reset_dist


def test_turtlebot3_trajectory_planner_values_drive_straight_to_a_goal_ahead():
    """TurtleBot3's base_local_planner_params.yaml: slow (0.08..0.18 m/s), short rollouts (0.8 s)
    and a gentle turn acceleration (0.6 rad/s^2). Rollouts that stayed at the current velocity
    scored every sample alike, and the first of equal costs (the hardest right turn) won: the
    robot circled through its recoveries even for a goal 1 m straight ahead."""
    p = lp.TrajectoryParams(
        max_vel_x=0.18,
        min_vel_x=0.08,
        max_vel_theta=1.0,
        min_vel_theta=-1.0,
        min_in_place_vel_theta=1.0,
        acc_lim_x=1.0,
        acc_lim_theta=0.6,
        holonomic_robot=False,
        sim_time=0.8,
        vx_samples=18,
        vtheta_samples=20,
        sim_granularity=0.05,
        xy_goal_tolerance=0.10,
        yaw_goal_tolerance=0.05,
    )
    cells = FootprintCells(
        parse_footprint([[-0.105, -0.105], [-0.105, 0.105], [0.041, 0.105], [0.041, -0.105]]), RES
    )
    ctl = lp.LocalController(lp.TrajectoryPlanner(p, cells, 0.1))
    plan = np.column_stack([np.linspace(0, 1, 40), np.zeros(40), np.zeros(40)])
    pose, vel, turns = np.zeros(3), np.zeros(2), []
    for _ in range(200):  # 20 s at 10 Hz
        m = cm.Costmap(60, 60, RES, pose[0] - 1.5, pose[1] - 1.5)
        out = ctl.compute(m, pose, vel, plan, 0.1)
        if out.goal_reached:
            break
        v, w = out.cmd
        turns.append(abs(w))
        pose = pose + np.array([v * math.cos(pose[2]) * 0.1, v * math.sin(pose[2]) * 0.1, w * 0.1])
        vel = np.array([v, w])
    assert out.goal_reached and len(turns) * 0.1 < 12.0, pose  # 1 m at >= 0.08 m/s
    assert max(turns) < 0.3 and abs(pose[1]) < 0.05


def test_a_trajectorys_obstacle_cost_is_the_highest_under_its_footprint_as_footprintcost_reads_it():
    # ROS's critics (TrajectoryPlanner's occ_cost, DWA's ObstacleCostFunction) take the highest
    # cost on the footprint's outline or at its centre: a robot driving along a wall pays for
    # its side nearest the wall, not for its centre's distance
    from twil_control.navigation.collision import GridChecker

    m = cm.Costmap(60, 60, RES, 0.0, 0.0)
    m.costs[:, 40:] = cm.LETHAL  # a wall from x = 2.0 m
    m.costs = cm.inflate(m.costs, RES, 0.199, 3.0, 1.5)
    cells = FootprintCells(FOOTPRINT, RES)
    checker = GridChecker(m, cells)
    ys = np.linspace(0.5, 2.5, 21)
    for x in (1.45, 1.55):  # the footprint's side 0.199 m nearer the wall than the centre
        traj = np.stack([np.full_like(ys, x), ys, np.full_like(ys, math.pi / 2)], axis=-1)[None]
        ok, occ = checker.trajectories(traj)

        # the oracle: the highest cost at points spread over the footprint polygon at each pose,
        # and over the polygon grown by a cell (the precomputed cells of a heading cover every
        # position of the centre within its cell, so they may reach one cell further)
        def highest(grow: float) -> int:
            u, v = np.meshgrid(
                np.linspace(-0.305 - grow, 0.305 + grow, 61), np.linspace(-0.199 - grow, 0.199 + grow, 41)
            )
            py = ys[:, None] + u.ravel()  # yaw pi/2: body x along +y, body y along -x
            px = np.broadcast_to(x - v.ravel(), py.shape)
            return int(m.costs[m.world_to_cell(px.ravel(), py.ravel())].max())

        centre = m.costs[m.world_to_cell(np.full_like(ys, x), ys)].max()
        assert ok[0] and highest(0.0) <= occ[0] <= highest(RES)
        assert highest(0.0) > centre + 40


def test_meter_scoring_scales_the_occupancy_weight_by_the_resolution_as_trajectoryplannerros():
    """TrajectoryPlannerROS multiplies gdist_scale, pdist_scale and occdist_scale by the costmap's
    resolution under meter_scoring: an inflated cell's cost (up to 253) weighs 0.05 times as much
    beside distances in metres, not the 25 that would stop a robot before every gap."""
    choices = {}
    for meter in (False, True):
        p = _params(dwa=True, sim_time=1.0, occdist_scale=0.1, pdist_scale=0.75, gdist_scale=1.0)
        p = lp.TrajectoryParams(**{**p.__dict__, "meter_scoring": meter})
        planner = lp.TrajectoryPlanner(p, FootprintCells(FOOTPRINT, RES), 0.05)
        m = cm.Costmap(120, 120, RES, -3.0, -3.0)
        m.costs[:] = 200  # an inflated band all round: every move costs the same occupancy
        m.costs[:, :56] = 0  # except behind the robot
        plan = np.column_stack([np.linspace(0, 2.5, 50), np.zeros(50)])
        choices[meter] = planner.choose(m, (0.0, 0.0, 0.0), (0.0, 0.0), plan, 0.05)
    # one cost scale throughout: the chosen cost is the unscaled one times the resolution
    assert choices[True].cost == pytest.approx(choices[False].cost * RES, rel=1e-9)


def test_distance_maps_take_unknown_cells_as_obstacles_and_end_the_local_plan_before_them():
    # MapGrid (base_local_planner's map_grid.cpp): updatePathCell stops the search at LETHAL,
    # INSCRIBED and NO_INFORMATION cells; setTargetCells and setLocalGoal take the plan from its
    # first point on a known cell up to the first point off the map or on an unknown cell
    m = cm.Costmap(100, 40, RES, 0.0, 0.0)  # 5 m x 2 m
    x, _ = m.cell_to_world(*np.indices(m.shape))
    m.costs[(x > 2.0) & (x < 2.5)] = cm.NO_INFORMATION  # an unknown band across the window
    plan = np.column_stack([np.linspace(0.1, 4.9, 97), np.full(97, 1.0)])
    path, goal, local_goal = lp.distance_maps(m, plan)
    assert 2.0 - RES <= local_goal[0] <= 2.0
    beyond = x > 2.5
    assert (path[beyond] >= lp.UNREACHABLE).all() and (goal[beyond] >= lp.UNREACHABLE).all()
    assert (path[x < 2.0] < lp.UNREACHABLE).all()


def test_plan_cells_seed_the_distance_maps_whatever_their_cost_and_sparse_plans_are_densified():
    # setTargetCells marks every (known) plan cell 0, INSCRIBED ones too; only the search beyond
    # them needs free cells. adjustPlanResolution fills the plan in to the resolution
    m = cm.Costmap(60, 40, RES, 0.0, 0.0)
    r, c = m.world_to_cell(np.array([1.0]), np.array([1.025]))
    m.costs[r[0], c[0] - 3 : c[0] + 3] = cm.INSCRIBED
    plan = np.array([[0.125, 1.025], [2.925, 1.025]])  # two cell centres 2.8 m apart
    path, goal, _ = lp.distance_maps(m, plan)
    assert (path[r[0], 2:58] == 0).all()
    assert path[r[0] + 1, c[0]] == 1.0 and path[r[0] - 1, c[0]] == 1.0


def test_every_point_from_the_current_pose_must_be_clear_and_reach_the_plan():
    # generateTrajectory (and DWAPlanner's critics) judge each point from the robot's own pose:
    # a footprint on an obstacle or on unknown cells, or a cell cut off from the path and goal,
    # anywhere along a trajectory makes it illegal, not only at its end
    planner = lp.TrajectoryPlanner(_params(), FootprintCells(FOOTPRINT, RES), 0.05)
    m = cm.Costmap(120, 80, RES, -3.0, -2.0)
    x, y = m.cell_to_world(*np.indices(m.shape))
    plan = np.column_stack([np.linspace(-2.5, 2.5, 101), np.zeros(101)])
    path_map, goal_map, _ = lp.distance_maps(m, plan)
    line = np.column_stack([np.linspace(-1.0, 1.0, 41), np.zeros(41), np.zeros(41)])[None]
    assert planner.legal(m, (-1.0, 0.0, 0.0), line, path_map, goal_map)[0].tolist() == [True]
    # an unknown cell under the footprint halfway (a new grid, as a costmap update brings)
    m.costs = np.where((np.abs(x) < 0.05) & (np.abs(y - 0.15) < 0.05), cm.NO_INFORMATION, cm.FREE).astype(
        np.uint8
    )
    assert planner.legal(m, (-1.0, 0.0, 0.0), line, path_map, goal_map)[0].tolist() == [False]
    # the robot's own footprint on a lethal cell (on its left side, 1 m behind the trajectory's
    # first point): DWAPlanner judges the own pose too, except with the filled footprint test
    # (no escape to get it off the obstacle)
    m.costs = np.where((np.abs(x + 2.0) < 0.05) & (np.abs(y - 0.2) < 0.03), cm.LETHAL, cm.FREE).astype(
        np.uint8
    )
    assert planner.legal(m, (-2.0, 0.0, 0.0), line, path_map, goal_map)[0].tolist() == [False]
    dwa = DWAPlanner(DWAParams(), FootprintCells(FOOTPRINT, RES), 0.05)
    assert dwa.legal(m, (-2.0, 0.0, 0.0), line, path_map, goal_map)[0].tolist() == [False]
    dwa = DWAPlanner(DWAParams(footprint_check="filled"), FootprintCells(FOOTPRINT, RES), 0.05)
    assert dwa.legal(m, (-2.0, 0.0, 0.0), line, path_map, goal_map)[0].tolist() == [True]
    # a point cut off from the plan (distance maps of an enclosed pocket), the end reachable
    pocket = np.full(m.shape, 1e9)
    pocket[(np.abs(x) > 0.2)] = 0.0
    assert lp.reachable_along(m, line, pocket, pocket).tolist() == [False]
    assert lp.reachable_along(m, line[:, :10], pocket, pocket).tolist() == [True]


def _line_cells(x0: int, y0: int, x1: int, y1: int) -> set[tuple[int, int]]:
    """The cells CostmapModel::lineCost reads from (x0, y0) to (x1, y1): those where a lone
    LETHAL cell makes the line illegal."""
    from twil_control.navigation.collision import _edge_cost

    cells = set()
    for cx in range(8):
        for cy in range(8):
            costs = np.zeros((8, 8), np.uint8)
            costs[cy, cx] = cm.LETHAL
            if _edge_cost(x0, y0, x1, y1, costs.ravel(), 8, 0) < 0:
                cells.add((cx, cy))
    return cells


def test_footprint_edges_are_rasterised_as_base_local_planners_line_iterator():
    # LineIterator: Bresenham with the error starting at half the major span, so a line and its
    # reverse may differ (worked by hand from line_iterator.h)
    assert _line_cells(0, 0, 5, 2) == {(0, 0), (1, 0), (2, 1), (3, 1), (4, 2), (5, 2)}
    assert _line_cells(0, 0, 4, 1) == {(0, 0), (1, 0), (2, 1), (3, 1), (4, 1)}
    assert _line_cells(4, 1, 0, 0) == {(4, 1), (3, 1), (2, 0), (1, 0), (0, 0)}
    assert _line_cells(0, 0, 1, 3) == {(0, 0), (0, 1), (1, 2), (1, 3)}
    assert _line_cells(3, 3, 3, 3) == {(3, 3)}


@pytest.mark.parametrize("planner", ["trajectory", "dwa"])
def test_footprint_check_outline_reads_the_edges_only_as_upstream_and_filled_the_whole_polygon(planner):
    # CostmapModel::footprintCost (both ROS local planners) returns -1 only for a LETHAL or
    # unknown cell on the footprint's rasterised edges: an obstacle inside the footprint, or a
    # centre within the inscribed radius of one, is legal (its cost still counts). The filled
    # test (this package's footprint_check: filled) refuses both
    m = cm.Costmap(80, 80, RES, -2.0, -2.0)
    x, y = m.cell_to_world(*np.indices(m.shape))
    cells = FootprintCells(FOOTPRINT, RES)
    pose = np.array([[[0.0, 0.0, 0.0]]])

    def judged(check: str, costs: np.ndarray) -> tuple[bool, float]:
        if planner == "dwa":
            chosen = DWAPlanner(DWAParams(footprint_check=check), cells, 0.05)
        else:
            chosen = lp.TrajectoryPlanner(_params(footprint_check=check), cells, 0.05)
        m.costs = costs
        ok, occ = chosen.footprint_ok(m, pose)
        return bool(ok[0]), float(occ[0])

    def obstacle(ahead: float) -> np.ndarray:
        """Inflated costs of a 2 x 2 cell obstacle `ahead` m in front of the centre."""
        lethal = ((np.abs(x - ahead) < 0.03) & (np.abs(y) < 0.03)).astype(np.uint8) * cm.LETHAL
        return cm.inflate(lethal, RES, 0.199, 3.0, 0.5)

    inside = obstacle(0.25)  # inside the front, beyond the inscribed radius: the edge INSCRIBED
    assert judged("outline", inside) == (True, float(cm.INSCRIBED))
    assert judged("filled", inside)[0] is False
    near = obstacle(0.1)  # the centre 10 cm from it: the centre INSCRIBED
    assert judged("outline", near) == (True, float(cm.INSCRIBED))
    assert judged("filled", near)[0] is False
    clear = obstacle(0.6)  # 30 cm clear of the front
    assert judged("filled", clear)[0] and judged("outline", clear)[0]
    edge = ((np.abs(x - 0.305) < 0.03) & (np.abs(y) < 0.03)).astype(np.uint8) * cm.LETHAL  # on the front edge
    assert judged("outline", edge)[0] is False and judged("filled", edge)[0] is False
    unknown = np.where(edge > 0, cm.NO_INFORMATION, cm.FREE).astype(np.uint8)
    assert judged("outline", unknown)[0] is False


def _footprint_cost(m: cm.Costmap, pose, polygon: np.ndarray) -> float:
    """CostmapModel::footprintCost of one pose, every edge rasterised afresh: the reference the
    compiled check of whole trajectories (which skips a pose whose cells repeat) must equal."""
    from twil_control.navigation.collision import _edge_cost

    x, y, yaw = pose
    c, s = np.cos(yaw), np.sin(yaw)
    corners = []
    for px, py in polygon:
        cx = (x + px * c - py * s - m.origin[0]) / m.resolution
        cy = (y + px * s + py * c - m.origin[1]) / m.resolution
        if not (0 <= cx < m.shape[1] and 0 <= cy < m.shape[0]):
            return -1.0
        corners.append((int(cx), int(cy)))
    costs = m.costs.ravel()
    edges = [_edge_cost(*a, *b, costs, m.shape[1], 0) for a, b in zip(corners, corners[1:] + corners[:1])]
    return -1.0 if min(edges) < 0 else max(edges)


def test_outline_check_of_trajectories_equals_each_pose_judged_on_its_own():
    # sparse obstacles, inflated, a few unknown cells; rollouts at the planners' fine steps (most
    # successive poses share their cells), some running into obstacles or off the grid
    from twil_control.navigation.collision import GridChecker

    rng = np.random.default_rng(3)
    m = cm.Costmap(90, 80, RES, -2.0, -2.0)
    lethal = (rng.random(m.shape) < 0.002).astype(np.uint8) * cm.LETHAL
    m.costs = cm.inflate(lethal, RES, 0.199, 3.0, 0.5)
    m.costs[rng.random(m.shape) < 0.001] = cm.NO_INFORMATION
    n, k, dt = 60, 100, 0.02
    v, w = rng.uniform(-0.5, 0.5, (n, 1)), rng.uniform(-1.6, 1.6, (n, 1))
    yaw = rng.uniform(-np.pi, np.pi, (n, 1)) + w * dt * np.arange(k)
    x = rng.uniform(-1.8, 1.8, (n, 1)) + np.cumsum(v * np.cos(yaw) * dt, axis=1)
    y = rng.uniform(-1.8, 2.2, (n, 1)) + np.cumsum(v * np.sin(yaw) * dt, axis=1)
    poses = np.stack([x, y, yaw], axis=2)
    checker = GridChecker(m, FootprintCells(FOOTPRINT, RES))
    ok, occ = checker.trajectories_outline(poses)
    polygon = np.asarray(FootprintCells(FOOTPRINT, RES).poly)
    for i in range(n):
        want_ok, want_occ = True, 0.0
        for pose in poses[i]:
            cx, cy = ((pose[:2] - m.origin) / RES).astype(float)
            f = _footprint_cost(m, pose, polygon) if 0 <= cx < m.shape[1] and 0 <= cy < m.shape[0] else -1.0
            if f < 0:
                want_ok = False
                break
            centre = m.costs[int(cy), int(cx)]
            want_occ = max(want_occ, f, 0.0 if centre == cm.NO_INFORMATION else float(centre))
        assert ok[i] == want_ok, i
        if want_ok:
            assert occ[i] == want_occ, i
    assert 10 < ok.sum() < n - 10  # both kinds of trajectory were met


def test_footprint_check_must_be_outline_or_filled():
    with pytest.raises(
        lp.LocalPlannerError, match="footprint_check must be one of outline, filled .got 'edges'"
    ):
        _params(footprint_check="edges")
    with pytest.raises(lp.LocalPlannerError, match="footprint_check"):
        DWAParams(footprint_check="")
