"""The BARN benchmark as its users run it: ``python -m twil_control.barn --world_idx N`` (run.py's
equivalent) with jackal_helper, jackal and jackal_gazebo found through ROS_PACKAGE_PATH (the
vendored copies: BARN worlds 0 and 6, their path files, the DWA stack's launch and parameter
files), its out.txt line, and BARN's own report_test.py reading it unchanged.

Three trials, their lines in one out file (a module fixture, run once): world 0 with jackal_helper's
move_base_DWA.launch (succeeded), world 6 with a stack that drives straight into the field
(collided: the first of two such trials run as test.sh's loop), world 0 with a stack that stops
short (a timeout, with a 2 s limit).
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest

from twil_control import PACKAGE_ROOT
from twil_control.barn import many, metric, trial

VENDOR = PACKAGE_ROOT / "tests" / "data" / "ros1" / "vendor"
STUBS = PACKAGE_ROOT / "tests" / "data" / "ros1" / "stubs"
STACKS = PACKAGE_ROOT / "tests" / "data" / "barn"
PATHS = VENDOR / "jackal_helper" / "worlds" / "BARN" / "path_files"


def _env() -> dict:
    return {**os.environ, "ROS_PACKAGE_PATH": f"{VENDOR}:{STUBS}", "PYTHONUNBUFFERED": "1"}


def _barn(out, *args) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "twil_control.barn", "--out", str(out), *args],
        env=_env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def _optimal_time(idx: int, init=(-2.25, 3.0)) -> float:
    """run.py's arithmetic, written out again: cells (x, y) -> 0.15 x - 4.575, 0.15 y + 5.075."""
    cells = np.load(PATHS / f"path_{idx}.npy").astype(float)
    points = np.vstack(
        [init, np.column_stack([0.15 * cells[:, 0] - 4.575, 0.15 * cells[:, 1] + 5.075]), (init[0], 13.0)]
    )
    return float(np.linalg.norm(np.diff(points, axis=0), axis=1).sum()) / 2


@pytest.fixture(scope="module")
def trials(tmp_path_factory):
    """The trials side by side, one process each as run.py (world 6's first of two, run 0 of
    test.sh's loop, is a `--world_idx 6` process of its own too), each with its own out file, then
    the three trials' lines in one out file in a fixed order."""
    folder = tmp_path_factory.mktemp("barn")
    args = {
        "dwa": ("--world_idx", "0"),
        "short": ("--world_idx", "0", "--time_limit", "2", "--nav_launch", str(STACKS / "stop_short.launch")),
    }
    procs = {name: _barn(folder / f"{name}.txt", *a) for name, a in args.items()}
    # test.sh's loop through the sweep's machinery: world 6 twice (seeds 0 and 1), one worker
    procs["many"] = _barn(folder / "many.txt", *MANY, "--dir", str(folder / "many.d"))
    runs = {}
    for name, proc in procs.items():
        stdout, stderr = proc.communicate(timeout=1200)
        runs[name] = subprocess.CompletedProcess(proc.args, proc.returncode, stdout, stderr)
    runs["folder"] = folder

    def lines(name: str) -> list[str]:
        path = folder / f"{name}.txt"
        return path.read_text().splitlines(keepends=True) if path.exists() else []

    out = folder / "out.txt"
    out.write_text("".join(lines("dwa") + lines("many")[:1] + lines("short")))
    return out, runs


MANY = (
    "--worlds",
    "6,6",
    "--runs",
    "2",
    "--workers",
    "1",
    "--nav_launch",
    str(STACKS / "drive_forward.launch"),
)


def _fields(line: str) -> tuple:
    f = line.split()
    assert len(f) == 6, line
    return int(f[0]), int(f[1]), int(f[2]), int(f[3]), float(f[4]), float(f[5])


@pytest.mark.slow
def test_dwa_trial_in_world_0_succeeds_and_writes_run_py_s_lines(trials):
    out, runs = trials
    run = runs["dwa"]
    assert run.returncode == 0, run.stderr[-2000:]
    lines = run.stdout.splitlines()
    assert (
        lines[0] == ">>>>>>>>>>>>>>>>>> Loading Gazebo Simulation with BARN/world_0.world <<<<<<<<<<<<<<<<<<"
    )
    assert ">>>>>>>>>>>>>>>>>> Test finished! <<<<<<<<<<<<<<<<<<" in lines
    world, success, collided, timeout, time, score = _fields(out.read_text().splitlines()[0])
    assert (world, success, collided, timeout) == (0, 1, 0, 0)
    # 10 m at DWA's max_vel_x 0.5 m/s takes 20 s at least. Gazebo's ten runs: eight succeed in
    # 28-53 s, one times out; this seed (76 s) turns in place and backs away from the first gap
    # for ~50 s before it passes
    assert 19.0 < time < 100.0
    best = _optimal_time(0)
    assert score == pytest.approx(best / min(max(time, 2 * best), 8 * best), abs=1e-4)
    assert f"Navigation succeeded with time {time:.4f} (s)" in lines
    assert f"Navigation metric: {score:.4f}" in lines


@pytest.mark.slow
def test_driving_into_the_field_is_reported_as_collided(trials):
    out, runs = trials
    assert runs["many"].returncode == 0, runs["many"].stderr[-2000:]
    world, success, collided, timeout, time, score = _fields(out.read_text().splitlines()[1])
    assert (world, success, collided, timeout, score) == (6, 0, 1, 0, 0.0)
    # from y = 3 at 0.5 m/s the field (y > 5) is 4 s away; the first cylinder ahead is met by 12 s
    assert 3.0 < time < 12.0
    # the trial's process printed run.py's lines (its log)
    log = (runs["folder"] / "many.d" / "runs" / "run_w006_r00.log").read_text()
    assert f"Navigation collided with time {time:.4f} (s)" in log.splitlines()


@pytest.mark.slow
def test_a_robot_that_stops_short_of_a_blocked_goal_times_out(trials):
    out, runs = trials
    assert runs["short"].returncode == 0, runs["short"].stderr[-2000:]
    world, success, collided, timeout, time, score = _fields(out.read_text().splitlines()[2])
    assert (world, success, collided, timeout, score) == (0, 0, 0, 1, 0.0)
    assert time == pytest.approx(2.0, abs=0.11)  # looked at every 0.1 s, as run.py does


@pytest.mark.slow
def test_barn_s_report_test_reads_the_out_file_unchanged(trials):
    out, _ = trials
    lines = out.read_text().splitlines()
    dwa_time = _fields(lines[0])[4]
    # report_test.py (vendored unchanged) reads jackal_helper/worlds/BARN/path_files from its cwd
    report = subprocess.run(
        [sys.executable, str(VENDOR / "the-barn-challenge" / "report_test.py"), "--out_path", str(out)],
        cwd=VENDOR,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert report.returncode == 0, report.stderr
    assert "Missing world_12" in report.stdout and "Test on world_0 not finished (2/10)" in report.stdout
    values = dict(
        (k.strip(), float(v)) for k, v in (p.split(":") for p in report.stdout.splitlines()[-1].split(","))
    )
    # per world means, then their mean over worlds 0 and 6: world 0 has a success and a timeout,
    # world 6 a collision; report_test.py takes its optimal time from (-2, 3), run.py from (-2.25, 3)
    best = _optimal_time(0, init=(-2.0, 3.0))
    assert values["Avg Time"] == pytest.approx(dwa_time, abs=1e-4)
    assert values["Avg Metric"] == pytest.approx(best / min(max(dwa_time, 2 * best), 8 * best) / 4, abs=1e-4)
    assert (values["Avg Success"], values["Avg Collision"], values["Avg Timeout"]) == (0.25, 0.5, 0.25)


@pytest.mark.slow
def test_many_trials_run_on_dask_are_recorded_and_a_rerun_runs_none_again(trials):
    _, runs = trials
    folder, first = runs["folder"], runs["many"]
    assert first.returncode == 0, first.stderr[-2000:]
    lines = (folder / "many.txt").read_text().splitlines()
    assert [_fields(line)[:4] for line in lines] == [(6, 0, 1, 0)] * 2  # run 0, then run 1
    records = [json.loads((folder / "many.d" / "runs" / f"run_w006_r0{k}.json").read_text()) for k in (0, 1)]
    assert [r["status"] for r in records] == ["ok", "ok"] and all(r["cpu_time"] > 1.0 for r in records)
    assert "Avg Success: 0.0000, Avg Collision: 1.0000" in first.stdout
    again = subprocess.run(
        [
            sys.executable,
            "-m",
            "twil_control.barn",
            "--out",
            str(folder / "again.txt"),
            *MANY,
            "--dir",
            str(folder / "many.d"),
        ],
        env=_env(),
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert again.returncode == 0 and "2 already recorded, 0 to run" in again.stderr
    assert (folder / "again.txt").read_text() == (folder / "many.txt").read_text()


@pytest.mark.slow
def test_a_trial_that_cannot_start_is_recorded_as_failed(tmp_path):
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "twil_control.barn",
            "--worlds",
            "6",
            "--workers",
            "1",
            "--out",
            str(tmp_path / "o.txt"),
        ]
        + ["--nav_launch", str(STACKS / "broken.launch")],
        env=_env(),
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 1 and (tmp_path / "o.txt").read_text() == ""
    record = json.loads((tmp_path / "o.txt.d" / "runs" / "run_w006_r00.json").read_text())
    assert record["status"] == "failed" and "unsupported node type" in record["error"]
    assert "1 failed" in run.stderr


def test_run_py_s_metric_and_out_line():
    best = _optimal_time(6)
    assert metric.path_length(PATHS / "path_6.npy", (-2.25, 3.0), (-2.25, 13.0)) / 2 == pytest.approx(
        best, rel=1e-12
    )
    assert metric.nav_metric(True, 1.0, best) == pytest.approx(0.5)  # clipped up to 2 optimal times
    assert metric.nav_metric(True, 100.0, best) == pytest.approx(1 / 8)  # clipped down to 8
    assert metric.nav_metric(False, 30.0, best) == 0.0
    assert metric.out_line(6, True, False, 23.45678, 0.31234) == "6 1 0 0 23.4568 0.3123\n"
    assert metric.out_line(12, False, False, 100.05, 0.0) == "12 0 0 1 100.0500 0.0000\n"


def test_worlds_and_indices_are_run_py_s():
    assert trial.world(0).name == "BARN/world_0.world" and trial.world(0).init == (-2.25, 3.0, 1.57)
    assert trial.world(301).name == "DynaBARN/world_1.world" and trial.world(301).goal == (-20.0, 0.0)
    with pytest.raises(trial.BarnError, match="world index 360 does not exist"):
        trial.world(360)
    assert many.parse_worlds("0:300:6") == list(range(0, 300, 6)) and len(many.parse_worlds("0:300:6")) == 50
    assert many.parse_worlds("0,6") == [0, 6] and many.parse_worlds("6,0,6") == [6, 0]
    with pytest.raises(trial.BarnError, match="--worlds"):
        many.parse_worlds("0:300:0")


def test_a_missing_catkin_src_is_one_error_line_and_exit_2(tmp_path):
    env = {**os.environ, "ROS_PACKAGE_PATH": str(tmp_path)}
    run = subprocess.run(
        [sys.executable, "-m", "twil_control.barn", "--world_idx", "0", "--out", str(tmp_path / "o.txt")],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 2
    errors = [line for line in run.stderr.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and "jackal_helper" in errors[0] and "ROS_PACKAGE_PATH" in errors[0]
    assert not (tmp_path / "o.txt").exists()


def test_the_many_trials_summary_is_report_test_s_arithmetic():
    lines = ["0 1 0 0 20.0000 0.3000\n", "0 0 1 0 5.0000 0.0000\n", "6 1 0 0 30.0000 0.2000\n"]
    text = many.summary(lines)
    # per world, then over worlds: time (20 + 30) / 2, metric (0.15 + 0.2) / 2, success (0.5 + 1) / 2
    assert text == (
        "Avg Time: 25.0000, Avg Metric: 0.1750, Avg Success: 0.7500, Avg Collision: 0.2500, Avg Timeout: 0.0000"
    )
    assert math.isclose(0.175, (0.15 + 0.2) / 2)
