"""Recording nothing is a warning: a recorded topic that no node publishes is named at start,
and one that got no message at the end; the bag is written as before."""

from __future__ import annotations

import textwrap

import pytest
from conftest import bag_connections

from twil_control.core.ros_node import RosNode
from twil_control.launch import node_types as registry
from twil_control.launch.__main__ import main


class Talker(RosNode):
    """Publishes on ~count at 10 Hz, advertises ~silent (never used) and latches ~latched."""

    def __init__(self, *a, **kw):
        super().__init__(*a, **kw)
        self.pub = self.create_publisher("~count", "std_msgs/Int32")
        self.create_publisher("~silent", "std_msgs/Int32")
        latched = self.create_publisher("~latched", "std_msgs/Int32", latch=True)
        latched.publish(latched._cls(data=7))
        self.create_timer(0.1, lambda event: self.pub.publish(self.pub._cls(data=1)))


@pytest.fixture(autouse=True)
def talker(monkeypatch):
    monkeypatch.setitem(registry.BUILTIN, "test_pkg/talker", f"{__name__}:Talker")


def _run(tmp_path, capsys, record: str = ""):
    launch = tmp_path / "t.launch.yaml"
    launch.write_text(
        textwrap.dedent(f"""
        launch:
          - node: {{pkg: test_pkg, type: talker, name: a}}
          {record}
    """)
    )
    bag = tmp_path / "out.bag"
    code = main([str(launch), "--duration", "0.5", "--bag", str(bag)])
    return code, [line for line in capsys.readouterr().err.splitlines() if "WARNING" in line], bag


def test_a_topic_nobody_publishes_is_warned_about_at_start_and_at_the_end(tmp_path, capsys):
    code, warnings, bag = _run(tmp_path, capsys, "- record: {topics: [/no_such_topic, /a/cuont, /a/count]}")
    assert code == 0
    assert warnings == [
        "[WARNING] [0.000]: record: no node publishes /no_such_topic, so the bag will hold nothing of it",
        "[WARNING] [0.000]: record: no node publishes /a/cuont, so the bag will hold nothing of it (published "
        "topics near it: /a/count)",
        "[WARNING] [0.500]: record: /no_such_topic got no message during the run",
        "[WARNING] [0.500]: record: /a/cuont got no message during the run",
    ]
    assert {t: c[2] for t, c in bag_connections(bag).items() if t != "/rosout"} == {"/a/count": 5}


def test_a_publisher_that_sends_nothing_is_named_at_the_end(tmp_path, capsys):
    code, warnings, bag = _run(tmp_path, capsys, "- record: {topics: [/a/silent, /a/latched]}")
    assert code == 0
    assert warnings == [
        "[WARNING] [0.500]: record: /a/silent got no message during the run (published by /a, "
        "which sent nothing)"
    ]
    assert {t: c[2] for t, c in bag_connections(bag).items() if t != "/rosout"} == {"/a/latched": 1}


def test_recording_every_topic_warns_about_none(tmp_path, capsys):
    code, warnings, bag = _run(tmp_path, capsys)
    assert code == 0 and warnings == []
    assert set(bag_connections(bag)) - {"/rosout"} == {"/a/count", "/a/latched"}
