"""One error family: a TwilControlError is bad input (one `error:` line, its exit code, 2); any
other exception is a bug, shown with its traceback, exit 1. Run as a user runs the launch, in a
process of its own, with pure ROS nodes (no simulated world: each run takes about 2 s)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from twil_control.errors import InputError, TwilControlError, exit_on_error

#: Registers the test's node type, then runs the launch's command line as `python -m` would.
LAUNCHER = """
import sys
from twil_control.launch import node_types
node_types.BUILTIN["test_pkg/broken"] = "broken_node:Broken"
from twil_control.launch.__main__ import main
sys.exit(main(sys.argv[1:]))
"""

BROKEN_NODE = """
from twil_control.core.ros_node import RosNode


class Broken(RosNode):
    \"\"\"Adds a number to None, in on_start or in its timer at t = 0.3 s (~where: start|timer).\"\"\"

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.where = self.get_param("~where", "timer")
        self.create_timer(0.1, self.tick)

    def on_start(self):
        if self.where == "start":
            self.add_one(None)

    def tick(self, event):
        if event.current_expected >= 0.3 - 1e-9:
            self.add_one(None)

    def add_one(self, value):
        return value + 1
"""


def _launch(tmp_path: Path, node: str, *argv: str) -> subprocess.CompletedProcess:
    (tmp_path / "launcher.py").write_text(LAUNCHER)
    (tmp_path / "broken_node.py").write_text(BROKEN_NODE)
    launch = tmp_path / "a.launch.yaml"
    launch.write_text(f"launch:\n  - node: {node}\n")
    env = dict(os.environ, PYTHONPATH=str(tmp_path))
    return subprocess.run(
        [sys.executable, str(tmp_path / "launcher.py"), str(launch), "--duration", "1", *argv],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )


@pytest.mark.parametrize("where", ["start", "timer"])
def test_a_type_error_in_a_node_prints_its_traceback_and_exits_1(tmp_path, where):
    node = f"{{pkg: test_pkg, type: broken, name: broken, required: true, params: {{where: {where}}}}}"
    r = _launch(tmp_path, node, "--no-bag")
    assert r.returncode == 1, r.stderr
    assert "Traceback (most recent call last)" in r.stderr
    assert "in add_one" in r.stderr and "TypeError: unsupported operand type(s) for +" in r.stderr
    assert "error: " not in r.stderr  # not reported as bad input


def test_a_bad_parameter_exits_2_with_one_line(tmp_path):
    node = "{pkg: robot_state_publisher, type: robot_state_publisher, name: rsp, params: {publish_frequency: -5}}"
    bag = tmp_path / "out.bag"
    r = _launch(tmp_path, node, "--bag", str(bag))
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), r.stderr
    assert "publish_frequency" in lines[0] and "-5" in lines[0], lines[0]
    assert not bag.exists()


def test_the_cli_wrapper_maps_only_the_family(capsys):
    class Missing(TwilControlError, LookupError):
        exit_code = 3

    def raises(error):
        def run():
            raise error

        return run

    assert exit_on_error(raises(InputError("--x must be > 0 (got -1)"))) == 2
    assert exit_on_error(raises(Missing("no such thing: y"))) == 3
    assert capsys.readouterr().err == "error: --x must be > 0 (got -1)\nerror: no such thing: y\n"
    with pytest.raises(TypeError):
        exit_on_error(raises(TypeError("a bug")))
    assert isinstance(InputError("v"), ValueError)  # code that catches ValueError still does
