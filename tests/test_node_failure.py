"""A node raising while time runs: the error is reported, the run ends, the bag keeps what was
recorded before the error and is a valid, indexed bag."""

from __future__ import annotations

import textwrap

from conftest import bag_connections, read_bag

from twil_control.core.ros_node import RosNode
from twil_control.launch import node_types as registry
from twil_control.launch.__main__ import main


class Exploding(RosNode):
    """Publishes a counter at 10 Hz and raises at t = 0.5 s."""

    def __init__(self, *a, **kw):
        super().__init__(*a, **kw)
        self.pub = self.create_publisher("counter", "std_msgs/Int32")
        self.count = 0
        self.create_timer(0.1, self.tick)

    def tick(self, event):
        if event.current_expected >= 0.5 - 1e-9:
            raise RuntimeError("deliberate failure for the test")
        self.count += 1
        self.pub.publish(self.pub._cls(data=self.count))


def test_exception_in_a_node_keeps_the_bag(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(registry.BUILTIN, "test_pkg/exploding", f"{__name__}:Exploding")
    launch = tmp_path / "explode.launch.yaml"
    launch.write_text(
        textwrap.dedent("""
        launch:
          - node: {pkg: twil_control, type: drake_world, name: world,
                   params: {world: "$(find twil_control)/sim/worlds/default.sdf"}}
          - node: {pkg: test_pkg, type: exploding, name: bomb}
    """)
    )
    bag = tmp_path / "out.bag"
    assert main([str(launch), "--duration", "2", "--bag", str(bag)]) == 1
    err = capsys.readouterr().err
    # a RuntimeError is not a TwilControlError: a bug, shown with its traceback down to the node
    assert "deliberate failure for the test" in err and "Traceback" in err and ", in tick" in err
    assert bag.exists()
    msgs = read_bag(bag)["/counter"]
    assert [m.data for _, m in msgs] == [1, 2, 3, 4]
    assert bag_connections(bag)["/counter"][2] == 4
