"""One run as a worker executes it: a timeout stops the launch the way Ctrl-C would (the bag is
closed and kept) and is recorded; a metrics-only pass recomputes metrics from an existing bag."""

from __future__ import annotations

import json

import pytest

from twil_control import PACKAGE_ROOT
from twil_control.sweep.worker import STOP_GRACE, RunTask, execute_run, read_record

pytestmark = pytest.mark.slow

WAM = str(PACKAGE_ROOT / "launch/wam_computed_torque.launch.yaml")


def test_a_run_past_its_timeout_is_stopped_and_recorded(tmp_path):
    timeout = 8.0  # long enough for the launch to start recording, even on a loaded machine
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
    assert record["error"].startswith("timed out after 8 s wall time")
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
