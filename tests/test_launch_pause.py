"""A paced run stopped for a while (SIGSTOP, then SIGCONT) resumes its pacing from where it was,
as Gazebo does, instead of running the lost wall time off unpaced; the log says how much wall
time was lost and when (launch/runner.py, _Pace). Bounds are lower bounds on wall time, which a
loaded machine only raises."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time

import pytest

from twil_control import PACKAGE_ROOT

pytestmark = pytest.mark.slow

DURATION, PAUSE = 4.0, 3.0


def test_a_run_stopped_and_continued_resumes_pacing_and_reports_the_pause(tmp_path):
    bag = tmp_path / "run.bag"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "twil_control.launch",
            str(PACKAGE_ROOT / "launch/wam_computed_torque.launch.yaml"),
            "--realtime",
            "1",
            "--duration",
            str(DURATION),
            "--bag",
            str(bag),
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        env=dict(os.environ, PYTHONUNBUFFERED="1"),
    )
    deadline = time.monotonic() + 300
    while not (tmp_path / "run.bag.active").exists():  # time has started: the bag is recording
        assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
        time.sleep(0.01)
    time.sleep(1.0)
    proc.send_signal(signal.SIGSTOP)
    time.sleep(PAUSE)
    proc.send_signal(signal.SIGCONT)
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err
    lost = re.findall(
        r"paced run: ([0-9.]+) s of wall time lost at t = ([0-9.]+) s: the process was stopped and continued",
        err,
    )
    assert len(lost) == 1, err
    assert float(lost[0][0]) >= PAUSE - 0.5 and 0.0 < float(lost[0][1]) < DURATION
    wall = float(re.search(r"simulated [0-9.]+ s in ([0-9.]+) s", err).group(1))
    assert wall >= DURATION + PAUSE - 0.5, err  # the pause was not run off unpaced
