"""dwa_local_planner's DWAPlannerROS: a user's parameter file (tests/data/ros1/nav, written in the
style of public robots' navigation packages) selects it and drives this project's local planner,
with the dynamic window of one control period; parameters it cannot honour are warned about
once, and a planner file with slips ROS ignores (a misspelt key, an unread name) runs."""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest
from test_nav_move_base import Harness

from twil_control import PACKAGE_ROOT
from twil_control.core.params import ParamServer
from twil_control.core.typed_params import load_typed
from twil_control.core.yaml_io import display_path
from twil_control.navigation import costmap as cm
from twil_control.navigation.dwa_planner import DWAParams, DWAPlanner, dwa_samples, velocity_samples
from twil_control.navigation.footprint import FootprintCells, parse_footprint
from twil_control.navigation.local_planner import LocalController
from twil_control.nodes.move_base import SUCCEEDED

DATA = PACKAGE_ROOT / "tests/data/ros1/nav"
DWA_FILE = DATA / "dwa_local_planner_params.yaml"
PLANNER_FILE = DATA / "planner.yaml"
DWA = "dwa_local_planner/DWAPlannerROS"


def _dwa_params(**overrides) -> DWAParams:
    server = ParamServer()
    server.load_file(DWA_FILE, "/move_base")
    for key, value in overrides.items():
        server.set(f"/move_base/DWAPlannerROS/{key}", value)
    return load_typed(server, "/move_base/DWAPlannerROS", DWAParams, warn=lambda message: None)


def test_velocity_samples_add_zero_between_a_negative_and_a_positive_sample():
    assert velocity_samples(-0.1, 0.2, 4).tolist() == pytest.approx([-0.1, 0.0, 0.1, 0.2])  # 0 is one
    assert velocity_samples(-0.15, 0.15, 4).tolist() == pytest.approx([-0.15, -0.05, 0.0, 0.05, 0.15])
    assert velocity_samples(0.3, 0.3, 5).tolist() == [0.3]  # an empty window: one sample


@pytest.mark.parametrize("v0, w0", [(0.0, 0.0), (0.2, 0.5), (0.3, -1.5), (-0.1, 1.4)])
def test_samples_lie_in_the_window_that_acc_lim_times_the_sim_period_reaches(v0, w0):
    p = _dwa_params()
    period = 1.0 / p.controller_frequency  # 10 Hz in the file: 0.1 s
    s = dwa_samples(p, v0, w0, period)
    vx_lo, vx_hi = max(p.min_vel_x, v0 - p.acc_lim_x * period), min(p.max_vel_x, v0 + p.acc_lim_x * period)
    th_lo, th_hi = (
        max(-p.max_vel_theta, w0 - p.acc_lim_theta * period),
        min(p.max_vel_theta, w0 + p.acc_lim_theta * period),
    )
    assert s[:, 0].min() == pytest.approx(vx_lo) and s[:, 0].max() == pytest.approx(vx_hi)
    assert th_lo - 1e-12 <= s[:, 1].min() and s[:, 1].max() <= th_hi + 1e-12
    # every sample moves: translating at min_vel_trans or turning at min_vel_theta (absolute)
    assert np.all((np.abs(s[:, 0]) >= p.min_vel_trans - 1e-4) | (np.abs(s[:, 1]) >= p.min_vel_theta - 1e-4))
    assert np.all(np.abs(s[:, 0]) <= p.max_vel_trans + 1e-4)
    # the generator's order: vx slowest first, vth from the most negative within each vx
    assert np.all(np.diff(s[:, 0]) >= 0)
    assert all(np.all(np.diff(s[s[:, 0] == vx, 1]) > 0) for vx in np.unique(s[:, 0]))


def test_without_use_dwa_the_window_spans_sim_time():
    p = _dwa_params(use_dwa=False)
    planner = DWAPlanner(
        p, FootprintCells(parse_footprint([[0.1, 0.1], [-0.1, 0.1], [-0.1, -0.1], [0.1, -0.1]]), 0.05), 0.1
    )
    s = planner.samples((0.0, 0.0))
    assert s[:, 0].max() == pytest.approx(p.max_vel_x) and s[:, 1].max() == pytest.approx(p.max_vel_theta)


def _drive(planner_params, goal, obstacle=None, steps=400, period=0.1):
    """Closed loop on a rolling 6 m grid around a unicycle: the DWA LocalController's commands."""
    res = 0.05
    cells = FootprintCells(parse_footprint([[0.15, 0.12], [-0.15, 0.12], [-0.15, -0.12], [0.15, -0.12]]), res)
    ctl = LocalController(DWAPlanner(planner_params, cells, 1.0 / planner_params.controller_frequency))
    pose, vel = np.zeros(3), np.zeros(2)
    s = np.linspace(0, 1, 80)[:, None]
    via = np.array([goal[0] / 2, 1.0]) if obstacle else np.array(goal[:2]) / 2
    plan_xy = np.vstack([s * via, via + s * (np.array(goal[:2]) - via)])
    plan = np.column_stack([plan_xy, np.full(len(plan_xy), goal[2])])
    cmds = []
    for k in range(steps):
        m = cm.Costmap(120, 120, res, pose[0] - 3, pose[1] - 3)
        if obstacle:
            r0, c0 = m.world_to_cell(obstacle[0], obstacle[1])
            r1, c1 = m.world_to_cell(obstacle[2], obstacle[3])
            m.costs[max(r0, 0) : max(r1, 0), max(c0, 0) : max(c1, 0)] = cm.LETHAL
        m.costs = cm.inflate(m.costs, res, cells.inscribed, 5.0, 0.4)
        out = ctl.compute(m, pose, vel, plan, period)
        if out.goal_reached:
            return k * period, pose, np.array(cmds)
        assert out.valid, (k, pose)
        v, w = out.cmd
        cmds.append((v, w))
        pose = pose + np.array([v * math.cos(pose[2]) * period, v * math.sin(pose[2]) * period, w * period])
        vel = np.array([v, w])
    return None, pose, np.array(cmds)


def test_dwa_drives_a_unicycle_to_a_goal_within_the_dynamic_window():
    p = _dwa_params()
    t, pose, cmds = _drive(p, (2.0, 0.5, math.pi / 2))
    assert t is not None and t < 25.0, pose
    assert math.hypot(pose[0] - 2.0, pose[1] - 0.5) <= p.xy_goal_tolerance + 1e-9
    assert abs(math.remainder(pose[2] - math.pi / 2, 2 * math.pi)) <= p.yaw_goal_tolerance + 1e-9
    # consecutive commands within acc_lim * sim_period (0.1 s) of each other, and the limits held
    # (at the goal the final rotation ramps at acc_lim_theta too)
    dv, dw = np.abs(np.diff(cmds, axis=0)).T
    assert dv.max() <= p.acc_lim_x * 0.1 + 1e-9 and dw.max() <= p.acc_lim_theta * 0.1 + 1e-9
    assert cmds[:, 0].max() <= p.max_vel_x + 1e-9 and np.abs(cmds[:, 1]).max() <= p.max_vel_theta + 1e-9


def test_dwa_goes_around_an_obstacle_on_the_plan():
    box = (0.8, -0.3, 1.2, 0.3)  # on the straight line from (0, 0) to (2, 0)
    t, pose, cmds = _drive(_dwa_params(), (2.0, 0.0, 0.0), obstacle=box)
    assert t is not None, pose
    assert math.hypot(pose[0] - 2.0, pose[1]) <= 0.1 + 1e-9


def _warnings(caplog) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.name == "twil_control.node.move_base"]


def test_move_base_selects_dwa_from_base_local_planner_and_reaches_the_goal(caplog):
    with caplog.at_level(logging.WARNING, logger="twil_control.node.move_base"):
        h = Harness(files=[DWA_FILE], base_local_planner=DWA)
    planner = h.mb.local.planner
    assert isinstance(planner, DWAPlanner)
    assert planner.sim_period == pytest.approx(0.1)  # DWAPlannerROS/controller_frequency 10
    assert (planner.p.max_vel_x, planner.p.min_vel_theta, planner.p.vth_samples) == (0.3, 0.6, 25)
    assert h.mb.params.controller_frequency == 20.0  # move_base's own rate is unchanged
    # what the simulation cannot honour: one warning each, naming the file and line; nothing for
    # the y axis set to 0 or the samples of a non-holonomic base
    warned = _warnings(caplog)
    for name, line in (
        ("stop_time_buffer", 41),
        ("scaling_speed", 42),
        ("max_scaling_factor", 43),
        ("publish_traj_pc", 49),
        ("publish_cost_grid_pc", 50),
    ):
        hits = [w for w in warned if f"'/move_base/DWAPlannerROS/{name}'" in w]
        assert (
            len(hits) == 1
            and hits[0].startswith(f"{display_path(DWA_FILE)}:{line}: parameter ")
            and "no effect" in hits[0]
        )
    assert not [
        w for w in warned if any(k in w for k in ("max_vel_y", "min_vel_y", "vy_samples", "acc_lim_y"))
    ]
    caplog.clear()
    h.run(0.5)
    h.send(5.0, 1.0, math.pi / 2)  # past the pillar at (3, 1)
    h.run(60.0)
    assert [r[1].status for r in h.results] == [SUCCEEDED]
    x, y, _ = h.robot.pose
    assert math.hypot(x - 5.0, y - 1.0) <= 0.1 + 1e-9
    cmds = np.array([(v, w) for _, v, w in h.robot.cmds])
    moving = cmds[np.any(cmds != 0, axis=1)]
    assert np.abs(moving[:, 0]).max() <= 0.3 + 1e-9 and np.abs(moving[:, 1]).max() <= 1.5 + 1e-9
    assert not [w for w in _warnings(caplog) if "no effect" in w]  # warned once, at load


def test_a_planner_file_with_slips_ros_ignores_warns_and_runs(caplog):
    with caplog.at_level(logging.WARNING, logger="twil_control.node.move_base"):
        h = Harness(files=[PLANNER_FILE], base_local_planner=DWA)
    warned = _warnings(caplog)
    misspelt = [w for w in warned if "recovery_behaviour_enabled" in w]
    assert misspelt == [
        f"{display_path(PLANNER_FILE)}:5: unknown parameter '/move_base/recovery_behaviour_enabled' (did you "
        f"mean 'recovery_behavior_enabled'?) is ignored, as move_base ignores parameters it does "
        f"not read; allowed: " + misspelt[0].split("allowed: ")[1]
    ]
    assert "recovery_behavior_enabled" in misspelt[0].split("allowed: ")[1]
    assert h.mb.params.recovery_behavior_enabled is True  # the default, as in ROS
    assert any(
        w.startswith(
            f"{display_path(PLANNER_FILE)}:26: unknown parameter '/move_base/DWAPlannerROS/acc_lim_th' "
            f"(did you mean 'acc_lim_theta'?) is ignored, as dwa_local_planner ignores"
        )
        for w in warned
    )
    # the names before Melodic: read, with nav_core's warning
    assert any(
        w.startswith(
            f"{display_path(PLANNER_FILE)}:33: parameter '/move_base/DWAPlannerROS/max_rot_vel' has been "
            f"renamed to 'max_vel_theta'"
        )
        for w in warned
    )
    assert h.mb.local.params.max_vel_theta == 1.2 and h.mb.local.params.min_vel_theta == 0.2
    # TrajectoryPlannerROS is not the local planner: what only it would read is not warned about
    assert not [w for w in warned if "'/move_base/TrajectoryPlannerROS/" in w]
    assert h.mb.local.planner.sim_period == pytest.approx(0.2)  # move_base's 5 Hz
    # and it drives: with this file's values (vx_samples 3, sim_time 1.7 s by default) every
    # forward sample moves at least 0.25 m/s x 1.7 s, so the robot stops short of the goal by up
    # to about that and turns in place there, as DWAPlanner does with them
    h.run(0.5)
    h.send(2.0, 2.5, 0.0)
    h.run(20.0)
    x, y, _ = h.robot.pose
    assert math.hypot(x - 2.0, y - 2.5) < 0.45 and h.mb.goal is not None and h.mb.state == "CONTROLLING"


def test_trajectory_planner_values_of_a_file_warn_when_it_is_the_local_planner(caplog):
    with caplog.at_level(logging.WARNING, logger="twil_control.node.move_base"):
        h = Harness(files=[PLANNER_FILE])
    warned = _warnings(caplog)
    assert any(
        w.startswith(
            f"{display_path(PLANNER_FILE)}:21: parameter '/move_base/TrajectoryPlannerROS/heading_scoring_timestep'"
            f" = 0.8 has no effect here"
        )
        for w in warned
    )
    assert h.mb.local.planner.sim_period == pytest.approx(0.05)  # its own controller_frequency 20


@pytest.mark.slow
def test_the_tiny_robot_reaches_a_near_goal_with_a_users_dwa_file(tmp_path, monkeypatch):
    """End to end in Drake: the tiny robot's diff-drive plugin and laser, move_base with the DWA
    file through base_local_planner dwa_local_planner/DWAPlannerROS, a goal 1 m ahead."""
    from conftest import read_bag

    from twil_control.core import packages
    from twil_control.launch.loader import load_launch
    from twil_control.launch.runner import RunOptions, run

    monkeypatch.setenv("ROS_PACKAGE_PATH", str(PACKAGE_ROOT / "tests/data/robots"))
    monkeypatch.setenv("TWIL_MESH_CACHE", str(tmp_path / "meshes"))
    packages.set_extra_paths([])
    result = run(
        load_launch(DATA / "tiny_dwa.launch"), RunOptions(duration=8.0, bag=tmp_path / "dwa.bag", seed=1)
    )
    assert result.error is None
    msgs = read_bag(result.bag)
    ((t, done),) = [(t, m) for t, m in msgs["/move_base/result"]]
    assert done.status.status == SUCCEEDED and t * 1e-9 < 7.0
    states = msgs["/gazebo/model_states"]
    pose = states[-1][1].pose[list(states[-1][1].name).index("tiny")].position
    assert math.hypot(pose.x - 1.0, pose.y) <= 0.1 + 0.02  # xy_goal_tolerance + rolling to a stop
    cmds = np.array([(m.linear.x, m.angular.z) for _, m in msgs["/cmd_vel"]])
    assert cmds[:, 0].max() <= 0.3 + 1e-9 and np.abs(cmds[:, 1]).max() <= 1.5 + 1e-9
    assert len(msgs["/move_base/DWAPlannerROS/local_plan"]) >= 10
