"""The keyboard teleops read the launch's own terminal: a launch run in tmux (a real terminal),
keys typed with send-keys, the commands read back from the run's bag. Each step waits on what
the terminal shows (the node's banner, the run's last line), not on fixed sleeps."""

from __future__ import annotations

import shutil
import subprocess
import sys
import time
import uuid

import pytest
from conftest import read_bag

from twil_control import PACKAGE_ROOT

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(
        shutil.which("tmux") is None, reason="tmux is installed by `make test` (Debian's tmux)"
    ),
]

LAUNCHES = {
    "teleop_twist_keyboard": """<launch>
  <group ns="kb_teleop">
    <node pkg="teleop_twist_keyboard" type="teleop_twist_keyboard.py" name="teleop_twist_kb"/>
  </group>
</launch>
""",
    "turtlebot3_teleop_key": """<launch>
  <param name="model" value="waffle"/>
  <node pkg="turtlebot3_teleop" type="turtlebot3_teleop_key" name="turtlebot3_teleop_keyboard"/>
</launch>
""",
}


def _pane(session: str) -> str:
    return subprocess.run(
        ["tmux", "capture-pane", "-p", "-t", session], capture_output=True, text=True, check=False
    ).stdout


def _wait_for(session: str, text: str, timeout: float = 60.0) -> str:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        screen = _pane(session)
        if text in screen:
            return screen
        time.sleep(0.1)
    raise AssertionError(f"{text!r} never showed in the terminal:\n{_pane(session)}")


def _drive(tmp_path, name: str, keys: list[tuple[str, float]], duration: float) -> dict:
    launch = tmp_path / f"{name}.launch"
    launch.write_text(LAUNCHES[name])
    bag = tmp_path / "run.bag"
    session = f"twil-{uuid.uuid4().hex[:8]}"
    command = (
        f"cd {PACKAGE_ROOT} && {sys.executable} -m twil_control.launch {launch} --realtime 1 "
        f"--duration {duration} --bag {bag}; echo RUN-ENDED $?; sleep 30"
    )
    subprocess.run(["tmux", "new-session", "-d", "-s", session, "-x", "200", "-y", "50", command], check=True)
    try:
        _wait_for(session, "speed" if name == "teleop_twist_keyboard" else "TurtleBot3")
        for key, pause in keys:
            subprocess.run(["tmux", "send-keys", "-t", session, "-l", key], check=True)
            time.sleep(pause)
        screen = _wait_for(session, "RUN-ENDED", timeout=120.0)
        assert "RUN-ENDED 0" in screen, screen
    finally:
        subprocess.run(["tmux", "kill-session", "-t", session], check=False)
    return read_bag(bag)


def test_teleop_twist_keyboard_drives_from_the_launch_terminal(tmp_path):
    bag = _drive(tmp_path, "teleop_twist_keyboard", [("i", 0.6), ("k", 0.3)], duration=6.0)
    commands = [(m.linear.x, m.angular.z) for _, m in bag["/kb_teleop/cmd_vel"]]
    # i: forward at ~speed (0.5 m/s), k (any other key): stop; one message per key (repeat_rate 0)
    assert commands == [(0.5, 0.0), (0.0, 0.0)]


def test_turtlebot3_teleop_key_ramps_to_its_target(tmp_path):
    bag = _drive(tmp_path, "turtlebot3_teleop_key", [("w", 0.05), ("w", 0.05), ("w", 1.0), (" ", 0.3)], 6.0)
    speeds = [m.linear.x for _, m in bag["/cmd_vel"]]
    # three w: target 0.03 m/s, reached in steps of 0.005 every 0.1 s; space stops at once
    assert max(speeds) == pytest.approx(0.03)
    steps = [b - a for a, b in zip(speeds, speeds[1:]) if b > a]
    assert steps and max(steps) == pytest.approx(0.005)
    assert speeds[-1] == 0.0
