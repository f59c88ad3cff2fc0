"""Sweeps end to end on Dask: a local cluster, a scheduler and workers started as separate
processes, a failing run, resume, and Ctrl-C. Runs are the WAM under computed torque for about
a second of simulated time (the first reference step is at 0.5 s), so every ok run has the
computed_torque metrics of analyze_bag."""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pandas as pd
import pytest

from twil_control import PACKAGE_ROOT
from twil_control.launch.__main__ import main as launch_main
from twil_control.sweep import load_sweep, run_sweep
from twil_control.sweep.__main__ import main as sweep_main
from twil_control.sweep.metrics import flatten, metrics_of

pytestmark = [pytest.mark.slow, pytest.mark.cluster]

DASK = Path(sys.executable).with_name("dask")
#: durations of the good runs (s): two, so that the best is a choice (each is a launch of its own,
#: run three times in this file: the local sweep, one by one, through the separate scheduler)
GOOD = [0.9, 1.2]
METRIC = "computed_torque.rms_deviation_all_joints_rad"

SWEEP = f"""
launch: launch/wam_computed_torque.launch.yaml
timeout: 120
list:
{"".join(f"  - {{duration: {d}}}{chr(10)}" for d in GOOD)}  - {{duration: 1.0, time_step: abc}}   # a bad arg value: the launch exits 2
objective: {{metric: {METRIC}, goal: min}}
plots: [{METRIC}]
"""


def _frame_without_timing(frame: pd.DataFrame) -> pd.DataFrame:
    """The table with what legitimately differs between two executions taken out."""
    out = frame.drop(columns=["wall_time"]).copy()
    out["bag"] = out["bag"].map(lambda p: Path(p).name if isinstance(p, str) else p)
    return out


@pytest.fixture(scope="module")
def sweep_file(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("sweep") / "wam_durations.yaml"
    path.write_text(SWEEP)
    return path


@pytest.fixture(scope="module")
def local(sweep_file, tmp_path_factory):
    out = tmp_path_factory.mktemp("local")
    outcome = run_sweep(load_sweep(sweep_file), out, workers=2, progress=False)
    return out, outcome


def test_local_sweep_matches_the_same_runs_done_one_by_one(local, tmp_path):
    _, outcome = local
    frame = outcome.frame
    good = frame[frame["time_step"].isna()].set_index("duration")
    assert list(good.index) == GOOD and (good["status"] == "ok").all()
    metric_columns = [c for c in outcome.metric_names if c.startswith("computed_torque.")]
    assert len(metric_columns) >= 20  # per-joint deviations, errors, step count, ...
    for duration in GOOD:
        bag = tmp_path / f"one_by_one_{duration}.bag"
        assert (
            launch_main(
                [
                    "launch/wam_computed_torque.launch.yaml",
                    "--duration",
                    str(duration),
                    "--seed",
                    "0",
                    "--bag",
                    str(bag),
                    "--quiet",
                ]
            )
            == 0
        )
        alone = flatten(metrics_of(bag, {}))
        row = good.loc[duration]
        assert alone["computed_torque.commands"] > 30  # the trajectory's samples from 0.5 s at 100 Hz
        for column in metric_columns:
            expected = alone[column]
            got = row[column]
            if isinstance(expected, float):  # the same launch, args and seed: the same bag
                assert math.isclose(got, expected, rel_tol=1e-12, abs_tol=1e-15), column
            else:
                assert got == (json.dumps(expected) if isinstance(expected, list) else expected)
    # the tables on disk are the returned frame
    assert pd.read_parquet(outcome.parquet)[METRIC].tolist()[: len(GOOD)] == good[METRIC].tolist()
    assert pd.read_csv(outcome.csv)["status"].tolist() == ["ok"] * len(GOOD) + ["failed"]


def test_failing_run_is_recorded_with_its_error_and_the_others_complete(local):
    out, outcome = local
    frame = outcome.frame
    bad = frame[frame["time_step"] == "abc"].iloc[0]
    assert bad["status"] == "failed"
    assert bad["error"].startswith("exit code 2: error:")
    assert "time_step' must be a number (got 'abc')" in bad["error"]
    assert pd.isna(bad["bag"]) and pd.isna(bad[METRIC])
    assert (frame["status"] == "ok").sum() == len(GOOD)
    assert f"runs: {len(GOOD) + 1}  ok: {len(GOOD)}  failed: 1" in outcome.summary
    best = frame.loc[frame[METRIC].idxmin()]
    assert f"best (min {METRIC}): run {best['index']} ({best['run_id']})" in outcome.summary
    assert [p.name for p in outcome.plots] == [f"{METRIC}.png"]
    record = json.loads((out / "runs" / f"run_{bad['run_id']}.json").read_text())
    assert record["returncode"] == 2


def test_rerun_runs_nothing_new_and_gives_the_same_table(local, sweep_file):
    out, first = local
    stamps = {p.name: p.stat().st_mtime_ns for p in (out / "runs").iterdir()}
    again = run_sweep(load_sweep(sweep_file), out, workers=2, progress=False)
    assert again.executed == 0
    assert {p.name: p.stat().st_mtime_ns for p in (out / "runs").iterdir()} == stamps
    pd.testing.assert_frame_equal(again.frame, first.frame)
    pd.testing.assert_frame_equal(pd.read_parquet(again.parquet), pd.read_parquet(first.parquet))


def _start(argv: list[str], log: Path) -> subprocess.Popen:
    return subprocess.Popen(
        argv, stdout=log.open("w"), stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, start_new_session=True
    )


def _stop_group(proc: subprocess.Popen) -> None:
    """SIGTERM to the process and its children (its own session), SIGKILL if they linger."""
    if proc.poll() is None:
        os.killpg(proc.pid, signal.SIGTERM)
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    try:  # nannies and worker processes of the group exit with it
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            os.killpg(proc.pid, 0)
            time.sleep(0.2)
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass


def test_sweep_through_a_separate_scheduler_gives_the_same_table(local, sweep_file, tmp_path):
    _, reference = local
    scheduler_file = tmp_path / "scheduler.json"
    procs = []
    try:
        procs.append(
            _start(
                [
                    str(DASK),
                    "scheduler",
                    "--host",
                    "127.0.0.1",
                    "--port",
                    "0",
                    "--no-dashboard",
                    "--scheduler-file",
                    str(scheduler_file),
                ],
                tmp_path / "scheduler.log",
            )
        )
        deadline = time.monotonic() + 60
        while not scheduler_file.exists():
            assert time.monotonic() < deadline and procs[0].poll() is None, (
                tmp_path / "scheduler.log"
            ).read_text()
            time.sleep(0.2)
        procs.append(
            _start(
                [
                    str(DASK),
                    "worker",
                    "--scheduler-file",
                    str(scheduler_file),
                    "--host",
                    "127.0.0.1",
                    "--nworkers",
                    "2",
                    "--nthreads",
                    "1",
                    "--no-dashboard",
                ],
                tmp_path / "worker.log",
            )
        )
        out = tmp_path / "remote"
        code = sweep_main([str(sweep_file), "--scheduler", str(scheduler_file), "--out", str(out)])
        assert code == 1  # one run failed (the bad arg)
        remote = pd.read_parquet(out / "results.parquet")
        pd.testing.assert_frame_equal(
            _frame_without_timing(remote), _frame_without_timing(pd.read_parquet(reference.parquet))
        )
    finally:
        for proc in reversed(procs):
            _stop_group(proc)
    for proc in procs:
        with pytest.raises(ProcessLookupError):
            os.killpg(proc.pid, 0)


def _default_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)  # a shell's background job would ignore SIGINT


def test_ctrl_c_stops_cleanly_and_keeps_the_finished_runs(tmp_path):
    sweep = tmp_path / "long.yaml"
    sweep.write_text(
        textwrap.dedent("""
        launch: launch/wam_computed_torque.launch.yaml
        timeout: 300
        list: [{duration: 0.6}, {duration: 60}, {duration: 61}]
        plots: [duration_s]
    """)
    )
    out = tmp_path / "out"
    log = tmp_path / "sweep.log"
    proc = subprocess.Popen(
        [sys.executable, "-m", "twil_control.sweep", str(sweep), "--out", str(out), "--workers", "2"],
        cwd=PACKAGE_ROOT,
        stdout=log.open("w"),
        stderr=subprocess.STDOUT,
        start_new_session=True,
        preexec_fn=_default_sigint,
    )
    try:
        deadline = time.monotonic() + 90
        while not list((out / "runs").glob("run_*.json")):  # the short run has finished
            assert time.monotonic() < deadline and proc.poll() is None, log.read_text()
            time.sleep(0.2)
        time.sleep(1.0)
        os.killpg(proc.pid, signal.SIGINT)  # what Ctrl-C on its terminal sends
        assert proc.wait(timeout=60) == 130, log.read_text()
    finally:
        _stop_group(proc)
    text = log.read_text()
    assert "interrupted" in text and "Traceback" not in text, text
    frame = pd.read_csv(out / "results.csv")
    assert frame["status"].tolist() == ["ok", "pending", "pending"]
    assert not list((out / "runs").glob("*.active"))  # no half-written bag left behind
    assert len(list((out / "runs").glob("*.bag"))) == 1
    running = subprocess.run(["pgrep", "-f", str(out)], capture_output=True, text=True).stdout
    assert running == "", running  # no launch outlives the sweep
