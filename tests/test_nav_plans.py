"""move_base's plan helpers as pure functions (navigation/plans.py, navigation/goals.py): the
reasons no plan can exist, the plan in the local frame from the robot on, the goals refused, a
plan blocked by what the costmap has since gained."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

from twil_control.navigation import costmap as cm
from twil_control.navigation.goals import validate_goal
from twil_control.navigation.plans import blocked_ahead, diagnose, prune, transform_path


def _room(wall_col: int | None = None) -> cm.Costmap:
    """A free 4 m x 4 m costmap at 0.1 m from (0, 0), optionally cut in two by a lethal wall."""
    m = cm.Costmap(40, 40, 0.1, 0.0, 0.0, default=cm.FREE)
    if wall_col is not None:
        m.costs[:, wall_col] = cm.LETHAL
    return m


def test_diagnose_names_why_no_plan_can_exist():
    free = _room()
    assert diagnose(free, (0.5, 0.5), (3.5, 3.5), allow_unknown=False) is None
    outside = diagnose(free, (0.5, 0.5), (5.0, 1.0), allow_unknown=False)
    assert outside.structural and "outside the map (x 0.00..4.00, y 0.00..4.00)" in outside.reason
    walled = diagnose(_room(wall_col=20), (0.5, 0.5), (3.5, 0.5), allow_unknown=False)
    assert walled.structural and "unreachable" in walled.reason
    in_wall = diagnose(_room(wall_col=20), (0.5, 0.5), (2.05, 0.5), allow_unknown=False)
    assert in_wall.structural and "is in an obstacle (cost 254)" in in_wall.reason


def test_a_plan_moved_into_the_local_frame_and_pruned_to_the_robot():
    plan = np.column_stack([np.linspace(0, 2, 21), np.zeros(21), np.zeros(21)])
    moved = transform_path(plan, (1.0, 2.0, math.pi / 2))  # x along +y, shifted by (1, 2)
    np.testing.assert_allclose(moved[-1], [1.0, 4.0, math.pi / 2], atol=1e-12)
    ahead = prune(moved, (1.02, 3.01))  # the robot next to the plan's point (1, 3), the 11th
    assert len(ahead) == 11
    np.testing.assert_allclose(ahead[0], [1.0, 3.0, math.pi / 2], atol=1e-12)


def _goal(x=1.0, y=2.0, qz=0.0, qw=1.0):
    return SimpleNamespace(
        pose=SimpleNamespace(
            position=SimpleNamespace(x=x, y=y, z=0.0), orientation=SimpleNamespace(x=0.0, y=0.0, z=qz, w=qw)
        )
    )


def test_goals_with_non_finite_values_or_an_unnormalised_quaternion_are_refused():
    assert validate_goal(_goal()) is None
    assert "NaN or infinite" in validate_goal(_goal(x=math.nan))
    assert "zero quaternion" in validate_goal(_goal(qw=0.0))
    assert "|q| = 1.100000" in validate_goal(_goal(qw=1.1))
    assert validate_goal(_goal(qw=1.0005)) is None  # within QUAT_TOLERANCE


def test_a_plan_is_blocked_by_a_cell_no_plan_could_cross_beyond_the_clearance_radius():
    # the plan along y = 2 from x 0.5 to 3.5; the robot at its start
    plan = np.column_stack([np.linspace(0.5, 3.5, 31), np.full(31, 2.05), np.zeros(31)])
    robot = (0.5, 2.05, 0.0)
    assert not blocked_ahead(_room(), plan, robot, 0.4, allow_unknown=False)
    walled = _room(wall_col=20)  # x 2.0..2.1 lethal, 1.5 m ahead
    assert blocked_ahead(walled, plan, robot, 0.4, allow_unknown=False)
    inscribed = _room()
    inscribed.costs[:, 20] = cm.INSCRIBED  # the planner's lethal_cost by default
    assert blocked_ahead(inscribed, plan, robot, 0.4, allow_unknown=False)
    assert not blocked_ahead(inscribed, plan, robot, 0.4, allow_unknown=False, lethal=cm.LETHAL)
    # an obstacle within the clearance radius is the robot's own inflation, not a blocked plan
    near = _room(wall_col=7)  # x 0.7..0.8: 0.2-0.3 m from the robot
    assert not blocked_ahead(near, plan, robot, 0.4, allow_unknown=False)
    # the part of the plan behind the robot does not count
    assert not blocked_ahead(walled, plan, (3.0, 2.05, 0.0), 0.4, allow_unknown=False)


def test_unknown_cells_block_a_plan_only_when_the_planner_may_not_cross_them():
    plan = np.column_stack([np.linspace(0.5, 3.5, 31), np.full(31, 2.05), np.zeros(31)])
    unknown = _room()
    unknown.costs[:, 25:28] = cm.NO_INFORMATION
    assert blocked_ahead(unknown, plan, (0.5, 2.05, 0.0), 0.4, allow_unknown=False)
    assert not blocked_ahead(unknown, plan, (0.5, 2.05, 0.0), 0.4, allow_unknown=True)
