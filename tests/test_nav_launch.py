"""The navigation launch end to end in Drake (slow): qbot reaching seeded random goals on the
house world through move_base with no contact with the world and near-optimal paths, the bag's
navigation analysis, and the same seed giving the same OMPL plans and commands."""
from __future__ import annotations

import importlib.util

import numpy as np
import pytest

from twil_control import PACKAGE_ROOT
from twil_control.bag.reader import Bag
from twil_control.launch.loader import load_launch
from twil_control.launch.runner import RunOptions, run
from twil_control.navigation import evaluation as ev

pytestmark = pytest.mark.slow


def _bench():
    spec = importlib.util.spec_from_file_location("nav_goals", PACKAGE_ROOT / "bench/nav_goals.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_qbot_reaches_three_random_goals_without_contact_on_near_optimal_paths(tmp_path):
    bench = _bench()
    map_yaml, m, cells = bench.house_map(tmp_path)
    goals = ev.sample_goals(m, cells, (0.0, 0.0, 0.0), 3, np.random.default_rng(5))
    metrics, result, _ = bench.run_goals(goals, 5, tmp_path, map_yaml, duration=300.0)
    rows = bench.score(metrics, m, tolerance=0.5)
    assert [r["status"] for r in rows] == ["SUCCEEDED"] * 3
    assert all(r["reached"] for r in rows)                      # within xy_goal_tolerance 0.5 m
    assert all(r["collision_samples"] == 0 for r in rows)       # no contact but the wheels on the floor
    assert np.mean([r["ratio"] for r in rows]) <= 1.15
    # the analysis of the real bag: times, paths and clearances that make sense
    for r, g in zip(rows, goals):
        assert (r["target_x_m"], r["target_y_m"]) == (g[0], g[1])
        assert 0 < r["time_s"] < 300 and r["path_length_m"] >= 0.9 * r["optimum_m"]
        assert r["min_clearance_m"] >= 0.199 - 0.05   # the inscribed radius, within a cell
    assert result.sim_time < 300.0   # the run ended when the goals were done


def _ompl_run(tmp_path, name: str, seed: int):
    plan = load_launch(PACKAGE_ROOT / "launch/qbot_navigation.launch.yaml",
                       {"slam": "false", "map": str(tmp_path / "house.yaml"), "goal": "-3.3 2.4 0.0",
                        "global_planner": "ompl_global_planner/OmplGlobalPlanner"})
    bag = tmp_path / name
    result = run(plan, RunOptions(duration=4.0, bag=bag, seed=seed))
    assert result.error is None
    b = Bag(bag)
    plans = [[(p.pose.position.x, p.pose.position.y) for p in msg.poses]
             for _, msg in b.messages("/move_base/OmplGlobalPlanner/plan")]
    cmds = [(t, m.linear.x, m.angular.z) for t, m in b.messages("/qbot/cmd_vel")]
    return plans, cmds


def test_the_same_seed_gives_the_same_ompl_plans_and_commands(tmp_path):
    _bench().house_map(tmp_path)
    a = _ompl_run(tmp_path, "a.bag", 3)
    b = _ompl_run(tmp_path, "b.bag", 3)
    c = _ompl_run(tmp_path, "c.bag", 4)
    assert a[0] and a[1]
    assert a == b
    assert a[0] != c[0]
