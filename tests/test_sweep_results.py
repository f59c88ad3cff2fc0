"""The sweep table, summary, plots and progress line, from records made up for the purpose."""

from __future__ import annotations

import json
import math

import pandas as pd

from twil_control.sweep import progress as progress_module
from twil_control.sweep.progress import ProgressLine
from twil_control.sweep.results import best_run, plot, plotted_metrics, summary, table, write_table
from twil_control.sweep.runs import Run

LAUNCH = "/x/launch/a.launch.yaml"


def _runs() -> list[Run]:
    values = [0.5, 1.0, 2.0, "abc"]
    return [
        Run(
            index=i,
            run_id=f"id{i}",
            launch=LAUNCH,
            args={"gain": v},
            varied={"gain": v},
            duration=1.0,
            seed=0,
        )
        for i, v in enumerate(values)
    ]


def _records() -> dict[str, dict]:
    def ok(i, t, err):
        return {
            "status": "ok",
            "error": None,
            "wall_time": 2.0 + i,
            "bag": f"/o/run_id{i}.bag",
            "metrics": {
                "ctl": {"convergence_time": t, "final_error": err},
                "per_goal": [{"status": "reached"}],
            },
        }

    return {
        "id0": ok(0, 4.0, 0.01),
        "id1": ok(1, 3.0, 0.03),
        "id2": ok(2, 5.0, 0.02),
        "id3": {
            "status": "failed",
            "error": "exit code 2: error: bad\nmore",
            "wall_time": 0.5,
            "bag": None,
            "metrics": None,
        },
    }


def test_table_has_one_row_per_run_with_args_status_and_flattened_metrics():
    runs = _runs()
    records = _records()
    del records["id2"]  # not finished yet
    frame, metrics = table(runs, records)
    assert list(frame.columns) == [
        "run_id",
        "index",
        "status",
        "error",
        "wall_time",
        "bag",
        "gain",
        "duration",
        "seed",
        "ctl.convergence_time",
        "ctl.final_error",
        "per_goal",
    ]
    assert metrics == ["ctl.convergence_time", "ctl.final_error", "per_goal"]
    assert list(frame["status"]) == ["ok", "ok", "pending", "failed"]
    assert frame.loc[1, "ctl.convergence_time"] == 3.0
    assert math.isnan(frame.loc[3, "ctl.convergence_time"])
    assert json.loads(frame.loc[0, "per_goal"]) == [{"status": "reached"}]
    assert frame.loc[3, "error"].startswith("exit code 2")


def test_tables_round_trip_through_csv_and_parquet(tmp_path):
    frame, _ = table(_runs(), _records())
    csv, parquet = write_table(frame, tmp_path)
    back = pd.read_parquet(parquet)
    assert list(back["gain"]) == ["0.5", "1.0", "2.0", "abc"]  # mixed column stored as text
    assert list(back["ctl.convergence_time"][:3]) == [4.0, 3.0, 5.0]
    from_csv = pd.read_csv(csv)
    assert list(from_csv["status"]) == ["ok", "ok", "ok", "failed"]
    assert from_csv.loc[3, "error"] == "exit code 2: error: bad\nmore"


def test_summary_counts_statistics_and_best_run():
    frame, metrics = table(_runs(), _records())
    text = summary(frame, metrics, ["gain"], ("ctl.convergence_time", "min"))
    lines = text.splitlines()
    assert lines[0] == "runs: 4  ok: 3  failed: 1"
    row = next(line for line in lines if line.startswith("ctl.convergence_time"))
    assert [float(v) for v in row.split()[1:]] == [4.0, 3.0, 5.0]  # mean, min, max
    assert "best (min ctl.convergence_time): run 1 (id1) ctl.convergence_time=3; gain=1.0" in text
    assert "failed run 3 (id3): exit code 2: error: bad" in text
    assert best_run(frame, ("ctl.final_error", "max"))["run_id"] == "id1"
    assert "none (no run has this metric)" in summary(frame, metrics, ["gain"], ("nope", "min"))


def test_one_plot_per_numeric_metric_that_varies(tmp_path):
    records = _records()
    for rec in list(records.values())[:3]:
        rec["metrics"]["ctl"]["wn"] = 5.0  # a constant echoed back: nothing to plot
    frame, metrics = table(_runs(), records)
    chosen = plotted_metrics(frame, metrics, None)
    assert chosen == ["ctl.convergence_time", "ctl.final_error"]
    assert plotted_metrics(frame, metrics, ("ctl.wn", "per_goal", "nope")) == ["ctl.wn"]
    paths = plot(frame, chosen, ["gain"], tmp_path)
    assert [p.name for p in paths] == ["ctl.convergence_time.png", "ctl.final_error.png"]
    assert all(p.stat().st_size > 1000 for p in paths)


def test_progress_line_extrapolates_the_eta(monkeypatch):
    now = [100.0]
    monkeypatch.setattr(progress_module.time, "monotonic", lambda: now[0])
    line = ProgressLine(total=10, already=2, enabled=False)
    now[0] = 130.0
    # 3 runs done in 30 s, 5 left: 50 s
    assert (
        line.text(done=3, failed=1, running=2)
        == "sweep: 5/10 done, 1 failed, 2 running, 30 s elapsed, ETA 50 s"
    )
    assert line.text(done=0, failed=0, running=2).endswith("ETA ?")


def test_progress_is_off_without_a_terminal_or_under_ci(monkeypatch):
    class Tty:
        def isatty(self):
            return True

    monkeypatch.setenv("CI", "true")
    assert not progress_module.progress_wanted(Tty())
    monkeypatch.delenv("CI")
    assert progress_module.progress_wanted(Tty())
