"""The navigation launch's goal sender (twil_control/move_base_goals) with no goals: move_base
waits for goals from elsewhere (the view's goal panel) and the run ends at --duration."""

from __future__ import annotations

import math

import pytest

from twil_control import PACKAGE_ROOT
from twil_control.bag.reader import Bag
from twil_control.core.messages import header, msg_class, time_msg
from twil_control.core.node import Master, Node
from twil_control.launch.loader import load_launch
from twil_control.launch.runner import RunOptions, run
from twil_control.nodes.move_base_goals import MoveBaseGoals


def _sender(master: Master, **params) -> MoveBaseGoals:
    for key, value in params.items():
        master.params.set(f"/goals/{key}", value)
    return MoveBaseGoals(master, "goals")


def test_with_no_goals_the_sender_sends_nothing_and_never_ends_the_run():
    master = Master()
    sent = []
    Node(master, "probe").create_subscription(
        "/move_base/goal", "twil_control/MoveBaseActionGoal", sent.append
    )
    sender = _sender(master)
    sender.on_start()
    master.spin_until(5.0)
    assert sent == [] and sender.goals == []
    assert sender.is_done() is False


def test_with_goals_the_sender_sends_the_first_after_start_delay_and_is_done_after_its_result():
    master = Master()
    sent = []
    Node(master, "probe").create_subscription(
        "/move_base/goal", "twil_control/MoveBaseActionGoal", lambda m: sent.append((master.clock.now(), m))
    )
    sender = _sender(master, goals="1 2 0.5", start_delay=0.5)
    sender.on_start()
    master.spin_until(1.0)
    assert len(sent) == 1 and sent[0][0] == pytest.approx(0.5)
    assert sent[0][1].goal.target_pose.pose.position.x == 1.0 and not sender.is_done()


def test_a_goal_without_a_result_within_timeout_is_cancelled_and_the_next_one_sent():
    master = Master()
    probe = Node(master, "probe")
    sent, cancels = [], []
    probe.create_subscription(
        "/move_base/goal",
        "twil_control/MoveBaseActionGoal",
        lambda m: sent.append((master.clock.now(), m.goal_id.id)),
    )
    probe.create_subscription(
        "/move_base/cancel", "actionlib_msgs/GoalID", lambda m: cancels.append((master.clock.now(), m.id))
    )
    sender = _sender(master, goals="1 2 0; 3 4 0", start_delay=0.5, timeout=2.0)
    sender.on_start()
    master.spin_until(3.0)
    assert sent == [(0.5, "/goals/goal_1")]
    assert len(cancels) == 1 and cancels[0][1] == "/goals/goal_1"
    assert cancels[0][0] == pytest.approx(2.5, abs=0.1 + 1e-9)  # checked every 0.1 s
    with pytest.raises(ValueError, match="timeout must be >= 0 s"):
        _sender(Master(), goals="1 2 0", timeout=-1.0)


def test_on_move_base_simple_goal_poses_go_one_after_each_result_whatever_its_id():
    # rviz's 2D Nav Goal: a bare PoseStamped; move_base names the goal itself, so the next
    # result after a goal is its result; a timeout cancels with an empty id (whatever is pursued)
    master = Master()
    probe = Node(master, "probe")
    sent, cancels = [], []
    probe.create_subscription(
        "/move_base_simple/goal", "geometry_msgs/PoseStamped", lambda m: sent.append((master.clock.now(), m))
    )
    probe.create_subscription("/move_base/cancel", "actionlib_msgs/GoalID", lambda m: cancels.append(m.id))
    results = probe.create_publisher("/move_base/result", "twil_control/MoveBaseActionResult")
    sender = _sender(
        master, goals="1 2 0; 3 4 1.5; 5 6 0", start_delay=0.5, timeout=4.0, topic="/move_base_simple/goal"
    )
    sender.on_start()
    master.spin_until(1.0)
    assert [(t, m.header.frame_id, m.pose.position.x) for t, m in sent] == [(0.5, "map", 1.0)]
    results.publish(
        msg_class("twil_control/MoveBaseActionResult")(
            header=header("", 0.9),
            status=msg_class("actionlib_msgs/GoalStatus")(
                goal_id=msg_class("actionlib_msgs/GoalID")(stamp=time_msg(0.5), id="/move_base-1-0.500"),
                status=3,
                text="goal reached",
            ),
            result=msg_class("twil_control/MoveBaseResult")(),
        )
    )
    master.spin_until(2.0)
    assert [m.pose.position.x for _, m in sent] == [1.0, 3.0]
    assert sent[1][1].pose.orientation.z == pytest.approx(math.sin(0.75), abs=1e-12)
    master.spin_until(5.2)  # the second goal's 4 s run out at 5.0 s
    assert cancels == [""] and [o[1] for o in sender.outcomes] == [3] and not sender.is_done()


def test_goals_and_a_goals_file_together_are_refused():
    with pytest.raises(ValueError, match="at most one of goals"):
        _sender(Master(), goals="1 2 0", file="goals.yaml")


def test_the_navigation_launch_without_a_goal_runs_until_the_duration_with_move_base_idle(tmp_path):
    plan = load_launch(PACKAGE_ROOT / "launch/qbot_navigation.launch.yaml", {})
    bag = tmp_path / "idle.bag"
    result = run(plan, RunOptions(duration=1.5, bag=bag))
    assert result.error is None
    assert result.sim_time == pytest.approx(1.5)  # not ended at once by a goal sender with nothing to do
    b = Bag(bag)
    # no goal was sent and move_base never commanded the robot (recorded topics are those with messages)
    assert "/move_base/goal" not in b.topics and "/move_base/result" not in b.topics
    assert "/qbot/cmd_vel" not in b.topics
    status = [m for _, m in b.messages("/move_base/status")]
    assert len(status) >= 5 and all(len(m.status_list) == 0 for m in status)  # 5 Hz, no goal
