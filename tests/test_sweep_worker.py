"""One run as a worker executes it: a timeout stops the launch the way Ctrl-C would (the bag is
closed and kept) and is recorded; a metrics-only pass recomputes metrics from an existing bag."""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest

from twil_control import PACKAGE_ROOT
from twil_control.sweep import worker
from twil_control.sweep.worker import STOP_GRACE, RunTask, execute_run, read_record

pytestmark = pytest.mark.slow

WAM = str(PACKAGE_ROOT / "launch/wam_computed_torque.launch.yaml")


class _ClockFromRecording:
    """The time module as the worker sees it, with a monotonic clock that stands still until the
    launch has started recording (its bag's .active file exists): a timeout counted from there
    does not depend on how long a loaded machine takes to start the launch. After `cap` real
    seconds without a recording it runs anyway (the test then fails on its assertions)."""

    def __init__(self, active: Path, cap: float = 120.0) -> None:
        self.active, self.cap = active, cap
        self.t0 = time.monotonic()
        self.started: float | None = None

    def monotonic(self) -> float:
        now = time.monotonic()
        if self.started is None:
            if not self.active.exists() and now - self.t0 < self.cap:
                return self.t0
            self.started = now
        return self.t0 + (now - self.started)

    def __getattr__(self, name):
        return getattr(time, name)


def test_a_run_past_its_timeout_is_stopped_and_recorded(tmp_path, monkeypatch):
    timeout = 6.0  # of recording: the simulated time passes 0.5 s well before, even under load
    monkeypatch.setattr(worker, "time", _ClockFromRecording(tmp_path / "run_t1.bag.active"))
    task = RunTask(
        run_id="t1",
        index=0,
        launch=WAM,
        argv=["--duration", "300", "--seed", "0"],
        run_dir=str(tmp_path),
        timeout=timeout,
    )
    record = execute_run(task)
    assert record["status"] == "timeout"
    assert record["error"].startswith("timed out after 6 s wall time")
    assert timeout <= record["wall_time"] < timeout + STOP_GRACE + 5
    # stopped with SIGINT: the launch closed its bag (no .active left) and exited 0
    assert record["returncode"] == 0
    assert record["bag"] == str(tmp_path / "run_t1.bag")
    assert (tmp_path / "run_t1.bag").stat().st_size > 1000
    assert not (tmp_path / "run_t1.bag.active").exists()
    assert read_record(tmp_path / "run_t1.json") == json.loads(json.dumps(record))

    # a metrics-only pass reads that bag again: it has the references from 0.5 s on
    again = execute_run(
        RunTask(
            run_id="t1",
            index=0,
            launch=WAM,
            argv=[],
            run_dir=str(tmp_path),
            timeout=timeout,
            metrics_only=True,
            record=record,
        )
    )
    assert again["status"] == "timeout" and again["metrics"]["computed_torque"]["commands"] >= 1
    assert again["metrics"]["duration_s"] > 0.5
