"""`rostopic pub` and `rosbag record` as launch nodes, as ROS users write them in launch files:
rostopic's modes (latched once, -1, -r RATE, --latch, -s) in simulated time, its YAML message
syntax, its errors; rosbag record's topics and its -O/-o naming the run's one bag. No world is
simulated: the runs take a fraction of a second."""

from __future__ import annotations

import logging
import re
import textwrap

import numpy as np
import pytest
from conftest import read_bag

from twil_control.core.node import Master
from twil_control.core.ros_node import NodeArgsError
from twil_control.launch import node_types
from twil_control.launch.__main__ import main
from twil_control.launch.loader import load_launch
from twil_control.launch.plan import LaunchError, RecordOutput
from twil_control.launch.runner import RunOptions, run


def _pub(master: Master, args: str, name: str = "pub"):
    cls = node_types.get("rostopic", "rostopic")
    return cls(master, name, "/", {}, ["pub", *__import__("shlex").split(args)])


def _received(master: Master, topic: str, msgtype: str) -> list:
    got = []
    master.bus.subscribe(topic, msgtype, lambda m: got.append((master.clock.now(), m)), node="/test")
    return got


def test_rate_publishes_at_every_period_of_simulated_time_from_time_0():
    master = Master()
    node = _pub(master, "-r 10 /cmd_vel geometry_msgs/Twist '{linear: {x: 0.2}, angular: {z: -0.5}}'")
    got = _received(master, "/cmd_vel", "geometry_msgs/Twist")
    node.on_start()
    master.spin_until(2.0)
    times = np.array([t for t, _ in got])
    assert len(times) == 21  # 0, 0.1, ..., 2.0
    np.testing.assert_allclose(times, np.arange(21) * 0.1, atol=1e-9)
    assert {(m.linear.x, m.linear.y, m.angular.z) for _, m in got} == {(0.2, 0.0, -0.5)}
    assert not master.bus.is_latched("/cmd_vel")  # -r without --latch


def test_without_rate_one_latched_message_reaches_late_subscribers_and_stays():
    master = Master()
    node = _pub(master, "/note std_msgs/String hello")
    node.on_start()
    master.spin_until(10.0)
    late = _received(master, "/note", "std_msgs/String")  # subscribes at t = 10 s
    assert [(t, m.data) for t, m in late] == [(10.0, "hello")]
    assert node.published == 1


def test_once_publishes_latched_then_exits_after_3_s_withdrawing_the_latched_message():
    master = Master()
    node = _pub(master, "/flag std_msgs/Bool true -1")  # -1 after the words, as optparse allows
    node.on_start()
    master.spin_until(2.9)
    early = _received(master, "/flag", "std_msgs/Bool")
    master.spin_until(3.1)
    late = _received(master, "/flag", "std_msgs/Bool")
    assert [(t, m.data) for t, m in early] == [(2.9, True)]
    assert late == [] and node.exited and master.bus.publishers_of("/flag") == []


def test_latch_with_rate_keeps_the_last_message_for_late_subscribers():
    master = Master()
    node = _pub(master, "--latch -r 2 /count std_msgs/Int32 '{data: 7}'")
    node.on_start()
    master.spin_until(1.2)
    late = _received(master, "/count", "std_msgs/Int32")
    assert node.published == 3 and [(t, m.data) for t, m in late] == [(1.2, 7)]


def test_message_values_as_rostopic_reads_them_positional_keywords_and_times():
    master = Master()
    master.clock.set(0.0)
    twist = _pub(master, "/cmd geometry_msgs/Twist -- '[0.5, 0, 0]' '[0, 0, -1.5]'", "twist")
    assert (twist.msg.linear.x, twist.msg.angular.z) == (0.5, -1.5)  # '--' before a negative number
    empty = _pub(master, "/e std_msgs/Empty '{}'", "empty")
    assert empty.msg.__msgtype__ == "std_msgs/msg/Empty"
    timed = _pub(master, "/t std_msgs/Header '{seq: 4, stamp: {secs: 3, nsecs: 250}, frame_id: map}'", "hdr")
    assert (timed.msg.seq, timed.msg.stamp.sec, timed.msg.stamp.nanosec, timed.msg.frame_id) == (
        4,
        3,
        250,
        "map",
    )
    stamped = _pub(
        master, "-s -r 4 /goal geometry_msgs/PoseStamped '{header: auto, pose: {orientation: {w: 1}}}'"
    )
    got = _received(master, "/goal", "geometry_msgs/PoseStamped")
    stamped.on_start()
    master.spin_until(1.0)
    # -s: 'auto' is stamped again at every publish, with simulated time
    stamps = [m.header.stamp.sec + m.header.stamp.nanosec * 1e-9 for _, m in got]
    np.testing.assert_allclose(stamps, [t for t, _ in got], atol=1e-9)
    np.testing.assert_allclose(stamps, [0.0, 0.25, 0.5, 0.75, 1.0], atol=1e-9)


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (
            "pub /x geometry_msgs/Twist '{linear: {q: 1}}'",
            "no field 'q' in geometry_msgs/Vector3; its fields: x, y, z",
        ),
        (
            "pub /x geometry_msgs/Twist '[1, 2, 3]'",
            "not enough values for geometry_msgs/Twist: 1 given, 2 expected (linear, angular)",
        ),
        ("pub /x std_msgs/String '{data: 3}'", "data: expected a string, got 3"),
        ("pub -r 10 -1 /x std_msgs/Bool true", "-r and -1 (--once) exclude each other"),
        ("pub -r 0 /x std_msgs/Bool true", "the rate must be a number of Hz > 0 (got 0.0)"),
        ("pub -r fast /x std_msgs/Bool true", "the rate 'fast' is not a number"),
        ("pub /x std_msgs/Bool", "give the message values"),
        ("pub /x", "give the message type"),
        ("pub /x std_msgs/Nope '{}'", "unknown message type 'std_msgs/Nope'"),
        (
            "pub /x std_msgs/Header '{stamp: 1.5}'",
            "stamp: 1.5 is not a time; give 'now', integer nanoseconds",
        ),
        ("pub /x std_msgs/String '{data: [1'", "a value is not YAML"),
        ("pub -f msgs.yaml /x std_msgs/String", "-f FILE is not supported here"),
        ("pub --bogus /x std_msgs/Bool true", "no such option: --bogus"),
        (
            "publish /x std_msgs/Bool true",
            "rostopic publish: the commands are pub, which publishes, and echo",
        ),
    ],
)
def test_a_wrong_rostopic_command_line_is_one_error_naming_the_node(args, expected):
    with pytest.raises((NodeArgsError, KeyError)) as err:
        node_types.get("rostopic", "rostopic")(Master(), "pub", "/", {}, __import__("shlex").split(args))
    assert expected in str(err.value) and "/pub" in str(err.value)


def _write(tmp_path, text: str, name: str = "run.launch"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text).lstrip())
    return path


PUB_AND_RECORD = """
<launch>
  <arg name="speed" default="0.2"/>
  <group ns="robot">
    <node pkg="rostopic" type="rostopic" name="drive"
          args="pub -r 10 cmd_vel geometry_msgs/Twist '{linear: {x: $(arg speed)}}'"/>
  </group>
  <node pkg="rostopic" type="rostopic" name="note" args="pub /note std_msgs/String 'started'"/>
  <node pkg="rostopic" type="rostopic" name="unrecorded" args="pub -r 5 /other std_msgs/Bool true"/>
  <node pkg="rosbag" type="record" name="record" args="-O {name} /robot/cmd_vel /note"/>
</launch>
"""


def test_rostopic_pub_in_a_launch_is_in_the_bag_that_rosbag_record_names(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    path = _write(tmp_path, PUB_AND_RECORD.replace("{name}", "drive_run"))
    assert main([str(path), "--duration", "2", "speed:=0.35"]) == 0
    bag = read_bag(tmp_path / "drive_run.bag")  # -O NAME: NAME.bag, relative to the working directory
    assert sorted(bag) == ["/note", "/robot/cmd_vel"]  # the named topics (and /rosout, silent here)
    times = np.array([t for t, _ in bag["/robot/cmd_vel"]]) * 1e-9
    # the bag starts once every node has started (rosbag record joining a running graph): the
    # unlatched message of time 0 is not in it, those of 0.1 .. 2.0 s are
    assert len(times) == 20
    np.testing.assert_allclose(np.diff(times), 0.1, atol=1e-9)
    np.testing.assert_allclose(times[[0, -1]], [0.1, 2.0], atol=1e-9)
    assert {m.linear.x for _, m in bag["/robot/cmd_vel"]} == {0.35}
    # the latched message of time 0 is: rosbag record gets it when it subscribes
    assert [(t, m.data) for t, m in bag["/note"]] == [(0, "started")]
    assert not list(tmp_path.glob("runs/*.bag"))  # one recording, not a second copy


def test_rosbag_record_prefix_names_the_bag_with_the_date_and_bag_wins_over_it(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    path = _write(tmp_path, PUB_AND_RECORD.replace("-O {name}", "-o out/drive"))
    (tmp_path / "out").mkdir()
    assert main([str(path), "--duration", "0.5"]) == 0
    (bag,) = (tmp_path / "out").iterdir()
    assert re.fullmatch(r"drive_\d{4}-\d\d-\d\d-\d\d-\d\d-\d\d\.bag", bag.name), bag.name
    assert main([str(path), "--duration", "0.5", "--bag", str(tmp_path / "given.bag")]) == 0
    assert (tmp_path / "given.bag").is_file() and len(list((tmp_path / "out").iterdir())) == 1
    assert (
        f"--bag {tmp_path / 'given.bag'}: the bag of rosbag record -o out/drive ({path}:9:3) is not written"
        in capsys.readouterr().err
    )


def test_rosbag_record_output_names_rules_and_conflicts(tmp_path):
    assert RecordOutput("run.bag", False, "").path("bag").name == "run.bag"
    assert RecordOutput("run", False, "").path("mcap").name == "run.mcap"
    assert RecordOutput("run.mcap", False, "").suffix_format() == "mcap"
    two = _write(
        tmp_path,
        """
        <launch>
          <node pkg="rosbag" type="record" name="a" args="-O one /x"/>
          <node pkg="rosbag" type="record" name="b" args="-O two /y"/>
        </launch>""",
    )
    with pytest.raises(LaunchError) as err:
        load_launch(two)
    assert str(err.value) == (
        f"{two}:3:3: rosbag record -O two names another bag than -O one at {two}:2:3; a launch records one bag"
    )
    both = _write(
        tmp_path,
        '<launch><node pkg="rosbag" type="record" name="a" args="-O a -o b -a"/></launch>',
        "b.launch",
    )
    with pytest.raises(LaunchError, match="takes one of -O and -o, once"):
        load_launch(both)
    plan = load_launch(
        _write(
            tmp_path,
            '<launch><node pkg="rosbag" type="record" name="a" args="--output-name=x -a"/></launch>',
            "c.launch",
        )
    )
    assert plan.record_output.option == "-O x" and plan.record_topics is None


def test_display_nodes_do_not_stop_a_headless_run_and_are_announced_once_each(tmp_path, caplog):
    path = _write(
        tmp_path,
        """
        <launch>
          <node pkg="rviz" type="rviz" name="rviz" args="-d $(dirname)/nav.rviz" required="true"/>
          <node pkg="gazebo_ros" type="gzclient" name="gazebo_gui" args="--verbose"/>
          <node pkg="rqt_robot_steering" type="rqt_robot_steering" name="steering"/>
          <node pkg="image_view" type="image_view" name="camera_view"/>
          <node pkg="rostopic" type="rostopic" name="echo" args="echo /note"/>
          <node pkg="rostopic" type="rostopic" name="note" args="pub /note std_msgs/String hi"/>
        </launch>""",
    )
    with caplog.at_level(logging.INFO, logger="twil_control.launch"):
        result = run(load_launch(path), RunOptions(duration=1.0))
    assert not result.failed and result.sim_time == pytest.approx(1.0)
    lines = [r.getMessage() for r in caplog.records if "only displays" in r.getMessage()]
    assert lines == [
        f"node /{name} ({kind}, {path}:{line}:3) only displays: not run headless (--view opens the browser "
        f"view in its place)"
        for name, kind, line in [
            ("rviz", "rviz/rviz", 2),
            ("gazebo_gui", "gazebo_ros/gzclient", 3),
            ("steering", "rqt_robot_steering/rqt_robot_steering", 4),
            ("camera_view", "image_view/image_view", 5),
            ("echo", "rostopic/rostopic", 6),
        ]
    ]
    from twil_control.launch.display_nodes import announce

    caplog.clear()
    with caplog.at_level(logging.INFO, logger="twil_control.launch"):
        assert announce(result.nodes, load_launch(path).nodes, view_served=True) == 5
    assert (
        "node /rviz (rviz/rviz, " in caplog.text
        and "the view (--view) shows the run in its place" in caplog.text
    )
