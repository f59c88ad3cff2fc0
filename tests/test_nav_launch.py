"""The navigation launch end to end in Drake (slow): qbot reaching a goal through a doorway of the
house world through move_base with no contact with the world on a near-optimal path, the bag's
navigation analysis, and the same seed giving the same bag's OMPL plans and commands. (The 20
seeded goals are bench/nav_goals.py's; that another seed gives other plans is
tests/test_nav_move_base.py's, without a launch.)"""

from __future__ import annotations

import importlib.util

import pytest

from twil_control import PACKAGE_ROOT
from twil_control.bag.reader import Bag
from twil_control.launch.loader import load_launch
from twil_control.launch.runner import RunOptions, run

pytestmark = pytest.mark.slow

# from the spawn (0, 0, 0) in the hall, through the 1 m doorway in the wall x = 2 (y 1.05..2.0)
# into the east room: a turn before and after the doorway
DOORWAY_GOAL = (3.2, 1.5, 0.0)


def _bench():
    spec = importlib.util.spec_from_file_location("nav_goals", PACKAGE_ROOT / "bench/nav_goals.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_qbot_reaches_a_goal_through_a_doorway_without_contact_on_a_near_optimal_path(tmp_path):
    bench = _bench()
    map_yaml, m, _ = bench.house_map(tmp_path)
    metrics, result, _ = bench.run_goals([DOORWAY_GOAL], 5, tmp_path, map_yaml, duration=120.0)
    [row] = bench.score(metrics, m, tolerance=0.5)
    assert row["status"] == "SUCCEEDED"
    assert row["reached"]  # within xy_goal_tolerance 0.5 m
    assert row["collision_samples"] == 0  # no contact but the wheels on the floor
    assert row["ratio"] <= 1.15  # driven / grid optimum (about 3.7 m)
    assert (row["target_x_m"], row["target_y_m"]) == DOORWAY_GOAL[:2]
    assert 0 < row["time_s"] < 120 and row["optimum_m"] > 3.0
    assert row["min_clearance_m"] >= 0.199 - 0.05  # the inscribed radius, within a cell
    assert result.sim_time < 120.0  # the run ended with the goal's result


def _ompl_run(tmp_path, name: str, seed: int):
    plan = load_launch(
        PACKAGE_ROOT / "launch/qbot_navigation.launch.yaml",
        {
            "slam": "false",
            "map": str(tmp_path / "house.yaml"),
            "goal": "-3.3 2.4 0.0",
            "global_planner": "ompl_global_planner/OmplGlobalPlanner",
        },
    )
    bag = tmp_path / name
    result = run(plan, RunOptions(duration=3.0, bag=bag, seed=seed))
    assert result.error is None
    b = Bag(bag)
    plans = [
        [(p.pose.position.x, p.pose.position.y) for p in msg.poses]
        for _, msg in b.messages("/move_base/OmplGlobalPlanner/plan")
    ]
    cmds = [(t, m.linear.x, m.angular.z) for t, m in b.messages("/qbot/cmd_vel")]
    return plans, cmds


def test_the_same_seed_gives_the_same_ompl_plans_and_commands(tmp_path):
    _bench().house_map(tmp_path)
    a = _ompl_run(tmp_path, "a.bag", 3)
    b = _ompl_run(tmp_path, "b.bag", 3)
    assert a[0] and len(a[1]) >= 20 * 1.5  # a plan, and 20 Hz commands for the 2 s after the goal
    assert any(v != 0.0 or w != 0.0 for _, v, w in a[1])  # the robot was being driven
    assert a == b
