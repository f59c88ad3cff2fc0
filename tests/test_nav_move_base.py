"""move_base on the in-process bus with a static map and a kinematic fake robot (no Drake):
goal outcomes and their actionlib status codes and texts."""

from __future__ import annotations

import math

import numpy as np
import pytest
from support.nav_fakes import KinematicRobot, move_base_params, occupancy_grid

from twil_control.core.messages import header, msg_class
from twil_control.core.node import Master, Node
from twil_control.nodes.move_base import ABORTED, ACTIVE, PREEMPTED, REJECTED, SUCCEEDED, MoveBase

RES = 0.05


def _room() -> np.ndarray:
    """A 6 m x 4 m room with walls, a closed 1 m box-room (walls all round) at x 4..5, y 2.5..3.5,
    and a pillar at (3, 1)."""
    g = np.zeros((80, 120), np.int8)
    g[:2, :] = g[-2:, :] = 100
    g[:, :2] = g[:, -2:] = 100
    g[50:70, 80:82] = g[50:70, 100:102] = 100  # closed room: x 4.0..5.1, y 2.5..3.5
    g[50:52, 80:102] = g[68:70, 80:102] = 100
    g[15:25, 55:65] = 100  # pillar x 2.75..3.25, y 0.75..1.25
    return g


class Harness:
    def __init__(
        self,
        planner: str = "navfn/NavfnROS",
        start=(1.0, 1.0, 0.0),
        publish_map: bool = True,
        seed: int = 0,
        files=(),
        **overrides,
    ) -> None:
        self.master = Master()
        self.master.seed = seed  # the launch's --seed
        move_base_params(self.master.params, planner, **overrides)
        for file in files:  # a user's files, loaded last into /move_base
            self.master.params.load_file(file, "/move_base")
        self.pub_node = Node(self.master, "test")
        self.map_pub = self.pub_node.create_publisher("/map", "nav_msgs/OccupancyGrid", latch=True)
        if publish_map:
            self.publish_map()
        self.robot = KinematicRobot(self.master, start)
        self.mb = MoveBase(self.master, "move_base")
        self.goal_pub = self.pub_node.create_publisher("/move_base_simple/goal", "geometry_msgs/PoseStamped")
        self.results = []
        self.status = []
        self.pub_node.create_subscription(
            "/move_base/result",
            "twil_control/MoveBaseActionResult",
            lambda m: self.results.append((self.master.clock.now(), m.status)),
        )
        self.pub_node.create_subscription(
            "/move_base/status", "actionlib_msgs/GoalStatusArray", lambda m: self.status.append(m)
        )

    def publish_map(self) -> None:
        self.map_pub.publish(occupancy_grid(_room(), RES))

    def send(self, x, y, yaw=0.0, quat=None):
        q = quat if quat is not None else (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))
        msg = msg_class("geometry_msgs/PoseStamped")(
            header=header("map", self.master.clock.now()),
            pose=msg_class("geometry_msgs/Pose")(
                position=msg_class("geometry_msgs/Point")(x=x, y=y, z=0.0),
                orientation=msg_class("geometry_msgs/Quaternion")(x=q[0], y=q[1], z=q[2], w=q[3]),
            ),
        )
        self.goal_pub.publish(msg)

    def run(self, seconds: float) -> None:
        self.master.spin_until(self.master.clock.now() + seconds)


def test_goal_is_reached_and_succeeds_with_the_robot_stopped():
    h = Harness()
    h.run(0.5)
    h.send(5.0, 1.0, math.pi / 2)
    h.run(60.0)
    assert [r[1].status for r in h.results] == [SUCCEEDED]
    x, y, yaw = h.robot.pose
    assert math.hypot(x - 5.0, y - 1.0) <= 0.5 + 1e-9  # xy_goal_tolerance
    assert abs(math.remainder(yaw - math.pi / 2, 2 * math.pi)) <= 0.5 + 1e-9
    assert h.robot.cmd == (0.0, 0.0)


def test_a_new_goal_preempts_the_current_one_which_then_becomes_active():
    h = Harness()
    h.run(0.5)
    h.send(5.0, 1.0)
    h.run(2.0)
    h.send(1.0, 3.0)
    h.run(0.2)
    assert [r[1].status for r in h.results] == [PREEMPTED]
    assert "preempted by goal" in h.results[0][1].text
    active = [s for s in h.status[-1].status_list if s.status == ACTIVE]
    assert len(active) == 1 and active[0].goal_id.id != h.results[0][1].goal_id.id
    h.run(60.0)
    assert [r[1].status for r in h.results] == [PREEMPTED, SUCCEEDED]


@pytest.mark.parametrize(
    "quat, expect",
    [
        ((0.0, 0.0, 0.0, 0.0), "zero quaternion"),
        ((0.0, 0.0, 0.0, 1.002), "not normalised"),
        ((0.0, 0.0, math.nan, 1.0), "NaN"),
    ],
)
def test_goals_with_nan_or_a_bad_quaternion_are_rejected(quat, expect):
    h = Harness()
    h.run(0.2)
    h.send(2.0, 1.0, quat=quat)
    h.run(0.5)
    assert [r[1].status for r in h.results] == [REJECTED]
    assert expect in h.results[0][1].text


def test_a_quaternion_within_tolerance_is_accepted():
    h = Harness()
    h.run(0.2)
    h.send(2.0, 1.0, quat=(0.0, 0.0, 0.0, 1.0009))
    h.run(0.5)
    assert h.results == []


@pytest.mark.parametrize(
    "goal, expect",
    [
        ((3.0, 1.0), "is in an obstacle"),  # the pillar
        ((9.0, 1.0), "is outside the map"),
        ((4.55, 3.0), "is unreachable"),  # inside the closed room
    ],
)
def test_impossible_goals_abort_with_distinct_reasons_and_the_robot_stops(goal, expect):
    """With move_base's default recoveries: planner_patience, then conservative reset, a full turn,
    aggressive reset and another full turn, then ABORTED, the robot commanded to stop."""
    patience = 2.0
    h = Harness(planner_patience=patience)
    h.run(0.2)
    t0 = h.master.clock.now()
    h.send(*goal)
    h.run(patience + 20.0)
    assert [r[1].status for r in h.results] == [ABORTED]
    t_abort, status = h.results[0]
    assert expect in status.text and "recovery" in status.text
    # each rotation turns 2 pi less the yaw tolerance at >= min_in_place_vel_theta (1 rad/s)
    tp = h.mb.traj_params
    turn = (2 * math.pi - tp.yaw_goal_tolerance) / tp.min_in_place_vel_theta
    assert patience + 2 * 1.0 < t_abort - t0 <= patience + 2 * turn + 0.5
    rotations = [c for c in h.robot.cmds if t0 < c[0] < t_abort and c[2] != 0.0]
    assert rotations and all(c[1] == 0.0 for c in rotations)  # the recoveries turn in place
    assert h.robot.cmd == (0.0, 0.0)
    x, y, _ = h.robot.pose
    assert math.hypot(x - 1.0, y - 1.0) < 1e-9  # never drove towards the goal


def test_a_goal_waits_for_the_map_and_patience_starts_when_it_arrives():
    h = Harness(publish_map=False, planner_patience=1.0)
    h.run(0.2)
    h.send(5.0, 1.0)
    h.run(10.0)  # far beyond patience plus recoveries: still waiting
    assert h.results == [] and h.robot.cmd == (0.0, 0.0)
    assert [s.status for s in h.status[-1].status_list] == [ACTIVE]
    h.publish_map()
    h.run(60.0)
    assert [r[1].status for r in h.results] == [SUCCEEDED]


def test_the_run_seed_reaches_the_ompl_planner_same_seed_same_plan_another_seed_another():
    """What the launch's --seed does to move_base's OMPL plans (the end-to-end bag equality is
    tests/test_nav_launch.py's): the same seed gives the same first plan, another seed another."""

    def first_plan(seed: int) -> list:
        h = Harness("ompl_global_planner/OmplGlobalPlanner", seed=seed)
        plans = []
        h.pub_node.create_subscription(
            "/move_base/OmplGlobalPlanner/plan",
            "nav_msgs/Path",
            lambda m: plans.append([(p.pose.position.x, p.pose.position.y) for p in m.poses]),
        )
        h.run(0.2)
        h.send(5.0, 1.0)
        h.run(0.2)
        assert plans, [r[1].text for r in h.results]
        return plans[0]

    a, b, c = first_plan(3), first_plan(3), first_plan(4)
    assert a == b
    assert a != c
