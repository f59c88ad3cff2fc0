"""TrajectoryPlanner's escape: a robot that can neither drive forward nor turn in place (its nose
close to a wall, the plan along the wall) backs out at escape_vel, then turns and follows the
plan; it backs out even into an obstacle, as upstream, but not when cut off from its plan. And
move_base's re-planning as soon as the global costmap blocks the plan it follows
(replan_when_blocked)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml
from support.nav_fakes import KinematicRobot, move_base_params, occupancy_grid

from twil_control import PACKAGE_ROOT
from twil_control.core.messages import header, msg_class
from twil_control.core.node import Master, Node
from twil_control.navigation import costmap as cm
from twil_control.navigation import local_planner as lp
from twil_control.navigation.collision import GridChecker
from twil_control.navigation.footprint import FootprintCells, parse_footprint
from twil_control.nodes.move_base import SUCCEEDED, MoveBase
from twil_control.nodes.move_base_params import MoveBaseParams

pytestmark = pytest.mark.kernels

RES = 0.05
FOOTPRINT = parse_footprint([[0.305, 0.199], [-0.305, 0.199], [-0.305, -0.199], [0.305, -0.199]])
CELLS = FootprintCells(FOOTPRINT, RES)


def _qbot_params(**kw) -> lp.TrajectoryParams:
    """config/base_local_planner_params.yaml's values (qbot)."""
    base = dict(
        max_vel_x=0.45,
        min_vel_x=0.1,
        max_vel_theta=2.0,
        min_vel_theta=-2.0,
        min_in_place_vel_theta=1.0,
        acc_lim_theta=3.2,
        acc_lim_x=2.5,
        xy_goal_tolerance=0.5,
        yaw_goal_tolerance=0.5,
        latch_xy_goal_tolerance=True,
        holonomic_robot=False,
        dwa=False,
        sim_time=1.0,
        vx_samples=3,
        vtheta_samples=20,
        rotate_to_heading_threshold=0.3,
    )
    base.update(kw)
    return lp.TrajectoryParams(**base)


def _wall_ahead(face_x: float) -> cm.Costmap:
    """A 6 m grid round the origin with a wall from x = face_x to face_x + 0.1, y -3..3, inflated as
    qbot's costmaps are (inscribed 0.199 m, inflation 0.55 m, factor 10)."""
    m = cm.Costmap(120, 120, RES, -3.0, -3.0)
    x, _ = m.cell_to_world(*np.indices(m.shape))
    m.costs[(x >= face_x) & (x < face_x + 0.1)] = cm.LETHAL
    m.costs = cm.inflate(m.costs, RES, CELLS.inscribed, 10.0, 0.55)
    return m


def _drive_along_the_wall(params, steps: int = 400, period: float = 0.05):
    """The robot at the origin facing +x, its nose 0.035 m from a wall (its corners sweep 0.36 m
    turning in place, the wall's face is 0.34 m from its centre); the plan runs along the wall to
    (0, 2.5). Returns the poses and the commands."""
    m = _wall_ahead(0.34)
    ctl = lp.LocalController(lp.TrajectoryPlanner(params, CELLS, period))
    plan = np.column_stack([np.zeros(60), np.linspace(0.0, 2.5, 60), np.full(60, math.pi / 2)])
    pose, vel = np.zeros(3), np.zeros(2)
    poses, cmds = [pose], []
    for _ in range(steps):
        out = ctl.compute(m, pose, vel, plan, period)
        if out.goal_reached:
            break
        v, w = out.cmd
        cmds.append((v, w, out.valid))
        pose = pose + np.array([v * math.cos(pose[2]) * period, v * math.sin(pose[2]) * period, w * period])
        vel = np.array([v, w])
        poses.append(pose)
    return m, np.array(poses), cmds


def test_a_robot_that_can_neither_drive_nor_turn_backs_out_then_follows_the_plan():
    p = _qbot_params()
    m, poses, cmds = _drive_along_the_wall(p)
    # the first command backs out, ramping towards escape_vel (-0.1 m/s) at acc_lim_x
    v0, w0, valid0 = cmds[0]
    assert valid0 and v0 == pytest.approx(max(p.escape_vel, -p.acc_lim_x * 0.05), abs=1e-9) and w0 == 0.0
    backing = [i for i, (v, _, _) in enumerate(cmds) if v < 0]
    # it backs out at most escape_reset_dist (0.1 m; here one step frees the turn), once, first
    assert backing == list(range(len(backing)))
    assert -p.escape_reset_dist - 0.01 <= poses[backing[-1] + 1][0] < 0.0
    # then turns and follows the plan: 2 m along the wall, every command valid, never touching it
    assert poses[-1][1] > 2.0 - p.xy_goal_tolerance
    assert all(valid for _, _, valid in cmds)
    checker = GridChecker(m, CELLS)
    assert checker.trajectories(poses[None])[0][0]


def test_without_an_escape_velocity_the_same_robot_gets_no_command():
    # escape_vel 0 (no backing out): nothing forward or in place is valid, as before the escape
    _, poses, cmds = _drive_along_the_wall(_qbot_params(escape_vel=0.0), steps=20)
    assert not any(valid for _, _, valid in cmds) and np.allclose(poses[-1], 0.0)


def _wedged_with_a_wall_behind() -> cm.Costmap:
    """The nose 0.035 m from a wall ahead and the tail 0.03 m from one behind."""
    m = _wall_ahead(0.34)
    x, _ = m.cell_to_world(*np.indices(m.shape))
    m.costs[(x <= -0.335) & (x > -0.435)] = cm.LETHAL
    m.costs = cm.inflate(m.costs, RES, CELLS.inscribed, 10.0, 0.55)
    return m


def test_backing_out_into_an_obstacle_is_driven_as_trajectory_planner_does():
    # createTrajectories' last resort (base_local_planner's trajectory_planner.cpp): when nothing
    # forward or in place is legal it rolls out escape_vel and drives it even when the footprint
    # meets an obstacle along it, the collision (-1) turned into a cost of 1.0; the escape starts
    p = _qbot_params()
    planner = lp.TrajectoryPlanner(p, CELLS, 0.05)
    plan = np.column_stack([np.zeros(60), np.linspace(0.0, 2.5, 60)])
    choice = planner.choose(_wedged_with_a_wall_behind(), (0.0, 0.0, 0.0), (0.0, 0.0), plan, 0.05)
    assert choice.valid and choice.cost == 1.0
    assert choice.cmd == pytest.approx((p.escape_vel, 0.0), abs=1e-12)
    assert planner.escape_from == (0.0, 0.0, 0.0)
    # through move_base's controller too: a valid command, so controller_patience does not run
    ctl = lp.LocalController(lp.TrajectoryPlanner(p, CELLS, 0.05))
    plan3 = np.column_stack([plan, np.full(60, math.pi / 2)])
    out = ctl.compute(_wedged_with_a_wall_behind(), (0.0, 0.0, 0.0), (0.0, 0.0), plan3, 0.05)
    assert out.valid and out.cmd == pytest.approx((p.escape_vel, 0.0), abs=1e-12)


def test_the_escape_lasts_until_escape_reset_dist_then_forward_motion_is_sampled_again():
    # escaping_ is cleared at the end of the cycle in which the robot is escape_reset_dist from
    # where the escape began: the cycles in between sample no forward motion
    p = _qbot_params()
    planner = lp.TrajectoryPlanner(p, CELLS, 0.05)
    m = _wedged_with_a_wall_behind()
    plan = np.column_stack([np.zeros(60), np.linspace(0.0, 2.5, 60)])
    planner.choose(m, (0.0, 0.0, 0.0), (0.0, 0.0), plan, 0.05)
    within = planner.choose(m, (-0.02, 0.0, 0.0), (p.escape_vel, 0.0), plan, 0.05)
    assert within.cmd[0] < 0 and planner.escape_from == (0.0, 0.0, 0.0)
    planner.choose(m, (-p.escape_reset_dist - 0.005, 0.0, 0.0), (p.escape_vel, 0.0), plan, 0.05)
    assert planner.escape_from is None


def test_a_robot_cut_off_from_its_plan_gets_no_command_not_even_backing_out():
    # generateTrajectory's -2: a point from which neither the path nor the goal can be reached,
    # met before any collision (here the robot's own cell: the plan lies beyond a wall across
    # the whole window), makes the escape trajectory illegal too, and starts no escape
    planner = lp.TrajectoryPlanner(_qbot_params(), CELLS, 0.05)
    plan = np.column_stack([np.full(60, 1.0), np.linspace(-1.0, 2.5, 60)])
    choice = planner.choose(_wall_ahead(0.34), (0.0, 0.0, 0.0), (0.0, 0.0), plan, 0.05)
    assert not choice.valid and choice.cmd == (0.0, 0.0)
    assert planner.escape_from is None


# -- move_base: re-planning when the global costmap blocks the plan ----------------------------
def _rooms(hole: bool) -> np.ndarray:
    """6 m x 4 m, walls round it and a wall at x = 3.0..3.1 with a door at y 3.0..3.9; with `hole`
    the wall's stretch y 1.4..2.6 is missing (unseen yet, as in a map being built)."""
    g = np.zeros((80, 120), np.int8)
    g[:2, :] = g[-2:, :] = 100
    g[:, :2] = g[:, -2:] = 100
    g[:60, 60:62] = 100  # y 0 .. 3.0
    g[78:, 60:62] = 100  # y 3.9 .. 4.0 (the outer wall)
    if hole:
        g[28:52, 60:62] = 0
    return g


class _Run:
    def __init__(self, **overrides) -> None:
        self.master = Master()
        move_base_params(self.master.params, **overrides)
        self.node = Node(self.master, "test")
        self.map_pub = self.node.create_publisher("/map", "nav_msgs/OccupancyGrid", latch=True)
        self.map_pub.publish(occupancy_grid(_rooms(hole=True), RES))
        self.robot = KinematicRobot(self.master, (1.0, 2.0, 0.0))
        self.mb = MoveBase(self.master, "move_base")
        self.plans: list[tuple[float, np.ndarray]] = []
        self.results = []
        self.node.create_subscription(
            "/move_base/NavfnROS/plan",
            "nav_msgs/Path",
            lambda m: self.plans.append(
                (self.master.clock.now(), np.array([(p.pose.position.x, p.pose.position.y) for p in m.poses]))
            ),
        )
        self.node.create_subscription(
            "/move_base/result", "twil_control/MoveBaseActionResult", lambda m: self.results.append(m.status)
        )
        self.trace: list[np.ndarray] = []
        self.node.create_timer(0.05, lambda e: self.trace.append(self.robot.pose.copy()))

    def go(self, wall_at: float, until: float) -> None:
        goal = msg_class("geometry_msgs/PoseStamped")(
            header=header("map", 0.0),
            pose=msg_class("geometry_msgs/Pose")(
                position=msg_class("geometry_msgs/Point")(x=5.0, y=2.0, z=0.0),
                orientation=msg_class("geometry_msgs/Quaternion")(x=0.0, y=0.0, z=0.0, w=1.0),
            ),
        )
        self.master.spin_until(0.2)
        self.node.create_publisher("/move_base_simple/goal", "geometry_msgs/PoseStamped").publish(goal)
        self.master.spin_until(wall_at)
        self.map_pub.publish(occupancy_grid(_rooms(hole=False), RES))  # the wall is seen
        self.master.spin_until(until)


def test_move_base_replans_as_soon_as_the_global_costmap_blocks_the_plan():
    run = _Run()
    run.go(wall_at=1.0, until=60.0)
    t0, first = run.plans[0]
    assert first[:, 1].max() < 2.6  # straight through the unseen stretch of the wall
    # the next plan comes at the global costmap's next update (5 Hz) after the wall appeared
    t1, second = next((t, p) for t, p in run.plans if t > 1.0)
    assert 1.0 < t1 <= 1.0 + 0.2 + 0.05 + 1e-9
    assert second[:, 1].max() > 3.0  # through the door
    assert [s.status for s in run.results] == [SUCCEEDED]
    # on its side of the wall the robot never came nearer the wall than 0.6 m below the door
    trace = np.array(run.trace)
    before = (trace[:, 1] < 2.7) & (trace[:, 0] < 3.0)
    assert trace[before, 0].max() < 3.0 - 0.6


def test_with_replan_when_blocked_false_the_stale_plan_is_followed_until_the_local_planner_fails():
    run = _Run(replan_when_blocked=False)
    run.go(wall_at=1.0, until=8.0)
    later = [t for t, _ in run.plans if t > 1.0]
    trace = np.array(run.trace)
    # move_base's own behaviour: the plan is kept while the local planner finds commands, so the
    # robot drives on towards the wall first
    assert not later or later[0] > 1.5
    assert trace[:, 0].max() > 3.0 - 0.6


def test_re_planning_when_blocked_is_off_by_default_and_on_in_qbots_move_base_file():
    assert MoveBaseParams().replan_when_blocked is False  # move_base's own behaviour
    qbot = yaml.safe_load((PACKAGE_ROOT / "config/move_base_params.yaml").read_text())
    assert qbot["replan_when_blocked"] is True
