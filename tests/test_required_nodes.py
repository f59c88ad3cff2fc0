"""roslaunch's required and respawn for in-process nodes, and the exit codes they lead to.

A required node's failure stops the launch (exit 2 before time starts, with no bag; exit 1
while time runs, with the bag closed); any other node's failure is logged, the node is taken
out, the launch goes on and still exits 1; respawn restarts it. Launches of pure ROS nodes
(no world) keep these tests fast; one runs through the Drake simulator."""

from __future__ import annotations

import textwrap

import pytest
from conftest import read_bag

from twil_control.core.ros_node import RosNode
from twil_control.launch import node_types as registry
from twil_control.launch.__main__ import main


class Counter(RosNode):
    """Publishes 1, 2, 3... on ~count at 10 Hz; fails fail_at (param) seconds after it was made,
    by raising or by calling self.fail(), in its timer or in on_start (fail_at = 0)."""

    def __init__(self, *a, **kw):
        super().__init__(*a, **kw)
        self.t0 = self.now()
        self.fail_at = self.get_param("~fail_at", -1.0)
        self.how = self.get_param("~how", "raise")
        self.pub = self.create_publisher("~count", "std_msgs/Int32")
        self.count = 0
        self.create_timer(0.1, self.tick)

    def _fail(self):
        if self.how == "raise":
            raise RuntimeError(f"deliberate failure of {self.fqn}")
        self.fail(f"{self.fqn} gives up on purpose")

    def on_start(self):
        if self.fail_at == 0.0:
            self._fail()

    def tick(self, event):
        if 0 < self.fail_at <= event.current_expected - self.t0 + 1e-9:
            self._fail()
        self.count += 1
        self.pub.publish(self.pub._cls(data=self.count))


class Listener(RosNode):
    """Subscribes to /a/count and raises on the third message."""

    def __init__(self, *a, **kw):
        super().__init__(*a, **kw)
        self.seen = 0
        self.create_subscription("/a/count", "std_msgs/Int32", self.on_count)

    def on_count(self, msg):
        self.seen += 1
        if self.seen == 3:
            raise ValueError("third message")


class WithSystems(Counter):
    def build_systems(self, sim):
        pass


@pytest.fixture(autouse=True)
def node_types(monkeypatch):
    for name, cls in (("counter", "Counter"), ("listener", "Listener"), ("with_systems", "WithSystems")):
        monkeypatch.setitem(registry.BUILTIN, f"test_pkg/{name}", f"{__name__}:{cls}")


def _launch(tmp_path, body: str) -> str:
    path = tmp_path / "t.launch.yaml"
    path.write_text("launch:\n" + textwrap.indent(textwrap.dedent(body), "  "))
    return str(path)


def _run(tmp_path, body, capsys, duration=2.0):
    bag = tmp_path / "out.bag"
    code = main([_launch(tmp_path, body), "--duration", str(duration), "--bag", str(bag)])
    return code, capsys.readouterr().err, bag


def _counts(bag, topic):
    return [m.data for _, m in read_bag(bag).get(topic, [])]


def _stamps(bag, topic):
    return [round(t * 1e-9, 3) for t, _ in read_bag(bag).get(topic, [])]


def test_a_required_node_failing_while_time_runs_stops_the_launch_and_keeps_the_bag(tmp_path, capsys):
    code, err, bag = _run(
        tmp_path,
        """
        - node: {pkg: test_pkg, type: counter, name: a, required: true, params: {fail_at: 0.5}}
        - node: {pkg: test_pkg, type: counter, name: b}
    """,
        capsys,
    )
    assert code == 1
    assert "required node /a failed at t = 0.500 s: RuntimeError: deliberate failure of /a" in err
    # a RuntimeError is not a TwilControlError: a bug, so its traceback is shown
    assert "stopped at t = 0.500 s" in err and "Traceback" in err
    assert _counts(bag, "/a/count") == [1, 2, 3, 4]
    assert _counts(bag, "/b/count") == [1, 2, 3, 4]  # /b's tick at 0.5 s comes after /a's: not run


def test_another_node_failing_is_logged_the_launch_goes_on_and_exits_1(tmp_path, capsys):
    code, err, bag = _run(
        tmp_path,
        """
        - node: {pkg: test_pkg, type: counter, name: a, params: {fail_at: 0.5, how: fail}}
        - node: {pkg: test_pkg, type: counter, name: b}
    """,
        capsys,
    )
    assert code == 1
    assert (
        "node /a failed at t = 0.500 s: /a gives up on purpose; the node is not required: the launch "
        "goes on without it"
    ) in err
    assert "1 node failure while the launch went on: node /a failed at t = 0.500 s" in err
    assert "Traceback" not in err and "RuntimeError" not in err  # fail(reason): the reason only
    assert _counts(bag, "/a/count") == [1, 2, 3, 4]  # its timer stopped
    assert _counts(bag, "/b/count") == list(range(1, 21))  # the others ran to the end


def test_a_subscriber_failing_is_its_own_failure_not_the_publishers(tmp_path, capsys):
    code, err, bag = _run(
        tmp_path,
        """
        - node: {pkg: test_pkg, type: counter, name: a, required: true}
        - node: {pkg: test_pkg, type: listener, name: l}
    """,
        capsys,
        duration=1.0,
    )
    assert code == 1
    assert (
        "node /l failed at t = 0.300 s: node /l: callback on /a/count raised ValueError: third message; "
        "the node is not required"
    ) in err
    assert _counts(bag, "/a/count") == list(range(1, 11))


def test_a_required_node_failing_in_on_start_exits_2_and_leaves_no_bag(tmp_path, capsys):
    code, err, bag = _run(
        tmp_path,
        """
        - node: {pkg: test_pkg, type: counter, name: a, required: true, params: {fail_at: 0.0, how: fail}}
    """,
        capsys,
    )
    assert code == 2
    assert (
        "error: required node /a failed at t = 0.000 s: /a gives up on purpose; the launch was not started"
    ) in err
    assert not bag.exists() and not bag.with_name("out.bag.active").exists()


def test_another_node_failing_in_on_start_lets_the_launch_run(tmp_path, capsys):
    code, err, bag = _run(
        tmp_path,
        """
        - node: {pkg: test_pkg, type: counter, name: a, params: {fail_at: 0.0}}
        - node: {pkg: test_pkg, type: counter, name: b}
    """,
        capsys,
        duration=1.0,
    )
    assert code == 1
    assert "node /a failed at t = 0.000 s: RuntimeError: deliberate failure of /a" in err
    assert _counts(bag, "/a/count") == [] and _counts(bag, "/b/count") == list(range(1, 11))


WORLD = """
        - node: {pkg: twil_control, type: drake_world, name: world,
                 params: {world: "$(find twil_control)/sim/worlds/default.sdf"}}"""


@pytest.mark.parametrize("world", ["", WORLD], ids=["timers alone", "in the simulation"])
def test_respawn_restarts_a_failed_node_with_a_new_instance(tmp_path, capsys, world):
    code, err, bag = _run(
        tmp_path,
        world
        + """
        - node: {pkg: test_pkg, type: counter, name: a, respawn: true, params: {fail_at: 0.45}}
    """,
        capsys,
        duration=1.15,
    )
    assert code == 1  # it failed, even if it came back
    # fails at 0.5 s (its fifth tick), is back at the next slice boundary (0.5 s) with its count
    # reset; the new instance fails at its fifth tick after its start, 1.0 s, and again
    assert _counts(bag, "/a/count") == [1, 2, 3, 4, 1, 2, 3, 4, 1]
    assert _stamps(bag, "/a/count") == [0.1, 0.2, 0.3, 0.4, 0.6, 0.7, 0.8, 0.9, 1.1]
    assert err.count("respawned node /a at t = ") == 2 and "launch goes on and respawns it" in err


@pytest.mark.parametrize(
    "node, message",
    [
        (
            "{pkg: test_pkg, type: counter, name: a, required: true, respawn: true}",
            "node /a is both required and respawn",
        ),
        (
            "{pkg: test_pkg, type: with_systems, name: a, respawn: true}",
            "node /a (test_pkg/with_systems) cannot respawn: it adds models or systems to the simulated world "
            "(build_systems)",
        ),
    ],
)
def test_respawn_that_cannot_work_is_refused_before_time_starts(tmp_path, capsys, node, message):
    code, err, bag = _run(tmp_path, f"- node: {node}\n", capsys)
    assert code == 2 and message in err and not bag.exists()


def test_required_node_failure_unwinds_the_drake_simulation(tmp_path, capsys):
    code, err, bag = _run(
        tmp_path,
        WORLD
        + """
        - node: {pkg: test_pkg, type: counter, name: a, required: true, params: {fail_at: 0.3}}
    """,
        capsys,
    )
    assert code == 1 and "required node /a failed at t = 0.300 s" in err and "stopped at t = 0.300 s" in err
    assert _counts(bag, "/a/count") == [1, 2]
